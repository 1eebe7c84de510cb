"""Batched episode runner, shared by ``crowdbench evaluate``, ``tables``, ``leaderboard`` and training's quick
evaluations; the metrics it records are defined in :mod:`crowdbench.metrics`.

Episode ``k`` of an evaluation with seed ``S`` always uses world seed ``S + k``, whatever the batch size, so results
do not depend on how many worlds run at once (for policies without cross-world state).
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable
from typing import Any

import numpy as np

from crowdbench.config import make_config
from crowdbench.humans.base import make as make_model
from crowdbench.metrics import Episode, EpisodeMeter, summarize
from crowdbench.policies.base import RobotPolicy, check_actions
from crowdbench.robots.observations import check_tier, make_observation
from crowdbench.worlds.world import OUTCOMES, CrowdWorld


def run_episodes(policy: RobotPolicy, episodes: int, seed: int = 0, num_worlds: int = 16,
                 layout: str = "circle_crossing", num_humans: int = 20, human_model: Any = "responsive_orca",
                 human_model_kwargs: dict | None = None, counterfactual: bool = False,
                 progress: Callable[[int], None] | None = None, sensing: str | None = None,
                 **world_options: Any) -> list[Episode]:
    """Run ``episodes`` episodes of ``policy`` in a batch of ``num_worlds`` worlds; returns them ordered by seed.

    ``sensing``: the most the robot's sensor may give (a tier of :data:`~crowdbench.robots.observations.SENSING`;
    None: whatever the policy asks for); a policy needing more is one ``ValueError``.

    With ``counterfactual``, a twin batch of the same seeds runs alongside with the robot absent (invisible to the
    pedestrians), for the pedestrians' delay (:mod:`crowdbench.metrics`); it costs a second crowd simulation.
    ``progress`` is called with the number of finished episodes whenever episodes finish.
    """
    if episodes < 1:
        raise ValueError(f"episodes must be ≥ 1, got {episodes}")
    check_tier(policy.observation, sensing)
    config = make_config(num_humans=num_humans, **world_options)
    B = min(num_worlds, episodes)
    model = make_model(human_model, **(human_model_kwargs or {})) if isinstance(human_model, str) else human_model
    twin_model = copy.deepcopy(model) if counterfactual else None
    world = CrowdWorld(config, B, layout, model)
    twin = (CrowdWorld(dataclasses.replace(config, robot_visible=False), B, layout, twin_model)
            if counterfactual else None)
    obs_builder = make_observation(policy.observation, config, **policy.observation_kwargs)
    meter = EpisodeMeter(B, world.dt, config.reward.goal_tolerance)
    next_k = B
    ep_seed = np.arange(B) + seed
    world.reset(seeds=[int(s) for s in ep_seed])
    if twin is not None:
        twin.reset(seeds=[int(s) for s in ep_seed])
    meter.start(np.arange(B), world)
    policy.reset()
    running = np.ones(B, dtype=bool)
    path = np.zeros(B)
    max_dv = np.zeros(B)
    still = np.zeros((B, 2))
    out: list[Episode] = []
    while running.any():
        obs = obs_builder.build(world)
        if policy.stateless and not running.all():  # the batch's tail: finished worlds need no decision
            rows = np.flatnonzero(running)
            action = np.zeros((B, 2))
            action[rows] = check_actions(policy, policy.act({k: v[rows] for k, v in obs.items()}), len(rows))
        else:
            action = check_actions(policy, policy.act(obs), B)
        prev_pos, prev_goal, prev_v = world.pos.copy(), world.goal.copy(), world.vel[:, 0].copy()
        twin_prev = (twin.pos.copy(), twin.goal.copy()) if twin is not None else None
        res = world.step(action)
        if twin is not None:
            twin.step(still)
        meter.update(world, res, prev_pos, prev_v, prev_goal, twin, twin_prev)
        v = world.vel[:, 0]
        path += np.linalg.norm(world.pos[:, 0] - prev_pos[:, 0], axis=-1)
        max_dv = np.maximum(max_dv, np.linalg.norm(v - prev_v, axis=-1))
        done = (res.terminated | res.truncated) & running
        for b in np.flatnonzero(done):
            outcome = OUTCOMES[int(res.outcome[b])]
            out.append(Episode(int(ep_seed[b]), outcome, float(world.steps[b] * world.dt), float(path[b]),
                               float(max_dv[b]), **meter.episode(b, outcome, float(path[b]))))
        if done.any() and progress is not None:
            progress(len(out))
        if done.any():
            restart = done.copy()
            for b in np.flatnonzero(done):
                if next_k < episodes:
                    ep_seed[b] = seed + next_k
                    next_k += 1
                else:
                    running[b] = restart[b] = False
            if restart.any():
                seeds = [int(s) for s in ep_seed[restart]]
                world.reset(seeds=seeds, mask=restart)
                if twin is not None:
                    twin.reset(seeds=seeds, mask=restart)
                meter.start(np.flatnonzero(restart), world)
            policy.reset(done)
            path[done] = 0.0
            max_dv[done] = 0.0
    return sorted(out, key=lambda e: e.seed)


__all__ = ["Episode", "run_episodes", "summarize"]
