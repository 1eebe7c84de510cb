"""Single-agent Gymnasium view of one crowd world: the robot acts, pedestrians follow their model.

Registered ids (after ``import crowdbench``): ``crowdbench/CircleCrossing-v0``, ``crowdbench/SquareCrossing-v0``,
``crowdbench/Intersection-v0``, ``crowdbench/SplitFlow-v0``, ``crowdbench/RandomWander-v0``. Keyword arguments are
those of :class:`CrowdNavEnv`, e.g. ``gymnasium.make("crowdbench/CircleCrossing-v0", num_humans=20)``.

Observation: the robot's dict observation (``relative`` by default); action: planar velocity [m/s] (or (v, ω));
reward: the paper's; ``terminated`` on success or collision, ``truncated`` at the time limit (the world owns it, so
no ``TimeLimit`` wrapper is added); ``info`` as the robot's in the PettingZoo env (outcome, reward terms, ...).
Seeding: ``reset(seed=s)`` starts exactly the episode that ``parallel_env(...).reset(seed=s)`` starts.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np

from crowdbench.envs.common import build_world, render_frame, robot_action_space, robot_info
from crowdbench.robots.observations import make_observation

LAYOUT_IDS = {
    "circle_crossing": "CircleCrossing",
    "square_crossing": "SquareCrossing",
    "intersection": "Intersection",
    "split_flow": "SplitFlow",
    "random_wander": "RandomWander",
}


class CrowdNavEnv(gymnasium.Env):
    """Robot navigation among pedestrians (see the module docstring)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(self, layout: str = "circle_crossing", num_humans: int = 20, human_model: Any = "responsive_orca",
                 observation: str = "relative", render_mode: str | None = None,
                 human_model_kwargs: dict | None = None, **world_options: Any) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode={render_mode!r}; valid choices: None, 'rgb_array'")
        self.world = build_world(layout, num_humans, human_model, human_model_kwargs, world_options)
        self._obs_builder = make_observation(observation, self.world.config)
        self.observation_space = self._obs_builder.space()
        self.action_space = robot_action_space(self.world.config)
        self.render_mode = render_mode
        self._renderer = None

    def _obs(self) -> dict[str, np.ndarray]:
        return {k: v[0] for k, v in self._obs_builder.build(self.world).items()}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        episode_seed = seed if seed is not None else int(self.np_random.integers(2**63 - 1))
        self.world.reset(seeds=[episode_seed])
        if self._renderer is not None:
            self._renderer.clear()
            self._renderer.record(self.world)
        return self._obs(), robot_info(self.world, None)

    def step(self, action):
        res = self.world.step(np.asarray(action, dtype=np.float64).reshape(1, 2))
        if self._renderer is not None:
            self._renderer.record(self.world)
        return (self._obs(), float(res.reward[0]), bool(res.terminated[0]), bool(res.truncated[0]),
                robot_info(self.world, res))

    def render(self):
        return render_frame(self)


def register_envs() -> None:
    """Register one Gymnasium id per layout (idempotent)."""
    for layout, name in LAYOUT_IDS.items():
        env_id = f"crowdbench/{name}-v0"
        if env_id not in gymnasium.registry:
            gymnasium.register(env_id, entry_point="crowdbench.envs.gym_env:CrowdNavEnv", kwargs={"layout": layout},
                               disable_env_checker=False)
