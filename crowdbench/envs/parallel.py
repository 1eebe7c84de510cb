"""PettingZoo ParallelEnv: the robot and every pedestrian are agents of one crowd world.

Agents: ``possible_agents = ["robot", "human_0", ..., "human_{H-1}"]`` (no ``"robot"`` with ``robot=None``);
``agents`` holds those present this episode (fewer pedestrians when ``humans_range`` draws a smaller crowd).

**Actions.** The robot's is a planar velocity [m/s] (``(v, ω)`` with ``kinematics="unicycle"``). A pedestrian's is
*normalised*: ``Box(-1, 1, (2,))``, mapped onto the disc of its own speed limit by the elliptical grid map
``v = v_pref · (a_x·√(1 − a_y²/2), a_y·√(1 − a_x²/2))`` — a bijection of the square onto the disc, so every action
is a distinct velocity and nothing is clipped; an action outside the box is an error. A pedestrian given an action
follows it; one left out of the actions dict is driven by the world's pedestrian model (when every pedestrian is
driven from outside the model is not stepped at all). So ``env.step({"robot": a})`` runs the usual benchmark.

**Robot** (``robot=``): ``"agent"`` (default) — an agent whose action is required; ``None`` — no robot (parked far
away, invisible; pure crowd episodes); or a registered robot policy name (:data:`crowdbench.policies.POLICIES`) —
driven inside the env, not an agent.

**Observations.** The robot's comes from the ``observation`` builder (:mod:`crowdbench.robots.observations`); each
pedestrian observes itself ([px, py, vx, vy, gx, gy, r, v_pref, θ]) and its neighbours within
``human_sensing_range`` ((Δx, Δy, vx, vy, r), nearest first, with a mask). ``flat_observations=True`` (for vectorised
MARL: SuperSuit, Gymnasium vector envs): every agent, robot included, observes ``Box`` = the pedestrians' layout
flattened (self 9, neighbours N_max·5, mask N_max) and acts in ``Box(-1, 1, (2,))`` (the robot's mapped like a
pedestrian's onto its own speed disc), and the agent set stays constant through an episode: an agent that is done
keeps receiving zero observations and zero reward until the episode ends (SuperSuit's convention).

**Rewards.** The robot's is the paper's (terms in ``infos["robot"]["reward_terms"]``); pedestrians earn the
``human_reward`` plug-in's (default ``progress``, :mod:`crowdbench.humans.rewards`; terms in
``infos["human_i"]["reward_terms"]``).

**Episode end.** On the robot's success or collision the robot is *terminated* and every pedestrian *truncated*;
after ``max_cycles`` steps (PettingZoo's meaning: the episode length; it replaces ``time_limit`` unless that is
given too), or at ``time_limit``, everyone is truncated. With ``pedestrians_finish=True`` a pedestrian reaching its
goal or touching someone is *terminated* and leaves the world; otherwise a pedestrian reaching its goal gets a new
one from the layout.

Other arguments: ``layout``, ``num_humans``, ``human_model`` (name or instance), ``human_model_kwargs``, ``seed``
(used by the first ``reset()`` without one), ``render_mode`` (``"rgb_array"``), ``observation_kwargs``, ``sensing``
(the most the robot's sensor gives, a tier of :data:`~crowdbench.robots.observations.SENSING`), and any
:class:`~crowdbench.config.WorldConfig` field. Environments pickle, deep-copy and restore to an identical state.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from crowdbench.envs.common import build_world, render_frame, robot_action_space, robot_info
from crowdbench.humans.rewards import Before, NoReward, contacts, make_reward
from crowdbench.robots.observations import (
    agent_observations,
    check_tier,
    human_observation_space,
    make_observation,
)
from crowdbench.worlds._kernels import agent_observations_batch, drive_actions
from crowdbench.worlds.world import PARK

ROBOT_MODES = ("agent", None, "a registered robot policy name")


def disc_velocity(action: np.ndarray, v_max: np.ndarray) -> np.ndarray:
    """Normalised actions ``(..., 2)`` in [−1, 1]² → velocities ``(..., 2)`` [m/s] inside the disc of radius
    ``v_max`` ``(...)``: the elliptical grid map (a bijection of the square onto the disc)."""
    x, y = action[..., 0], action[..., 1]
    v = np.stack([x * np.sqrt(1.0 - 0.5 * y * y), y * np.sqrt(1.0 - 0.5 * x * x)], -1)
    return v * np.asarray(v_max)[..., None]


def square(v: np.ndarray) -> np.ndarray:
    """The inverse of :func:`disc_velocity` for ``v_max = 1``: points ``(..., 2)`` of the unit disc → the normalised
    actions in [−1, 1]² that map onto them (the elliptical grid map's inverse, Fong 2015)."""
    u, w = v[..., 0], v[..., 1]
    s = u * u - w * w
    t1 = np.sqrt(np.maximum(2.0 + s + 2.0 * np.sqrt(2.0) * u, 0.0))
    t2 = np.sqrt(np.maximum(2.0 + s - 2.0 * np.sqrt(2.0) * u, 0.0))
    t3 = np.sqrt(np.maximum(2.0 - s + 2.0 * np.sqrt(2.0) * w, 0.0))
    t4 = np.sqrt(np.maximum(2.0 - s - 2.0 * np.sqrt(2.0) * w, 0.0))
    return np.clip(np.stack([0.5 * (t1 - t2), 0.5 * (t3 - t4)], -1), -1.0, 1.0)


def check_normalised(agent: str, action: np.ndarray) -> np.ndarray:
    """``action`` as a float64 ``(2,)`` inside [−1, 1]², else one ``ValueError`` naming the agent."""
    a = np.asarray(action, dtype=np.float64).reshape(2)
    if not (np.isfinite(a).all() and (np.abs(a) <= 1.0 + 1e-6).all()):
        raise ValueError(f"action for {agent!r} = {a.tolist()}; valid choices: two numbers in [-1, 1] (normalised: "
                         "mapped onto the agent's speed disc)")
    return np.clip(a, -1.0, 1.0)


def _columns(values: dict[str, np.ndarray], names: list[str], slots: np.ndarray):
    """Per slot of ``slots`` ``(n,)``, a tuple of ``values[name][0, slot]`` over ``names`` as Python scalars of the
    arrays' common dtype (what ``np.stack(...).tolist()`` gives, without building the rows in numpy): one list per
    name, zipped (the per-agent dicts are then built in comprehensions, the agent-steps' only Python)."""
    if not names:
        return ()
    dtype = np.result_type(*(values[k] for k in names))
    return zip(*[values[k][0, slots].astype(dtype, copy=False).tolist() for k in names], strict=True)


class CrowdParallelEnv(ParallelEnv):
    """See the module docstring."""

    metadata = {"name": "crowdbench_v0", "render_modes": ["rgb_array"], "render_fps": 4, "is_parallelizable": True}

    def __init__(self, layout: str = "circle_crossing", num_humans: int = 20, human_model: Any = "orca",
                 seed: int | None = None, render_mode: str | None = None, observation: str = "relative",
                 max_cycles: int | None = None, human_model_kwargs: dict | None = None,
                 observation_kwargs: dict | None = None, sensing: str | None = None, robot: str | None = "agent",
                 flat_observations: bool = False, human_reward: Any = "progress",
                 pedestrians_finish: bool = False, **world_options: Any):
        check_tier(observation, sensing)  # the robot's observation needs no more than the sensor gives
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode={render_mode!r}; valid choices: None, 'rgb_array'")
        if max_cycles is not None and (not isinstance(max_cycles, (int, np.integer)) or isinstance(max_cycles, bool)
                                       or max_cycles < 1):
            raise ValueError(f"max_cycles={max_cycles!r}; valid choices: None or an integer ≥ 1")
        if seed is not None and (not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0):
            raise ValueError(f"seed={seed!r}; valid choices: None or an integer ≥ 0")
        for name, flag in (("flat_observations", flat_observations), ("pedestrians_finish", pedestrians_finish)):
            if not isinstance(flag, bool):
                raise ValueError(f"{name}={flag!r}; valid choices: True, False")
        self._robot_policy = None
        if robot is not None and robot != "agent":
            from crowdbench.policies import POLICIES, make_policy

            if robot not in POLICIES.names():
                raise ValueError(f"robot={robot!r}; valid choices: 'agent', None, or a registered robot policy "
                                 f"({', '.join(POLICIES.names())})")
        if robot is None:
            world_options = {**world_options, "robot_visible": False}
        if max_cycles is not None and "time_limit" not in world_options:
            world_options = {**world_options, "time_limit": float(max_cycles) * world_options.get("time_step", 0.25)}
        self.world = build_world(layout, num_humans, human_model, human_model_kwargs, world_options)
        self.config = self.world.config
        if robot is not None and robot != "agent":
            self._robot_policy = make_policy(robot, self.config)
            self._robot_obs = make_observation(self._robot_policy.observation, self.config,
                                               **self._robot_policy.observation_kwargs)
        self.robot_mode = robot
        self.render_mode = render_mode
        self.max_cycles = max_cycles
        self.flat = flat_observations
        self.pedestrians_finish = pedestrians_finish
        self.human_reward = make_reward(human_reward)
        self._obs_builder = make_observation(observation, self.config, **(observation_kwargs or {}))
        self._seed = seed
        H = self.world.num_humans
        self._robot_agent = robot == "agent"
        self.possible_agents = (["robot"] if self._robot_agent else []) + [f"human_{i}" for i in range(H)]
        self.agents = list(self.possible_agents)
        self._renderer = None
        self._done: set[str] = set()
        self._slot = {f"human_{i}": i for i in range(H)}
        self._no_reward = np.zeros((1, H))
        self._agents_changed()
        self._state_space = spaces.Box(-1e5, 1e5, (len(self.possible_agents) * 7,), np.float32)
        n = self.config.max_humans_observed
        self._flat_space = spaces.Box(-1e5, 1e5, (9 + 6 * n,), np.float32)
        self._unit_box = spaces.Box(-1.0, 1.0, (2,), np.float32)

    # ------------------------------------------------------------------ pickling
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_renderer"] = None  # a figure; rebuilt by the next render()
        return state

    # spaces must be the same object on every call
    @functools.cache  # noqa: B019
    def observation_space(self, agent: str) -> spaces.Space:
        self._check_agent(agent)
        if self.flat:
            return self._flat_space
        if agent == "robot":
            return self._obs_builder.space()
        return human_observation_space(self.config)

    @functools.cache  # noqa: B019
    def action_space(self, agent: str) -> spaces.Space:
        self._check_agent(agent)
        if agent == "robot" and not self.flat:
            return robot_action_space(self.config)
        return self._unit_box

    @property
    def state_space(self) -> spaces.Box:
        return self._state_space

    def _check_agent(self, agent: str) -> None:
        if agent not in self.possible_agents:
            raise ValueError(f"unknown agent {agent!r}; valid: {', '.join(self.possible_agents[:2])} … "
                             f"{self.possible_agents[-1]}")

    # ------------------------------------------------------------------ API
    def reset(self, seed: int | None = None, options: dict | None = None):
        if seed is None:
            seed, self._seed = self._seed, None
        w = self.world
        w.reset(seeds=[seed])
        if self.robot_mode is None:  # no robot: parked far away, out of everyone's way
            w.set_agents(0, positions=np.concatenate([[[-PARK, -PARK]], w.pos[0, 1:]]),
                         goals=np.concatenate([[[-PARK, -PARK]], w.goal[0, 1:]]))
        if self._robot_policy is not None:
            self._robot_policy.reset()
        self._cycles = 0
        self._done = set()
        n = int(w.active[0, 1:].sum())
        humans = [f"human_{i}" for i in range(w.num_humans if self.flat else n)]
        self.agents = (["robot"] if self._robot_agent else []) + humans
        self._agents_changed()
        if self._renderer is not None:
            self._renderer.clear()
        obs = self._observations()
        infos: dict[str, dict] = {a: {} for a in self.agents}
        if self._robot_agent:
            infos["robot"] = robot_info(w, None, w.human_model.info())
        return obs, infos

    def _human_actions(self, actions: dict[str, Any]) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The driven pedestrians' velocities ``(1, H, 2)`` and mask ``(1, H)`` (None, None when nobody is driven);
        one compiled check and map for all of them (:func:`~crowdbench.worlds._kernels.drive_actions`)."""
        keys = [a for a, act in actions.items() if a != "robot" and act is not None and a not in self._done]
        if not keys:
            return None, None
        slot = self._slot
        try:
            idx = np.fromiter((slot[k] for k in keys), dtype=np.int64, count=len(keys))
        except KeyError:
            idx = None
        if idx is None or any(k not in self._live for k in keys):
            bad = next(k for k in keys if k not in self._live)
            raise ValueError(f"action for {bad!r}, which is not a live agent; live agents: {self.agents}")
        try:
            a = np.asarray([actions[k] for k in keys], dtype=np.float64).reshape(len(keys), 2)
        except ValueError:
            raise ValueError("pedestrian actions: valid choices are two numbers in [-1, 1] per agent") from None
        H = self.world.num_humans
        human_actions, override = np.zeros((1, H, 2)), np.zeros((1, H), dtype=bool)
        bad_row = drive_actions(a, idx, self.world.v_pref[0, 1:], human_actions[0], override[0])
        if bad_row >= 0:
            check_normalised(keys[bad_row], a[bad_row])  # raises, naming the agent
        return human_actions, override

    def _robot_action(self, actions: dict[str, Any]) -> np.ndarray:
        w = self.world
        if self._robot_policy is not None:
            return np.asarray(self._robot_policy.act(self._robot_obs.build(w)), dtype=np.float64).reshape(2)
        if not self._robot_agent:
            return np.zeros(2)
        if "robot" not in actions:
            raise ValueError("actions must include 'robot' (pedestrians left out are driven by the pedestrian "
                             "model); build the env with robot=None or robot=POLICY for crowd-only control")
        if "robot" in self._done:
            return np.zeros(2)
        if not self.flat:
            return np.asarray(actions["robot"], dtype=np.float64).reshape(2)
        a = check_normalised("robot", actions["robot"])
        if self.config.kinematics == "holonomic":
            return disc_velocity(a, w.v_pref[0, 0])
        return np.array([(a[0] + 1.0) / 2.0 * w.v_pref[0, 0], a[1] * self.config.max_angular_speed])

    def step(self, actions: dict[str, Any]):
        w = self.world
        robot_action = self._robot_action(actions)
        human_actions, override = self._human_actions(actions)
        scored = not isinstance(self.human_reward, NoReward)
        before = Before.of(w) if scored or self.pedestrians_finish else None
        res = w.step(robot_action, human_actions, override)
        self._cycles += 1
        arrived = w._reached
        h_reward, h_terms = self.human_reward(w, before, arrived) if scored else (self._no_reward, {})
        robot_done, trunc = res.done(0)
        if not self._robot_agent and self._robot_policy is None:  # no robot: its (parked) outcome means nothing
            robot_done, trunc = False, bool(w.steps[0] >= w.config.max_steps)
        trunc = trunc or (self.max_cycles is not None and self._cycles >= self.max_cycles)
        finished = np.zeros(w.num_humans, dtype=bool)
        if self.pedestrians_finish:
            ped, robot_hit = contacts(w)
            finished = (arrived[0] | ped[0] | robot_hit[0] | (w.spawns[0, 1:] != before.spawns[0])) & \
                w.active[0, 1:]
            w.retire(finished[None])
        episode_over = robot_done or trunc
        agents = self.agents
        rewards, terminations = dict.fromkeys(agents, 0.0), dict.fromkeys(agents, False)
        truncations = dict.fromkeys(agents, False)
        if self._done:
            humans = [a for a in agents if a != "robot" and a not in self._done]
            slots = np.fromiter((self._slot[a] for a in humans), dtype=np.int64, count=len(humans))
        else:
            humans, slots = agents[1 if self._robot_agent else 0:], self._agent_slots
        crowd = w.human_model.info()
        infos = self._human_infos(humans, slots, crowd, h_terms)
        if len(humans):
            fin = finished[slots]
            rewards.update(zip(humans, h_reward[0, slots].tolist(), strict=True))
            terminations.update(zip(humans, fin.tolist(), strict=True))
            if episode_over:
                truncations.update(zip(humans, (~fin).tolist(), strict=True))
        if self._done:  # finished agents kept in the set (flat mode) get empty infos
            for a in self._done:
                infos.setdefault(a, {})
        if self._robot_agent:
            if "robot" not in self._done:
                rewards["robot"] = res.reward.item(0)
                terminations["robot"] = robot_done
                truncations["robot"] = trunc and not robot_done
            infos["robot"] = robot_info(w, res, crowd)
        obs = self._observations()
        if self._renderer is not None:
            self._renderer.record(w)
        newly_done = {a for a in self.agents if terminations[a] or truncations[a]}
        if self.flat:
            if episode_over or len(self._done | newly_done) == len(self.agents):
                self.agents = []
            else:  # finished agents stay, seeing zeros, until everyone is done (SuperSuit's convention)
                for a in newly_done:
                    terminations[a] = truncations[a] = False
                self._done |= newly_done
        elif episode_over:
            self.agents = []
        elif newly_done:
            self.agents = [a for a in self.agents if a not in newly_done]
        if self.agents is not agents:
            self._agents_changed()
        return obs, rewards, terminations, truncations, infos

    def _agents_changed(self) -> None:
        """Caches of the live agent list: its set and its pedestrians' slots."""
        self._live = set(self.agents)
        humans = self.agents[1 if self._robot_agent else 0:]
        self._agent_slots = np.fromiter((self._slot[a] for a in humans), dtype=np.int64, count=len(humans))

    def _observations(self) -> dict[str, Any]:
        """Every live agent's observation: views into one batched array per field."""
        w = self.world
        if self.flat:
            n = self.config.max_humans_observed
            A = w.num_agents
            me, nb, mask = np.empty((1, A, 9), np.float32), np.empty((1, A, n, 5), np.float32), \
                np.empty((1, A, n), np.float32)
            agent_observations_batch(w.pos, w.vel, w.goal, w.radius, w.v_pref, w.heading, w.active,
                                     self.config.human_sensing_range, self.config.robot_visible, me, nb, mask,
                                     w.grid_min)
            flat = np.concatenate([me[0], nb[0].reshape(A, -1), mask[0]], axis=1)
            rows = {"robot": 0, **{f"human_{i}": i + 1 for i in range(w.num_humans)}}
            return {a: flat[rows[a]] if a not in self._done else np.zeros_like(flat[0]) for a in self.agents}
        robot, h = agent_observations(self._obs_builder, w)
        obs: dict[str, Any] = {"robot": {k: v[0] for k, v in robot.items()}} if self._robot_agent else {}
        me, nb, mask, slot = h["self"], h["neighbors"], h["mask"], self._slot
        for agent in self.agents:
            if agent != "robot":
                i = slot[agent]
                obs[agent] = {"self": me[i], "neighbors": nb[i], "mask": mask[i]}
        return obs

    def _human_infos(self, humans: list[str], slots: np.ndarray, crowd: dict[str, np.ndarray],
                     terms: dict[str, np.ndarray]) -> dict[str, dict[str, Any]]:
        """Per live pedestrian (slots ``slots``): the model's analysis values (``crowd``: arrays ``(B, H)``) and, with
        a pedestrian reward, its named terms (``reward_terms``)."""
        cnames, tnames = list(crowd), list(terms)
        crows = _columns(crowd, cnames, slots)
        if not tnames:
            if not cnames:
                return {a: {} for a in humans}
            return {a: dict(zip(cnames, c, strict=True)) for a, c in zip(humans, crows, strict=True)}
        trows = _columns(terms, tnames, slots)
        if not cnames:
            return {a: {"reward_terms": dict(zip(tnames, t, strict=True))} for a, t in zip(humans, trows, strict=True)}
        return {a: {**dict(zip(cnames, c, strict=True)), "reward_terms": dict(zip(tnames, t, strict=True))}
                for a, c, t in zip(humans, crows, trows, strict=True)}

    def state(self) -> np.ndarray:
        """Global state ``(A * 7,)``: per agent [px, py, vx, vy, gx, gy, r] (robot first; padding slots parked)."""
        w = self.world
        s = np.concatenate([w.pos[0], w.vel[0], w.goal[0], w.radius[0, :, None]], 1).astype(np.float32)
        return (s if self._robot_agent else s[1:]).ravel()

    def render(self):
        return render_frame(self)

    def close(self) -> None:
        self._renderer = None


def parallel_env(**kwargs: Any) -> CrowdParallelEnv:
    """``crowdbench.parallel_env(layout="circle_crossing", num_humans=20, human_model="orca", ...)``."""
    return CrowdParallelEnv(**kwargs)


def raw_env(**kwargs: Any):
    """The AEC form (PettingZoo's convention for an environment module): :func:`parallel_env` through
    ``parallel_to_aec``."""
    from pettingzoo.utils.conversions import parallel_to_aec

    return parallel_to_aec(parallel_env(**kwargs))


def env(**kwargs: Any):
    """:func:`raw_env` with PettingZoo's usual wrappers (``AssertOutOfBounds`` on the Box actions,
    ``OrderEnforcing``)."""
    from pettingzoo.utils import wrappers

    e = raw_env(**kwargs)
    e = wrappers.AssertOutOfBoundsWrapper(e)
    return wrappers.OrderEnforcingWrapper(e)
