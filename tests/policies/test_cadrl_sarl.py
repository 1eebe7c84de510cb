"""CADRL and SARL: the joint state by hand and under rotation, the 81 actions, the swept look-ahead reward, the fast
network paths against the reference, the greedy planner's behaviour, training → checkpoint → exact resume."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from crowdbench import checkpoints
from crowdbench.cli import main
from crowdbench.config import make_config
from crowdbench.policies import make_policy
from crowdbench.policies.value.lookahead import (
    CROWDNAV_REWARD,
    DUMMY_DISTANCE,
    Scene,
    action_set,
    current_state,
    free_space_value,
    lookahead,
    lookahead_reference,
)
from crowdbench.policies.value.model import build_net
from crowdbench.policies.value.policy import SARLPolicy
from crowdbench.training.value import ValueTrainConfig, ValueTrainer, train_value


def obs_of(robot_pos, goal, humans, robot_vel=(0.0, 0.0), n_max=6):
    """A one-world full_state observation: humans = [(x, y, vx, vy, r), ...] in world coordinates."""
    robot = np.array([[*robot_pos, 0.3, *goal, 1.0, 0.0, *robot_vel]], np.float32)
    h = np.zeros((1, n_max, 5), np.float32)
    m = np.zeros((1, n_max), np.float32)
    for i, (x, y, vx, vy, r) in enumerate(humans):
        h[0, i] = (x - robot_pos[0], y - robot_pos[1], vx, vy, r)
        m[0, i] = 1.0
    return {"robot": robot, "humans": h, "mask": m}


def test_action_set_is_crowdnavs():
    a = action_set()
    assert a.shape == (81, 2) and np.all(a[0] == 0.0)
    speeds = np.linalg.norm(a[1:6], axis=1)
    np.testing.assert_allclose(speeds, [(math.exp((i + 1) / 5) - 1) / (math.e - 1) for i in range(5)], rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(a[1:], axis=1).max(), 1.0)
    headings = np.arctan2(a[1::5, 1], a[1::5, 0]) % (2 * np.pi)
    np.testing.assert_allclose(headings, np.linspace(0, 2 * np.pi, 16, endpoint=False), atol=1e-12)


def test_joint_state_by_hand_and_invariant_to_rotating_the_scene():
    # robot at the origin heading for (0, 5): the goal direction is the new x axis, so a pedestrian 1 m east of the
    # robot is on its right (y = -1), one 2 m north is straight ahead
    scene = Scene.from_obs(obs_of((0, 0), (0, 5), [(1, 0, 0, 1, 0.4), (0, 2, 0, 0, 0.3)], robot_vel=(0, 0.5)), 5.0)
    s = current_state(scene)[0].numpy()
    np.testing.assert_allclose(s[0, :6], [5.0, 1.0, 0.0, 0.3, 0.5, 0.0], atol=1e-6)
    np.testing.assert_allclose(s[0, 6:], [0.0, -1.0, 1.0, 0.0, 0.4, 1.0, 0.7], atol=1e-6)
    np.testing.assert_allclose(s[1, 6:8], [2.0, 0.0], atol=1e-6)
    # rotate and translate the whole scene: the joint state does not change
    c, sn = math.cos(1.1), math.sin(1.1)

    def tf(x, y, dx=3.0, dy=-2.0):
        return c * x - sn * y + dx, sn * x + c * y + dy

    def rot(vx, vy):
        return c * vx - sn * vy, sn * vx + c * vy

    moved = obs_of(tf(0, 0), tf(0, 5), [(*tf(1, 0), *rot(0, 1), 0.4), (*tf(0, 2), 0, 0, 0.3)],
                   robot_vel=rot(0, 0.5))
    np.testing.assert_allclose(current_state(Scene.from_obs(moved, 5.0))[0].numpy(), s, atol=1e-5)


def test_scene_keeps_the_sensed_pedestrians_and_a_far_dummy_when_none():
    scene = Scene.from_obs(obs_of((0, 0), (0, 5), [(0, 3, 0, 0, 0.3), (0, 6, 0, 0, 0.3)]), 5.0)
    assert scene.mask.tolist() == [[True]] and scene.sensed.tolist() == [[True]]  # the one at 6 m is not sensed
    empty = Scene.from_obs(obs_of((0, 0), (0, 5), [(0, 9, 0, 0, 0.3)]), 5.0)
    assert empty.mask.tolist() == [[True]] and empty.sensed.tolist() == [[False]]
    np.testing.assert_allclose(empty.rel[0, 0].numpy(), [0.0, -DUMMY_DISTANCE])  # behind, away from the goal


def test_lookahead_reward_is_swept_and_follows_crowdnav():
    # a pedestrian 0.9 m ahead walking at the robot at 1 m/s: full speed ahead collides within the step
    scene = Scene.from_obs(obs_of((0, 0), (0, 5), [(0, 0.9, 0, -1, 0.3)]), 5.0)
    acts = torch.tensor([[0.0, 0.0], [0.0, 1.0], [0.0, -1.0], [1.0, 0.0]])
    nxt, r = lookahead(scene, acts, 0.25, 0.3)
    assert nxt.shape == (1, 4, 1, 13)
    assert r[0, 1] == CROWDNAV_REWARD.collision  # swept: the discs meet mid-step
    # stop: closest surface distance 0.9 - 0.25 - 0.6 = 0.05 m < 0.2 m → discomfort (0.05 - 0.2)·0.5·0.25
    np.testing.assert_allclose(float(r[0, 0]), (0.05 - 0.2) * 0.5 * 0.25, rtol=1e-5)
    assert r[0, 2] == 0.0  # backing off at 1 m/s keeps 0.3 m
    # the goal 0.2 m ahead is reached by a 1 m/s step towards it
    goal_scene = Scene.from_obs(obs_of((0, 0), (0, 0.2), [(4, 4, 0, 0, 0.3)]), 5.0)
    assert lookahead(goal_scene, acts, 0.25, 0.3)[1][0].tolist() == [1.0, 1.0, 0.0, 0.0]  # stay, ahead: within 0.3
    # the next state: robot moved by a·dt, pedestrian by its velocity (constant-velocity propagation)
    np.testing.assert_allclose(nxt[0, 2, 0, 6:8].numpy(), [0.9 - 0.25 + 0.25, 0.0], atol=1e-6)


def random_crowd_obs(rng: np.random.Generator, near_goal: bool) -> dict[str, np.ndarray]:
    """A batch of full_state observations: 1–24 worlds, 1–30 slots (some masked), pedestrians at rest or walking,
    some at the robot's position or touching it; robots on, near or far from their goals."""
    B, N = int(rng.integers(1, 25)), int(rng.integers(1, 31))
    robot = np.zeros((B, 9))
    robot[:, 0:2] = rng.uniform(-7, 7, (B, 2))
    robot[:, 2] = rng.uniform(0.2, 0.5, B)
    robot[:, 3:5] = robot[:, 0:2] + rng.normal(0, 0.2, (B, 2)) if near_goal else rng.uniform(-7, 7, (B, 2))
    robot[:, 5] = rng.uniform(0.5, 1.5, B)
    robot[:, 7:9] = rng.uniform(-1, 1, (B, 2))
    humans = np.zeros((B, N, 5))
    humans[..., 0:2] = rng.normal(0, 3, (B, N, 2)) * rng.uniform(0.0, 1.5, (B, N, 1))
    humans[..., 2:4] = rng.uniform(-1.5, 1.5, (B, N, 2)) * (rng.random((B, N, 1)) < 0.8)
    humans[..., 4] = rng.uniform(0.3, 0.5, (B, N))
    order = np.argsort(np.linalg.norm(humans[..., :2], axis=-1), axis=1)
    humans = np.take_along_axis(humans, order[..., None], 1)
    mask = np.sort((rng.random((B, N)) < 0.9).astype(np.float32), axis=1)[:, ::-1].copy()
    return {"robot": robot.astype(np.float32), "humans": humans.astype(np.float32), "mask": mask}


def test_compiled_lookahead_equals_the_torch_reference_bit_for_bit():
    # the decisions (argmax over Q) and so every leaderboard cell depend on the last bit of the look-ahead
    rng = np.random.default_rng(0)
    acts = torch.as_tensor(action_set(), dtype=torch.float32)
    seen: set[str] = set()
    for trial in range(60):
        scene = Scene.from_obs(random_crowd_obs(rng, near_goal=trial % 5 == 0), [5.0, 2.0, 1e9][trial % 3])
        dt, tol = [0.25, 0.1, 0.4][trial % 3], [0.3, 0.2][trial % 2]
        with torch.inference_mode():
            nxt, r = lookahead(scene, acts, dt, tol)
            nxt_ref, r_ref = lookahead_reference(scene, acts, dt, tol)
        assert nxt.dtype == nxt_ref.dtype == torch.float32 and nxt.shape == nxt_ref.shape
        assert torch.equal(nxt, nxt_ref) and torch.equal(r, r_ref), f"trial {trial}"
        seen |= {"collision" if x == CROWDNAV_REWARD.collision else "success" if x == CROWDNAV_REWARD.success
                 else "discomfort" if x < 0 else "free" for x in r.flatten().tolist()}
    assert seen == {"collision", "success", "discomfort", "free"}  # every branch of the reward was compared


@pytest.mark.parametrize("method", ["cadrl", "sarl"])
def test_fast_path_equals_the_reference_values_and_gradients(method):
    torch.manual_seed(0)
    net = build_net(method)
    x = torch.randn(40, 9, 13)
    mask = torch.rand(40, 9) < 0.5
    mask[:, 0] = True
    fast, ref = net(x, mask), net.reference(x, mask)
    torch.testing.assert_close(fast, ref, rtol=1e-5, atol=1e-6)
    g_fast = torch.autograd.grad(fast.square().sum(), list(net.parameters()))
    g_ref = torch.autograd.grad(net.reference(x, mask).square().sum(), list(net.parameters()))
    for a, b in zip(g_fast, g_ref, strict=True):
        torch.testing.assert_close(a, b, rtol=1e-4, atol=1e-6)
    # padding never matters: garbage in the masked slots leaves the values unchanged
    y = torch.where(mask.unsqueeze(-1), x, torch.full_like(x, 1e3))
    torch.testing.assert_close(net(y, mask), fast)
    # every slot filled (one robot's look-ahead): the dense branch equals the masked one bit for bit
    full = torch.ones(40, 9, dtype=torch.bool)
    padded = net(torch.cat([x, torch.zeros(40, 1, 13)], 1), torch.cat([full, torch.zeros(40, 1, dtype=torch.bool)], 1))
    assert torch.equal(net(x, full), padded)
    # without autograd (look-ahead) the ReLUs run in place: the same values bit for bit, dense and masked
    with torch.inference_mode():
        assert torch.equal(net(x, full), padded) and torch.equal(net(x, mask), fast)


def test_architectures_are_the_papers():
    sizes = {m: [tuple(p.shape) for p in build_net(m).parameters()] for m in ("cadrl", "sarl")}
    assert sizes["cadrl"] == [(150, 13), (150,), (100, 150), (100,), (100, 100), (100,), (1, 100), (1,)]
    assert [s for s in sizes["sarl"] if len(s) == 2] == [(150, 13), (100, 150), (100, 100), (50, 100), (100, 200),
                                                         (100, 100), (1, 100), (150, 56), (100, 150), (100, 100),
                                                         (1, 100)]
    with pytest.raises(ValueError, match="valid choices"):
        build_net("sarl", {"mlp4_dims": [3]})


class GoalDistanceValue(torch.nn.Module):
    """A hand-made value: closer to the goal is better (−d_g), so the planner's choices come from the reward."""

    def forward(self, state, mask):
        return -state[:, 0, 0]


def test_greedy_lookahead_heads_for_the_goal_and_sidesteps_a_collision():
    policy = SARLPolicy(make_config(max_humans_observed=6), net=GoalDistanceValue())
    free = policy.act(obs_of((0, 0), (0, 5), []))[0]
    np.testing.assert_allclose(free, [0.0, 1.0], atol=1e-6)
    blocked = policy.act(obs_of((0, 0), (0, 5), [(0, 0.9, 0, -1, 0.3)]))[0]
    assert blocked[1] < 0.99  # not straight ahead into the pedestrian
    scene = Scene.from_obs(obs_of((0, 0), (0, 5), [(0, 0.9, 0, -1, 0.3)]), 5.0)
    chosen = torch.as_tensor(blocked, dtype=torch.float32)[None]
    assert lookahead(scene, chosen, 0.25, 0.3)[1][0, 0] > CROWDNAV_REWARD.collision


class FleeValue(torch.nn.Module):
    """A value that prefers being far from the goal (+d_g): what a misfitted network can say about empty space."""

    def forward(self, state, mask):
        return state[:, 0, 0]


def test_free_space_value_by_hand_and_it_overrides_the_network_only_when_nobody_is_sensed():
    dt, gamma, tol = 0.25, 0.9, 0.3
    v = free_space_value(torch.tensor([0.2, 0.3, 5.3]), torch.tensor([1.0, 1.0, 1.0]), dt, gamma, tol)
    np.testing.assert_allclose(v.numpy(), [1.0, 1.0, 0.9**5], rtol=1e-6)  # 20 steps of γ^{0.25}
    cfg = make_config(max_humans_observed=6)
    fleeing = SARLPolicy(cfg, net=FleeValue(), free_space=False)
    assert fleeing.act(obs_of((0, 0), (0, 5), []))[0][1] < -0.9  # the network's view of empty space: run away
    analytic = SARLPolicy(cfg, net=FleeValue(), free_space=True)
    np.testing.assert_allclose(analytic.act(obs_of((0, 0), (0, 5), []))[0], [0.0, 1.0], atol=1e-6)
    crowd = obs_of((0, 0), (0, 5), [(3, 0, 0, 0, 0.3)])  # someone sensed: the network decides, as before
    np.testing.assert_array_equal(analytic.act(crowd), fleeing.act(crowd))


def test_td_targets_use_the_free_space_value_for_next_states_with_nobody_sensed(tmp_path):
    from crowdbench.training.value import Rollout

    assert not ValueTrainConfig(method="cadrl").free_space and not ValueTrainConfig.from_dict({}).free_space
    trainer = ValueTrainer(tiny_value(method="cadrl", free_space=True), str(tmp_path / "run"), quiet=True)
    trainer.target = FleeValue()
    T, n = 4, trainer.config.max_humans_observed
    states = np.zeros((T, n, 13), np.float32)
    states[:, 0, 0] = [6.0, 5.0, 4.0, 3.3]  # d_g
    states[:, 0, 1] = 1.0  # v_pref
    masks = np.zeros((T, n), np.float32)
    masks[:, 0] = 1.0
    free = np.array([False, True, False, True])
    ep = Rollout(states, masks, np.array([0.0, -0.1, 0.0, 0.0]), "success", free)
    got = trainer.targets(ep, imitation=False)
    g = trainer.gamma_step
    want = [0.0 + g * 0.9 ** (5.0 - 0.3), -0.1 + g * 4.0, 0.0 + g * 0.9 ** (3.3 - 0.3), 0.0]
    np.testing.assert_allclose(got, want, rtol=1e-5)
    trainer.save()
    assert checkpoints.load(tmp_path / "run" / "policy.pt", "cadrl")["free_space"] is True
    assert make_policy("cadrl", checkpoint=str(tmp_path / "run" / "policy.pt")).free_space


def tiny_value(**kw) -> ValueTrainConfig:
    base = dict(il_episodes=8, il_epochs=2, rl_episodes=8, worlds=4, batches_per_episode=3, epsilon_decay=4,
                target_update=4, capacity=5000, humans_range=(2, 5), checkpoint_every=4, eval_every=0,
                eval_episodes=4)
    base.update(kw)
    return ValueTrainConfig(**base)


@pytest.mark.parametrize("method", ["cadrl", "sarl"])
def test_training_resumes_exactly_and_the_checkpoint_evaluates(method, tmp_path):
    straight = train_value(tiny_value(method=method), str(tmp_path / "a"), quiet=True)
    split = ValueTrainer(tiny_value(method=method), str(tmp_path / "b"), quiet=True)
    split.train(rounds=6)  # 2 demonstration rounds, 2 epochs, the switch, 1 RL round; checkpoint written
    assert split.phase == "rl" and split.episode == 4
    resumed = train_value(tiny_value(method=method), str(tmp_path / "b"), resume=str(tmp_path / "b"), quiet=True)
    assert straight.phase == resumed.phase == "done" and resumed.episode == 8
    for k, v in straight.net.state_dict().items():
        assert torch.equal(v, resumed.net.state_dict()[k]), k
    np.testing.assert_array_equal(straight.memory.data["value"], resumed.memory.data["value"])
    np.testing.assert_array_equal(straight.history["success"], resumed.history["success"])
    # the shipped file holds weights and metadata only, loads safely, and drives the registered policy
    ckpt = checkpoints.load(tmp_path / "a" / "policy.pt", method)
    assert "memory" not in ckpt and ckpt["seed"] == 0 and ckpt["gamma"] == 0.9
    policy = make_policy(method, checkpoint=str(tmp_path / "a" / "policy.pt"))
    assert policy.plan(obs_of((0, 0), (0, 5), [(0, 2, 0, 0, 0.3)], n_max=30))[0].shape == (1, 2)
    other = "sarl" if method == "cadrl" else "cadrl"
    with pytest.raises(ValueError, match=f"holds method '{method}'"):
        make_policy(other, checkpoint=str(tmp_path / "a" / "policy.pt"))
    with pytest.raises(ValueError, match="configuration differs"):
        train_value(tiny_value(method=method, seed=1), str(tmp_path / "b"), resume=str(tmp_path / "b"), quiet=True)


def test_cli_evaluates_a_value_checkpoint_and_rejects_foreign_options(tmp_path, capsys):
    trainer = ValueTrainer(tiny_value(method="cadrl", eval_every=0), str(tmp_path / "run"), quiet=True)
    trainer.save()  # an untrained network is a valid checkpoint
    assert main(["evaluate", "cadrl", "--checkpoint", str(tmp_path / "run" / "policy.pt"), "--episodes", "4",
                 "--humans", "5"]) == 0
    assert "success_rate" in capsys.readouterr().out
    assert main(["train", "sarl", "--epochs", "2"]) == 2
    assert "options of the PPO methods" in capsys.readouterr().err
    assert main(["train", "h2int", "--il-episodes", "2"]) == 2
    assert "value-based methods" in capsys.readouterr().err
    with pytest.raises(ValueError, match="rho_range"):
        ValueTrainConfig(rho_range=(0.5, 0.2))


@pytest.mark.slow
def test_cli_trains_a_value_method(tmp_path):
    out = tmp_path / "run"
    assert main(["train", "cadrl", "--il-episodes", "4", "--rl-episodes", "4", "--worlds", "4",
                 "--out", str(out)]) == 0
    assert (out / "policy.pt").exists() and (out / "curve.png").exists()


def test_imitation_checkpoints_every_tenth_epoch_and_resumes_exactly(tmp_path, monkeypatch):
    from crowdbench.training import value

    saves: list[tuple[str, int]] = []
    real_save = ValueTrainer.save

    def counting_save(self, *args, **kwargs):
        saves.append((self.phase, self.epoch))
        return real_save(self, *args, **kwargs)

    monkeypatch.setattr(ValueTrainer, "save", counting_save)
    monkeypatch.setattr(value, "IL_CHECKPOINT_EVERY", 2)
    cfg = tiny_value(method="cadrl", il_epochs=5, rl_episodes=4)
    straight = train_value(cfg, str(tmp_path / "a"), quiet=True)
    assert [e for p, e in saves if p == "il_fit"] == [0, 2, 4]  # after collecting, then every second epoch
    split = ValueTrainer(cfg, str(tmp_path / "b"), quiet=True)
    split.train(rounds=5)  # 2 demonstration rounds, 3 epochs: the stop checkpoints between those
    assert split.phase == "il_fit" and split.epoch == 3
    resumed = train_value(cfg, str(tmp_path / "b"), resume=str(tmp_path / "b"), quiet=True)
    assert resumed.phase == "done"
    for k, v in straight.net.state_dict().items():
        assert torch.equal(v, resumed.net.state_dict()[k]), k
