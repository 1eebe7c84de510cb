"""Helpers shared by the PettingZoo and Gymnasium adapters."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from gymnasium import spaces

from crowdbench.config import WorldConfig, make_config
from crowdbench.worlds.world import CrowdWorld, StepResult


def build_world(layout: str, num_humans: int, human_model: Any, human_model_kwargs: dict | None,
                world_options: dict[str, Any]) -> CrowdWorld:
    """One world (batch of one) from keyword options; unknown options raise ``TypeError`` naming the valid ones."""
    config = make_config(num_humans=num_humans, **world_options)
    return CrowdWorld(config, num_worlds=1, layout=layout, human_model=human_model,
                      human_model_kwargs=human_model_kwargs)


def robot_action_space(config: WorldConfig) -> spaces.Box:
    """holonomic: (vx, vy) in [-v_pref, v_pref]² (norm clipped to v_pref); unicycle: (v, ω) in [0, v_pref] × ±ω_max."""
    if config.kinematics == "holonomic":
        v = config.robot_v_pref
        return spaces.Box(-v, v, (2,), np.float32)
    return spaces.Box(np.array([0.0, -config.max_angular_speed], np.float32),
                      np.array([config.robot_v_pref, config.max_angular_speed], np.float32), dtype=np.float32)


def robot_info(world: CrowdWorld, res: StepResult | None, crowd: dict[str, np.ndarray] | None = None) -> dict[str, Any]:
    """The robot's info dict for world 0: outcome, named reward terms, clearance, overlaps, crowd analysis arrays
    (``crowd``: the pedestrian model's ``info()``, fetched here when not given)."""
    info: dict[str, Any] = {} if res is None else res.scalars(0)
    info["time"] = world.steps.item(0) * world.dt
    crowd = world.human_model.info() if crowd is None else crowd
    info["crowd"] = {k: v[0].copy() for k, v in crowd.items()} if crowd else {}
    return info


def config_fields() -> list[str]:
    return [f.name for f in dataclasses.fields(WorldConfig)]


def render_frame(env) -> Any:
    """``render()`` of both adapters: an RGB frame of world 0 with ``render_mode="rgb_array"``, else None."""
    if env.render_mode is None:
        return None
    from crowdbench.render import Renderer

    if env._renderer is None:
        env._renderer = Renderer(env.world)
        env._renderer.record(env.world)
    return env._renderer.frame(env.world)
