"""The trajectory-predictor plug-in contract, the robot's track of what it has seen, and two reference predictors.

A predictor answers "where will each pedestrian the robot sees now be in 1…K steps?" from the positions the robot has
seen over the last ``T`` steps (:class:`Track`). It is part of the robot's perception (AIG-GST's spatial edges and its
prediction-intrusion reward read it), never of the world::

    class Mine(Predictor):
        def predict(self, track, world):        # track.pos (B, T, H, 2), track.seen (B, T, H)
            return np.repeat(track.pos[:, -1, :, None], self.horizon, axis=2)   # (B, H, K, 2): standing still

    PREDICTORS.register("mine", Mine)            # or the entry-point group crowdbench.predictors

Built in: ``const_vel`` (the last seen displacement, repeated), ``truth`` (the pedestrians' own model rolled forward
on a copy of the world, CrowdNav++'s ``truth``) and ``gst`` (the learned predictor, :mod:`crowdbench.predictors.gst`).
Units: metres, world frame; one step = the world's time step.
"""

from __future__ import annotations

import copy
from abc import ABC, abstractmethod

import numpy as np

from crowdbench.registry import Registry

OBSERVED = 5
"""Steps of history a track keeps (the current one included): CrowdNav++'s GST observes 5."""
HORIZON = 5
"""Predicted steps: CrowdNav++'s 5 × 0.25 s = 1.25 s."""
MAX_STEP = 1.0
"""A pedestrian that moved farther than this in one step was re-spawned: its track restarts [m]."""


class Track:
    """The last ``length`` positions of every pedestrian slot as the robot saw them, per world.

    ``pos`` ``(B, T, H, 2)`` [m] (index ``T − 1`` = now; entries not seen hold the last seen position) and ``seen``
    ``(B, T, H)`` bool (in sensing range at that step and the same person as now). A world's track restarts when its
    episode step counter does not follow on (a reset; also one that reads the same as before with the pedestrians
    elsewhere — an episode that ended on its first step), and a slot's when its pedestrian jumped (a re-spawn);
    calling :meth:`update` twice for the same state changes nothing, so any number of observation builds per step is
    safe.
    """

    def __init__(self, num_worlds: int, num_humans: int, length: int = OBSERVED) -> None:
        self.pos = np.zeros((num_worlds, length, num_humans, 2))
        self.seen = np.zeros((num_worlds, length, num_humans), dtype=bool)
        self.step = np.full(num_worlds, -2, dtype=np.int64)  # the first update restarts every world

    def update(self, positions: np.ndarray, seen: np.ndarray, steps: np.ndarray) -> None:
        """Record the current ``positions`` ``(B, H, 2)`` and visibility ``seen`` ``(B, H)`` at episode steps
        ``steps`` ``(B,)``."""
        # a new step, or a new episode whose counter reads as the last one did (an episode that ended on its first
        # step restarts at 0 again): the positions tell
        new = (steps != self.step) | (positions != self.pos[:, -1]).any(axis=(1, 2))
        if not new.any():
            return
        restart = new & (steps != self.step + 1)
        if restart.any():
            self.seen[restart] = False
            self.pos[restart] = positions[restart, None]
        idx = np.flatnonzero(new)
        jumped = np.linalg.norm(positions[idx] - self.pos[idx, -1], axis=-1) > MAX_STEP  # (k, H)
        self.pos[idx] = np.roll(self.pos[idx], -1, axis=1)
        self.seen[idx] = np.roll(self.seen[idx], -1, axis=1)
        self.seen[idx, :-1] &= ~jumped[:, None, :]
        self.pos[idx, -1] = positions[idx]
        self.seen[idx, -1] = seen[idx]
        self.step[idx] = steps[idx]


class Predictor(ABC):
    """Base class of trajectory predictors (see the module docstring)."""

    horizon: int = HORIZON

    @abstractmethod
    def predict(self, track: Track, world) -> np.ndarray:
        """Positions ``(B, H, horizon, 2)`` [m] of every pedestrian slot 1…horizon steps ahead. Only the slots seen
        now (``track.seen[:, -1]``) are read; ``world`` (a :class:`~crowdbench.worlds.CrowdWorld`) is for oracles."""


PREDICTORS: Registry[Predictor] = Registry("trajectory predictor", "crowdbench.predictors")


@PREDICTORS.register("const_vel")
class ConstantVelocity(Predictor):
    """The last seen displacement per step, repeated (zero when the previous step was not seen): what the robot's
    own observations support without a model. CrowdNav++'s ``const_vel`` reads the simulator's velocities instead."""

    def predict(self, track: Track, world) -> np.ndarray:
        return constant_velocity(track.pos, track.seen, self.horizon)


def constant_velocity(pos: np.ndarray, seen: np.ndarray, horizon: int = HORIZON) -> np.ndarray:
    """Constant-velocity positions ``(S, A, horizon, 2)`` from observed positions ``pos`` ``(S, T, A, 2)`` and
    ``seen`` ``(S, T, A)`` (a track's layout): the last seen displacement repeated, zero where the previous step was
    not seen."""
    now, prev = pos[:, -1], pos[:, -2]
    step = np.where((seen[:, -1] & seen[:, -2])[..., None], now - prev, 0.0)
    k = np.arange(1, horizon + 1, dtype=now.dtype)[:, None]
    return now[:, :, None, :] + k * step[:, :, None, :]


@PREDICTORS.register("truth")
class GroundTruth(Predictor):
    """The pedestrians' own model rolled ``horizon`` steps on a copy of its state (CrowdNav++'s ``truth``): the robot
    keeps its velocity, goals stay, no collisions are resolved, and the model's generators are copies (the world's
    are untouched). An oracle for comparison, about one world step of cost per predicted step."""

    def predict(self, track: Track, world) -> np.ndarray:
        model, rngs = copy.deepcopy(world.human_model), copy.deepcopy(world.model_rngs)
        state = copy.copy(world.crowd_state())
        pos, vel = world.pos.copy(), world.vel.copy()
        out = np.empty((world.num_worlds, world.num_humans, self.horizon, 2))
        for k in range(self.horizon):
            state.positions, state.velocities = pos[:, 1:], vel[:, 1:]
            state.robot_position, state.robot_velocity = pos[:, 0], vel[:, 0]
            vel[:, 1:] = model.step(state, rngs)
            pos = pos + vel * world.dt
            out[:, :, k] = pos[:, 1:]
        return out


def make_predictor(name: str | Predictor, **kwargs) -> Predictor:
    """A predictor by registry name (or an instance, returned as is)."""
    if isinstance(name, Predictor):
        return name
    if not isinstance(name, str):
        raise ValueError(f"predictor={name!r}; valid choices: {', '.join(PREDICTORS.names())}")
    return PREDICTORS.make(name, **kwargs)
