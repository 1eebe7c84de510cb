"""ORCA: reference RVO2 trajectories, behaviour (swaps, deadlock, obstacles), the Python-RVO2 facade."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from crowdbench.config import WorldConfig
from crowdbench.humans.orca import PyRVOSimulator
from crowdbench.worlds import CrowdWorld


def pref_velocity(pos, goal, max_speed, dt):
    d = np.asarray(goal) - np.asarray(pos)
    dist = np.hypot(*d)
    return d / dt if dist < max_speed * dt else d / dist * max_speed


def run_reference(ref, use_stored_pref=False):
    p = ref["params"]
    sim = PyRVOSimulator(p["timeStep"], p["neighborDist"], p["maxNeighbors"], p["timeHorizon"], p["timeHorizonObst"],
                         p["radius"], p["maxSpeed"])
    for s in ref["starts"]:
        sim.addAgent(tuple(s))
    pos, vel = [np.array(ref["starts"], float)], [np.zeros((len(ref["starts"]), 2))]
    for k in range(ref["num_steps"]):
        for i, g in enumerate(ref["goals"]):
            pv = ref["pref_velocities"][k][i] if use_stored_pref else pref_velocity(sim.getAgentPosition(i), g,
                                                                                   p["maxSpeed"], p["timeStep"])
            sim.setAgentPrefVelocity(i, tuple(pv))
        sim.doStep()
        pos.append(np.array([sim.getAgentPosition(i) for i in range(sim.getNumAgents())]))
        vel.append(np.array([sim.getAgentVelocity(i) for i in range(sim.getNumAgents())]))
    return np.array(pos), np.array(vel)


@pytest.mark.parametrize("scenario", ["headon2", "circle8"])
def test_matches_rvo2_float64_within_1e6(orca_reference, scenario):
    ref = orca_reference[scenario]
    pos, vel = run_reference(ref)
    np.testing.assert_allclose(pos, np.array(ref["float64_variant"]["positions"]), atol=1e-6, rtol=0)
    np.testing.assert_allclose(vel, np.array(ref["float64_variant"]["velocities"]), atol=1e-6, rtol=0)


@pytest.mark.parametrize("scenario", ["headon2", "circle8"])
def test_matches_rvo2_float32_within_1e4(orca_reference, scenario):
    ref = orca_reference[scenario]
    pos, _ = run_reference(ref, use_stored_pref=True)
    np.testing.assert_allclose(pos, np.array(ref["positions"]), atol=1e-4, rtol=0)


def test_circle8_deadlock_is_reproduced(orca_reference):
    ref = orca_reference["circle8"]
    pos, vel = run_reference(ref)
    final = pos[-1]
    assert np.allclose(np.linalg.norm(final, axis=1), 0.84, atol=0.05)  # stalled on a ring of radius ~0.84 m
    assert np.linalg.norm(vel[-1], axis=1).max() < 0.02  # speed -> 0 (preferred speed is 1 m/s)
    assert np.linalg.norm(pos[-1] - pos[-21], axis=1).max() < 0.1  # nobody got anywhere in the last 5 s
    assert np.allclose(np.linalg.norm(final - np.array(ref["goals"]), axis=1), ref["final_distance_to_goal"], atol=1e-4)


def _min_pair_gap(pos, radius):
    d = np.linalg.norm(pos[:, :, None] - pos[:, None], axis=-1) + np.eye(pos.shape[1]) * 1e9
    return d.min() - 2 * radius


def test_head_on_swap_no_overlap_both_arrive():
    sim = PyRVOSimulator(0.25, 10, 10, 5, 5, 0.3, 1.0)
    starts, goals = [(-4, 0), (4, 0.01)], [(4, 0), (-4, 0.01)]
    for s in starts:
        sim.addAgent(s)
    traj = []
    for _ in range(60):
        for i, g in enumerate(goals):
            sim.setAgentPrefVelocity(i, tuple(pref_velocity(sim.getAgentPosition(i), g, 1.0, 0.25)))
        sim.doStep()
        traj.append([sim.getAgentPosition(i) for i in range(2)])
    traj = np.array(traj)
    assert _min_pair_gap(traj, 0.3) > 0.005  # the reference sidesteps with 0.609 m between centres
    np.testing.assert_allclose(traj[-1], goals, atol=1e-9)


@pytest.mark.parametrize("seed", range(10))
def test_perturbed_circle_swap_no_overlap_all_arrive(seed):
    """6 agents on a radius-4 circle, angles jittered by ±0.2 rad to break the symmetry that deadlocks circle-8:
    ORCA resolves every one of these swaps; discs may touch (gap ~1e-10) but never overlap."""
    n, R = 6, 4.0
    rng = np.random.default_rng(seed)
    ang = 2 * np.pi * np.arange(n) / n + rng.uniform(-0.2, 0.2, n)
    starts = R * np.stack([np.cos(ang), np.sin(ang)], 1)
    goals = -starts
    sim = PyRVOSimulator(0.25, 10, 10, 5, 5, 0.3, 1.0)
    for s in starts:
        sim.addAgent(tuple(s))
    traj = []
    for _ in range(240):
        for i in range(n):
            sim.setAgentPrefVelocity(i, tuple(pref_velocity(sim.getAgentPosition(i), goals[i], 1.0, 0.25)))
        sim.doStep()
        traj.append([sim.getAgentPosition(i) for i in range(n)])
    traj = np.array(traj)
    assert _min_pair_gap(traj, 0.3) > -1e-9
    np.testing.assert_allclose(traj[-1], goals, atol=1e-6)


@pytest.mark.parametrize(("goal", "arrives"), [((2.0, 3.0), True), ((0.2, 3.0), False)])
def test_obstacle_is_never_entered(goal, arrives):
    """A box between start and goal. Seen obliquely the agent slides round its corner and arrives; head-on it stops
    in front of it — RVO2 is a local method with no global planner (its examples add a roadmap). Either way it keeps
    its radius from the box."""
    sim = PyRVOSimulator(0.25, 10, 10, 5, 5, 0.3, 1.0)
    sim.addAgent((0.0, -3.0))
    sim.addObstacle([(-1.5, -0.1), (1.5, -0.1), (1.5, 0.1), (-1.5, 0.1)])  # counter-clockwise box
    sim.processObstacles()
    assert sim.getNumObstacleVertices() == 4
    closest = np.inf
    for _ in range(120):
        sim.setAgentPrefVelocity(0, tuple(pref_velocity(sim.getAgentPosition(0), goal, 1.0, 0.25)))
        sim.doStep()
        x, y = sim.getAgentPosition(0)
        closest = min(closest, np.hypot(max(abs(x) - 1.5, 0.0), max(abs(y) - 0.1, 0.0)))
    assert closest >= 0.3 - 1e-9
    at_goal = np.hypot(*(np.subtract(sim.getAgentPosition(0), goal))) < 1e-6
    assert at_goal == arrives


def test_facade_api_shape():
    sim = PyRVOSimulator(0.1, 5, 4, 2, 2, 0.4, 2.0)
    a = sim.addAgent((1, 2))
    b = sim.addAgent((3, 4), 5, 4, 2, 2, 0.5, 1.5, (0.1, 0.0))
    assert (a, b, sim.getNumAgents()) == (0, 1, 2)
    assert sim.getAgentRadius(1) == 0.5 and sim.getAgentMaxSpeed(1) == 1.5
    assert sim.getAgentVelocity(1) == (0.1, 0.0)
    sim.setAgentPosition(0, (0, 0))
    sim.setAgentVelocity(0, (0.5, 0))
    sim.doStep()
    assert sim.getGlobalTime() == pytest.approx(0.1)
    with pytest.raises(IndexError, match="agent_no=5"):
        sim.getAgentPosition(5)


def test_facade_agents_added_between_steps_and_queries_are_all_there():
    """Agents added one by one — between steps, setters, getters and neighbour queries — each get their own number
    and parameters, and the simulation equals one built with all of them first, bit for bit."""
    rng = np.random.default_rng(5)
    pts = rng.uniform(-3.0, 3.0, (12, 2))

    def add(sim, k):
        return sim.addAgent((float(pts[k, 0]), float(pts[k, 1])), 4.0 + k % 3, 3 + k % 4, 2.0, 2.0, 0.2 + 0.01 * k,
                            1.0 + 0.05 * k, (0.1 * (k % 2), 0.0))

    def prefs(sim):
        for i in range(sim.getNumAgents()):
            sim.setAgentPrefVelocity(i, (float(-pts[i, 0]), float(-pts[i, 1])))

    late = PyRVOSimulator(0.25, 5.0, 5, 2.0, 2.0, 0.3, 1.0)
    assert [add(late, k) for k in range(5)] == list(range(5))
    prefs(late)
    late.doStep()
    assert late.getAgentNumAgentNeighbors(0) >= 1
    moved = [late.getAgentPosition(i) for i in range(5)], [late.getAgentVelocity(i) for i in range(5)]
    assert [add(late, k) for k in range(5, 12)] == list(range(5, 12))
    assert late.getNumAgents() == 12 and late.getAgentRadius(11) == pytest.approx(0.31)
    fresh = PyRVOSimulator(0.25, 5.0, 5, 2.0, 2.0, 0.3, 1.0)
    fresh.addAgent((0.0, 0.0))
    fresh.setAgentRadius(0, 0.45)  # right after adding, before anything else made the blocks
    fresh.setAgentMaxNeighbors(0, 2)
    assert fresh.getAgentRadius(0) == 0.45 and fresh.getNumAgents() == 1

    first = PyRVOSimulator(0.25, 5.0, 5, 2.0, 2.0, 0.3, 1.0)
    for k in range(12):
        add(first, k)
    for i in range(5):
        first.setAgentPosition(i, moved[0][i])
        first.setAgentVelocity(i, moved[1][i])
    for sim in (late, first):
        for _ in range(4):
            prefs(sim)
            sim.doStep()
    for i in range(12):
        assert late.getAgentPosition(i) == first.getAgentPosition(i)
        assert late.getAgentVelocity(i) == first.getAgentVelocity(i)


_V_PREF = {"preferred_speed": None, "neighbor_dist_range": None}


@pytest.mark.parametrize(("kwargs", "max_neighbors", "radius", "crowdnav_pref"), [
    ({}, 13, 0.46, True),  # CrowdNav++'s pedestrians (the default): unit preferred velocity, U(5, 10) m neighbours
    ({**_V_PREF}, 13, 0.46, False),  # v_pref toward the goal, 10 m
    ({"safety_space": 0.0, "max_neighbors": 10, **_V_PREF}, 10, 0.31, False),  # CrowdNav's
])
def test_world_orca_equals_facade(kwargs, max_neighbors, radius, crowdnav_pref):
    """The world's batched ORCA pedestrians (robot invisible) follow exactly what PyRVOSimulator computes — with
    CrowdNav++'s preferred velocity (the goal vector cut to 1 m/s) and its crowd-wide neighbour distance draw."""
    w = CrowdWorld(WorldConfig(num_humans=12, robot_visible=False, time_limit=1e9, human_radius_range=None,
                               human_v_pref_range=None), 1, "circle_crossing_legacy", "orca", kwargs)
    nd = float(w.human_model._flt[2, 0, 1])
    assert (w.human_model._flt[2, 0, 1:] == nd).all()  # one draw for the crowd placed at reset
    assert (5.0 <= nd <= 10.0) if crowdnav_pref else nd == 10.0
    sim = PyRVOSimulator(0.25, nd, max_neighbors, 5, 5, radius, 1.0)
    for i in range(12):
        sim.addAgent(tuple(w.pos[0, i + 1]))
    for _ in range(120):
        for i in range(12):
            p = np.asarray(sim.getAgentPosition(i))
            d = w.goal[0, i + 1] - p
            pref = (d / max(np.linalg.norm(d), 1.0) if crowdnav_pref
                    else pref_velocity(tuple(p), w.goal[0, i + 1], 1.0, 0.25))
            sim.setAgentPrefVelocity(i, tuple(pref))
        sim.doStep()
        w.step(np.zeros((1, 2)))
        np.testing.assert_allclose([sim.getAgentPosition(i) for i in range(12)], w.pos[0, 1:], atol=1e-9)


def test_orca_pedestrians_avoid_world_walls():
    box = ((-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0))
    w = CrowdWorld(WorldConfig(num_humans=12, obstacles=(box,), time_limit=1e9, robot_visible=False), 2,
                   "circle_crossing", "orca")
    from crowdbench.geometry import point_segment_distance

    for _ in range(160):
        w.step(np.zeros((2, 2)))
        d = point_segment_distance(w.pos[:, 1:, None], w.edges[None, None, :, 0], w.edges[None, None, :, 1])
        assert d.min() >= 0.3 - 1e-6  # ORCA's obstacle lines keep them off the box (the clamp never needed)


@pytest.mark.parametrize("m", [0, 1, 7, 8, 9, 20, 63, 64, 65, 120])
@pytest.mark.parametrize("k_max", [1, 5, 10, 30, 200])
@pytest.mark.parametrize("ties", [True, False])
def test_neighbour_selection_is_rvo2s(m, k_max, ties):
    """The kernel's neighbour selection (branch-free ranks up to ``RANK_MAX`` candidates, insertion beyond), given
    candidates in any order, keeps RVO2's result: the ``k_max`` smallest squared distances ascending, equal
    distances in agent-index order."""
    from crowdbench.humans.orca_kernel import RANK_MAX, _select

    rng = np.random.default_rng(m * 1000 + k_max + ties)
    d = rng.integers(0, 6, m) * 0.5 if ties else rng.uniform(0, 100, m)  # many exact ties, or none
    idx = rng.choice(500, m, replace=False).astype(np.int64)  # any order
    cand_d, cand_idx = np.append(d, np.full(8, -7.0)), np.append(idx, np.full(8, -7))
    nb_d, nb_idx = np.full(m + 1, -1.0), np.full(m + 1, -1, np.int64)
    cnt = _select(cand_d, cand_idx, m, k_max, nb_d, nb_idx, np.zeros(RANK_MAX, np.int64))
    want = sorted(zip(d.tolist(), idx.tolist(), strict=True))[:k_max]
    assert cnt == len(want)
    assert list(zip(nb_d[:cnt].tolist(), nb_idx[:cnt].tolist(), strict=True)) == want


@pytest.mark.parametrize("n", [40, 200, 1000])
def test_grid_neighbour_search_is_bit_identical_to_brute_force(n):
    """Above ``GRID_MIN`` agents ORCA finds neighbours on a grid of cells; over 20 steps of a jittered grid crowd
    crossing its centre (nobody overlapping at the start), with obstacles, inactive agents and an ignored slot, the
    velocities equal the brute-force search's bit for bit."""
    from crowdbench.humans.orca_kernel import GRID_MIN, build_obstacles, orca_batch

    assert n > GRID_MIN
    rng = np.random.default_rng(n)
    side = int(np.ceil(np.sqrt(n)))
    xy = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n] * 1.2
    pos = (xy - xy.mean(0) + rng.uniform(-0.2, 0.2, (n, 2)))[None].astype(np.float64)
    goal = -pos
    f = np.ones((1, n))
    active = rng.random((1, n)) > 0.05
    ignore = np.full((1, n), -1, np.int64)
    ignore[0, ::7] = 3
    obst = build_obstacles([[(-3.0, -3.0), (3.0, -3.0), (3.0, -2.0), (-3.0, -2.0)]])
    args = (0.3 * f, 1.2 * f, 10.0 * f, np.full((1, n), 10, np.int64), 5.0 * f, 5.0 * f, active,
            np.ones((1, n), bool), ignore)
    a_pos, b_pos = pos.copy(), pos.copy()
    a_vel, b_vel = np.zeros_like(pos), np.zeros_like(pos)
    for _ in range(20):
        a_out, b_out = np.empty_like(pos), np.empty_like(pos)
        orca_batch(a_pos, a_vel, pref_velocity_batch(a_pos, goal), *args, *obst, 0.25, a_out)  # grid (default)
        orca_batch(b_pos, b_vel, pref_velocity_batch(b_pos, goal), *args, *obst, 0.25, b_out, 10**9)  # brute
        np.testing.assert_array_equal(a_out, b_out)
        a_vel, b_vel = a_out, b_out
        a_pos, b_pos = a_pos + a_vel * 0.25, b_pos + b_vel * 0.25


def pref_velocity_batch(pos: np.ndarray, goal: np.ndarray) -> np.ndarray:
    d = goal - pos
    return d / np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1.0)


KERNEL_OUTPUTS = Path(__file__).resolve().parents[1] / "data" / "orca_kernel_outputs.npz"


def _kernel_scenario(name: str):
    """``orca_batch`` inputs of the recorded-kernel scenarios: ``circle``/``grid`` — ``bench_crowd(200, 1, name)``
    with the benchmark's parameters; ``mixed`` — 3 worlds of 40 (brute force) with an obstacle, inactive,
    uncontrolled and ignored agents, varied radii, speeds and neighbour caps."""
    from crowdbench.bench import bench_crowd
    from crowdbench.humans.orca_kernel import build_obstacles

    if name in ("circle", "grid"):
        pos = bench_crowd(200, 1, name)
        f = np.ones(pos.shape[:2])
        args = (0.31 * f, f, 10.0 * f, np.full(f.shape, 10, np.int64), 5.0 * f, 5.0 * f, f > 0, f > 0,
                np.full(f.shape, -1, np.int64))
        return pos, args, build_obstacles([])
    rng = np.random.default_rng(46)
    pos = rng.uniform(-4.0, 4.0, (3, 40, 2))
    shape = pos.shape[:2]
    ignore = np.full(shape, -1, np.int64)
    ignore[:, ::5] = 0
    args = (rng.uniform(0.2, 0.4, shape), rng.uniform(0.8, 1.5, shape), rng.uniform(2.0, 10.0, shape),
            rng.integers(0, 12, shape), rng.uniform(1.0, 5.0, shape), rng.uniform(1.0, 5.0, shape),
            rng.random(shape) > 0.1, rng.random(shape) > 0.1, ignore)
    obst = build_obstacles([[(-1.0, -1.0), (1.0, -1.0), (1.0, 0.0), (-1.0, 0.0)], [(2.0, 2.0), (3.0, 3.0)],
                            [(-3.0, 1.0), (-2.0, 2.5), (-3.5, 3.0)]])
    return pos, args, obst


def _kernel_run(name: str, steps: int = 4) -> np.ndarray:
    """Velocities ``(steps, B, A, 2)`` of ``orca_batch`` over ``steps`` steps of :func:`_kernel_scenario`."""
    from crowdbench.humans import preferred_velocity
    from crowdbench.humans.orca_kernel import orca_batch

    pos, args, obst = _kernel_scenario(name)
    goal, vel, vmax = -pos, np.zeros_like(pos), args[1]
    outs = []
    for _ in range(steps):
        out = np.empty_like(pos)
        orca_batch(pos, vel, preferred_velocity(pos, goal, vmax, 0.25), *args, *obst, 0.25, out)
        outs.append(out)
        vel = out
        pos = pos + vel * 0.25
    return np.array(outs)


@pytest.mark.parametrize("name", ["circle", "grid", "mixed"])
def test_kernel_equals_recorded_output_bit_for_bit(name):
    """The optimised kernel's velocities equal those the kernel gave before its speed work (issue 46), bit for bit:
    ``tests/data/orca_kernel_outputs.npz``, written by ``python tests/humans/test_orca.py`` with the kernel of
    commit 09f4722 (N = 200 circle and grid crowds — overlapping people, infeasible programs, the grid search —
    and small mixed worlds with obstacles, brute force)."""
    want = np.load(KERNEL_OUTPUTS)[name]
    np.testing.assert_array_equal(_kernel_run(name), want)


if __name__ == "__main__":  # regenerate tests/data/orca_kernel_outputs.npz (only from a kernel known to be right)
    np.savez_compressed(KERNEL_OUTPUTS, **{k: _kernel_run(k) for k in ("circle", "grid", "mixed")})


@pytest.mark.parametrize("n", [10, 100])  # brute-force and grid neighbour search
@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_a_non_finite_position_is_one_clear_error_not_a_crash(n, bad):
    sim = PyRVOSimulator(0.25, 10.0, 10, 5.0, 5.0, 0.3, 1.0)
    for i in range(n):
        sim.addAgent((float(i % 10), float(i // 10)))
    sim.setAgentPosition(n // 2, (bad, 0.0))
    with pytest.raises(ValueError, match="non-finite position"):
        sim.doStep()


def test_orca_advance_is_orca_batch_then_the_position_update():
    """``orca_advance`` (RVO2's ``doStep`` on block arrays) equals ``orca_batch`` followed by each active agent's
    position advanced by its new velocity, bit for bit, with obstacles, an inactive agent and an ignored slot."""
    from crowdbench.humans import preferred_velocity
    from crowdbench.humans.orca_kernel import build_obstacles, orca_advance, orca_batch

    rng = np.random.default_rng(3)
    start = rng.uniform(-6, 6, (2, 50, 2))
    B, N = start.shape[:2]
    f = np.ones((B, N))
    flt = np.stack([0.3 * f, f, 10 * f, 5 * f, 5 * f])
    ints = np.stack([np.full((B, N), 10), np.full((B, N), -1)]).astype(np.int64)
    ints[1, 0, 5] = 2
    flags = np.ones((2, B, N), bool)
    flags[0, 0, 3] = False
    obst = build_obstacles([[(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]])
    vec = np.zeros((4, B, N, 2))
    vec[0] = start
    pos, vel = start.copy(), np.zeros_like(start)
    for _ in range(10):
        pref = preferred_velocity(pos, -start, f, 0.25)
        vec[2] = pref
        out = np.empty_like(pos)
        orca_batch(pos, vel, pref, flt[0], flt[1], flt[2], ints[0], flt[3], flt[4], flags[0], flags[1], ints[1],
                   *obst, 0.25, out)
        vel, pos = out, pos + np.where(flags[0][..., None], out * 0.25, 0.0)
        orca_advance(vec, flt, ints, flags, *obst, 0.25)
        np.testing.assert_array_equal(vec[1], vel)
        np.testing.assert_array_equal(vec[0], pos)
    assert np.array_equal(vec[0, 0, 3], start[0, 3])  # the inactive agent stays


def _pillar_field(rng: np.random.Generator, count: int) -> list[list[tuple[float, float]]]:
    """Obstacles of many kinds over a 24 × 24 m square: square and triangular pillars (counter-clockwise), a
    non-convex L, two-sided segments, one long diagonal wall (many cells of its bounding box hold no part of it)."""
    polys: list[list[tuple[float, float]]] = [[(-12.0, -12.0), (12.0, 11.0)],
                                              [(4.0, 4.0), (7.0, 4.0), (7.0, 5.0), (5.0, 5.0), (5.0, 7.0), (4.0, 7.0)]]
    for k in range(count):
        x, y = rng.uniform(-11.0, 11.0, 2)
        s = rng.uniform(0.2, 0.8)
        if k % 3 == 0:
            polys.append([(x, y), (x + s, y), (x + s, y + s), (x, y + s)])
        elif k % 3 == 1:
            polys.append([(x, y), (x + s, y), (x + 0.5 * s, y + s)])
        else:
            polys.append([(x, y), (x + s, y + rng.uniform(-s, s))])
    return polys


def test_the_edge_scan_and_the_obstacle_tree_give_the_same_neighbours_in_the_same_order():
    """An agent's obstacle neighbours by a scan of every edge equal those of RVO2's tree query — the same edges in
    the same order, ties (corners, two crossing segments) in the tree's visiting order — for points inside the
    field, at its edges and far outside; the ties are many, and often not in index order."""
    from crowdbench.humans.orca_kernel import _obstacle_neighbors, _tree_obstacle_neighbors, build_obstacles

    rng = np.random.default_rng(7)
    opoint, onext, _, _, _, otree = build_obstacles(_pillar_field(rng, 60))
    V = len(opoint)
    stack = np.empty((2 * V + 2, 2), np.int64)
    pts = np.concatenate([rng.uniform(-14.0, 14.0, (3000, 2)), [[40.0, 40.0], [-30.0, 0.0]]])
    found = ties = reordered = 0
    for px, py in pts:
        for reach in (0.8, 2.5, 5.3):
            a_idx, a_d = np.empty(V + 1, np.int64), np.empty(V + 1)
            b_idx, b_d = np.empty(V + 1, np.int64), np.empty(V + 1)
            na = _obstacle_neighbors(px, py, reach**2, opoint, onext, otree, a_idx, a_d)
            nb = _tree_obstacle_neighbors(px, py, reach**2, opoint, onext, otree, stack, b_idx, b_d)
            assert na == nb
            np.testing.assert_array_equal(a_idx[:na], b_idx[:nb])
            np.testing.assert_array_equal(a_d[:na], b_d[:nb])
            found += na
            tied = a_d[1:na] == a_d[: max(na - 1, 0)]
            ties += int(tied.sum())
            reordered += int((tied & (a_idx[1:na] < a_idx[: max(na - 1, 0)])).sum())  # the tree, not the index, decided
    assert found > 10_000 and ties > 1_000 and reordered > 100


def test_obstacle_tree_splits_edges_as_rvo2_does():
    """``processObstacles`` gives RVO2's obstacle vertices — its tree's splits included — with the same numbers,
    links and (float32) positions (when Python-RVO2 is installed)."""
    rvo2 = pytest.importorskip("rvo2")
    polys = _pillar_field(np.random.default_rng(3), 40)
    sims = [PyRVOSimulator(0.25, 10.0, 10, 5.0, 5.0, 0.3, 1.0), rvo2.PyRVOSimulator(0.25, 10.0, 10, 5.0, 5.0, 0.3,
                                                                                     1.0)]
    for sim in sims:
        for poly in polys:
            sim.addObstacle([(float(x), float(y)) for x, y in poly])
        sim.processObstacles()
    n = sims[1].getNumObstacleVertices()
    assert sims[0].getNumObstacleVertices() == n > sum(len(p) for p in polys)  # edges were split
    for v in range(n):
        assert sims[0].getNextObstacleVertexNo(v) == sims[1].getNextObstacleVertexNo(v)
        assert sims[0].getPrevObstacleVertexNo(v) == sims[1].getPrevObstacleVertexNo(v)
        np.testing.assert_allclose(sims[0].getObstacleVertex(v), sims[1].getObstacleVertex(v), atol=1e-5)


RVO2_LARGE = Path(__file__).resolve().parents[1] / "data" / "orca_rvo2_large.npz"


def _rvo2_large(name: str) -> tuple[dict[str, np.ndarray], PyRVOSimulator]:
    """A scenario of ``tests/data/orca_rvo2_large.npz`` (written by ``tests/data/make_rvo2_references.py`` from
    Python-RVO2) and a ``PyRVOSimulator`` holding its agents and obstacles."""
    with np.load(RVO2_LARGE) as d:
        sc = {k.split("/", 1)[1]: d[k] for k in d.files if k.startswith(name + "/")}
    sim = PyRVOSimulator(0.25, 10.0, 10, 5.0, 5.0, 0.31, 1.0)
    for q in sc["start"]:
        sim.addAgent((float(q[0]), float(q[1])))
    if "polygons" in sc:
        for poly in np.split(sc["polygons"], np.cumsum(sc["polygon_sizes"])[:-1]):
            sim.addObstacle([(float(x), float(y)) for x, y in poly])
    sim.processObstacles()
    return sc, sim


def _step_from(sim: PyRVOSimulator, start: np.ndarray, pos: np.ndarray, vel: np.ndarray,
               shift: tuple[int, np.ndarray] | None = None) -> np.ndarray:
    """Set every agent to ``pos``/``vel`` (RVO2's state; agent ``shift[0]`` moved by ``shift[1]``), preferred
    velocities toward −start as the reference run set them, one ``doStep``; returns the new velocities."""
    from crowdbench.humans import preferred_velocity

    n = len(start)
    pref = preferred_velocity(pos, -start, np.ones(n), 0.25)
    for i in range(n):
        sim.setAgentPosition(i, (float(pos[i, 0]), float(pos[i, 1])))
        sim.setAgentVelocity(i, (float(vel[i, 0]), float(vel[i, 1])))
        sim.setAgentPrefVelocity(i, (float(pref[i, 0]), float(pref[i, 1])))
    if shift is not None:
        i, d = shift
        sim.setAgentPosition(i, (float(pos[i, 0] + d[0]), float(pos[i, 1] + d[1])))
    sim.doStep()
    return np.array([sim.getAgentVelocity(i) for i in range(n)])


@pytest.mark.parametrize("name", ["lattice-200", "lattice-1000", "pillars-200", "pillars-1000"])
def test_neighbours_are_rvo2s_in_rvo2s_order(name):
    """During each of the first three steps of RVO2's runs (``tests/data/orca_rvo2_large.npz``: 200 and 1,000 people
    on a lattice, and crossing halls of pillars with 364 and 964 obstacle vertices — the edge scan and the obstacle
    tree), every agent's agent neighbours and obstacle neighbours are RVO2's, in RVO2's order."""
    sc, sim = _rvo2_large(name)
    n = len(sc["start"])
    with_obstacles = 0
    for k in range(3):
        _step_from(sim, sc["start"], sc["pos"][k].astype(np.float64), sc["vel"][k].astype(np.float64))
        for i in range(n):
            got = [sim.getAgentAgentNeighbor(i, j) for j in range(sim.getAgentNumAgentNeighbors(i))]
            assert got == [x for x in sc["agent_nb"][k, i] if x >= 0], (k, i)
            got = [sim.getAgentObstacleNeighbor(i, j) for j in range(sim.getAgentNumObstacleNeighbors(i))]
            assert got == [x for x in sc["obst_nb"][k, i] if x >= 0], (k, i)
            with_obstacles += len(got) > 1
    assert (with_obstacles > n) == name.startswith("pillars")


@pytest.mark.parametrize("n", [200, 1000])
def test_a_large_lattice_crowd_ends_where_rvo2s_does(n):
    """From RVO2's start, 20 steps of ``PyRVOSimulator`` (float64) end within 1e-3 m of RVO2's run (float32)."""
    sc, sim = _rvo2_large(f"lattice-{n}")
    start = sc["start"]
    for _ in range(20):
        here = np.array([sim.getAgentPosition(i) for i in range(n)])
        from crowdbench.humans import preferred_velocity

        pref = preferred_velocity(here, -start, np.ones(n), 0.25)
        for i in range(n):
            sim.setAgentPrefVelocity(i, (float(pref[i, 0]), float(pref[i, 1])))
        sim.doStep()
    end = np.array([sim.getAgentPosition(i) for i in range(n)])
    assert list(sc["steps"]) == [0, 1, 2, 3, 20]
    assert np.abs(end - sc["pos"][-1]).max() < 1e-3


@pytest.mark.parametrize("name", ["pillars-200", "pillars-1000"])
def test_among_pillars_each_step_agrees_with_rvo2_unless_on_a_switch(name):
    """Given RVO2's state at every step of its runs among pillars (200 people, 364 obstacle vertices, 20 steps; 1,000
    people, 964 vertices, 10 steps), ``PyRVOSimulator``'s next velocities equal RVO2's within 1e-3 m/s — except
    where the state lies on one of ORCA's switches (a constraint covered or not, a program feasible or not), which
    float32 and float64 may take either way: there a shift of the agent by at most 1e-6 m gives RVO2's velocity.
    (Before the obstacle tree's order, a corner's two edges came in index order and an agent's velocity differed by
    0.43 m/s, robust to shifts of 1e-4 m.)"""
    sc, sim = _rvo2_large(name)
    start, n = sc["start"], len(sc["start"])
    rng = np.random.default_rng(0)
    apart = 0
    for k in range(len(sc["steps"]) - 1):
        pos, vel = sc["pos"][k].astype(np.float64), sc["vel"][k].astype(np.float64)
        want, got = sc["vel"][k + 1], _step_from(sim, start, pos, vel)
        for i in np.flatnonzero(np.abs(got - want).max(1) > 1e-3):
            apart += 1
            shifted = [_step_from(sim, start, pos, vel, (i, rng.uniform(-1e-6, 1e-6, 2)))[i] for _ in range(8)]
            assert min(np.abs(v - want[i]).max() for v in shifted) < 1e-3, f"step {k} agent {i}: {got[i]} vs {want[i]}"
    assert apart <= n // 50  # a few switches among the agent-steps
