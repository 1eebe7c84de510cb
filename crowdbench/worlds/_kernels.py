"""Compiled (numba) kernels of the world's hot path: one call per phase of a step over all ``(B, A)`` agents.

Private below :class:`~crowdbench.worlds.world.CrowdWorld` and the observation builders. Each kernel performs the
same floating-point operations, in the same order, as the plain numpy reference it replaces, and is tested equal to
it bit for bit (``tests/worlds/test_kernels.py``):

* :func:`advance` = :func:`motion` then :func:`outcome` (one dispatch per step);
* :func:`motion` — pedestrian speed clipping, continuous collision against static edges, robot–pedestrian swept
  clearance, integration (reference: ``crowdbench.worlds.reference.motion``, built on :mod:`crowdbench.geometry`);
* :func:`outcome` — which agents turn, goal distance, the paper's reward terms, episode outcome, pedestrian
  overlaps, goal arrivals (reference: ``reference.outcome``);
* :func:`robot_observation` / :func:`human_observation` — nearest-first observation arrays in float32
  (reference: ``reference.robot_observation`` / ``reference.human_observation``); both at once for one world:
  :func:`one_world_observations`;
* :func:`agent_observations_batch` — every agent's (robot included) observation in the pedestrians' layout, all
  worlds at once (the multi-agent interfaces);
* :func:`drive_actions` — externally driven pedestrians' normalised actions to velocities (checked);
* :func:`crowd_clearance` — each pedestrian's nearest surface distance and contacts (pedestrian rewards);
* :func:`first_clear` — the first re-spawn candidate clear of everyone (reference: ``reference.first_clear``).
* :func:`spawn_clear`, :func:`change_goals` — CrowdNav++'s spawn and goal-change clearance (reference:
  ``reference.spawn_clear``).
* :func:`assign_slots` — persistent slots of a by-identity observation when a world has more pedestrians than
  slots (reference: ``reference.assign_slots``).

Large crowds: the kernels whose brute force is quadratic in a world's agents — the pedestrians' observations (each
agent's nearest neighbours), :func:`crowd_clearance`, the overlap count of :func:`outcome` — search a cell grid
(:mod:`crowdbench.spatial`) in a world with more than ``grid_min`` (default :data:`~crowdbench.spatial.GRID_MIN`)
agents to search, the same agents with the same float operations, ranked by (distance, index) as the brute-force
insertion orders them: bit for bit the same outputs (``tests/worlds/test_grid.py``). The robot's observation is one
query per world (linear) and stays brute force.

Why compiled: a world step of a small crowd is a few hundred numpy calls on arrays of a handful of elements, so
per-call overhead (≈ 1 µs each) dominated; each kernel here costs one dispatch (≈ 1–3 µs) plus its arithmetic.
The dispatch grows with the number of array arguments (≈ 70 ns each), so :func:`advance` takes its outputs in
blocks. ``error_model="numpy"`` (as the ORCA kernel): divisions here are guarded, and need no zero check.
"""

# numba-cache-key: crowdbench.geometry 31fac0ddc665
# numba-cache-key: crowdbench.spatial b0452486ca54

from __future__ import annotations

import math

import numba as nb
import numpy as np

from crowdbench.geometry import pair_overlaps
from crowdbench.spatial import (
    GRID_MIN,
    GRID_PER_CELL,
    RANK_MAX,
    build_grid,
    count_members,
    disc_row_span,
    disc_rows,
    finite_world,
    grid_scratch,
    member_max,
    select_nearest,
)

INF = np.inf


@nb.njit(cache=True, inline="always", error_model="numpy")
def _point_segment(px, py, ax, ay, bx, by):  # pragma: no cover - numba
    """``geometry.point_segment_distance`` for one point and one segment."""
    abx, aby = bx - ax, by - ay
    denom = max(abx * abx + aby * aby, 1e-18)
    t = min(max(((px - ax) * abx + (py - ay) * aby) / denom, 0.0), 1.0)
    dx, dy = px - (ax + t * abx), py - (ay + t * aby)
    return math.sqrt(dx * dx + dy * dy)


@nb.njit(cache=True, inline="always", error_model="numpy")
def _segment_segment(p0x, p0y, p1x, p1y, ax, ay, bx, by):  # pragma: no cover - numba
    """``geometry.segment_segment_distance`` for one pair of segments."""
    d = min(min(_point_segment(p0x, p0y, ax, ay, bx, by), _point_segment(p1x, p1y, ax, ay, bx, by)),
            min(_point_segment(ax, ay, p0x, p0y, p1x, p1y), _point_segment(bx, by, p0x, p0y, p1x, p1y)))
    rx, ry, sx, sy = p1x - p0x, p1y - p0y, bx - ax, by - ay
    denom = rx * sy - ry * sx
    if abs(denom) > 1e-15:
        qx, qy = ax - p0x, ay - p0y
        t = (qx * sy - qy * sx) / denom
        u = (qx * ry - qy * rx) / denom
        if t >= 0 and t <= 1 and u >= 0 and u <= 1:
            return 0.0
    return d


@nb.njit(cache=True, inline="always", error_model="numpy")
def _touches(sx, sy, ex, ey, r, edges):  # pragma: no cover - numba
    """Whether the segment (sx, sy)–(ex, ey) comes within ``r`` of any edge ``(S, 2, 2)``."""
    for s in range(edges.shape[0]):
        if _segment_segment(sx, sy, ex, ey, edges[s, 0, 0], edges[s, 0, 1], edges[s, 1, 0], edges[s, 1, 1]) <= r:
            return True
    return False


@nb.njit(cache=True, error_model="numpy")
def motion(pos, vel, v_pref, radius, active, edges, dt, iters, disp, robot_hit, d_min,
           clip_robot):  # pragma: no cover - numba
    """The motion of one step, in place.

    Args (``B`` worlds of ``A`` agents, ``S`` static edges):
        pos: ``(B, A, 2)`` [m] (agent 0 = robot), in/out: start positions; on return ``pos + vel·dt`` with the
            final velocities (bit for bit what pymunk's kinematic integration computes).
        vel: ``(B, A, 2)`` [m/s], in/out: the robot's commanded velocity and the pedestrians' wanted ones; on return
            pedestrians (and the robot if ``clip_robot``) are clipped to ``v_pref`` ``(B, A)``, inactive agents are
            at rest, and with static edges ``(S, 2, 2)`` every velocity is ``disp / dt``, the displacement cut at
            contact (bisection, ``iters``).
        radius: ``(B, A)`` [m]. active: ``(B, A)`` bool. dt: [s].
        disp: Out ``(B, A, 2)``: the displacements [m].
        robot_hit: Out ``(B,)`` bool: the robot's full sweep touches an edge.
        d_min: Out ``(B,)``: smallest robot–pedestrian surface distance along the linear motions [m] (inf if none).

    Returns:
        False, with nothing changed, when an active pedestrian's velocity is NaN or infinite.

    """
    B, A = radius.shape
    for b in range(B):
        for a in range(1, A):
            if active[b, a] and not (math.isfinite(vel[b, a, 0]) and math.isfinite(vel[b, a, 1])):
                return False
    has_edges = edges.shape[0] > 0
    for b in range(B):
        for a in range(A):
            vx, vy = vel[b, a, 0], vel[b, a, 1]
            if not active[b, a]:
                vx = vy = 0.0
            elif a > 0 or clip_robot:
                n = math.sqrt(vx * vx + vy * vy)
                f = min(1.0, v_pref[b, a] / max(n, 1e-12))
                vx, vy = vx * f, vy * f
            dx, dy = vx * dt, vy * dt
            hit = False
            if has_edges and active[b, a]:
                sx, sy, r = pos[b, a, 0], pos[b, a, 1], radius[b, a]
                hit = _touches(sx, sy, sx + dx, sy + dy, r, edges)
                frac = 1.0
                if hit:
                    lo, hi = 0.0, 1.0
                    for _ in range(iters):
                        mid = 0.5 * (lo + hi)
                        if _touches(sx, sy, sx + mid * dx, sy + mid * dy, r, edges):
                            hi = mid
                        else:
                            lo = mid
                    frac = lo
                dx, dy = dx * frac, dy * frac
            if has_edges:
                vx, vy = dx / dt, dy / dt
            vel[b, a, 0], vel[b, a, 1] = vx, vy
            disp[b, a, 0], disp[b, a, 1] = dx, dy
            if a == 0:
                robot_hit[b] = hit
        best = INF
        for h in range(1, A):
            rpx, rpy = pos[b, h, 0] - pos[b, 0, 0], pos[b, h, 1] - pos[b, 0, 1]
            rdx, rdy = disp[b, h, 0] - disp[b, 0, 0], disp[b, h, 1] - disp[b, 0, 1]
            vv = rdx * rdx + rdy * rdy
            t = min(max(-(rpx * rdx + rpy * rdy) / max(vv, 1e-18), 0.0), 1.0)
            cx, cy = rpx + t * rdx, rpy + t * rdy
            surface = math.sqrt(cx * cx + cy * cy) - radius[b, h] - radius[b, 0]
            if active[b, h] and surface < best:
                best = surface
        d_min[b] = best
        for a in range(A):
            pos[b, a, 0] = pos[b, a, 0] + vel[b, a, 0] * dt
            pos[b, a, 1] = pos[b, a, 1] + vel[b, a, 1] * dt
    return True


@nb.njit(cache=True, error_model="numpy")
def outcome(pos, vel, goal, radius, active, heading, steps, prev_goal_dist, d_min, robot_hit, robot_turns,
            max_steps, rw, change_every, terms, reward, result, terminated, truncated, overlaps, reached,
            change_due, grid_min=GRID_MIN):  # pragma: no cover - numba
    """Everything decided after the motion, in place.

    Args (``B`` worlds of ``A`` agents):
        pos, vel, goal: ``(B, A, 2)`` after the move [m, m/s, m]. radius: ``(B, A)`` [m]. active: ``(B, A)`` bool.
        heading: ``(B, A)`` [rad], in/out: agents that moved face their velocity now (``atan2``, libm's: numpy's
            ``arctan2`` differs from it in the last bit on CPUs where numpy vectorises it), the others keep theirs,
            and so does the robot when ``robot_turns`` (a unicycle, whose heading its action sets).
        steps: ``(B,)`` in/out, incremented. prev_goal_dist: ``(B,)`` [m], in/out: becomes this step's distance.
        d_min: ``(B,)`` [m] and robot_hit ``(B,)`` from :func:`motion`. max_steps: episode limit [steps].
        rw: ``(7,)`` reward constants (success, collision, discomfort distance, discomfort scale, progress scale,
            time penalty, goal tolerance). change_every: steps between random goal changes (0 = none).
        terms: Out ``(5, B)``: success, collision, discomfort, progress, time terms. reward: Out ``(B,)``: their sum.
        result: Out ``(B,)`` int: 0 running, 1 success, 2 collision, 3 timeout (``world.OUTCOMES``).
        terminated, truncated: Out ``(B,)`` bool: success or collision; time limit reached otherwise.
        overlaps: Out ``(B,)`` int: overlapping pedestrian pairs. reached: Out ``(B, A - 1)`` bool: pedestrians
            within one radius of their goal. change_due: Out ``(B,)`` bool: a random goal change is due.
        grid_min: worlds with more active pedestrians count overlaps on a grid of cells
            (:func:`~crowdbench.geometry.pair_overlaps`; the same count).

    Returns:
        Events as bits: 1 = a pedestrian reached its goal, 2 = a random goal change is due somewhere.

    """
    B, A = radius.shape
    events = 0
    for b in range(B):
        for a in range(A):
            vx, vy = vel[b, a, 0], vel[b, a, 1]
            if vx * vx + vy * vy > 1e-12 and not (a == 0 and robot_turns):
                heading[b, a] = math.atan2(vy, vx)
        gx, gy = goal[b, 0, 0] - pos[b, 0, 0], goal[b, 0, 1] - pos[b, 0, 1]
        gdist = math.sqrt(gx * gx + gy * gy)
        success = gdist <= rw[6]
        collision = (d_min[b] <= 0.0 or robot_hit[b]) and not success
        discomfort = not success and not collision and d_min[b] < rw[2]
        t0 = rw[0] if success else 0.0
        t1 = rw[1] if collision else 0.0
        t2 = rw[3] * (d_min[b] - rw[2]) if discomfort else 0.0
        t3 = rw[4] * (prev_goal_dist[b] - gdist) if not (success or collision or discomfort) else 0.0
        t4 = rw[5]
        terms[0, b], terms[1, b], terms[2, b], terms[3, b], terms[4, b] = t0, t1, t2, t3, t4
        reward[b] = (((t0 + t1) + t2) + t3) + t4
        prev_goal_dist[b] = gdist
        steps[b] += 1
        terminated[b] = success or collision
        truncated[b] = not terminated[b] and steps[b] >= max_steps
        result[b] = 1 if success else 2 if collision else 3 if truncated[b] else 0
        change_due[b] = change_every > 0 and steps[b] % change_every == 0
        if change_due[b]:
            events |= 2
        for h in range(1, A):
            dx, dy = goal[b, h, 0] - pos[b, h, 0], goal[b, h, 1] - pos[b, h, 1]
            r = radius[b, h]
            reached[b, h - 1] = active[b, h] and dx * dx + dy * dy <= r * r
            if reached[b, h - 1]:
                events |= 1
    overlaps[:] = pair_overlaps(pos[:, 1:], radius[:, 1:], active[:, 1:], grid_min)
    return events


@nb.njit(cache=True, error_model="numpy")
def advance(robot_vel, human_vel, pos, vel, v_pref, radius, active, edges, dt, iters, disp, clip_robot, goal, heading,
            steps, prev_goal_dist, robot_turns, max_steps, rw, change_every, floats, ints, flags, reached,
            change_due, mirror, grid_min=GRID_MIN):  # pragma: no cover - numba
    """The new velocities into ``vel`` (``robot_vel`` ``(B, 2)``, ``human_vel`` ``(B, A - 1, 2)`` [m/s]), then
    :func:`motion` then :func:`outcome` in one compiled call (a world step's arithmetic), writing the step's
    figures into three blocks (fewer arguments to pass): ``floats`` ``(7, B)`` — five reward terms, reward, d_min —,
    ``ints`` ``(2, B)`` — outcome, pedestrian overlaps —, ``flags`` ``(3, B)`` bool — robot hit an obstacle,
    terminated, truncated. ``mirror`` ``(B, ≥ A, 2)``: out, the new positions again (pymunk's synchronisation
    rows). ``grid_min``: :func:`outcome`'s. Returns -1 when :func:`motion` refused non-finite velocities (nothing
    moved), else :func:`outcome`'s event bits."""
    terms, reward, d_min, result, overlaps = floats[:5], floats[5], floats[6], ints[0], ints[1]
    robot_hit, terminated, truncated = flags[0], flags[1], flags[2]
    B, A = radius.shape
    for b in range(B):
        vel[b, 0, 0], vel[b, 0, 1] = robot_vel[b, 0], robot_vel[b, 1]
        for h in range(1, A):
            vel[b, h, 0], vel[b, h, 1] = human_vel[b, h - 1, 0], human_vel[b, h - 1, 1]
    if not motion(pos, vel, v_pref, radius, active, edges, dt, iters, disp, robot_hit, d_min, clip_robot):
        return -1
    for b in range(B):
        for a in range(A):
            mirror[b, a, 0], mirror[b, a, 1] = pos[b, a, 0], pos[b, a, 1]
    return outcome(pos, vel, goal, radius, active, heading, steps, prev_goal_dist, d_min, robot_hit, robot_turns,
                   max_steps, rw, change_every, terms, reward, result, terminated, truncated, overlaps, reached,
                   change_due, grid_min)


@nb.njit(cache=True, inline="always", error_model="numpy")
def _insert(dist, idx, count, cap, d, j):  # pragma: no cover - numba
    """Insert candidate ``j`` at distance ``d`` into the sorted first ``count`` entries of ``dist``/``idx``, keeping
    at most ``cap`` (ties keep index order, as a stable sort would). Returns the new count."""
    if count == cap and not d < dist[cap - 1]:
        return count
    if count < cap:
        count += 1
    k = count - 1
    while k > 0 and d < dist[k - 1]:
        dist[k], idx[k] = dist[k - 1], idx[k - 1]
        k -= 1
    dist[k], idx[k] = d, j
    return count


@nb.njit(cache=True, error_model="numpy")
def robot_observation(pos, vel, goal, radius, v_pref, heading, active, max_range, by_id, robot, humans,
                      mask):  # pragma: no cover - numba
    """The robot's observation arrays, nearest pedestrian first, in place.

    Args (``B`` worlds of ``A`` agents, ``n`` observed slots):
        pos, vel, goal: ``(B, A, 2)``. radius, v_pref, heading: ``(B, A)``. active: ``(B, A)`` bool.
        max_range: Sensing range [m]: pedestrians whose surface distance to the robot (centre distance minus both
            radii, CrowdNav++'s ``detect_visible``, ``crowd_sim.py:547-550``) exceeds it are left out (``inf``:
            none). Nearest first sorts by centre distance.
        by_id: Slot ``j`` holds pedestrian ``j`` (zero and masked when left out) instead of the nearest-first order.
        robot: Out ``(B, 9)`` float32 = [px, py, r, gx, gy, v_pref, θ, vx, vy].
        humans: Out ``(B, n, F)`` float32: F = 2 (Δx, Δy) or 5 (Δx, Δy, vx, vy, r), nearest first (ties by index)
            or by pedestrian index, zero-padded.
        mask: Out ``(B, n)`` float32: 1 for real entries.

    """
    B, A = radius.shape
    n, F = humans.shape[1], humans.shape[2]
    dist = np.empty(max(n, 1))
    idx = np.empty(max(n, 1), np.int64)
    for b in range(B):
        robot[b, 0], robot[b, 1], robot[b, 2] = pos[b, 0, 0], pos[b, 0, 1], radius[b, 0]
        robot[b, 3], robot[b, 4], robot[b, 5] = goal[b, 0, 0], goal[b, 0, 1], v_pref[b, 0]
        robot[b, 6], robot[b, 7], robot[b, 8] = heading[b, 0], vel[b, 0, 0], vel[b, 0, 1]
        count = 0
        for h in range(1, A):
            dx, dy = pos[b, h, 0] - pos[b, 0, 0], pos[b, h, 1] - pos[b, 0, 1]
            d = math.sqrt(dx * dx + dy * dy)
            if active[b, h] and d - radius[b, h] - radius[b, 0] <= max_range:
                if by_id:
                    if h <= n:
                        idx[count], count = h, count + 1
                elif n > 0:
                    count = _insert(dist, idx, count, n, d, h)
        humans[b] = 0.0
        mask[b] = 0.0
        for k in range(count):
            h = idx[k]
            j = h - 1 if by_id else k
            mask[b, j] = 1.0
            humans[b, j, 0] = pos[b, h, 0] - pos[b, 0, 0]
            humans[b, j, 1] = pos[b, h, 1] - pos[b, 0, 1]
            if F == 5:
                humans[b, j, 2], humans[b, j, 3], humans[b, j, 4] = vel[b, h, 0], vel[b, h, 1], radius[b, h]




OBS_MAX_CELL = 0.5
"""Largest grid cell of the observation kernels, as a fraction of the sensing range."""
NEAR_FACTOR = 1.6
"""The observation kernels first search a disc expected to hold this many times as many agents as slots (from
the local density; any value gives the same neighbours, this one is the fastest found in the concourse at
N = 500 and 1,000)."""


@nb.njit(cache=True, inline="always", error_model="numpy")
def _gather_disc(pos, b, i, reach, sensing_range, cell_start, sx, sy, sidx, geo, cand_d, cand_idx):  # pragma: no cover
    """The grid members (not ``i``) of the cells within ``reach`` [m] of agent ``i`` whose centre distance ``d`` is
    ≤ ``sensing_range`` [m], as candidates (``d``, index) in ``cand_d``/``cand_idx`` (``(A + 8,)``), without
    branches; returns their count. ``d`` is computed as the brute-force loop does (member minus agent ``i``)."""
    px, py = pos[b, i, 0], pos[b, i, 1]
    r0, r1 = disc_rows(py, reach, geo)
    m = 0
    for gy in range(r0, r1 + 1):
        t0, t1 = disc_row_span(gy, px, py, reach, geo, cell_start)
        for t in range(t0, t1):
            dx, dy = sx[t] - px, sy[t] - py
            d = math.sqrt(dx * dx + dy * dy)
            j = sidx[t]
            cand_d[m], cand_idx[m] = d, j
            m += (d <= sensing_range) & (j != i)
    return m


@nb.njit(cache=True, inline="always", error_model="numpy")
def _local_reach(px, py, want, cell_start, geo):  # pragma: no cover - numba
    """The radius [m] of a disc around (``px``, ``py``) expected to hold ``want`` grid members, from their density
    in the 5 × 5 cells around the point (inf when those are empty)."""
    c, nx, ny, inv_c = geo[2], int(geo[3]), int(geo[4]), geo[6]
    cx = int(min(max((px - geo[0]) * inv_c, 0.0), nx - 1.0))
    cy = int(min(max((py - geo[1]) * inv_c, 0.0), ny - 1.0))
    x0, x1, y0, y1 = max(cx - 2, 0), min(cx + 2, nx - 1), max(cy - 2, 0), min(cy + 2, ny - 1)
    count = 0
    for gy in range(y0, y1 + 1):
        count += cell_start[gy * nx + x1 + 1] - cell_start[gy * nx + x0]
    if count == 0:
        return np.inf
    return math.sqrt(want * (x1 - x0 + 1) * (y1 - y0 + 1) * c * c / (math.pi * count))


@nb.njit(cache=True, inline="always", error_model="numpy")
def _grid_neighbors(pos, b, i, sensing_range, n, cell_start, sx, sy, sidx, geo, cand_d, cand_idx, rank, dist,
                    idx):  # pragma: no cover - numba
    """Agent ``i``'s ``n`` nearest grid members (not ``i``) whose centre distance ``d`` is ≤ ``sensing_range``
    [m], sorted by (d, index) into ``dist``/``idx`` (length ≥ A + 1); returns their count: the neighbours of the
    brute-force loop in its order (a stable insertion over ascending indices, :func:`_insert`).

    First only the disc expected to hold ``NEAR_FACTOR``·n members (:func:`_local_reach`) when it is inside the
    range: if its n-th nearest is nearer than the disc's radius (less the rounding slack), nobody outside can
    displace one; otherwise the whole range. Candidates are gathered, then ranked
    (:func:`~crowdbench.spatial.select_nearest`: faster than inserting them as they come, and order-free).
    ``cand_*`` ``(A + 8,)``, ``rank`` ``(RANK_MAX,)``: scratch."""
    near = _local_reach(pos[b, i, 0], pos[b, i, 1], NEAR_FACTOR * n, cell_start, geo)
    if near < sensing_range:
        m = _gather_disc(pos, b, i, near, sensing_range, cell_start, sx, sy, sidx, geo, cand_d, cand_idx)
        cnt = select_nearest(cand_d, cand_idx, m, n, dist, idx, rank)
        if cnt == n and dist[n - 1] < near - 2.0 * geo[5]:
            return cnt
    m = _gather_disc(pos, b, i, sensing_range, sensing_range, cell_start, sx, sy, sidx, geo, cand_d, cand_idx)
    return select_nearest(cand_d, cand_idx, m, n, dist, idx, rank)


@nb.njit(cache=True, inline="always", error_model="numpy")
def _observation_grid(pos, active, b, sensing_range, robot_visible, n, grid_min, grid):  # pragma: no cover - numba
    """Build world ``b``'s grid of observable agents (active; the robot only when ``robot_visible``) into
    ``grid`` (:func:`~crowdbench.spatial.grid_scratch`) when there are more than ``grid_min`` of them, the world's
    positions are finite and ``n`` slots and a range (≥ 0) are asked for; returns whether it did."""
    first = 0 if robot_visible else 1
    members = count_members(active, b, first)
    if not (n > 0 and sensing_range >= 0.0 and members > grid_min and finite_world(pos, b)):
        return False
    cell_start, cell_of, sx, sy, sidx, geo = grid
    build_grid(pos, active, b, OBS_MAX_CELL * sensing_range, GRID_PER_CELL, cell_start, cell_of, sx, sy, sidx, geo,
               first)
    return True


@nb.njit(cache=True, error_model="numpy")
def human_observation(pos, vel, goal, radius, v_pref, heading, active, world, sensing_range, robot_visible, me,
                      neighbors, mask, grid_min=GRID_MIN):  # pragma: no cover - numba
    """Every pedestrian slot's own observation of world ``world``, in place.

    Args (``B`` worlds of ``A`` agents, ``H = A - 1`` pedestrians, ``n`` observed slots):
        pos, vel, goal: ``(B, A, 2)``. radius, v_pref, heading: ``(B, A)``. active: ``(B, A)`` bool. world: the
            world to observe (the batch is passed whole: cheaper than seven views).
        sensing_range: Neighbours farther than this [m] are left out. robot_visible: whether the robot (agent 0)
            can be a neighbour.
        me: Out ``(H, 9)`` float32 = [px, py, vx, vy, gx, gy, r, v_pref, θ].
        neighbors: Out ``(H, n, 5)`` float32: (Δx, Δy, vx, vy, r) of the nearest agents (ties by index),
            zero-padded.
        mask: Out ``(H, n)`` float32.
        grid_min: with more observable agents than this the neighbours are found on a grid of cells
            (:mod:`crowdbench.spatial`, near-linear in the crowd), else by brute force — the same bits either way.

    """
    A = radius.shape[1]
    n = neighbors.shape[1]
    grid = grid_scratch(A)
    use_grid = _observation_grid(pos, active, world, sensing_range, robot_visible, n, grid_min, grid)
    cell_start, _, sx, sy, sidx, geo = grid
    cand_d, cand_idx = np.empty(A + 8), np.empty(A + 8, np.int64)
    rank = np.empty(RANK_MAX, np.int64)
    dist = np.empty(A + 1 if use_grid else max(n, 1))
    idx = np.empty(A + 1 if use_grid else max(n, 1), np.int64)
    b = world
    for i in range(1, A):
        m = me[i - 1]
        m[0], m[1], m[2], m[3] = pos[b, i, 0], pos[b, i, 1], vel[b, i, 0], vel[b, i, 1]
        m[4], m[5], m[6], m[7], m[8] = goal[b, i, 0], goal[b, i, 1], radius[b, i], v_pref[b, i], heading[b, i]
        count = 0
        if use_grid:
            count = _grid_neighbors(pos, b, i, sensing_range, n, cell_start, sx, sy, sidx, geo, cand_d, cand_idx,
                                    rank, dist, idx)
        elif n > 0:
            for j in range(A):
                dx, dy = pos[b, j, 0] - pos[b, i, 0], pos[b, j, 1] - pos[b, i, 1]
                d = math.sqrt(dx * dx + dy * dy)
                if active[b, j] and d <= sensing_range and j != i and (j > 0 or robot_visible):
                    count = _insert(dist, idx, count, n, d, j)
        neighbors[i - 1] = 0.0
        mask[i - 1] = 0.0
        for s in range(count):
            j = idx[s]
            mask[i - 1, s] = 1.0
            f = neighbors[i - 1, s]
            f[0], f[1] = pos[b, j, 0] - pos[b, i, 0], pos[b, j, 1] - pos[b, i, 1]
            f[2], f[3], f[4] = vel[b, j, 0], vel[b, j, 1], radius[b, j]


@nb.njit(cache=True, error_model="numpy")
def agent_observations_batch(pos, vel, goal, radius, v_pref, heading, active, sensing_range, robot_visible, me,
                             neighbors, mask, grid_min=GRID_MIN):  # pragma: no cover - numba
    """Every agent's own observation in every world — the robot (agent 0) included, in the pedestrians' layout
    (:func:`human_observation`) — in place; inactive agents observe zeros (multi-agent testbed).

    Args (``B`` worlds of ``A`` agents, ``n`` observed slots): as :func:`human_observation` without ``world``;
        me: Out ``(B, A, 9)``; neighbors: Out ``(B, A, n, 5)``; mask: Out ``(B, A, n)`` (float32). The robot sees
        the pedestrians within ``sensing_range``; a pedestrian sees the robot only when ``robot_visible``.
        grid_min: as :func:`human_observation`'s, per world.
    """
    B, A = radius.shape
    n = neighbors.shape[2]
    grid = grid_scratch(A)
    cell_start, _, sx, sy, sidx, geo = grid
    cand_d, cand_idx = np.empty(A + 8), np.empty(A + 8, np.int64)
    rank = np.empty(RANK_MAX, np.int64)
    dist = np.empty(A + 1)
    idx = np.empty(A + 1, np.int64)
    for b in range(B):
        use_grid = _observation_grid(pos, active, b, sensing_range, robot_visible, n, grid_min, grid)
        for i in range(A):
            m = me[b, i]
            neighbors[b, i] = 0.0
            mask[b, i] = 0.0
            if not active[b, i]:
                m[:] = 0.0
                continue
            m[0], m[1], m[2], m[3] = pos[b, i, 0], pos[b, i, 1], vel[b, i, 0], vel[b, i, 1]
            m[4], m[5], m[6], m[7], m[8] = goal[b, i, 0], goal[b, i, 1], radius[b, i], v_pref[b, i], heading[b, i]
            count = 0
            if use_grid:
                count = _grid_neighbors(pos, b, i, sensing_range, n, cell_start, sx, sy, sidx, geo, cand_d,
                                        cand_idx, rank, dist, idx)
            elif n > 0:
                for j in range(A):
                    if j == i or not active[b, j] or (j == 0 and not robot_visible):
                        continue
                    dx, dy = pos[b, j, 0] - pos[b, i, 0], pos[b, j, 1] - pos[b, i, 1]
                    d = math.sqrt(dx * dx + dy * dy)
                    if d <= sensing_range:
                        count = _insert(dist, idx, count, n, d, j)
            for s in range(count):
                j = idx[s]
                mask[b, i, s] = 1.0
                f = neighbors[b, i, s]
                f[0], f[1] = pos[b, j, 0] - pos[b, i, 0], pos[b, j, 1] - pos[b, i, 1]
                f[2], f[3], f[4] = vel[b, j, 0], vel[b, j, 1], radius[b, j]


@nb.njit(cache=True, inline="always", error_model="numpy")
def _disc_min_surface(pos, radius, b, i, reach, best, cell_start, sx, sy, sidx, geo):  # pragma: no cover - numba
    """``best`` lowered to the smallest surface distance [m] from agent ``i`` to the grid's other members within
    ``reach`` [m] (centre distance, may be inf) — computed as the brute-force loop does."""
    px, py, ri = pos[b, i, 0], pos[b, i, 1], radius[b, i]
    r0, r1 = disc_rows(py, reach, geo)
    for gy in range(r0, r1 + 1):
        t0, t1 = disc_row_span(gy, px, py, reach, geo, cell_start)
        for t in range(t0, t1):
            j = sidx[t]
            if j != i:
                dx, dy = sx[t] - px, sy[t] - py
                best = min(best, math.sqrt(dx * dx + dy * dy) - ri - radius[b, j])
    return best


@nb.njit(cache=True, inline="always", error_model="numpy")
def _grid_clearance(pos, radius, b, i, r_max, cell_start, sx, sy, sidx, geo):  # pragma: no cover - numba
    """The smallest surface distance [m] from pedestrian ``i`` to the grid's other members (inf if none): the
    brute-force minimum, bit for bit (the same distances; a minimum is order-free). Scans the disc one cell wider
    than touching reach (``r_i + r_max``); unless the best distance found there proves that nobody beyond it is
    nearer, once more the disc that this distance reaches (the whole grid if none was found), which does."""
    ri, eps = radius[b, i], geo[5]
    reach = ri + r_max + geo[2]
    best = _disc_min_surface(pos, radius, b, i, reach, np.inf, cell_start, sx, sy, sidx, geo)
    # anyone unvisited is farther than `reach` (centres): surface > reach − r_i − r_max, less rounding (≪ eps)
    if not best < reach - ri - r_max - 2.0 * eps:
        reach = best + ri + r_max + 2.0 * eps if best < np.inf else np.inf
        best = _disc_min_surface(pos, radius, b, i, reach, best, cell_start, sx, sy, sidx, geo)
    return best


CLEARANCE_MAX_CELL = 2.0
"""Largest grid cell of :func:`crowd_clearance`, as a multiple of the largest pedestrian radius."""


@nb.njit(cache=True, error_model="numpy")
def crowd_clearance(pos, radius, active, robot_visible, nearest, touch_ped, touch_robot,
                    grid_min=GRID_MIN):  # pragma: no cover
    """Per pedestrian of every world, in place: ``nearest`` ``(B, H)`` — the smallest surface distance to another
    active agent (the robot counted when ``robot_visible``; inf if none) [m] —, ``touch_ped`` / ``touch_robot``
    ``(B, H)`` bool — its disc overlaps another pedestrian's / the robot's. Inactive pedestrians: inf, False.
    ``pos`` ``(B, A, 2)`` [m], ``radius`` ``(B, A)`` [m], ``active`` ``(B, A)`` bool. A world with more than
    ``grid_min`` active pedestrians searches them on a grid of cells (:mod:`crowdbench.spatial`), the robot
    directly — the same bits as the brute-force loop (a pedestrian touches another exactly when its smallest
    distance to the pedestrians is negative)."""
    B, A = radius.shape
    grid = grid_scratch(A)
    cell_start, cell_of, sx, sy, sidx, geo = grid
    for b in range(B):
        if count_members(active, b, 1) > grid_min and finite_world(pos, b):
            r_max = member_max(radius, active, b, 1)
            build_grid(pos, active, b, max(CLEARANCE_MAX_CELL * r_max, 1e-3), GRID_PER_CELL, cell_start, cell_of,
                       sx, sy, sidx, geo, 1)
            robot = robot_visible and active[b, 0]
            for i in range(1, A):
                near, tp, tr = np.inf, False, False
                if active[b, i]:
                    near = _grid_clearance(pos, radius, b, i, r_max, cell_start, sx, sy, sidx, geo)
                    tp = near < 0.0
                    if robot:
                        dx, dy = pos[b, 0, 0] - pos[b, i, 0], pos[b, 0, 1] - pos[b, i, 1]
                        d = math.sqrt(dx * dx + dy * dy) - radius[b, i] - radius[b, 0]
                        near = min(d, near)
                        tr = d < 0.0
                nearest[b, i - 1], touch_ped[b, i - 1], touch_robot[b, i - 1] = near, tp, tr
            continue
        for i in range(1, A):
            near, tp, tr = np.inf, False, False
            if active[b, i]:
                for j in range(A):
                    if j == i or not active[b, j] or (j == 0 and not robot_visible):
                        continue
                    dx, dy = pos[b, j, 0] - pos[b, i, 0], pos[b, j, 1] - pos[b, i, 1]
                    d = math.sqrt(dx * dx + dy * dy) - radius[b, i] - radius[b, j]
                    near = min(near, d)
                    if d < 0.0:
                        if j == 0:
                            tr = True
                        else:
                            tp = True
            nearest[b, i - 1], touch_ped[b, i - 1], touch_robot[b, i - 1] = near, tp, tr


@nb.njit(cache=True, error_model="numpy")
def drive_actions(actions, slots, v_max, velocities, driven):  # pragma: no cover - numba
    """Normalised actions ``(k, 2)`` of the pedestrians ``slots`` ``(k,)`` → their velocities in ``velocities``
    ``(H, 2)`` [m/s] (the elliptical grid map onto each disc of radius ``v_max[slot]``) and ``driven[slot] = True``.
    Returns the row of the first action outside [−1, 1]² or not finite (nothing written then), else −1."""
    k = actions.shape[0]
    for i in range(k):
        x, y = actions[i, 0], actions[i, 1]
        if not (abs(x) <= 1.0 + 1e-6 and abs(y) <= 1.0 + 1e-6):  # also false for NaN
            return i
    for i in range(k):
        x, y = min(max(actions[i, 0], -1.0), 1.0), min(max(actions[i, 1], -1.0), 1.0)
        h = slots[i]
        velocities[h, 0] = v_max[h] * x * math.sqrt(1.0 - 0.5 * y * y)
        velocities[h, 1] = v_max[h] * y * math.sqrt(1.0 - 0.5 * x * x)
        driven[h] = True
    return -1


@nb.njit(cache=True, error_model="numpy")
def one_world_observations(pos, vel, goal, radius, v_pref, heading, active, max_range, by_id, sensing_range,
                           robot_visible, robot, humans, mask, me, neighbors, hmask,
                           grid_min=GRID_MIN):  # pragma: no cover - numba
    """:func:`robot_observation` then :func:`human_observation` of a batch of one world in one dispatch (the
    PettingZoo adapter builds both every step); arguments as theirs."""
    robot_observation(pos, vel, goal, radius, v_pref, heading, active, max_range, by_id, robot, humans, mask)
    human_observation(pos, vel, goal, radius, v_pref, heading, active, 0, sensing_range, robot_visible, me,
                      neighbors, hmask, grid_min)


@nb.njit(cache=True, error_model="numpy")
def spawn_clear(cands, pos, goal, radius, active, skip, r_new, gap, with_goals):  # pragma: no cover - numba
    """Index of the first candidate point ``cands`` ``(m, 2)`` at least ``r_new + radius[j] + gap`` [m] from every
    active agent ``j != skip`` of one world (``pos``, ``goal`` ``(A, 2)``, ``radius`` ``(A,)``, ``active``
    ``(A,)``): from its position and, with ``with_goals``, from its goal too (CrowdNav++'s spawn and goal-change
    test, ``crowd_sim_var_num.py:131-140``, ``crowd_sim.py:437-444``); ``-1`` if no candidate is clear."""
    m, A = cands.shape[0], radius.shape[0]
    for k in range(m):
        clear = True
        for j in range(A):
            if j == skip or not active[j]:
                continue
            need = r_new + radius[j] + gap
            dx, dy = cands[k, 0] - pos[j, 0], cands[k, 1] - pos[j, 1]
            if not math.sqrt(dx * dx + dy * dy) >= need:
                clear = False
                break
            if with_goals:
                dx, dy = cands[k, 0] - goal[j, 0], cands[k, 1] - goal[j, 1]
                if not math.sqrt(dx * dx + dy * dy) >= need:
                    clear = False
                    break
        if clear:
            return k
    return -1


@nb.njit(cache=True, error_model="numpy")
def first_clear(starts, pos, radius, active, agent, gap):  # pragma: no cover - numba
    """Index of the first candidate start ``(m, 2)`` whose centre distance to every other active agent of the world
    (``pos`` ``(A, 2)``, ``radius`` ``(A,)``, ``active`` ``(A,)``) is at least both radii + ``gap`` [m], where
    ``agent`` is the one being placed; ``m - 1`` if none is (the calibrated crowd's re-spawn,
    ``CrowdWorld._respawn``)."""
    k = spawn_clear(starts, pos, pos, radius, active, agent, radius[agent], gap, False)
    return starts.shape[0] - 1 if k < 0 else k


@nb.njit(cache=True, error_model="numpy")
def change_goals(cands, slots, pos, goal, radius, active, gap):  # pragma: no cover - numba
    """CrowdNav++'s random goal change of one world (``crowd_sim.py:415-450``), in place: agent ``slots[i]`` takes
    the first of its candidate goals ``cands[i]`` ``(m, 2)`` that is :func:`spawn_clear` of every other active agent's
    position and goal, in slot order (a later agent is checked against the new goals of earlier ones); an agent with
    no clear candidate keeps its goal. Returns how many goals changed."""
    changed = 0
    for i in range(slots.shape[0]):
        a = slots[i]
        k = spawn_clear(cands[i], pos, goal, radius, active, a, radius[a], gap, True)
        if k >= 0:
            goal[a, 0], goal[a, 1] = cands[i, k, 0], cands[i, k, 1]
            changed += 1
    return changed


@nb.njit(cache=True, error_model="numpy")
def assign_slots(seen, dist, spawns, steps, who, slot_of, last_spawns, last_step):  # pragma: no cover - numba
    """Persistent observation slots, in place, for worlds with more pedestrians ``H`` than slots ``n``.

    Inputs ``seen`` ``(B, H)`` bool (in sensing range), ``dist`` ``(B, H)`` [m] (any order-preserving distance; only
    seen entries are read), ``spawns`` ``(B, H)`` (re-spawn counts) and the episode step ``steps`` ``(B,)``. State
    kept between calls: ``who`` ``(B, n)`` (the pedestrian in each slot, −1 free), ``slot_of`` ``(B, H)`` (its
    inverse, −1 none), ``last_spawns`` ``(B, H)`` and ``last_step`` ``(B,)``. Per world: every slot frees when the step
    counter neither repeats nor follows on (a new episode); a slot frees when its pedestrian is out of view or was
    re-spawned; then the seen pedestrians without a slot take the free slots nearest first (ties by index), lowest
    slot first, until none is free. Calling it twice on the same state changes nothing."""
    B, H = seen.shape
    n = who.shape[1]
    for b in range(B):
        if steps[b] != last_step[b] and steps[b] != last_step[b] + 1:
            for s in range(n):
                who[b, s] = -1
            for h in range(H):
                slot_of[b, h] = -1
        for s in range(n):
            h = who[b, s]
            if h >= 0 and (not seen[b, h] or spawns[b, h] != last_spawns[b, h]):
                who[b, s] = -1
                slot_of[b, h] = -1
        key = np.where(seen[b], dist[b], INF)
        order = np.argsort(key, kind="mergesort")
        free = 0
        for i in range(H):
            h = order[i]
            if not seen[b, h]:
                break
            if slot_of[b, h] >= 0:
                continue
            while free < n and who[b, free] >= 0:
                free += 1
            if free == n:
                break
            who[b, free] = h
            slot_of[b, h] = free
        for h in range(H):
            last_spawns[b, h] = spawns[b, h]
        last_step[b] = steps[b]
