"""The training speed-ups change nothing but speed: sharded worlds, data-parallel threads, robot-only last stage."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from tensordict import TensorDict

from crowdbench.config import make_config
from crowdbench.policies.h2int_net import VARIANTS, H2INTActor, H2INTEncoder
from crowdbench.training.rollout import collect
from crowdbench.training.shards import ShardedWorlds, ShardSpec
from crowdbench.training.vecenv import CrowdVecEnv, Curriculum


def _rollout(processes: int, steps: int = 150, pipelined: bool = False) -> tuple[list, float, int]:
    env = CrowdVecEnv(24, seed=3, processes=processes, humans_range=(10, 30),
                      curriculum=Curriculum(window=20, cooldown=20, eta=2.0))  # records outcomes, never lowers ρ
    g = torch.Generator().manual_seed(0)
    out = []
    try:
        for _ in range(steps):
            actions = torch.randn(24, 2, generator=g)
            if pipelined:  # group by group, as the pipelined collector does
                parts = []
                for k, sl in enumerate(env.groups):
                    env.step_async(k, actions[sl])
                    parts.append(env.step_wait(k))
                obs = torch.cat([p[0] for p in parts], 0)
                rew, done = torch.cat([p[1] for p in parts]), torch.cat([p[2] for p in parts])
                time_outs = torch.cat([p[3]["time_outs"] for p in parts])
            else:
                obs, rew, done, extras = env.step(actions)
                time_outs = extras["time_outs"]
            full = env.get_observations()
            assert all(torch.equal(full[k], obs[k]) for k in ("robot", "humans", "mask"))
            out.append((obs["robot"].clone(), obs["humans"].clone(), obs["mask"].clone(), rew.clone(), done.clone(),
                        time_outs.clone(), env.episode_length_buf.clone()))
    finally:
        env.close()
    return out, env.curriculum.rho, env.episodes


@pytest.mark.parametrize(("processes", "pipelined"), [(3, False), (2, True)])
def test_sharded_worlds_give_identical_rollouts(processes, pipelined):
    one, _, eps1 = _rollout(1)
    other, _, eps2 = _rollout(processes, pipelined=pipelined)
    assert eps1 == eps2 > 10  # episodes ended and restarted (same-step auto-reset, fresh seeds) during the rollout
    for a, b in zip(one, other, strict=True):
        for x, y in zip(a, b, strict=True):
            assert torch.equal(x, y)


def test_curriculum_does_not_depend_on_batching():
    import numpy as np

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


def test_pipelined_collection_writes_the_same_transitions():
    """The pipelined collector fills rsl-rl's storage as the synchronous alg.act/env.step loop does."""
    from crowdbench.training.train import TrainConfig, Trainer

    stores = []
    for processes in (1, 2):
        cfg = TrainConfig(num_envs=16, steps_per_env=60, d_model=16, heads=2, ffn=16, gru_hidden=16,
                          head_dims=(16,), humans_range=(15, 25), eval_every=0, env_processes=processes, threads=1)
        tr = Trainer(cfg, "/tmp/crowdbench-test-pipeline", quiet=True)
        try:
            torch.manual_seed(5)
            # start the episodes late (as rsl-rl's init_at_random_ep_len does): time-outs and restarts happen
            tr.env.episode_length_buf[:] = torch.arange(150, 198, 3)
            with torch.inference_mode():
                obs, _, _ = collect(tr.alg, tr.env, tr.env.get_observations(), cfg.steps_per_env)
            st = tr.alg.storage
            stores.append({"obs": st.observations["humans"].clone(), "actions": st.actions.clone(),
                           "rewards": st.rewards.clone(), "dones": st.dones.clone(), "values": st.values.clone(),
                           "logp": st.actions_log_prob.clone(), "hidden": st.saved_hidden_state_a[0].clone(),
                           "last": obs["robot"].clone(), "h": tr.alg.actor.rnn.hidden_state.clone()})
        finally:
            tr.close()
    a, b = stores
    assert a["dones"].sum() >= 3, int(a["dones"].sum())
    for key in a:
        assert torch.allclose(a[key], b[key], atol=1e-5), key


def test_worker_acting_is_the_trainers_policy_for_any_process_count(tmp_path):
    """With the world processes acting, the stored transitions are the same for 1 and 2 processes, and every
    stored value, mean and log-probability is what the training process's own network gives for the stored
    observation and recurrent state (the policy snapshot is exact, recurrent states carry over and reset)."""
    from crowdbench.training.train import TrainConfig, Trainer

    stores = []
    for processes in (1, 2):
        cfg = TrainConfig(num_envs=16, steps_per_env=40, d_model=16, heads=2, ffn=16, gru_hidden=16,
                          head_dims=(16,), humans_range=(15, 25), eval_every=0, env_processes=processes, threads=1)
        assert cfg.worker_acting
        tr = Trainer(cfg, str(tmp_path / str(processes)), quiet=True)
        try:
            torch.manual_seed(5)
            tr.env.episode_length_buf[:] = torch.arange(150, 198, 3)  # time-outs and restarts inside the rollout
            with torch.inference_mode():
                collect(tr.alg, tr.env, tr.env.get_observations(), 20, worker_acting=True)  # states carry over
                tr.alg.storage.clear()
                obs, _, _ = collect(tr.alg, tr.env, tr.env.get_observations(), 20, worker_acting=True)
            st = tr.alg.storage
            stores.append({"obs": st.observations["humans"].clone(), "actions": st.actions.clone(),
                           "rewards": st.rewards.clone(), "dones": st.dones.clone(), "values": st.values.clone(),
                           "logp": st.actions_log_prob.clone(), "mu": st.distribution_params[0].clone(),
                           "hidden": st.saved_hidden_state_a[0].clone(), "h": tr.alg.actor.rnn.hidden_state.clone()})
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


def test_per_thread_ppo_update_equals_rsl_rl_update(tmp_path):
    """crowdbench.policies.parallel_ppo (forward, PPO losses and backward per thread) leaves the networks, the
    optimiser, the adaptive learning rate and the reported losses as rsl-rl's PPO.update does, to float rounding."""
    import copy

    from crowdbench.policies import parallel_ppo
    from crowdbench.policies.parallel import trajectory_shares
    from crowdbench.training.train import TrainConfig, Trainer

    cfg = TrainConfig(num_envs=16, steps_per_env=40, d_model=16, heads=2, ffn=16, gru_hidden=16, head_dims=(16,),
                      humans_range=(15, 25), eval_every=0, env_processes=1, threads=2, mini_batches=2, epochs=2,
                      desired_kl=1e-4)  # a tiny KL target: the learning rate adapts within the update
    tr = Trainer(cfg, str(tmp_path), quiet=True)
    try:
        alg = tr.alg
        tr.env.episode_length_buf[:] = torch.arange(150, 198, 3)  # time-outs: several trajectories per world
        with torch.inference_mode():
            obs, _, _ = collect(alg, tr.env, tr.env.get_observations(), cfg.steps_per_env)
            alg.compute_returns(obs)
        assert parallel_ppo.applies(alg)
        batch = next(alg.storage.recurrent_mini_batch_generator(2, 1))
        assert batch.masks.shape[1] > 8  # more trajectories than the mini-batch's 8 worlds
        trajs, envs = trajectory_shares(batch.masks, torch.ones(batch.masks.shape[1]), 2)
        assert sorted(torch.cat(envs).tolist()) == list(range(8))
        assert sorted(torch.cat(trajs).tolist()) == list(range(batch.masks.shape[1]))
        start = copy.deepcopy((alg.actor.state_dict(), alg.critic.state_dict(), alg.optimizer.state_dict(),
                               alg.learning_rate, alg.storage))
        before = [p.detach().clone() for p in (*alg.actor.parameters(), *alg.critic.parameters())]
        results = []
        for parallel in (True, False):
            alg.actor.load_state_dict(start[0])
            alg.critic.load_state_dict(start[1])
            alg.optimizer.load_state_dict(start[2])
            alg.learning_rate = start[3]
            for group in alg.optimizer.param_groups:
                group["lr"] = start[3]
            alg.storage = copy.deepcopy(start[4])
            alg.parallel_update = parallel
            losses = alg.update()
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


def _batch(n: int = 512, n_max: int = 30, seed: int = 0):
    g = torch.Generator().manual_seed(seed)
    robot = torch.randn(n, 9, generator=g)
    edges = torch.randn(n, n_max, 2, generator=g) * 3
    seen = torch.randint(0, n_max + 1, (n,), generator=g)
    valid = torch.arange(n_max)[None] < seen[:, None]  # sorted by distance: padding at the end
    return robot, edges, valid


@pytest.mark.parametrize("variant", VARIANTS)
def test_data_parallel_threads_match_one_thread(variant):
    robot, edges, valid = _batch()
    obs = TensorDict({"robot": robot, "humans": edges, "mask": valid.float()}, batch_size=[len(robot)])
    torch.manual_seed(0)
    actor = H2INTActor(obs, {"actor": ["robot"]}, "actor", 2, variant=variant)
    results = []
    for threads in (1, 2):
        actor.threads = threads
        actor.zero_grad()
        z = actor.bucketed(robot, edges, valid)
        (z.square().sum() + z[:, 0].sum()).backward()
        results.append((z.detach(), [p.grad.clone() for p in actor.encoder.parameters() if p.grad is not None]))
        with torch.inference_mode():  # a large inference batch takes the threaded path too
            big = [torch.cat([t] * 2) for t in (robot, edges, valid)]
            assert torch.allclose(actor.bucketed(*big)[: len(robot)], z.detach(), atol=1e-6)
    (z1, g1), (z2, g2) = results
    assert torch.allclose(z1, z2, atol=1e-6)  # grouping changes only the padding, i.e. kernel rounding
    assert len(g1) == len(g2) > 10
    for a, b in zip(g1, g2, strict=True):
        # float32 sums over 512 samples in another order: equal to a relative 1e-5 of the gradient's norm
        assert (a - b).norm() <= 1e-5 * a.norm() + 1e-7


@pytest.mark.parametrize("variant", VARIANTS)
def test_robot_only_last_stage_equals_full_stage(variant):
    """The last stage computes only the robot token; a full pass over every token gives the same robot output."""
    robot, edges, valid = _batch(64)
    torch.manual_seed(1)
    enc = H2INTEncoder(30, variant)
    z = enc(robot, edges, valid)
    # reference: the same computation with every stage over all tokens, robot token taken at the end
    phi_r = enc.robot_mlp(enc.robot_norm(robot)).unsqueeze(1)
    x = torch.cat([phi_r, enc.edge_mlp(edges / enc.edge_scale)], 1) + enc.type_emb(enc.types) + enc.pos_emb(
        enc.positions)
    tok = torch.cat([valid.new_ones((len(robot), 1)), valid], 1)
    for stage in enc.stages:
        x = stage(x, tok)
    assert torch.allclose(z, enc.final_ln(x[:, 0]), atol=1e-5)


def test_scripted_inference_follows_training_updates():
    """Rollouts use a TorchScript copy of the encoder; it must see in-place optimiser steps and the normaliser's
    replaced buffers, and must not add keys to checkpoints."""
    robot, edges, valid = _batch(256)
    obs = TensorDict({"robot": robot, "humans": edges, "mask": valid.float()}, batch_size=[len(robot)])
    actor = H2INTActor(obs, {"actor": ["robot"]}, "actor", 2)
    keys = set(actor.state_dict())
    with torch.inference_mode():
        actor.bucketed(robot, edges, valid)  # builds the scripted encoder
    actor.encoder.robot_norm._std = actor.encoder.robot_norm._std * 2  # EmpiricalNormalization.update replaces it
    with torch.no_grad():
        for p in actor.encoder.parameters():
            p.mul_(1.1)  # optimiser steps are in place
    with torch.inference_mode():
        scripted = actor.bucketed(robot, edges, valid)
    eager = actor.bucketed(robot, edges, valid).detach()  # grad mode: the eager encoder
    assert torch.allclose(scripted, eager, atol=1e-5)
    assert set(actor.state_dict()) == keys


def test_dead_worker_and_bad_speed_settings_fail_clearly():
    from crowdbench.training.train import TrainConfig

    spec = ShardSpec(make_config(), 4, "circle_crossing", "responsive_orca", {"responsiveness": 0.5})
    worlds = ShardedWorlds(spec, shards=2, local=False)
    try:
        worlds.procs[1].kill()
        worlds.procs[1].join()
        with pytest.raises(RuntimeError, match="exited unexpectedly"):
            worlds.send_step(1, np.zeros((2, 2)), np.zeros(2, dtype=np.int64), 0.5)
            worlds.wait(1)
    finally:
        worlds.close()
    for bad in ({"threads": 0}, {"env_processes": 0}, {"epochs": 0}, {"env_processes": 300}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            TrainConfig(**bad)


def test_bucket_partition_is_optimal_and_covers_the_batch():
    """Groups are contiguous in the sorted order, cover every sample, respect the cap, and cost no more than every
    other contiguous split (brute force over all splits of small batches)."""
    import itertools

    from crowdbench.policies.buckets import partition

    def cost(last: list[int], sizes: list[int], overhead: float) -> float:
        total, start = 0.0, 0
        for n in sizes:
            total += (max(last[start:start + n]) + 1) * n + overhead
            start += n
        return total

    rng = np.random.default_rng(0)
    for _ in range(40):
        last = sorted(rng.integers(0, 12, size=int(rng.integers(1, 11))).tolist())
        overhead, cap = float(rng.choice([0.0, 3.0, 20.0])), int(rng.integers(1, 5))
        sizes = partition(torch.tensor(last), cap, overhead)
        assert sum(sizes) == len(last) and 1 <= len(sizes) <= cap and min(sizes) > 0
        best = min(cost(last, [b - a for a, b in zip((0, *cuts), (*cuts, len(last)), strict=True)], overhead)
                   for k in range(cap) for cuts in itertools.combinations(range(1, len(last)), k))
        assert cost(last, sizes, overhead) == pytest.approx(best), (last, overhead, cap, sizes)
    assert partition(torch.zeros(0, dtype=torch.long)) == []
    # the rare crowded sample no longer pads the rest: 1,000 samples seeing 2, ten seeing 25
    sizes = partition(torch.tensor([2] * 1000 + [25] * 10), 8, 64.0)
    assert sizes == [1000, 10]
    with pytest.raises(ValueError, match="max_groups"):
        partition(torch.tensor([1, 2]), 0)
