"""How good is a crowd? Goal arrivals and pedestrian–pedestrian contacts, counted from the pedestrians' own
observations in a robot-free PettingZoo episode (``crowdbench crowd-stats``).

* **arrival** — a pedestrian's goal is replaced while it stands within 1 m of the old one (its ``self`` observation
  before the step: [px, py, vx, vy, gx, gy, r, …]); random goal changes elsewhere do not count;
* **contact step** — a pair of pedestrians whose discs overlap after a step (each pair counted once per step).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def crowd_stats(human_model: str, seeds: range | list[int] = range(5), num_humans: int = 20, max_cycles: int = 400,
                human_model_kwargs: dict | None = None) -> dict[str, Any]:
    """Totals over ``seeds`` of ``parallel_env(num_humans, robot=None, max_cycles)`` episodes: ``arrivals``,
    ``contact_steps``, and their means per episode."""
    import crowdbench

    arrivals = contacts = 0
    for seed in seeds:
        env = crowdbench.parallel_env(num_humans=num_humans, robot=None, max_cycles=max_cycles,
                                      human_model=human_model, human_model_kwargs=human_model_kwargs,
                                      human_reward="none")
        obs, _ = env.reset(seed=seed)
        prev = np.stack([obs[a]["self"] for a in env.agents]).astype(np.float64)
        while env.agents:
            agents = list(env.agents)
            obs, *_ = env.step({})
            if not obs:
                break
            me = np.stack([obs[a]["self"] for a in agents]).astype(np.float64)
            replaced = np.linalg.norm(me[:, 4:6] - prev[:, 4:6], axis=1) > 1e-6
            near = np.linalg.norm(prev[:, 0:2] - prev[:, 4:6], axis=1) < 1.0
            arrivals += int((replaced & near).sum())
            d = np.linalg.norm(me[:, None, 0:2] - me[None, :, 0:2], axis=-1) - me[:, None, 6] - me[None, :, 6]
            contacts += int(np.triu(d < 0, 1).sum())
            prev = me
    n = len(seeds)
    return {"model": human_model, "episodes": n, "arrivals": arrivals, "contact_steps": contacts,
            "arrivals_per_episode": arrivals / n, "contact_steps_per_episode": contacts / n}
