"""Crowd layouts: where the robot and the pedestrians start, where they go, and what replaces a reached goal.

A layout is a plug-in: subclass :class:`Layout`, implement :meth:`Layout.candidates` and :meth:`Layout.renew_goals`,
and register it with :func:`register`. Placement is bounded (see :func:`place_without_overlap`): a layout that cannot
fit the requested crowd raises ``ValueError`` instead of looping forever.
"""

# numba-cache-key: crowdbench.geometry 31fac0ddc665
# numba-cache-key: crowdbench.worlds._kernels 34b006d3166a

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import ClassVar

import numba as nb
import numpy as np

from crowdbench.geometry import Polygon, obstacle_edges, point_segment_distance
from crowdbench.registry import Registry

LAYOUTS: Registry[Layout] = Registry("layout", "crowdbench.layouts")
register = LAYOUTS.register

PLACEMENT_GAP = 0.2
"""Extra clearance between any two start positions (and any two goals) at placement [m] (CrowdNav's discomfort_dist)."""
ROBOT_MODES = ("fixed", "random")


class Layout(ABC):
    """Geometry of one crowd scenario.

    Class attributes:
        name: Registry name.
        robot_start, robot_goal: Robot start and goal [m].
        half_size: Half-width of the square arena used for walls, rendering and wandering [m].
    """

    name: ClassVar[str] = ""
    robot_start: tuple[float, float] = (0.0, -6.0)
    robot_goal: tuple[float, float] = (0.0, 6.0)
    half_size: float = 7.0
    separate_goals: ClassVar[bool] = True
    """Whether goals must be as far apart as starts (False for layouts whose goals lie on a shared exit line)."""
    spacing: float = 0.8
    """Mean clearance between two pedestrians' centres at placement (set by :func:`place_without_overlap`) [m]."""
    placement_gap: float = PLACEMENT_GAP
    """Clearance beyond both radii between start positions (and goals) at placement [m] (:func:`place_without_overlap`;
    dense layouts use less)."""
    robot: str = "fixed"
    """``fixed``: the robot crosses from :attr:`robot_start` to :attr:`robot_goal` every episode; ``random``: start
    and goal drawn per episode uniformly in ``[-robot_area, robot_area]²``, at least ``robot_min_distance`` apart
    (CrowdNav++), so no single route can be memorised."""
    robot_area: float = 6.0
    """Half-width of the square the random robot start and goal are drawn in [m]."""
    robot_min_distance: float = 8.0
    """Smallest start–goal distance of a random robot crossing [m]."""
    goal_change_interval: float = 0.0
    """Every this many seconds each pedestrian takes a new goal (:meth:`changed_goals`) with probability
    :attr:`goal_change_prob` (CrowdNav++: 5 s, 0.5); 0 = never [s]."""
    goal_change_prob: float = 0.0
    """Probability of a goal change at each :attr:`goal_change_interval` [-]."""

    def configure_robot(self, robot: str = "fixed", robot_area: float = 6.0, robot_min_distance: float = 8.0) -> None:
        """Set the robot's start/goal rule (see :attr:`robot`); validates the arguments."""
        if robot not in ROBOT_MODES:
            raise ValueError(f"robot={robot!r}; valid choices: {', '.join(ROBOT_MODES)}")
        if not 0 < robot_min_distance <= 2 * math.sqrt(2) * robot_area * 0.95:
            raise ValueError(f"robot_min_distance={robot_min_distance}; valid choices: (0, "
                             f"{2 * math.sqrt(2) * robot_area * 0.95:.2f}] for robot_area={robot_area}")
        self.robot, self.robot_area, self.robot_min_distance = robot, float(robot_area), float(robot_min_distance)

    def configure_goal_changes(self, interval: float = 0.0, prob: float = 0.0) -> None:
        """Set the random goal changes (see :attr:`goal_change_interval`); validates the arguments."""
        if interval < 0 or not 0.0 <= prob <= 1.0:
            raise ValueError(f"goal_change_interval={interval}, goal_change_prob={prob}; valid choices: an interval "
                             "≥ 0 s (0 = never) and a probability in [0, 1]")
        self.goal_change_interval, self.goal_change_prob = float(interval), float(prob)

    def robot_endpoints(self, rng: np.random.Generator, edges: np.ndarray, radius: float
                        ) -> tuple[np.ndarray, np.ndarray]:
        """The robot's start and goal for one episode, ``(2,)`` each [m]. ``fixed`` draws nothing; ``random`` draws
        batches of 64 candidate pairs and takes the first that is far enough apart and clear of the static edges
        ``edges`` ``(S, 2, 2)`` by more than ``radius``."""
        if self.robot == "fixed":
            return np.asarray(self.robot_start, dtype=np.float64), np.asarray(self.robot_goal, dtype=np.float64)
        for _ in range(64):
            c = rng.uniform(-self.robot_area, self.robot_area, (64, 4))
            ok = np.hypot(c[:, 0] - c[:, 2], c[:, 1] - c[:, 3]) >= self.robot_min_distance
            if len(edges):
                for pts in (c[:, :2], c[:, 2:]):
                    ok &= (point_segment_distance(pts[:, None], edges[None, :, 0], edges[None, :, 1]) > radius).all(1)
            hits = np.flatnonzero(ok)
            if len(hits):
                return c[hits[0], :2].copy(), c[hits[0], 2:].copy()
        raise ValueError(f"layout {self.name!r}: no robot start/goal {self.robot_min_distance} m apart found clear of "
                         "the obstacles; lower robot_min_distance")

    def obstacles(self) -> tuple[Polygon, ...]:
        """Static obstacles of the layout (vertex lists, metres); none by default."""
        return ()

    @abstractmethod
    def candidates(self, rng: np.random.Generator, index: int, n: int, m: int) -> tuple[np.ndarray, np.ndarray]:
        """Draw ``m`` candidate (start, goal) pairs for pedestrian ``index`` of ``n``: two ``(m, 2)`` arrays [m]."""

    renew_uniforms: ClassVar[int] = 0
    """How many U[0, 1) numbers :meth:`renew_goals` consumes per pedestrian."""

    @abstractmethod
    def renew_goals(self, u: np.ndarray, positions: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """New goals ``(k, 2)`` for ``k`` pedestrians at ``positions`` ``(k, 2)`` that reached ``goals`` ``(k, 2)``.

        ``u`` ``(k, renew_uniforms)`` are uniform draws from each pedestrian's world generator: the world draws
        them (one call per world) so that this method is vectorised over all worlds at once.
        """

    def changed_goals(self, u: np.ndarray, positions: np.ndarray, goals: np.ndarray) -> np.ndarray:
        """New goals ``(k, 2)`` of a random goal change (``u`` ``(k, renew_uniforms)``); default:
        :meth:`renew_goals`."""
        return self.renew_goals(u, positions, goals)

    respawn: bool = False
    """Whether a pedestrian reaching its goal is re-spawned (:meth:`respawn_candidates`) instead of getting a new
    goal."""
    spawn_gap: float | None = None
    """``None``: a re-spawn takes the first of 16 candidates clear of the others' positions by both radii +
    :data:`PLACEMENT_GAP`, else the last. A number [m]: CrowdNav++'s rule — clear of every agent's position *and*
    goal by both radii + ``spawn_gap``, and with no clear candidate the re-spawn waits a step (never an overlap)."""
    spawn_candidates: int = 16
    """Candidates drawn per re-spawn (and per goal change, with :meth:`goal_candidates`) per step [-]."""

    def goal_candidates(self, rng: np.random.Generator, v_pref: np.ndarray, m: int) -> np.ndarray | None:
        """Optional: ``m`` candidate goals ``(k, m, 2)`` [m] of a random goal change for ``k`` pedestrians of preferred
        speeds ``v_pref`` ``(k,)``, checked for clearance like a CrowdNav++ spawn (needs :attr:`spawn_gap`). ``None``
        (default): goal changes use :meth:`changed_goals` unchecked."""
        return None

    def respawn_candidates(self, rng: np.random.Generator, m: int) -> tuple[np.ndarray, np.ndarray]:
        """``m`` candidate (start, goal) pairs for a re-spawned pedestrian (default: :meth:`candidates`)."""
        return self.candidates(rng, 0, 1, m)

    def sample(
        self,
        rng: np.random.Generator,
        n: int,
        human_radius: float,
        robot_radius: float,
        obstacles: Sequence[Polygon] = (),
        robot_points: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Place ``n`` pedestrians without overlap; returns ``(starts, goals)``, each ``(n, 2)`` [m]. ``robot_points``
        ``(2, 2)``: this episode's robot start and goal (default: the fixed ones)."""
        return place_without_overlap(self, rng, n, human_radius, robot_radius, obstacles, robot_points=robot_points)


def _inside_polygons(points: np.ndarray, obstacles: Sequence[Polygon]) -> np.ndarray:
    """Even-odd test: True where a point ``(m, 2)`` lies inside any closed polygon (≥ 3 vertices)."""
    inside = np.zeros(len(points), dtype=bool)
    for poly in obstacles:
        if len(poly) < 3:
            continue
        v = np.asarray(poly, dtype=np.float64)
        w = np.roll(v, -1, axis=0)
        x, y = points[:, None, 0], points[:, None, 1]
        cond = (v[None, :, 1] > y) != (w[None, :, 1] > y)
        xint = v[None, :, 0] + (y - v[None, :, 1]) * (w[None, :, 0] - v[None, :, 0]) / np.where(
            w[None, :, 1] != v[None, :, 1], w[None, :, 1] - v[None, :, 1], 1.0)
        inside ^= (cond & (x < xint)).sum(axis=1) % 2 == 1
    return inside


@nb.njit(cache=True)
def _clear(pts: np.ndarray, others: np.ndarray, dmin: np.ndarray, ok: np.ndarray) -> None:
    """``ok[c] &= |pts[c] − others[j]| ≥ dmin[j]`` for every j (the same float operations as ``np.linalg.norm``)."""
    for c in range(pts.shape[0]):
        if not ok[c]:
            continue
        for j in range(others.shape[0]):
            dx = pts[c, 0] - others[j, 0]
            dy = pts[c, 1] - others[j, 1]
            if not np.sqrt(dx * dx + dy * dy) >= dmin[j]:
                ok[c] = False
                break


def place_without_overlap(
    layout: Layout,
    rng: np.random.Generator,
    n: int,
    human_radius: float | np.ndarray,
    robot_radius: float,
    obstacles: Sequence[Polygon] = (),
    pool: int = 32,
    rounds: int = 48,
    robot_points: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Greedy bounded dart-throwing.

    Pedestrian ``i`` (radius ``human_radius[i]``, or one radius for all) takes the first of ``pool`` vectorised
    candidates whose start is clear of every accepted start, the robot's start and goal, and the obstacles, and whose
    goal is clear of every accepted goal and the robot's start and goal (clearance: both radii +
    the layout's ``placement_gap``, :data:`PLACEMENT_GAP` by default). After ``rounds`` pools without success it
    raises ``ValueError`` — at most
    ``n * pool * rounds`` candidates are ever drawn. Sets ``layout.spacing`` (the mean clearance between two
    pedestrians, for layouts that size their spawn areas by it).
    """
    starts = np.empty((n, 2))
    goals = np.empty((n, 2))
    radii = np.broadcast_to(np.asarray(human_radius, dtype=np.float64), (n,))
    robot_pts = (np.array([layout.robot_start, layout.robot_goal], dtype=np.float64) if robot_points is None
                 else np.ascontiguousarray(robot_points, dtype=np.float64))
    gap = layout.placement_gap
    if n:
        layout.spacing = 2 * float(radii.mean()) + gap
    edges = obstacle_edges(obstacles)
    for i in range(n):
        d_hr = np.full(2, radii[i] + robot_radius + gap)
        d_hh = radii[i] + radii[:i] + gap
        for _ in range(rounds):
            s, g = layout.candidates(rng, i, n, pool)
            s, g = np.ascontiguousarray(s, dtype=np.float64), np.ascontiguousarray(g, dtype=np.float64)
            ok = np.ones(len(s), dtype=bool)
            for pts, acc, separate in ((s, starts[:i], True), (g, goals[:i], layout.separate_goals)):
                _clear(pts, robot_pts, d_hr, ok)
                if i and separate:
                    _clear(pts, acc, d_hh, ok)
            if len(edges):
                for pts in (s, g):
                    clear = point_segment_distance(pts[:, None], edges[None, :, 0], edges[None, :, 1])
                    ok &= (clear >= radii[i] + gap).all(axis=1) & ~_inside_polygons(pts, obstacles)
            hits = np.flatnonzero(ok)
            if len(hits):
                starts[i], goals[i] = s[hits[0]], g[hits[0]]
                break
        else:
            raise ValueError(
                f"layout {layout.name!r} cannot fit num_humans={n} pedestrians of radius up to {radii.max()} m: "
                f"pedestrian {i} found no free start/goal in {pool * rounds} candidates; lower num_humans")
    return starts, goals


ARRIVALS = ("turn", "respawn")


CROWDNAV_GAP = 0.25
"""CrowdNav++'s placement clearance beyond both radii: ``discomfort_dist`` (``configs/config.py:34``) [m]."""


@register("circle_crossing")
class CircleCrossing(Layout):
    """The default training layout: CrowdNav++'s circle crossing, rule for rule (Shuijing725/
    CrowdNav_Prediction_AttnGraph @3907731; ``docs/benchmark.md`` lists every rule and each departure).

    * **Start** (``crowd_sim_var_num.py:121-128``): a uniform angle θ on the circle of radius ``radius`` (6√2 m,
      ``configs/config.py:40``), each coordinate plus a one-sided U[0, ``noise``) (``noise_range = 2``); the
      **goal** is ``−start`` (line 144), never checked.
    * **Clearance** (lines 129-140): a start is accepted when it is at least ``r_new + r_j + 0.25`` m
      (:data:`CROWDNAV_GAP`, ``discomfort_dist``) from every agent already placed — robot included — both from its
      position and from its goal. CrowdNav++ loops until one is found; here the draw is bounded
      (:meth:`sample`: 48 pools of 32 candidates per pedestrian, then ``ValueError``).
    * **Arrival** (``crowd_sim_pred.py:206-211``): a pedestrian within its own radius of its goal is re-spawned —
      new radius and speed, a fresh start by the same rule, checked against everyone including its old self —
      (:attr:`respawn`); with no clear candidate among :attr:`spawn_candidates` the re-spawn **waits** (the
      pedestrian stays at its goal) and is tried again the next step, so no spawn ever overlaps.
    * **Random goal changes** (``crowd_sim_pred.py:201-204``, ``crowd_sim.py:415-450``): every 5 s each pedestrian
      with probability 0.5 takes a goal at a uniform angle on the circle plus a symmetric U[−v_pref/2, v_pref/2)
      per coordinate, checked like a start against every other agent's position and goal (later pedestrians
      against the earlier ones' new goals); with no clear candidate among :attr:`spawn_candidates` it keeps its
      goal.
    * **Robot** (``crowd_sim_var_num.py:95-101``): start and goal uniform in [−6, 6]², at least 8 m apart, drawn
      before the pedestrians (:meth:`Layout.robot_endpoints`).

    Args:
        radius: Circle radius [m]. noise: Width of the one-sided start noise per coordinate [m].
        robot, robot_area, robot_min_distance: The robot's start/goal rule (:meth:`Layout.configure_robot`).
        goal_change_interval, goal_change_prob: Random goal changes [s], [-] (0 = never).
    """

    name = "circle_crossing"
    respawn = True
    spawn_gap: float = CROWDNAV_GAP
    spawn_candidates: int = 16
    """Candidates tried per re-spawn or goal change per step (CrowdNav++ retries without bound)."""

    def __init__(self, radius: float = 6 * math.sqrt(2), noise: float = 2.0, robot: str = "random",
                 robot_area: float = 6.0, robot_min_distance: float = 8.0, goal_change_interval: float = 5.0,
                 goal_change_prob: float = 0.5) -> None:
        if not radius > 0 or noise < 0:
            raise ValueError(f"radius={radius}, noise={noise}; valid choices: radius > 0 [m], noise ≥ 0 [m]")
        self.radius, self.noise = float(radius), float(noise)
        self.configure_robot(robot, robot_area, robot_min_distance)
        self.configure_goal_changes(goal_change_interval, goal_change_prob)
        self.half_size = max(radius + noise, robot_area) + 1.0

    def candidates(self, rng, index, n, m):
        ang = rng.uniform(0.0, 2 * math.pi, m)
        s = self.radius * np.stack([np.cos(ang), np.sin(ang)], 1) + rng.uniform(0.0, self.noise, (m, 2))
        return s, -s

    def renew_goals(self, u, positions, goals):  # arrivals re-spawn (see respawn)
        raise NotImplementedError("circle_crossing re-spawns arriving pedestrians")

    def goal_candidates(self, rng: np.random.Generator, v_pref: np.ndarray, m: int) -> np.ndarray:
        """``m`` candidate goals ``(k, m, 2)`` [m] of a random goal change for ``k`` pedestrians of preferred speeds
        ``v_pref`` ``(k,)`` [m/s] (``crowd_sim.py:427-432``)."""
        k = len(v_pref)
        ang = rng.uniform(0.0, 2 * math.pi, (k, m))
        noise = (rng.random((k, m, 2)) - 0.5) * v_pref[:, None, None]
        return self.radius * np.stack([np.cos(ang), np.sin(ang)], -1) + noise

    def sample(self, rng, n, human_radius, robot_radius, obstacles=(), robot_points=None):
        """CrowdNav++'s placement (class docstring), bounded: returns ``(starts, goals)``, each ``(n, 2)`` [m]."""
        from crowdbench.worlds._kernels import spawn_clear

        radii = np.broadcast_to(np.asarray(human_radius, dtype=np.float64), (n,))
        robot_pts = (np.array([self.robot_start, self.robot_goal], dtype=np.float64) if robot_points is None
                     else np.ascontiguousarray(robot_points, dtype=np.float64))
        # agents placed so far: row 0 the robot (position = its start, goal = its goal), then the pedestrians
        pos, goal = np.zeros((n + 1, 2)), np.zeros((n + 1, 2))
        rad, active = np.zeros(n + 1), np.zeros(n + 1, dtype=bool)
        pos[0], goal[0], rad[0], active[0] = robot_pts[0], robot_pts[1], robot_radius, True
        for i in range(n):
            for _ in range(48):
                s, _g = self.candidates(rng, i, n, 32)
                k = spawn_clear(np.ascontiguousarray(s), pos, goal, rad, active, -1, radii[i], self.spawn_gap, True)
                if k >= 0:
                    pos[i + 1], goal[i + 1], rad[i + 1], active[i + 1] = s[k], -s[k], radii[i], True
                    break
            else:
                raise ValueError(f"layout {self.name!r} cannot fit num_humans={n} pedestrians of radius up to "
                                 f"{radii.max()} m: pedestrian {i} found no clear start in {48 * 32} candidates; "
                                 "lower num_humans")
        self.spacing = 2 * float(radii.mean()) + self.spawn_gap if n else self.spacing
        return pos[1:].copy(), goal[1:].copy()


@register("circle_crossing_calibrated")
class CircleCrossingCalibrated(Layout):
    """crowdbench 0.2's default circle crossing, kept for comparison (its rules were chosen by fitting the paper's
    ORCA row; see ``docs/benchmark.md``). Pedestrians start on a circle of radius ``radius`` centred at the origin,
    each coordinate perturbed by U(−noise, noise); goals are antipodal (``goal = −start``); placement clearance
    0.2 m between starts and between goals (:func:`place_without_overlap`). ``arrival="respawn"``: a pedestrian
    reaching its goal is replaced by a new one at the first of 16 fresh circle starts clear of the others' positions
    (else the last candidate); ``"turn"``: it is sent to a new point on the circle at a uniformly random angle
    within ±45° of the antipode of where it stands. Random goal changes pick a uniform point on the circle, each
    coordinate perturbed by U(−1/2, 1/2) m. Its pedestrians walked at their own preferred speed: pair it with
    ``human_model_kwargs={"preferred_speed": None, "neighbor_dist_range": None}`` for the whole former crowd.

    Args:
        radius: Circle radius [m]. noise: Half-width of the start noise per coordinate [m].
        arrival: ``respawn`` or ``turn``.
        robot, robot_area, robot_min_distance: The robot's start/goal rule (:meth:`Layout.configure_robot`).
        goal_change_interval, goal_change_prob: Random goal changes [s], [-].
    """

    name = "circle_crossing_calibrated"

    def __init__(self, radius: float = 6 * math.sqrt(2), noise: float = 1.0, arrival: str = "respawn",
                 robot: str = "random", robot_area: float = 6.0, robot_min_distance: float = 8.0,
                 goal_change_interval: float = 5.0, goal_change_prob: float = 0.5) -> None:
        if not radius > 0 or noise < 0:
            raise ValueError(f"radius={radius}, noise={noise}; valid choices: radius > 0 [m], noise ≥ 0 [m]")
        if arrival not in ARRIVALS:
            raise ValueError(f"arrival={arrival!r}; valid choices: {', '.join(ARRIVALS)}")
        self.radius, self.noise, self.arrival = float(radius), float(noise), arrival
        self.respawn = arrival == "respawn"
        self.configure_robot(robot, robot_area, robot_min_distance)
        self.configure_goal_changes(goal_change_interval, goal_change_prob)
        self.half_size = max(radius + noise, robot_area) + 1.0

    def candidates(self, rng, index, n, m):
        ang = rng.uniform(0.0, 2 * math.pi, m)
        s = self.radius * np.stack([np.cos(ang), np.sin(ang)], 1) + rng.uniform(-self.noise, self.noise, (m, 2))
        return s, -s

    renew_uniforms = 3

    def renew_goals(self, u, positions, goals):
        ang = np.arctan2(-positions[:, 1], -positions[:, 0]) + (u[:, 0] - 0.5) * (math.pi / 2)
        return _on_circle(self.radius, ang, (u[:, 1:3] - 0.5) * (2 * self.noise))

    def changed_goals(self, u, positions, goals):
        ang = u[:, 0] * 2 * math.pi
        return _on_circle(self.radius, ang, u[:, 1:3] - 0.5)


@register("circle_crossing_legacy")
class CircleCrossingLegacy(CircleCrossingCalibrated):
    """crowdbench's original circle crossing, kept for comparison: circle radius 6 m, noise ±0.5 m, the robot always
    from (0, −6) to (0, 6) on the pedestrians' own ring, pedestrians turn round near the antipode on arrival, no
    random goal changes. A learned policy can memorise one route here (``studies/crowdbench-0.2/README.md``)."""

    name = "circle_crossing_legacy"

    def __init__(self, radius: float = 6.0, noise: float = 0.5, arrival: str = "turn", robot: str = "fixed",
                 robot_area: float = 6.0, robot_min_distance: float = 8.0, goal_change_interval: float = 0.0,
                 goal_change_prob: float = 0.0) -> None:
        super().__init__(radius, noise, arrival, robot, robot_area, robot_min_distance, goal_change_interval,
                         goal_change_prob)
        self.half_size = radius + 1.0


@register("square_crossing")
class SquareCrossing(Layout):
    """CrowdNav's square crossing. Each pedestrian picks a side s = ±1 at random, starts uniformly in the half
    ``x ∈ s·[0, w/2], y ∈ [-w/2, w/2]`` of a ``w`` = 10 m square and aims at a uniform point of the opposite half.
    A reached goal is replaced by a uniform point of the half opposite to where the pedestrian stands.
    """

    name = "square_crossing"

    def __init__(self, width: float = 10.0) -> None:
        self.width = width
        self.half_size = max(width / 2, 6.0) + 1.0

    def _half(self, rng, sign: np.ndarray) -> np.ndarray:
        m = len(sign)
        return np.stack([rng.uniform(0, self.width / 2, m) * sign, rng.uniform(-self.width / 2, self.width / 2, m)], 1)

    def candidates(self, rng, index, n, m):
        sign = np.where(rng.random(m) > 0.5, -1.0, 1.0)
        return self._half(rng, sign), self._half(rng, -sign)

    renew_uniforms = 2

    def renew_goals(self, u, positions, goals):
        sign = np.where(positions[:, 0] >= 0, -1.0, 1.0)
        return np.stack([u[:, 0] * self.width / 2 * sign, (u[:, 1] - 0.5) * self.width], 1)


class _Streams(Layout):
    """Pedestrians enter in bands along the arena boundary and walk straight across to a goal on the opposite
    boundary line (same lateral offset); on arrival they turn round (the goal is mirrored along the stream axis), so
    density holds. Band depth grows with the crowd so the band can always hold its share.
    """

    half_size = 7.0
    extent = 6.0
    """Streams enter and leave on the lines at ±``extent`` [m] (inside the 14 m arena)."""
    lane_half_width = 3.5
    separate_goals = False

    def __init__(self, robot: str = "random", robot_area: float = 6.0, robot_min_distance: float = 8.0) -> None:
        self.configure_robot(robot, robot_area, robot_min_distance)

    def _depth(self, n_stream: int) -> float:
        # random sequential placement fills ~half the area: give each pedestrian ~3.5 spacing² of band
        return float(min(self.extent, max(2.0, 3.5 * n_stream * self.spacing**2 / (2 * self.lane_half_width))))

    def _stream(self, index: int, n: int) -> tuple[np.ndarray, np.ndarray, int]:
        """(entry direction unit vector, lane axis unit vector, pedestrians in this stream)."""
        raise NotImplementedError

    def candidates(self, rng, index, n, m):
        direction, lane, k = self._stream(index, n)
        depth = self._depth(k)
        along = -self.extent + rng.uniform(0, depth, m)
        across = rng.uniform(-self.lane_half_width, self.lane_half_width, m)
        s = along[:, None] * direction + across[:, None] * lane
        g = self.extent * direction + across[:, None] * lane
        return s, np.broadcast_to(g, s.shape).copy()

    def renew_goals(self, u, positions, goals):
        new = goals.copy()
        axis = np.argmax(np.abs(goals), axis=1)  # the stream axis: where the goal sits on the boundary line
        new[np.arange(len(new)), axis] *= -1.0
        return new


@register("intersection")
class Intersection(_Streams):
    """Test-only. Two orthogonal streams crossing a 12 m square: even-indexed pedestrians walk west→east in the band
    ``|y| ≤ 3.5`` m, odd-indexed ones north→south in the band ``|x| ≤ 3.5`` m, each entering from its boundary.
    The robot's start and goal are drawn per episode (``robot="random"``, the default; ``"fixed"``: from (0, −6) to
    (0, 6)).
    """

    name = "intersection"

    def _stream(self, index, n):
        if index % 2 == 0:
            return np.array([1.0, 0.0]), np.array([0.0, 1.0]), (n + 1) // 2
        return np.array([0.0, -1.0]), np.array([1.0, 0.0]), n // 2


@register("split_flow")
class SplitFlow(_Streams):
    """Test-only. Opposing horizontal traffic: even-indexed pedestrians enter from the west boundary and walk east,
    odd-indexed ones from the east walking west, all in the band ``|y| ≤ 3.5`` m. The robot's start and goal are
    drawn per episode (``robot="random"``, the default; ``"fixed"``: across the flow from (0, −6) to (0, 6)).
    """

    name = "split_flow"

    def _stream(self, index, n):
        if index % 2 == 0:
            return np.array([1.0, 0.0]), np.array([0.0, 1.0]), (n + 1) // 2
        return np.array([-1.0, 0.0]), np.array([0.0, 1.0]), n // 2


@register("random_wander")
class RandomWander(Layout):
    """Test-only. Starts and goals uniform over the square ``[-a, a]²`` (a = 5.5 m); a reached goal is replaced by
    another uniform point of that square. The robot's start and goal are drawn per episode (``robot="random"``, the
    default; ``"fixed"``: from (0, −6) to (0, 6)).
    """

    name = "random_wander"
    half_size = 7.0

    def __init__(self, extent: float = 5.5, robot: str = "random", robot_area: float = 6.0,
                 robot_min_distance: float = 8.0) -> None:
        self.extent = extent
        self.configure_robot(robot, robot_area, robot_min_distance)

    def _uniform(self, rng, m: int) -> np.ndarray:
        return rng.uniform(-self.extent, self.extent, (m, 2))

    def candidates(self, rng, index, n, m):
        return self._uniform(rng, m), self._uniform(rng, m)

    renew_uniforms = 2

    def renew_goals(self, u, positions, goals):
        return (2 * u - 1) * self.extent


for _scene in ("eth", "hotel", "univ", "zara1", "zara2"):  # loaded on first use (they read package data)
    LAYOUTS.register(_scene, f"crowdbench.worlds.recorded:{_scene.capitalize()}Scene")


def make_layout(name: str | Layout, **kwargs) -> Layout:
    """Resolve a layout by registry name (or pass an instance through)."""
    if isinstance(name, Layout):
        return name
    if not isinstance(name, str):
        raise ValueError(f"layout={name!r}; valid choices: a Layout instance or one of {', '.join(LAYOUTS.names())}")
    return LAYOUTS.make(name, **kwargs)


def _on_circle(radius: float, ang: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """``radius·(cos, sin)(ang) + offset`` ``(k, 2)`` [m], written into ``offset`` (a fresh array): goal renewal runs
    in the step, where ``np.stack`` would cost more than the arithmetic."""
    offset[:, 0] += radius * np.cos(ang)
    offset[:, 1] += radius * np.sin(ang)
    return offset


@register("concourse")
class Concourse(Layout):
    """A station concourse for hundreds of people: a ``2·half_width`` m square hall (30 × 30 m by default) with a
    wall on each side broken by a ``door`` m entrance at its middle, and eight 1.2 m square pillars on a ring at
    ``half_width/2`` around the open centre. People start anywhere in the hall (placed without overlap) and walk to
    a point of an entrance; on arrival they re-enter through an entrance chosen at random and head for another one,
    so four streams cross the hall all episode. The robot crosses the hall between two uniform points at least
    ``robot_min_distance`` apart, clear of walls and pillars. Large crowds: 500 people fit with the default radii
    U(0.3, 0.5) m (placed 0.05 m apart); for 1,000 give smaller ones (``human_radius_range=(0.2, 0.3)``).
    """

    name = "concourse"
    separate_goals = False
    respawn = True
    placement_gap = 0.05

    def __init__(self, half_width: float = 15.0, door: float = 4.0, robot_min_distance: float = 15.0) -> None:
        if not half_width > 4 or not 0 < door < half_width:
            raise ValueError(f"half_width={half_width}, door={door}; valid choices: half_width > 4 m and "
                             "0 < door < half_width [m]")
        self.half_width, self.door = float(half_width), float(door)
        self.half_size = half_width + 1.0
        self.robot, self.robot_area = "random", half_width - 1.0
        self.robot_min_distance = float(robot_min_distance)
        w = self.half_width
        self._doors = np.array([[0.0, -w], [w, 0.0], [0.0, w], [-w, 0.0]])  # door centres on the walls

    def obstacles(self) -> tuple[Polygon, ...]:
        w, d = self.half_width, self.door / 2
        walls = (((-w, -w), (-d, -w)), ((d, -w), (w, -w)), ((w, -w), (w, -d)), ((w, d), (w, w)),
                 ((w, w), (d, w)), ((-d, w), (-w, w)), ((-w, w), (-w, d)), ((-w, -d), (-w, -w)))
        r, s = w / 2, 0.6
        pillars = tuple(((cx - s, cy - s), (cx + s, cy - s), (cx + s, cy + s), (cx - s, cy + s))
                        for cx in (-r, 0.0, r) for cy in (-r, 0.0, r) if (cx, cy) != (0.0, 0.0))
        return walls + pillars

    def _door_points(self, rng: np.random.Generator, which: np.ndarray) -> np.ndarray:
        """A point of each chosen entrance ``which`` ``(m,)``, 0.8 m inside the hall, spread across the door [m]."""
        c = self._doors[which]
        inward = -c / self.half_width
        across = np.stack([-inward[:, 1], inward[:, 0]], 1)
        return c + 0.8 * inward + rng.uniform(-0.4, 0.4, (len(which), 1)) * self.door * across

    def candidates(self, rng, index, n, m):
        starts = rng.uniform(-self.half_width + 0.6, self.half_width - 0.6, (m, 2))
        return starts, self._door_points(rng, rng.integers(0, 4, m))

    def respawn_candidates(self, rng, m):
        enter = rng.integers(0, 4, m)
        leave = (enter + rng.integers(1, 4, m)) % 4  # another entrance
        return self._door_points(rng, enter), self._door_points(rng, leave)

    renew_uniforms = 0

    def renew_goals(self, u, positions, goals):  # arrivals re-spawn (see respawn)
        raise NotImplementedError("concourse re-spawns arriving pedestrians")

    def robot_endpoints(self, rng, edges, radius):
        polys = [p for p in self.obstacles() if len(p) >= 3]
        for _ in range(64):
            s, g = super().robot_endpoints(rng, edges, radius)
            pts = np.stack([s, g])
            if not _inside_polygons(pts, polys).any():
                return s, g
        raise ValueError("layout 'concourse': no robot crossing found clear of the pillars")
