"""Episode metrics shared by ``crowdbench evaluate``, ``tables`` and ``leaderboard``: the paper's six, the field's
social metrics, and 95 % confidence intervals.

Per episode (distances are edge to edge, "pedestrian" = an active one, steps of Δt):

* ``outcome`` — success, collision or timeout; ``time`` [s]; ``path_length`` [m]; ``max_delta_v`` [m/s], the largest
  ‖v_t − v_{t−1}‖ from rest (the paper's six, with the rates and means below);
* ``min_distance`` [m] — the smallest robot–pedestrian distance, swept within steps (negative = overlap);
* ``personal_space`` [-] — share of steps with every pedestrian more than 0.5 m from the robot's edge;
* ``min_ttc`` [s] — the smallest time to collision under constant velocities at any step, capped at 5 s (0 = touching);
* ``jerk`` [m/s³] — mean ‖(a_t − a_{t−1})/Δt‖ of the robot, a_t = (v_t − v_{t−1})/Δt, from rest;
* ``spl`` [-] — success × ℓ / max(path, ℓ), ℓ = straight start–goal distance less the goal tolerance (Anderson et al.
  2018);
* ``irregularity`` [rad] — mean angle between the robot's motion and the direction to its goal, weighted by distance;
* ``intrusions_unaware`` / ``intrusions_aware`` [-] — pedestrian-steps within 0.5 m of the robot's edge while that
  pedestrian's latent state ξ is 0 (has not noticed the robot) / 1 (models without ξ: all counted as unaware);
* ``ped_progress`` / ``ped_progress_alone`` [m] — the pedestrians' summed progress towards their goals, with the robot
  and in a counterfactual run of the same seed with the robot absent (pedestrians blind to it; only when requested).

Aggregates (:func:`summarize`): success / collision / timeout rates with **Wilson** 95 % intervals; navigation time and
path length over successful episodes and Δv over all, with **bootstrap** 95 % intervals (2,000 resamples, fixed seed);
the means of the social metrics; ``unaware_share`` = unaware / all intrusions; ``ped_delay`` = progress alone / progress
with the robot − 1 (the extra time pedestrians need per metre because of the robot).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PERSONAL_SPACE = 0.5
"""Edge-to-edge distance below which a pedestrian's personal space is entered [m]."""
TTC_CAP = 5.0
"""Time-to-collision values are capped here (ORCA's horizon) [s]."""
Z95 = 1.959963984540054


@dataclass
class Episode:
    """One finished episode (units in :mod:`crowdbench.metrics`)."""

    seed: int
    outcome: str
    time: float
    path_length: float
    max_delta_v: float
    min_distance: float = math.nan
    personal_space: float = math.nan
    min_ttc: float = math.nan
    jerk: float = math.nan
    spl: float = math.nan
    irregularity: float = math.nan
    intrusions_unaware: float = math.nan
    intrusions_aware: float = math.nan
    ped_progress: float = math.nan
    ped_progress_alone: float = math.nan


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval of a rate ``k / n``."""
    if n == 0:
        return (math.nan, math.nan)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def bootstrap_mean(values: np.ndarray, resamples: int = 2000, seed: int = 0) -> tuple[float, float]:
    """Percentile-bootstrap 95 % interval of the mean of ``values`` (NaN for fewer than 2 values)."""
    x = np.asarray(values, dtype=np.float64)
    if len(x) < 2:
        return (math.nan, math.nan)
    idx = np.random.default_rng(seed).integers(0, len(x), (resamples, len(x)))
    means = x[idx].mean(axis=1)
    return (float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975)))


def summarize(episodes: list[Episode]) -> dict:
    """The paper's columns plus the social metrics, and ``ci``: 95 % intervals of the paper's columns."""
    n = len(episodes)
    if n == 0:
        raise ValueError("summarize needs at least one episode")
    ok = [e for e in episodes if e.outcome == "success"]
    counts = {k: sum(e.outcome == k for e in episodes) for k in ("success", "collision", "timeout")}
    times = np.array([e.time for e in ok])
    paths = np.array([e.path_length for e in ok])
    dv = np.array([e.max_delta_v for e in episodes])
    out: dict = {
        "episodes": n,
        "success_rate": counts["success"] / n,
        "collision_rate": counts["collision"] / n,
        "timeout_rate": counts["timeout"] / n,
        "nav_time": float(times.mean()) if ok else math.nan,
        "path_length": float(paths.mean()) if ok else math.nan,
        "delta_v": float(dv.mean()),
    }

    def mean(field: str) -> float:
        v = np.array([getattr(e, field) for e in episodes], dtype=np.float64)
        v = v[np.isfinite(v)]
        return float(v.mean()) if len(v) else math.nan

    for field in ("min_distance", "personal_space", "min_ttc", "jerk", "spl", "irregularity", "intrusions_unaware",
                  "intrusions_aware"):
        out[field] = mean(field)
    unaware = sum(e.intrusions_unaware for e in episodes if np.isfinite(e.intrusions_unaware))
    aware = sum(e.intrusions_aware for e in episodes if np.isfinite(e.intrusions_aware))
    out["unaware_share"] = unaware / (unaware + aware) if unaware + aware > 0 else math.nan
    with_robot = sum(e.ped_progress for e in episodes if np.isfinite(e.ped_progress_alone))
    alone = sum(e.ped_progress_alone for e in episodes if np.isfinite(e.ped_progress_alone))
    out["ped_delay"] = alone / with_robot - 1.0 if with_robot > 0 else math.nan
    out["ci"] = {f"{k}_rate": list(wilson(c, n)) for k, c in counts.items()}
    out["ci"].update(nav_time=list(bootstrap_mean(times)), path_length=list(bootstrap_mean(paths)),
                     delta_v=list(bootstrap_mean(dv)))
    return out


class EpisodeMeter:
    """Running per-world accumulators of the social metrics over a batch of ``B`` worlds (vectorised; updated once
    per step by the episode runner)."""

    def __init__(self, num_worlds: int, dt: float, goal_tolerance: float) -> None:
        self.dt, self.tol = dt, goal_tolerance
        B = num_worlds
        self.min_distance = np.full(B, np.inf)
        self.clear_steps = np.zeros(B)
        self.min_ttc = np.full(B, TTC_CAP)
        self.jerk_sum = np.zeros(B)
        self.jerk_steps = np.zeros(B)
        self.prev_acc = np.zeros((B, 2))
        self.angle_dist = np.zeros(B)
        self.straight = np.zeros(B)
        self.unaware = np.zeros(B)
        self.aware = np.zeros(B)
        self.progress = np.zeros(B)
        self.progress_alone = np.full(B, np.nan)

    def start(self, worlds: np.ndarray, world) -> None:
        """New episodes in ``worlds`` (indices) of ``world`` (after its reset)."""
        self.min_distance[worlds] = np.inf
        self.min_ttc[worlds] = TTC_CAP
        for a in (self.clear_steps, self.jerk_sum, self.jerk_steps, self.angle_dist, self.unaware, self.aware,
                  self.progress):
            a[worlds] = 0.0
        self.prev_acc[worlds] = 0.0
        self.progress_alone[worlds] = np.nan
        gap = np.linalg.norm(world.goal[worlds, 0] - world.pos[worlds, 0], axis=-1)
        self.straight[worlds] = np.maximum(gap - self.tol, 0.0)

    def update(self, world, res, prev_pos: np.ndarray, prev_vel: np.ndarray, prev_goal: np.ndarray,
               twin=None, twin_prev: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        """Account one step of every world: ``prev_pos`` and ``prev_goal`` are every agent's position and goal
        ``(B, A, 2)`` and ``prev_vel`` the robot's velocity ``(B, 2)`` before it; ``twin`` is the counterfactual world
        (robot absent) stepped alongside, ``twin_prev`` its (positions, goals) ``(B, A, 2)`` before the step."""
        dt = self.dt
        self.min_distance = np.minimum(self.min_distance, res.d_min)
        rel = world.pos[:, 1:] - world.pos[:, :1]
        act = world.active[:, 1:]
        gap = np.linalg.norm(rel, axis=-1) - world.radius[:, 1:] - world.radius[:, :1]
        near = act & (gap < PERSONAL_SPACE)
        self.clear_steps += ~near.any(axis=1)
        xi = world.human_model.info().get("xi")
        aware = near & xi if xi is not None else np.zeros_like(near)
        self.aware += aware.sum(axis=1)
        self.unaware += (near & ~aware).sum(axis=1)
        # time to collision under constant velocities, from the post-step state
        v = world.vel[:, 1:] - world.vel[:, :1]
        r = world.radius[:, 1:] + world.radius[:, :1]
        a = np.einsum("bhi,bhi->bh", v, v)
        b = np.einsum("bhi,bhi->bh", rel, v)
        c = np.einsum("bhi,bhi->bh", rel, rel) - r * r
        disc = b * b - a * c
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.where((disc >= 0) & (b < 0) & (a > 0), (-b - np.sqrt(np.maximum(disc, 0))) / a, np.inf)
        t = np.where(c <= 0, 0.0, t)
        self.min_ttc = np.minimum(self.min_ttc, np.where(act, t, np.inf).min(axis=1, initial=np.inf))
        # jerk and irregularity of the robot
        vel = world.vel[:, 0]
        acc = (vel - prev_vel) / dt
        self.jerk_sum += np.where(self.jerk_steps >= 1, np.linalg.norm(acc - self.prev_acc, axis=-1) / dt, 0.0)
        self.jerk_steps += 1
        self.prev_acc = acc
        move = world.pos[:, 0] - prev_pos[:, 0]
        dist = np.linalg.norm(move, axis=-1)
        to_goal = world.goal[:, 0] - prev_pos[:, 0]
        cos = np.einsum("bi,bi->b", move, to_goal) / np.maximum(dist * np.linalg.norm(to_goal, axis=-1), 1e-12)
        self.angle_dist += np.arccos(np.clip(cos, -1.0, 1.0)) * dist
        self.progress += _progress(world, prev_pos, prev_goal)
        if twin is not None and twin_prev is not None:
            step = _progress(twin, *twin_prev)
            self.progress_alone = np.where(np.isnan(self.progress_alone), 0.0, self.progress_alone) + step

    def episode(self, b: int, outcome: str, path_length: float) -> dict[str, float]:
        """The metrics of world ``b``'s finished episode (steps counted by the runner's calls to :meth:`update`)."""
        steps = max(self.jerk_steps[b], 1.0)
        success = outcome == "success"
        return {
            "min_distance": float(self.min_distance[b]),
            "personal_space": float(self.clear_steps[b] / steps),
            "min_ttc": float(self.min_ttc[b]),
            "jerk": float(self.jerk_sum[b] / max(self.jerk_steps[b] - 1, 1)),
            "spl": float(success * self.straight[b] / max(path_length, self.straight[b], 1e-12)),
            "irregularity": float(self.angle_dist[b] / path_length) if path_length > 0 else math.nan,
            "intrusions_unaware": float(self.unaware[b]),
            "intrusions_aware": float(self.aware[b]),
            "ped_progress": float(self.progress[b]),
            "ped_progress_alone": float(self.progress_alone[b]),
        }


def _progress(world, prev_pos: np.ndarray, prev_goal: np.ndarray) -> np.ndarray:
    """Summed progress of each world's active pedestrians towards the goals they had before the step ``(B,)`` [m]
    (``prev_*``: ``(B, A, 2)`` before it); a re-spawned pedestrian (moved farther than its speed allows) counts 0."""
    pos, prev_pos, prev_goal = world.pos[:, 1:], prev_pos[:, 1:], prev_goal[:, 1:]
    before = np.linalg.norm(prev_goal - prev_pos, axis=-1)
    after = np.linalg.norm(prev_goal - pos, axis=-1)
    step = before - after
    limit = world.v_pref[:, 1:] * world.dt + 1e-9
    ok = world.active[:, 1:] & (np.linalg.norm(pos - prev_pos, axis=-1) <= limit)
    return np.where(ok, step, 0.0).sum(axis=1)
