"""Recorded people as pedestrians: ``replay`` and ``reactive_replay`` (layouts ``eth``, ``hotel``, ``univ``,
``zara1``, ``zara2``; :mod:`crowdbench.worlds.recorded`).

Per episode each world draws one of its scene's test recordings and a start frame (uniformly, so that a ``horizon``
of recording follows), then gives the recorded people of that window to the pedestrian slots: a person takes the
first slot free over the whole time it is present, in order of appearance (``num_humans`` is the cap on people
present at once; one who finds no free slot is left out). A person is present at time t when both annotated frames
around t exist; its position is the linear interpolation between them (frames are 0.4 s apart, world steps need
not be). It appears at its recorded position and leaves by disappearing (:meth:`HumanModel.script`); its goal is its
last recorded position and its speed limit its fastest recorded speed (so the world never clips it).

* ``replay`` — everyone moves exactly as recorded, regardless of the robot (SocNavBench's setting).
* ``reactive_replay`` — the recorded path is each person's preferred velocity, ``v_rec + (p_rec − p)/τ`` (τ = 1 s:
  off the path, it steers back), and each person runs ORCA against the robot alone (CrowdNav++'s ORCA settings,
  robot visible): it avoids the robot when it comes near, then rejoins its recording. People never avoid each other
  beyond what the recording shows.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from crowdbench.datasets.ethucy import DT as FRAME_DT
from crowdbench.humans.base import CrowdState, HumanModel, register
from crowdbench.humans.orca import ORCAParams
from crowdbench.humans.orca_kernel import build_obstacles, orca_batch


def _window(pos: np.ndarray, t0: int, frames: int, dt: float, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``(steps, P, 2)`` [m] and presence ``(steps, P)`` of the recording ``pos`` ``(T, P, 2)`` (NaN =
    not annotated) at world times ``k·dt`` after frame ``t0``, interpolated between annotated frames."""
    w = pos[t0:t0 + frames]
    x = np.arange(steps) * dt / FRAME_DT
    j = np.minimum(np.floor(x).astype(np.int64), len(w) - 1)
    j1 = np.minimum(j + 1, len(w) - 1)
    f = (x - j)[:, None, None]
    p = w[j] * (1 - f) + w[j1] * f
    exact = (f[:, 0, 0] < 1e-9)[:, None]
    present = ~np.isnan(w[j][..., 0]) & (exact | ~np.isnan(w[j1][..., 0]))
    p = np.where(exact[..., None], w[j], p)
    return np.where(present[..., None], p, 0.0), present


class _Recorded(HumanModel):
    """Shared machinery: per world, the episode's recorded window laid out on the slots."""

    def __init__(self, horizon: float = 60.0) -> None:
        if not horizon > 0:
            raise ValueError(f"horizon={horizon!r}; valid choices: a duration > 0 [s]")
        self.horizon = float(horizon)
        self.dropped = np.zeros(0, dtype=np.int64)

    def bind(self, num_worlds: int, num_humans: int, obstacles, time_step: float) -> None:
        super().bind(num_worlds, num_humans, obstacles, time_step)
        self.dt = time_step
        self.steps = math.ceil(self.horizon / time_step) + 2
        B, H, K = num_worlds, num_humans, self.steps
        self._pos = np.zeros((B, K, H, 2))
        self._present = np.zeros((B, K, H), dtype=bool)
        self._who = np.full((B, K, H), -1, dtype=np.int64)
        self._goal = np.zeros((B, H, 2))
        self._vmax = np.ones((B, H))
        self._k = np.zeros(B, dtype=np.int64)
        self._placed = np.zeros((B, H), dtype=np.int64) - 1  # who each slot shows now
        self.dropped = np.zeros(B, dtype=np.int64)
        self._goals_by_slot = np.zeros((B, K, H, 2))
        self._vmax_by_slot = np.ones((B, K, H))

    def reset(self, worlds: np.ndarray, rngs: Sequence[np.random.Generator], state: CrowdState) -> None:
        recordings = getattr(state.layout, "recordings", None)
        if not recordings:
            raise ValueError(f"human_model={self.name!r} replays recorded people; valid layouts: eth, hotel, univ, "
                             f"zara1, zara2 (got {getattr(state.layout, 'name', state.layout)!r})")
        names = sorted(recordings)
        K, H = self.steps, self.num_humans
        frames = math.ceil(self.horizon / FRAME_DT) + 2
        for b in worlds:
            rng = rngs[b]
            _, _, pos = recordings[names[int(rng.integers(len(names)))]]
            t0 = int(rng.integers(0, max(1, len(pos) - frames + 1)))
            p, present = _window(pos, t0, frames, self.dt, K)
            people = np.flatnonzero(present.any(axis=0))
            first = present[:, people].argmax(axis=0)
            last = K - 1 - present[::-1, people].argmax(axis=0)
            speed = np.linalg.norm(np.diff(p[:, people], axis=0), axis=-1) / self.dt
            speed = np.where(present[1:, people] & present[:-1, people], speed, 0.0).max(axis=0, initial=0.0)
            self._pos[b], self._present[b], self._who[b] = 0.0, False, -1
            free_from = np.zeros(H, dtype=np.int64)  # the first step each slot is free again
            dropped = 0
            for i in np.argsort(first, kind="stable"):
                q, k0, k1 = people[i], first[i], last[i]
                slot = np.flatnonzero(free_from <= k0)
                if not len(slot):
                    dropped += 1
                    continue
                h = slot[0]
                free_from[h] = k1 + 2  # one empty step between occupants: leaving and arriving never coincide
                span = slice(k0, k1 + 1)
                self._present[b, span, h] = present[span, q]
                self._pos[b, span, h] = p[span, q]
                self._who[b, span, h] = q
                self._goals_by_slot[b, span, h] = p[k1, q]
                self._vmax_by_slot[b, span, h] = max(1.5, 1.25 * speed[i])
            self.dropped[b] = dropped
            self._k[b] = 0
            self._placed[b] = -1

    def script(self, state: CrowdState) -> tuple[np.ndarray, ...]:
        b = np.arange(self.num_worlds)
        k = np.minimum(self._k, self.steps - 1)
        present, who = self._present[b, k], np.where(self._present[b, k], self._who[b, k], -1)
        moved = present & (who != self._placed)
        self._placed = who
        return (moved, self._pos[b, k], self._goals_by_slot[b, k], self._vmax_by_slot[b, k], present)

    def _targets(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Recorded positions at the next step ``(B, H, 2)``, their velocities ``(B, H, 2)`` and which slots keep
        the same person present through the step ``(B, H)``."""
        b = np.arange(self.num_worlds)
        k = np.minimum(self._k, self.steps - 2)
        nxt = self._pos[b, k + 1]
        keep = self._present[b, k] & self._present[b, k + 1] & (self._who[b, k] == self._who[b, k + 1])
        return nxt, (nxt - self._pos[b, k]) / self.dt, keep

    def info(self) -> dict[str, np.ndarray]:
        return {"recorded_id": self._placed.copy()}


@register("replay")
class Replay(_Recorded):
    """Recorded people moving exactly as recorded, blind to the robot (module docstring). Args: ``horizon`` [s] of
    recording per episode (past it the scene is empty)."""

    name = "replay"

    def step(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        nxt, _, keep = self._targets()
        self._k += 1
        return np.where(keep[..., None], (nxt - state.positions) / self.dt, 0.0)


@register("reactive_replay")
class ReactiveReplay(_Recorded):
    """Recorded paths as preferred velocities, ORCA against the robot only (module docstring). Args: ``horizon``
    [s]; ``tau`` [s], how fast a displaced person steers back to its recording; ``orca``: :class:`ORCAParams`
    fields for the robot avoidance."""

    name = "reactive_replay"

    def __init__(self, horizon: float = 60.0, tau: float = 1.0, **orca) -> None:
        super().__init__(horizon)
        if not tau > 0:
            raise ValueError(f"tau={tau!r}; valid choices: a time > 0 [s]")
        self.tau = float(tau)
        self.params = ORCAParams.of("pedestrian model reactive_replay", **orca)
        self._obst = build_obstacles([])

    def step(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        _, v_rec, keep = self._targets()
        b = np.arange(self.num_worlds)
        k = np.minimum(self._k, self.steps - 1)
        off = self._pos[b, k] - state.positions
        self._k += 1
        B, H, p = self.num_worlds, self.num_humans, self.params
        vmax = self._vmax_by_slot[b, k]
        pref = v_rec + off / self.tau
        speed = np.linalg.norm(pref, axis=-1)
        pref *= np.minimum(1.0, vmax / np.maximum(speed, 1e-12))[..., None]
        # one two-agent ORCA problem per pedestrian: [robot, pedestrian]
        n = B * H
        pos = np.stack([np.repeat(state.robot_position, H, axis=0), state.positions.reshape(n, 2)], 1)
        vel = np.stack([np.repeat(state.robot_velocity, H, axis=0), state.velocities.reshape(n, 2)], 1)
        prefs = np.stack([np.zeros((n, 2)), pref.reshape(n, 2)], 1)
        pad = p.radius_pad + p.safety_space
        rad = np.stack([np.repeat(state.robot_radius, H), state.radii.reshape(n)], 1) + pad
        vm = np.stack([np.ones(n), vmax.reshape(n)], 1)
        act = np.stack([np.full(n, bool(state.robot_visible)), keep.reshape(n)], 1)
        ctrl = np.zeros((n, 2), dtype=bool)
        ctrl[:, 1] = True
        out = np.zeros((n, 2, 2))
        orca_batch(pos, vel, prefs, rad, vm, np.full((n, 2), p.neighbor_dist), np.ones((n, 2), np.int64),
                   np.full((n, 2), p.time_horizon), np.full((n, 2), p.time_horizon_obst), act, ctrl,
                   np.full((n, 2), -1, np.int64), *self._obst, self.dt, out)
        return np.where(keep[..., None], out[:, 1].reshape(B, H, 2), 0.0)
