"""Deployment helpers that need no learning library: turn a policy's planar velocity command into bounded (v, ω)
for a differential-drive base, as the paper's robot does."""

from __future__ import annotations

import math

import numpy as np


def planar_to_unicycle(velocity: np.ndarray, heading: np.ndarray, v_max: float = 1.0,
                       w_max: float = math.pi / 2, turn_gain: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Convert planar velocity commands ``(..., 2)`` [m/s, world frame] and robot headings ``(...)`` [rad] into
    bounded (v [m/s], ω [rad/s]) for a differential-drive base.

    The command is expressed in the robot frame; ω = clip(turn_gain · heading error, ±w_max) turns toward it and
    v = clip(|cmd| · max(cos(heading error), 0), 0, v_max) drives only the part of it along the current heading (a
    command behind the robot makes it turn on the spot).
    """
    velocity = np.asarray(velocity, dtype=np.float64)
    heading = np.asarray(heading, dtype=np.float64)
    speed = np.hypot(velocity[..., 0], velocity[..., 1])
    err = np.arctan2(velocity[..., 1], velocity[..., 0]) - heading
    err = (err + np.pi) % (2 * np.pi) - np.pi
    err = np.where(speed > 1e-9, err, 0.0)
    w = np.clip(turn_gain * err, -w_max, w_max)
    v = np.clip(speed * np.maximum(np.cos(err), 0.0), 0.0, v_max)
    return v, w
