"""The robot-policy plug-in contract.

A robot policy maps a batch of robot observations to a batch of actions. It never holds or steps an environment.

    class MyPolicy(RobotPolicy):
        observation = "estimated_state"      # which observation builder it needs (its sensing tier follows)
        def act(self, obs):                  # obs: dict of (B, ...) arrays
            return np.zeros((len(obs["robot"]), 2))

Register it with ``crowdbench.policies.register("mine", MyPolicy)`` or the entry-point group ``crowdbench.policies``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from crowdbench.config import WorldConfig
from crowdbench.registry import Registry


class RobotPolicy(ABC):
    """Base class of robot policies.

    Class attributes:
        observation: Name of the robot observation builder the policy consumes (``relative``, ``estimated_state``,
            ``observed_state``, ``full_state``, …, :mod:`crowdbench.robots.observations`); it fixes the policy's
            sensing tier (:attr:`sensing`). A policy may set it per instance (e.g. from a ``sensing`` option).
        kinematics: Robot kinematics the actions are meant for.
        stateless: A world's action depends on that world's current observation only (no memory, no batch-wide
            state), so :func:`~crowdbench.evaluation.run_episodes` asks only for the worlds still running once a
            batch's last episodes are under way (CADRL and SARL, whose look-ahead dominates their evaluation).
    """

    observation: ClassVar[str] = "relative"
    kinematics: ClassVar[tuple[str, ...]] = ("holonomic",)
    stateless: ClassVar[bool] = False

    def __init__(self, config: WorldConfig | None = None) -> None:
        self.config = config or WorldConfig()
        if self.config.kinematics not in self.kinematics:
            raise ValueError(f"{type(self).__name__} supports kinematics {self.kinematics}, "
                             f"got {self.config.kinematics!r}")

    @property
    def sensing(self) -> str:
        """The sensing tier of :attr:`observation` (``positions``, ``velocities`` or ``full``)."""
        from crowdbench.robots.observations import observation_sensing

        return observation_sensing(self.observation)

    @property
    def observation_kwargs(self) -> dict[str, Any]:
        """Options of the :attr:`observation` builder (e.g. which predictor ``predicted`` runs); default none."""
        return {}

    def reset(self, done: np.ndarray | None = None) -> None:
        """Forget per-episode state (e.g. recurrent memory) of worlds where ``done`` ``(B,)`` is True (all if None)."""

    @abstractmethod
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Actions ``(B, 2)`` for observations ``obs`` (dict of ``(B, ...)`` arrays)."""


class PolicyError(RuntimeError):
    """A robot policy returned something unusable (wrong shape, NaN or inf); names the policy."""


def check_actions(policy: RobotPolicy, action: np.ndarray, num_worlds: int) -> np.ndarray:
    """``action`` as a float64 ``(num_worlds, 2)`` array, or :class:`PolicyError` naming the policy and the fault."""
    name = type(policy).__name__
    try:
        a = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise PolicyError(f"robot policy {name} returned actions that are not numbers ({e})") from None
    if a.shape != (num_worlds, 2):
        raise PolicyError(f"robot policy {name} returned actions of shape {a.shape}; expected ({num_worlds}, 2)")
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        raise PolicyError(f"robot policy {name} returned NaN or inf actions (worlds {np.flatnonzero(bad).tolist()})")
    return a


POLICIES: Registry[RobotPolicy] = Registry("robot policy", "crowdbench.policies")
register = POLICIES.register


def make_policy(name: str, config: WorldConfig | None = None, **kwargs) -> RobotPolicy:
    """Instantiate a robot policy by registry name."""
    return POLICIES.make(name, config=config, **kwargs)
