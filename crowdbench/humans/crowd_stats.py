"""How good is a crowd? Statistics of a pedestrian model in robot-free PettingZoo episodes, counted from the
pedestrians' own observations (``self`` = [px, py, vx, vy, gx, gy, r, v_pref, θ]; ``crowdbench crowd-stats``).

* **arrival** — a pedestrian's goal is replaced while it stands within 1 m of the old one (its observation before
  the step); random goal changes elsewhere do not count;
* **contact step** — a pair of pedestrians whose discs overlap after a step (each pair counted once per step);
  **collisions per pedestrian-minute** — contact steps × 2 (both people) per minute of pedestrian time;
* **time to goal** — from a pedestrian's (re)spawn to its arrival, over completed trips [s];
* **path irregularity** — mean absolute change of walking direction per step while walking (speed > 0.1 m/s) [rad];
* **speed** — the 50th and 95th percentiles of every pedestrian's speed at every step [m/s].
"""

from __future__ import annotations

from typing import Any

import numpy as np


def crowd_stats(human_model: str, seeds: range | list[int] = range(5), num_humans: int = 20, max_cycles: int = 400,
                human_model_kwargs: dict | None = None) -> dict[str, Any]:
    """Totals and means over ``seeds`` of ``parallel_env(num_humans, robot=None, max_cycles)`` episodes (module
    docstring)."""
    import crowdbench

    arrivals = contacts = 0
    trips: list[float] = []
    turns: list[np.ndarray] = []
    speeds: list[np.ndarray] = []
    ped_seconds = 0.0
    for seed in seeds:
        env = crowdbench.parallel_env(num_humans=num_humans, robot=None, max_cycles=max_cycles,
                                      human_model=human_model, human_model_kwargs=human_model_kwargs,
                                      human_reward="none")
        obs, _ = env.reset(seed=seed)
        dt = env.config.time_step
        prev = np.stack([obs[a]["self"] for a in env.agents]).astype(np.float64)
        since = np.zeros(len(prev))  # time since each pedestrian's (re)spawn [s]
        while env.agents:
            agents = list(env.agents)
            obs, *_ = env.step({})
            if not obs:
                break
            me = np.stack([obs[a]["self"] for a in agents]).astype(np.float64)
            since += dt
            ped_seconds += dt * len(me)
            replaced = np.linalg.norm(me[:, 4:6] - prev[:, 4:6], axis=1) > 1e-6
            arrived = replaced & (np.linalg.norm(prev[:, 0:2] - prev[:, 4:6], axis=1) < 1.0)
            arrivals += int(arrived.sum())
            trips += since[arrived].tolist()
            since[arrived] = 0.0
            d = np.linalg.norm(me[:, None, 0:2] - me[None, :, 0:2], axis=-1) - me[:, None, 6] - me[None, :, 6]
            contacts += int(np.triu(d < 0, 1).sum())
            v, v0 = me[:, 2:4], prev[:, 2:4]
            s, s0 = np.linalg.norm(v, axis=1), np.linalg.norm(v0, axis=1)
            speeds.append(s[~arrived])
            walking = (s > 0.1) & (s0 > 0.1) & ~arrived
            turn = np.arctan2(v[:, 1], v[:, 0]) - np.arctan2(v0[:, 1], v0[:, 0])
            turns.append(np.abs((turn + np.pi) % (2 * np.pi) - np.pi)[walking])
            prev = me
    n = len(seeds)
    sp = np.concatenate(speeds) if speeds else np.zeros(1)
    return {"model": human_model, "episodes": n, "arrivals": arrivals, "contact_steps": contacts,
            "arrivals_per_episode": arrivals / n, "contact_steps_per_episode": contacts / n,
            "collisions_per_ped_minute": 2 * contacts / max(ped_seconds / 60, 1e-9),
            "time_to_goal_s": float(np.mean(trips)) if trips else float("nan"),
            "path_irregularity_rad": float(np.concatenate(turns).mean()) if turns else float("nan"),
            "speed_p50": float(np.percentile(sp, 50)), "speed_p95": float(np.percentile(sp, 95))}
