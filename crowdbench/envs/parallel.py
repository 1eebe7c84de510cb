"""PettingZoo ParallelEnv: the robot and every pedestrian are agents of one crowd world.

Agents: ``possible_agents = ["robot", "human_0", ..., "human_{H-1}"]``; ``agents`` holds the robot and the
pedestrians present this episode (fewer when ``humans_range`` draws a smaller crowd).

Actions: every agent's action is a planar velocity [m/s] (the robot's is (v, ω) with ``kinematics="unicycle"``).
**A pedestrian given an action in ``step()`` follows it; a pedestrian left out of the actions dict is driven by the
world's pedestrian model** — so ``env.step({"robot": a})`` runs the usual benchmark, and any subset of pedestrians
can be driven from outside (multi-agent testbed). The robot's action is required.

Observations: the robot's comes from the ``observation`` builder (``relative`` — the paper's — or ``full_state``,
see :mod:`crowdbench.robots.observations`); each pedestrian observes itself ([px, py, vx, vy, gx, gy, r, v_pref, θ])
and its neighbours within ``human_sensing_range`` ((Δx, Δy, vx, vy, r), nearest first, with a mask).

Rewards: the robot's is the paper's reward (terms in ``infos["robot"]["reward_terms"]``); pedestrians get 0.

Episode end: on the robot's success or collision the robot is *terminated* and every pedestrian *truncated*; at the
time limit (``time_limit``, or ``max_cycles`` steps if set) everyone is truncated. Pedestrians never leave early:
a pedestrian reaching its goal gets a new one from the layout.

Arguments: ``layout``, ``num_humans``, ``human_model`` (name or instance), ``human_model_kwargs``, ``seed`` (used
by the first ``reset()`` without a seed), ``render_mode`` (``"rgb_array"``), ``observation`` (and its builder's
``observation_kwargs``), ``sensing`` (the most the robot's sensor gives, a tier of
:data:`~crowdbench.robots.observations.SENSING`: an ``observation`` needing more is one ``ValueError``; None: no
limit), ``max_cycles``, and any :class:`~crowdbench.config.WorldConfig` field as a keyword.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from crowdbench.envs.common import build_world, render_frame, robot_action_space, robot_info
from crowdbench.robots.observations import agent_observations, check_tier, human_observation_space, make_observation


class CrowdParallelEnv(ParallelEnv):
    """See the module docstring."""

    metadata = {"name": "crowdbench_v0", "render_modes": ["rgb_array"], "render_fps": 4, "is_parallelizable": True}

    def __init__(self, layout: str = "circle_crossing", num_humans: int = 20, human_model: Any = "orca",
                 seed: int | None = None, render_mode: str | None = None, observation: str = "relative",
                 max_cycles: int | None = None, human_model_kwargs: dict | None = None,
                 observation_kwargs: dict | None = None, sensing: str | None = None, **world_options: Any):
        check_tier(observation, sensing)  # the robot's observation needs no more than the sensor gives
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode={render_mode!r}; valid choices: None, 'rgb_array'")
        if max_cycles is not None and (not isinstance(max_cycles, (int, np.integer)) or isinstance(max_cycles, bool)
                                       or max_cycles < 1):
            raise ValueError(f"max_cycles={max_cycles!r}; valid choices: None or an integer ≥ 1")
        if seed is not None and (not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0):
            raise ValueError(f"seed={seed!r}; valid choices: None or an integer ≥ 0")
        self.world = build_world(layout, num_humans, human_model, human_model_kwargs, world_options)
        self.config = self.world.config
        self.render_mode = render_mode
        self.max_cycles = max_cycles
        self._obs_builder = make_observation(observation, self.config, **(observation_kwargs or {}))
        self._seed = seed
        H = self.world.num_humans
        self.possible_agents = ["robot"] + [f"human_{i}" for i in range(H)]
        self.agents = list(self.possible_agents)
        self._renderer = None
        self._state_space = spaces.Box(-1e5, 1e5, (len(self.possible_agents) * 7,), np.float32)

    # spaces must be the same object on every call
    @functools.cache  # noqa: B019
    def observation_space(self, agent: str) -> spaces.Space:
        if agent == "robot":
            return self._obs_builder.space()
        self._check_agent(agent)
        return human_observation_space(self.config)

    @functools.cache  # noqa: B019
    def action_space(self, agent: str) -> spaces.Space:
        if agent == "robot":
            return robot_action_space(self.config)
        self._check_agent(agent)
        v = self.config.human_v_pref
        return spaces.Box(-v, v, (2,), np.float32)

    @property
    def state_space(self) -> spaces.Box:
        return self._state_space

    def _check_agent(self, agent: str) -> None:
        if agent not in self.possible_agents:
            raise ValueError(f"unknown agent {agent!r}; valid: 'robot', 'human_0' … 'human_{self.world.num_humans-1}'")

    # ------------------------------------------------------------------ API
    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is None:
            seed, self._seed = self._seed, None
        self.world.reset(seeds=[seed])
        self._cycles = 0
        n = int(self.world.active[0, 1:].sum())
        self.agents = ["robot"] + [f"human_{i}" for i in range(n)]
        if self._renderer is not None:
            self._renderer.clear()
        obs = self._observations()
        infos = {a: {} for a in self.agents}
        infos["robot"] = robot_info(self.world, None, self.world.human_model.info())
        return obs, infos

    def step(self, actions: dict[str, Any]):
        if "robot" not in actions:
            raise ValueError("actions must include 'robot' (pedestrians left out are driven by the pedestrian model)")
        human_actions = override = None
        if len(actions) > 1:
            H = self.world.num_humans
            human_actions, override = np.zeros((1, H, 2)), np.zeros((1, H), dtype=bool)
            for agent, act in actions.items():
                if agent == "robot" or act is None:
                    continue
                if agent not in self.agents:
                    raise ValueError(f"action for {agent!r}, which is not a live agent; live agents: {self.agents}")
                i = int(agent.split("_")[1])
                human_actions[0, i] = np.asarray(act, dtype=np.float64).reshape(2)
                override[0, i] = True
        res = self.world.step(actions["robot"], human_actions, override)
        self._cycles += 1
        robot_done, trunc = res.done(0)
        trunc = trunc or (self.max_cycles is not None and self._cycles >= self.max_cycles)
        obs = self._observations()
        agents = self.agents
        rewards = dict.fromkeys(agents, 0.0)
        rewards["robot"] = res.reward.item(0)
        terminations = dict.fromkeys(agents, False)
        terminations["robot"] = robot_done
        truncations = dict.fromkeys(agents, trunc or robot_done)
        truncations["robot"] = trunc and not robot_done
        crowd = self.world.human_model.info()
        infos = self._human_infos(crowd)
        infos["robot"] = robot_info(self.world, res, crowd)
        if self._renderer is not None:
            self._renderer.record(self.world)
        if robot_done or trunc:
            self.agents = []
        return obs, rewards, terminations, truncations, infos

    def _observations(self) -> dict[str, dict[str, np.ndarray]]:
        """Every live agent's observation: views into one batched array per field (``agents[1:]`` are
        ``human_0 … human_{n-1}`` in order, so row ``i`` belongs to ``human_i``)."""
        robot, h = agent_observations(self._obs_builder, self.world)
        obs = {"robot": {k: v[0] for k, v in robot.items()}}
        if len(self.agents) > 1:
            for agent, me, nb, mask in zip(self.agents[1:], h["self"], h["neighbors"], h["mask"], strict=False):
                obs[agent] = {"self": me, "neighbors": nb, "mask": mask}
        return obs

    def _human_infos(self, crowd: dict[str, np.ndarray]) -> dict[str, dict[str, Any]]:
        """Per pedestrian: the model's analysis values (``crowd``: arrays ``(B, H)``) as Python scalars."""
        if not crowd:
            return {agent: {} for agent in self.agents[1:]}
        keys = list(crowd)
        columns = [crowd[k][0].tolist() for k in keys]
        return {agent: dict(zip(keys, values, strict=True))
                for agent, *values in zip(self.agents[1:], *columns, strict=False)}

    def state(self) -> np.ndarray:
        """Global state ``(A * 7,)``: per agent [px, py, vx, vy, gx, gy, r] (robot first; padding slots parked)."""
        w = self.world
        return np.concatenate([w.pos[0], w.vel[0], w.goal[0], w.radius[0, :, None]], 1).astype(np.float32).ravel()

    def render(self):
        return render_frame(self)

    def close(self) -> None:
        self._renderer = None


def parallel_env(**kwargs: Any) -> CrowdParallelEnv:
    """``crowdbench.parallel_env(layout="circle_crossing", num_humans=20, human_model="orca", ...)``."""
    return CrowdParallelEnv(**kwargs)
