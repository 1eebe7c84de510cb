"""Observation builders (plug-ins): batched numpy from the world's state to per-agent observation dicts.

Robot observations (registry :data:`OBSERVATIONS`):

* ``relative`` (the paper's): ``robot`` ``(9,)`` = [px, py, r, gx, gy, v_pref, θ, vx, vy]; ``humans``
  ``(N_max, 2)`` = (Δx, Δy) of pedestrians whose centre is within ``sensing_range``, nearest first, zero-padded;
  ``mask`` ``(N_max,)`` = 1 for real entries. No pedestrian velocities, no responsiveness state.
* ``full_state`` (for ORCA/SF/CADRL/SARL-style baselines): ``robot`` as above; ``humans`` ``(N_max, 5)`` =
  (Δx, Δy, vx, vy, r) of *every* pedestrian (no range limit), nearest first; ``mask``.

Units: metres, m/s, radians. Arrays are float32.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from gymnasium import spaces

from crowdbench.config import WorldConfig
from crowdbench.geometry import norm
from crowdbench.registry import Registry

BOUND = 1.0e5
"""Finite bound of the Box spaces [m or m/s] (parked padding slots sit at 1e4 m)."""


class Observation(ABC):
    """Robot observation builder. ``build`` returns a dict of float32 arrays with leading dimension ``B``."""

    name: str = ""

    def __init__(self, config: WorldConfig) -> None:
        self.config = config

    @abstractmethod
    def space(self) -> spaces.Dict:
        """Single-world observation space."""

    @abstractmethod
    def build(self, world) -> dict[str, np.ndarray]:
        """Batched observation of ``world`` (a :class:`~crowdbench.worlds.CrowdWorld`)."""


OBSERVATIONS: Registry[Observation] = Registry("robot observation", "crowdbench.observations")


def robot_vector(world) -> np.ndarray:
    """``(B, 9)`` = [px, py, r, gx, gy, v_pref, θ, vx, vy] of the robot."""
    return np.concatenate([world.pos[:, 0], world.radius[:, :1], world.goal[:, 0], world.v_pref[:, :1],
                           world.heading[:, :1], world.vel[:, 0]], axis=1).astype(np.float32)


def nearest(world, n_max: int, max_range: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Indices ``(B, n_max)`` of pedestrians (0-based, into ``pos[:, 1:]``) sorted by distance to the robot, the
    relative positions ``(B, n_max, 2)`` and the validity mask ``(B, n_max)`` (within ``max_range``, active).
    """
    rel = world.pos[:, 1:] - world.pos[:, :1]
    dist = norm(rel)
    key = np.where(world.active[:, 1:] & (dist <= max_range), dist, np.inf)
    B, H = key.shape
    k = min(n_max, H)
    order = np.zeros((B, n_max), dtype=np.int64)
    valid = np.zeros((B, n_max), dtype=bool)
    rel_sorted = np.zeros((B, n_max, 2))
    order[:, :k] = np.argsort(key, axis=1, kind="stable")[:, :k]
    valid[:, :k] = np.take_along_axis(key, order[:, :k], axis=1) < np.inf
    rel_sorted[:, :k] = np.take_along_axis(rel, order[:, :k, None], axis=1) * valid[:, :k, None]
    return order, rel_sorted, valid


def _robot_box() -> spaces.Box:
    return spaces.Box(-BOUND, BOUND, (9,), np.float32)


@OBSERVATIONS.register("relative")
class RelativeObservation(Observation):
    """The paper's partial observation (robot state + relative pedestrian positions within sensing range)."""

    name = "relative"

    def space(self) -> spaces.Dict:
        n = self.config.max_humans_observed
        return spaces.Dict({"robot": _robot_box(), "humans": spaces.Box(-BOUND, BOUND, (n, 2), np.float32),
                            "mask": spaces.Box(0.0, 1.0, (n,), np.float32)})

    def build(self, world) -> dict[str, np.ndarray]:
        _, rel, valid = nearest(world, self.config.max_humans_observed, self.config.sensing_range)
        return {"robot": robot_vector(world), "humans": rel.astype(np.float32), "mask": valid.astype(np.float32)}


@OBSERVATIONS.register("full_state")
class FullStateObservation(Observation):
    """Full observability: every pedestrian's relative position, velocity and radius."""

    name = "full_state"

    def space(self) -> spaces.Dict:
        n = self.config.max_humans_observed
        return spaces.Dict({"robot": _robot_box(), "humans": spaces.Box(-BOUND, BOUND, (n, 5), np.float32),
                            "mask": spaces.Box(0.0, 1.0, (n,), np.float32)})

    def build(self, world) -> dict[str, np.ndarray]:
        order, rel, valid = nearest(world, self.config.max_humans_observed, np.inf)
        vel = np.take_along_axis(world.vel[:, 1:], order[..., None], axis=1)
        rad = np.take_along_axis(world.radius[:, 1:], order, axis=1)
        feats = np.concatenate([rel, vel, rad[..., None]], -1) * valid[..., None]
        return {"robot": robot_vector(world), "humans": feats.astype(np.float32), "mask": valid.astype(np.float32)}


def human_observation_space(config: WorldConfig) -> spaces.Dict:
    """Each pedestrian agent's observation: ``self`` (9,) = [px, py, vx, vy, gx, gy, r, v_pref, θ];
    ``neighbors`` (N_max, 5) = (Δx, Δy, vx, vy, r) of other agents (robot included when visible) within
    ``human_sensing_range``, nearest first; ``mask`` (N_max,).
    """
    n = config.max_humans_observed
    return spaces.Dict({"self": spaces.Box(-BOUND, BOUND, (9,), np.float32),
                        "neighbors": spaces.Box(-BOUND, BOUND, (n, 5), np.float32),
                        "mask": spaces.Box(0.0, 1.0, (n,), np.float32)})


def human_observations(world, b: int) -> dict[str, np.ndarray]:
    """Observations of all pedestrian slots of world ``b``, vectorised: arrays ``(H, ...)``."""
    cfg = world.config
    n = cfg.max_humans_observed
    p, v, r = world.pos[b], world.vel[b], world.radius[b]
    me = np.concatenate([p[1:], v[1:], world.goal[b, 1:], r[1:, None], world.v_pref[b, 1:, None],
                         world.heading[b, 1:, None]], 1)
    rel = p[None, :] - p[1:, None]  # (H, A, 2): agent j relative to pedestrian i
    dist = norm(rel)
    ok = world.active[b][None, :] & (dist <= cfg.human_sensing_range)
    ok[np.arange(len(ok)), np.arange(1, len(ok) + 1)] = False  # not itself
    if not cfg.robot_visible:
        ok[:, 0] = False
    key = np.where(ok, dist, np.inf)
    k = min(n, key.shape[1])
    order = np.argsort(key, axis=1, kind="stable")[:, :k]
    valid = np.take_along_axis(key, order, axis=1) < np.inf
    feats = np.concatenate([np.take_along_axis(rel, order[..., None], 1), v[order], r[order][..., None]], -1)
    feats *= valid[..., None]
    out_f = np.zeros((len(me), n, 5))
    out_m = np.zeros((len(me), n))
    out_f[:, :k], out_m[:, :k] = feats, valid
    return {"self": me.astype(np.float32), "neighbors": out_f.astype(np.float32), "mask": out_m.astype(np.float32)}


def make_observation(name: str, config: WorldConfig) -> Observation:
    """Robot observation builder by registry name."""
    if not isinstance(name, str):
        raise ValueError(f"observation={name!r}; valid choices: {', '.join(OBSERVATIONS.names())}")
    return OBSERVATIONS.get(name)(config)
