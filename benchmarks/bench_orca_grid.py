"""ORCA neighbour search, grid against brute force, in alternation (the kernel's ``grid_min`` argument).

    python benchmarks/bench_orca_grid.py [--steps 20] [--repeats 3]

The crowd of ``crowdbench.bench.orca_agent_steps_per_s`` (people on a circle crossing through its centre; one world;
neighbour distance 10 m, 10 neighbours): agent-steps per second with the grid (the default above 64 agents) and with
brute force (``grid_min`` above N), alternated per repeat, and whether the two give bit-identical velocities.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from crowdbench.humans import preferred_velocity
from crowdbench.humans.orca_kernel import build_obstacles, orca_batch


def run(n: int, steps: int, grid_min: int) -> tuple[float, np.ndarray]:
    rng = np.random.default_rng(0)
    radius = max(4.0, n * 0.8 / (2 * np.pi) * 1.3)
    ang = rng.uniform(0, 2 * np.pi, (1, n))
    pos = radius * np.stack([np.cos(ang), np.sin(ang)], -1) + rng.uniform(-0.3, 0.3, (1, n, 2))
    goal, vel, f = -pos, np.zeros_like(pos), np.ones((1, n))
    args = (0.31 * f, f, 10.0 * f, np.full((1, n), 10, np.int64), 5.0 * f, 5.0 * f, np.ones((1, n), bool),
            np.ones((1, n), bool), np.full((1, n), -1, np.int64))
    obst, out = build_obstacles([]), np.empty_like(pos)
    elapsed = 0.0
    for _ in range(steps):
        pref = preferred_velocity(pos, goal, f, 0.25)
        t = time.perf_counter()
        orca_batch(pos, vel, pref, *args, *obst, 0.25, out, grid_min)
        elapsed += time.perf_counter() - t
        vel = out.copy()
        pos = pos + vel * 0.25
    return steps * n / elapsed, pos


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=20)
    p.add_argument("--repeats", type=int, default=3)
    a = p.parse_args()
    run(100, 2, 64), run(100, 2, 10**9)  # compile
    for n in (20, 50, 100, 200, 500, 1000):
        grid, brute = [], []
        for _ in range(a.repeats):
            g, pg = run(n, a.steps, 64)
            b, pb = run(n, a.steps, 10**9)
            grid.append(g)
            brute.append(b)
        print(f"N = {n:>5}: grid {np.median(grid) / 1e6:.3f} M agent-steps/s, brute force {np.median(brute) / 1e6:.3f}"
              f" M ({np.median(grid) / np.median(brute):.2f}×); identical after {a.steps} steps: "
              f"{np.array_equal(pg, pb)}")


if __name__ == "__main__":
    main()
