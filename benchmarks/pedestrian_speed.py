"""Pedestrian speed distribution of the default crowd against the former (calibrated) one.

    python benchmarks/pedestrian_speed.py [--worlds 32] [--steps 200] [--seed 12345]

Prints the 50th / 95th / 99th percentiles of every active pedestrian's speed over all steps [m/s], with the robot
standing at its start (latent-responsive ORCA, ρ = 0.5). CrowdNav++'s pedestrians cruise at min(1, v_pref).
"""

from __future__ import annotations

import argparse

import numpy as np

from crowdbench.config import WorldConfig
from crowdbench.worlds import CrowdWorld

CROWDS = {
    "circle_crossing (CrowdNav++)": ("circle_crossing", {}),
    "circle_crossing_calibrated (former)": ("circle_crossing_calibrated",
                                            {"preferred_speed": None, "neighbor_dist_range": None}),
}


def speeds(layout: str, model: dict, worlds: int, steps: int, seed: int) -> np.ndarray:
    w = CrowdWorld(WorldConfig(time_limit=1e9), worlds, layout, "responsive_orca", {"responsiveness": 0.5, **model})
    w.reset(seeds=[seed + k for k in range(worlds)])
    out = []
    for _ in range(steps):
        w.step(np.zeros((worlds, 2)))
        out.append(np.linalg.norm(w.vel[:, 1:], axis=-1)[w.active[:, 1:]])
    return np.concatenate(out)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--worlds", type=int, default=32)
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--seed", type=int, default=12345)
    a = p.parse_args()
    for name, (layout, model) in CROWDS.items():
        q = np.percentile(speeds(layout, model, a.worlds, a.steps, a.seed), [50, 95, 99])
        print(f"{name:<38} p50 {q[0]:.3f}  p95 {q[1]:.3f}  p99 {q[2]:.3f} m/s")


if __name__ == "__main__":
    main()
