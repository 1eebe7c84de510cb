"""Batched episode runner and the paper's six metrics, shared by ``crowdbench demo``/``evaluate`` and leaderboards.

Episode ``k`` of an evaluation with seed ``S`` always uses world seed ``S + k``, whatever the batch size, so results
do not depend on how many worlds run at once (for policies without cross-world state).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from crowdbench.config import make_config
from crowdbench.policies.base import RobotPolicy
from crowdbench.robots.observations import make_observation
from crowdbench.worlds.world import OUTCOMES, CrowdWorld


@dataclass
class Episode:
    """One finished episode."""

    seed: int
    outcome: str
    """``success``, ``collision`` or ``timeout``."""
    time: float
    """Episode duration [s]."""
    path_length: float
    """Robot path length [m]."""
    max_delta_v: float
    """Largest step-to-step change of the robot's velocity vector, ‖v_t − v_{t−1}‖, over the episode, starting from
    rest (v_0 = 0) as in the paper, whose ORCA and SF rows read Δv = 1.00 = v_pref [m/s]."""


def summarize(episodes: list[Episode]) -> dict[str, float]:
    """The paper's columns: success / collision / timeout rates, navigation time and path length (means over
    successful episodes; NaN if none) and Δv (mean over all episodes of ``max_delta_v``)."""
    n = len(episodes)
    if n == 0:
        raise ValueError("summarize needs at least one episode")
    ok = [e for e in episodes if e.outcome == "success"]
    return {
        "episodes": n,
        "success_rate": len(ok) / n,
        "collision_rate": sum(e.outcome == "collision" for e in episodes) / n,
        "timeout_rate": sum(e.outcome == "timeout" for e in episodes) / n,
        "nav_time": float(np.mean([e.time for e in ok])) if ok else float("nan"),
        "path_length": float(np.mean([e.path_length for e in ok])) if ok else float("nan"),
        "delta_v": float(np.mean([e.max_delta_v for e in episodes])),
    }


def run_episodes(policy: RobotPolicy, episodes: int, seed: int = 0, num_worlds: int = 16,
                 layout: str = "circle_crossing", num_humans: int = 20, human_model: Any = "responsive_orca",
                 human_model_kwargs: dict | None = None, **world_options: Any) -> list[Episode]:
    """Run ``episodes`` episodes of ``policy`` in a batch of ``num_worlds`` worlds; returns them ordered by seed."""
    if episodes < 1:
        raise ValueError(f"episodes must be ≥ 1, got {episodes}")
    config = make_config(num_humans=num_humans, **world_options)
    B = min(num_worlds, episodes)
    world = CrowdWorld(config, B, layout, human_model, human_model_kwargs)
    obs_builder = make_observation(policy.observation, config)
    next_k = B
    ep_seed = np.arange(B) + seed
    world.reset(seeds=[int(s) for s in ep_seed])
    policy.reset()
    running = np.ones(B, dtype=bool)
    path = np.zeros(B)
    max_dv = np.zeros(B)
    prev_v = np.zeros((B, 2))
    out: list[Episode] = []
    while running.any():
        action = policy.act(obs_builder.build(world))
        start = world.pos[:, 0].copy()
        res = world.step(action)
        v = world.vel[:, 0]
        path += np.linalg.norm(world.pos[:, 0] - start, axis=-1)
        dv = np.linalg.norm(v - prev_v, axis=-1)
        max_dv = np.maximum(max_dv, dv)
        prev_v = v.copy()
        done = (res.terminated | res.truncated) & running
        for b in np.flatnonzero(done):
            out.append(Episode(int(ep_seed[b]), OUTCOMES[int(res.outcome[b])], float(world.steps[b] * world.dt),
                               float(path[b]), float(max_dv[b])))
        if done.any():
            restart = done.copy()
            for b in np.flatnonzero(done):
                if next_k < episodes:
                    ep_seed[b] = seed + next_k
                    next_k += 1
                else:
                    running[b] = restart[b] = False
            if restart.any():
                world.reset(seeds=[int(s) for s in ep_seed[restart]], mask=restart)
            policy.reset(done)
            path[done] = 0.0
            max_dv[done] = 0.0
            prev_v[done] = 0.0
    return sorted(out, key=lambda e: e.seed)

