"""AIG-GST's network: what it attends to (only pedestrians in view, no slot order, nobody in view is fine), the
original's sizes, and training through crowdbench's PPO path with the intrusion penalty in the reward."""

from __future__ import annotations

import numpy as np
import torch
from tensordict import TensorDict

from crowdbench.policies.aig.model import AIGConfig, build_actor

K = 6


def _obs(n: int, g: torch.Generator, visible: float = 0.6) -> dict[str, torch.Tensor]:
    count = (torch.rand(n, generator=g) * (K + 1) * visible).long().clamp(max=K)
    mask = (torch.arange(K)[None] < count[:, None]).float()  # nearest first: a prefix
    humans = torch.randn(n, K, 12, generator=g) * 3 * mask.unsqueeze(-1)
    return {"robot": torch.randn(n, 9, generator=g), "humans": humans, "mask": mask}


def test_encoder_sees_only_pedestrians_in_view_and_no_slot_order():
    torch.manual_seed(0)
    actor = build_actor(AIGConfig(), K).eval()
    g = torch.Generator().manual_seed(1)
    obs = _obs(16, g)
    obs["mask"][0] = 0.0
    obs["humans"][0] = 0.0  # nobody in view
    with torch.no_grad():
        z = actor.encode_samples(obs)
        assert torch.isfinite(z).all()
        hidden = obs["mask"] < 0.5
        other = {**obs, "humans": torch.where(hidden.unsqueeze(-1), 9.0, obs["humans"])}
        torch.testing.assert_close(actor.encode_samples(other), z)  # what is out of view does not matter
        # the pedestrians in view in another order (self-attention and pooling have no order)
        perm_obs = {k: v.clone() for k, v in obs.items()}
        for i in range(16):
            c = int(obs["mask"][i].sum())
            p = torch.randperm(c, generator=g)
            perm_obs["humans"][i, :c] = obs["humans"][i, p]
        torch.testing.assert_close(actor.encode_samples(perm_obs), z, rtol=1e-4, atol=1e-5)


def _grads(actor, fn, obs) -> dict[str, torch.Tensor]:
    actor.zero_grad()
    fn(obs).square().sum().backward()
    return {n: p.grad.clone() for n, p in actor.named_parameters() if p.grad is not None}


def test_packed_encoder_equals_the_originals_padded_layout_with_gradients():
    """The fast path (pedestrians packed, ragged attention, the two input maps as one product) computes the
    original's function: outputs and every parameter's gradient as the padded reference, for batches with fewer and
    with more pedestrians than the attention width (both branches of the product). In float64, so that rounding
    (the float32 attention scale of the ragged kernel, ~1e-8) cannot hide a wrong term."""
    torch.manual_seed(0)
    actor = build_actor(AIGConfig(edge_dims=(16, 8), heads=2, human_embed=8, attention=4), K).double()
    g = torch.Generator().manual_seed(3)
    for n in (3, 40):  # 3 rows: ≤ 8 pedestrians (two maps in turn); 40 rows: > 8 (one fused map)
        obs = {k: v.double() for k, v in _obs(n, g, visible=1.0).items()}
        obs["mask"][0] = 0.0  # a row with nobody in view
        obs["mask"][1] = 1.0
        torch.testing.assert_close(actor.encode_samples(obs), actor.encode_samples_reference(obs),
                                   rtol=1e-6, atol=1e-7)
        fast, ref = _grads(actor, actor.encode_samples, obs), _grads(actor, actor.encode_samples_reference, obs)
        assert set(fast) == set(ref)
        for name, gr in ref.items():  # the keys' biases have a zero gradient (softmax is shift-invariant)
            torch.testing.assert_close(fast[name], gr, rtol=1e-6, atol=1e-6, msg=name)


def test_sizes_are_the_originals():
    actor = build_actor(AIGConfig(), 20)
    assert actor.self_attn.embed_dim == 512 and actor.self_attn.num_heads == 8
    assert [m.out_features for m in actor.edge_embed if isinstance(m, torch.nn.Linear)] == [128, 512]
    assert actor.robot_embed[0].in_features == 9 and actor.robot_embed[0].out_features == 256
    assert actor.rnn.rnn.hidden_size == 128 and actor.rnn.out.out_features == 256
    obs = TensorDict({k: v for k, v in _obs(4, torch.Generator().manual_seed(2)).items()}, batch_size=[4])
    obs["humans"] = torch.zeros(4, 20, 12)
    obs["mask"] = torch.zeros(4, 20)
    with torch.no_grad():
        assert actor(obs).shape == (4, 2)


def test_trains_with_the_intrusion_penalty_and_drives_a_robot(tmp_path):
    from crowdbench.config import WorldConfig
    from crowdbench.evaluation import run_episodes
    from crowdbench.policies.aig.policy import AIGPolicy, load_actor
    from crowdbench.training.config import TrainConfig
    from crowdbench.training.shards import Shard, ShardSpec
    from crowdbench.training.trainer import train

    # the shard adds the observation's penalty to the world's reward on steps that did not end an episode
    spec = ShardSpec(WorldConfig(num_humans=12), 4, "circle_crossing", "responsive_orca", {}, "predicted",
                     {"predictor": "const_vel", "intrusion_distance": 2.0})
    shard = Shard(spec, [np.random.SeedSequence(i) for i in range(4)])
    shard.reset_all(0.0)
    found = False
    for _ in range(60):
        steps = shard.world.steps.copy()
        world_reward = []
        orig = shard.world.step

        def spy(a, _orig=orig, _out=world_reward):
            res = _orig(a)
            _out.append((res.reward.copy(), res.terminated | res.truncated))
            return res

        shard.world.step = spy
        out = shard.step(np.tile([[0.0, 1.0]], (4, 1)), steps + 1, 0.0)
        base, done = world_reward[0]
        extra = shard.obs_builder.reward(out.obs)
        np.testing.assert_allclose(out.reward, base + np.where(done, 0.0, extra))
        found |= bool((extra[~done] < 0).any())
    assert found  # some predicted positions came within 2 m of the robot: penalised

    cfg = TrainConfig.for_method("aig_gst", model={"predictor": "const_vel"}, num_envs=8, steps_per_env=8,
                                 mini_batches=2, iterations=2, threads=1, env_processes=1, eval_every=0,
                                 humans_range=(2, 4))
    tr = train(cfg, str(tmp_path), quiet=True)
    assert tr.iteration == 2
    actor, meta = load_actor(str(tmp_path / "last.pt"))
    policy = AIGPolicy(WorldConfig(), actor=actor)
    assert policy.observation_kwargs == {"predictor": "const_vel"} and meta["iteration"] == 2
    episodes = run_episodes(policy, 4, num_worlds=2, num_humans=5)
    assert len(episodes) == 4 and all(e.outcome in ("success", "collision", "timeout") for e in episodes)


def test_named_widths_of_the_recurrent_baselines():
    import pytest

    from crowdbench.policies.dsrnn.training import SMALL
    from crowdbench.training.config import TrainConfig
    from crowdbench.training.methods import PPO_METHODS

    aig = PPO_METHODS.get("aig_gst")()
    small = TrainConfig.for_method("aig_gst", model=aig.variant_model("small")).model
    assert aig.label(small) == "aig_gst-small" and aig.label(AIGConfig()) == "aig_gst"
    actor = build_actor(small, K)
    assert actor.self_attn.embed_dim == 128 and sum(p.numel() for p in actor.parameters()) < 250_000
    dsrnn = PPO_METHODS.get("dsrnn")()
    assert dsrnn.label(TrainConfig.for_method("dsrnn", model=dsrnn.variant_model("small")).model) == "dsrnn-small"
    # the default is `small` (the original widths cannot plateau here), the original's widths stay one name away
    assert TrainConfig.for_method("dsrnn").model == TrainConfig.for_method("dsrnn", model=SMALL).model
    assert TrainConfig.for_method("aig_gst").model == small and dsrnn.variant_model(None) == SMALL
    assert TrainConfig.for_method("aig_gst", model=aig.variant_model("original")).model == AIGConfig()
    assert PPO_METHODS.get("h2int")().variant_model(None) == {}
    with pytest.raises(ValueError, match="valid choices: original, small"):
        aig.variant_model("huge")
    assert PPO_METHODS.get("h2int")().variant_model("flat") == {"variant": "flat"}


def test_shipped_checkpoint_loads_safely_and_navigates_a_crowd_better_than_driving_straight(shipped_against_straight):
    """The shipped ``aig_gst`` (the `small` widths, seed 0, trained on the CrowdNav++ crowd with the ``gst-crowdnavpp``
    predictor to 30.0 M env steps; package data) loads with ``weights_only=True`` and, on the same 48 seeded
    crossings among 20 pedestrians (ρ = 0.5, the bar cell — as DS-RNN's test), reaches the goal clearly more often
    than the robot that drives straight at it."""
    ckpt, aig, straight = shipped_against_straight("aig_gst", humans=20, episodes=48)
    assert ckpt["seed"] == 0 and ckpt["model"]["robot_embed"] == 64  # the `small` widths
    assert ckpt["model"]["predictor_checkpoint"] == "gst-crowdnavpp"
    assert (ckpt["iteration"], ckpt["env_steps"]) == (5209, 30_003_840)
    # measured: 0.854 against 0.229 (41 against 11 of 48)
    assert aig["success_rate"] >= straight["success_rate"] + 0.15, (aig, straight)


def test_new_runs_read_the_default_predictor():
    """AIG-GST's default predictor checkpoint is the predictors' default (the networks may not import the
    predictors' layer, so the name is written twice; this keeps the two equal)."""
    from crowdbench.policies.aig.model import AIGConfig
    from crowdbench.predictors.gst import DEFAULT_CHECKPOINT

    assert AIGConfig().predictor_checkpoint == DEFAULT_CHECKPOINT
