"""``learned_crowd``: pedestrians driven by a shared policy trained with rsl-rl PPO in the multi-agent testbed
(``crowdbench train-crowd``, :mod:`crowdbench.training.crowd`).

Each pedestrian sees only what a pedestrian agent observes (:mod:`crowdbench.envs.marl`), turned into
goal-aligned features (:func:`features`): the frame rotates with the direction to its goal, so the policy is the
same whichever way a person walks. The policy — an MLP, run here in numpy (no torch at run time) — gives the mean
of a Gaussian over pre-squash actions; its ``tanh`` is the normalised action in that frame, mapped onto the
pedestrian's speed disc (:func:`crowdbench.envs.parallel.disc_velocity`) and rotated back to the world
(:func:`to_world`). The weights, their configuration and provenance ship as
``humans/checkpoints/learned_crowd.pt`` (weights only: ``torch.load(weights_only=True)``).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from crowdbench.humans.base import CrowdState, HumanModel

NEIGHBOURS = 8
"""Nearest agents each pedestrian attends to [-]."""
FEATURES = 5 + 6 * NEIGHBOURS
"""Per pedestrian: goal distance, v_pref, radius, own velocity (2); per neighbour Δ position (2), velocity (2),
radius, mask — all in the goal-aligned frame."""
SENSING = 5.0
"""Range of each pedestrian's neighbour observation [m]."""
CHECKPOINT = Path(__file__).resolve().parent / "checkpoints" / "learned_crowd.pt"


def observe(pos: np.ndarray, vel: np.ndarray, goal: np.ndarray, radius: np.ndarray, v_pref: np.ndarray,
            heading: np.ndarray, active: np.ndarray, robot_visible: bool) -> tuple[np.ndarray, ...]:
    """Every agent's own observation in every world (the compiled ``agent_observations_batch``), with
    :data:`NEIGHBOURS` slots: ``me`` ``(B, A, 9)``, ``neighbors`` ``(B, A, K, 5)``, ``mask`` ``(B, A, K)``."""
    from crowdbench.worlds._kernels import agent_observations_batch

    B, A = radius.shape
    me = np.empty((B, A, 9), np.float32)
    nb = np.empty((B, A, NEIGHBOURS, 5), np.float32)
    mask = np.empty((B, A, NEIGHBOURS), np.float32)
    agent_observations_batch(pos, vel, goal, radius, v_pref, heading, active, SENSING, robot_visible, me, nb, mask)
    return me, nb, mask


def features(me: np.ndarray, nb: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Goal-aligned features ``(..., FEATURES)`` float32 from observations ``me`` ``(..., 9)`` = [px, py, vx, vy,
    gx, gy, r, v_pref, θ], ``nb`` ``(..., K, 5)`` = (Δx, Δy, vx, vy, r) and ``mask`` ``(..., K)``: x points at the
    goal; distances in metres (goal distance capped at 10 m), velocities in m/s."""
    g = me[..., 4:6] - me[..., 0:2]
    dist = np.linalg.norm(g, axis=-1, keepdims=True)
    c, s = np.split(g / np.maximum(dist, 1e-6), 2, axis=-1)  # (…, 1) each

    def rot(v: np.ndarray) -> np.ndarray:  # world → goal frame
        cc, ss = c[..., None, :] if v.ndim > c.ndim else c, s[..., None, :] if v.ndim > s.ndim else s
        return np.concatenate([v[..., :1] * cc + v[..., 1:2] * ss, -v[..., :1] * ss + v[..., 1:2] * cc], -1)

    own = np.concatenate([np.minimum(dist, 10.0), me[..., 7:8], me[..., 6:7], rot(me[..., 2:4])], -1)
    m = mask[..., None]
    nbf = np.concatenate([rot(nb[..., 0:2]), rot(nb[..., 2:4]), nb[..., 4:5], m], -1) * m
    out = np.concatenate([own, nbf.reshape(*nbf.shape[:-2], -1)], -1)
    return out.astype(np.float32)


def to_world(action: np.ndarray, me: np.ndarray) -> np.ndarray:
    """Actions ``(..., 2)`` given in the goal-aligned frame of :func:`features` → the world frame (``me`` ``(..., 9)``
    the acting agents' own observations)."""
    g = me[..., 4:6] - me[..., 0:2]
    u = g / np.maximum(np.linalg.norm(g, axis=-1, keepdims=True), 1e-6)
    c, s = u[..., 0], u[..., 1]
    return np.stack([c * action[..., 0] - s * action[..., 1], s * action[..., 0] + c * action[..., 1]], -1)


class MLP:
    """The policy's mean network in numpy: ``Linear → ELU → … → Linear`` (rsl-rl's ``MLPModel`` layout)."""

    def __init__(self, weights: list[tuple[np.ndarray, np.ndarray]]) -> None:
        self.weights = [(np.asarray(w, np.float32), np.asarray(b, np.float32)) for w, b in weights]

    def __call__(self, x: np.ndarray) -> np.ndarray:
        for k, (w, b) in enumerate(self.weights):
            x = x @ w.T + b
            if k < len(self.weights) - 1:
                x = np.where(x > 0, x, np.expm1(np.minimum(x, 0.0)))  # ELU
        return x


def load(path: str | os.PathLike | None = None) -> tuple[MLP, dict[str, Any]]:
    """The shipped (or a given) crowd policy and its metadata; ``weights_only`` loading."""
    import torch

    path = Path(path or CHECKPOINT)
    if not path.exists():
        raise ValueError(f"learned_crowd: no checkpoint at {str(path)!r}; train one with `crowdbench train-crowd` "
                         "or pass checkpoint=PATH")
    ckpt = torch.load(path, map_location="cpu", weights_only=True)
    if not isinstance(ckpt, dict) or ckpt.get("method") != "learned_crowd":
        raise ValueError(f"{str(path)!r} is not a learned_crowd checkpoint")
    layers = ckpt["mean_layers"]
    return MLP([(layers[f"{k}.weight"].numpy(), layers[f"{k}.bias"].numpy()) for k in ckpt["layer_names"]]), ckpt


class LearnedCrowd(HumanModel):
    """Pedestrians acting by the trained crowd policy (module docstring). Args: ``checkpoint`` (path; default the
    shipped one). Deterministic: the policy's mean action."""

    def __init__(self, checkpoint: str | None = None) -> None:
        import hashlib

        self.policy, self.meta = load(checkpoint)
        path = Path(checkpoint or CHECKPOINT)
        self.fingerprint = hashlib.sha256(path.read_bytes()).hexdigest()[:16]
        """SHA-256 (16 hex) of the weights file: part of every board cell's scenario digest."""

    def step(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        from crowdbench.envs.parallel import disc_velocity

        B, H = state.radii.shape
        pos = np.concatenate([state.robot_position[:, None], state.positions], 1)
        vel = np.concatenate([state.robot_velocity[:, None], state.velocities], 1)
        goal = np.concatenate([state.robot_position[:, None], state.goals], 1)
        radius = np.concatenate([state.robot_radius[:, None], state.radii], 1)
        v_pref = np.concatenate([np.ones((B, 1)), state.v_pref], 1)
        heading = np.concatenate([np.zeros((B, 1)), state.headings], 1)
        active = np.concatenate([np.ones((B, 1), bool), state.active], 1)
        me, nb, mask = observe(pos, vel, goal, radius, v_pref, heading, active, bool(state.robot_visible))
        x = features(me[:, 1:], nb[:, 1:], mask[:, 1:])
        a = np.tanh(self.policy(x.reshape(B * H, -1))).reshape(B, H, 2).astype(np.float64)
        v = to_world(disc_velocity(a, state.v_pref), me[:, 1:].astype(np.float64))
        return np.where(state.active[..., None], v, 0.0)
