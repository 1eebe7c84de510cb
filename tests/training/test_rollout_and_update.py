"""The one rollout and the one update change nothing but speed: sharded worlds (fork or spawn), world processes that
act, the per-thread PPO update against rsl-rl's own ``PPO.update``."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import torch
from rsl_rl.algorithms import PPO

from crowdbench.config import make_config
from crowdbench.training.config import TrainConfig
from crowdbench.training.curriculum import Curriculum
from crowdbench.training.rollout import PolicySnapshot, collect
from crowdbench.training.shards import ShardedWorlds, ShardSpec
from crowdbench.training.threads import trajectory_shares
from crowdbench.training.trainer import Trainer
from crowdbench.training.vecenv import CrowdVecEnv

SMALL = {"d_model": 16, "heads": 2, "ffn": 16, "gru_hidden": 16, "head_dims": (16,)}


def small(**kw) -> TrainConfig:
    base = dict(num_envs=16, steps_per_env=40, model=SMALL, humans_range=(15, 25), eval_every=0)
    return TrainConfig(**{**base, **kw})


def _rollout(processes: int, steps: int = 150, start_method: str | None = None) -> tuple[list, int]:
    env = CrowdVecEnv(24, seed=3, processes=processes, humans_range=(10, 30), start_method=start_method,
                      curriculum=Curriculum(window=20, cooldown=20, eta=2.0))  # records outcomes, never lowers ρ
    g = torch.Generator().manual_seed(0)
    out = []
    try:
        for _ in range(steps):
            obs, rew, done, extras = env.step(torch.randn(24, 2, generator=g))
            full = env.get_observations()
            assert all(torch.equal(full[k], obs[k]) for k in ("robot", "humans", "mask"))
            out.append((obs["robot"].clone(), obs["humans"].clone(), obs["mask"].clone(), rew.clone(), done.clone(),
                        extras["time_outs"].clone(), env.episode_length_buf.clone()))
    finally:
        env.close()
    return out, env.episodes


@pytest.mark.parametrize(("processes", "start_method"), [(3, None), (2, "spawn")])
def test_sharded_worlds_give_identical_rollouts(processes, start_method):
    one, eps1 = _rollout(1)
    other, eps2 = _rollout(processes, start_method=start_method)
    assert eps1 == eps2 > 10  # episodes ended and restarted (same-step auto-reset, fresh seeds) during the rollout
    for a, b in zip(one, other, strict=True):
        for x, y in zip(a, b, strict=True):
            assert torch.equal(x, y)


def test_curriculum_does_not_depend_on_batching():
    rng = np.random.default_rng(0)
    outcomes = rng.random(3000) < 0.93
    whole, parts = Curriculum(window=50, cooldown=50), Curriculum(window=50, cooldown=50)
    whole.record(outcomes, len(outcomes))
    total = 0
    for chunk in np.array_split(outcomes, 137):
        total += len(chunk)
        parts.record(chunk, total)
    assert whole.changes == parts.changes and len(whole.changes) == 8 and whole.rho == 0.0


def test_shard_worker_errors_are_reported():
    spec = ShardSpec(make_config(), 4, "circle_crossing", "responsive_orca", {"responsiveness": 0.5})
    worlds = ShardedWorlds(spec, shards=2)
    try:
        with pytest.raises(RuntimeError, match="worker failed"):  # the worker's traceback is raised here
            worlds.call("step", [(np.zeros((2, 2)), np.zeros(2, dtype=np.int64), None), (None, None, None)])
    finally:
        worlds.close()
    with pytest.raises(ValueError, match="shards"):
        ShardedWorlds(spec, shards=5)
    with pytest.raises(ValueError, match="start_method='nope'; valid choices"):
        ShardedWorlds(spec, shards=2, start_method="nope")


def _stored(tr: Trainer) -> dict[str, torch.Tensor]:
    st = tr.alg.storage
    return {"obs": st.observations["humans"].clone(), "actions": st.actions.clone(), "rewards": st.rewards.clone(),
            "dones": st.dones.clone(), "values": st.values.clone(), "logp": st.actions_log_prob.clone(),
            "mu": st.distribution_params[0].clone(), "hidden": st.saved_hidden_state_a[0].clone(),
            "h": tr.alg.actor.rnn.hidden_state.clone()}


@pytest.mark.parametrize("start_method", [None, "spawn"])
def test_world_processes_act_as_the_trainers_policy_for_any_process_count(tmp_path, start_method, monkeypatch):
    """The stored transitions are the same for 1 and 2 world processes (fork, or spawn as on macOS), and every
    stored value, mean and log-probability is what the training process's own network gives for the stored
    observation and recurrent state (the snapshot is exact, recurrent states carry over and reset)."""
    import crowdbench.training.trainer as trainer_module

    if start_method:  # the trainer builds its env with the default start method: force spawn for this test
        real = trainer_module.CrowdVecEnv
        monkeypatch.setattr(trainer_module, "CrowdVecEnv", lambda *a, **k: real(*a, start_method=start_method, **k))
    stores = []
    for processes in (1, 2):
        tr = Trainer(small(env_processes=processes, threads=1), str(tmp_path / str(processes)), quiet=True)
        try:
            torch.manual_seed(5)
            tr.env.episode_length_buf[:] = torch.arange(150, 198, 3)  # time-outs and restarts inside the rollout
            with torch.inference_mode():
                snap = PolicySnapshot.of(tr.alg, tr.build)
                collect(tr.alg, tr.env, tr.env.get_observations(), 20, snap)  # states carry over
                tr.alg.storage.clear()
                collect(tr.alg, tr.env, tr.env.get_observations(), 20, snap)
            st = tr.alg.storage
            stores.append(_stored(tr))
            ended = st.dones[:-1, :, 0].bool()  # an episode ended at step t: its world starts t + 1 from zero
            assert ended.any() and st.saved_hidden_state_a[0][1:][:, 0][ended].abs().max() == 0
            actor, critic = tr.alg.actor, tr.alg.critic
            with torch.inference_mode():
                for t in range(20):
                    actor.rnn.hidden_state = st.saved_hidden_state_a[0][t].clone()
                    o = st.observations[t]
                    actor(o, stochastic_output=True)
                    assert torch.allclose(actor.output_mean, st.distribution_params[0][t], atol=1e-5)
                    assert torch.allclose(critic(o), st.values[t], atol=1e-5)
                    logp = actor.get_output_log_prob(st.actions[t])
                    assert torch.allclose(logp, st.actions_log_prob[t].squeeze(-1), atol=1e-4)
        finally:
            tr.close()
    a, b = stores
    assert a["dones"].sum() >= 3, int(a["dones"].sum())
    assert a["hidden"].abs().sum() > 0
    for key in a:
        assert torch.allclose(a[key], b[key], atol=1e-5), key


@pytest.mark.parametrize("threads", [1, 2])
def test_per_thread_ppo_update_equals_rsl_rl_update(tmp_path, threads):
    """SharedTrunkPPO.update (forward, PPO losses and backward per thread; inline for one thread) leaves the
    networks, the optimiser, the adaptive learning rate and the reported losses as rsl-rl's PPO.update does, to
    float rounding."""
    tr = Trainer(small(env_processes=1, threads=threads, mini_batches=2, epochs=2, desired_kl=1e-4),
                 str(tmp_path), quiet=True)  # a tiny KL target: the learning rate adapts within the update
    try:
        alg = tr.alg
        tr.env.episode_length_buf[:] = torch.arange(150, 198, 3)  # time-outs: several trajectories per world
        with torch.inference_mode():
            obs, _, _ = collect(alg, tr.env, tr.env.get_observations(), 40, PolicySnapshot.of(alg, tr.build))
            alg.compute_returns(obs)
        batch = next(alg.storage.recurrent_mini_batch_generator(2, 1))
        assert batch.masks.shape[1] > 8  # more trajectories than the mini-batch's 8 worlds
        trajs, envs = trajectory_shares(batch.masks, torch.ones(batch.masks.shape[1]), 2)
        assert sorted(torch.cat(envs).tolist()) == list(range(8))
        assert sorted(torch.cat(trajs).tolist()) == list(range(batch.masks.shape[1]))
        trajs, envs = trajectory_shares(batch.masks, torch.ones(batch.masks.shape[1]), 12)  # more threads than worlds
        assert len(envs) == len(trajs) == 8 and all(e.numel() == 1 for e in envs)
        assert sorted(torch.cat(trajs).tolist()) == list(range(batch.masks.shape[1]))
        start = copy.deepcopy((alg.actor.state_dict(), alg.critic.state_dict(), alg.optimizer.state_dict(),
                               alg.learning_rate, alg.storage))
        before = [p.detach().clone() for p in (*alg.actor.parameters(), *alg.critic.parameters())]
        results = []
        for update in (type(alg).update, PPO.update):
            alg.actor.load_state_dict(start[0])
            alg.critic.load_state_dict(start[1])
            alg.optimizer.load_state_dict(start[2])
            alg.learning_rate = start[3]
            for group in alg.optimizer.param_groups:
                group["lr"] = start[3]
            alg.storage = copy.deepcopy(start[4])
            losses = update(alg)
            results.append((losses, alg.learning_rate, [p.detach().clone() for p in alg.actor.parameters()]
                            + [p.detach().clone() for p in alg.critic.parameters()]))
        (l1, lr1, p1), (l2, lr2, p2) = results
        assert lr1 == lr2 != start[3]
        for key in ("value", "surrogate", "entropy"):
            assert abs(l1[key] - l2[key]) <= 1e-5 * max(1.0, abs(l2[key])), key
        assert max(float((a - b).abs().max()) for a, b in zip(p2, before, strict=True)) > 1e-4  # it did learn
        for a, b in zip(p1, p2, strict=True):
            assert torch.allclose(a, b, atol=1e-5), (a - b).abs().max()
    finally:
        tr.close()


def test_unsupported_ppo_settings_fail_clearly():
    from crowdbench.training.ppo import check_gaussian

    class NotGaussian:
        pass

    with pytest.raises(ValueError, match="valid choices: GaussianDistribution"):
        check_gaussian(NotGaussian())


def test_dead_worker_and_bad_speed_settings_fail_clearly():
    spec = ShardSpec(make_config(), 4, "circle_crossing", "responsive_orca", {"responsiveness": 0.5})
    worlds = ShardedWorlds(spec, shards=2, local=False)
    try:
        worlds.procs[1].kill()
        worlds.procs[1].join()
        with pytest.raises(RuntimeError, match="exited unexpectedly"):
            worlds.send(1, "step", np.zeros((2, 2)), np.zeros(2, dtype=np.int64), 0.5)
            worlds.wait(1)
    finally:
        worlds.close()
    for bad in ({"threads": 0}, {"env_processes": 0}, {"epochs": 0}, {"env_processes": 300}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            TrainConfig(**bad)
