"""Observation builders (plug-ins): batched numpy from the world's state to per-agent observation dicts.

Robot observations (registry :data:`OBSERVATIONS`). Every builder belongs to one **sensing tier**
(:data:`SENSING`), what the robot's sensor gives it; the leaderboard ranks every method at ``positions``:

* ``positions`` — the paper's: each step, the relative positions of the pedestrians within the sensing range
  (CrowdNav++'s ``detect_visible``: surface distance ≤ ``sensing_range``), with their identity (who is who from one
  step to the next), nothing else.
* ``velocities`` — CrowdNav's observable state: plus each sensed pedestrian's true velocity and radius.
* ``full`` — privileged (debugging): every pedestrian, any range, true velocities and radii.

Builders:

* ``relative`` (positions): ``robot`` ``(9,)`` = [px, py, r, gx, gy, v_pref, θ, vx, vy]; ``humans``
  ``(N_max, 2)`` = (Δx, Δy) of the sensed pedestrians, nearest first, zero-padded; ``mask`` ``(N_max,)`` = 1 for
  real entries.
* ``relative_by_id`` (positions): ``relative`` with slot j = pedestrian j (recurrent per-pedestrian states, DS-RNN);
  in a crowd larger than ``N_max``, slots lent to people while they stay in view (:class:`RelativeByIdObservation`).
* ``predicted`` (positions; AIG-GST's, :mod:`crowdbench.predictors.observation`): ``relative`` plus each
  pedestrian's predicted positions; stateful (it keeps the robot's track of what it has seen).
* ``estimated_state`` (positions): the state layout below with velocities *estimated* from the positions
  (:class:`EstimatedStateObservation`), for methods that need velocities (ORCA, Social Force, CADRL, SARL).
* ``observed_state`` (velocities): ``humans`` ``(N_max, 5)`` = (Δx, Δy, vx, vy, r) of the sensed pedestrians,
  nearest first.
* ``full_state`` (full): the same layout for *every* pedestrian (no range limit).

Units: metres, m/s, radians. Arrays are float32.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import ClassVar

import numpy as np
from gymnasium import spaces

from crowdbench.config import WorldConfig
from crowdbench.registry import Registry
from crowdbench.worlds._kernels import assign_slots, human_observation, one_world_observations, robot_observation

BOUND = 1.0e5
"""Finite bound of the Box spaces [m or m/s] (parked padding slots sit at 1e4 m)."""


SENSING = ("positions", "velocities", "full")
"""Sensing tiers, least to most information (see the module docstring)."""
STATE_OBSERVATIONS = {"positions": "estimated_state", "velocities": "observed_state", "full": "full_state"}
"""The ``(Δx, Δy, vx, vy, r)`` builder of each tier, for policies that read pedestrian states."""


def check_sensing(sensing: str, field: str = "sensing") -> str:
    """``sensing`` if it is a tier of :data:`SENSING`, else one ``ValueError`` naming ``field`` and the tiers."""
    if sensing not in SENSING:
        raise ValueError(f"{field}={sensing!r}; valid choices: {', '.join(SENSING)}")
    return sensing


def check_tier(observation: str, allowed: str | None) -> None:
    """A ``ValueError`` when robot observation ``observation`` needs a higher tier than ``allowed`` (None: any)."""
    if allowed is None:
        return
    check_sensing(allowed)
    need = observation_sensing(observation)
    if SENSING.index(need) > SENSING.index(allowed):
        raise ValueError(f"observation {observation!r} needs sensing tier {need!r}, but this environment gives "
                         f"sensing={allowed!r}; valid choices for the policy: a tier in "
                         f"{', '.join(SENSING[:SENSING.index(allowed) + 1])} (e.g. the policy's sensing= option)")


def observation_sensing(observation: str) -> str:
    """The sensing tier of robot observation builder ``observation`` (a registry name)."""
    return OBSERVATIONS.get(observation).sensing


class Observation(ABC):
    """Robot observation builder. ``build`` returns a dict of float32 arrays with leading dimension ``B``."""

    name: str = ""
    sensing: ClassVar[str] = "positions"
    """The sensing tier (:data:`SENSING`) of what :meth:`build` reveals."""

    def __init__(self, config: WorldConfig) -> None:
        self.config = config

    @abstractmethod
    def space(self) -> spaces.Dict:
        """Single-world observation space."""

    @abstractmethod
    def build(self, world) -> dict[str, np.ndarray]:
        """Batched observation of ``world`` (a :class:`~crowdbench.worlds.CrowdWorld`)."""

    def reward(self, obs: dict[str, np.ndarray]) -> np.ndarray | None:
        """Optional: a training reward term ``(B,)`` computed from what this observation shows (added to the world's
        reward on the steps that did not end the episode; AIG-GST's prediction-intrusion penalty). ``None``: none."""
        return None

    def fused_spec(self, world) -> tuple[int, float, int, bool] | None:
        """``(features, max_range, slots, by_id)`` where the one compiled kernel of :func:`agent_observations` builds
        this observation of a one-world ``world`` together with the pedestrians'; ``None`` (the default): it does
        not, and :meth:`build` runs."""
        return None


OBSERVATIONS: Registry[Observation] = Registry("robot observation", "crowdbench.observations")


def _robot_arrays(B: int, n_max: int, features: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Uninitialised outputs of the robot builders: robot ``(B, 9)``, humans ``(B, n_max, features)``, mask
    ``(B, n_max)`` (float32; the kernels write every element)."""
    return (np.empty((B, 9), np.float32), np.empty((B, n_max, features), np.float32),
            np.empty((B, n_max), np.float32))


def _human_arrays(H: int, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Uninitialised outputs of the pedestrians' builder: self ``(H, 9)``, neighbors ``(H, n, 5)``, mask ``(H, n)``."""
    return np.empty((H, 9), np.float32), np.empty((H, n, 5), np.float32), np.empty((H, n), np.float32)


def _build(world, features: int, max_range: float, n_max: int, by_id: bool = False) -> dict[str, np.ndarray]:
    """Robot vector, pedestrian features ``(B, n_max, features)`` (nearest first, or slot ``j`` = pedestrian ``j``
    with ``by_id``) and mask (one compiled kernel)."""
    robot, humans, mask = _robot_arrays(world.num_worlds, n_max, features)
    robot_observation(world.pos, world.vel, world.goal, world.radius, world.v_pref, world.heading, world.active,
                      max_range, by_id, robot, humans, mask)
    return {"robot": robot, "humans": humans, "mask": mask}


def nearest_first(rel: np.ndarray, seen: np.ndarray, feats: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Every pedestrian's features cut to the ``n`` nearest in view, nearest first (ties by index).

    Args:
        rel: Positions relative to the robot ``(B, H, 2)`` [m].
        seen: In view ``(B, H)`` bool.
        feats: Per-pedestrian features ``(B, H, F)``.
        n: Slots (``N_max``); with fewer people in view, the rest are zero with mask 0.

    Returns:
        ``humans`` ``(B, n, F)`` float32 and ``mask`` ``(B, n)`` float32.
    """
    B, H, F = feats.shape
    dist = np.where(seen, np.hypot(rel[..., 0], rel[..., 1]), np.inf)
    k = min(n, H)
    order = np.argsort(dist, axis=1, kind="stable")[:, :k]
    humans = np.zeros((B, n, F), np.float32)
    mask = np.zeros((B, n), np.float32)
    mask[:, :k] = np.take_along_axis(seen, order, 1)
    humans[:, :k] = np.where(mask[:, :k, None] > 0.5, np.take_along_axis(feats, order[..., None], 1), 0.0)
    return humans, mask


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
        return _build(world, *self.kernel_spec())

    def kernel_spec(self) -> tuple[int, float, int, bool]:
        """``(features, max_range, slots, by_id)`` of the compiled builder (:func:`agent_observations` fuses it
        with the pedestrians' observations)."""
        return 2, self.config.sensing_range, self.config.max_humans_observed, False

    def fused_spec(self, world) -> tuple[int, float, int, bool] | None:
        """:meth:`kernel_spec`: the one compiled kernel builds this observation of any one-world ``world``."""
        return self.kernel_spec()


@OBSERVATIONS.register("relative_by_id")
class RelativeByIdObservation(RelativeObservation):
    """The paper's observation with each slot following one person instead of nearest first. For recurrent
    policies that keep a state per pedestrian (DS-RNN's spatial-edge GRUs follow one person each).

    * Up to ``N_max`` pedestrians in the world: ``humans[j]`` is pedestrian ``j``'s (Δx, Δy), zero with
      ``mask[j] = 0`` while it is outside ``sensing_range`` or absent (one compiled kernel, stateless).
    * More pedestrians than slots (a large crowd): slots are lent to people as they come into view and kept while
      they stay in it (:func:`~crowdbench.worlds._kernels.assign_slots`): a slot frees when its person leaves the
      sensing range or is re-spawned, and everyone in view without a slot takes a free one, nearest first; with
      more people in view than slots, those farthest wait for a slot to free. A slot's recurrent state then passes
      to its next person, as a re-spawned pedestrian's does. Stateful in this case, so one builder serves one batch
      of worlds; a world whose step counter restarts (a new episode) starts with every slot free.
    """

    name = "relative_by_id"

    def __init__(self, config: WorldConfig) -> None:
        super().__init__(config)
        self._slots: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    def kernel_spec(self) -> tuple[int, float, int, bool]:
        return 2, self.config.sensing_range, self.config.max_humans_observed, True

    def fused_spec(self, world) -> tuple[int, float, int, bool] | None:
        """The stateless kernel up to ``N_max`` pedestrians; ``None`` (lent slots, stateful) beyond."""
        return self.kernel_spec() if world.num_humans <= self.config.max_humans_observed else None

    def build(self, world) -> dict[str, np.ndarray]:
        B, H, n = world.num_worlds, world.num_humans, self.config.max_humans_observed
        if n >= H:
            return _build(world, *self.kernel_spec())
        obs = _build(world, 2, self.config.sensing_range, H, by_id=True)
        seen = obs["mask"] > 0.5
        if self._slots is None or self._slots[1].shape != (B, H):
            self._slots = (np.full((B, n), -1, np.int64), np.full((B, H), -1, np.int64),
                           np.zeros((B, H), np.int64), np.full(B, -2, np.int64))
        who, slot_of, last_spawns, last_step = self._slots
        dist = np.hypot(obs["humans"][..., 0], obs["humans"][..., 1]).astype(np.float64)
        assign_slots(seen, dist, world.spawns[:, 1:], world.steps, who, slot_of, last_spawns, last_step)
        held = who >= 0
        idx = np.where(held, who, 0)
        humans = np.where(held[..., None], np.take_along_axis(obs["humans"], idx[..., None], 1), 0.0)
        return {"robot": obs["robot"], "humans": humans.astype(np.float32), "mask": held.astype(np.float32)}


@OBSERVATIONS.register("full_state")
class FullStateObservation(Observation):
    """Full observability (tier ``full``): every pedestrian's relative position, velocity and radius."""

    name = "full_state"
    sensing = "full"

    def space(self) -> spaces.Dict:
        n = self.config.max_humans_observed
        return spaces.Dict({"robot": _robot_box(), "humans": spaces.Box(-BOUND, BOUND, (n, 5), np.float32),
                            "mask": spaces.Box(0.0, 1.0, (n,), np.float32)})

    def build(self, world) -> dict[str, np.ndarray]:
        return _build(world, *self.kernel_spec())

    def kernel_spec(self) -> tuple[int, float, int, bool]:
        """See :meth:`RelativeObservation.kernel_spec`."""
        return 5, np.inf, self.config.max_humans_observed, False

    def fused_spec(self, world) -> tuple[int, float, int, bool] | None:
        """See :meth:`RelativeObservation.fused_spec`."""
        return self.kernel_spec()


@OBSERVATIONS.register("observed_state")
class ObservedStateObservation(FullStateObservation):
    """Tier ``velocities`` (CrowdNav's observable state): (Δx, Δy, vx, vy, r) of the pedestrians within the sensing
    range, nearest first — true velocities and radii."""

    name = "observed_state"
    sensing = "velocities"

    def kernel_spec(self) -> tuple[int, float, int, bool]:
        """See :meth:`RelativeObservation.kernel_spec`."""
        return 5, self.config.sensing_range, self.config.max_humans_observed, False


@OBSERVATIONS.register("estimated_state")
class EstimatedStateObservation(Observation):
    """Tier ``positions`` for methods that need pedestrian states: the ``full_state`` layout (Δx, Δy, v̂x, v̂y, r̂)
    of the pedestrians within the sensing range, nearest first, built from what ``relative_by_id`` gives.

    * **Velocity estimator**: the finite difference of a pedestrian's last two sightings on consecutive steps,
      v̂ = (p_t − p_{t−1}) / dt (world frame; the robot knows its own position). A pedestrian seen for the first
      time — or again after a gap, or a slot whose person was re-spawned — has no velocity yet: v̂ = 0.
    * **Radius**: not sensed; every pedestrian is given r̂ = the largest radius the world's configuration allows
      (``human_radius_range[1]``, else ``human_radius``) — a conservative prior, not a measurement.

    Stateful (it keeps the last sightings), so one builder serves one batch of worlds; a world whose step counter
    restarts (a new episode) starts with no sightings.
    """

    name = "estimated_state"
    sensing = "positions"

    def __init__(self, config: WorldConfig) -> None:
        super().__init__(config)
        rr = config.human_radius_range
        self.assumed_radius = float(rr[1] if rr is not None else config.human_radius)
        self._last: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    def space(self) -> spaces.Dict:
        n = self.config.max_humans_observed
        return spaces.Dict({"robot": _robot_box(), "humans": spaces.Box(-BOUND, BOUND, (n, 5), np.float32),
                            "mask": spaces.Box(0.0, 1.0, (n,), np.float32)})

    def build(self, world) -> dict[str, np.ndarray]:
        B, H, n = world.num_worlds, world.num_humans, self.config.max_humans_observed
        obs = _build(world, 2, self.config.sensing_range, H, by_id=True)
        seen = obs["mask"] > 0.5  # (B, H)
        pos = obs["humans"].astype(np.float64) + world.pos[:, None, 0]  # world frame (B, H, 2)
        spawns, steps = world.spawns[:, 1:], world.steps
        vel = np.zeros((B, H, 2))
        last = self._last
        if last is not None and last[0].shape == pos.shape:
            p0, seen0, spawns0, steps0 = last
            ok = seen & seen0 & (spawns == spawns0) & (steps == steps0 + 1)[:, None]
            vel = np.where(ok[..., None], (pos - p0) / world.dt, 0.0)
        self._last = (pos, seen, spawns.copy(), steps.copy())
        feats = np.concatenate([obs["humans"], vel.astype(np.float32),
                                np.full((B, H, 1), self.assumed_radius, np.float32)], -1)
        humans, mask = nearest_first(obs["humans"], seen, feats, n)
        return {"robot": obs["robot"], "humans": humans, "mask": mask}


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
    """Observations of all pedestrian slots of world ``b`` (one compiled kernel): arrays ``(H, ...)``."""
    cfg = world.config
    me, nb, mask = _human_arrays(world.num_humans, cfg.max_humans_observed)
    human_observation(world.pos, world.vel, world.goal, world.radius, world.v_pref, world.heading, world.active, b,
                      cfg.human_sensing_range, cfg.robot_visible, me, nb, mask, world.grid_min)
    return {"self": me, "neighbors": nb, "mask": mask}


def agent_observations(builder: Observation, world) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The robot's observation (``builder``, arrays with a leading dimension of 1) and every pedestrian slot's
    (:func:`human_observations`) of a one-world ``world``: one compiled call for the compiled builders
    (``relative``, ``relative_by_id``, ``full_state``: their ``kernel_spec``), the builder then the pedestrians'
    kernel for any other, or where the builder's ``fused_spec`` declines the world."""
    compiled = type(builder).build in _COMPILED_BUILDS and world.num_worlds == 1  # (a subclass may override build)
    spec = builder.fused_spec(world) if compiled else None
    if spec is None:
        return builder.build(world), human_observations(world, 0)
    features, max_range, n_max, by_id = spec
    cfg = world.config
    robot, humans, mask = _robot_arrays(1, n_max, features)
    me, nb, hmask = _human_arrays(world.num_humans, cfg.max_humans_observed)
    one_world_observations(world.pos, world.vel, world.goal, world.radius, world.v_pref, world.heading,
                           world.active, max_range, by_id, cfg.human_sensing_range, cfg.robot_visible, robot, humans,
                           mask, me, nb, hmask, world.grid_min)
    return {"robot": robot, "humans": humans, "mask": mask}, {"self": me, "neighbors": nb, "mask": hmask}


_COMPILED_BUILDS = (RelativeObservation.build, RelativeByIdObservation.build, FullStateObservation.build)
"""Builders :func:`agent_observations` fuses with the pedestrians' kernel (``ObservedState`` inherits the last)."""

OBSERVATIONS.register("predicted", "crowdbench.predictors.observation:PredictedObservation")


def make_observation(name: str, config: WorldConfig, **kwargs) -> Observation:
    """Robot observation builder by registry name (``kwargs``: the builder's options, e.g. ``predicted``'s
    ``predictor``)."""
    if not isinstance(name, str):
        raise ValueError(f"observation={name!r}; valid choices: {', '.join(OBSERVATIONS.names())}")
    return OBSERVATIONS.make(name, config=config, **kwargs) if kwargs else OBSERVATIONS.get(name)(config)
