"""PettingZoo and Gymnasium adapters: conformance, multi-step determinism, the external-driving contract."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test

import crowdbench
from crowdbench.envs.gym_env import LAYOUT_IDS


def test_parallel_api_test_passes():
    env = crowdbench.parallel_env(num_humans=6, human_model="responsive_orca")
    parallel_api_test(env, num_cycles=300)


def test_parallel_api_test_variable_crowd():
    env = crowdbench.parallel_env(num_humans=8, humans_range=(2, 8), human_model="social_force")
    parallel_api_test(env, num_cycles=100)


@pytest.mark.parametrize("name", LAYOUT_IDS.values())
def test_check_env_every_layout(name):
    env = gymnasium.make(f"crowdbench/{name}-v0", num_humans=10)
    check_env(env.unwrapped)
    env.close()


def test_gym_make_default_and_kwargs():
    env = gymnasium.make("crowdbench/CircleCrossing-v0", num_humans=20)
    obs, info = env.reset(seed=3)
    assert obs["humans"].shape == (30, 2) and obs["robot"].shape == (9,)
    assert obs["mask"].sum() <= 20
    obs, r, term, trunc, info = env.step(env.action_space.sample())
    assert set(info["reward_terms"]) == {"success", "collision", "discomfort", "progress", "time"}
    assert r == pytest.approx(sum(info["reward_terms"].values()))


def _rollout_parallel(seed, steps=200):
    env = crowdbench.parallel_env(num_humans=12, human_model="responsive_orca", time_limit=1e9)
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(steps):
        acts = {a: rng.uniform(-1, 1, 2) for a in env.agents if a in ("robot", "human_0", "human_1")}
        obs, rew, term, trunc, info = env.step(acts)
        out.append((obs["robot"]["humans"].copy(), rew["robot"], env.state(), info["robot"]["crowd"]["xi"]))
        if not env.agents:
            obs, _ = env.reset(seed=int(rng.integers(1 << 30)))
    return out


def test_same_seed_identical_200_step_rollouts():
    a, b = _rollout_parallel(11), _rollout_parallel(11)
    for x, y in zip(a, b, strict=True):
        for u, v in zip(x, y, strict=True):
            np.testing.assert_array_equal(u, v)
    c = _rollout_parallel(12)
    assert any(not np.array_equal(x[2], y[2]) for x, y in zip(a, c, strict=True))


def test_gym_and_pettingzoo_start_the_same_episode():
    g = gymnasium.make("crowdbench/SquareCrossing-v0", num_humans=7, human_model="orca").unwrapped
    p = crowdbench.parallel_env(layout="square_crossing", num_humans=7, human_model="orca")
    og, _ = g.reset(seed=5)
    op, _ = p.reset(seed=5)
    for k in og:
        np.testing.assert_array_equal(og[k], op["robot"][k])
    for _ in range(30):
        og, rg, *_ = g.step(np.array([0.2, 0.9]))
        op, rp, *_ = p.step({"robot": np.array([0.2, 0.9])})
        assert rg == rp["robot"]


def test_driven_pedestrian_follows_its_action_others_follow_the_model():
    env = crowdbench.parallel_env(num_humans=5, human_model="orca", time_limit=1e9)
    env.reset(seed=0)
    ref = crowdbench.parallel_env(num_humans=5, human_model="orca", time_limit=1e9)
    ref.reset(seed=0)
    before = env.world.pos[0, 1].copy()
    env.step({"robot": np.zeros(2), "human_0": np.array([0.4, -0.2])})
    np.testing.assert_allclose(env.world.pos[0, 1] - before, np.array([0.4, -0.2]) * 0.25)
    ref.step({"robot": np.zeros(2)})
    assert not np.allclose(env.world.pos[0, 1], ref.world.pos[0, 1])


def test_robot_action_required_and_unknown_agent_rejected():
    env = crowdbench.parallel_env(num_humans=3)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="actions must include 'robot'"):
        env.step({"human_0": np.zeros(2)})
    with pytest.raises(ValueError, match="not a live agent"):
        env.step({"robot": np.zeros(2), "human_9": np.zeros(2)})


def test_episode_end_removes_everyone():
    env = crowdbench.parallel_env(num_humans=3, time_limit=1.0)
    env.reset(seed=0)
    for _ in range(4):
        _, _, term, trunc, info = env.step({"robot": np.zeros(2)})
    assert env.agents == [] and trunc["robot"] and not term["robot"] and all(trunc.values())
    assert info["robot"]["outcome"] == "timeout"


def test_rgb_array_frames():
    env = crowdbench.parallel_env(num_humans=5, render_mode="rgb_array")
    env.reset(seed=0)
    env.step({"robot": np.array([0.0, 1.0])})
    frame = env.render()
    assert frame.dtype == np.uint8 and frame.shape == (480, 480, 3) and frame.std() > 0
    g = gymnasium.make("crowdbench/CircleCrossing-v0", num_humans=5, render_mode="rgb_array")
    g.reset(seed=0)
    assert g.render().shape == (480, 480, 3)


def test_full_state_observation():
    env = crowdbench.parallel_env(num_humans=4, observation="full_state")
    obs, _ = env.reset(seed=0)
    h = obs["robot"]["humans"]
    assert h.shape == (30, 5) and obs["robot"]["mask"].sum() == 4
    # the radius column holds the episode's drawn radii (rows sorted by distance)
    np.testing.assert_allclose(np.sort(h[:4, 4]), np.sort(env.world.radius[0, 1:5]), atol=1e-6)
    assert ((h[:4, 4] >= 0.3) & (h[:4, 4] <= 0.5)).all()


def test_relative_by_id_observation_keeps_each_pedestrian_in_its_slot():
    """Slot j is pedestrian j at every step: its relative position while within 5 m surface to surface (CrowdNav++'s
    sensing), zero and masked otherwise — and the same entries as the nearest-first observation, permuted."""
    env = crowdbench.parallel_env(num_humans=12, observation="relative_by_id")
    sorted_obs = crowdbench.robots.make_observation("relative", env.config)
    obs, _ = env.reset(seed=3)
    seen = set()
    for _ in range(40):
        w = env.world
        rel = w.pos[0, 1:13] - w.pos[0, 0]
        inside = np.linalg.norm(rel, axis=1) - w.radius[0, 1:13] - w.radius[0, 0] <= 5.0
        o = obs["robot"]
        np.testing.assert_array_equal(o["mask"][:12], inside.astype(np.float32))
        np.testing.assert_allclose(o["humans"][:12][inside], rel[inside], atol=1e-5)
        assert not o["humans"][:12][~inside].any() and not o["mask"][12:].any()
        s = sorted_obs.build(w)
        assert sorted(map(tuple, o["humans"][o["mask"] > 0])) == sorted(map(tuple, s["humans"][0][s["mask"][0] > 0]))
        seen |= set(np.flatnonzero(inside))
        obs, *_ = env.step({"robot": np.array([0.0, 0.0])})
    assert len(seen) >= 3  # several people came into view


def test_unknown_option_and_render_mode_errors():
    with pytest.raises(TypeError, match="unknown world option"):
        crowdbench.parallel_env(num_humen=3)
    with pytest.raises(ValueError, match="render_mode='human'; valid choices"):
        crowdbench.parallel_env(render_mode="human")
    with pytest.raises(ValueError, match="unknown robot observation 'x'"):
        crowdbench.parallel_env(observation="x")
