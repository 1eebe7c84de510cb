"""ORCA's grid cell size against Python-RVO2: copies of ``crowdbench/humans/orca_kernel.py`` with another
``GRID_PER_CELL`` (uncached), alternated with RVO2.

    PYTHONPATH=. python studies/speed-2026-12-05/orca_per_cell.py [--per-cell 2,3,4] [--specs 200:circle:1,...]
"""

import argparse
import importlib.util
import os
import re
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "benchmarks"))
import bench_orca_rvo2 as bench  # noqa: E402

from crowdbench.bench import bench_crowd  # noqa: E402

p = argparse.ArgumentParser()
p.add_argument("--per-cell", default="2,3,4")
p.add_argument("--specs", default="50:circle:64,50:grid:64,100:circle:64,20:circle:64,200:circle:1,1000:circle:1,"
                                  "200:grid:1,1000:grid:1,100:circle:1,50:circle:1,50:grid:1")
p.add_argument("--rounds", type=int, default=3)
a = p.parse_args()
with open(os.path.join(HERE, "..", "..", "crowdbench", "humans", "orca_kernel.py")) as f:
    src = f.read().replace("cache=True", "cache=False")
tmp = tempfile.mkdtemp()
kernels = {}
for pc in a.per_cell.split(","):
    path = os.path.join(tmp, f"orca_pc{pc}.py")
    with open(path, "w") as f:
        f.write(re.sub(r"^GRID_PER_CELL = [\d.]+", f"GRID_PER_CELL = {float(pc)}", src, flags=re.M))
    spec = importlib.util.spec_from_file_location(f"orca_pc{pc}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    kernels[pc] = mod.orca_batch
for s in a.specs.split(","):
    n, crowd, w = s.split(":")
    start = bench_crowd(int(n), int(w), crowd)
    ep, st = bench.plan(int(n), int(w), 100_000)
    for k in kernels.values():
        bench.crowdbench_run(start, 1, 2, kernel=k)
    ratios = {pc: [] for pc in kernels}
    for _ in range(a.rounds):
        peer = bench.rvo2_run(start, ep, st)
        for pc, k in kernels.items():
            ratios[pc].append(bench.crowdbench_run(start, ep, st, kernel=k) / peer)
    print(s, " | ".join(f"per_cell {pc}: {' '.join(f'{x:.2f}' for x in v)}" for pc, v in ratios.items()), flush=True)
