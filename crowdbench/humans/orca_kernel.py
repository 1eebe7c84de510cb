"""RVO2 (van den Berg et al., ORCA) ported line-for-line to numba, batched over worlds and agents.

Source of truth: the reference C++ library, RVO2 2.0.x (``Agent::computeNeighbors``, ``Agent::computeNewVelocity``,
``linearProgram1/2/3``, ``KdTree::buildObstacleTreeRecursive``, ``KdTree::queryObstacleTreeRecursive``,
``RVOSimulator::addObstacle``). Differences:

* computed in float64 (the C++ library uses float32; see ``tests/data/README.md`` for the tolerances this meets);
* agent neighbours are found by brute force in small crowds and on a grid of cells above ``GRID_MIN`` agents
  (the cells around an agent ranked, then the rows of cells that the k-th distance still reaches — RVO2's kd-tree
  query with its shrinking range, on cells; the cell lists and the ranking are :mod:`crowdbench.spatial`'s, shared
  with the world's kernels). The same set as RVO2's — the ``max_neighbors`` nearest agents strictly within
  ``neighbor_dist`` sorted by squared distance —, only exact distance *ties* may be ordered differently (RVO2
  keeps kd-tree visiting order; here it is index order, on either path: the grid and the brute force give
  bit-identical velocities, tested at N = 200 and 1,000);
* obstacle edges are RVO2's after its obstacle tree split them (``KdTree::buildObstacleTree``, :func:`build_obstacles`);
  an agent's obstacle neighbours — the edges within ``time_horizon_obst * max_speed + radius`` seen from their
  right side — are found on that tree above ``OBST_TREE_MIN`` vertices and by a scan of every edge below, in RVO2's
  order either way, ties included: for obstacles they are systematic (the two edges of a corner nearest to an
  agent are equally far) and decide which edge makes the constraint (the scan orders them by the tree,
  :func:`_visited_before`);
* each agent may ignore one other agent (``ignore``), used by the latent-responsive crowd to hide the robot.

All worlds share one obstacle set. Obstacles are stored RVO2-style as vertices with ``next``/``prev`` links,
``unit_dir`` and ``convex`` flags (see :func:`build_obstacles`).

Compiled with numba's ``error_model="numpy"``: a float division by zero gives inf/nan instead of raising, so no
zero check guards each division (every division here is guarded as in RVO2); 8 % faster at N = 20, same results.
"""

# numba-cache-key: crowdbench.spatial b0452486ca54

from __future__ import annotations

from collections.abc import Sequence

import numba as nb
import numpy as np

from crowdbench.spatial import RANK_MAX
from crowdbench.spatial import build_grid as _build_grid
from crowdbench.spatial import count_members as _count_members
from crowdbench.spatial import grid_scratch as _grid_scratch
from crowdbench.spatial import insert_nearest as _insert_nearest
from crowdbench.spatial import select_nearest as _select

RVO_EPSILON = 1e-5


def build_obstacles(polygons: Sequence[Sequence[tuple[float, float]]]) -> tuple[np.ndarray, ...]:
    """RVO2's ``addObstacle`` for each polygon (vertices counter-clockwise; 2 vertices = a two-sided segment), then
    its ``processObstacles``: the obstacle tree (:func:`_obstacle_tree`), which splits some edges in two.

    Returns ``(point (V, 2), next (V,), prev (V,), unit_dir (V, 2), convex (V,), tree (V, 6))`` — ``V`` vertices
    after the splits (RVO2's ``getNumObstacleVertices``), each the start of one edge. ``tree`` int64: columns 0–4
    describe node ``k`` (the root is node 0) — its edge, left child, right child (-1: none), parent (-1: the root),
    depth —, column 5 the node of edge ``k``.
    """
    pts, nxt, prv, udir, convex = [], [], [], [], []
    for poly in polygons:
        v = [tuple(map(float, p)) for p in poly]
        if len(v) < 2:
            raise ValueError(f"an obstacle needs ≥ 2 vertices, got {len(v)}")
        base, n = len(pts), len(v)
        for i in range(n):
            pts.append(v[i])
            nxt.append(base + (i + 1) % n)
            prv.append(base + (i - 1) % n)
            d = np.subtract(v[(i + 1) % n], v[i])
            udir.append(tuple(d / np.hypot(*d)))
            if n == 2:
                convex.append(True)
            else:
                a, b, c = v[(i - 1) % n], v[i], v[(i + 1) % n]
                convex.append(_left_of(a, b, c) >= 0.0)
    nodes = _obstacle_tree(pts, nxt, prv, udir, convex)
    tree = np.full((len(nodes), 6), -1, np.int64)
    for k, (edge, left, right) in enumerate(nodes):
        tree[k, :3] = edge, left, right
        tree[edge, 5] = k
        for child in (left, right):
            if child >= 0:
                tree[child, 3] = k
    tree[:, 4] = 0
    for k in range(1, len(nodes)):  # parents come before their children
        tree[k, 4] = tree[tree[k, 3], 4] + 1
    return (np.asarray(pts, np.float64).reshape(-1, 2), np.asarray(nxt, np.int64), np.asarray(prv, np.int64),
            np.asarray(udir, np.float64).reshape(-1, 2), np.asarray(convex, np.bool_), tree)


def _obstacle_tree(pts: list, nxt: list, prv: list, udir: list, convex: list) -> list[list[int]]:
    """RVO2's ``KdTree::buildObstacleTreeRecursive`` (c2c46ba ``src/KdTree.cpp:127-245``) on the vertex lists, which
    it extends in place where it splits an edge (a new convex vertex at the split point, appended; links updated).

    Each node takes the edge whose line leaves the fewest edges on its larger side (then on its smaller side; the
    first such edge in list order), the others go left (``leftOf ≥ −ε`` at both ends), right (``≤ ε``) or are split
    at the line; the left subtree is built before the right one (splits there change links the right side sees).
    Computed in float32 on the float32-rounded vertices, as RVO2 does, so that the same edges are chosen and split
    at the same points (a split point is kept at its float32 value; the polygons' own vertices stay float64).
    Returns the nodes ``[edge, left, right]``, root first."""
    f32 = np.float32
    eps = f32(RVO_EPSILON)
    p32 = np.zeros((2 * len(pts) + 16, 2), f32)  # the vertices in float32, room for splits (grown when full)
    p32[: len(pts)] = np.asarray(pts, np.float64).reshape(-1, 2)
    nodes: list[list[int]] = []
    todo: list[tuple[list[int], int, int]] = [(list(range(len(pts))), -1, 0)]  # (edges, parent node, side)
    while todo:
        edges, parent, side = todo.pop()
        if not edges:
            continue
        a, b = p32[edges], p32[[nxt[j] for j in edges]]
        n = len(edges)
        big, small = np.empty(n, np.int64), np.empty(n, np.int64)
        for r0 in range(0, n, 256):  # candidate lines in blocks of rows: memory O(256 · n), not O(n²)
            r1 = min(n, r0 + 256)
            l1, l2 = _left_of_lines(a[r0:r1], b[r0:r1], a), _left_of_lines(a[r0:r1], b[r0:r1], b)
            is_left = (l1 >= -eps) & (l2 >= -eps)
            is_right = ~is_left & (l1 <= eps) & (l2 <= eps)
            split = ~is_left & ~is_right
            rows = np.arange(r1 - r0)
            for m in (is_left, is_right, split):
                m[rows, r0 + rows] = False  # not the line's own edge
            n_left = is_left.sum(1) + split.sum(1)
            n_right = is_right.sum(1) + split.sum(1)
            big[r0:r1], small[r0:r1] = np.maximum(n_left, n_right), np.minimum(n_left, n_right)
        i = int(np.lexsort((small, big))[0])  # stable: the first of the best
        node = len(nodes)
        nodes.append([edges[i], -1, -1])
        if parent >= 0:
            nodes[parent][side] = node
        l1, l2 = _left_of_lines(a[i:i + 1], b[i:i + 1], a)[0], _left_of_lines(a[i:i + 1], b[i:i + 1], b)[0]
        goes_left = (l1 >= -eps) & (l2 >= -eps)
        goes_right = ~goes_left & (l1 <= eps) & (l2 <= eps)
        left_edges: list[int] = []
        right_edges: list[int] = []
        i1 = edges[i]
        i2 = nxt[i1]
        for j, j1 in enumerate(edges):
            if j == i:
                continue
            if goes_left[j]:
                left_edges.append(j1)
            elif goes_right[j]:
                right_edges.append(j1)
            else:  # split edge j1 → j2 where the line of i1 → i2 crosses it (float32, as RVO2)
                j2 = nxt[j1]
                (ix1, iy1), (ix2, iy2), (jx1, jy1), (jx2, jy2) = p32[i1], p32[i2], p32[j1], p32[j2]
                t = (((ix2 - ix1) * (jy1 - iy1) - (iy2 - iy1) * (jx1 - ix1))
                     / ((ix2 - ix1) * (jy1 - jy2) - (iy2 - iy1) * (jx1 - jx2)))
                new = len(pts)
                point = (jx1 + t * (jx2 - jx1), jy1 + t * (jy2 - jy1))
                pts.append((float(point[0]), float(point[1])))
                if new == len(p32):
                    p32 = np.concatenate([p32, np.zeros_like(p32)])
                p32[new] = point
                prv.append(j1)
                nxt.append(j2)
                convex.append(True)
                udir.append(udir[j1])
                nxt[j1] = new
                prv[j2] = new
                if l1[j] > 0.0:
                    left_edges.append(j1)
                    right_edges.append(new)
                else:
                    right_edges.append(j1)
                    left_edges.append(new)
        todo.append((right_edges, node, 2))  # popped after the whole left subtree
        todo.append((left_edges, node, 1))
    return nodes


def _left_of_lines(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """RVO2's ``leftOf(a_i, b_i, c_j)`` for every line ``i`` (through ``a_i``, ``b_i``) and point ``j``: ``(I, J)``, in
    the inputs' dtype."""
    return ((a[:, None, 0] - c[None, :, 0]) * (b[:, None, 1] - a[:, None, 1])
            - (a[:, None, 1] - c[None, :, 1]) * (b[:, None, 0] - a[:, None, 0]))


def _left_of(a, b, c) -> float:
    return (a[0] - c[0]) * (b[1] - a[1]) - (a[1] - c[1]) * (b[0] - a[0])


@nb.njit(cache=True, inline="always", error_model="numpy")
def _det(ax, ay, bx, by):
    return ax * by - ay * bx


@nb.njit(cache=True, inline="always", error_model="numpy")
def _lp1(lp, ld, line_no, radius, optx, opty, direction_opt, res):
    """linearProgram1: optimise on line ``line_no`` subject to lines ``< line_no`` and the speed circle."""
    px, py = lp[line_no, 0], lp[line_no, 1]
    dx, dy = ld[line_no, 0], ld[line_no, 1]
    dot = px * dx + py * dy
    disc = dot * dot + radius * radius - (px * px + py * py)
    if disc < 0.0:
        return False
    sq = np.sqrt(disc)
    t_left = -dot - sq
    t_right = -dot + sq
    for i in range(line_no):
        denom = _det(dx, dy, ld[i, 0], ld[i, 1])
        numer = _det(ld[i, 0], ld[i, 1], px - lp[i, 0], py - lp[i, 1])
        if abs(denom) <= RVO_EPSILON:
            if numer < 0.0:
                return False
            continue
        t = numer / denom
        if denom >= 0.0:
            t_right = min(t_right, t)
        else:
            t_left = max(t_left, t)
        if t_left > t_right:
            return False
    if direction_opt:
        if optx * dx + opty * dy > 0.0:
            res[0], res[1] = px + t_right * dx, py + t_right * dy
        else:
            res[0], res[1] = px + t_left * dx, py + t_left * dy
    else:
        t = dx * (optx - px) + dy * (opty - py)
        if t < t_left:
            t = t_left
        elif t > t_right:
            t = t_right
        res[0], res[1] = px + t * dx, py + t * dy
    return True


@nb.njit(cache=True, inline="always", error_model="numpy")
def _lp2(lp, ld, n, radius, optx, opty, direction_opt, res):
    """linearProgram2: returns the index of the first line that failed (``n`` on success); ``res`` is updated."""
    if direction_opt:
        res[0], res[1] = optx * radius, opty * radius
    elif optx * optx + opty * opty > radius * radius:
        inv = 1.0 / np.sqrt(optx * optx + opty * opty)
        res[0], res[1] = optx * inv * radius, opty * inv * radius
    else:
        res[0], res[1] = optx, opty
    for i in range(n):
        if _det(ld[i, 0], ld[i, 1], lp[i, 0] - res[0], lp[i, 1] - res[1]) > 0.0:
            tx, ty = res[0], res[1]
            if not _lp1(lp, ld, i, radius, optx, opty, direction_opt, res):
                res[0], res[1] = tx, ty
                return i
    return n


@nb.njit(cache=True, error_model="numpy")
def _lp3(lp, ld, n, n_obst, begin, radius, res, pp, pd):
    """linearProgram3: minimise the maximum penetration of agent lines when the 2-D program is infeasible."""
    distance = 0.0
    for i in range(begin, n):
        if _det(ld[i, 0], ld[i, 1], lp[i, 0] - res[0], lp[i, 1] - res[1]) > distance:
            m = 0
            for j in range(n_obst):
                pp[m, 0], pp[m, 1], pd[m, 0], pd[m, 1] = lp[j, 0], lp[j, 1], ld[j, 0], ld[j, 1]
                m += 1
            for j in range(n_obst, i):
                determinant = _det(ld[i, 0], ld[i, 1], ld[j, 0], ld[j, 1])
                if abs(determinant) <= RVO_EPSILON:
                    if ld[i, 0] * ld[j, 0] + ld[i, 1] * ld[j, 1] > 0.0:
                        continue
                    ptx = 0.5 * (lp[i, 0] + lp[j, 0])
                    pty = 0.5 * (lp[i, 1] + lp[j, 1])
                else:
                    s = _det(ld[j, 0], ld[j, 1], lp[i, 0] - lp[j, 0], lp[i, 1] - lp[j, 1]) / determinant
                    ptx = lp[i, 0] + s * ld[i, 0]
                    pty = lp[i, 1] + s * ld[i, 1]
                ddx = ld[j, 0] - ld[i, 0]
                ddy = ld[j, 1] - ld[i, 1]
                inv = 1.0 / np.sqrt(ddx * ddx + ddy * ddy)
                pp[m, 0], pp[m, 1], pd[m, 0], pd[m, 1] = ptx, pty, ddx * inv, ddy * inv
                m += 1
            tx, ty = res[0], res[1]
            if _lp2(pp, pd, m, radius, -ld[i, 1], ld[i, 0], True, res) < m:
                res[0], res[1] = tx, ty
            distance = _det(ld[i, 0], ld[i, 1], lp[i, 0] - res[0], lp[i, 1] - res[1])


@nb.njit(cache=True, inline="always", error_model="numpy")
def _vertex_legs(rx, ry, dsq, r):
    """Left and right leg directions of the velocity obstacle of a vertex at relative position (rx, ry)."""
    leg = np.sqrt(dsq - r * r)
    return ((rx * leg - ry * r) / dsq, (rx * r + ry * leg) / dsq,
            (rx * leg + ry * r) / dsq, (-rx * r + ry * leg) / dsq)


@nb.njit(cache=True, inline="always", error_model="numpy")
def _cutoff_circle_line(vx, vy, cx, cy, rad, lp, ld, n):
    """Line ``n``: the velocity projected on the cut-off circle of centre (cx, cy) and radius ``rad``."""
    wx, wy = vx - cx, vy - cy
    inv = 1.0 / np.sqrt(wx * wx + wy * wy)
    wx, wy = wx * inv, wy * inv
    ld[n, 0], ld[n, 1] = wy, -wx
    lp[n, 0], lp[n, 1] = cx + rad * wx, cy + rad * wy


@nb.njit(cache=True, inline="always", error_model="numpy")
def _edge_dsq(o, px, py, range_sq, opoint, onext):  # pragma: no cover - numba
    """Squared distance [m²] from the point to edge ``o`` if the edge is an obstacle neighbour of an agent there —
    seen from its right side, nearer than ``range_sq`` (``KdTree::queryObstacleTreeRecursive``'s tests) —, else
    inf."""
    o2 = onext[o]
    ax, ay = opoint[o, 0], opoint[o, 1]
    bx, by = opoint[o2, 0], opoint[o2, 1]
    left = (ax - px) * (by - ay) - (ay - py) * (bx - ax)  # leftOf(a, b, agent)
    abx, aby = bx - ax, by - ay
    ab2 = abx * abx + aby * aby
    if left * left / ab2 >= range_sq or left >= 0.0:
        return np.inf
    rr = ((px - ax) * abx + (py - ay) * aby) / ab2
    if rr < 0.0:
        dsq = (px - ax) ** 2 + (py - ay) ** 2
    elif rr > 1.0:
        dsq = (px - bx) ** 2 + (py - by) ** 2
    else:
        dsq = (px - ax - rr * abx) ** 2 + (py - ay - rr * aby) ** 2
    return dsq if dsq < range_sq else np.inf


@nb.njit(cache=True, inline="always", error_model="numpy")
def _visited_before(e1, e2, px, py, opoint, onext, otree):  # pragma: no cover - numba
    """Whether RVO2's obstacle-tree query from (``px``, ``py``) (:func:`_tree_obstacle_neighbors`) reaches edge
    ``e1`` before edge ``e2`` (both reached): at their nearest common node, the subtree on the agent's side of its
    line comes first, then the node, then the far subtree."""
    a, b = otree[e1, 5], otree[e2, 5]
    da, db = otree[a, 4], otree[b, 4]
    ca = cb = -1  # the children of the common node on the way to a and to b (-1: a or b is that node)
    while da > db:
        ca, a, da = a, otree[a, 3], da - 1
    while db > da:
        cb, b, db = b, otree[b, 3], db - 1
    while a != b:
        ca, cb, a, b = a, b, otree[a, 3], otree[b, 3]
    o = otree[a, 0]
    o2 = onext[o]
    ax, ay = opoint[o, 0], opoint[o, 1]
    left = (ax - px) * (opoint[o2, 1] - ay) - (ay - py) * (opoint[o2, 0] - ax)
    near = otree[a, 1] if left >= 0.0 else otree[a, 2]
    if ca == -1:  # e1's node is the common one: e1 comes first iff e2 lies on the far side
        return cb != near
    return ca == near


@nb.njit(cache=True, error_model="numpy")
def _obstacle_neighbors(px, py, range_sq, opoint, onext, otree, ob_idx, ob_d):  # pragma: no cover - numba
    """Every obstacle neighbour of an agent at (``px``, ``py``) by a scan of all edges, sorted by squared distance
    into ``ob_d``/``ob_idx`` — equal distances (the two edges of a corner nearest to the agent) in the order RVO2's
    tree query reaches them (:func:`_visited_before`), as :func:`_tree_obstacle_neighbors`. Returns their count."""
    n_ob = 0
    for o in range(opoint.shape[0]):
        dsq = _edge_dsq(o, px, py, range_sq, opoint, onext)
        if dsq < np.inf:
            k = n_ob
            while k != 0 and (dsq < ob_d[k - 1] or (dsq == ob_d[k - 1]
                                                    and _visited_before(o, ob_idx[k - 1], px, py, opoint, onext,
                                                                        otree))):
                ob_d[k], ob_idx[k] = ob_d[k - 1], ob_idx[k - 1]
                k -= 1
            ob_d[k], ob_idx[k] = dsq, o
            n_ob += 1
    return n_ob


OBST_TREE_MIN = 512
"""Obstacle sets with more vertices (after RVO2's splits) than this are searched on the tree
(:func:`_tree_obstacle_neighbors`), smaller ones by a scan of every edge (:func:`_obstacle_neighbors`); both give
the same neighbours in the same order. Per query (one core, range 5.31 m, ``benchmarks/bench_orca_obstacles.py``'s
pillar halls): 52 vertices scan 0.12 µs, tree 0.25; 364 scan 1.08 / 0.72 µs, tree 1.48 / 0.54 (dense / sparse
pillars); 964 scan 1.97, tree 1.02; 1,524 scan 3.30, tree 1.71. A module constant, not an argument: an omitted
argument's compile-time default made numba's ``orca_batch`` 2.4× slower."""


@nb.njit(cache=True, error_model="numpy")
def _tree_obstacle_neighbors(px, py, range_sq, opoint, onext, otree, stack, ob_idx, ob_d):  # pragma: no cover
    """Every obstacle neighbour of an agent at (``px``, ``py``) on RVO2's obstacle tree (``otree`` from
    :func:`build_obstacles`), in RVO2's order: ``KdTree::queryObstacleTreeRecursive`` — the agent's side of each
    node's line first, then the node's edge if the agent sees it from its right side and its line is in range, then
    the far side — with ``Agent::insertObstacleNeighbor``'s insertion (sorted by squared distance, equal distances
    in visiting order). The recursion runs on ``stack`` (scratch ``(2·V + 2, 2)`` int64). Returns the count."""
    n_ob = 0
    if otree.shape[0] == 0:
        return 0
    stack[0, 0], stack[0, 1] = 0, 0
    sp = 1
    while sp > 0:
        sp -= 1
        nd, phase = stack[sp, 0], stack[sp, 1]
        o = otree[nd, 0]
        o2 = onext[o]
        ax, ay = opoint[o, 0], opoint[o, 1]
        bx, by = opoint[o2, 0], opoint[o2, 1]
        left = (ax - px) * (by - ay) - (ay - py) * (bx - ax)  # leftOf(a, b, agent)
        if phase == 0:  # the agent's side first, then come back to this node
            stack[sp, 0], stack[sp, 1] = nd, 1
            sp += 1
            child = otree[nd, 1] if left >= 0.0 else otree[nd, 2]
            if child >= 0:
                stack[sp, 0], stack[sp, 1] = child, 0
                sp += 1
            continue
        abx, aby = bx - ax, by - ay
        ab2 = abx * abx + aby * aby
        if left * left / ab2 < range_sq:
            if left < 0.0:
                dsq = _edge_dsq(o, px, py, range_sq, opoint, onext)
                if dsq < np.inf:
                    k = n_ob
                    while k != 0 and dsq < ob_d[k - 1]:
                        ob_d[k], ob_idx[k] = ob_d[k - 1], ob_idx[k - 1]
                        k -= 1
                    ob_d[k], ob_idx[k] = dsq, o
                    n_ob += 1
            child = otree[nd, 2] if left >= 0.0 else otree[nd, 1]
            if child >= 0:
                stack[sp, 0], stack[sp, 1] = child, 0
                sp += 1
    return n_ob


@nb.njit(cache=True, error_model="numpy")
def _obstacle_lines(px, py, vx, vy, r, th_obst, opoint, onext, oprev, odir, oconvex, lp, ld, ob_idx,
                    n_ob):  # pragma: no cover - numba
    """The ORCA lines of one agent's obstacle neighbours ``ob_idx[:n_ob]`` (nearest first); returns the number of
    lines written."""
    inv_th = 1.0 / th_obst
    n = 0
    radius_sq = r * r
    for k in range(n_ob):
        o1 = ob_idx[k]
        o2 = onext[o1]
        r1x, r1y = opoint[o1, 0] - px, opoint[o1, 1] - py
        r2x, r2y = opoint[o2, 0] - px, opoint[o2, 1] - py
        covered = False
        for j in range(n):
            if (_det(inv_th * r1x - lp[j, 0], inv_th * r1y - lp[j, 1], ld[j, 0], ld[j, 1]) - inv_th * r >= -RVO_EPSILON
                    and _det(inv_th * r2x - lp[j, 0], inv_th * r2y - lp[j, 1], ld[j, 0], ld[j, 1]) - inv_th * r
                    >= -RVO_EPSILON):
                covered = True
                break
        if covered:
            continue
        dsq1 = r1x * r1x + r1y * r1y
        dsq2 = r2x * r2x + r2y * r2y
        obx, oby = opoint[o2, 0] - opoint[o1, 0], opoint[o2, 1] - opoint[o1, 1]
        s = (-r1x * obx - r1y * oby) / (obx * obx + oby * oby)
        dlx, dly = -r1x - s * obx, -r1y - s * oby
        dsq_line = dlx * dlx + dly * dly
        if s < 0.0 and dsq1 <= radius_sq:
            if oconvex[o1]:
                inv = 1.0 / np.sqrt(dsq1)
                lp[n, 0], lp[n, 1], ld[n, 0], ld[n, 1] = 0.0, 0.0, -r1y * inv, r1x * inv
                n += 1
            continue
        elif s > 1.0 and dsq2 <= radius_sq:
            if oconvex[o2] and _det(r2x, r2y, odir[o2, 0], odir[o2, 1]) >= 0.0:
                inv = 1.0 / np.sqrt(dsq2)
                lp[n, 0], lp[n, 1], ld[n, 0], ld[n, 1] = 0.0, 0.0, -r2y * inv, r2x * inv
                n += 1
            continue
        elif s >= 0.0 and s < 1.0 and dsq_line <= radius_sq:
            lp[n, 0], lp[n, 1], ld[n, 0], ld[n, 1] = 0.0, 0.0, -odir[o1, 0], -odir[o1, 1]
            n += 1
            continue

        if s < 0.0 and dsq_line <= radius_sq:  # viewed obliquely: the left vertex defines the obstacle
            if not oconvex[o1]:
                continue
            o2 = o1
            llx, lly, rlx, rly = _vertex_legs(r1x, r1y, dsq1, r)
        elif s > 1.0 and dsq_line <= radius_sq:  # viewed obliquely: the right vertex defines the obstacle
            if not oconvex[o2]:
                continue
            o1 = o2
            llx, lly, rlx, rly = _vertex_legs(r2x, r2y, dsq2, r)
        else:
            if oconvex[o1]:
                llx, lly, _, _ = _vertex_legs(r1x, r1y, dsq1, r)
            else:
                llx, lly = -odir[o1, 0], -odir[o1, 1]
            if oconvex[o2]:
                _, _, rlx, rly = _vertex_legs(r2x, r2y, dsq2, r)
            else:
                rlx, rly = odir[o1, 0], odir[o1, 1]

        left_nb = oprev[o1]
        left_foreign = False
        right_foreign = False
        if oconvex[o1] and _det(llx, lly, -odir[left_nb, 0], -odir[left_nb, 1]) >= 0.0:
            llx, lly = -odir[left_nb, 0], -odir[left_nb, 1]
            left_foreign = True
        if oconvex[o2] and _det(rlx, rly, odir[o2, 0], odir[o2, 1]) <= 0.0:
            rlx, rly = odir[o2, 0], odir[o2, 1]
            right_foreign = True

        lcx, lcy = inv_th * (opoint[o1, 0] - px), inv_th * (opoint[o1, 1] - py)
        rcx, rcy = inv_th * (opoint[o2, 0] - px), inv_th * (opoint[o2, 1] - py)
        cvx, cvy = rcx - lcx, rcy - lcy
        same = o1 == o2
        t = 0.5 if same else ((vx - lcx) * cvx + (vy - lcy) * cvy) / (cvx * cvx + cvy * cvy)
        t_left = (vx - lcx) * llx + (vy - lcy) * lly
        t_right = (vx - rcx) * rlx + (vy - rcy) * rly

        if (t < 0.0 and t_left < 0.0) or (same and t_left < 0.0 and t_right < 0.0):
            _cutoff_circle_line(vx, vy, lcx, lcy, r * inv_th, lp, ld, n)  # project on left cut-off circle
            n += 1
            continue
        elif t > 1.0 and t_right < 0.0:
            _cutoff_circle_line(vx, vy, rcx, rcy, r * inv_th, lp, ld, n)  # project on right cut-off circle
            n += 1
            continue

        inf = np.inf
        dsq_cut = inf if (t < 0.0 or t > 1.0 or same) else (vx - (lcx + t * cvx)) ** 2 + (vy - (lcy + t * cvy)) ** 2
        dsq_left = inf if t_left < 0.0 else (vx - (lcx + t_left * llx)) ** 2 + (vy - (lcy + t_left * lly)) ** 2
        dsq_right = inf if t_right < 0.0 else (vx - (rcx + t_right * rlx)) ** 2 + (vy - (rcy + t_right * rly)) ** 2
        if dsq_cut <= dsq_left and dsq_cut <= dsq_right:
            dx, dy = -odir[o1, 0], -odir[o1, 1]
            ld[n, 0], ld[n, 1] = dx, dy
            lp[n, 0], lp[n, 1] = lcx + r * inv_th * (-dy), lcy + r * inv_th * dx
            n += 1
        elif dsq_left <= dsq_right:
            if left_foreign:
                continue
            ld[n, 0], ld[n, 1] = llx, lly
            lp[n, 0], lp[n, 1] = lcx + r * inv_th * (-lly), lcy + r * inv_th * llx
            n += 1
        else:
            if right_foreign:
                continue
            dx, dy = -rlx, -rly
            ld[n, 0], ld[n, 1] = dx, dy
            lp[n, 0], lp[n, 1] = rcx + r * inv_th * (-dy), rcy + r * inv_th * dx
            n += 1
    return n


@nb.njit(cache=True, inline="always", error_model="numpy")
def _gather(i, skip, px, py, bound, sx, sy, sidx, t0, t1, cand_d, cand_idx, m):  # pragma: no cover - numba
    """Append the sorted agents ``t0 ≤ t < t1`` with squared distance ``< bound`` (not ``i``, not ``skip``) to the
    candidates, without branches; returns the new count (``cand_*`` need one spare slot)."""
    for t in range(t0, t1):
        dsq = (px - sx[t]) ** 2 + (py - sy[t]) ** 2
        j = sidx[t]
        cand_d[m], cand_idx[m] = dsq, j
        m += (dsq < bound) & (j != i) & (j != skip)
    return m


@nb.njit(cache=True, inline="always", error_model="numpy")
def _scan(i, skip, px, py, range_sq, k_max, sx, sy, sidx, t0, t1, nb_d, nb_idx, cnt, bound):  # pragma: no cover
    """Sorted agents ``t0 ≤ t < t1`` into the nearest list (``bound``: the k-th distance once full, else the range);
    returns the new (count, bound)."""
    for t in range(t0, t1):
        dsq = (px - sx[t]) ** 2 + (py - sy[t]) ** 2
        if dsq <= bound:
            j = sidx[t]
            if j != i and j != skip and dsq < range_sq:  # noqa: SIM109 (numba-friendly)
                cnt = _insert_nearest(nb_d, nb_idx, cnt, k_max, dsq, j)
                if cnt == k_max:
                    bound = nb_d[cnt - 1]
    return cnt, bound


@nb.njit(cache=True, inline="always", error_model="numpy")
def _grid_nearest(i, skip, px, py, range_sq, k_max, cell_start, sx, sy, sidx, geo, cand_d, cand_idx, rank, nb_d,
                  nb_idx, near_d, near_idx):  # pragma: no cover - numba
    """The ``k_max`` nearest active agents (not ``i``, not ``skip``) strictly within ``range_sq`` of point
    (``px``, ``py``) on :func:`_build_grid`'s cells — exactly the set and order of the brute-force search (distance,
    then index), whatever order the candidates come in. Returns their count.

    1. Squares of cells around the point, 3 × 3 then growing ring by ring until they hold ``k_max`` candidates in
       range (or cover the range): gathered without branches, then ranked (:func:`_select`); the k-th distance is
       the new bound.
    2. Each row of cells that the disc of that bound reaches, over the columns that the disc spans at the row's
       nearest edge, outside the square — one contiguous run each —, candidates inserted as they come (few: the
       bound rejects most), the bound shrinking.
    """
    minx, miny, c = geo[0], geo[1], geo[2]
    nx, ny = int(geo[3]), int(geo[4])
    eps, inv_c = geo[5], geo[6]  # (any cell (cx, cy) would give the same result: the bounds are geometric)
    cx = min(max(int((px - minx) * inv_c), 0), nx - 1)
    cy = min(max(int((py - miny) * inv_c), 0), ny - 1)
    x0, x1 = max(cx - 1, 0), min(cx + 1, nx - 1)
    y0, y1 = max(cy - 1, 0), min(cy + 1, ny - 1)
    m = 0
    for gy in range(y0, y1 + 1):
        row = gy * nx
        m = _gather(i, skip, px, py, range_sq, sx, sy, sidx, cell_start[row + x0], cell_start[row + x1 + 1], cand_d,
                    cand_idx, m)
    r = 1
    while m < k_max:
        # unvisited agents lie outside the square: at least as far as its nearest side with cells beyond
        lower = np.inf
        if cx - r > 0:
            lower = min(lower, px - (minx + (cx - r) * c))
        if cx + r < nx - 1:
            lower = min(lower, minx + (cx + r + 1) * c - px)
        if cy - r > 0:
            lower = min(lower, py - (miny + (cy - r) * c))
        if cy + r < ny - 1:
            lower = min(lower, miny + (cy + r + 1) * c - py)
        lower = max(lower - eps, 0.0)
        if lower * lower >= range_sq:
            return _select(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank)
        r += 1
        nx0, nx1 = max(cx - r, 0), min(cx + r, nx - 1)
        ny0, ny1 = max(cy - r, 0), min(cy + r, ny - 1)
        for gy in range(ny0, ny1 + 1):
            row = gy * nx
            if y0 <= gy <= y1:
                m = _gather(i, skip, px, py, range_sq, sx, sy, sidx, cell_start[row + nx0], cell_start[row + x0],
                            cand_d, cand_idx, m)
                m = _gather(i, skip, px, py, range_sq, sx, sy, sidx, cell_start[row + x1 + 1],
                            cell_start[row + nx1 + 1], cand_d, cand_idx, m)
            else:
                m = _gather(i, skip, px, py, range_sq, sx, sy, sidx, cell_start[row + nx0], cell_start[row + nx1 + 1],
                            cand_d, cand_idx, m)
        x0, x1, y0, y1 = nx0, nx1, ny0, ny1
    # agents outside the square are at least `lower` away (its nearest side with cells beyond)
    lower = np.inf
    if x0 > 0:
        lower = min(lower, px - (minx + x0 * c))
    if x1 < nx - 1:
        lower = min(lower, minx + (x1 + 1) * c - px)
    if y0 > 0:
        lower = min(lower, py - (miny + y0 * c))
    if y1 < ny - 1:
        lower = min(lower, miny + (y1 + 1) * c - py)
    lower = max(lower - eps, 0.0)
    inner = lower * lower
    if inner >= range_sq:  # the whole range lies in the square
        return _select(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank)
    q = 0  # the candidates inside the square's inscribed disc: if k_max of them, the nearest are theirs (fewer to rank)
    for p in range(m):
        near_d[q], near_idx[q] = cand_d[p], cand_idx[p]
        q += cand_d[p] < inner
    if q >= k_max:
        return _select(near_d, near_idx, q, k_max, nb_d, nb_idx, rank)
    cnt = _select(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank)
    bound = nb_d[cnt - 1]  # beyond `lower`: rows of cells outside the square that the disc of sqrt(bound) reaches
    # every agent beyond the disc is out; rows and columns widened by the rounding slack
    reach = np.sqrt(bound) + eps
    r0 = min(max(int(np.floor((py - reach - miny) * inv_c)), 0), ny - 1)
    r1 = min(max(int(np.floor((py + reach - miny) * inv_c)), 0), ny - 1)
    for gy in range(r0, r1 + 1):
        if gy < cy:
            gap = py - (miny + (gy + 1) * c) - eps
        elif gy > cy:
            gap = (miny + gy * c) - py - eps
        else:
            gap = 0.0
        gap = max(gap, 0.0)
        if gap * gap > bound:
            continue
        half = np.sqrt(bound - gap * gap) + eps
        g0 = min(max(int(np.floor((px - half - minx) * inv_c)), 0), nx - 1)
        g1 = min(max(int(np.floor((px + half - minx) * inv_c)), 0), nx - 1)
        row = gy * nx
        if y0 <= gy <= y1:  # the square is done: left and right of it
            if g0 < x0:
                cnt, bound = _scan(i, skip, px, py, range_sq, k_max, sx, sy, sidx, cell_start[row + g0],
                                   cell_start[row + x0], nb_d, nb_idx, cnt, bound)
            if g1 > x1:
                cnt, bound = _scan(i, skip, px, py, range_sq, k_max, sx, sy, sidx, cell_start[row + x1 + 1],
                                   cell_start[row + g1 + 1], nb_d, nb_idx, cnt, bound)
        else:
            cnt, bound = _scan(i, skip, px, py, range_sq, k_max, sx, sy, sidx, cell_start[row + g0],
                               cell_start[row + g1 + 1], nb_d, nb_idx, cnt, bound)
    return cnt


@nb.njit(cache=True, inline="always", error_model="numpy")
def _brute_nearest(b, i, skip, px, py, range_sq, k_max, pos, active, cand_d, cand_idx, nb_d, nb_idx,
                   rank):  # pragma: no cover - numba
    """The ``k_max`` nearest active agents of world ``b`` (not ``i``, not ``skip``) strictly within ``range_sq`` of
    (``px``, ``py``) by brute force, into ``nb_d``/``nb_idx`` sorted (distance, then index); returns their count."""
    m = 0
    for j in range(pos.shape[1]):
        if j == i or j == skip or not active[b, j]:  # noqa: SIM109 (numba-friendly)
            continue
        dsq = (px - pos[b, j, 0]) ** 2 + (py - pos[b, j, 1]) ** 2
        if dsq < range_sq:
            cand_d[m], cand_idx[m] = dsq, j
            m += 1
    return _select(cand_d, cand_idx, m, k_max, nb_d, nb_idx, rank)


GRID_MIN = 32
"""Worlds with more active agents than this find neighbours on a grid (:func:`_grid_nearest`), smaller ones by
brute force; both give the same neighbours in the same order. The break-even against Python-RVO2 (alternated, one
core): at N = 50 the grid gives 0.99–1.15× RVO2 in one world against 0.90–0.91× by brute force, at N = 20 brute
force is ahead (1.06–1.10× against 0.90–0.93× with a threshold of 16)."""

GRID_PER_CELL = 4.0
"""Agents per grid cell on average (the cell size; any gives the same neighbours). Against Python-RVO2
(alternated, one core), 4 beat 2, 3, 6 and 8 on the lattice crowd (1 world, N = 200: 1.69–1.76× RVO2 against
1.52–1.55× with 2) and at N = 50, and tied on the ring at N = 200 and 1,000."""
GRID_MAX_CELL = 0.5
"""Largest grid cell, as a fraction of the largest neighbour distance."""


@nb.njit(cache=True, inline="always", error_model="numpy")
def _search_scratch(A, V, otree):  # pragma: no cover - numba
    """The neighbour searches' work arrays for ``A`` agents and ``V`` obstacle vertices: candidate, near and result
    distances/indices of the agent search (+ 8: the spare slot of ``_gather`` and the padding of ``_select``; + 1: the
    discard slot of ``_select``), the obstacle result, the rank buffer, the obstacle-tree stack and the grid's."""
    cell_start, cell_of, sx, sy, sidx, geo = _grid_scratch(A)
    return (np.empty(A + 8), np.empty(A + 8, np.int64), np.empty(A + 8), np.empty(A + 8, np.int64), np.empty(A + 1),
            np.empty(A + 1, np.int64), np.empty(V + 1), np.empty(V + 1, np.int64), np.empty(RANK_MAX, np.int64),
            np.empty((2 * otree.shape[0] + 2, 2), np.int64), cell_start, cell_of, sx, sy, sidx, geo)


@nb.njit(cache=True, inline="always", error_model="numpy")
def _world_grid(pos, active, neighbor_dist, b, grid_min, cell_start, cell_of, sx, sy, sidx, geo):  # pragma: no cover
    """Whether world ``b`` finds agent neighbours on a grid of cells (more than ``grid_min`` active agents); if so,
    builds it (cells sized by the world's largest neighbour distance)."""
    A = pos.shape[1]
    if not (grid_min < A and _count_members(active, b, 0) > grid_min):
        return False
    reach = 0.0
    for j in range(A):
        reach = max(reach, neighbor_dist[b, j])
    _build_grid(pos, active, b, reach * GRID_MAX_CELL, GRID_PER_CELL, cell_start, cell_of, sx, sy, sidx, geo)
    return True


@nb.njit(cache=True, inline="always", error_model="numpy")
def _find_obstacles(use_tree, px, py, range_sq, opoint, onext, otree, ostack, ob_idx, ob_d):  # pragma: no cover
    """Obstacle edges within ``range_sq`` of (``px``, ``py``) into ``ob_idx``/``ob_d`` in RVO2's order: on the tree
    when ``use_tree`` (more than :data:`OBST_TREE_MIN` vertices), else by the scan. Returns their count."""
    if use_tree:
        return _tree_obstacle_neighbors(px, py, range_sq, opoint, onext, otree, ostack, ob_idx, ob_d)
    return _obstacle_neighbors(px, py, range_sq, opoint, onext, otree, ob_idx, ob_d)



@nb.njit(cache=True, error_model="numpy")
def orca_batch(pos, vel, pref, radius, max_speed, neighbor_dist, max_neighbors, time_horizon, time_horizon_obst,
               active, controlled, ignore, opoint, onext, oprev, odir, oconvex, otree, dt, out, grid_min=GRID_MIN):
    """New ORCA velocities for every controlled agent of every world.

    Args (``B`` worlds, ``A`` agents, ``V`` obstacle vertices; floats in m, s, m/s):
        pos, vel, pref: ``(B, A, 2)`` positions, current velocities, preferred velocities.
        radius, max_speed, neighbor_dist, time_horizon, time_horizon_obst: ``(B, A)`` per-agent parameters.
        max_neighbors: ``(B, A)`` int.
        active: ``(B, A)`` bool; inactive agents are nobody's neighbour and are not computed.
        controlled: ``(B, A)`` bool; uncontrolled agents (e.g. the robot) are neighbours only; ``out`` = ``vel``.
        ignore: ``(B, A)`` int; agent ``i`` never takes agent ``ignore[b, i]`` as a neighbour (-1: none).
        opoint, onext, oprev, odir, oconvex, otree: obstacles and their tree from :func:`build_obstacles` (shared
            by all worlds).
        dt: time step [s] (used for the collision cut-off when agents already overlap).
        out: ``(B, A, 2)`` output velocities.
        grid_min: a world with more active agents finds neighbours on a grid of cells (:func:`_grid_nearest`,
            near-linear in the crowd), else by brute force — the same neighbours in the same order either way.
    """
    B, A = pos.shape[0], pos.shape[1]
    V = opoint.shape[0]
    L = V + A + 1
    lp = np.empty((L, 2))
    ld = np.empty((L, 2))
    pp = np.empty((L, 2))
    pd = np.empty((L, 2))
    res = np.empty(2)
    inv_dt = 1.0 / dt
    (cand_d, cand_idx, near_d, near_idx, nb_d, nb_idx, ob_d, ob_idx, rank, ostack, cell_start, cell_of, sx, sy, sidx,
     geo) = _search_scratch(A, V, otree)
    use_tree = V > OBST_TREE_MIN
    for b in range(B):
        for j in range(A):
            if active[b, j] and not (np.isfinite(pos[b, j, 0]) and np.isfinite(pos[b, j, 1])):
                raise ValueError("orca_batch: pos holds a non-finite position (NaN or inf) of an active agent; "
                                 "valid choices: finite positions [m]")
        use_grid = _world_grid(pos, active, neighbor_dist, b, grid_min, cell_start, cell_of, sx, sy, sidx, geo)
        for i in range(A):
            if not (active[b, i] and controlled[b, i]):
                out[b, i, 0], out[b, i, 1] = vel[b, i, 0], vel[b, i, 1]
                continue
            px, py = pos[b, i, 0], pos[b, i, 1]
            vx, vy = vel[b, i, 0], vel[b, i, 1]
            r = radius[b, i]
            ms = max_speed[b, i]
            n = 0
            if V > 0:
                th_obst = time_horizon_obst[b, i]
                ob_range_sq = (th_obst * ms + r) ** 2
                n_ob = _find_obstacles(use_tree, px, py, ob_range_sq, opoint, onext, otree, ostack, ob_idx, ob_d)
                n = _obstacle_lines(px, py, vx, vy, r, th_obst, opoint, onext, oprev, odir, oconvex, lp, ld, ob_idx,
                                    n_ob)
            n_obst = n
            # agent neighbours: nearest max_neighbors strictly within neighbor_dist, sorted, stable on ties
            k_max = max_neighbors[b, i]
            range_sq = neighbor_dist[b, i] ** 2
            cnt = 0
            skip = ignore[b, i]
            # spelled out (as in orca_neighbors): behind one more inlined helper this loop measured 5–10 % slower
            # (benchmarks/ab_orca.py)
            if k_max > 0 and use_grid:
                cnt = _grid_nearest(i, skip, px, py, range_sq, k_max, cell_start, sx, sy, sidx, geo, cand_d, cand_idx,
                                    rank, nb_d, nb_idx, near_d, near_idx)
            elif k_max > 0:
                cnt = _brute_nearest(b, i, skip, px, py, range_sq, k_max, pos, active, cand_d, cand_idx, nb_d, nb_idx,
                                     rank)
            inv_th = 1.0 / time_horizon[b, i]
            for k in range(cnt):
                j = nb_idx[k]
                rpx, rpy = pos[b, j, 0] - px, pos[b, j, 1] - py
                rvx, rvy = vx - vel[b, j, 0], vy - vel[b, j, 1]
                dsq = rpx * rpx + rpy * rpy
                cr = r + radius[b, j]
                cr_sq = cr * cr
                if dsq > cr_sq:
                    wx, wy = rvx - inv_th * rpx, rvy - inv_th * rpy
                    w_len_sq = wx * wx + wy * wy
                    dot1 = wx * rpx + wy * rpy
                    if dot1 < 0.0 and dot1 * dot1 > cr_sq * w_len_sq:
                        w_len = np.sqrt(w_len_sq)
                        uwx, uwy = wx / w_len, wy / w_len
                        dx, dy = uwy, -uwx
                        ux, uy = (cr * inv_th - w_len) * uwx, (cr * inv_th - w_len) * uwy
                    else:
                        leg = np.sqrt(dsq - cr_sq)
                        if _det(rpx, rpy, wx, wy) > 0.0:
                            dx, dy = (rpx * leg - rpy * cr) / dsq, (rpx * cr + rpy * leg) / dsq
                        else:
                            dx, dy = -(rpx * leg + rpy * cr) / dsq, -(-rpx * cr + rpy * leg) / dsq
                        dot2 = rvx * dx + rvy * dy
                        ux, uy = dot2 * dx - rvx, dot2 * dy - rvy
                else:
                    wx, wy = rvx - inv_dt * rpx, rvy - inv_dt * rpy
                    w_len = np.sqrt(wx * wx + wy * wy)
                    uwx, uwy = wx / w_len, wy / w_len
                    dx, dy = uwy, -uwx
                    ux, uy = (cr * inv_dt - w_len) * uwx, (cr * inv_dt - w_len) * uwy
                lp[n, 0], lp[n, 1] = vx + 0.5 * ux, vy + 0.5 * uy
                ld[n, 0], ld[n, 1] = dx, dy
                n += 1
            fail = _lp2(lp, ld, n, ms, pref[b, i, 0], pref[b, i, 1], False, res)
            if fail < n:
                _lp3(lp, ld, n, n_obst, fail, ms, res, pp, pd)
            out[b, i, 0], out[b, i, 1] = res[0], res[1]


@nb.njit(cache=True, error_model="numpy")
def orca_neighbors(pos, radius, max_speed, neighbor_dist, max_neighbors, time_horizon_obst, active, ignore, opoint,
                   onext, otree, agent_nb, agent_cnt, obst_nb, obst_cnt, grid_min=GRID_MIN):  # pragma: no cover
    """Each active agent's neighbours as :func:`orca_batch` finds them (the same searches, the same order: RVO2's
    ``agentNeighbors_`` and ``obstacleNeighbors_``), for inspection and tests; same arguments as ``orca_batch``.

    Out: ``agent_nb`` ``(B, A, K)`` int64 (K ≥ the largest ``max_neighbors``) and ``agent_cnt`` ``(B, A)`` — agent
    indices, nearest first; ``obst_nb`` ``(B, A, V)`` and ``obst_cnt`` — obstacle edges (their first vertex's
    number), nearest first. Inactive agents get counts 0."""
    B, A = pos.shape[0], pos.shape[1]
    V = opoint.shape[0]
    (cand_d, cand_idx, near_d, near_idx, nb_d, nb_idx, ob_d, ob_idx, rank, ostack, cell_start, cell_of, sx, sy, sidx,
     geo) = _search_scratch(A, V, otree)
    use_tree = V > OBST_TREE_MIN
    for b in range(B):
        use_grid = _world_grid(pos, active, neighbor_dist, b, grid_min, cell_start, cell_of, sx, sy, sidx, geo)
        for i in range(A):
            agent_cnt[b, i] = obst_cnt[b, i] = 0
            if not active[b, i]:
                continue
            px, py = pos[b, i, 0], pos[b, i, 1]
            if V > 0:
                ob_range_sq = (time_horizon_obst[b, i] * max_speed[b, i] + radius[b, i]) ** 2
                n_ob = _find_obstacles(use_tree, px, py, ob_range_sq, opoint, onext, otree, ostack, ob_idx, ob_d)
                obst_cnt[b, i] = n_ob
                obst_nb[b, i, :n_ob] = ob_idx[:n_ob]
            k_max = max_neighbors[b, i]
            range_sq = neighbor_dist[b, i] ** 2
            cnt = 0
            skip = ignore[b, i]
            if k_max > 0 and use_grid:  # as orca_batch (spelled out there: see its comment)
                cnt = _grid_nearest(i, skip, px, py, range_sq, k_max, cell_start, sx, sy, sidx, geo, cand_d, cand_idx,
                                    rank, nb_d, nb_idx, near_d, near_idx)
            elif k_max > 0:
                cnt = _brute_nearest(b, i, skip, px, py, range_sq, k_max, pos, active, cand_d, cand_idx, nb_d, nb_idx,
                                     rank)
            agent_cnt[b, i] = cnt
            agent_nb[b, i, :cnt] = nb_idx[:cnt]


@nb.njit(cache=True, error_model="numpy")
def orca_advance(vec, flt, ints, flags, opoint, onext, oprev, odir, oconvex, otree, dt):  # pragma: no cover - numba
    """One ORCA simulation step in place, RVO2's ``doStep``: new velocities (:func:`orca_batch`), then every active
    agent's position advanced by its new velocity times ``dt`` [s]. Agent arrays in blocks (one argument each
    instead of twelve, so a call on one small world costs little more than its arithmetic): ``vec`` ``(4, B, A, 2)`` —
    positions [m] and velocities [m/s] (both updated), preferred velocities [m/s], scratch —, ``flt`` ``(5, B, A)``
    — radii [m], max speeds [m/s], neighbour distances [m], time horizons for agents and for obstacles [s] —,
    ``ints`` ``(2, B, A)`` — neighbour caps, ignored slot (-1: none) —, ``flags`` ``(2, B, A)`` bool — active,
    controlled; obstacles from :func:`build_obstacles`."""
    pos, vel, out = vec[0], vec[1], vec[3]
    orca_batch(pos, vel, vec[2], flt[0], flt[1], flt[2], ints[0], flt[3], flt[4], flags[0], flags[1], ints[1], opoint,
               onext, oprev, odir, oconvex, otree, dt, out)
    active = flags[0]
    B, A = pos.shape[0], pos.shape[1]
    for b in range(B):
        for i in range(A):
            vx, vy = out[b, i, 0], out[b, i, 1]
            vel[b, i, 0], vel[b, i, 1] = vx, vy
            if active[b, i]:
                pos[b, i, 0] += vx * dt
                pos[b, i, 1] += vy * dt


@nb.njit(cache=True, error_model="numpy")
def orca_inputs(robot_pos, robot_vel, robot_radius, positions, velocities, goals, radii, v_pref, active,
                ignore_robot, pad, dt, pref_speed, pos, vel, pref, rad, vmax, act, ignore):  # pragma: no cover - numba
    """Fill :func:`orca_batch`'s agent arrays ``[robot, pedestrians...]`` from a crowd state, in place.

    Args (``B`` worlds of ``H`` pedestrians):
        robot_pos, robot_vel: ``(B, 2)``. robot_radius: ``(B,)``. positions, velocities, goals: ``(B, H, 2)``.
        radii, v_pref: ``(B, H)``. active, ignore_robot: ``(B, H)`` bool. pad: added to every radius [m].
        dt: [s]. pref_speed: > 0: the preferred velocity is the goal vector cut to this length [m/s] (CrowdNav++'s
            ``crowd_nav/policy/orca.py:98-100``: a unit vector, the raw goal vector within 1 m), the speed limit
            ``v_pref``; ≤ 0: ``v_pref`` toward the goal, a goal closer than ``v_pref·dt`` reached in one step (as
            ``humans.preferred_velocity``).
        pos, vel, pref: Out ``(B, 1 + H, 2)``. rad, vmax: Out ``(B, 1 + H)``. act: Out bool. ignore: Out int
            (0 = leave the robot out, -1 = nobody). Row 0 (the robot) gets position, velocity, radius, activity.

    """
    B, H = radii.shape
    inv_dt = 1.0 / dt
    for b in range(B):
        pos[b, 0, 0], pos[b, 0, 1] = robot_pos[b, 0], robot_pos[b, 1]
        vel[b, 0, 0], vel[b, 0, 1] = robot_vel[b, 0], robot_vel[b, 1]
        rad[b, 0], act[b, 0], ignore[b, 0] = robot_radius[b] + pad, True, -1
        for h in range(H):
            px, py = positions[b, h, 0], positions[b, h, 1]
            pos[b, h + 1, 0], pos[b, h + 1, 1] = px, py
            vel[b, h + 1, 0], vel[b, h + 1, 1] = velocities[b, h, 0], velocities[b, h, 1]
            dx, dy = goals[b, h, 0] - px, goals[b, h, 1] - py
            dist = np.sqrt(dx * dx + dy * dy)
            vp = v_pref[b, h]
            if pref_speed > 0:
                scale = pref_speed / dist if dist > pref_speed else 1.0
            else:
                scale = inv_dt if dist < vp * dt else vp / max(dist, 1e-12)
            pref[b, h + 1, 0], pref[b, h + 1, 1] = dx * scale, dy * scale
            rad[b, h + 1], vmax[b, h + 1], act[b, h + 1] = radii[b, h] + pad, vp, active[b, h]
            ignore[b, h + 1] = 0 if ignore_robot[b, h] else -1


@nb.njit(cache=True, error_model="numpy")
def orca_step(robot_pos, robot_vel, robot_radius, positions, velocities, goals, radii, v_pref, active, ignore_robot,
              pad, dt, pref_speed, vec, flt, ints, flags, opoint, onext, oprev, odir, oconvex,
              otree):  # pragma: no cover - numba
    """:func:`orca_inputs` then :func:`orca_batch` in one compiled call (the pedestrian model's step), on agent
    arrays packed in blocks (one argument each instead of thirteen): ``vec`` ``(4, B, A, 2)`` — positions,
    velocities, preferred velocities, out: new velocities —, ``flt`` ``(5, B, A)`` — radii, max speeds (both
    filled here), neighbour distances, time horizons for agents and for obstacles —, ``ints`` ``(2, B, A)`` —
    neighbour caps, ignored slot (filled here) —, ``flags`` ``(2, B, A)`` bool — active (filled here), controlled."""
    pos, vel, pref, out = vec[0], vec[1], vec[2], vec[3]
    rad, vmax, act, ignore = flt[0], flt[1], flags[0], ints[1]
    orca_inputs(robot_pos, robot_vel, robot_radius, positions, velocities, goals, radii, v_pref, active, ignore_robot,
                pad, dt, pref_speed, pos, vel, pref, rad, vmax, act, ignore)
    orca_batch(pos, vel, pref, rad, vmax, flt[2], ints[0], flt[3], flt[4], act, flags[1], ignore, opoint, onext,
               oprev, odir, oconvex, otree, dt, out)
