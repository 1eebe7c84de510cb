"""Pedestrian models against recorded people: ADE / FDE on the ETH/UCY test scenes (``crowdbench crowd-validate``).

Protocol (the field's standard, made explicit):

* frames every 0.4 s; windows of 20 consecutive frames (frame numbers ``f, f + 10, …, f + 190``) sliding by one
  frame; a sample is a pedestrian annotated in all 20 frames of a window — so a window over an annotation gap holds no
  sample (time-consistent windows; Social GAN's loader slides over the *distinct* frames instead, which joins frames
  across a gap — :func:`samples` with ``contiguous=False`` gives that variant);
* observe 8 frames, predict 12; ADE = mean displacement over the 12 predicted frames, FDE = displacement at the last
  [m]; both averaged over every (pedestrian, window) sample of the scene's test recordings.

Predictors:

* ``const_vel`` — the velocity between the last two observed positions, extrapolated (the reference);
* any pedestrian model (``orca``, ``social_force``, ``responsive_orca``, plug-ins) — rolled out for 12 steps of 0.4 s
  from the last observed state: position, velocity from the last two observed positions, radius 0.3 m, speed limit
  ``v_pref`` = the pedestrian's mean observed speed (over its 7 observed steps), goal = its **recorded endpoint** (its
  position in the window's last frame). Every sample of a window is simulated jointly, in one world per window, with
  no robot (``responsive_orca`` then behaves as ORCA). Models run with their defaults; nothing is fitted.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from crowdbench.datasets.ethucy import DT, FRAME_STEP, SCENES, scene_recordings

__all__ = ["SCENES", "const_vel", "markdown", "rollout", "samples", "validate"]

OBS, PRED = 8, 12
WINDOW = OBS + PRED
PREDICTORS_BUILTIN = ("const_vel",)


def samples(rows: np.ndarray, contiguous: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Every (pedestrian, window) sample of one recording: ``traj`` ``(S, 20, 2)`` [m] and ``window`` ``(S,)`` (the
    window's index, grouping the samples simulated together)."""
    frames = np.unique(rows[:, 0])
    if contiguous:
        frames = np.arange(frames[0], frames[-1] + FRAME_STEP / 2, FRAME_STEP)
    ids, p = np.unique(rows[:, 1], return_inverse=True)
    t = np.searchsorted(frames, rows[:, 0])
    keep = (t < len(frames)) & (frames[np.minimum(t, len(frames) - 1)] == rows[:, 0])
    pos = np.full((len(frames), len(ids), 2), np.nan)
    pos[t[keep], p[keep]] = rows[keep, 2:4]
    valid = ~np.isnan(pos[..., 0])
    c = np.concatenate([np.zeros((1, len(ids)), np.int64), np.cumsum(valid, axis=0)])
    full = (c[WINDOW:] - c[:-WINDOW]) == WINDOW  # (T − 19, P): present in every frame of window s
    s, q = np.nonzero(full)
    idx = s[:, None] + np.arange(WINDOW)
    return pos[idx, q[:, None]], s


def const_vel(obs: np.ndarray) -> np.ndarray:
    """Constant-velocity prediction ``(S, 12, 2)`` from observations ``(S, 8, 2)``."""
    v = obs[:, -1] - obs[:, -2]
    return obs[:, -1, None] + np.arange(1, PRED + 1)[None, :, None] * v[:, None]


def rollout(model_name: str, traj: np.ndarray, window: np.ndarray, seed: int = 0) -> np.ndarray:
    """A pedestrian model's prediction ``(S, 12, 2)``: the samples of each window simulated together (module
    docstring), every window one world of one batch."""
    from crowdbench.humans import make as make_model
    from crowdbench.humans.base import CrowdState

    groups, slot = np.unique(window, return_inverse=True)
    order = np.argsort(slot, kind="stable")
    counts = np.bincount(slot)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    rank = np.empty(len(slot), np.int64)
    rank[order] = np.arange(len(slot)) - np.repeat(first, counts)
    B, H = len(groups), int(counts.max())
    obs = traj[:, :OBS]
    pos = np.full((B, H, 2), 1e4) + 3.0 * np.arange(H)[None, :, None]  # unused slots parked far apart
    vel, goal = np.zeros((B, H, 2)), pos.copy()
    v_pref, active = np.full((B, H), 1.0), np.zeros((B, H), bool)
    pos[slot, rank] = obs[:, -1]
    vel[slot, rank] = (obs[:, -1] - obs[:, -2]) / DT
    goal[slot, rank] = traj[:, -1]
    steps = np.linalg.norm(np.diff(obs, axis=1), axis=-1) / DT
    v_pref[slot, rank] = np.maximum(steps.mean(axis=1), 1e-3)
    active[slot, rank] = True
    radii = np.full((B, H), 0.3)
    model = make_model(model_name)
    model.bind(B, H, (), DT)
    rngs = [np.random.default_rng([seed, b]) for b in range(B)]
    state = CrowdState(positions=pos, velocities=vel, goals=goal, radii=radii, v_pref=v_pref,
                       headings=np.arctan2(vel[..., 1], vel[..., 0]), active=active,
                       robot_position=np.full((B, 2), -1e6), robot_velocity=np.zeros((B, 2)),
                       robot_radius=np.full(B, 0.3), robot_visible=False, obstacles=(), edges=np.zeros((0, 2, 2)),
                       time_step=DT, spawns=np.zeros((B, H), np.int64))
    model.reset(np.arange(B), rngs, state)
    out = np.empty((len(slot), PRED, 2))
    for k in range(PRED):
        v = np.where(active[..., None], np.asarray(model.step(state, rngs), dtype=np.float64), 0.0)
        vel[:] = v
        pos += v * DT
        moving = np.hypot(v[..., 0], v[..., 1]) > 1e-9
        state.headings[:] = np.where(moving, np.arctan2(v[..., 1], v[..., 0]), state.headings)
        out[:, k] = pos[slot, rank]
    return out


def validate(models: Sequence[str], scenes: Sequence[str] = tuple(SCENES), contiguous: bool = True
             ) -> dict[str, dict[str, dict[str, Any]]]:
    """``{scene: {model: {"ade": m, "fde": m, "samples": n}}}`` on each scene's test recordings."""
    from crowdbench.humans import HUMAN_MODELS

    known = (*PREDICTORS_BUILTIN, *HUMAN_MODELS.names())
    bad = [m for m in models if m not in known]
    if bad or not models:
        raise ValueError(f"--models {','.join(models)!r}; valid choices: {', '.join(known)}")
    bad = [s for s in scenes if s not in SCENES]
    if bad:
        raise ValueError(f"scenes {bad}; valid choices: {', '.join(SCENES)}")
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for scene in scenes:
        parts = [samples(rows, contiguous) for _, rows in scene_recordings(scene, "test")]
        out[scene] = {}
        for m in models:
            err = []
            for traj, window in parts:
                if not len(traj):
                    continue
                pred = const_vel(traj[:, :OBS]) if m == "const_vel" else rollout(m, traj, window)
                err.append(np.linalg.norm(pred - traj[:, OBS:], axis=-1))
            e = np.concatenate(err) if err else np.zeros((0, PRED))
            out[scene][m] = {"ade": float(e.mean()) if len(e) else float("nan"),
                             "fde": float(e[:, -1].mean()) if len(e) else float("nan"), "samples": int(len(e))}
    return out


def markdown(result: dict[str, dict[str, dict[str, Any]]]) -> str:
    """ADE / FDE [m] per scene and model, with the sample counts."""
    models = list(next(iter(result.values())))
    lines = ["| model | " + " | ".join(result) + " | mean |", "|---|" + "---|" * (len(result) + 1)]
    for m in models:
        cells = [f"{result[s][m]['ade']:.3f} / {result[s][m]['fde']:.3f}" for s in result]
        mean_ade = np.mean([result[s][m]["ade"] for s in result])
        mean_fde = np.mean([result[s][m]["fde"] for s in result])
        lines.append(f"| {m} | " + " | ".join(cells) + f" | {mean_ade:.3f} / {mean_fde:.3f} |")
    lines.append("| samples | " + " | ".join(f"{result[s][models[0]]['samples']:,}" for s in result) + " | |")
    return "\n".join(lines)
