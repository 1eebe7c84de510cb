"""ORCA's grid threshold against Python-RVO2: ``orca_batch(..., grid_min=g)`` for several g, alternated with RVO2.

    PYTHONPATH=. python studies/speed-2026-12-05/orca_grid_min.py [--specs 20:circle:1,50:circle:1]
                                                                  [--grid-min 64,32,16]

Each spec is ``N:crowd:worlds`` (``bench_crowd``'s crowds); per round one RVO2 run, then one crowdbench run per
threshold, with ``benchmarks/bench_orca_rvo2.py``'s runs; prints crowdbench / RVO2 per round.
"""

import argparse
import functools
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "benchmarks"))
import bench_orca_rvo2 as bench  # noqa: E402

from crowdbench.bench import bench_crowd  # noqa: E402
from crowdbench.humans.orca_kernel import orca_batch  # noqa: E402

p = argparse.ArgumentParser()
p.add_argument("--specs", default="20:circle:1,50:circle:1,50:circle:64,20:grid:1,50:grid:1,100:circle:1")
p.add_argument("--grid-min", default="64,32,16")
p.add_argument("--rounds", type=int, default=3)
a = p.parse_args()
gms = [int(g) for g in a.grid_min.split(",")]
for spec in a.specs.split(","):
    n, crowd, w = spec.split(":")
    start = bench_crowd(int(n), int(w), crowd)
    ep, st = bench.plan(int(n), int(w), 100_000)
    kernels = {g: functools.partial(orca_batch, grid_min=g) for g in gms}
    for k in kernels.values():
        bench.crowdbench_run(start, 1, 2, kernel=k)
    ratios = {g: [] for g in gms}
    for _ in range(a.rounds):
        peer = bench.rvo2_run(start, ep, st)
        for g, k in kernels.items():
            ratios[g].append(bench.crowdbench_run(start, ep, st, kernel=k) / peer)
    print(spec, " | ".join(f"grid_min {g}: {' '.join(f'{x:.2f}' for x in v)}" for g, v in ratios.items()), flush=True)
