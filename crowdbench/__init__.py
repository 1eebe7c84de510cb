"""crowdbench: a fast, faithful benchmark for robot navigation in dense, uncertain crowds.

Entry points: :func:`parallel_env`, :func:`raw_env` (AEC) and :func:`env` (AEC, wrapped) — PettingZoo, every agent —,
``gymnasium.make("crowdbench/CircleCrossing-v0")``
(robot only; ids registered on import), :class:`~crowdbench.worlds.CrowdWorld` (the batched core).
"""

from __future__ import annotations

from crowdbench.envs import CrowdNavEnv, CrowdParallelEnv, env, parallel_env, raw_env, register_envs

__version__ = "0.3.0"
__all__ = ["CrowdNavEnv", "CrowdParallelEnv", "__version__", "env", "parallel_env", "raw_env"]

register_envs()
