"""Layouts: non-overlapping bounded placement, geometry, goal renewal, clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from crowdbench.config import WorldConfig
from crowdbench.worlds import LAYOUTS, CrowdWorld, make_layout


@pytest.mark.parametrize("name", LAYOUTS.names())
@pytest.mark.parametrize("seed", range(5))
def test_thirty_pedestrians_placed_without_overlap(name, seed):
    lay = make_layout(name)
    rng = np.random.default_rng(seed)
    robot = np.stack(lay.robot_endpoints(rng, np.zeros((0, 2, 2)), 0.3))
    starts, goals = lay.sample(rng, 30, 0.3, 0.3, robot_points=robot)
    for pts in (starts, goals) if lay.separate_goals else (starts,):
        d = np.linalg.norm(pts[:, None] - pts[None], axis=-1) + np.eye(30) * 99
        gap = lay.placement_gap  # PLACEMENT_GAP but in dense layouts (the concourse)
        assert d.min() >= 0.6 + gap - 1e-12
        assert np.linalg.norm(pts[:, None] - robot[None], axis=-1).min() >= 0.6 + gap - 1e-12


def test_circle_crossing_geometry():
    """CrowdNav++'s start rule: a uniform angle on the 6√2 m circle plus a one-sided U[0, 2) per coordinate
    (crowd_sim_var_num.py:121-128), goal = −start; the calibrated and legacy crowds keep theirs."""
    lay = make_layout("circle_crossing")
    R = 6 * np.sqrt(2)
    s, g = lay.candidates(np.random.default_rng(4), 0, 1, 1000)
    rng = np.random.default_rng(4)
    ang = rng.uniform(0, 2 * np.pi, 1000)
    np.testing.assert_array_equal(s, R * np.stack([np.cos(ang), np.sin(ang)], 1) + rng.uniform(0, 2, (1000, 2)))
    np.testing.assert_array_equal(g, -s)
    assert abs((s - R * np.stack([np.cos(ang), np.sin(ang)], 1)).mean() - 1.0) < 0.05  # shifted by +(1, 1)
    calibrated = make_layout("circle_crossing_calibrated")
    starts, goals = calibrated.sample(np.random.default_rng(0), 20, 0.3, 0.3)
    np.testing.assert_allclose(goals, -starts)
    r = np.linalg.norm(starts, axis=1)
    assert (r > R - np.sqrt(2) - 1e-9).all() and (r < R + np.sqrt(2) + 1e-9).all()
    legacy = make_layout("circle_crossing_legacy")
    starts, _ = legacy.sample(np.random.default_rng(0), 20, 0.3, 0.3)
    r = np.linalg.norm(starts, axis=1)
    assert (r > 6 - 0.5 * np.sqrt(2) - 1e-9).all() and (r < 6 + 0.5 * np.sqrt(2) + 1e-9).all()
    s, g = legacy.robot_endpoints(np.random.default_rng(0), np.zeros((0, 2, 2)), 0.3)
    assert tuple(s) == (0.0, -6.0) and tuple(g) == (0.0, 6.0)


@pytest.mark.parametrize("seed", range(6))
def test_circle_crossing_placement_is_crowdnavpps_clearance(seed):
    """Each start is ≥ r_i + r_j + 0.25 m from every earlier agent's start *and* goal, the robot's included
    (crowd_sim_var_num.py:129-140); the goals (−start) are not checked."""
    lay = make_layout("circle_crossing")
    rng = np.random.default_rng(seed)
    robot = np.stack(lay.robot_endpoints(rng, np.zeros((0, 2, 2)), 0.3))
    radii = rng.uniform(0.3, 0.5, 25)
    starts, goals = lay.sample(rng, 25, radii, 0.3, robot_points=robot)
    np.testing.assert_array_equal(goals, -starts)
    for i in range(25):
        for pts, rad in ((robot, np.full(2, 0.3)), (starts[:i], radii[:i]), (goals[:i], radii[:i])):
            if len(pts):
                assert (np.linalg.norm(starts[i] - pts, axis=1) >= radii[i] + rad + 0.25 - 1e-12).all()


@pytest.mark.parametrize("name", ["circle_crossing", "intersection", "split_flow", "random_wander"])
def test_random_robot_crossings_vary_and_keep_their_distance(name):
    lay = make_layout(name)
    rng = np.random.default_rng(0)
    pairs = np.array([np.concatenate(lay.robot_endpoints(rng, np.zeros((0, 2, 2)), 0.3)) for _ in range(400)])
    assert (np.hypot(pairs[:, 0] - pairs[:, 2], pairs[:, 1] - pairs[:, 3]) >= 8.0).all()
    assert (np.abs(pairs) <= 6.0).all()
    heading = np.arctan2(pairs[:, 3] - pairs[:, 1], pairs[:, 2] - pairs[:, 0])
    assert np.histogram(heading, bins=8, range=(-np.pi, np.pi))[0].min() > 20  # every direction is crossed
    with pytest.raises(ValueError, match="robot='diagonal'; valid choices: fixed, random"):
        make_layout(name, robot="diagonal")


def test_square_crossing_goals_on_the_opposite_side():
    starts, goals = make_layout("square_crossing").sample(np.random.default_rng(1), 20, 0.3, 0.3)
    assert (np.sign(starts[:, 0]) == -np.sign(goals[:, 0])).all()
    assert (np.abs(starts) <= 5 + 1e-9).all() and (np.abs(goals) <= 5 + 1e-9).all()


def test_streams_cross_the_arena():
    starts, goals = make_layout("split_flow").sample(np.random.default_rng(2), 20, 0.3, 0.3)
    assert (np.abs(goals[:, 0]) == 6.0).all() and (np.sign(starts[:, 0]) == -np.sign(goals[:, 0])).all()
    starts, goals = make_layout("intersection").sample(np.random.default_rng(2), 20, 0.3, 0.3)
    east, south = starts[0::2], starts[1::2]
    assert (goals[0::2, 0] == 6.0).all() and (goals[1::2, 1] == -6.0).all()
    assert (east[:, 0] < -2).all() and (south[:, 1] > 2).all()


def test_impossible_crowd_raises_clear_error():
    with pytest.raises(ValueError, match="cannot fit num_humans=200"):
        make_layout("circle_crossing").sample(np.random.default_rng(0), 200, 0.3, 0.3)


@pytest.mark.parametrize(("layout", "bound", "model"), [
    ("circle_crossing_legacy", 7.5, {"preferred_speed": None, "neighbor_dist_range": None}),  # its own pedestrians
    ("circle_crossing", 12.0, {})])
def test_goals_renew_so_density_holds(layout, bound, model):
    w = CrowdWorld(WorldConfig(num_humans=20, time_limit=1e9, human_v_pref_range=None), 2, layout, "orca", model)
    first_goals = w.goal[:, 1:].copy()
    for _ in range(240):  # 60 s: every pedestrian reaches its first goal
        w.step(np.zeros((2, 2)))
    assert (np.linalg.norm(w.goal[:, 1:] - first_goals, axis=-1) > 1e-9).mean() > 0.9
    # still spread over the circle crossing area, nobody stuck at a boundary
    assert (np.linalg.norm(w.pos[:, 1:], axis=-1) < bound).all()
    assert (np.linalg.norm(w.pos[:, 1:], axis=-1) < 3.0).sum() >= 2  # the centre stays busy


def test_respawn_and_goal_changes_follow_crowdnav_plus_plus():
    """Arrivals are re-spawned at rest by the start rule (goal = −start), never within r_i + r_j + 0.25 m of anyone's
    position or goal, their slot's ``spawns`` count going up; every 5 s about half of the pedestrians change goal
    to a point of the circle plus U[−v_pref/2, v_pref/2) per coordinate (crowd_sim.py:415-450); goals change at
    no other time."""
    w = CrowdWorld(WorldConfig(num_humans=20, time_limit=1e9), 4, "circle_crossing", "orca")
    R = 6 * np.sqrt(2)
    changes, respawns = [], 0
    for t in range(1, 241):
        before_goal, before_spawns = w.goal.copy(), w.spawns.copy()
        w.step(np.zeros((4, 2)))
        respawned = w.spawns != before_spawns
        assert (w.spawns - before_spawns <= 1).all() and not respawned[:, 0].any()
        changed = (np.linalg.norm(w.goal - before_goal, axis=-1) > 1e-9) & ~respawned
        changed[:, 0] = False
        if t % 20 == 0:
            changes.append(changed[:, 1:].sum() / 80)
            off = np.linalg.norm(w.goal[changed], axis=-1) - R
            assert (np.abs(off) <= np.sqrt(2) * w.v_pref[changed] / 2 + 1e-9).all()
        else:
            assert not changed.any()  # between ticks only re-spawns change goals
        if respawned.any():
            respawns += int(respawned.sum())
            r = np.linalg.norm(w.pos[respawned], axis=-1)
            assert ((r >= R - 2 * np.sqrt(2)) & (r <= R + 2 * np.sqrt(2))).all()
            np.testing.assert_allclose(w.goal[respawned], -w.pos[respawned])
            assert (np.linalg.norm(w.vel[respawned], axis=-1) == 0).all()
            for b, a in zip(*np.nonzero(respawned), strict=True):
                others = np.flatnonzero(w.active[b] & (np.arange(21) != a))
                need = w.radius[b, a] + w.radius[b, others] + 0.25
                assert (np.linalg.norm(w.pos[b, others] - w.pos[b, a], axis=-1) >= need - 1e-9).all()
                assert (np.linalg.norm(w.goal[b, others] - w.pos[b, a], axis=-1) >= need - 1e-9).all()
    assert respawns > 20
    assert 0.35 < np.mean(changes) < 0.65


def test_a_respawn_with_no_room_waits_at_the_goal():
    """No clear start (every candidate blocked): the pedestrian stays where it is, and is re-spawned once room
    appears — never on top of anyone."""
    w = CrowdWorld(WorldConfig(num_humans=2, time_limit=1e9, human_radius_range=None, human_v_pref_range=None), 1,
                   "circle_crossing", "orca")
    w.layout.spawn_candidates = 1
    calls = {"n": 0}
    real = w.layout.respawn_candidates

    def blocked(rng, m):  # the first three re-spawn attempts land on pedestrian 1's position
        calls["n"] += 1
        s, g = real(rng, m)
        if calls["n"] <= 3:
            s = np.repeat(w.pos[0, 2:3], m, 0)
            g = -s
        return s, g

    w.layout.respawn_candidates = blocked
    w.set_agents(0, positions=np.array([[0, -3], [4, 4], [-6, -6]]), goals=np.array([[0, 3], [4.1, 4], [-6, -7]]))
    w.step(np.zeros((1, 2)))
    assert calls["n"] == 1 and w.spawns[0, 1] == 0  # waited
    w.step(np.zeros((1, 2)))
    w.step(np.zeros((1, 2)))
    assert calls["n"] == 3 and w.spawns[0, 1] == 0
    w.step(np.zeros((1, 2)))
    assert w.spawns[0, 1] == 1 and np.linalg.norm(w.pos[0, 1] - w.pos[0, 2]) >= 0.6 + 0.25


def test_the_concourse_holds_hundreds_with_streams_between_its_entrances():
    import crowdbench

    env = crowdbench.parallel_env(layout="concourse", num_humans=500)
    env.reset(seed=0)
    w = env.world
    lay = w.layout
    pos = w.pos[0, 1:]
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1) - w.radius[0, 1:, None] - w.radius[0, None, 1:]
    assert (d + np.eye(500) * 99).min() >= lay.placement_gap - 1e-12  # 500 placed without overlap
    goals = w.goal[0, 1:]
    near_door = np.linalg.norm(goals[:, None] - lay._doors[None], axis=-1).min(axis=1)
    assert (near_door < lay.door / 2 + 1.0).all()  # every goal is an entrance
    for _ in range(50):
        env.step({"robot": np.zeros(2)})
    assert np.isfinite(w.pos).all() and len(env.agents) == 501
