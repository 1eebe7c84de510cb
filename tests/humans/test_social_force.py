"""Social Force: never through walls, arrival without division by zero, mutual repulsion."""

from __future__ import annotations

import numpy as np

from crowdbench.config import WorldConfig, make_config
from crowdbench.geometry import point_segment_distance, segment_segment_distance
from crowdbench.worlds import CrowdWorld


def test_social_force_pedestrians_never_pass_through_walls():
    walls = [((-3.0, -0.5), (3.0, -0.5)), ((-2.0, 1.5), (2.0, 1.5), (2.0, 2.0), (-2.0, 2.0))]
    cfg = make_config(num_humans=20, obstacles=walls, arena_walls=True, time_limit=1e9, robot_visible=False)
    w = CrowdWorld(cfg, 4, "circle_crossing_legacy", "social_force")
    for _ in range(240):
        prev = w.pos.copy()
        w.step(np.zeros((4, 2)))
        a, b = w.edges[None, None, :, 0], w.edges[None, None, :, 1]
        assert (segment_segment_distance(prev[:, 1:, None], w.pos[:, 1:, None], a, b) > 0).all()
        assert (point_segment_distance(w.pos[:, 1:, None], a, b).min(-1) >= 0.3 - 1e-4).all()


def test_arrival_is_finite_and_settles_on_goal():
    w = CrowdWorld(WorldConfig(num_humans=1, robot_visible=False, time_limit=1e9), 1, "circle_crossing",
                   "social_force")
    A = w.num_agents
    pos = np.array([[0.0, -6.0], [3.0, 3.0]])
    w.set_agents(0, positions=pos, velocities=np.zeros((A, 2)), goals=np.array([[0.0, 6.0], [3.0, 3.0001]]))
    for _ in range(20):
        w.step(np.zeros((1, 2)))
        assert np.isfinite(w.vel).all()


def test_head_on_pedestrians_repel():
    w = CrowdWorld(WorldConfig(num_humans=2, robot_visible=False, time_limit=1e9), 1, "circle_crossing",
                   "social_force")
    pos = np.array([[0.0, -6.0], [-3.0, 3.0], [3.0, 3.05]])
    goals = np.array([[0.0, 6.0], [3.0, 3.0], [-3.0, 3.05]])
    w.set_agents(0, positions=pos, velocities=np.zeros((3, 2)), goals=goals)
    gaps = []
    for _ in range(40):
        w.step(np.zeros((1, 2)))
        gaps.append(np.linalg.norm(w.pos[0, 1] - w.pos[0, 2]) - 0.6)
    assert min(gaps) > -0.3  # they deflect instead of walking through each other
    assert abs(w.pos[0, 1, 1] - 3.0) > 0.01 or abs(w.pos[0, 2, 1] - 3.05) > 0.01
