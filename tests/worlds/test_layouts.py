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
    starts, goals = lay.sample(np.random.default_rng(seed), 30, 0.3, 0.3)
    for pts in (starts, goals) if lay.separate_goals else (starts,):
        d = np.linalg.norm(pts[:, None] - pts[None], axis=-1) + np.eye(30) * 99
        assert d.min() >= 0.6 + PLACEMENT_GAP - 1e-12
        robot = np.array([lay.robot_start, lay.robot_goal])
        assert np.linalg.norm(pts[:, None] - robot[None], axis=-1).min() >= 0.6 + PLACEMENT_GAP - 1e-12


def test_circle_crossing_geometry():
    lay = make_layout("circle_crossing")
    starts, goals = lay.sample(np.random.default_rng(0), 20, 0.3, 0.3)
    np.testing.assert_allclose(goals, -starts)
    r = np.linalg.norm(starts, axis=1)
    assert (r > 6 - 0.5 * np.sqrt(2) - 1e-9).all() and (r < 6 + 0.5 * np.sqrt(2) + 1e-9).all()
    assert lay.robot_start == (0.0, -6.0) and lay.robot_goal == (0.0, 6.0)


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


def test_goals_renew_so_density_holds():
    w = CrowdWorld(WorldConfig(num_humans=20, time_limit=1e9), 2, "circle_crossing", "orca")
    first_goals = w.goal[:, 1:].copy()
    for _ in range(240):  # 60 s: every pedestrian reaches its first goal
        w.step(np.zeros((2, 2)))
    assert (np.linalg.norm(w.goal[:, 1:] - first_goals, axis=-1) > 1e-9).mean() > 0.9
    # still spread over the circle crossing area, nobody stuck at a boundary
    assert (np.linalg.norm(w.pos[:, 1:], axis=-1) < 7.5).all()
