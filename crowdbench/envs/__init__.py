"""Thin adapters over :class:`~crowdbench.worlds.CrowdWorld`: PettingZoo (multi-agent) and Gymnasium (robot)."""

from __future__ import annotations

from crowdbench.envs.gym_env import CrowdNavEnv, register_envs
from crowdbench.envs.parallel import CrowdParallelEnv, env, parallel_env, raw_env

__all__ = ["CrowdNavEnv", "CrowdParallelEnv", "env", "parallel_env", "raw_env", "register_envs"]
