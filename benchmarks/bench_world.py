"""World throughput: µs per world-step (world step + robot observation), and layout placement time.

    python benchmarks/bench_world.py [--quick]

One core (pinned). "no model" uses a zero-cost pedestrian model (a fixed velocity array) so the figure is the
world alone: action clipping, swept collision checks, pymunk synchronisation and integration, reward, pedestrian
overlap counting, goal renewal and the `relative` robot observation. Medians of 7 repeats, spread = max - min.
"""

from __future__ import annotations

import argparse

import numpy as np
from common import ConstantVelocity, machine, pin_one_core, time_it

from crowdbench.config import WorldConfig
from crowdbench.robots import make_observation
from crowdbench.worlds import LAYOUTS, CrowdWorld, make_layout


def world_step_us(n: int, batch: int, model, steps: int) -> tuple[float, float]:
    w = CrowdWorld(WorldConfig(num_humans=n, time_limit=1e9), batch, "circle_crossing", model)
    obs = make_observation("relative", w.config)
    action = np.tile([0.0, 0.5], (batch, 1))
    w.step(action)  # warm-up (numba compile for ORCA models)

    def run():
        for _ in range(steps):
            w.step(action)
            obs.build(w)

    med, spread = time_it(run)
    scale = 1e6 / (steps * batch)
    return med * scale, spread * scale


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true")
    args = p.parse_args()
    pin_one_core()
    steps = 20 if args.quick else 100
    print(f"machine: {machine()}; pinned to 1 core")
    print("\nworld step + robot observation, µs per world-step (median [spread])")
    print(f"{'N':>4} {'batch':>6} {'no model':>18} {'responsive_orca':>18} {'env-steps/s (resp.)':>20}")
    for n in (10, 20, 30, 50):
        for batch in (1, 64):
            st = steps * (8 if batch == 1 else 1)
            a = world_step_us(n, batch, ConstantVelocity(), st)
            b = world_step_us(n, batch, "responsive_orca", st)
            print(f"{n:>4} {batch:>6} {a[0]:>10.1f} [{a[1]:5.1f}] {b[0]:>10.1f} [{b[1]:5.1f}] {1e6 / b[0]:>20,.0f}")
    print("\nplacement of 30 pedestrians, ms per episode reset (median of 200 placements)")
    for name in LAYOUTS.names():
        lay = make_layout(name)
        rng = np.random.default_rng(0)
        med, spread = time_it(lambda lay=lay, rng=rng: lay.sample(rng, 30, 0.3, 0.3), repeats=200)
        print(f"  {name:<16} {med * 1e3:6.2f} ms [spread {spread * 1e3:.2f}]")


if __name__ == "__main__":
    main()
