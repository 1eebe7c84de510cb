"""DS-RNN's recurrence: rollout steps and the update's padded trajectories agree, the attention sees only the slots in
view and no slot order, out-of-view slots keep their state, done worlds restart from zero, and the actor trains and
drives a robot through crowdbench's PPO path."""

from __future__ import annotations

import pytest
import torch
from rsl_rl.utils import split_and_pad_trajectories
from tensordict import TensorDict

from crowdbench.policies.dsrnn.model import DSRNNConfig, DSRNNCore, build_actor

K = 6


def _obs(n: int, g: torch.Generator, visible: float = 0.6) -> torch.Tensor:
    robot = torch.randn(n, 9, generator=g)
    mask = (torch.rand(n, K, generator=g) < visible).float()
    rel = torch.randn(n, K, 2, generator=g) * 3 * mask.unsqueeze(-1)
    return torch.cat([robot, rel.reshape(n, -1), mask], -1)


def _core() -> DSRNNCore:
    torch.manual_seed(0)
    return DSRNNCore(DSRNNConfig(), K)


def test_rollout_steps_and_padded_trajectories_agree():
    core, g = _core(), torch.Generator().manual_seed(1)
    T, n = 7, 4
    xs = torch.stack([_obs(n, g) for _ in range(T)])  # (T, n, ·)
    dones = torch.zeros(T, n)
    dones[2, 1] = dones[4, 3] = 1.0  # episodes end in worlds 1 and 3
    outs, states = [], []
    with torch.no_grad():
        for t in range(T):
            states.append(core.hidden_state if core.hidden_state is not None else torch.zeros(1, n, core.state_dim))
            outs.append(core(xs[t])[0])
            core.reset(dones[t])
        stepped = torch.stack(outs)
        # the update: trajectories split at dones, padded, each from its stored initial state
        padded, masks = split_and_pad_trajectories(xs, dones.unsqueeze(-1).bool())
        starts = torch.zeros(T, n, dtype=torch.bool)
        starts[0], starts[1:] = True, dones[:-1].bool()
        h_all = torch.stack(states)[:, 0]  # (T, n, S): the state before each step, as rsl-rl stores it
        init = h_all.transpose(0, 1)[starts.T].unsqueeze(0)  # one initial state per trajectory, world-major order
        batched = core(padded, masks, init)
    torch.testing.assert_close(batched, stepped, rtol=1e-5, atol=1e-6)


def test_update_on_state_parts_has_the_joined_states_gradients():
    """The update steps the state's parts (no join and re-slice per step): the same outputs, and the same gradients
    up to the order autograd sums them in."""
    core, g = _core(), torch.Generator().manual_seed(2)
    T, n = 6, 5
    xs = torch.stack([_obs(n, g) for _ in range(T)])
    h0 = torch.randn(1, n, core.state_dim, generator=g) * 0.1
    w = torch.randn(T, n, DSRNNConfig().latent, generator=g)
    (core(xs, torch.ones(T, n, dtype=torch.bool), h0) * w).sum().backward()
    parts_grads = [p.grad.clone() for p in core.parameters()]
    core.zero_grad()
    h, outs = h0[0], []
    for t in range(T):  # the joined state, as the rollout steps it
        out, h = core.cell(xs[t], h)
        outs.append(out)
    (torch.stack(outs) * w).sum().backward()
    for a, b in zip(parts_grads, (p.grad for p in core.parameters()), strict=True):
        torch.testing.assert_close(a, b, rtol=1e-5, atol=1e-6)


def test_attention_ignores_slots_out_of_view_and_slot_order():
    core, g = _core(), torch.Generator().manual_seed(2)
    n = 5
    x = _obs(n, g)
    h = torch.randn(n, core.state_dim, generator=g)
    with torch.no_grad():
        out, h_next = core.cell(x, h)
        # a slot out of view keeps its state; a slot in view updates it
        seen = (x[:, 9 + 2 * K:] > 0.5).reshape(-1)
        before, after = (v[:, 256:256 + K * 256].reshape(n * K, 256) for v in (h, h_next))
        torch.testing.assert_close(after[~seen], before[~seen])
        assert (after[seen] != before[seen]).any(-1).all()
        # what a slot out of view holds (input and state) does not matter now
        hidden = x[:, 9 + 2 * K:] < 0.5
        x2, h2 = x.clone(), h.clone()
        rel = x2[:, 9:9 + 2 * K].view(n, K, 2)
        rel[hidden] = 7.0
        hs = h2[:, 256:256 + K * 256].view(n, K, 256)
        hs[hidden] = 1.0
        torch.testing.assert_close(core.cell(x2, h2)[0], out)
        # permuting the slots (with their states) changes nothing: attention has no slot order
        perm = torch.randperm(K, generator=g)
        x3, h3 = x.clone(), h.clone()
        x3[:, 9:9 + 2 * K] = x[:, 9:9 + 2 * K].view(n, K, 2)[:, perm].reshape(n, -1)
        x3[:, 9 + 2 * K:] = x[:, 9 + 2 * K:][:, perm]
        h3[:, 256:256 + K * 256] = h[:, 256:256 + K * 256].view(n, K, 256)[:, perm].reshape(n, -1)
        torch.testing.assert_close(core.cell(x3, h3)[0], out, rtol=1e-5, atol=1e-6)
        # nobody in view: a finite latent, no NaN from an empty softmax
        assert torch.isfinite(core.cell(_obs(n, g, visible=0.0), h)[0]).all()


def test_nearest_slots_follow_crowdnav_plus_plus():
    """``slots="nearest"`` (CrowdNav++'s DS-RNN): the nearest-first ``relative`` observation, an unseen slot is the
    far dummy whatever it held, and every slot's state is stepped and attended."""
    import pytest

    from crowdbench.policies.dsrnn.model import DUMMY
    from crowdbench.policies.dsrnn.training import DSRNNMethod

    cfg = DSRNNConfig(slots="nearest")
    assert cfg.observation == "relative" and DSRNNConfig().observation == "relative_by_id"
    assert DSRNNMethod().observation_name(cfg) == "relative"
    with pytest.raises(ValueError, match="slots='sorted'; valid choices: by_id, nearest"):
        DSRNNConfig(slots="sorted")
    torch.manual_seed(0)
    core, g = DSRNNCore(cfg, K), torch.Generator().manual_seed(5)
    n = 5
    x = _obs(n, g)
    h = torch.randn(n, core.state_dim, generator=g)
    with torch.no_grad():
        out, h_next = core.cell(x, h)
        before, after = (v[:, 256:256 + K * 256].reshape(n * K, 256) for v in (h, h_next))
        assert (after != before).any(-1).all()  # every slot stepped, in view or not
        hidden = x[:, 9 + 2 * K:] < 0.5
        x2 = x.clone()
        x2[:, 9:9 + 2 * K].view(n, K, 2)[hidden] = 7.0  # what an unseen slot holds is replaced by the dummy
        torch.testing.assert_close(core.cell(x2, h)[0], out)
        x3 = x.clone()
        x3[:, 9:9 + 2 * K].view(n, K, 2)[hidden] = DUMMY
        x3[:, 9 + 2 * K:] = 1.0  # … so it equals a pedestrian seen at the dummy's place
        torch.testing.assert_close(core.cell(x3, h)[0], out)


def test_done_worlds_restart_from_zero_state():
    core, g = _core(), torch.Generator().manual_seed(3)
    with torch.no_grad():
        core(_obs(3, g))
        core(_obs(3, g))
        core.reset(torch.tensor([0.0, 1.0, 0.0]))
        assert not core.hidden_state[0, 1].any() and core.hidden_state[0, 0].abs().sum() > 0
        fresh = _core()
        x = _obs(3, g)
        torch.testing.assert_close(core(x)[0, 1], fresh(x)[0, 1])


def test_actor_steps_its_own_recurrent_state():
    actor = build_actor(DSRNNConfig(), K)
    g = torch.Generator().manual_seed(4)
    x = _obs(8, g)
    obs = TensorDict({"robot": x[:, :9], "humans": x[:, 9:9 + 2 * K].view(8, K, 2), "mask": x[:, 9 + 2 * K:]},
                     batch_size=[8])
    with torch.no_grad():
        a = actor(obs)
    assert a.shape == (8, 2) and torch.isfinite(a).all()
    assert actor.rnn.hidden_state.shape == (1, 8, actor.rnn.state_dim)
    assert actor.rnn.state_dim == 256 + K * 256 + 128


def test_trains_checkpoints_resumes_and_drives_a_robot(tmp_path):
    """Two PPO iterations through crowdbench.training with DS-RNN's recipe, a checkpoint that loads under
    weights_only, and the deterministic policy stepping like the actor's own recurrence."""
    import numpy as np

    from crowdbench.config import WorldConfig
    from crowdbench.evaluation import run_episodes
    from crowdbench.policies.dsrnn.policy import DSRNNPolicy, load_actor
    from crowdbench.robots import make_observation
    from crowdbench.training.config import TrainConfig
    from crowdbench.training.trainer import train
    from crowdbench.worlds import CrowdWorld

    cfg = TrainConfig.for_method("dsrnn", num_envs=8, steps_per_env=8, mini_batches=2, iterations=2, threads=1,
                                 env_processes=1, eval_every=0, humans_range=(2, 4))
    assert (cfg.learning_rate, cfg.schedule, cfg.epochs, cfg.anneal) == (4e-5, "fixed", 5, False)
    tr = train(cfg, str(tmp_path), quiet=True)
    assert tr.iteration == 2
    actor, meta = load_actor(str(tmp_path / "last.pt"))
    assert meta["iteration"] == 2
    policy = DSRNNPolicy(WorldConfig(), actor=actor)
    w = CrowdWorld(WorldConfig(num_humans=6), 3, "circle_crossing", "responsive_orca")
    obs_builder = make_observation("relative_by_id", w.config)
    actor.rnn.reset()
    for _ in range(5):
        obs = obs_builder.build(w)
        a = policy.act(obs)
        with torch.no_grad():
            expected = actor(TensorDict({k: torch.as_tensor(v) for k, v in obs.items()}, batch_size=[3]))
        np.testing.assert_allclose(a, expected.numpy(), rtol=1e-5, atol=1e-6)
        w.step(a)
    episodes = run_episodes(policy, 4, num_worlds=2, num_humans=5)
    assert len(episodes) == 4 and all(e.outcome in ("success", "collision", "timeout") for e in episodes)


def test_shipped_checkpoint_loads_safely_and_navigates_a_crowd_better_than_driving_straight(shipped_against_straight):
    """The shipped ``dsrnn`` (the `small` widths, seed 0, trained on the CrowdNav++ crowd: 24.0 M env steps with
    H²INT's PPO schedule and fixed policy std 0.3, then fine-tuned 6.0 M steps at std 0.15 and a fixed learning rate
    of 3e-5; package data)
    loads with ``weights_only=True`` and, on the same 48 seeded crossings among 20 pedestrians (ρ = 0.5, the bar cell),
    reaches the goal clearly more often than the robot that drives straight at it."""
    ckpt, dsrnn, straight = shipped_against_straight("dsrnn", humans=20, episodes=48)
    assert ckpt["seed"] == 0 and ckpt["model"]["edge_rnn"] == 64  # the `small` widths
    assert ckpt["model"]["learn_std"] is False and ckpt["model"]["action_std"] == 0.15
    init = ckpt["train_config"]["init"]  # the fine-tune's start: the σ = 0.3 run at 24.0 M env steps
    assert (init["method"], init["seed"], init["iteration"], init["env_steps"]) == ("dsrnn", 0, 4168, 24_007_680)
    # measured: 0.938 against 0.229 (45 against 11 of 48)
    assert dsrnn["success_rate"] >= straight["success_rate"] + 0.15, (dsrnn, straight)


@pytest.mark.parametrize("method", ["dsrnn", "aig_gst"])
def test_learn_std_false_keeps_the_policy_noise_fixed_through_training(tmp_path, method):
    """`--model learn_std=false --model action_std=0.3` (H²INT's fixed covariance) leaves the std at 0.3 after
    PPO updates, while the original's learned std moves from its 1.0 start — for both recurrent baselines."""
    from crowdbench.training.config import TrainConfig
    from crowdbench.training.trainer import train

    extra = {"predictor": "const_vel"} if method == "aig_gst" else {}
    stds = []
    for learn in (False, True):
        model = {**extra, "learn_std": learn, "action_std": 0.3 if not learn else 1.0}
        cfg = TrainConfig.for_method(method, model=model,
                                     num_envs=8, steps_per_env=8, mini_batches=2, iterations=2, threads=1,
                                     env_processes=1, eval_every=0, humans_range=(2, 4), learning_rate=1e-2)
        tr = train(cfg, str(tmp_path / str(learn)), quiet=True)
        ckpt = torch.load(tmp_path / str(learn) / "last.pt", weights_only=True)
        assert tr.iteration == 2 and len(tr.history["action_std"]) == 2  # the history records the noise
        stds.append(ckpt["actor"]["distribution.std_param"])
    assert torch.equal(stds[0], torch.full((2,), 0.3)) and tr.history["action_std"][-1] == pytest.approx(
        stds[1].mean().item())
    assert not torch.allclose(stds[1], torch.ones(2))
