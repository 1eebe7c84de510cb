"""Layouts: non-overlapping bounded placement, geometry, goal renewal, clear errors."""

from __future__ import annotations

import numpy as np
import pytest

from crowdbench.config import WorldConfig
from crowdbench.worlds import LAYOUTS, CrowdWorld, make_layout
from crowdbench.worlds.layouts import PLACEMENT_GAP


@pytest.mark.parametrize("name", LAYOUTS.names())
@pytest.mark.parametrize("seed", range(5))
def test_thirty_pedestrians_placed_without_overlap(name, seed):
    lay = make_layout(name)
    rng = np.random.default_rng(seed)
    robot = np.stack(lay.robot_endpoints(rng, np.zeros((0, 2, 2)), 0.3))
    starts, goals = lay.sample(rng, 30, 0.3, 0.3, robot_points=robot)
    for pts in (starts, goals) if lay.separate_goals else (starts,):
        d = np.linalg.norm(pts[:, None] - pts[None], axis=-1) + np.eye(30) * 99
        assert d.min() >= 0.6 + PLACEMENT_GAP - 1e-12
        assert np.linalg.norm(pts[:, None] - robot[None], axis=-1).min() >= 0.6 + PLACEMENT_GAP - 1e-12


def test_circle_crossing_geometry():
    lay = make_layout("circle_crossing")  # CrowdNav++'s: circle 6√2 m, noise ±1 m, robot start/goal drawn
    starts, goals = lay.sample(np.random.default_rng(0), 20, 0.3, 0.3)
    np.testing.assert_allclose(goals, -starts)
    r = np.linalg.norm(starts, axis=1)
    R = 6 * np.sqrt(2)
    assert (r > R - np.sqrt(2) - 1e-9).all() and (r < R + np.sqrt(2) + 1e-9).all()
    legacy = make_layout("circle_crossing_legacy")
    starts, _ = legacy.sample(np.random.default_rng(0), 20, 0.3, 0.3)
    r = np.linalg.norm(starts, axis=1)
    assert (r > 6 - 0.5 * np.sqrt(2) - 1e-9).all() and (r < 6 + 0.5 * np.sqrt(2) + 1e-9).all()
    s, g = legacy.robot_endpoints(np.random.default_rng(0), np.zeros((0, 2, 2)), 0.3)
    assert tuple(s) == (0.0, -6.0) and tuple(g) == (0.0, 6.0)


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


@pytest.mark.parametrize(("layout", "bound"), [("circle_crossing_legacy", 7.5), ("circle_crossing", 11.0)])
def test_goals_renew_so_density_holds(layout, bound):
    w = CrowdWorld(WorldConfig(num_humans=20, time_limit=1e9, human_v_pref_range=None), 2, layout, "orca")
    first_goals = w.goal[:, 1:].copy()
    for _ in range(240):  # 60 s: every pedestrian reaches its first goal
        w.step(np.zeros((2, 2)))
    assert (np.linalg.norm(w.goal[:, 1:] - first_goals, axis=-1) > 1e-9).mean() > 0.9
    # still spread over the circle crossing area, nobody stuck at a boundary
    assert (np.linalg.norm(w.pos[:, 1:], axis=-1) < bound).all()
    assert (np.linalg.norm(w.pos[:, 1:], axis=-1) < 3.0).sum() >= 2  # the centre stays busy


def test_respawn_and_goal_changes_follow_crowdnav_plus_plus():
    """Arrivals are re-spawned at rest on the circle with goal = −start; every 5 s about half of the pedestrians
    change goal to a point near the circle; goals change at no other time."""
    w = CrowdWorld(WorldConfig(num_humans=20, time_limit=1e9), 4, "circle_crossing", "orca")
    R = 6 * np.sqrt(2)
    changes, respawns = [], 0
    for t in range(1, 241):
        before_goal = w.goal.copy()
        w.step(np.zeros((4, 2)))
        changed = np.linalg.norm(w.goal - before_goal, axis=-1) > 1e-9
        changed[:, 0] = False
        if t % 20 == 0:
            changes.append(changed[:, 1:].mean())
            r = np.linalg.norm(w.goal[changed], axis=-1)
            assert ((r > R - 1.0) & (r < R + 1.0)).all()
        elif changed.any():  # between ticks only arrivals change goal: re-spawned
            respawns += int(changed.sum())
            r = np.linalg.norm(w.pos[changed], axis=-1)
            assert ((r > R - 1.5) & (r < R + 1.5)).all()
            np.testing.assert_allclose(w.goal[changed], -w.pos[changed])
            assert (np.linalg.norm(w.vel[changed], axis=-1) == 0).all()
            others = np.linalg.norm(w.pos[:, :, None] - w.pos[:, None], axis=-1) + np.eye(21) * 99
            assert (others[changed].min(axis=-1) >= 0.6 - 1e-9).all()  # never on top of anyone
    assert respawns > 20
    assert 0.35 < np.mean(changes) < 0.65
