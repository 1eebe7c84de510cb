"""The metrics module: intervals by hand, each social metric on a scripted scene, the pedestrians' delay against the
counterfactual run."""

from __future__ import annotations

import math

import numpy as np
import pytest

from crowdbench.config import make_config
from crowdbench.evaluation import run_episodes
from crowdbench.metrics import Episode, EpisodeMeter, bootstrap_mean, summarize, wilson
from crowdbench.policies import make_policy
from crowdbench.worlds import CrowdWorld


def test_wilson_interval_by_hand():
    lo, hi = wilson(0, 10)
    assert lo == 0.0 and hi == pytest.approx(0.2775, abs=1e-4)
    lo, hi = wilson(5, 10)
    assert (lo, hi) == (pytest.approx(0.2366, abs=1e-4), pytest.approx(0.7634, abs=1e-4))
    assert wilson(500, 500)[1] == 1.0 and wilson(500, 500)[0] == pytest.approx(0.99237, abs=1e-4)


def test_bootstrap_interval_holds_the_mean_and_narrows_with_more_data():
    rng = np.random.default_rng(1)
    small, big = rng.normal(10, 2, 20), rng.normal(10, 2, 2000)
    for x in (small, big):
        lo, hi = bootstrap_mean(x)
        assert lo < x.mean() < hi
    assert np.subtract(*bootstrap_mean(big)[::-1]) < np.subtract(*bootstrap_mean(small)[::-1]) / 5
    assert math.isnan(bootstrap_mean(np.array([1.0]))[0])


def test_summary_carries_intervals_and_social_means():
    eps = [Episode(0, "success", 10.0, 12.0, 1.0, intrusions_unaware=3, intrusions_aware=1),
           Episode(1, "collision", 3.0, 3.0, 0.5, intrusions_unaware=0, intrusions_aware=0)]
    s = summarize(eps)
    assert s["ci"]["success_rate"] == list(wilson(1, 2))
    assert s["unaware_share"] == 0.75 and s["intrusions_unaware"] == 1.5
    assert math.isnan(s["ci"]["nav_time"][0])  # one successful episode: no interval


def scripted(human_pos, human_vel, robot_vel=(0.0, 1.0)):
    """One world, robot at the origin heading for (0, 10), one linear pedestrian."""
    cfg = make_config(num_humans=1, human_radius_range=None, human_v_pref_range=None)
    world = CrowdWorld(cfg, 1, "circle_crossing", "linear")
    world.set_agents(0, positions=np.array([[0.0, 0.0], human_pos]), velocities=np.array([robot_vel, human_vel]),
                     goals=np.array([[0.0, 10.0], np.add(human_pos, np.multiply(human_vel, 100.0))]))
    meter = EpisodeMeter(1, world.dt, cfg.reward.goal_tolerance)
    meter.start(np.array([0]), world)
    return world, meter


def step(world, meter, action=(0.0, 1.0)):
    prev = (world.pos.copy(), world.vel[:, 0].copy(), world.goal.copy())
    res = world.step(np.array([action]))
    meter.update(world, res, prev[0], prev[1], prev[2])
    return res


def test_time_to_collision_distance_and_personal_space_on_a_head_on_approach():
    world, meter = scripted((0.0, 4.0), (0.0, -1.0))
    step(world, meter)
    # after one step: 3.5 m apart, closing at 2 m/s, radii 0.3 + 0.3
    assert meter.min_ttc[0] == pytest.approx((3.5 - 0.6) / 2, abs=1e-9)
    assert meter.min_distance[0] == pytest.approx(3.5 - 0.6, abs=1e-9)
    m = meter.episode(0, "timeout", 0.25)
    assert m["personal_space"] == 1.0 and m["intrusions_unaware"] == 0.0
    for _ in range(6):
        step(world, meter)
    m = meter.episode(0, "timeout", 7 * 0.25)
    assert m["personal_space"] < 1.0 and m["intrusions_unaware"] >= 1  # the linear pedestrian has no ξ: unaware


def test_straight_run_has_no_irregularity_and_full_spl_and_a_turn_has_both():
    world, meter = scripted((8.0, 8.0), (0.0, 0.0), robot_vel=(0.0, 0.0))
    for _ in range(8):
        step(world, meter)
    m = meter.episode(0, "success", 2.0)
    assert m["irregularity"] == pytest.approx(0.0, abs=1e-6)
    assert m["spl"] == pytest.approx(1.0)  # ℓ = 10 − 0.3 m > path: capped at 1
    assert m["jerk"] == pytest.approx(16.0 / 7)  # one jump from rest (a: 4 → 0 m/s² in 0.25 s), then constant
    world, meter = scripted((8.0, 8.0), (0.0, 0.0), robot_vel=(0.0, 0.0))
    step(world, meter, (1.0, 0.0))  # sideways: 90° off the goal direction
    m = meter.episode(0, "timeout", 0.25)
    assert m["irregularity"] == pytest.approx(math.pi / 2, abs=1e-6) and m["spl"] == 0.0


def test_intrusions_are_split_by_the_latent_state():
    world, meter = scripted((0.0, 0.7), (1.0, 0.0), robot_vel=(0.0, 0.0))  # walks past within 0.5 m
    world.human_model.info = lambda: {"xi": np.array([[True]])}
    step(world, meter, (0.0, 0.0))
    assert (meter.aware[0], meter.unaware[0]) == (1.0, 0.0)
    world.human_model.info = lambda: {"xi": np.array([[False]])}
    step(world, meter, (0.0, 0.0))
    assert (meter.aware[0], meter.unaware[0]) == (1.0, 1.0)


def test_pedestrian_delay_is_near_zero_when_nobody_responds_and_positive_when_everyone_does():
    """Nobody responds: the only trace of the robot is that re-spawns and goal changes keep clear of it (CrowdNav++'s
    placement checks the robot too), so the delay is near zero — exactly zero with the calibrated crowd's rules."""
    kw = dict(episodes=12, num_worlds=12, num_humans=10, counterfactual=True)
    blind = run_episodes(make_policy("linear"), human_model_kwargs={"responsiveness": 0.0, "spread": 0.0}, **kw)
    assert abs(summarize(blind)["ped_delay"]) < 0.01
    calibrated = run_episodes(make_policy("linear"), layout="circle_crossing_calibrated",
                              human_model_kwargs={"responsiveness": 0.0, "spread": 0.0}, **kw)
    assert summarize(calibrated)["ped_delay"] == 0.0
    seen = run_episodes(make_policy("linear"), human_model_kwargs={"responsiveness": 1.0, "spread": 0.0}, **kw)
    assert summarize(seen)["ped_delay"] > 0.0
    plain = run_episodes(make_policy("linear"), 12, num_worlds=12, num_humans=10,
                         human_model_kwargs={"responsiveness": 1.0, "spread": 0.0})
    assert [e.outcome for e in plain] == [e.outcome for e in seen]  # the twin does not change the episodes
    assert all(math.isnan(e.ped_progress_alone) for e in plain)
