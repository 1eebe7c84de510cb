"""Pedestrian rewards (plug-ins): what a pedestrian agent earns each step in the multi-agent testbed.

A reward is a callable class registered in :data:`HUMAN_REWARDS` (``human_reward=NAME`` in
:func:`crowdbench.parallel_env` and the batched :class:`~crowdbench.envs.marl.CrowdMARLEnv`; third-party packages
use the entry-point group ``crowdbench.human_rewards``). It sees the world before and after the step and returns
``(B, H)`` rewards plus its named terms (each ``(B, H)``), which the environments report in ``infos``.

Shipped: ``progress`` (below) and ``none`` (zero).
"""

from __future__ import annotations

from dataclasses import dataclass

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
    crowd_clearance(world.pos, world.radius, world.active, bool(world.config.robot_visible), near, ped, robot)
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
        p, act = world.pos[:, 1:], world.active[:, 1:]
        moved_on = world.spawns[:, 1:] != before.spawns  # re-spawned: measure at the goal it reached
        here = np.where((moved_on | arrived)[..., None], before.goals, p)
        progress = np.linalg.norm(before.goals - before.positions, axis=-1) - np.linalg.norm(before.goals - here,
                                                                                              axis=-1)
        d, ped, robot = clearance(world)
        terms = {"progress": self.w_progress * progress, "goal": self.w_goal * (arrived | moved_on),
                 "collision": self.w_collision * (ped | robot),
                 "intrusion": self.w_intrusion * np.clip(self.personal - d, 0.0, self.personal),
                 "time": np.full(act.shape, self.w_time)}
        terms = {k: np.where(act | moved_on | arrived, v, 0.0).astype(np.float64) for k, v in terms.items()}
        return sum(terms.values()), terms


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
