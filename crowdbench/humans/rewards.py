"""Pedestrian rewards (plug-ins): what a pedestrian agent earns each step in the multi-agent testbed.

A reward is a callable class registered in :data:`HUMAN_REWARDS` (``human_reward=NAME`` in
:func:`crowdbench.parallel_env` and the batched :class:`~crowdbench.envs.marl.CrowdMARLEnv`; third-party packages
use the entry-point group ``crowdbench.human_rewards``). It sees the world before and after the step and returns
``(B, H)`` rewards plus its named terms (each ``(B, H)``), which the environments report in ``infos``.

Shipped: ``progress`` (below) and ``none`` (zero).
"""

# numba-cache-key: crowdbench.worlds._kernels 34b006d3166a

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np

from crowdbench.registry import Registry


@dataclass
class Before:
    """The world's pedestrian state before a step (copies): positions and goals ``(B, H, 2)`` [m], ``spawns``
    ``(B, H)``."""

    positions: np.ndarray
    goals: np.ndarray
    spawns: np.ndarray

    @classmethod
    def of(cls, world) -> Before:
        return cls(world.pos[:, 1:].copy(), world.goal[:, 1:].copy(), world.spawns[:, 1:].copy())


class HumanReward:
    """Base class: ``__call__(world, before, arrived) -> (reward (B, H), terms {name: (B, H)})``; ``arrived``
    ``(B, H)`` bool marks pedestrians that reached their goal this step (before any re-spawn moved them)."""

    terms: tuple[str, ...] = ()

    def __call__(self, world, before: Before, arrived: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        raise NotImplementedError


HUMAN_REWARDS: Registry[HumanReward] = Registry("pedestrian reward", "crowdbench.human_rewards")
register = HUMAN_REWARDS.register


def clearance(world) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pedestrian ``(B, H)``: the smallest surface distance to another agent [m] (the robot counted when
    visible; inf when alone), touching another pedestrian, touching the robot (one compiled pass)."""
    from crowdbench.worlds._kernels import crowd_clearance

    B, H = world.num_worlds, world.num_humans
    near, ped, robot = np.empty((B, H)), np.empty((B, H), bool), np.empty((B, H), bool)
    crowd_clearance(world.pos, world.radius, world.active, bool(world.config.robot_visible), near, ped, robot,
                    world.grid_min)
    return near, ped, robot


def contacts(world) -> tuple[np.ndarray, np.ndarray]:
    """Per pedestrian ``(B, H)``: touching another pedestrian (discs overlapping), touching the (visible) robot."""
    _, ped, robot = clearance(world)
    return ped, robot


@register("progress")
class Progress(HumanReward):
    """Goal progress with the costs of a crowd worth walking in, per step:

    * ``progress`` = ``w_progress`` · (distance to the goal before − after) [1/m], the goal held before the step;
    * ``goal`` = ``w_goal`` on arrival;
    * ``collision`` = ``w_collision`` when its disc overlaps another pedestrian's or the robot's;
    * ``intrusion`` = ``w_intrusion`` · (``personal`` − d) for the nearest other agent's surface distance d below
      ``personal`` [1/m];
    * ``time`` = ``w_time``.
    """

    terms = ("progress", "goal", "collision", "intrusion", "time")

    def __init__(self, w_progress: float = 1.0, w_goal: float = 1.0, w_collision: float = -1.0,
                 w_intrusion: float = -1.0, personal: float = 0.2, w_time: float = -0.01) -> None:
        self.w_progress, self.w_goal, self.w_collision = w_progress, w_goal, w_collision
        self.w_intrusion, self.personal, self.w_time = w_intrusion, personal, w_time

    def __call__(self, world, before, arrived):
        near, ped, robot = clearance(world)
        terms = np.empty((5, world.num_worlds, world.num_humans))
        _progress_terms(before.positions, before.goals, before.spawns, world.pos, world.active, world.spawns, arrived,
                        near, ped | robot, np.array([self.w_progress, self.w_goal, self.w_collision, self.w_intrusion,
                                                     self.personal, self.w_time]), terms)
        return terms.sum(axis=0), dict(zip(self.terms, terms, strict=True))


@nb.njit(cache=True, error_model="numpy")
def _progress_terms(p0, g0, spawns0, pos, active, spawns, arrived, near, touch, w, out):  # pragma: no cover - numba
    """:class:`Progress`'s five terms ``out`` ``(5, B, H)`` from each pedestrian's nearest surface distance ``near``
    and contact flag ``touch`` (:func:`clearance`), weights ``w`` = progress, goal, collision, intrusion, personal
    distance, time; pedestrians neither active nor just arrived or re-spawned earn 0."""
    B, A = active.shape
    for b in range(B):
        for i in range(1, A):
            h = i - 1
            done = arrived[b, h] or spawns[b, i] != spawns0[b, h]
            if not (active[b, i] or done):
                for t in range(5):
                    out[t, b, h] = 0.0
                continue
            gx, gy = g0[b, h, 0], g0[b, h, 1]
            d0 = np.sqrt((gx - p0[b, h, 0]) ** 2 + (gy - p0[b, h, 1]) ** 2)
            d1 = 0.0 if done else np.sqrt((gx - pos[b, i, 0]) ** 2 + (gy - pos[b, i, 1]) ** 2)
            out[0, b, h] = w[0] * (d0 - d1)
            out[1, b, h] = w[1] if done else 0.0
            out[2, b, h] = w[2] if touch[b, h] else 0.0
            out[3, b, h] = w[3] * min(max(w[4] - near[b, h], 0.0), w[4])
            out[4, b, h] = w[5]


@register("none")
class NoReward(HumanReward):
    """Zero for everyone (pedestrians as part of the scenery)."""

    def __call__(self, world, before, arrived):
        return np.zeros(world.active[:, 1:].shape), {}


def make_reward(name: str | HumanReward | None) -> HumanReward:
    """A pedestrian reward by name (None: ``none``; an instance passes through)."""
    if isinstance(name, HumanReward):
        return name
    if name is None:
        return NoReward()
    if not isinstance(name, str):
        raise ValueError(f"human_reward={name!r}; valid choices: {', '.join(HUMAN_REWARDS.names())}")
    return HUMAN_REWARDS.make(name)
