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
    v_pref = env.world.v_pref[0, 1]
    env.step({"robot": np.zeros(2), "human_0": np.array([0.4, -0.2])})  # normalised: the elliptical grid map
    want = v_pref * np.array([0.4 * np.sqrt(1 - 0.02), -0.2 * np.sqrt(1 - 0.08)])
    np.testing.assert_allclose(env.world.pos[0, 1] - before, want * 0.25)
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


@pytest.mark.parametrize("batched", [False, True])
def test_relative_by_id_in_a_crowd_larger_than_its_slots_lends_slots_that_follow_people(batched):
    """40 pedestrians, 8 slots: everyone in view is someone's slot while slots last (the nearest first), a person
    keeps their slot while in view, and people with an index beyond the slot count are seen too."""
    if batched:
        cfg = crowdbench.config.make_config(num_humans=40, max_humans_observed=8)
        world = crowdbench.worlds.CrowdWorld(cfg, 2, "circle_crossing", "orca")
        world.reset(seeds=[4, 5])
        builder = crowdbench.robots.make_observation("relative_by_id", cfg)
    else:
        env = crowdbench.parallel_env(num_humans=40, max_humans_observed=8, observation="relative_by_id")
        last, _ = env.reset(seed=4)
        world = env.world
    holder = {}
    high_ids = set()
    for t in range(30):
        o = builder.build(world) if batched else {k: v[None] for k, v in last["robot"].items()}
        for b in range(world.num_worlds):
            rel = world.pos[b, 1:] - world.pos[b, 0]
            surface = np.linalg.norm(rel, axis=1) - world.radius[b, 1:] - world.radius[b, 0]
            inside = np.flatnonzero(surface <= 5.0)
            held = o["mask"][b] > 0.5
            assert held.sum() == min(8, len(inside))
            who = [int(np.flatnonzero(np.all(np.abs(rel - o["humans"][b, s]) < 1e-5, axis=1))[0])
                   for s in np.flatnonzero(held)]
            assert set(who) <= set(inside.tolist())
            if len(inside) > 8:  # the nearest take the slots first, unless an earlier holder is still in view
                assert min(surface[inside]) in surface[who]
            for s, h in zip(np.flatnonzero(held), who, strict=True):
                if (b, h) in holder and h in inside and holder[(b, h)][1] == t - 1:
                    assert holder[(b, h)][0] == s  # kept its slot
                holder[(b, h)] = (s, t)
            high_ids |= {h for h in who if h >= 8}
        if batched:
            world.step(np.zeros((2, 2)))
        else:
            last, *_ = env.step({"robot": np.array([0.0, 0.0])})
    assert high_ids  # people beyond the first 8 indices are seen


def test_unknown_option_and_render_mode_errors():
    with pytest.raises(TypeError, match="unknown world option"):
        crowdbench.parallel_env(num_humen=3)
    with pytest.raises(ValueError, match="render_mode='human'; valid choices"):
        crowdbench.parallel_env(render_mode="human")
    with pytest.raises(ValueError, match="unknown robot observation 'x'"):
        crowdbench.parallel_env(observation="x")


# ---------------------------------------------------------------------------------------- multi-agent testbed
def test_pettingzoo_conventions_env_raw_env_and_api_tests():
    from pettingzoo.test import api_test, parallel_api_test

    api_test(crowdbench.env(num_humans=10), num_cycles=30)
    from pettingzoo import AECEnv

    assert isinstance(crowdbench.raw_env(num_humans=3), AECEnv)
    for kw in ({"flat_observations": True}, {"robot": None}, {"robot": "orca", "flat_observations": True},
               {"pedestrians_finish": True, "robot": None}):
        parallel_api_test(crowdbench.parallel_env(num_humans=8, **kw), num_cycles=40)


@pytest.mark.parametrize("how", ["pickle", "deepcopy"])
def test_a_restored_env_steps_to_the_same_observations(how):
    import copy
    import pickle

    env = crowdbench.parallel_env(num_humans=10, human_model="responsive_orca", robot=None)
    env.reset(seed=3)
    for _ in range(5):
        env.step({})
    twin = pickle.loads(pickle.dumps(env)) if how == "pickle" else copy.deepcopy(env)
    for _ in range(60):
        a, *_ = env.step({"human_2": np.array([0.5, -0.5])})
        b, *_ = twin.step({"human_2": np.array([0.5, -0.5])})
        for agent in a:
            for k in a[agent]:
                np.testing.assert_array_equal(a[agent][k], b[agent][k])
    np.testing.assert_array_equal(env.world.physics_positions(), twin.world.physics_positions())


def test_flat_observations_one_box_for_everyone_and_constant_agents():
    env = crowdbench.parallel_env(num_humans=6, flat_observations=True)
    obs, _ = env.reset(seed=1)
    spaces_ = {id(env.observation_space(a)) for a in env.possible_agents}
    assert len(spaces_) == 1 and {env.action_space(a).shape for a in env.possible_agents} == {(2,)}
    assert set(obs) == set(env.possible_agents) and obs["robot"].shape == (9 + 6 * 30,)
    crowd = crowdbench.parallel_env(num_humans=6, flat_observations=True, pedestrians_finish=True, robot=None,
                                    time_limit=60.0)
    crowd.reset(seed=1)
    agents, finished = list(crowd.agents), set()
    while crowd.agents:
        assert crowd.agents == agents  # constant until everyone is done
        earlier = set(finished)
        obs, rew, term, trunc, _ = crowd.step({})  # the pedestrian model walks them to their goals
        finished |= {a for a in crowd.agents if not obs[a].any()}
        assert all(rew[a] == 0.0 and not obs[a].any() for a in earlier & set(rew))
    assert len(finished) >= 3  # pedestrians finished one by one, then saw zeros


def test_normalised_actions_are_never_clipped_and_out_of_range_is_an_error():
    from crowdbench.envs.parallel import disc_velocity

    a = np.random.default_rng(0).uniform(-1, 1, (1000, 2))
    v = disc_velocity(a, np.ones(1000))
    assert (np.linalg.norm(v, axis=-1) <= 1 + 1e-12).all()
    np.testing.assert_allclose(np.linalg.norm(disc_velocity(np.array([[1.0, 1.0]]), np.ones(1)), axis=-1), 1.0)
    env = crowdbench.parallel_env(num_humans=3)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action for 'human_1'.*valid choices: two numbers in \\[-1, 1\\]"):
        env.step({"robot": np.zeros(2), "human_1": np.array([1.5, 0.0])})
    p0, vmax = env.world.pos[0, 2].copy(), env.world.v_pref[0, 2]
    env.step({"robot": np.zeros(2), "human_1": np.array([1.0, 1.0])})  # the corner: full speed, diagonal
    assert np.linalg.norm(env.world.pos[0, 2] - p0) == pytest.approx(vmax * 0.25)


def test_progress_reward_pays_walking_to_the_goal_more_than_walking_away():
    env = crowdbench.parallel_env(num_humans=4, robot=None, human_reward="progress")
    env.reset(seed=2)
    w = env.world
    to_goal = w.goal[0, 1] - w.pos[0, 1]
    toward = to_goal / np.abs(to_goal).max()
    _, r_to, _, _, info = env.step({"human_0": toward, "human_1": np.zeros(2)})
    env.reset(seed=2)
    _, r_away, _, _, _ = env.step({"human_0": -toward, "human_1": np.zeros(2)})
    assert r_to["human_0"] > 0 > r_away["human_0"]
    assert set(info["human_0"]["reward_terms"]) == {"progress", "goal", "collision", "intrusion", "time"}
    with pytest.raises(ValueError, match="unknown pedestrian reward 'fast'; valid choices: none, progress"):
        crowdbench.parallel_env(human_reward="fast")


def test_no_robot_and_max_cycles_mean_what_pettingzoo_says():
    env = crowdbench.parallel_env(num_humans=20, robot=None, max_cycles=400)
    obs, _ = env.reset(seed=0)
    assert "robot" not in env.possible_agents and "robot" not in obs
    steps = 0
    while env.agents:
        env.step({})
        steps += 1
    assert steps == 400  # not cut at the 50 s time limit
    with pytest.raises(ValueError, match="robot='drone'; valid choices: 'agent', None, or a registered robot"):
        crowdbench.parallel_env(robot="drone")


def test_supersuit_vectorises_the_flat_env_across_processes():
    ss = pytest.importorskip("supersuit")
    venv = ss.concat_vec_envs_v1(ss.pettingzoo_env_to_vec_env_v1(crowdbench.parallel_env(num_humans=10,
                                                                                          flat_observations=True)),
                                 2, num_cpus=2, base_class="gymnasium")
    obs, _ = venv.reset(seed=0)
    assert obs.shape == (22, 189)
    for _ in range(200):
        obs, rew, term, trunc, _ = venv.step(np.stack([venv.action_space.sample() for _ in range(venv.num_envs)]))
    assert np.isfinite(obs).all() and rew.shape == (22,)
    venv.close()


def test_finished_pedestrians_leave_and_the_others_keep_their_own_rewards():
    """With pedestrians leaving one by one, every remaining agent's progress term is its own (slot, not list
    position): the distance to its goal before the step minus after, from its own observations."""
    env = crowdbench.parallel_env(num_humans=8, robot=None, pedestrians_finish=True, time_limit=60.0)
    obs, _ = env.reset(seed=4)
    gone: set[str] = set()
    while env.agents:
        before = {a: obs[a]["self"].astype(np.float64) for a in env.agents}
        obs, rew, term, trunc, info = env.step({})
        for a, me in before.items():
            if term[a]:
                gone.add(a)
                assert not env.world.active[0, int(a.split("_")[1]) + 1]  # left the world
                continue
            if a in obs:
                p_after = obs[a]["self"][0:2].astype(np.float64)
                want = np.linalg.norm(me[4:6] - me[0:2]) - np.linalg.norm(me[4:6] - p_after)
                assert info[a]["reward_terms"]["progress"] == pytest.approx(want, abs=1e-5)
        assert not gone & set(env.agents)
    assert len(gone) >= 4


def _human_infos_before(humans, slots, crowd, terms):
    """``CrowdParallelEnv._human_infos`` as it was (rows stacked in numpy, one dict per agent in a loop): the
    oracle of the faster form."""
    n = len(humans)
    cnames, tnames = list(crowd), list(terms)
    crows = np.stack([crowd[k][0, slots] for k in cnames], 1).tolist() if cnames else [()] * n
    trows = np.stack([terms[k][0, slots] for k in tnames], 1).tolist() if tnames else None
    if trows is None:
        return {a: dict(zip(cnames, c, strict=True)) for a, c in zip(humans, crows, strict=True)}
    infos = {}
    for agent, c, t in zip(humans, crows, trows, strict=True):
        info = dict(zip(cnames, c, strict=True))
        info["reward_terms"] = dict(zip(tnames, t, strict=True))
        infos[agent] = info
    return infos


@pytest.mark.parametrize("model,reward", [("responsive_orca", "progress"), ("orca", "progress"),
                                          ("responsive_orca", "none"), ("orca", "none")])
def test_pedestrian_infos_are_what_they_were(model, reward):
    """The pedestrians' infos — the model's analysis values (mixed dtypes: floats and flags, given as the stacked
    rows' common type) and the reward terms — equal the former per-agent construction, keys and types included."""
    env = crowdbench.parallel_env(num_humans=6, human_model=model, human_reward=reward, seed=1)
    env.reset()
    for _ in range(3):
        w = env.world
        _, _, _, _, infos = env.step({"robot": np.array([0.4, 0.1]), "human_2": np.array([0.5, 0.5])})
        humans = [a for a in infos if a != "robot"]
        crowd = w.human_model.info()
        terms = {k: np.asarray([[infos[a]["reward_terms"][k] for a in humans]]) for k in
                 (infos[humans[0]].get("reward_terms") or {})}
        slots = np.arange(len(humans))
        want = _human_infos_before(humans, slots, crowd, terms)
        got = env._human_infos(humans, slots, crowd, terms)
        assert got == want
        assert [[type(v) for v in got[a].values()] for a in humans] == \
            [[type(v) for v in want[a].values()] for a in humans]
        assert {a: infos[a] for a in humans} == want
