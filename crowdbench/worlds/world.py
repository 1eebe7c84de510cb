"""The batched crowd world: ``B`` independent worlds stepped together, each with one robot and ``H`` pedestrians.

State lives in arrays shaped ``(B, A, ...)`` with ``A = 1 + H``; agent 0 is the robot. The simulation core knows
nothing of PettingZoo, Gymnasium or rsl-rl: the environments in :mod:`crowdbench.envs` are thin views over it.

Physics scheme (see README, "Physics"):

* Each world owns a :class:`pymunk.Space` holding the static obstacles (segments, polygons) and one KINEMATIC
  circle body per agent, kept at the agents' positions (spatial queries: :meth:`CrowdWorld.space`). The step's
  arithmetic runs in compiled kernels (:mod:`crowdbench.worlds._kernels`, tested bit for bit against
  :mod:`crowdbench.worlds.reference`); the motion kernel integrates ``p ← p + v·dt``, exactly what ``cpSpaceStep``
  does to a kinematic body, and the bodies follow in one ``pymunk.batch`` call per world, never per agent.
* Collisions follow CrowdNav's semantics — *detected, not resolved*: agents are velocity-controlled and do not push
  each other. The robot collides when its disc touches a pedestrian's or an obstacle's at any time within the step
  (swept test, closest approach of the two linear motions); pedestrian–pedestrian overlaps are counted in the info.
* Nothing passes through an obstacle: before anything moves, every agent's displacement is cut at its time of
  impact with the static edges (vectorised continuous collision detection), so a disc stops at contact. This avoids
  the dynamic-body pitfall where velocity control lets discs tunnel at dt = 0.25 s.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pymunk

from crowdbench.config import WorldConfig
from crowdbench.geometry import norm, obstacle_edges
from crowdbench.humans.base import CrowdState, HumanModel, PedestrianModelError, make
from crowdbench.spatial import GRID_MIN
from crowdbench.worlds._kernels import advance, change_goals, first_clear, spawn_clear
from crowdbench.worlds.layouts import Layout, make_layout
from crowdbench.worlds.physics import PymunkWorlds
from crowdbench.worlds.reference import clip_norm

RUNNING, SUCCESS, COLLISION, TIMEOUT = 0, 1, 2, 3
OUTCOMES = ("running", "success", "collision", "timeout")
REWARD_TERMS = ("success", "collision", "discomfort", "progress", "time")
PARK = 1.0e4
"""Inactive pedestrian slots are parked this far away [m] (beyond every sensing and interaction range)."""


class StepResult:
    """What one batched step produced: views into the three blocks the step allocated — ``(7, B)`` float64 rows
    (five reward terms, reward, d_min), ``(2, B)`` int64 (outcome, overlaps), ``(3, B)`` bool (obstacle hit,
    terminated, truncated) —, so that building it costs nothing and one world's figures come out in a few calls
    (:meth:`scalars`). Every array has leading dimension ``B``; each access returns a fresh view of the same
    memory."""

    __slots__ = ("_f", "_i", "_b")

    def __init__(self, floats: np.ndarray, ints: np.ndarray, flags: np.ndarray) -> None:
        self._f, self._i, self._b = floats, ints, flags

    @property
    def reward(self) -> np.ndarray:
        """Robot reward ``(B,)`` = sum of ``terms``."""
        return self._f[5]

    @property
    def terms(self) -> dict[str, np.ndarray]:
        """Named reward terms (:data:`REWARD_TERMS`), each ``(B,)``."""
        f = self._f
        return {name: f[i] for i, name in enumerate(REWARD_TERMS)}

    @property
    def terminated(self) -> np.ndarray:
        """``(B,)`` bool: success or collision."""
        return self._b[1]

    @property
    def truncated(self) -> np.ndarray:
        """``(B,)`` bool: time limit reached without termination."""
        return self._b[2]

    @property
    def outcome(self) -> np.ndarray:
        """``(B,)`` int: RUNNING, SUCCESS, COLLISION or TIMEOUT."""
        return self._i[0]

    @property
    def d_min(self) -> np.ndarray:
        """Smallest robot–pedestrian surface distance during the step ``(B,)`` [m] (inf without pedestrians)."""
        return self._f[6]

    @property
    def human_overlaps(self) -> np.ndarray:
        """Pedestrian pairs overlapping at the end of the step ``(B,)``."""
        return self._i[1]

    @property
    def robot_hit_obstacle(self) -> np.ndarray:
        """``(B,)`` bool."""
        return self._b[0]

    def done(self, world: int = 0) -> tuple[bool, bool]:
        """World ``world``'s ``(terminated, truncated)`` as Python bools."""
        return self._b.item(1, world), self._b.item(2, world)

    def scalars(self, world: int = 0) -> dict:
        """World ``world``'s figures as Python scalars: ``outcome`` (name), ``reward_terms`` (dict), ``d_min``,
        ``human_overlaps``, ``robot_hit_obstacle``."""
        if world == 0 and self._f.shape[1] == 1:  # one world: contiguous columns
            f, (outcome, overlaps) = self._f.ravel().tolist(), self._i.ravel().tolist()
        else:
            f, (outcome, overlaps) = self._f[:, world].tolist(), self._i[:, world].tolist()
        t = REWARD_TERMS  # a literal dict: half the cost of dict(zip(...)) on this per-step path
        terms = {t[0]: f[0], t[1]: f[1], t[2]: f[2], t[3]: f[3], t[4]: f[4]}
        return {"outcome": OUTCOMES[outcome], "reward_terms": terms, "d_min": f[6], "human_overlaps": overlaps,
                "robot_hit_obstacle": self._b.item(0, world)}


class CrowdWorld:
    """A batch of crowd worlds.

    Args:
        config: Geometry, timing and sensing shared by all worlds.
        num_worlds: Batch size ``B``.
        layout: Layout name or instance.
        human_model: Pedestrian model name or instance (see :mod:`crowdbench.humans`).
        human_model_kwargs: Keyword arguments for a model given by name.

    """

    def __init__(
        self,
        config: WorldConfig | None = None,
        num_worlds: int = 1,
        layout: str | Layout = "circle_crossing",
        human_model: str | HumanModel = "linear",
        human_model_kwargs: dict | None = None,
    ) -> None:
        self.config = config = config or WorldConfig()
        if not isinstance(config, WorldConfig):
            raise ValueError(f"config={config!r}; valid choices: a WorldConfig (crowdbench.config.make_config)")
        if not isinstance(num_worlds, (int, np.integer)) or isinstance(num_worlds, bool) or num_worlds < 1:
            raise ValueError(f"num_worlds={num_worlds!r}; valid choices: an integer ≥ 1")
        if human_model_kwargs is not None and not isinstance(human_model_kwargs, dict):
            raise ValueError(f"human_model_kwargs={human_model_kwargs!r}; valid choices: None or a dict of the "
                             "pedestrian model's arguments")
        self.num_worlds = B = num_worlds
        self.num_humans = H = config.max_humans
        self.num_agents = A = H + 1
        self.layout = make_layout(layout)
        self.human_model = make(human_model, **(human_model_kwargs or {}))
        walls: tuple = ()
        if config.arena_walls:
            s = self.layout.half_size
            corners = [(-s, -s), (s, -s), (s, s), (-s, s)]
            walls = tuple((corners[i], corners[(i + 1) % 4]) for i in range(4))
        self.obstacles = tuple(self.layout.obstacles()) + walls + tuple(config.obstacles)
        self.edges = obstacle_edges(self.obstacles)  # (S, 2, 2)
        self._check_robot_clear(config.robot_radius)
        self.dt = config.time_step

        self.pos = np.zeros((B, A, 2))
        self.vel = np.zeros((B, A, 2))
        self.goal = np.zeros((B, A, 2))
        self.radius = np.full((B, A), config.human_radius)
        self.radius[:, 0] = config.robot_radius
        self.v_pref = np.full((B, A), config.human_v_pref)
        self.v_pref[:, 0] = config.robot_v_pref
        self.heading = np.zeros((B, A))
        self.active = np.zeros((B, A), dtype=bool)
        self.spawns = np.zeros((B, A), dtype=np.int64)
        """``(B, A)``: how many times each agent slot was re-spawned this episode — a slot's occupant is a new person
        whenever its count changes (identity for trackers and per-person model state)."""
        self.steps = np.zeros(B, dtype=np.int64)
        self.prev_goal_dist = np.zeros(B)
        self.rngs: list[np.random.Generator] = [np.random.default_rng(0) for _ in range(B)]
        self.model_rngs: list[np.random.Generator] = [np.random.default_rng(0) for _ in range(B)]
        park_x, park_y = np.meshgrid(PARK + 3.0 * np.arange(A), PARK + 3.0 * np.arange(B))
        self._park = np.stack([park_x, park_y], -1)  # (B, A, 2): distinct, far-away slots

        self.physics = PymunkWorlds(self.radius[0], self.obstacles, B)
        interval = self.layout.goal_change_interval
        self._change_every = round(interval / self.dt) if interval else 0  # steps between random goal changes
        self.human_model.bind(B, H, self.obstacles, self.dt)
        rw = config.reward
        self._rw = np.array([rw.success, rw.collision, rw.discomfort_dist, rw.discomfort_scale, rw.progress_scale,
                             rw.time_penalty, rw.goal_tolerance])
        self._unicycle = config.kinematics == "unicycle"
        self._max_steps = config.max_steps
        self._disp = np.zeros((B, A, 2))  # scratch of the step kernel
        self._still = np.zeros((B, 0, 2))  # the pedestrians' velocities when there are none
        self._hv_shape = (B, H, 2)
        self._reached, self._change_due = np.zeros((B, H), dtype=bool), np.zeros(B, dtype=bool)  # its event outputs
        self._state: CrowdState | None = None
        self.grid_min = GRID_MIN
        """The world's kernels (overlaps, pedestrian observations and clearance) search a world's neighbours on a
        grid of cells when it has more active agents than this, by brute force otherwise: the same results bit for
        bit, so this only trades speed (set it above ``num_agents`` to time the brute force)."""
        self.reset(seeds=list(range(B)))
        self.physics.verify()

    def _check_robot_clear(self, radius: float) -> None:
        from crowdbench.geometry import point_segment_distance
        from crowdbench.worlds.layouts import _inside_polygons

        if self.layout.robot != "fixed":  # drawn per episode, clear of the obstacles (Layout.robot_endpoints)
            return
        pts = np.array([self.layout.robot_start, self.layout.robot_goal], dtype=np.float64)
        if len(self.edges):
            d = point_segment_distance(pts[:, None], self.edges[None, :, 0], self.edges[None, :, 1]).min(axis=1)
            bad = (d <= radius) | _inside_polygons(pts, self.obstacles)
            if bad.any():
                raise ValueError(f"obstacles: the robot's {'start' if bad[0] else 'goal'} "
                                 f"{tuple(pts[int(not bad[0])])} lies on or within {radius} m of an obstacle")

    # ------------------------------------------------------------------ pickling
    def __getstate__(self) -> dict:
        """Everything but pymunk's spaces (C objects that do not pickle; rebuilt from the arrays on load) and the
        cached :class:`CrowdState` (views, rebuilt on first use)."""
        state = self.__dict__.copy()
        state["physics"], state["_state"] = None, None
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update({"grid_min": GRID_MIN, **state})  # (worlds pickled before it existed)
        B = self.num_worlds
        self.physics = PymunkWorlds(self.radius[0], self.obstacles, B)
        for b in range(B):
            self.physics.set_radii(b, self.radius[b])
        self.physics.set_positions(np.arange(B), self.pos)

    def retire(self, mask: np.ndarray) -> None:
        """Take the pedestrians ``mask`` ``(B, H)`` bool out of their episode: inactive, parked far away, at rest
        (multi-agent episodes in which pedestrians finish one by one); back at the next reset."""
        mask = np.asarray(mask, dtype=bool)
        if not mask.any():
            return
        self.active[:, 1:][mask] = False
        self.pos[:, 1:][mask] = self.goal[:, 1:][mask] = self._park[:, 1:][mask]
        self.vel[:, 1:][mask] = 0.0
        worlds = np.flatnonzero(mask.any(axis=1))
        self.physics.set_positions(worlds, self.pos[worlds])

    def space(self, world: int) -> pymunk.Space:
        """The pymunk space of world ``world`` (for spatial queries and custom physics; keep it in sync yourself)."""
        return self.physics.spaces[world]

    # ------------------------------------------------------------------ state views
    def crowd_state(self) -> CrowdState:
        """The batched view handed to pedestrian models: views of the world's arrays, which every step and reset
        update in place (so the view is built once)."""
        if self._state is None:
            self._state = self._crowd_state()
        return self._state

    def _crowd_state(self) -> CrowdState:
        return CrowdState(
            positions=self.pos[:, 1:], velocities=self.vel[:, 1:], goals=self.goal[:, 1:], radii=self.radius[:, 1:],
            v_pref=self.v_pref[:, 1:], headings=self.heading[:, 1:], active=self.active[:, 1:],
            robot_position=self.pos[:, 0], robot_velocity=self.vel[:, 0], robot_radius=self.radius[:, 0],
            robot_visible=self.config.robot_visible, obstacles=self.obstacles, edges=self.edges, time_step=self.dt,
            spawns=self.spawns[:, 1:], layout=self.layout)

    def goal_distance(self) -> np.ndarray:
        """Robot centre to goal ``(B,)`` [m]."""
        return norm(self.goal[:, 0] - self.pos[:, 0])

    # ------------------------------------------------------------------ reset
    def reset(self, seeds: Sequence[int | None] | int | None = None, mask: np.ndarray | None = None) -> None:
        """Start new episodes.

        Args:
            seeds: One seed per selected world (or one int for a single selected world). World ``b``'s episode
                generator is ``np.random.default_rng(seed)`` (layout placement, goal renewal); ``None`` draws fresh
                entropy. The pedestrian model gets a child stream spawned from it (``rng.spawn(1)``), so a model's
                draws never shift the layout's: models with and without randomness see identical crowds.
            mask: ``(B,)`` bool, the worlds to reset (default: all).

        """
        idx = np.arange(self.num_worlds) if mask is None else np.flatnonzero(mask)
        if seeds is None or isinstance(seeds, (int, np.integer)):
            seeds = [seeds] * len(idx) if seeds is None or len(idx) == 1 else [int(seeds) + i for i in range(len(idx))]
        if len(seeds) != len(idx):
            raise ValueError(f"seeds has {len(seeds)} entries for {len(idx)} worlds to reset")
        cfg, lay = self.config, self.layout
        for b, seed in zip(idx, seeds, strict=True):
            rng = self.rngs[b] = np.random.default_rng(seed)
            self.model_rngs[b] = rng.spawn(1)[0]
            n = cfg.num_humans if cfg.humans_range is None else int(rng.integers(cfg.humans_range[0],
                                                                                   cfg.humans_range[1] + 1))
            r_start, r_goal = lay.robot_endpoints(rng, self.edges, cfg.robot_radius)
            self._draw_attributes(b, rng, slice(1, n + 1))
            starts, goals = lay.sample(rng, n, self.radius[b, 1:n + 1], cfg.robot_radius, self.obstacles,
                                       robot_points=np.stack([r_start, r_goal]))
            self.pos[b] = self._park[b]
            self.goal[b] = self._park[b]
            self.pos[b, 0], self.goal[b, 0] = r_start, r_goal
            self.pos[b, 1:n + 1], self.goal[b, 1:n + 1] = starts, goals
            self.active[b] = False
            self.active[b, :n + 1] = True
        d = self.goal[idx] - self.pos[idx]
        self.heading[idx] = np.arctan2(d[..., 1], d[..., 0])
        self.vel[idx] = 0.0
        self.spawns[idx] = 0
        self.steps[idx] = 0
        self.prev_goal_dist[idx] = self.goal_distance()[idx]
        self.physics.set_positions(idx, self.pos[idx])
        self.human_model.reset(idx, self.model_rngs, self.crowd_state())
        self._apply_script()

    def _attribute_draws(self, rng: np.random.Generator, k: int) -> tuple[np.ndarray | None, np.ndarray | None]:
        """``k`` pedestrians' radii [m] and preferred speeds [m/s] drawn from the config's ranges (radii first, then
        speeds, capped at ``human_speed_cap``; None where the config gives fixed values): CrowdNav++'s randomised
        attributes."""
        cfg = self.config
        r = rng.uniform(*cfg.human_radius_range, k) if cfg.human_radius_range is not None else None
        v = rng.uniform(*cfg.human_v_pref_range, k) if cfg.human_v_pref_range is not None else None
        if v is not None and cfg.human_speed_cap is not None:
            v = np.minimum(v, cfg.human_speed_cap)
        return r, v

    def _draw_attributes(self, b: int, rng: np.random.Generator, slots: slice | int) -> None:
        """Per-pedestrian radius and preferred speed of world ``b``'s agents ``slots`` (a slice, or one agent index;
        :meth:`_attribute_draws`; pymunk's shapes follow)."""
        rows = slice(slots, slots + 1) if isinstance(slots, (int, np.integer)) else slots
        r, v = self._attribute_draws(rng, len(self.radius[b, rows]))
        if r is not None:
            self.radius[b, rows] = r
            self.physics.set_radii(b, self.radius[b], slots)
        if v is not None:
            self.v_pref[b, rows] = v

    def set_agents(self, world: int, positions: np.ndarray | None = None, velocities: np.ndarray | None = None,
                   goals: np.ndarray | None = None) -> None:
        """Script the state of world ``world`` (scenario set-up, tests): arrays ``(A, 2)`` for agents
        ``[robot, human_0, ...]`` [m, m/s]; rows for inactive slots are ignored. Keeps pymunk in sync and resets the
        progress reference to the new goal distance."""
        act = self.active[world]
        if positions is not None:
            self.pos[world, act] = np.asarray(positions, dtype=np.float64)[act]
            self.physics.set_positions(np.array([world]), self.pos[world][None])
        if velocities is not None:
            self.vel[world, act] = np.asarray(velocities, dtype=np.float64)[act]
        if goals is not None:
            self.goal[world, act] = np.asarray(goals, dtype=np.float64)[act]
        self.prev_goal_dist[world] = self.goal_distance()[world]

    def physics_positions(self) -> np.ndarray:
        """Agent positions as stored in the pymunk bodies, ``(B, A, 2)`` [m] (equal to :attr:`pos`)."""
        return np.array([[tuple(b.position) for b in s.agent_bodies] for s in self.physics.spaces])

    # ------------------------------------------------------------------ step
    def robot_velocity(self, action: np.ndarray) -> np.ndarray:
        """Planar robot velocity ``(B, 2)`` [m/s] from an action ``(B, 2)``; updates the heading for unicycles.

        holonomic: action = (vx, vy) [m/s], norm clipped to v_pref. unicycle: action = (v [m/s], ω [rad/s]),
        v clipped to [0, v_pref] and ω to ±max_angular_speed; the heading turns by ω·dt before moving.
        """
        action = np.asarray(action, dtype=np.float64).reshape(self.num_worlds, 2)
        vp = self.v_pref[:, 0]
        if self.config.kinematics == "holonomic":
            return clip_norm(action, vp)
        v = np.clip(action[:, 0], 0.0, vp)
        w = np.clip(action[:, 1], -self.config.max_angular_speed, self.config.max_angular_speed)
        self.heading[:, 0] = _wrap(self.heading[:, 0] + w * self.dt)
        return v[:, None] * np.stack([np.cos(self.heading[:, 0]), np.sin(self.heading[:, 0])], -1)

    def step(
        self,
        robot_action: np.ndarray,
        human_actions: np.ndarray | None = None,
        human_override: np.ndarray | None = None,
    ) -> StepResult:
        """Advance every world by one time step.

        Args:
            robot_action: ``(B, 2)``, see :meth:`robot_velocity`.
            human_actions: Optional ``(B, H, 2)`` velocities [m/s] for externally driven pedestrians.
            human_override: ``(B, H)`` bool: which pedestrians follow ``human_actions`` instead of the model. When
                it covers every active pedestrian the pedestrian model is not stepped at all.

        The pedestrian model runs first (its own kernels), then the step's arithmetic in one compiled call
        (:func:`crowdbench.worlds._kernels.advance`, tested bit for bit against the numpy of
        :mod:`crowdbench.worlds.reference`); pymunk's bodies follow in one call per world.
        """
        B = self.num_worlds
        hv = self._still  # (B, 0, 2) without pedestrians
        if self.num_humans:  # from the pre-step state
            if human_override is not None and human_override.any():
                if (human_override | ~self.active[:, 1:]).all():  # everyone driven from outside: no model step
                    hv = np.where(human_override[..., None], human_actions, 0.0)
                else:
                    hv = np.where(human_override[..., None], human_actions,
                                  self._human_velocities(self.crowd_state()))
            else:
                hv = self._human_velocities(self.crowd_state())
        unicycle = self._unicycle
        # the kernel copies both into vel (and clips the holonomic robot's to v_pref)
        rv = self.robot_velocity(robot_action) if unicycle else np.asarray(robot_action, dtype=np.float64)
        floats, ints, flags = np.empty((7, B)), np.empty((2, B), dtype=np.int64), np.empty((3, B), dtype=bool)
        events = advance(rv.reshape(B, 2), hv, self.pos, self.vel, self.v_pref, self.radius, self.active, self.edges,
                         self.dt, 20, self._disp, not unicycle, self.goal, self.heading, self.steps,
                         self.prev_goal_dist, unicycle, self._max_steps, self._rw, self._change_every, floats, ints,
                         flags, self._reached, self._change_due, self.physics.mirror, self.grid_min)
        if events < 0:
            raise self._non_finite(human_override)
        self.physics.sync()  # the kernel wrote the positions into its rows
        if events & 2:  # CrowdNav++'s order: goal changes, then arrivals (crowd_sim_pred.py:201-211)
            self._change_goals(np.flatnonzero(self._change_due))
            if events & 1:  # a changed goal may end an arrival
                self._reached &= self._within_goal()
        if events & 1:
            self._renew_goals(self._reached)
        self._apply_script()
        return StepResult(floats, ints, flags)

    def _human_velocities(self, state: CrowdState) -> np.ndarray:
        """The pedestrian model's velocities ``(B, H, 2)``; a model that raises or returns the wrong shape, NaN or
        inf is reported by name (:class:`~crowdbench.humans.base.PedestrianModelError`), not as a physics error."""
        try:
            hv = np.asarray(self.human_model.step(state, self.model_rngs), dtype=np.float64)
        except Exception as e:
            name = type(self.human_model).__name__
            raise PedestrianModelError(f"pedestrian model {name} failed: {type(e).__name__}: {e}") from e
        if hv.shape != self._hv_shape:
            name = type(self.human_model).__name__
            raise PedestrianModelError(f"pedestrian model {name} returned velocities of shape {hv.shape}; expected "
                                       f"({self.num_worlds}, {self.num_humans}, 2)")
        return hv

    def _non_finite(self, override: np.ndarray | None) -> Exception:
        """The error for NaN or inf velocities of active pedestrians (found by the motion kernel before anything
        moved): the pedestrian model's fault unless they came from ``human_actions``."""
        bad = ~np.isfinite(self.vel[:, 1:]).all(axis=-1) & self.active[:, 1:]
        if override is not None and (bad & override).any():
            return ValueError("human_actions: NaN or inf velocities for externally driven pedestrians "
                              f"{np.argwhere(bad & override).tolist()} (world, pedestrian)")
        return PedestrianModelError(f"pedestrian model {type(self.human_model).__name__} returned NaN or inf "
                                    "velocities")

    def _renew_goals(self, reached: np.ndarray) -> None:
        """Pedestrians within one radius of their goal (``reached`` ``(B, H)`` bool) get a new one by the layout's
        rule (vectorised over worlds; the uniforms come from each world's own generator, one call per world that
        needs any)."""
        bi, hi = np.nonzero(reached)  # sorted by world, then pedestrian
        if not len(bi):
            return
        if self.layout.respawn:
            self._respawn(bi, hi + 1)
            return
        m = self.layout.renew_uniforms
        if m:
            worlds, counts = np.unique(bi, return_counts=True)
            u = np.concatenate([self.rngs[b].random((c, m)) for b, c in zip(worlds, counts, strict=True)])
        else:
            u = np.empty((len(bi), 0))
        self.goal[bi, hi + 1] = self.layout.renew_goals(u, self.pos[bi, hi + 1], self.goal[bi, hi + 1])


    def _apply_script(self) -> None:
        """Place the pedestrians a scripted model moves directly (:meth:`~crowdbench.humans.HumanModel.script`:
        recorded people appearing, leaving, or jumping to their recording): positions and goals set, velocities
        zeroed, activity updated, leavers parked; pymunk follows. A no-op for models without a script."""
        script = self.human_model.script(self.crowd_state())
        if script is None:
            return
        moved, positions, goals, v_pref, active = script
        was = self.active[:, 1:].copy()
        gone = was & ~active
        if not (moved.any() or gone.any() or (active & ~was).any()):
            return
        self.active[:, 1:] |= active
        self.retire(gone)  # leavers: inactive, parked, at rest
        self.pos[:, 1:][moved], self.goal[:, 1:][moved] = positions[moved], goals[moved]
        self.v_pref[:, 1:][moved] = v_pref[moved]
        self.vel[:, 1:][moved] = 0.0
        worlds = np.flatnonzero(moved.any(axis=1))
        if len(worlds):
            self.physics.set_positions(worlds, self.pos[worlds])

    def _within_goal(self) -> np.ndarray:
        """``(B, H)`` bool: active pedestrians within their own radius of their goal (the arrival test)."""
        d = self.goal[:, 1:] - self.pos[:, 1:]
        return self.active[:, 1:] & (d[..., 0] ** 2 + d[..., 1] ** 2 <= self.radius[:, 1:] ** 2)

    def _respawn(self, bi: np.ndarray, ai: np.ndarray) -> None:
        """Replace agents ``ai`` of worlds ``bi`` (pedestrians that reached their goal) by new ones at a fresh start
        of the layout, with new attributes if drawn, at rest; their :attr:`spawns` count goes up. The layout's
        :attr:`~crowdbench.worlds.layouts.Layout.spawn_gap` sets the rule: CrowdNav++'s (the first of
        ``spawn_candidates`` candidates clear of every agent's position and goal — the leaving pedestrian's
        included — by both radii + the gap, else the re-spawn waits a step: the pedestrian stays at its goal), or
        the calibrated crowd's (clear of the others' positions by both radii +
        :data:`~crowdbench.worlds.layouts.PLACEMENT_GAP`, else the last candidate). The slot's pedestrian-model
        state (e.g. its responsiveness) carries over."""
        from crowdbench.worlds.layouts import PLACEMENT_GAP

        lay = self.layout
        gap, m = lay.spawn_gap, lay.spawn_candidates
        for b in (bi[:1] if bi[0] == bi[-1] else np.unique(bi)):
            rng = self.rngs[b]
            for a in ai[bi == b]:
                a = int(a)
                r_new, v_new = self._attribute_draws(rng, 1)
                s, g = lay.respawn_candidates(rng, m)
                s = np.ascontiguousarray(s, dtype=np.float64)
                r = self.radius[b, a] if r_new is None else r_new[0]
                if gap is None:
                    self.radius[b, a] = r
                    k = first_clear(s, self.pos[b], self.radius[b], self.active[b], a, PLACEMENT_GAP)
                else:
                    k = spawn_clear(s, self.pos[b], self.goal[b], self.radius[b], self.active[b], -1, r, gap, True)
                    if k < 0:
                        continue  # no room: the re-spawn waits (tried again next step)
                    self.radius[b, a] = r
                if r_new is not None:
                    self.physics.set_radii(b, self.radius[b], a)
                if v_new is not None:
                    self.v_pref[b, a] = v_new[0]
                self.pos[b, a], self.goal[b, a], self.vel[b, a] = s[k], g[k], 0.0
                self.spawns[b, a] += 1
            self.physics.set_positions(np.array([b]), self.pos[b][None])

    def _change_goals(self, worlds: np.ndarray) -> None:
        """Random goal changes in ``worlds`` (their episode step is a multiple of the layout's interval): each active
        pedestrian takes a new goal with the layout's probability — checked for clearance and kept when none is
        clear (:meth:`Layout.goal_candidates`, CrowdNav++), or :meth:`Layout.changed_goals` unchecked."""
        m, p, lay = self.layout.renew_uniforms, self.layout.goal_change_prob, self.layout
        if lay.spawn_gap is not None and type(lay).goal_candidates is not Layout.goal_candidates:
            for b in worlds.tolist():
                rng = self.rngs[b]
                slots = np.flatnonzero(self.active[b, 1:]) + 1
                change = slots[rng.random(len(slots)) <= p]  # CrowdNav++: random() <= goal_change_chance
                if len(change):
                    cands = np.ascontiguousarray(lay.goal_candidates(rng, self.v_pref[b, change],
                                                                     lay.spawn_candidates))
                    change_goals(cands, change, self.pos[b], self.goal[b], self.radius[b], self.active[b],
                                 lay.spawn_gap)
            return
        for b in worlds.tolist():
            slots = np.flatnonzero(self.active[b, 1:]) + 1
            u = self.rngs[b].random((len(slots), 1 + m))
            pick = u[:, 0] < p
            change = slots[pick]
            if len(change):
                goal = self.goal[b]
                goal[change] = self.layout.changed_goals(u[pick, 1:], self.pos[b, change], goal[change])


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi
