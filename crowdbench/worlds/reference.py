"""Plain numpy reference of the world's compiled kernels (:mod:`crowdbench.worlds._kernels`).

Same signatures, same results bit for bit (``tests/worlds/test_kernels.py``). This is the readable statement of
what a step does — broadcasts over ``(B, A)`` built on :mod:`crowdbench.geometry` — and the kernels' test oracle;
the world itself runs the kernels.
"""

from __future__ import annotations

import math

import numpy as np

from crowdbench.geometry import norm, pair_overlaps, swept_pair_min_distance, swept_segment_fraction

BRUTE_FORCE = np.iinfo(np.int64).max
"""A ``grid_min`` that no crowd exceeds: the compiled kernels' brute-force path."""


def _atan2(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The C library's ``atan2`` element by element (numpy's ``arctan2`` is vectorised differently on some CPUs)."""
    return np.array([math.atan2(a, b) for a, b in zip(y.tolist(), x.tolist(), strict=True)], dtype=np.float64)


def clip_norm(v: np.ndarray, vmax: np.ndarray) -> np.ndarray:
    """Scale vectors ``(..., 2)`` down to at most ``vmax`` ``(...)`` in norm."""
    n = norm(v)
    return v * np.minimum(1.0, vmax / np.maximum(n, 1e-12))[..., None]


def motion(pos, vel, v_pref, radius, active, edges, dt, iters, disp, robot_hit, d_min, clip_robot) -> bool:
    """See :func:`crowdbench.worlds._kernels.motion`."""
    if not np.isfinite(vel[:, 1:][active[:, 1:]]).all():
        return False
    if clip_robot:
        vel[:, 0] = clip_norm(vel[:, 0], v_pref[:, 0])
    vel[:, 1:] = clip_norm(vel[:, 1:], v_pref[:, 1:])
    vel[~active] = 0.0
    d = vel * dt
    robot_hit[:] = False
    if len(edges):
        frac, hit = swept_segment_fraction(pos, d, radius, edges, iters)
        frac[~active] = 1.0
        d *= frac[..., None]
        vel[:] = d / dt
        robot_hit[:] = hit[:, 0]
    disp[:] = d
    centre = swept_pair_min_distance(pos[:, 1:] - pos[:, :1], d[:, 1:] - d[:, :1])
    surface = centre - radius[:, 1:] - radius[:, :1]
    d_min[:] = np.where(active[:, 1:], surface, np.inf).min(axis=1, initial=np.inf)
    pos += vel * dt
    return True


def outcome(pos, vel, goal, radius, active, heading, steps, prev_goal_dist, d_min, robot_hit, robot_turns,
            max_steps, rw, change_every, terms, reward, result, terminated, truncated, overlaps, reached,
            change_due, grid_min=None) -> int:
    """See :func:`crowdbench.worlds._kernels.outcome` (the paper's piecewise reward, first matching case wins;
    ``grid_min`` is the kernels' choice of neighbour search, and the reference counts overlaps by brute force)."""
    moving = np.einsum("bai,bai->ba", vel, vel) > 1e-12
    if robot_turns:
        moving[:, 0] = False
    heading[moving] = _atan2(vel[..., 1][moving], vel[..., 0][moving])  # libm's atan2, element by element
    gdist = norm(goal[:, 0] - pos[:, 0])
    success = gdist <= rw[6]
    collision = ((d_min <= 0.0) | robot_hit) & ~success
    discomfort = ~success & ~collision & (d_min < rw[2])
    progress = ~success & ~collision & ~discomfort
    terms[0] = np.where(success, rw[0], 0.0)
    terms[1] = np.where(collision, rw[1], 0.0)
    terms[2] = np.where(discomfort, rw[3] * (d_min - rw[2]), 0.0)
    terms[3] = np.where(progress, rw[4] * (prev_goal_dist - gdist), 0.0)
    terms[4] = rw[5]
    reward[:] = (((terms[0] + terms[1]) + terms[2]) + terms[3]) + terms[4]
    prev_goal_dist[:] = gdist
    steps += 1
    terminated[:] = success | collision
    truncated[:] = ~terminated & (steps >= max_steps)
    result[:] = np.select([success, collision, truncated], [1, 2, 3], 0)
    change_due[:] = (steps % change_every == 0) if change_every > 0 else False
    overlaps[:] = pair_overlaps(pos[:, 1:], radius[:, 1:], active[:, 1:], BRUTE_FORCE)
    d = goal[:, 1:] - pos[:, 1:]
    reached[:] = active[:, 1:] & (d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1] <= radius[:, 1:] * radius[:, 1:])
    return int(reached.any()) | 2 * int(change_due.any())


def advance(robot_vel, human_vel, pos, vel, v_pref, radius, active, edges, dt, iters, disp, clip_robot, goal, heading,
            steps, prev_goal_dist, robot_turns, max_steps, rw, change_every, floats, ints, flags, reached,
            change_due, mirror, grid_min=None) -> int:
    """See :func:`crowdbench.worlds._kernels.advance`."""
    terms, reward, d_min, result, overlaps = floats[:5], floats[5], floats[6], ints[0], ints[1]
    robot_hit, terminated, truncated = flags[0], flags[1], flags[2]
    vel[:, 0], vel[:, 1:] = robot_vel, human_vel
    if not motion(pos, vel, v_pref, radius, active, edges, dt, iters, disp, robot_hit, d_min, clip_robot):
        return -1
    mirror[:, : pos.shape[1]] = pos
    return outcome(pos, vel, goal, radius, active, heading, steps, prev_goal_dist, d_min, robot_hit, robot_turns,
                   max_steps, rw, change_every, terms, reward, result, terminated, truncated, overlaps, reached,
                   change_due)


def robot_observation(pos, vel, goal, radius, v_pref, heading, active, max_range, by_id, robot, humans,
                      mask) -> None:
    """See :func:`crowdbench.worlds._kernels.robot_observation`."""
    robot[:] = np.concatenate([pos[:, 0], radius[:, :1], goal[:, 0], v_pref[:, :1], heading[:, :1], vel[:, 0]], 1)
    rel = pos[:, 1:] - pos[:, :1]
    dist = norm(rel)
    surface = dist - radius[:, 1:] - radius[:, :1]
    key = np.where(active[:, 1:] & (surface <= max_range), dist, np.inf)
    B, H = key.shape
    k = min(humans.shape[1], H)
    order = np.broadcast_to(np.arange(k), (B, k)) if by_id else np.argsort(key, axis=1, kind="stable")[:, :k]
    valid = np.take_along_axis(key, order, axis=1) < np.inf
    feats = [np.take_along_axis(rel, order[..., None], axis=1)]
    if humans.shape[2] == 5:
        feats += [np.take_along_axis(vel[:, 1:], order[..., None], axis=1),
                  np.take_along_axis(radius[:, 1:], order, axis=1)[..., None]]
    humans[:] = 0.0
    mask[:] = 0.0
    humans[:, :k] = np.where(valid[..., None], np.concatenate(feats, -1), 0.0)
    mask[:, :k] = valid


def human_observation(pos, vel, goal, radius, v_pref, heading, active, world, sensing_range, robot_visible, me,
                      neighbors, mask, grid_min=None) -> None:
    """See :func:`crowdbench.worlds._kernels.human_observation` (``grid_min``: the kernel's choice of neighbour
    search, unused here)."""
    pos, vel, goal, radius, v_pref = pos[world], vel[world], goal[world], radius[world], v_pref[world]
    heading, active = heading[world], active[world]
    me[:] = np.concatenate([pos[1:], vel[1:], goal[1:], radius[1:, None], v_pref[1:, None], heading[1:, None]], 1)
    rel = pos[None, :] - pos[1:, None]  # (H, A, 2): agent j relative to pedestrian i
    dist = norm(rel)
    ok = active[None, :] & (dist <= sensing_range)
    ok[np.arange(len(ok)), np.arange(1, len(ok) + 1)] = False  # not itself
    if not robot_visible:
        ok[:, 0] = False
    key = np.where(ok, dist, np.inf)
    k = min(neighbors.shape[1], key.shape[1])
    order = np.argsort(key, axis=1, kind="stable")[:, :k]
    valid = np.take_along_axis(key, order, axis=1) < np.inf
    feats = np.concatenate([np.take_along_axis(rel, order[..., None], 1), vel[order], radius[order][..., None]], -1)
    neighbors[:] = 0.0
    mask[:] = 0.0
    neighbors[:, :k] = np.where(valid[..., None], feats, 0.0)
    mask[:, :k] = valid


def first_clear(starts, pos, radius, active, agent, gap) -> int:
    """See :func:`crowdbench.worlds._kernels.first_clear`."""
    others = active.copy()
    others[agent] = False
    need = radius[agent] + radius[others] + gap
    d = np.linalg.norm(starts[:, None] - pos[others][None], axis=-1)
    ok = np.flatnonzero((d >= need).all(axis=1))
    return int(ok[0]) if len(ok) else len(starts) - 1


def spawn_clear(cands, pos, goal, radius, active, skip, r_new, gap, with_goals) -> int:
    """See :func:`crowdbench.worlds._kernels.spawn_clear`."""
    others = active.copy()
    if skip >= 0:
        others[skip] = False
    need = r_new + radius[others] + gap
    ok = (np.linalg.norm(cands[:, None] - pos[others][None], axis=-1) >= need).all(axis=1)
    if with_goals:
        ok &= (np.linalg.norm(cands[:, None] - goal[others][None], axis=-1) >= need).all(axis=1)
    hits = np.flatnonzero(ok)
    return int(hits[0]) if len(hits) else -1


def assign_slots(seen, dist, spawns, steps, who, slot_of, last_spawns, last_step) -> None:
    """Persistent observation slots (the compiled ``assign_slots``'s statement, same arguments and state)."""
    n = who.shape[1]
    for b in range(seen.shape[0]):
        if steps[b] not in (last_step[b], last_step[b] + 1):  # a new episode
            who[b] = -1
            slot_of[b] = -1
        for s in range(n):  # out of view or re-spawned: the slot frees
            h = who[b, s]
            if h >= 0 and (not seen[b, h] or spawns[b, h] != last_spawns[b, h]):
                who[b, s] = slot_of[b, h] = -1
        newcomers = [h for h in sorted(np.flatnonzero(seen[b]), key=lambda h: (dist[b, h], h)) if slot_of[b, h] < 0]
        free = [s for s in range(n) if who[b, s] < 0]
        for h, s in zip(newcomers, free, strict=False):
            who[b, s], slot_of[b, h] = h, s
        last_spawns[b] = spawns[b]
        last_step[b] = steps[b]
