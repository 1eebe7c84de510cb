"""Does a pre-allocated workspace lower ``orca_advance``'s per-call floor (issue 46's one-world target at N ≤ 50)?

    PYTHONPATH=. python studies/speed-2026-12-06/advance_workspace.py [--rounds 3]

``orca_batch`` allocates ~21 work arrays per call (≈ 0.5 µs measured alone, ``studies/speed-2026-12-05/call_floor.py``).
Here its body runs with the work arrays handed in: either as one tuple argument (``ws``) or sliced from two flat
buffers made once (``ws2``: a float64 and an int64 buffer; views inside the kernel). The variants are built from
``orca_kernel.py``'s own ``orca_batch`` source at run time (the allocations cut out), checked bitwise equal to
``orca_advance`` over 60 steps at N = 20 and 50, then timed against it in alternation in one process (µs per call,
best of 3 blocks of 20,000 calls; the lattice crowd of ``bench_orca_rvo2.py``).
"""

from __future__ import annotations

import argparse
import importlib.util
import inspect
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from crowdbench.bench import ORCA_BENCH, bench_crowd
from crowdbench.humans import orca_kernel, preferred_velocity
from crowdbench.humans.orca_kernel import build_obstacles, orca_advance

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "speed-2026-12-05"))
from call_floor import per_call  # noqa: E402

HEADER = '''"""variants of orca_advance with work arrays handed in (generated)"""
import numba as nb
import numpy as np
from crowdbench.humans.orca_kernel import (_find_obstacles, _obstacle_lines, _grid_nearest, _brute_nearest, _lp2,
    _lp3, _det, _world_grid, _search_scratch, OBST_TREE_MIN, GRID_MIN)


@nb.njit(error_model="numpy")
def _core(pos, vel, pref, radius, max_speed, neighbor_dist, max_neighbors, time_horizon, time_horizon_obst,
          active, controlled, ignore, opoint, onext, oprev, odir, oconvex, otree, dt, out, grid_min,
          lp, ld, pp, pd, res, cand_d, cand_idx, near_d, near_idx, nb_d, nb_idx, ob_d, ob_idx, rank, ostack,
          cell_start, cell_of, sx, sy, sidx, geo):
'''
TAIL = '''

@nb.njit(error_model="numpy")
def workspace(A, V, otree):
    L = V + A + 1
    lines = (np.empty((L, 2)), np.empty((L, 2)), np.empty((L, 2)), np.empty((L, 2)), np.empty(2))
    return lines + _search_scratch(A, V, otree)


@nb.njit(error_model="numpy")
def adv_ws(vec, flt, ints, flags, opoint, onext, oprev, odir, oconvex, otree, dt, ws):
    pos, vel, out = vec[0], vec[1], vec[3]
    (lp, ld, pp, pd, res, cand_d, cand_idx, near_d, near_idx, nb_d, nb_idx, ob_d, ob_idx, rank, ostack,
     cell_start, cell_of, sx, sy, sidx, geo) = ws
    _core(pos, vel, vec[2], flt[0], flt[1], flt[2], ints[0], flt[3], flt[4], flags[0], flags[1], ints[1], opoint,
          onext, oprev, odir, oconvex, otree, dt, out, GRID_MIN, lp, ld, pp, pd, res, cand_d, cand_idx, near_d,
          near_idx, nb_d, nb_idx, ob_d, ob_idx, rank, ostack, cell_start, cell_of, sx, sy, sidx, geo)
    active = flags[0]
    B, A = pos.shape[0], pos.shape[1]
    for b in range(B):
        for i in range(A):
            vx, vy = out[b, i, 0], out[b, i, 1]
            vel[b, i, 0], vel[b, i, 1] = vx, vy
            if active[b, i]:
                pos[b, i, 0] += vx * dt
                pos[b, i, 1] += vy * dt


@nb.njit(error_model="numpy")
def workspace2(A, V, otree):
    L = V + A + 1
    nf = 8 * L + 2 + 2 * (A + 8) + (A + 1) + (V + 1) + 2 * A + 7
    T = 2 * otree.shape[0] + 2
    ni = 2 * (A + 8) + (A + 1) + (V + 1) + 64 + 2 * T + 16 * A + 2 + 2 * A
    return np.empty(nf), np.empty(ni, np.int64)


@nb.njit(error_model="numpy")
def adv_ws2(vec, flt, ints, flags, opoint, onext, oprev, odir, oconvex, otree, dt, wf, wi):
    pos, vel, out = vec[0], vec[1], vec[3]
    B, A = pos.shape[0], pos.shape[1]
    V = opoint.shape[0]
    L = V + A + 1
    o = 0
    lp = wf[o:o + 2 * L].reshape((L, 2)); o += 2 * L
    ld = wf[o:o + 2 * L].reshape((L, 2)); o += 2 * L
    pp = wf[o:o + 2 * L].reshape((L, 2)); o += 2 * L
    pd = wf[o:o + 2 * L].reshape((L, 2)); o += 2 * L
    res = wf[o:o + 2]; o += 2
    cand_d = wf[o:o + A + 8]; o += A + 8
    near_d = wf[o:o + A + 8]; o += A + 8
    nb_d = wf[o:o + A + 1]; o += A + 1
    ob_d = wf[o:o + V + 1]; o += V + 1
    sx = wf[o:o + A]; o += A
    sy = wf[o:o + A]; o += A
    geo = wf[o:o + 7]
    o = 0
    cand_idx = wi[o:o + A + 8]; o += A + 8
    near_idx = wi[o:o + A + 8]; o += A + 8
    nb_idx = wi[o:o + A + 1]; o += A + 1
    ob_idx = wi[o:o + V + 1]; o += V + 1
    rank = wi[o:o + 64]; o += 64
    T = 2 * otree.shape[0] + 2
    ostack = wi[o:o + 2 * T].reshape((T, 2)); o += 2 * T
    cell_start = wi[o:o + 16 * A + 2]; o += 16 * A + 2
    cell_of = wi[o:o + A]; o += A
    sidx = wi[o:o + A]
    _core(pos, vel, vec[2], flt[0], flt[1], flt[2], ints[0], flt[3], flt[4], flags[0], flags[1], ints[1], opoint,
          onext, oprev, odir, oconvex, otree, dt, out, GRID_MIN, lp, ld, pp, pd, res, cand_d, cand_idx, near_d,
          near_idx, nb_d, nb_idx, ob_d, ob_idx, rank, ostack, cell_start, cell_of, sx, sy, sidx, geo)
    active = flags[0]
    for b in range(B):
        for i in range(A):
            vx, vy = out[b, i, 0], out[b, i, 1]
            vel[b, i, 0], vel[b, i, 1] = vx, vy
            if active[b, i]:
                pos[b, i, 0] += vx * dt
                pos[b, i, 1] += vy * dt
'''


def variants():
    """The generated module: ``orca_batch``'s body without its allocations as ``_core``, and the two callers."""
    src = inspect.getsource(orca_kernel.orca_batch)
    body = src[src.index("    B, A = pos.shape[0], pos.shape[1]"):]
    for cut in ("    lp = np.empty((L, 2))\n    ld = np.empty((L, 2))\n    pp = np.empty((L, 2))\n"
                "    pd = np.empty((L, 2))\n    res = np.empty(2)\n",
                "    (cand_d, cand_idx, near_d, near_idx, nb_d, nb_idx, ob_d, ob_idx, rank, ostack, cell_start, "
                "cell_of, sx, sy, sidx,\n     geo) = _search_scratch(A, V, otree)\n"):
        assert cut in body, cut
        body = body.replace(cut, "")
    path = Path(tempfile.mkdtemp()) / "advance_variants.py"
    path.write_text(HEADER + body + TAIL)
    spec = importlib.util.spec_from_file_location("advance_variants", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod


def make(mod, n: int, kind: str):
    """One step of ``n`` lattice agents with ``kind`` (``old``, ``ws``, ``ws2``); returns (step, vec)."""
    a = ORCA_BENCH.batch_args(1, n)
    flt, ints, flags = np.stack([a[0], a[1], a[2], a[4], a[5]]), np.stack([a[3], a[8]]), np.stack([a[6], a[7]])
    start = bench_crowd(n, 1, "grid")
    vec = np.zeros((4, 1, n, 2))
    obst = build_obstacles([])
    speed = np.full((1, n), ORCA_BENCH.max_speed)
    ws = mod.workspace(n, obst[0].shape[0], obst[5])
    wf, wi = mod.workspace2(n, obst[0].shape[0], obst[5])
    k = [0]

    def step() -> float:
        if k[0] % 20 == 0:
            vec[:] = 0.0
            vec[0] = start
        k[0] += 1
        vec[2] = preferred_velocity(vec[0], -start, speed, ORCA_BENCH.dt)
        t = time.perf_counter()
        if kind == "ws":
            mod.adv_ws(vec, flt, ints, flags, *obst, ORCA_BENCH.dt, ws)
        elif kind == "ws2":
            mod.adv_ws2(vec, flt, ints, flags, *obst, ORCA_BENCH.dt, wf, wi)
        else:
            orca_advance(vec, flt, ints, flags, *obst, ORCA_BENCH.dt)
        return time.perf_counter() - t

    return step, vec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    mod = variants()
    for n in (20, 50):
        steps = [make(mod, n, kind) for kind in ("old", "ws", "ws2")]
        for _ in range(60):
            for s, _v in steps:
                s()
            assert all(np.array_equal(steps[0][1], v) for _s, v in steps[1:]), n
    print("bitwise equal to orca_advance: yes")
    for r in range(args.rounds):
        line = []
        for n in (1, 20, 50):
            t = {kind: per_call(make(mod, n, kind)[0], 20_000, 3, True) for kind in ("old", "ws", "ws2")}
            line.append(f"N = {n}: {t['old']:.2f} · {t['ws']:.2f} · {t['ws2']:.2f} µs")
        print(f"round {r + 1} (orca_advance · ws · ws2): " + " | ".join(line), flush=True)


if __name__ == "__main__":
    main()
