"""ORCA pedestrians (RVO2-faithful, batched numba kernel) and a drop-in replacement for Python-RVO2.

* :class:`ORCA` — the pedestrian model: every pedestrian runs ORCA toward its goal among the other pedestrians, the
  static obstacles and (when visible) the robot. CrowdNav's defaults.
* :class:`PyRVOSimulator` — Python-RVO2's API (``rvo2.PyRVOSimulator``) on top of the same kernel, so code written
  for the unmaintained ``rvo2`` package runs unchanged: ``from crowdbench.humans.orca import PyRVOSimulator``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from crowdbench.humans.base import CrowdState, HumanModel, register
from crowdbench.humans.orca_kernel import build_obstacles, orca_advance, orca_neighbors, orca_step
from crowdbench.validate import check_fields


@dataclass(frozen=True)
class ORCAParams:
    """ORCA parameters, CrowdNav++'s pedestrians by default (``crowd_nav/policy/orca.py``,
    ``configs/config.py:116-120``, ``crowd_sim/envs/utils/agent.py:20-23``): a unit preferred velocity capped by
    each pedestrian's ``v_pref``, horizons 5 s, a 0.15 m safety space, every agent a neighbour, and the
    neighbour distance drawn from U(5, 10) m.
    CrowdNav's original pedestrians: ``safety_space=0, max_neighbors=10, neighbor_dist_range=None``."""

    neighbor_dist: float = 10.0
    """Neighbours are searched within this distance [m] (when ``neighbor_dist_range`` is None)."""
    neighbor_dist_range: tuple[float, float] | None = (5.0, 10.0)
    """CrowdNav++'s quirk, mirrored: every agent it creates redraws ``neighbor_dist`` ~ U(lo, hi) into the *shared*
    config, and an ORCA simulator reads it once, when it is built. So the crowd placed at reset shares the last draw
    (one U(lo, hi) per episode here), and a re-spawned pedestrian takes a fresh draw of its own while the others
    keep theirs. None: ``neighbor_dist`` for everyone [m]."""
    preferred_speed: float | None = 1.0
    """Length of the preferred velocity [m/s]: the goal vector cut to this length — CrowdNav++'s unit vector, the
    raw goal vector within 1 m (``orca.py:98-100``) — while ``v_pref`` is only the speed limit (``orca.py:86``):
    a pedestrian cruises at min(1, v_pref) m/s and exceeds 1 m/s only while avoiding. None: ``v_pref`` toward the
    goal, landing on it within a step (RVO2's examples, crowdbench's calibrated crowd)."""
    max_neighbors: int | None = None
    """At most this many agent neighbours; ``None`` = every agent within ``neighbor_dist`` (CrowdNav++) [-]."""
    time_horizon: float = 5.0
    """Agent–agent avoidance horizon [s]."""
    time_horizon_obst: float = 5.0
    """Agent–obstacle avoidance horizon [s]."""
    radius_pad: float = 0.01
    """Added to every agent's radius inside ORCA (CrowdNav's ``radius + 0.01``) [m]."""
    safety_space: float = 0.15
    """Extra clearance added to every radius inside ORCA [m] (CrowdNav++: 0.15 for pedestrians and robot)."""

    def __post_init__(self) -> None:
        check_fields(self)
        for name in ("neighbor_dist", "time_horizon", "time_horizon_obst", "safety_space", "preferred_speed"):
            v = getattr(self, name)
            if isinstance(v, int) and not isinstance(v, bool):  # one float kernel signature, not one per type
                object.__setattr__(self, name, float(v))
        for name in ("neighbor_dist", "time_horizon", "time_horizon_obst"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if self.max_neighbors is not None and self.max_neighbors < 0:
            raise ValueError(f"max_neighbors must be ≥ 0 or None (every agent), got {self.max_neighbors}")
        if self.safety_space < 0:
            raise ValueError(f"safety_space must be ≥ 0, got {self.safety_space}")
        r = self.neighbor_dist_range
        if r is not None and not (len(r) == 2 and 0 < r[0] <= r[1]):
            raise ValueError(f"neighbor_dist_range={r!r}; valid choices: None or (lo, hi) with 0 < lo ≤ hi [m]")
        if self.preferred_speed is not None and not self.preferred_speed > 0:
            raise ValueError(f"preferred_speed={self.preferred_speed!r}; valid choices: None (v_pref) or a speed "
                             "> 0 [m/s]")

    @classmethod
    def of(cls, owner: str, **params) -> ORCAParams:
        """``ORCAParams(**params)``, an unknown name being one ``ValueError`` naming ``owner`` and the valid ones."""
        valid = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(params) - set(valid))
        if unknown:
            raise ValueError(f"{owner}: unknown argument(s) {unknown}; valid choices: {', '.join(valid)}")
        if isinstance(params.get("neighbor_dist_range"), list):
            params = {**params, "neighbor_dist_range": tuple(params["neighbor_dist_range"])}
        return cls(**params)

    def neighbors(self, num_agents: int) -> int:
        """The neighbour cap for a world of ``num_agents`` agents."""
        return num_agents if self.max_neighbors is None else self.max_neighbors


class ORCABase(HumanModel):
    """Shared machinery: agent arrays ``[robot, humans...]`` per world, handed to :func:`orca_batch`."""

    def __init__(self, **params) -> None:
        self.params = ORCAParams.of(f"pedestrian model {type(self).__name__}", **params)

    def bind(self, num_worlds: int, num_humans: int, obstacles, time_step: float) -> None:
        super().bind(num_worlds, num_humans, obstacles, time_step)
        p, B, A = self.params, num_worlds, num_humans + 1
        self._obst = build_obstacles(obstacles) if obstacles else build_obstacles([])
        # orca_step's agent arrays [robot, pedestrians...] in four blocks (fewer arguments to pass per call):
        self._vec = np.zeros((4, B, A, 2))  # positions, velocities, preferred velocities, output [m, m/s]
        self._flt = np.zeros((5, B, A))  # radii, max speeds, neighbour distance, time horizons (agents, obstacles)
        self._flt[2:] = np.array([p.neighbor_dist, p.time_horizon, p.time_horizon_obst])[:, None, None]
        self._int = np.full((2, B, A), -1, dtype=np.int64)  # neighbour caps, robot slot to ignore (-1: nobody)
        self._int[0] = p.neighbors(A)
        self._flags = np.ones((2, B, A), dtype=bool)  # active, controlled (not the robot: the world moves it)
        self._flags[1, :, 0] = False
        self._pad = p.radius_pad + p.safety_space  # added to every radius [m]
        self._pref_speed = p.preferred_speed or 0.0  # 0: v_pref (orca_inputs)
        self._seen, self._hidden = np.zeros((B, num_humans), dtype=bool), np.ones((B, num_humans), dtype=bool)
        self._spawns = np.zeros((B, num_humans), dtype=np.int64)  # the world's re-spawn counts at the last draw
        self._nd_rngs: list[np.random.Generator] = [np.random.default_rng(0) for _ in range(B)]

    def reset(self, worlds: np.ndarray, rngs: Sequence[np.random.Generator], state: CrowdState) -> None:
        """New episodes in ``worlds``: with ``neighbor_dist_range``, one neighbour distance per world, shared by
        its whole crowd (CrowdNav++'s quirk, :class:`ORCAParams`)."""
        r = self.params.neighbor_dist_range
        if r is None:
            return
        for b in worlds:  # a child stream of the world's: a subclass's own draws from rngs[b] stay as they were
            self._nd_rngs[b] = rngs[b].spawn(1)[0]
            self._flt[2, b] = self._nd_rngs[b].uniform(*r)
        spawns = getattr(state, "spawns", None)
        if spawns is not None:
            self._spawns[worlds] = spawns[worlds]

    def _redraw_respawned(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> None:
        """A re-spawned pedestrian (its slot's ``spawns`` count changed) draws its own neighbour distance."""
        spawns = getattr(state, "spawns", None)
        if self.params.neighbor_dist_range is None or spawns is None:
            return
        new = spawns != self._spawns
        if new.any():
            for b, h in zip(*np.nonzero(new), strict=True):
                self._flt[2, b, h + 1] = self._nd_rngs[b].uniform(*self.params.neighbor_dist_range)
            self._spawns[new] = spawns[new]

    def robot_ignored(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        """``(B, H)`` bool: pedestrians that leave the robot out of their neighbour set this step (read-only)."""
        return self._hidden if not state.robot_visible else self._seen

    def step(self, state: CrowdState, rngs: Sequence[np.random.Generator]) -> np.ndarray:
        """ORCA velocities ``(B, H, 2)`` [m/s] in one compiled call (:func:`orca_step`: ``orca_inputs`` fills the
        agent arrays — :func:`~crowdbench.humans.preferred_velocity` toward each goal —, ``orca_batch`` solves)."""
        self._redraw_respawned(state, rngs)
        ignore_robot = self.robot_ignored(state, rngs)
        if ignore_robot.__class__ is not np.ndarray or ignore_robot.dtype != np.bool_ \
                or ignore_robot.shape != state.active.shape:
            ignore_robot = np.broadcast_to(np.asarray(ignore_robot, dtype=bool), state.active.shape)
        orca_step(state.robot_position, state.robot_velocity, state.robot_radius, state.positions, state.velocities,
                  state.goals, state.radii, state.v_pref, state.active, ignore_robot, self._pad, state.time_step,
                  self._pref_speed, self._vec, self._flt, self._int, self._flags, *self._obst)
        return self._vec[3, :, 1:]  # a view, rewritten by the next step (the world copies it); no stored view: a
        # deep copy of the model (the "truth" predictor) must not keep one into the original's memory


@register("orca")
class ORCA(ORCABase):
    """RVO2 ORCA pedestrians. The robot is a neighbour whenever it is visible (``robot_visible``); keyword arguments
    are :class:`ORCAParams` fields."""


class PyRVOSimulator:
    """Drop-in replacement for Python-RVO2's ``rvo2.PyRVOSimulator`` (same constructor and method names).

    Args:
        timeStep: [s]. neighborDist: [m]. maxNeighbors: [-]. timeHorizon, timeHorizonObst: [s]. radius: [m].
        maxSpeed: [m/s]. velocity: initial velocity of added agents [m/s].

    ``doStep`` runs the batched numba kernel once for all agents (float64). Obstacles become active after
    ``processObstacles()``, as in RVO2.
    """

    def __init__(self, timeStep: float, neighborDist: float, maxNeighbors: int, timeHorizon: float,
                 timeHorizonObst: float, radius: float, maxSpeed: float, velocity: tuple[float, float] = (0.0, 0.0)):
        self.time_step = float(timeStep)
        self.defaults = (float(neighborDist), int(maxNeighbors), float(timeHorizon), float(timeHorizonObst),
                         float(radius), float(maxSpeed), (float(velocity[0]), float(velocity[1])))
        self.global_time = 0.0
        # agents in orca_advance's blocks, one world: positions, velocities, preferred velocities, scratch [m, m/s];
        # radii, max speeds, neighbour distances, time horizons, obstacle time horizons; neighbour caps, ignored
        # slot; active, controlled
        self._vec = np.zeros((4, 1, 0, 2))
        self._flt = np.zeros((5, 1, 0))
        self._int = np.zeros((2, 1, 0), np.int64)
        self._flags = np.ones((2, 1, 0), bool)
        self._xy: list[list[float]] | None = None  # positions as Python lists, made on demand (fast getters)
        self._new: list[tuple] = []  # agents added since the blocks were last extended (:meth:`_flush`)
        self._pending: list[list[tuple[float, float]]] = []
        self._obstacles: list[list[tuple[float, float]]] = []
        self._obst = build_obstacles([])
        self._last: tuple | None = None  # the state the last doStep started from (for the neighbour queries)
        self._neighbors: tuple[np.ndarray, ...] | None = None

    # --- agents
    def addAgent(self, pos, neighborDist=None, maxNeighbors=None, timeHorizon=None, timeHorizonObst=None,
                 radius=None, maxSpeed=None, velocity=None) -> int:
        d = self.defaults
        nd, mn, th, tho, r, ms = (g if g is not None else dv for g, dv in
                                  zip((neighborDist, maxNeighbors, timeHorizon, timeHorizonObst, radius, maxSpeed),
                                      d[:6], strict=True))
        v = velocity if velocity is not None else d[6]
        self._new.append((float(pos[0]), float(pos[1]), float(v[0]), float(v[1]), float(r), float(ms), float(nd),
                          float(th), float(tho), int(mn)))
        return self.getNumAgents() - 1

    def _flush(self) -> None:
        """Append the agents added since the last flush to the blocks, in one copy (adding agents one by one stays
        linear in their number)."""
        if not self._new:
            return
        a = np.array(self._new, float)  # (n, 10): position, velocity, radius, max speed, neighbour distance, horizons
        k = len(a)
        vec = np.zeros((4, 1, k, 2))
        vec[0, 0], vec[1, 0] = a[:, 0:2], a[:, 2:4]
        ints = np.stack([np.array([x[9] for x in self._new], np.int64), np.full(k, -1, np.int64)])[:, None]
        self._vec = np.concatenate([self._vec, vec], axis=2)
        self._flt = np.concatenate([self._flt, a[:, 4:9].T[:, None]], axis=2)
        self._int = np.concatenate([self._int, ints], axis=2)
        self._flags = np.concatenate([self._flags, np.ones((2, 1, k), bool)], axis=2)
        self._new, self._xy = [], None

    def getNumAgents(self) -> int:
        return self._vec.shape[2] + len(self._new)

    def _check(self, agent_no: int) -> int:
        self._flush()
        if not 0 <= agent_no < self._vec.shape[2]:
            raise IndexError(f"agent_no={agent_no} out of range; {self._vec.shape[2]} agents")
        return agent_no

    def _set2(self, block: int, agent_no: int, xy) -> None:
        i = self._check(agent_no)
        self._vec[block, 0, i, 0] = float(xy[0])
        self._vec[block, 0, i, 1] = float(xy[1])

    def _set_parameter(self, row: int, agent_no: int, value: float, ints: bool = False) -> None:
        """Row ``row`` of the float parameters (``ints``: of the integer ones) of agent ``agent_no`` set to
        ``value``, the agents added so far in the blocks first; the last step's neighbour queries keep the
        parameters that step ran with (copied on this first write)."""
        i = self._check(agent_no)
        if self._last is not None and self._last[1] is self._flt:
            self._last = (self._last[0], self._flt.copy(), self._int.copy())
        (self._int if ints else self._flt)[row, 0, i] = value

    def setAgentPrefVelocity(self, agent_no: int, velocity) -> None:
        self._set2(2, agent_no, velocity)

    def setAgentPosition(self, agent_no: int, position) -> None:
        self._set2(0, agent_no, position)
        self._xy = None

    def setAgentVelocity(self, agent_no: int, velocity) -> None:
        self._set2(1, agent_no, velocity)

    def setAgentRadius(self, agent_no: int, radius: float) -> None:
        self._set_parameter(0, agent_no, float(radius))

    def setAgentMaxSpeed(self, agent_no: int, max_speed: float) -> None:
        self._set_parameter(1, agent_no, float(max_speed))

    def setAgentNeighborDist(self, agent_no: int, dist: float) -> None:
        self._set_parameter(2, agent_no, float(dist))

    def setAgentMaxNeighbors(self, agent_no: int, n: int) -> None:
        self._set_parameter(0, agent_no, int(n), ints=True)

    def setAgentTimeHorizon(self, agent_no: int, t: float) -> None:
        self._set_parameter(3, agent_no, float(t))

    def setAgentTimeHorizonObst(self, agent_no: int, t: float) -> None:
        self._set_parameter(4, agent_no, float(t))

    def getAgentPosition(self, agent_no: int) -> tuple[float, float]:
        i = self._check(agent_no)
        if self._xy is None:
            self._xy = self._vec[0, 0].tolist()
        return tuple(self._xy[i])

    def getAgentVelocity(self, agent_no: int) -> tuple[float, float]:
        i = self._check(agent_no)
        return float(self._vec[1, 0, i, 0]), float(self._vec[1, 0, i, 1])

    def getAgentPrefVelocity(self, agent_no: int) -> tuple[float, float]:
        i = self._check(agent_no)
        return float(self._vec[2, 0, i, 0]), float(self._vec[2, 0, i, 1])

    def getAgentRadius(self, agent_no: int) -> float:
        i = self._check(agent_no)
        return float(self._flt[0, 0, i])

    def getAgentMaxSpeed(self, agent_no: int) -> float:
        i = self._check(agent_no)
        return float(self._flt[1, 0, i])

    def getGlobalTime(self) -> float:
        return self.global_time

    def getTimeStep(self) -> float:
        return self.time_step

    def setTimeStep(self, time_step: float) -> None:
        self.time_step = float(time_step)

    # --- obstacles
    def addObstacle(self, vertices) -> int:
        """Add a polygon (counter-clockwise vertices; 2 vertices = segment). Active after :meth:`processObstacles`."""
        if len(vertices) < 2:
            raise ValueError("addObstacle needs at least 2 vertices")
        first = sum(len(o) for o in self._obstacles) + sum(len(o) for o in self._pending)
        self._pending.append([(float(x), float(y)) for x, y in vertices])
        return first

    def processObstacles(self) -> None:
        self._obstacles.extend(self._pending)
        self._pending = []
        self._obst = build_obstacles(self._obstacles)

    def getNumObstacleVertices(self) -> int:
        """Obstacle vertices after :meth:`processObstacles` — RVO2's count, edges split by its obstacle tree
        included."""
        return len(self._obst[0])

    # --- neighbours of the last step (RVO2: computed in doStep from the state it started from)
    def _neighbor_lists(self) -> tuple[np.ndarray, ...]:
        if self._last is None:
            raise RuntimeError("agent neighbours exist after doStep; valid choices: call doStep first")
        if self._neighbors is None:
            pos, flt, ints = self._last
            n, V = pos.shape[1], len(self._obst[0])
            k = max(int(ints[0].max()), 1)
            out = (np.empty((1, n, k), np.int64), np.empty((1, n), np.int64), np.empty((1, n, max(V, 1)), np.int64),
                   np.empty((1, n), np.int64))
            orca_neighbors(pos, flt[0], flt[1], flt[2], ints[0], flt[4], np.ones((1, n), bool), ints[1],
                           self._obst[0], self._obst[1], self._obst[5], *out)
            self._neighbors = out
        return self._neighbors

    def getAgentNumAgentNeighbors(self, agent_no: int) -> int:
        return int(self._neighbor_lists()[1][0, agent_no])

    def getAgentAgentNeighbor(self, agent_no: int, neighbor_no: int) -> int:
        nb, cnt = self._neighbor_lists()[:2]
        if not 0 <= neighbor_no < cnt[0, agent_no]:
            raise IndexError(f"neighbor_no={neighbor_no}; valid choices: 0 … {cnt[0, agent_no] - 1}")
        return int(nb[0, agent_no, neighbor_no])

    def getAgentNumObstacleNeighbors(self, agent_no: int) -> int:
        return int(self._neighbor_lists()[3][0, agent_no])

    def getAgentObstacleNeighbor(self, agent_no: int, neighbor_no: int) -> int:
        nb, cnt = self._neighbor_lists()[2:]
        if not 0 <= neighbor_no < cnt[0, agent_no]:
            raise IndexError(f"neighbor_no={neighbor_no}; valid choices: 0 … {cnt[0, agent_no] - 1}")
        return int(nb[0, agent_no, neighbor_no])

    def getObstacleVertex(self, vertex_no: int) -> tuple[float, float]:
        return float(self._obst[0][vertex_no, 0]), float(self._obst[0][vertex_no, 1])

    def getNextObstacleVertexNo(self, vertex_no: int) -> int:
        return int(self._obst[1][vertex_no])

    def getPrevObstacleVertexNo(self, vertex_no: int) -> int:
        return int(self._obst[2][vertex_no])

    # --- simulation
    def doStep(self) -> None:
        """Advance all agents by one time step (synchronous: all new velocities from the old state), in place:
        :func:`~crowdbench.humans.orca_kernel.orca_advance` on the agent blocks."""
        self._flush()
        if self._vec.shape[2]:
            self._last, self._neighbors = (self._vec[0].copy(), self._flt, self._int), None  # parameters: copy on write
            orca_advance(self._vec, self._flt, self._int, self._flags, *self._obst, self.time_step)
            self._xy = None
        self.global_time += self.time_step
