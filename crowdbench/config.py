"""Typed, frozen configuration of a crowd world. Every field carries its unit."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from crowdbench.validate import check_fields

KINEMATICS = ("holonomic", "unicycle")
MAX_HUMANS = 1000
"""Upper bound on pedestrians per world (ORCA's pairwise work and memory grow with its square)."""


@dataclass(frozen=True)
class RewardConfig:
    """The paper's reward (§Reward Function Design). Terms are reported by name in ``info["reward_terms"]``."""

    success: float = 10.0
    """Reward when the goal distance is ≤ ``goal_tolerance`` [-]."""
    collision: float = -20.0
    """Reward when the robot touches a pedestrian or an obstacle during the step [-]."""
    discomfort_dist: float = 0.25
    """Surface-to-surface distance below which the discomfort penalty applies [m]."""
    discomfort_scale: float = 10.0
    """Penalty is ``discomfort_scale * (d_min - discomfort_dist)`` for ``0 < d_min < discomfort_dist`` [1/m]."""
    progress_scale: float = 4.0
    """Otherwise ``progress_scale * (previous - current goal distance)`` [1/m]."""
    time_penalty: float = -0.025
    """Added on every step [-]."""
    goal_tolerance: float = 0.3
    """Success when the robot centre is within this distance of its goal [m]."""

    def __post_init__(self) -> None:
        check_fields(self)
        if not self.goal_tolerance > 0 or not self.discomfort_dist >= 0:
            raise ValueError(f"goal_tolerance={self.goal_tolerance}, discomfort_dist={self.discomfort_dist}; valid "
                             "choices: goal_tolerance > 0 and discomfort_dist ≥ 0 [m]")


@dataclass(frozen=True)
class WorldConfig:
    """Geometry, timing and sensing of a batch of crowd worlds.

    All worlds of a batch share one config. Unknown keys are an error (see :func:`make_config`).
    """

    num_humans: int = 20
    """Pedestrians per world [-]. ``humans_range`` overrides it with a per-episode draw."""
    humans_range: tuple[int, int] | None = None
    """If set, each episode draws its pedestrian count uniformly from ``[lo, hi]`` (inclusive) [-]."""
    max_humans_observed: int = 30
    """``N_max``: the robot observation is padded (or cut, nearest first) to this many pedestrians [-]."""
    time_step: float = 0.25
    """Simulation step [s]."""
    time_limit: float = 50.0
    """Episode truncation time [s]."""
    robot_radius: float = 0.3
    """[m]"""
    human_radius: float = 0.3
    """Pedestrian radius when ``human_radius_range`` is None [m]."""
    robot_v_pref: float = 1.0
    """Robot preferred (and maximum) speed [m/s]."""
    human_v_pref: float = 1.0
    """Pedestrian preferred (and maximum) speed when ``human_v_pref_range`` is None [m/s]."""
    human_radius_range: tuple[float, float] | None = (0.3, 0.5)
    """Each pedestrian's radius is drawn per episode (and per re-spawn) from U(lo, hi) — CrowdNav++'s
    ``randomize_attributes`` (``crowd_sim/envs/utils/agent.py:44-50``); None: every pedestrian has ``human_radius``
    [m]."""
    human_v_pref_range: tuple[float, float] | None = (0.5, 1.5)
    """Each pedestrian's ``v_pref`` is drawn from U(lo, hi) (then capped at ``human_speed_cap`` if set) — CrowdNav++'s
    range. It is the pedestrian's speed *limit*; how fast it prefers to walk is the pedestrian model's (CrowdNav++'s
    ORCA: 1 m/s, :class:`~crowdbench.humans.orca.ORCAParams`). None: ``human_v_pref`` [m/s]."""
    human_speed_cap: float | None = None
    """Optional upper bound on drawn ``v_pref`` (None: no cap, as CrowdNav++) [m/s]."""
    sensing_range: float = 5.0
    """Robot sensing range: pedestrians whose surface distance to the robot (centre distance minus both radii,
    CrowdNav++'s ``detect_visible``) is larger are not observed [m]."""
    human_sensing_range: float = 5.0
    """Range of each pedestrian's own observation of its neighbours [m]."""
    kinematics: str = "holonomic"
    """``"holonomic"`` (action = planar velocity, clipped to v_pref) or ``"unicycle"`` (action = (v, ω))."""
    max_angular_speed: float = math.pi
    """Unicycle turn-rate limit [rad/s]."""
    robot_visible: bool = True
    """If False the robot is invisible to pedestrian models (CrowdNav's ``robot.visible = False``)."""
    arena_walls: bool = False
    """Surround the layout's arena with four wall segments."""
    obstacles: tuple[tuple[tuple[float, float], ...], ...] = ()
    """Extra static obstacles: each a vertex list; 2 vertices = a wall segment, ≥ 3 = a closed polygon [m]."""
    reward: RewardConfig = field(default_factory=RewardConfig)

    def __post_init__(self) -> None:
        check_fields(self)
        if self.kinematics not in KINEMATICS:
            raise ValueError(f"kinematics={self.kinematics!r}; valid choices: {', '.join(KINEMATICS)}")
        positive = ("time_step", "time_limit", "robot_radius", "human_radius", "robot_v_pref", "human_v_pref",
                    "sensing_range", "human_sensing_range", "max_angular_speed")
        for name in positive:
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        if not 0 <= self.num_humans <= MAX_HUMANS:
            raise ValueError(f"num_humans={self.num_humans}; valid choices: 0 … {MAX_HUMANS}")
        if not 1 <= self.max_humans_observed <= MAX_HUMANS:
            raise ValueError(f"max_humans_observed={self.max_humans_observed}; valid choices: 1 … {MAX_HUMANS}")
        if self.humans_range is not None:
            lo, hi = self.humans_range
            if not 0 <= lo <= hi <= MAX_HUMANS:
                raise ValueError(f"humans_range={self.humans_range}; valid choices: (lo, hi) with 0 ≤ lo ≤ hi ≤ "
                                 f"{MAX_HUMANS}")
        if self.human_speed_cap is not None and not self.human_speed_cap > 0:
            raise ValueError(f"human_speed_cap={self.human_speed_cap!r}; valid choices: None or a speed > 0 [m/s]")
        for name in ("human_radius_range", "human_v_pref_range"):
            rng = getattr(self, name)
            if rng is not None and not (len(rng) == 2 and 0 < rng[0] <= rng[1]):
                raise ValueError(f"{name}={rng!r}; valid choices: None or (lo, hi) with 0 < lo ≤ hi")
        for k, poly in enumerate(self.obstacles):
            if len(poly) < 2:
                raise ValueError(f"obstacles[{k}] needs ≥ 2 vertices, got {len(poly)}")

    @property
    def max_humans(self) -> int:
        """Pedestrian slots per world (the padded array size ``H``)."""
        return self.humans_range[1] if self.humans_range is not None else self.num_humans

    @property
    def max_steps(self) -> int:
        """Steps before truncation: ``ceil(time_limit / time_step)``."""
        return math.ceil(self.time_limit / self.time_step - 1e-9)


def make_config(**kwargs: Any) -> WorldConfig:
    """Build a :class:`WorldConfig`, rejecting unknown keys with the list of valid ones."""
    valid = {f.name for f in dataclasses.fields(WorldConfig)}
    unknown = sorted(set(kwargs) - valid)
    if unknown:
        raise TypeError(f"unknown world option(s) {unknown}; valid options: {', '.join(sorted(valid))}")
    for key in ("human_radius_range", "human_v_pref_range"):
        if isinstance(kwargs.get(key), list):
            kwargs[key] = tuple(kwargs[key])
    if isinstance(kwargs.get("reward"), dict):
        rvalid = {f.name for f in dataclasses.fields(RewardConfig)}
        bad = sorted(set(kwargs["reward"]) - rvalid)
        if bad:
            raise TypeError(f"unknown reward option(s) {bad}; valid options: {', '.join(sorted(rvalid))}")
        kwargs["reward"] = RewardConfig(**kwargs["reward"])
    if "obstacles" in kwargs:
        try:
            kwargs["obstacles"] = tuple(tuple((float(x), float(y)) for x, y in poly) for poly in kwargs["obstacles"])
        except (TypeError, ValueError):
            raise ValueError(f"obstacles={kwargs['obstacles']!r}; valid choices: a list of obstacles, each a list of "
                             "(x, y) vertices [m]") from None
    hr = kwargs.get("humans_range")
    if isinstance(hr, (list, tuple)) and all(isinstance(v, (int, np.integer)) for v in hr):
        kwargs["humans_range"] = tuple(int(v) for v in hr)
    return WorldConfig(**kwargs)
