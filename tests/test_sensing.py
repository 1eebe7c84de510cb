"""The faithful benchmark: CrowdNav++'s walking rules, its sensing distance, one sensing tier per robot, the velocity
estimator, and the board against the paper."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import crowdbench
from crowdbench.config import WorldConfig
from crowdbench.evaluation import run_episodes
from crowdbench.policies import make_policy
from crowdbench.robots.observations import make_observation
from crowdbench.worlds import CrowdWorld


def test_default_crowd_walks_like_crowdnavpp():
    """Preferred velocity a unit vector, v_pref only the limit: the 95th percentile of speed stays near 1 m/s."""
    w = CrowdWorld(WorldConfig(time_limit=1e9), 8, "circle_crossing", "responsive_orca")
    speeds = []
    for _ in range(200):
        w.step(np.zeros((8, 2)))
        speeds.append(np.linalg.norm(w.vel[:, 1:], axis=-1)[w.active[:, 1:]])
    assert np.percentile(np.concatenate(speeds), 95) <= 1.15


@pytest.mark.parametrize(("v_pref", "cruise"), [(1.4, 1.0), (0.6, 0.6)])
def test_a_lone_pedestrian_cruises_at_min_of_one_and_v_pref(v_pref, cruise):
    w = CrowdWorld(WorldConfig(num_humans=1, time_limit=1e9, human_radius_range=None, human_v_pref_range=None,
                               human_v_pref=v_pref, robot_visible=False), 1, "circle_crossing", "orca")
    w.set_agents(0, positions=np.array([[20.0, 20.0], [0.0, 0.0]]), goals=np.array([[20.0, 21.0], [6.0, 0.0]]))
    w.step(np.zeros((1, 2)))
    assert np.linalg.norm(w.vel[0, 1]) == pytest.approx(cruise)
    for _ in range(30):
        w.step(np.zeros((1, 2)))
    d = np.linalg.norm(w.goal[0, 1] - w.pos[0, 1])
    if d < 1.0:  # within 1 m the preferred velocity is the goal vector itself: it slows down
        assert np.linalg.norm(w.vel[0, 1]) <= 1.0


def test_neighbour_distance_is_one_draw_per_crowd_and_a_fresh_one_per_respawn():
    w = CrowdWorld(WorldConfig(time_limit=1e9), 6, "circle_crossing", "orca")
    nd = w.human_model._flt[2][:, 1:]
    assert ((nd >= 5.0) & (nd <= 10.0)).all()
    assert (nd == nd[:, :1]).all() and len(np.unique(nd[:, 0])) == 6  # shared within a world, drawn per world
    before = nd.copy()
    for _ in range(120):
        w.step(np.zeros((6, 2)))
    nd = w.human_model._flt[2][:, 1:]
    respawned = w.spawns[:, 1:] > 0
    assert respawned.any() and (nd[~respawned] == before[~respawned]).all()
    assert (nd[respawned] != before[respawned]).all()


def test_the_robot_senses_by_surface_distance():
    """CrowdNav++'s detect_visible: ‖p_r − p_h‖ − r_r − r_h ≤ 5 m."""
    w = CrowdWorld(WorldConfig(num_humans=2, human_radius_range=None, human_radius=0.5), 1, "circle_crossing",
                   "orca")
    w.set_agents(0, positions=np.array([[0.0, 0.0], [5.75, 0.0], [0.0, 5.85]]))
    obs = make_observation("relative", w.config).build(w)
    assert obs["mask"][0].tolist()[:2] == [1.0, 0.0]
    np.testing.assert_allclose(obs["humans"][0, 0], [5.75, 0.0], atol=1e-6)


def test_the_velocity_estimator_differences_consecutive_sightings():
    w = CrowdWorld(WorldConfig(num_humans=20, time_limit=1e9, sensing_range=50.0), 3, "circle_crossing", "orca")
    est = make_observation("estimated_state", w.config)
    first = est.build(w)
    assert (first["humans"][..., 2:4] == 0).all()  # nobody has a velocity yet
    assert (first["humans"][..., 4][first["mask"] > 0] == 0.5).all()  # the largest radius the crowd allows
    for _ in range(30):
        prev = w.pos.copy()
        prev_spawns = w.spawns.copy()
        w.step(np.zeros((3, 2)))
        o = est.build(w)
        for b in range(3):
            rel = o["humans"][b, :, :2].astype(np.float64)
            for k in np.flatnonzero(o["mask"][b] > 0):
                h = 1 + int(np.argmin(np.linalg.norm(w.pos[b, 1:] - w.pos[b, 0] - rel[k], axis=-1)))
                want = 0.0 if w.spawns[b, h] != prev_spawns[b, h] else (w.pos[b, h] - prev[b, h]) / w.dt
                np.testing.assert_allclose(o["humans"][b, k, 2:4], want, atol=1e-4)
    w.reset(seeds=[7, 8, 9])
    assert (est.build(w)["humans"][..., 2:4] == 0).all()  # a new episode: no sightings


def test_a_policy_needing_more_than_the_sensor_gives_is_one_clear_error():
    with pytest.raises(ValueError, match="observation 'full_state' needs sensing tier 'full'.*sensing='positions'"):
        run_episodes(make_policy("orca", sensing="full"), 1, sensing="positions")
    with pytest.raises(ValueError, match="observation 'observed_state' needs sensing tier 'velocities'"):
        crowdbench.parallel_env(observation="observed_state", sensing="positions")
    with pytest.raises(ValueError, match="sensing='eyes'; valid choices: positions, velocities, full"):
        make_policy("social_force", sensing="eyes")
    assert make_policy("orca").sensing == "positions" and make_policy("linear").sensing == "positions"
    assert make_policy("orca", sensing="velocities").observation == "observed_state"


def test_leaderboard_list_shows_every_entrys_sensing_tier():
    out = subprocess.run([sys.executable, "-m", "crowdbench.cli", "leaderboard", "list"], capture_output=True,
                         text=True, check=True).stdout
    entries = out.split("registered robot policies")[0]
    lines = {ln.split()[0]: ln for ln in entries.splitlines() if ln.startswith("  ")}
    assert "sensing=positions" in lines["orca"] and "sensing=positions" in lines["social_force"]
    assert "sensing=velocities" in lines["orca-velocities"]
    from crowdbench.leaderboard import STALE

    for name in STALE:  # trained on the former crowd: off the board until retrained
        assert "not on the board" in lines[name]
    for name, line in lines.items():  # every other entry shows its tier
        assert name in STALE or "sensing=" in line


def _cell(rate: float, episodes: int = 100, check: float | None = None) -> dict:
    res = {"success_rate": rate, "episodes": episodes}
    out = {"fingerprint": {"policy": "orca", "kwargs": {}, "sensing": "positions", "scenario": "x"}, "result": res}
    if check is not None:
        out["check"] = {"success_rate": check, "episodes": episodes}
    return out


def test_the_paper_report_pools_table_three_and_flags_disagreeing_ranges(tmp_path):
    from crowdbench.leaderboard import paper

    folder = tmp_path / "cells" / "orca"
    folder.mkdir(parents=True)
    cells = {"I-medium": _cell(0.9, check=0.5), "I-high": _cell(0.95, check=0.93)}
    for lay, rate in (("intersection", 0.6), ("split-flow", 0.7), ("random-wander", 0.8)):
        cells[f"III-{lay}-low"] = _cell(rate, check=rate)
    for name, c in cells.items():
        (folder / f"{name}.json").write_text(json.dumps(c))
    rows = {(r["table"], r["row"]): r for r in paper.compare(str(tmp_path))}
    assert rows[("I", "Medium")]["paper"] == 91 and rows[("I", "Medium")]["agree"] is False
    assert rows[("I", "High")]["agree"] is True
    pooled = rows[("III", "pooled Low")]
    assert pooled["ours"][0] == pytest.approx(0.7) and pooled["ours"][3] == 300 and pooled["paper"] == 72
    assert ("II", "N=10") not in rows  # no stored cell: no row
    text = paper.report(str(tmp_path))
    assert "I Medium" in text.split("disagree")[-1] and (tmp_path / "PAPER.md").exists()
