"""What one ORCA step costs before any agent is computed: crowdbench's ``orca_advance`` call against Python-RVO2's
``doStep`` (issue 46's one-world target at small N).

    PYTHONPATH=. python studies/speed-2026-12-05/call_floor.py [--rounds 3]

Prints µs per call (best of ``--rounds``): ``orca_advance`` on one world of 1 agent and of 20 (the lattice crowd of
``bench_orca_rvo2.py``: 20 steps from the start toward the goals, preferred velocities set before each step), RVO2's
``doStep`` on the same — only the step call timed (``perf_counter`` around it), as ``bench_orca_rvo2.py`` times
them — and the parts of crowdbench's floor: a compiled no-op with ``orca_advance``'s 11 arguments (numba's dispatch:
argument typing and unboxing), the same with one array, and 21 small allocations inside compiled code
(``orca_advance``'s work arrays).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numba as nb
import numpy as np

from crowdbench.bench import ORCA_BENCH, bench_crowd
from crowdbench.humans import preferred_velocity
from crowdbench.humans.orca_kernel import build_obstacles, orca_advance


@nb.njit(cache=False)
def _noop11(a, b, c, d, e, f, g, h, i, j, dt):  # pragma: no cover - numba
    return 0


@nb.njit(cache=False)
def _noop1(a):  # pragma: no cover - numba
    return 0


@nb.njit(cache=False)
def _alloc21(n):  # pragma: no cover - numba
    s = 0
    for _ in range(21):
        s += np.empty(n + 8).shape[0]
    return s


def per_call(fn: Callable[[], object], calls: int, rounds: int, self_timed: bool = False) -> float:
    """Best over ``rounds`` of the µs per call of ``fn``: the whole call, or with ``self_timed`` the seconds ``fn``
    returns (its own timing of the part that counts)."""
    fn()
    best = np.inf
    for _ in range(rounds):
        total = 0.0
        t = time.perf_counter()
        for _ in range(calls):
            part = fn()
            if self_timed:
                total += part  # type: ignore[operator]
        best = min(best, (total if self_timed else time.perf_counter() - t) / calls * 1e6)
    return best


def ours(n: int, bind: Callable[..., Callable[..., object]] | None = None) -> Callable[[], float]:
    """One ``orca_advance`` step of ``n`` lattice agents (the start restored every 20 steps); returns its seconds.
    ``bind(*args)``: what to call instead of ``orca_advance`` with those arguments (e.g. its compiled entry point)."""
    a = ORCA_BENCH.batch_args(1, n)
    flt, ints, flags = np.stack([a[0], a[1], a[2], a[4], a[5]]), np.stack([a[3], a[8]]), np.stack([a[6], a[7]])
    start = bench_crowd(n, 1, "grid")
    vec = np.zeros((4, 1, n, 2))
    obst = build_obstacles([])
    speed = np.full((1, n), ORCA_BENCH.max_speed)
    fn = bind(vec, flt, ints, flags, *obst, ORCA_BENCH.dt) if bind else orca_advance
    k = [0]

    def step() -> float:
        if k[0] % 20 == 0:
            vec[:] = 0.0
            vec[0] = start
        k[0] += 1
        vec[2] = preferred_velocity(vec[0], -start, speed, ORCA_BENCH.dt)
        t = time.perf_counter()
        fn(vec, flt, ints, flags, *obst, ORCA_BENCH.dt)
        return time.perf_counter() - t

    return step


def rvo2_step(n: int) -> Callable[[], float]:
    """One Python-RVO2 ``doStep`` of the same ``n`` agents (a fresh simulator every 20 steps); returns its seconds."""
    import rvo2

    start = bench_crowd(n, 1, "grid")[0]
    speed = np.full(n, ORCA_BENCH.max_speed)
    state: dict = {"k": 0}

    def step() -> float:
        if state["k"] % 20 == 0:
            sim = rvo2.PyRVOSimulator(*ORCA_BENCH.simulator_args())
            for p in start:
                sim.addAgent((float(p[0]), float(p[1])))
            sim.processObstacles()
            state["sim"] = sim
        state["k"] += 1
        sim = state["sim"]
        here = np.array([sim.getAgentPosition(i) for i in range(n)])
        pref = preferred_velocity(here, -start, speed, ORCA_BENCH.dt)
        for i in range(n):
            sim.setAgentPrefVelocity(i, (float(pref[i, 0]), float(pref[i, 1])))
        t = time.perf_counter()
        sim.doStep()
        return time.perf_counter() - t

    return step


def noop_args() -> list[np.ndarray]:
    """``orca_advance``'s ten array arguments for one world of 20 agents without obstacles (``dt`` follows)."""
    return ([np.zeros((4, 1, 20, 2)), np.zeros((5, 1, 20)), np.zeros((2, 1, 20), np.int64),
             np.zeros((2, 1, 20), bool)] + list(build_obstacles([])))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    arrs = noop_args()
    print(f"compiled no-op, 11 arguments   {per_call(lambda: _noop11(*arrs, 0.25), 200_000, args.rounds):6.2f} µs")
    print(f"compiled no-op, 1 array        {per_call(lambda: _noop1(arrs[0]), 200_000, args.rounds):6.2f} µs")
    print(f"21 allocations (compiled)      {per_call(lambda: _alloc21(20), 200_000, args.rounds):6.2f} µs")
    try:
        import rvo2  # noqa: F401
    except ImportError:
        rvo2 = None
    for n in (1, 20):
        line = f"N = {n:<3} orca_advance {per_call(ours(n), 20_000, args.rounds, True):6.2f} µs"
        if rvo2 is not None:
            line += f"   RVO2 doStep {per_call(rvo2_step(n), 20_000, args.rounds, True):6.2f} µs"
        print(line)


if __name__ == "__main__":
    main()
