"""Old code against new, in alternation: ORCA agent-steps per CPU second of ``orca_batch`` (and ``orca_advance``).

    git worktree add /tmp/old <commit>
    PYTHONPATH=. python benchmarks/ab_orca.py --old /tmp/old [--rounds 3] [--target 100000]

The cases: one world of 20 people on the jittered lattice and of 200 and 1,000 on the ring
(``crowdbench.bench.bench_crowd``, as ``bench_orca_rvo2.py``: no obstacles), then 200 people crossing the pillar
hall of ``bench_orca_obstacles.py`` at 3 m spacing (364 vertices: the scan) and 1,000 at 4 m (964 vertices: the
tree). Each round runs every case once with ``/tmp/old`` first on ``PYTHONPATH`` and once with this checkout, in
fresh processes, with this checkout's benchmark scripts (``bench_orca_rvo2.crowdbench_run``,
``bench_orca_obstacles.ours``) driving either kernel; the figure is agent-steps per second of process CPU time,
which other work on the machine disturbs less than wall-clock. Only figures of the same round compare.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
CASES = ("lattice-20", "ring-200", "ring-1000", "pillars-200", "pillars-1000")

LOOP = r"""
import json, sys
sys.path.insert(0, sys.argv[1])
import bench_orca_obstacles as bo
import bench_orca_rvo2 as br
from crowdbench.bench import bench_crowd
case, target = sys.argv[2], int(sys.argv[3])
kind, n = case.split("-"); n = int(n)
if kind == "pillars":
    start, polys = bo.pillar_hall(n, 3.0 if n <= 200 else 4.0)
    bo.ours(start, polys, 2)  # compile
    rounds = max(1, target // (20 * n))
    print(json.dumps(1e6 / min(bo.ours(start, polys, 20)[0] for _ in range(rounds))))
else:
    start = bench_crowd(n, 1, "grid" if kind == "lattice" else "circle")
    episodes, steps = br.plan(n, 1, target)
    br.crowdbench_run(start, 1, 2)  # compile
    print(json.dumps(br.crowdbench_run(start, episodes, steps)))
"""


def measure(tree: Path, case: str, target: int) -> float:
    """Agent-steps per CPU second of ``case`` in one fresh process importing crowdbench from ``tree``."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    out = subprocess.run([sys.executable, "-c", LOOP, str(HERE), case, str(target)], env=env, cwd="/", check=True,
                         capture_output=True, text=True).stdout
    return float(json.loads(out.strip().splitlines()[-1]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old", required=True, type=Path, help="checkout of the old code (git worktree)")
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=CASES)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--target", type=int, default=100_000, help="agent-steps per measurement")
    args = ap.parse_args()
    new_tree = HERE.parent
    print(f"{'case':>13} {'round':>5} {'old':>12} {'new':>12} {'new / old':>10}   agent-steps per CPU second")
    for case in args.cases:
        for r in range(args.rounds):
            old, new = measure(args.old, case, args.target), measure(new_tree, case, args.target)
            print(f"{case:>13} {r + 1:>5} {old:12,.0f} {new:12,.0f} {new / old:10.3f}", flush=True)


if __name__ == "__main__":
    main()
