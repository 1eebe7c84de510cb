"""Old code against new, in alternation: µs per ``env.step`` of one PettingZoo world (resets excluded).

    git worktree add /tmp/old <commit>
    python benchmarks/ab_one_world.py --old /tmp/old [--n 5] [--rounds 3] [--steps 6000]

Each round runs the same loop once with ``/tmp/old`` first on ``PYTHONPATH`` and once with this checkout, in fresh
processes pinned to one core, and prints the best of three passes for each (µs per step, 1,000 warm-up steps). The
robot heads for its goal at full speed (computed outside the timer); a finished episode is reset outside the timer.
This machine's speed drifts from minute to minute, so only figures from the same round compare; pause other work on
the machine while it runs.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

LOOP = r"""
import os, sys, time
import numpy as np
os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
import crowdbench

def bench(env, steps):
    obs, _ = env.reset(seed=0)
    episodes, total, n = 0, 0.0, 0
    for i in range(steps):
        d = env.world.goal[0, 0] - env.world.pos[0, 0]
        a = {"robot": d / max(float(np.hypot(d[0], d[1])), 1e-9)}
        t = time.perf_counter()
        obs, _, term, trunc, _ = env.step(a)
        dt = time.perf_counter() - t
        if i >= 1000:
            total, n = total + dt, n + 1
        if term["robot"] or trunc["robot"]:
            episodes += 1
            obs, _ = env.reset(seed=episodes)
    return total / n * 1e6

env = crowdbench.parallel_env(num_humans=int(sys.argv[1]))
print(min(bench(env, int(sys.argv[2])) for _ in range(3)))
"""


def run(tree: Path | None, n: int, steps: int) -> float:
    env = dict(os.environ)
    if tree is not None:
        env["PYTHONPATH"] = str(tree) + os.pathsep + env.get("PYTHONPATH", "")
    out = subprocess.run([sys.executable, "-c", LOOP, str(n), str(steps)], env=env, cwd="/", check=True,
                         capture_output=True, text=True).stdout
    return float(out.split()[-1])


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--old", type=Path, required=True, help="checkout of the old code (a git worktree)")
    p.add_argument("--n", type=int, default=5, help="pedestrians")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--steps", type=int, default=6000)
    args = p.parse_args()
    here = Path(__file__).resolve().parents[1]
    for r in range(args.rounds):
        old, new = run(args.old, args.n, args.steps), run(here, args.n, args.steps)
        print(f"round {r + 1}: old {old:.1f} µs, new {new:.1f} µs per env.step (N = {args.n}), ratio {old / new:.2f}")


if __name__ == "__main__":
    main()
