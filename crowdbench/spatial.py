"""Cell lists: near-linear neighbour queries for large crowds (compiled, numba), shared by the ORCA kernel
(:mod:`crowdbench.humans.orca_kernel`) and the world's kernels (:mod:`crowdbench.worlds._kernels`,
:func:`crowdbench.geometry.pair_overlaps`).

One world's member agents are sorted into square cells (:func:`build_grid`, a counting sort, O(A)); a query then
visits only the cells that a disc around a point reaches (:func:`disc_rows`, :func:`disc_row_span`: one contiguous
run of the sorted agents per row of cells). Callers apply their own exact predicate to the agents visited — the
same floating-point expression, on the same coordinates, as their brute-force loop — so the grid path selects the
same agents; where order matters they rank by (key, index) (:func:`select_nearest`, :func:`insert_nearest`), the
order a brute-force loop over ascending indices produces with a stable insertion. Every geometric bound is widened
by the grid's rounding slack (``geo[5]``), so an agent is never missed for a rounding of its cell.

numba's on-disk cache does not follow imports: every module whose cached kernels call these carries a
``# numba-cache-key`` line with this file's digest, which ``tests/test_numba_cache_keys.py`` keeps current (so an
edit here changes those modules and their caches recompile).

Grid layout (the ``geo`` array, 7 floats): min x, min y, cell size [m], nx, ny (cells per row and column), slack
[m], 1 / cell size. The agents of cell ``k = gy·nx + gx`` are ``sidx[cell_start[k]:cell_start[k + 1]]`` (index
order) at ``(sx[t], sy[t])`` (copies of their positions).
"""

from __future__ import annotations

import numba as nb
import numpy as np

GRID_MIN = 128
"""The world's kernels use a grid for a world with more member agents than this (observations, pedestrian
clearance, overlap counting) and brute force below; both give the same results bit for bit. Where the grid starts
to pay (one core, 0.6 people/m², 30 observed slots within 5 m): ≈ 50 agents for clearance and overlaps, ≈ 150 for
the observations (about 16 µs apart at either end)."""

GRID_PER_CELL = 2.0
"""Member agents per cell on average (the cell size; any gives the same results)."""

RANK_MAX = 64
"""Up to this many candidates :func:`select_nearest` ranks them without branches; beyond, it inserts them one by
one."""


@nb.njit(cache=True)
def grid_scratch(A):  # pragma: no cover - numba
    """Scratch of :func:`build_grid` for ``A`` agents: ``cell_start`` ``(16·A + 2,)`` int64, ``cell_of`` ``(A,)``
    int64, ``sx``, ``sy`` ``(A,)`` float64, ``sidx`` ``(A,)`` int64, ``geo`` ``(7,)``."""
    return (np.empty(16 * A + 2, np.int64), np.empty(A, np.int64), np.empty(A), np.empty(A),
            np.empty(A, np.int64), np.empty(7))


@nb.njit(cache=True, error_model="numpy")
def build_grid(pos, active, b, max_cell, per_cell, cell_start, cell_of, sx, sy, sidx, geo,
               first=0):  # pragma: no cover - numba
    """Cell lists of world ``b``'s member agents — active, index ≥ ``first`` — (counting sort), cells row by row
    (``k = gy·nx + gx``): the agents of cell ``k`` are ``sidx[cell_start[k]:cell_start[k + 1]]`` in index order, at
    ``(sx, sy)`` (copies of their positions, so that a row of cells is one contiguous run of memory).

    Args: ``pos`` ``(B, A, 2)`` [m], ``active`` ``(B, A)`` bool (positions of members must be finite). ``geo``
    (out): min x, min y, cell size, nx, ny, slack, 1 / cell size. The cell size gives about ``per_cell`` agents per
    cell on average, at most ``max_cell`` [m], with at most ``len(cell_start) − 1`` cells; ``slack`` [m] bounds how
    far rounding may put an agent outside its cell. ``cell_of`` (scratch, length A): each agent's cell."""
    A = pos.shape[1]
    minx = miny = np.inf
    maxx = maxy = -np.inf
    n = 0
    for j in range(first, A):
        if active[b, j]:
            x, y = pos[b, j, 0], pos[b, j, 1]
            minx, maxx, miny, maxy = min(minx, x), max(maxx, x), min(miny, y), max(maxy, y)
            n += 1
    if n == 0:
        minx = miny = maxx = maxy = 0.0
    w, h = max(maxx - minx, 1e-6), max(maxy - miny, 1e-6)
    c = max(min(np.sqrt(w * h / max(n, 1) * per_cell), max_cell), 1e-3)
    cap = cell_start.shape[0] - 1
    while (int(w / c) + 1) * (int(h / c) + 1) > cap:
        c *= 1.25
    nx, ny = int(w / c) + 1, int(h / c) + 1
    geo[0], geo[1], geo[2], geo[3], geo[4] = minx, miny, c, nx, ny
    geo[5] = 1e-9 * (1.0 + abs(minx) + abs(miny) + w + h + c)
    geo[6] = 1.0 / c
    cell_start[: nx * ny + 1] = 0
    for j in range(first, A):
        if active[b, j]:
            k = min(int((pos[b, j, 1] - miny) / c), ny - 1) * nx + min(int((pos[b, j, 0] - minx) / c), nx - 1)
            cell_of[j] = k
            cell_start[k + 1] += 1
    for k in range(nx * ny):
        cell_start[k + 1] += cell_start[k]
    for j in range(first, A):  # ascending j: each cell lists its agents in index order; cell_start[k] ends at k + 1's
        if active[b, j]:
            k = cell_of[j]
            t = cell_start[k]
            sx[t], sy[t], sidx[t] = pos[b, j, 0], pos[b, j, 1], j
            cell_start[k] = t + 1
    for k in range(nx * ny, 0, -1):
        cell_start[k] = cell_start[k - 1]
    cell_start[0] = 0


@nb.njit(cache=True, inline="always", error_model="numpy")
def _clamp_cell(v, n):  # pragma: no cover - numba
    """Cell coordinate ``floor(v)`` clamped to ``0 … n − 1`` (``v`` may be ±inf)."""
    return int(min(max(v, 0.0), n - 1.0))


@nb.njit(cache=True, inline="always", error_model="numpy")
def disc_rows(py, reach, geo):  # pragma: no cover - numba
    """The rows of cells ``r0 … r1`` (inclusive) that can hold an agent within ``reach`` [m] (may be inf) of a point
    at height ``py``."""
    miny, inv_c, ny, eps = geo[1], geo[6], geo[4], geo[5]
    return _clamp_cell((py - reach - eps - miny) * inv_c, ny), _clamp_cell((py + reach + eps - miny) * inv_c, ny)


@nb.njit(cache=True, inline="always", error_model="numpy")
def disc_row_span(gy, px, py, reach, geo, cell_start):  # pragma: no cover - numba
    """The run ``t0 ≤ t < t1`` of sorted agents in row ``gy`` over the columns that the disc of radius ``reach``
    [m] around (``px``, ``py``) spans at the row's nearest edge (empty when the row is beyond the disc): every
    agent of the row within ``reach`` of the point is in it."""
    minx, miny, c, nx, eps, inv_c = geo[0], geo[1], geo[2], geo[3], geo[5], geo[6]
    top, bottom = miny + (gy + 1) * c, miny + gy * c
    gap = max(max(py - top, bottom - py) - eps, 0.0)
    if gap > reach:
        return 0, 0
    half = np.sqrt(reach * reach - gap * gap) + eps
    row = gy * int(nx)
    return (cell_start[row + _clamp_cell((px - half - minx) * inv_c, nx)],
            cell_start[row + _clamp_cell((px + half - minx) * inv_c, nx) + 1])


@nb.njit(cache=True, inline="always", error_model="numpy")
def insert_nearest(nb_d, nb_idx, cnt, k_max, key, j):  # pragma: no cover - numba
    """Insert candidate ``j`` (distance key ``key``) into the sorted ``k_max``-nearest list ``nb_d``/``nb_idx``
    (order: key, then index — the brute-force order); returns the new count."""
    if cnt == k_max and not (key < nb_d[cnt - 1] or (key == nb_d[cnt - 1] and j < nb_idx[cnt - 1])):
        return cnt
    k = cnt if cnt < k_max else cnt - 1
    while k > 0 and (key < nb_d[k - 1] or (key == nb_d[k - 1] and j < nb_idx[k - 1])):
        nb_d[k], nb_idx[k] = nb_d[k - 1], nb_idx[k - 1]
        k -= 1
    nb_d[k], nb_idx[k] = key, j
    return cnt + 1 if cnt < k_max else cnt


@nb.njit(cache=True, inline="always", error_model="numpy")
def select_nearest(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank):  # pragma: no cover - numba
    """The ``k_max`` smallest (key, index) pairs of ``m`` candidates in any order (keys ``cand_d``, agent indices
    ``cand_idx``), sorted — key, equal keys in index order (RVO2's ``insertAgentNeighbor`` result, and a stable
    insertion over ascending indices). Written to ``nb_d``/``nb_idx`` (length ≥ ``m`` + 1: the last slot takes the
    discarded); returns their count. ``cand_*`` need 7 spare slots (the padding), ``rank`` (scratch) ``RANK_MAX``
    slots.

    Up to ``RANK_MAX`` candidates each one's rank is counted without branches: the strict ranks of eight candidates
    at a time, held in registers while every candidate is compared with them (vector compares; 3–4× faster than
    insertion at 20 candidates, whose data-dependent branches mispredict). Distinct keys give ranks 0, …, m − 1
    (sum m(m − 1)/2); equal keys share one and lower the sum, and only then are the ranks counted again with the
    index breaking ties. Beyond, insertion into the sorted prefix with the cut-off shrinking to the k-th key (RVO2's
    own procedure) wins.
    """
    cnt = min(m, k_max)
    if m <= RANK_MAX:
        discard = nb_d.shape[0] - 1
        mp = (m + 7) & ~7
        for p in range(m, mp):
            cand_d[p] = np.inf
        for p0 in range(0, mp, 8):
            d0, d1, d2, d3 = cand_d[p0], cand_d[p0 + 1], cand_d[p0 + 2], cand_d[p0 + 3]
            d4, d5, d6, d7 = cand_d[p0 + 4], cand_d[p0 + 5], cand_d[p0 + 6], cand_d[p0 + 7]
            r0 = r1 = r2 = r3 = r4 = r5 = r6 = r7 = 0
            for q in range(m):
                dq = cand_d[q]
                r0 += dq < d0
                r1 += dq < d1
                r2 += dq < d2
                r3 += dq < d3
                r4 += dq < d4
                r5 += dq < d5
                r6 += dq < d6
                r7 += dq < d7
            rank[p0], rank[p0 + 1], rank[p0 + 2], rank[p0 + 3] = r0, r1, r2, r3
            rank[p0 + 4], rank[p0 + 5], rank[p0 + 6], rank[p0 + 7] = r4, r5, r6, r7
        total = 0
        for p in range(m):
            total += rank[p]
        if total != m * (m - 1) // 2:  # equal keys: rank again, the index breaking ties
            for p in range(m):
                rank[p] = 0
            for q in range(m):
                dq, iq = cand_d[q], cand_idx[q]
                for p in range(m):
                    rank[p] += (dq < cand_d[p]) | ((dq == cand_d[p]) & (iq < cand_idx[p]))
        for p in range(m):
            slot = rank[p] if rank[p] < cnt else discard
            nb_d[slot], nb_idx[slot] = cand_d[p], cand_idx[p]
        return cnt
    c = 0
    for p in range(m):
        c = insert_nearest(nb_d, nb_idx, c, k_max, cand_d[p], cand_idx[p])
    return cnt


@nb.njit(cache=True, error_model="numpy")
def finite_world(pos, b):  # pragma: no cover - numba
    """Whether every agent of world ``b`` (``pos`` ``(B, A, 2)`` [m]) is at a finite position: the grid paths need
    it (the brute-force loops give non-finite positions their own meaning, so a world holding one uses those)."""
    for j in range(pos.shape[1]):  # noqa: SIM110 (numba-friendly)
        if not (np.isfinite(pos[b, j, 0]) and np.isfinite(pos[b, j, 1])):
            return False
    return True


@nb.njit(cache=True, inline="always", error_model="numpy")
def count_members(active, b, first):  # pragma: no cover - numba
    """How many agents ``j ≥ first`` of world ``b`` are active (``active`` ``(B, A)`` bool)."""
    n = 0
    for j in range(first, active.shape[1]):
        n += active[b, j]
    return n


@nb.njit(cache=True, inline="always", error_model="numpy")
def member_max(values, active, b, first):  # pragma: no cover - numba
    """The largest ``values[b, j]`` over the active agents ``j ≥ first`` of world ``b`` (``values``, ``active``
    ``(B, A)``); 0 if none (e.g. the largest radius [m], which sizes a grid's cells)."""
    out = 0.0
    for j in range(first, active.shape[1]):
        if active[b, j]:
            out = max(out, values[b, j])
    return out
