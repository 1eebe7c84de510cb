"""Classic (non-learned) robot policies: ``linear`` (straight to the goal), ``orca`` (RVO2 among the sensed
pedestrians) and ``social_force``. ``orca`` and ``social_force`` read pedestrian states at a chosen sensing tier
(``sensing=``: ``positions`` — velocities estimated from the positions, the board's tier —, ``velocities`` or
``full``; :mod:`crowdbench.robots.observations`)."""

from __future__ import annotations

import numpy as np

from crowdbench.humans.base import preferred_velocity
from crowdbench.humans.orca import ORCAParams
from crowdbench.humans.orca_kernel import build_obstacles, orca_batch
from crowdbench.policies.base import RobotPolicy, register
from crowdbench.robots.observations import STATE_OBSERVATIONS, check_sensing


def _goal_velocity(robot: np.ndarray, dt: float) -> np.ndarray:
    """Preferred velocity toward the goal from robot vectors ``(B, 9)`` = [px, py, r, gx, gy, v_pref, θ, vx, vy]."""
    return preferred_velocity(robot[:, 0:2], robot[:, 3:5], robot[:, 5], dt)


@register("linear")
class LinearPolicy(RobotPolicy):
    """Drive straight at the goal at v_pref, ignoring everyone (a lower bound)."""

    observation = "relative"

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return _goal_velocity(obs["robot"].astype(np.float64), self.config.time_step)


def _capped_goal_velocity(robot: np.ndarray, speed: float | None, dt: float) -> np.ndarray:
    """CrowdNav++'s ORCA preferred velocity (``crowd_nav/policy/orca.py:98-100``): the goal vector cut to ``speed``
    [m/s] (None: :func:`_goal_velocity`)."""
    if speed is None:
        return _goal_velocity(robot, dt)
    d = robot[:, 3:5] - robot[:, 0:2]
    dist = np.linalg.norm(d, axis=-1)
    return d * np.where(dist > speed, speed / np.maximum(dist, 1e-12), 1.0)[:, None]


@register("orca")
class ORCAPolicy(RobotPolicy):
    """The robot runs RVO2 ORCA among the sensed pedestrians (positions, velocities, radii at its ``sensing`` tier),
    as CrowdNav++'s ORCA robot (``crowd_nav/policy/orca.py``); it assumes the pedestrians reciprocate. Keyword
    arguments: ``sensing`` (default ``positions``) and :class:`ORCAParams` (CrowdNav++'s: preferred velocity a unit
    vector, safety space 0.15 m, every pedestrian a neighbour; the robot keeps ``neighbor_dist`` — its sensed
    pedestrians are all nearer — and ignores ``neighbor_dist_range``). Static obstacles in ``config.obstacles`` are
    avoided too."""

    observation = "estimated_state"

    def __init__(self, config=None, sensing: str = "positions", **params) -> None:
        super().__init__(config)
        self.observation = STATE_OBSERVATIONS[check_sensing(sensing, "robot policy orca: sensing")]
        self.params = ORCAParams.of("robot policy orca", **params)
        self._obst = build_obstacles(self.config.obstacles)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        p, cfg = self.params, self.config
        robot = obs["robot"].astype(np.float64)
        humans = obs["humans"].astype(np.float64)
        valid = obs["mask"] > 0.5
        B, N = valid.shape
        A = N + 1
        pad = p.radius_pad + p.safety_space
        pos = np.concatenate([robot[:, None, 0:2], robot[:, None, 0:2] + humans[..., 0:2]], 1)
        vel = np.concatenate([robot[:, None, 7:9], humans[..., 2:4]], 1)
        rad = np.concatenate([robot[:, None, 2], humans[..., 4]], 1) + pad
        pref = np.zeros((B, A, 2))
        pref[:, 0] = _capped_goal_velocity(robot, p.preferred_speed, cfg.time_step)
        vmax = np.repeat(robot[:, 5:6], A, 1)
        active = np.concatenate([np.ones((B, 1), bool), valid], 1)
        controlled = np.zeros((B, A), bool)
        controlled[:, 0] = True
        out = np.empty((B, A, 2))
        orca_batch(pos, vel, pref, rad, vmax, np.full((B, A), p.neighbor_dist),
                   np.full((B, A), p.neighbors(A), np.int64), np.full((B, A), p.time_horizon),
                   np.full((B, A), p.time_horizon_obst), active, controlled, np.full((B, A), -1, np.int64),
                   *self._obst, cfg.time_step, out)
        return out[:, 0]


@register("social_force")
class SocialForcePolicy(RobotPolicy):
    """CrowdNav++'s Social Force robot (``crowd_nav/policy/social_force.py``): v ← v + dt·[KI·(v_des − v) +
    Σⱼ A·exp((r + rⱼ − dⱼ)/B)·n̂ⱼ], clipped to v_pref, over the sensed pedestrians at its ``sensing`` tier (default
    ``positions``; it reads positions and radii). Same constants as the pedestrian model (A = 2, B = 1, KI = 1).
    """

    observation = "estimated_state"

    def __init__(self, config=None, sensing: str = "positions", A: float = 2.0, B: float = 1.0,
                 KI: float = 1.0) -> None:
        super().__init__(config)
        self.observation = STATE_OBSERVATIONS[check_sensing(sensing, "robot policy social_force: sensing")]
        self.A, self.B, self.KI = A, B, KI

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        robot = obs["robot"].astype(np.float64)
        humans = obs["humans"].astype(np.float64)
        valid = obs["mask"] > 0.5
        v = robot[:, 7:9]
        acc = self.KI * (_goal_velocity(robot, self.config.time_step) - v)
        away = -humans[..., 0:2]  # from each pedestrian to the robot
        dist = np.maximum(np.linalg.norm(away, axis=-1), 1e-9)
        mag = np.where(valid, self.A * np.exp((robot[:, None, 2] + humans[..., 4] - dist) / self.B), 0.0)
        acc += ((mag / dist)[..., None] * away).sum(axis=1)
        new_v = v + self.config.time_step * acc
        speed = np.linalg.norm(new_v, axis=-1)
        return new_v * np.minimum(1.0, robot[:, 5] / np.maximum(speed, 1e-12))[:, None]
