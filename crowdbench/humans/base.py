"""The pedestrian-model plug-in contract.

A pedestrian model maps the batched world state to the pedestrians' new velocities, ``(num_worlds, num_humans, 2)``
in m/s. It is called once per world step for all worlds of a batch; implementations must be vectorised over worlds
and pedestrians (numpy, numba, torch...), not loop over agents in Python.

Minimal example (a model that walks straight to the goal)::

    import numpy as np
    from crowdbench.humans import HumanModel, preferred_velocity, register

    @register("straight")
    class Straight(HumanModel):
        def step(self, state, rngs):
            return preferred_velocity(state.positions, state.goals, state.v_pref, state.time_step)

Third-party packages expose models by name through the entry-point group ``crowdbench.humans``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from crowdbench.geometry import Polygon
from crowdbench.registry import Registry


@dataclass
class CrowdState:
    """Read-only batched view of the world handed to pedestrian models. ``B`` worlds, ``H`` pedestrian slots.

    Arrays are views into the world's state: models must not write to them.
    """

    positions: np.ndarray
    """Pedestrian centres, ``(B, H, 2)`` [m]."""
    velocities: np.ndarray
    """Pedestrian velocities of the previous step, ``(B, H, 2)`` [m/s]."""
    goals: np.ndarray
    """Pedestrian goals, ``(B, H, 2)`` [m]."""
    radii: np.ndarray
    """``(B, H)`` [m]."""
    v_pref: np.ndarray
    """Preferred (= maximum) speeds, ``(B, H)`` [m/s]."""
    headings: np.ndarray
    """Facing directions, ``(B, H)`` [rad] (direction of motion, kept while standing)."""
    active: np.ndarray
    """``(B, H)`` bool: False for padding slots of worlds with fewer pedestrians (parked far away, ignore them)."""
    robot_position: np.ndarray
    """``(B, 2)`` [m]."""
    robot_velocity: np.ndarray
    """``(B, 2)`` [m/s]."""
    robot_radius: np.ndarray
    """``(B,)`` [m]."""
    robot_visible: bool
    """False when the world is configured with an invisible robot: models must then ignore it."""
    obstacles: tuple[Polygon, ...]
    """Static obstacles shared by all worlds: vertex lists (2 = segment, ≥ 3 = closed polygon, CCW) [m]."""
    edges: np.ndarray
    """The obstacles' edges, ``(S, 2, 2)`` [m]."""
    time_step: float
    """[s]"""
    spawns: np.ndarray | None = None
    """``(B, H)`` int: re-spawns of each slot this episode — a new person whenever it changes (None: never)."""
    layout: Any = None
    """The worlds' :class:`~crowdbench.worlds.layouts.Layout` (recorded-scene models read their recording from it)."""


class HumanModel(ABC):
    """Base class of pedestrian models. Only :meth:`step` is compulsory.

    Lifecycle: the world calls :meth:`bind` once, :meth:`reset` whenever some worlds start a new episode, then
    :meth:`step` every step.
    """

    num_worlds: int = 0
    num_humans: int = 0

    def bind(self, num_worlds: int, num_humans: int, obstacles: Sequence[Polygon], time_step: float) -> None:
        """Optional: allocate per-world state for ``num_worlds`` × ``num_humans`` pedestrians."""
        self.num_worlds, self.num_humans = num_worlds, num_humans

    def reset(self, worlds: np.ndarray, rngs: Sequence[np.random.Generator], state: CrowdState) -> None:
        """Optional: start new episodes in ``worlds`` (int indices ``(k,)``); ``rngs[b]`` is world b's generator."""

    @abstractmethod
    def step(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        """Return the pedestrians' velocities for this step, ``(B, H, 2)`` [m/s].

        ``rngs[b]`` is world ``b``'s episode generator: the only source of randomness a model may use. Callers copy
        the result before the next call, so it may be a view of the model's own buffer.
        """

    def info(self) -> dict[str, np.ndarray]:
        """Optional: per-pedestrian arrays ``(B, H)`` exposed in the world's info for analysis."""
        return {}

    def script(self, state: CrowdState) -> tuple[np.ndarray, ...] | None:
        """Optional, for models that place people directly (recorded crowds): called after every reset and step,
        returns ``(moved, positions, goals, v_pref, active)`` — ``(B, H)`` bool slots to put at ``positions``
        ``(B, H, 2)`` [m] with ``goals`` ``(B, H, 2)`` [m] and speed limits ``v_pref`` ``(B, H)`` [m/s] (velocity
        zeroed), and ``(B, H)`` bool which slots are present (a slot that stops being present is parked).
        ``None`` (default): the world moves everyone by velocity."""
        return None


class PedestrianModelError(RuntimeError):
    """A pedestrian model raised or returned unusable velocities; names the model."""


HUMAN_MODELS: Registry[HumanModel] = Registry("pedestrian model", "crowdbench.humans")
register = HUMAN_MODELS.register


def make(name: str | HumanModel, **kwargs) -> HumanModel:
    """Instantiate a pedestrian model by registry name (an instance is passed through)."""
    if isinstance(name, HumanModel):
        return name
    if not isinstance(name, str):
        raise ValueError(f"human_model={name!r}; valid choices: a HumanModel instance or one of "
                         f"{', '.join(HUMAN_MODELS.names())}")
    return HUMAN_MODELS.make(name, **kwargs)


def preferred_velocity(positions: np.ndarray, goals: np.ndarray, v_pref: np.ndarray, time_step: float) -> np.ndarray:
    """Velocity toward the goal at ``v_pref``, scaled down to land exactly on the goal when it is closer than one
    step (``|d| < v_pref·dt`` → ``d / dt``), as in RVO2's examples and CrowdNav.

    Shapes: ``positions, goals`` ``(..., 2)`` [m]; ``v_pref`` ``(...)`` [m/s] → ``(..., 2)`` [m/s].
    """
    d = goals - positions
    dist = np.linalg.norm(d, axis=-1)
    near = dist < v_pref * time_step
    scale = np.where(near, 1.0 / time_step, v_pref / np.maximum(dist, 1e-12))
    return d * scale[..., None]


@register("linear")
class Linear(HumanModel):
    """Non-reactive pedestrians: constant preferred velocity toward the goal, ignoring everyone and everything."""

    def step(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        return preferred_velocity(state.positions, state.goals, state.v_pref, state.time_step)
