"""Does calling ``orca_advance`` through its compiled entry point, past numba's per-call type dispatch, lower the
one-world call floor (issue 46's one-world target at N ≤ 50)?

    PYTHONPATH=. python studies/speed-2026-12-06/advance_entry_point.py [--rounds 3]

numba's dispatcher types all 11 arguments of ``orca_advance`` on every call; the compiled version's entry point
(the private ``Dispatcher.overloads[signature].entry_point``) skips that. Prints µs per call (best of 3 blocks of
20,000 calls, ``perf_counter`` around the call only) of a compiled no-op with the same 11 arguments and of
``orca_advance`` on the lattice crowd of ``bench_orca_rvo2.py`` (N = 1, 20, 50), each through the dispatcher and
through the entry point, alternated in one process.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numba
import numpy as np

from crowdbench.bench import ORCA_BENCH, bench_crowd
from crowdbench.humans import preferred_velocity
from crowdbench.humans.orca_kernel import build_obstacles, orca_advance

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "speed-2026-12-05"))
from call_floor import _noop11, per_call  # noqa: E402


def entry(kernel, *args):
    """The compiled entry point of ``kernel`` for the types of ``args``."""
    sig = tuple(numba.typeof(a) for a in args)
    if sig not in kernel.overloads:
        kernel.compile(sig)
    return kernel.overloads[sig].entry_point


def step(n: int, direct: bool):
    a = ORCA_BENCH.batch_args(1, n)
    flt, ints, flags = np.stack([a[0], a[1], a[2], a[4], a[5]]), np.stack([a[3], a[8]]), np.stack([a[6], a[7]])
    start = bench_crowd(n, 1, "grid")
    vec = np.zeros((4, 1, n, 2))
    obst = build_obstacles([])
    speed = np.full((1, n), ORCA_BENCH.max_speed)
    fn = entry(orca_advance, vec, flt, ints, flags, *obst, ORCA_BENCH.dt) if direct else orca_advance
    k = [0]

    def one() -> float:
        if k[0] % 20 == 0:
            vec[:] = 0.0
            vec[0] = start
        k[0] += 1
        vec[2] = preferred_velocity(vec[0], -start, speed, ORCA_BENCH.dt)
        t = time.perf_counter()
        fn(vec, flt, ints, flags, *obst, ORCA_BENCH.dt)
        return time.perf_counter() - t

    return one


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    arrs = ([np.zeros((4, 1, 20, 2)), np.zeros((5, 1, 20)), np.zeros((2, 1, 20), np.int64),
             np.zeros((2, 1, 20), bool)] + list(build_obstacles([])))
    noop = entry(_noop11, *arrs, 0.25)
    for r in range(args.rounds):
        parts = [f"no-op {per_call(lambda: _noop11(*arrs, 0.25), 200_000, 3):.2f} · "
                 f"{per_call(lambda: noop(*arrs, 0.25), 200_000, 3):.2f}"]
        for n in (1, 20, 50):
            parts.append(f"N = {n}: {per_call(step(n, False), 20_000, 3, True):.2f} · "
                         f"{per_call(step(n, True), 20_000, 3, True):.2f}")
        print(f"round {r + 1} (µs, dispatcher · entry point): " + " | ".join(parts), flush=True)


if __name__ == "__main__":
    main()
