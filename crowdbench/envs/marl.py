"""A batched multi-agent interface over the compiled core, VMAS-style: ``B`` worlds × ``A`` agents as arrays.

    env = CrowdMARLEnv(num_worlds=64, num_humans=20, robot=None, human_reward="progress", device="cpu")
    obs = env.reset(seed=0)                         # (B, A, D) torch tensor (numpy with device=None)
    obs, rewards, dones, info = env.step(actions)   # actions (B, A, 2) in [-1, 1]; rewards (B, A); dones (B,)

Agents are the pedestrian slots (and the robot, first, with ``robot="agent"``); every agent observes the flat
pedestrian layout of :class:`~crowdbench.envs.parallel.CrowdParallelEnv` (``flat_observations``: self 9, neighbours
N_max·5, mask N_max; zeros for an absent slot) and acts in [−1, 1]², mapped onto its own speed disc (no clipping).
Pedestrians driven here are never stepped by the pedestrian model (which then only matters for the robot's
policy, if any). A world whose episode ends (time limit, or the robot's success or collision) is reset at once with
its next seed, and ``dones`` marks it for that step (the observation is the new episode's first) — as rsl-rl and
VMAS expect. ``info``: ``reward_terms`` (each ``(B, A)``), ``arrived`` ``(B, H)`` (pedestrians that reached their
goal this step), ``contacts`` ``(B, H)`` (pedestrians touching another or the robot).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from crowdbench.config import make_config
from crowdbench.envs.parallel import disc_velocity
from crowdbench.humans.rewards import Before, contacts, make_reward
from crowdbench.worlds._kernels import agent_observations_batch
from crowdbench.worlds.world import PARK, CrowdWorld


class CrowdMARLEnv:
    """See the module docstring. Args: ``num_worlds`` B, ``num_humans``, ``layout``, ``human_model`` (drives
    nobody the learner drives; kept for its world rules), ``robot`` (``"agent"``, None, or a robot policy name),
    ``human_reward``, ``max_cycles`` (episode length in steps; default the ``time_limit``), ``seed`` (world b's
    e-th episode runs seed ``seed + e·B + b``), ``device`` (a torch device, or None for numpy), and any
    :class:`~crowdbench.config.WorldConfig` field."""

    def __init__(self, num_worlds: int = 64, num_humans: int = 20, layout: str = "circle_crossing",
                 human_model: Any = "orca", robot: str | None = None, human_reward: Any = "progress",
                 max_cycles: int | None = None, seed: int = 0, device: Any = "cpu", **world_options: Any) -> None:
        if robot is None:
            world_options = {**world_options, "robot_visible": False}
        if max_cycles is not None:
            if not isinstance(max_cycles, (int, np.integer)) or max_cycles < 1:
                raise ValueError(f"max_cycles={max_cycles!r}; valid choices: None or an integer ≥ 1")
            world_options.setdefault("time_limit", float(max_cycles) * world_options.get("time_step", 0.25))
        self.config = make_config(num_humans=num_humans, **world_options)
        self.world = CrowdWorld(self.config, num_worlds, layout, human_model)
        self.robot_mode, self.reward = robot, make_reward(human_reward)
        self._policy = self._robot_obs = None
        if robot not in (None, "agent"):
            from crowdbench.policies import POLICIES, make_policy
            from crowdbench.robots.observations import make_observation

            if robot not in POLICIES.names():
                raise ValueError(f"robot={robot!r}; valid choices: 'agent', None, or a registered robot policy "
                                 f"({', '.join(POLICIES.names())})")
            self._policy = make_policy(robot, self.config)
            self._robot_obs = make_observation(self._policy.observation, self.config,
                                               **self._policy.observation_kwargs)
        self.num_worlds, self.num_humans = num_worlds, self.world.num_humans
        self._first = 0 if robot == "agent" else 1  # agent rows are world slots [first, A)
        self.num_agents = self.world.num_agents - self._first
        n = self.config.max_humans_observed
        self.obs_dim = 9 + 6 * n
        self.seed = int(seed)
        self.device = device
        A = self.world.num_agents
        self._me = np.empty((num_worlds, A, 9), np.float32)
        self._nb = np.empty((num_worlds, A, n, 5), np.float32)
        self._mask = np.empty((num_worlds, A, n), np.float32)
        self._next_seed = np.zeros(num_worlds, dtype=np.int64)

    # ------------------------------------------------------------------ helpers
    def _out(self, x: np.ndarray) -> Any:
        if self.device is None:
            return x
        import torch

        return torch.as_tensor(x, device=self.device)

    def _observe(self) -> np.ndarray:
        w = self.world
        agent_observations_batch(w.pos, w.vel, w.goal, w.radius, w.v_pref, w.heading, w.active,
                                 self.config.human_sensing_range, self.config.robot_visible, self._me, self._nb,
                                 self._mask, w.grid_min)
        B, A = self._me.shape[:2]
        flat = np.concatenate([self._me, self._nb.reshape(B, A, -1), self._mask], axis=2)
        return flat[:, self._first:]

    def _reset_worlds(self, mask: np.ndarray) -> None:
        idx = np.flatnonzero(mask)
        seeds = [int(s) for s in self._next_seed[idx]]  # world b's episodes: seed + b, seed + b + B, … never reused
        self._next_seed[idx] += self.num_worlds
        w = self.world
        w.reset(seeds=seeds, mask=mask)
        if self.robot_mode is None:
            w.pos[idx, 0] = w.goal[idx, 0] = -PARK
            w.physics.set_positions(idx, w.pos[idx])
            w.prev_goal_dist[idx] = 0.0
        if self._policy is not None:
            self._policy.reset(mask)

    # ------------------------------------------------------------------ API
    def reset(self, seed: int | None = None) -> Any:
        """Start every world (world b on seed ``seed + b``, later episodes on fresh seeds); returns ``(B, A, D)``."""
        if seed is not None:
            self.seed = int(seed)
        self._next_seed = self.seed + np.arange(self.num_worlds)
        self._reset_worlds(np.ones(self.num_worlds, dtype=bool))
        return self._out(self._observe())

    def step(self, actions: Any) -> tuple[Any, Any, Any, dict[str, Any]]:
        """``actions`` ``(B, A, 2)`` in [−1, 1] (numpy or torch) → ``(obs (B, A, D), rewards (B, A), dones (B,),
        info)``. ``actions=None``: the pedestrian model drives every pedestrian (and the robot stands, if an
        agent) — the same step with nobody driven from outside."""
        if actions is None:
            actions = np.zeros((self.num_worlds, self.num_agents, 2))
            driven = False
        else:
            driven = True
        a = actions.detach().cpu().numpy() if hasattr(actions, "detach") else np.asarray(actions)
        a = a.astype(np.float64, copy=False)
        B, A = self.num_worlds, self.num_agents
        if a.shape != (B, A, 2):
            raise ValueError(f"actions of shape {a.shape}; expected (num_worlds, num_agents, 2) = ({B}, {A}, 2)")
        if not (np.isfinite(a).all() and (np.abs(a) <= 1.0 + 1e-6).all()):
            raise ValueError("actions: valid choices are numbers in [-1, 1] (normalised, mapped onto each agent's "
                             "speed disc); got values outside or NaN")
        a = np.clip(a, -1.0, 1.0)
        w = self.world
        v = disc_velocity(a, w.v_pref[:, self._first:])
        if self.robot_mode == "agent":
            robot = v[:, 0]
        elif self._policy is not None:
            robot = np.asarray(self._policy.act(self._robot_obs.build(w)), dtype=np.float64)
        else:
            robot = np.zeros((B, 2))
        human = v[:, 1:] if self.robot_mode == "agent" else v
        before = Before.of(w)
        res = w.step(robot, human, w.active[:, 1:].copy()) if driven else w.step(robot)
        arrived = w._reached.copy()
        h_reward, h_terms = self.reward(w, before, arrived)
        ped, robot_hit = contacts(w)
        rewards = h_reward if self.robot_mode != "agent" else np.concatenate([res.reward[:, None], h_reward], 1)
        terms = h_terms if self.robot_mode != "agent" else {
            k: np.concatenate([np.zeros((B, 1)), t], 1) for k, t in h_terms.items()}
        done = (w.steps >= self.config.max_steps) | (res.terminated if self.robot_mode is not None else False)
        info = {"reward_terms": {k: self._out(t) for k, t in terms.items()}, "arrived": self._out(arrived),
                "contacts": self._out(ped | robot_hit), "outcome": self._out(res.outcome.copy())}
        if done.any():
            self._reset_worlds(done)
        return self._out(self._observe()), self._out(rewards.astype(np.float32)), self._out(done), info
