"""ORCA kernel throughput (agent-steps per second), one core, 64 worlds, agents on a circle crossing.

    python benchmarks/bench_orca.py [--quick]

Times :func:`crowdbench.humans.orca_kernel.orca_batch` alone (neighbour search, half-planes, linear programs)
while the crowd evolves (positions integrated between calls, outside the timing). Reference: the C++ RVO2 library
does ~700,000 agent-steps/s at 20 agents on this machine (DEVELOPERS.md).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from common import machine, pin_one_core

from crowdbench.humans import preferred_velocity
from crowdbench.humans.orca_kernel import build_obstacles, orca_batch


def agent_steps_per_s(n: int, worlds: int, steps: int, seed: int = 0) -> tuple[float, float]:
    rng = np.random.default_rng(seed)
    radius_circle = max(4.0, n * 0.8 / (2 * np.pi) * 1.3)
    ang = rng.uniform(0, 2 * np.pi, (worlds, n))
    pos = radius_circle * np.stack([np.cos(ang), np.sin(ang)], -1) + rng.uniform(-0.3, 0.3, (worlds, n, 2))
    goal = -pos
    vel = np.zeros_like(pos)
    f = np.ones((worlds, n))
    args = (0.31 * f, 1.0 * f, 10.0 * f, np.full((worlds, n), 10, np.int64), 5.0 * f, 5.0 * f,
            np.ones((worlds, n), bool), np.ones((worlds, n), bool), np.full((worlds, n), -1, np.int64))
    obst = build_obstacles([])
    out = np.empty_like(pos)
    times = []
    for k in range(steps + 3):
        pref = preferred_velocity(pos, goal, f, 0.25)
        t = time.perf_counter()
        orca_batch(pos, vel, pref, *args, *obst, 0.25, out)
        if k >= 3:
            times.append(time.perf_counter() - t)
        vel = out.copy()
        pos = pos + vel * 0.25
    per_call = np.array(times)
    rates = worlds * n / per_call
    return float(np.median(rates)), float(rates.max() - rates.min())


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true")
    args = p.parse_args()
    pin_one_core()
    print(f"machine: {machine()}; pinned to 1 core")
    print(f"{'agents/world':>13} {'worlds':>7} {'agent-steps/s (median)':>24} {'spread':>12}")
    for n in (20, 50, 200):
        steps = (20 if args.quick else 120) if n < 200 else (5 if args.quick else 30)
        med, spread = agent_steps_per_s(n, 64, steps)
        print(f"{n:>13} {64:>7} {med:>24,.0f} {spread:>12,.0f}")


if __name__ == "__main__":
    main()
