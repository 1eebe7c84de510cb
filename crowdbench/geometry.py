"""Vectorised 2-D geometry used in the step path. All functions broadcast over leading dimensions.

Shapes: points and vectors are ``(..., 2)`` float64 arrays in metres; distances are ``(...)``.
"""

# numba-cache-key: crowdbench.spatial b0452486ca54

from __future__ import annotations

from collections.abc import Sequence

import numba as nb
import numpy as np

from crowdbench.spatial import (
    GRID_MIN,
    GRID_PER_CELL,
    build_grid,
    count_members,
    disc_row_span,
    disc_rows,
    finite_world,
    grid_scratch,
    member_max,
)

Polygon = Sequence[tuple[float, float]]


def obstacle_edges(obstacles: Sequence[Polygon]) -> np.ndarray:
    """Edges of static obstacles, shape ``(S, 2, 2)`` = (edge, endpoint, xy).

    A 2-vertex obstacle is one wall segment; ≥ 3 vertices form a closed polygon (all its edges).
    """
    edges: list[tuple[tuple[float, float], tuple[float, float]]] = []
    for poly in obstacles:
        pts = [tuple(map(float, p)) for p in poly]
        if len(pts) == 2:
            edges.append((pts[0], pts[1]))
        else:
            edges.extend((pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts)))
    return np.asarray(edges, dtype=np.float64).reshape(-1, 2, 2)


def norm(v: np.ndarray) -> np.ndarray:
    """Euclidean norm over the last axis of ``(..., 2)`` vectors (faster than ``np.linalg.norm`` for 2-D)."""
    return np.sqrt(v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1])


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from points ``p`` to segments ``a``–``b`` [m]."""
    ab = b - a
    denom = np.maximum(np.einsum("...i,...i->...", ab, ab), 1e-18)
    t = np.clip(np.einsum("...i,...i->...", p - a, ab) / denom, 0.0, 1.0)
    closest = a + t[..., None] * ab
    return norm(p - closest)


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def segment_segment_distance(p0: np.ndarray, p1: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Minimum distance between segments ``p0``–``p1`` and ``a``–``b`` (0 where they cross) [m]."""
    d = np.minimum(
        np.minimum(point_segment_distance(p0, a, b), point_segment_distance(p1, a, b)),
        np.minimum(point_segment_distance(a, p0, p1), point_segment_distance(b, p0, p1)),
    )
    r, s = p1 - p0, b - a
    denom = _cross(r, s)
    safe = np.where(np.abs(denom) > 1e-15, denom, 1.0)
    t = _cross(a - p0, s) / safe
    u = _cross(a - p0, r) / safe
    crossing = (np.abs(denom) > 1e-15) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    return np.where(crossing, 0.0, d)


def swept_segment_fraction(
    p0: np.ndarray, disp: np.ndarray, radius: np.ndarray, edges: np.ndarray, iters: int = 20
) -> tuple[np.ndarray, np.ndarray]:
    """How far discs can move before touching a static edge.

    Args:
        p0: Disc centres at the start of the step, ``(B, A, 2)``.
        disp: Intended displacements over the step, ``(B, A, 2)``.
        radius: Disc radii, ``(B, A)``.
        edges: Static edges per world, ``(B, S, 2, 2)`` (or ``(S, 2, 2)``, shared).
        iters: Bisection iterations (the fraction is resolved to ``2**-iters``).

    Returns:
        ``(fraction, hit)``: ``fraction`` in [0, 1] ``(B, A)`` is the largest safe share of ``disp`` such that the
        disc stays at distance > its radius from every edge along the way (1 where nothing is in the way);
        ``hit`` ``(B, A)`` is True where the full sweep would touch an edge.

    """
    if edges.shape[-3] == 0:
        shape = p0.shape[:-1]
        return np.ones(shape), np.zeros(shape, dtype=bool)
    if edges.ndim == 3:
        edges = np.broadcast_to(edges, (p0.shape[0], *edges.shape))
    a = edges[:, None, :, 0, :]  # (B, 1, S, 2)
    b = edges[:, None, :, 1, :]
    start = p0[:, :, None, :]  # (B, A, 1, 2)
    r = radius[:, :, None]
    dist = segment_segment_distance(start, start + disp[:, :, None, :], a, b)  # (B, A, S)
    hit = (dist <= r).any(axis=-1)
    frac = np.ones(p0.shape[:-1])
    if not hit.any():
        return frac, hit
    bi, ai = np.nonzero(hit)
    s0 = p0[bi, ai][:, None, :]  # (K, 1, 2)
    dk = disp[bi, ai][:, None, :]
    rk = radius[bi, ai][:, None]
    ak, bk = edges[bi, :, 0, :], edges[bi, :, 1, :]  # (K, S, 2)
    lo = np.zeros(len(bi))
    hi = np.ones(len(bi))
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        touch = (segment_segment_distance(s0, s0 + mid[:, None, None] * dk, ak, bk) <= rk).any(axis=-1)
        hi = np.where(touch, mid, hi)
        lo = np.where(touch, lo, mid)
    frac[bi, ai] = lo
    return frac, hit


def swept_pair_min_distance(rel_p0: np.ndarray, rel_disp: np.ndarray) -> np.ndarray:
    """Minimum of ``|rel_p0 + t * rel_disp|`` over ``t ∈ [0, 1]`` (closest approach of two linear motions) [m]."""
    vv = np.einsum("...i,...i->...", rel_disp, rel_disp)
    t = np.clip(-np.einsum("...i,...i->...", rel_p0, rel_disp) / np.maximum(vv, 1e-18), 0.0, 1.0)
    return norm(rel_p0 + t[..., None] * rel_disp)


@nb.njit(cache=True)
def pair_overlaps(pos: np.ndarray, radius: np.ndarray, active: np.ndarray,
                  grid_min: int = GRID_MIN) -> np.ndarray:  # pragma: no cover
    """Overlapping pairs per world: ``pos`` ``(B, A, 2)`` [m], ``radius`` ``(B, A)`` [m], ``active`` ``(B, A)`` bool
    → ``(B,)`` int64 counts of pairs ``i < j``, both active, with centre distance² < (r_i + r_j)² (the same float
    operations as the broadcast numpy form, without its ``(B, A, A)`` temporaries). A world with more than
    ``grid_min`` active agents visits, for each ``i``, only the agents of the cells within ``r_i + r_max`` of it
    (:mod:`crowdbench.spatial`): the same pairs, the same test, the same count."""
    B, A = radius.shape
    out = np.zeros(B, dtype=np.int64)
    cell_start, cell_of, sx, sy, sidx, geo = grid_scratch(A)
    for b in range(B):
        n = 0
        if count_members(active, b, 0) > grid_min and finite_world(pos, b):
            r_max = member_max(radius, active, b, 0)
            build_grid(pos, active, b, max(2.0 * r_max, 1e-3), GRID_PER_CELL, cell_start, cell_of, sx, sy, sidx,
                       geo)
            for i in range(A):
                if not active[b, i]:
                    continue
                px, py, ri = pos[b, i, 0], pos[b, i, 1], radius[b, i]
                reach = ri + r_max
                r0, r1 = disc_rows(py, reach, geo)
                for gy in range(r0, r1 + 1):
                    t0, t1 = disc_row_span(gy, px, py, reach, geo, cell_start)
                    for t in range(t0, t1):
                        j = sidx[t]
                        if j > i:
                            dx = px - sx[t]
                            dy = py - sy[t]
                            rr = ri + radius[b, j]
                            n += dx * dx + dy * dy < rr * rr
            out[b] = n
            continue
        for i in range(A):
            if not active[b, i]:
                continue
            for j in range(i + 1, A):
                if active[b, j]:
                    dx = pos[b, i, 0] - pos[b, j, 0]
                    dy = pos[b, i, 1] - pos[b, j, 1]
                    rr = radius[b, i] + radius[b, j]
                    if dx * dx + dy * dy < rr * rr:
                        n += 1
        out[b] = n
    return out
