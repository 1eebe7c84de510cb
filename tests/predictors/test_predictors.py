"""Trajectory predictors: the robot's track (resets, re-spawns, repeated builds), constant velocity and the oracle by
hand, the ``predicted`` observation and its intrusion penalty, and the learned GST predictor (learns, saves, loads
safely, has no pedestrian order)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from crowdbench import checkpoints
from crowdbench.config import make_config
from crowdbench.predictors import ConstantVelocity, GroundTruth, Track, make_predictor
from crowdbench.predictors.gst import GSTConfig, GSTModel, GSTPredictor
from crowdbench.predictors.observation import PredictedObservation
from crowdbench.predictors.training import PredictorTrainConfig, RecordConfig, compare, record, train
from crowdbench.robots import make_observation
from crowdbench.worlds import CrowdWorld


def test_track_restarts_on_reset_and_respawn_and_ignores_repeated_builds():
    tr = Track(1, 2, length=3)
    p = np.array([[[0.0, 0.0], [5.0, 0.0]]])
    for step in range(3):
        tr.update(p + [[[0.1 * step, 0.0], [0.0, 0.0]]], np.array([[True, True]]), np.array([step]))
    assert tr.seen.all() and np.allclose(tr.pos[0, :, 0, 0], [0.0, 0.1, 0.2])
    before = tr.pos.copy(), tr.seen.copy()
    tr.update(p + [[[0.2, 0.0], [0.0, 0.0]]], np.array([[True, False]]), np.array([2]))  # the same state again
    assert np.array_equal(tr.pos, before[0]) and np.array_equal(tr.seen, before[1])
    jumped = p + [[[0.3, 0.0], [3.0, 0.0]]]  # pedestrian 1 re-spawned 3 m away
    tr.update(jumped, np.array([[True, True]]), np.array([3]))
    assert tr.seen[0, :, 0].all() and tr.seen[0, :, 1].tolist() == [False, False, True]
    tr.update(p, np.array([[True, False]]), np.array([0]))  # a new episode
    assert tr.seen[0].tolist() == [[False, False], [False, False], [True, False]]
    # the next episode also starts at step 0 (this one ended on its first step): the positions tell it apart
    tr.update(p + 4.0, np.array([[True, True]]), np.array([0]))
    assert tr.seen[0].tolist() == [[False, False], [False, False], [True, True]]
    np.testing.assert_allclose(tr.pos[0], np.broadcast_to(p[0] + 4.0, (3, 2, 2)))


def test_constant_velocity_extrapolates_the_last_seen_step():
    tr = Track(1, 2, length=2)
    tr.update(np.array([[[0.0, 0.0], [1.0, 1.0]]]), np.array([[True, False]]), np.array([0]))
    tr.update(np.array([[[0.2, 0.1], [1.5, 1.0]]]), np.array([[True, True]]), np.array([1]))
    pred = ConstantVelocity().predict(tr, None)
    np.testing.assert_allclose(pred[0, 0], [[0.2 + 0.2 * k, 0.1 + 0.1 * k] for k in range(1, 6)])
    np.testing.assert_allclose(pred[0, 1], [[1.5, 1.0]] * 5)  # not seen one step ago: standing


def test_truth_predicts_the_next_step_the_world_takes_and_leaves_the_world_alone():
    w = CrowdWorld(make_config(num_humans=8), 2, "circle_crossing", "responsive_orca")
    w.reset(seeds=[3, 4])
    for _ in range(3):
        w.step(np.tile([[0.0, 0.5]], (2, 1)))
    tr = Track(2, 8)
    pred = GroundTruth().predict(tr, w)
    before = w.pos.copy()
    w.step(w.vel[:, 0].copy())  # the robot keeps its velocity, as the oracle assumes
    moved = np.linalg.norm(w.pos[:, 1:] - before[:, 1:], axis=-1) < 1.0
    np.testing.assert_allclose(pred[:, :, 0][moved], w.pos[:, 1:][moved], atol=1e-9)
    again = GroundTruth().predict(tr, w)  # the world's own generators and model state were not advanced
    assert np.isfinite(again).all()


def _world(n: int = 10, worlds: int = 3) -> CrowdWorld:
    w = CrowdWorld(make_config(num_humans=n), worlds, "circle_crossing", "responsive_orca")
    w.reset(seeds=list(range(worlds)))
    return w


def test_predicted_observation_nearest_first_with_predictions_relative_to_the_robot():
    w = _world()
    ob = make_observation("predicted", w.config, predictor="const_vel")
    rel = make_observation("relative", w.config)
    for _ in range(4):
        o = ob.build(w)
        r = rel.build(w)
        w.step(np.tile([[0.3, 0.3]], (3, 1)))
    assert o["humans"].shape == (3, 30, 12)
    np.testing.assert_array_equal(o["mask"], r["mask"])  # the same pedestrians, in the same (nearest-first) order
    np.testing.assert_allclose(o["humans"][..., :2], r["humans"], atol=1e-5)
    assert not o["humans"][o["mask"] < 0.5].any()
    # constant velocity: consecutive predictions differ by the same step
    d = np.diff(o["humans"][..., 2:].reshape(3, 30, 5, 2), axis=2)[o["mask"] > 0.5]
    np.testing.assert_allclose(d, np.repeat(d[:, :1], 4, axis=1), atol=1e-4)


def test_intrusion_penalty_by_hand():
    ob = PredictedObservation(make_config(max_humans_observed=3), predictor="const_vel")
    humans = np.zeros((3, 3, 12), np.float32)
    humans[:, :, :] = 5.0  # far
    humans[1, 0, 2 + 2 * 2:2 + 2 * 2 + 2] = (0.3, 0.2)  # world 1: k = 3 predicted within 0.6 m
    humans[2, 1, 2:4] = (0.1, 0.0)  # world 2: k = 1 within, but the slot is masked
    humans[2, 0, 2 + 2 * 3:2 + 2 * 3 + 2] = (0.0, 0.5)  # ... and k = 4 within
    mask = np.array([[1, 1, 0], [1, 0, 0], [1, 0, 0]], np.float32)
    got = ob.reward({"robot": np.zeros((3, 9), np.float32), "humans": humans, "mask": mask})
    np.testing.assert_allclose(got, [0.0, -20 / 2**4, -20 / 2**5])
    with pytest.raises(ValueError, match="intrusion_distance"):
        PredictedObservation(make_config(), predictor="const_vel", intrusion_distance=0.0)
    with pytest.raises(ValueError, match="predictor"):
        make_predictor("nope")


def test_gst_has_no_pedestrian_order_and_an_untrained_step_is_finite():
    torch.manual_seed(0)
    m = GSTModel(GSTConfig()).eval()
    g = torch.Generator().manual_seed(1)
    pos = torch.randn(4, 5, 6, 2, generator=g) * 3
    seen = torch.rand(4, 5, 6, generator=g) < 0.7
    seen[0] = False  # a scene with nobody
    with torch.no_grad():
        mean, std, rho = m(pos, seen)
        perm = torch.randperm(6, generator=g)
        mean2 = m(pos[:, :, perm], seen[:, :, perm])[0]
    assert torch.isfinite(mean).all() and (std > 0).all() and (rho.abs() < 1).all()
    now = seen[:, -1]
    torch.testing.assert_close(mean2[now[:, perm]], mean[:, perm][now[:, perm]], rtol=1e-4, atol=1e-5)


def test_gst_packed_steps_equal_the_plain_modules_with_gradients():
    """The fast path (pedestrians present packed, ragged attention) computes the plain modules' function on every
    slot: means, deviations, correlations and every parameter's gradient, up to rounding."""
    torch.manual_seed(0)
    m = GSTModel(GSTConfig(embed=16, heads=4, lstm=8))
    g = torch.Generator().manual_seed(2)
    pos = torch.randn(6, 5, 7, 2, generator=g) * 3
    seen = torch.rand(6, 5, 7, generator=g) < 0.5
    seen[0] = False  # a scene with nobody
    seen[1, :4] = False  # … seen only now
    grads, outs = [], []
    for reference in (False, True):
        m.zero_grad()
        out = m(pos, seen, reference=reference)
        sum(o.square().sum() for o in out).backward()
        grads.append({n: p.grad.clone() for n, p in m.named_parameters()})
        outs.append([o.detach() for o in out])
    for a, b in zip(*outs, strict=True):
        torch.testing.assert_close(a, b, rtol=1e-5, atol=1e-5)
    for name, gr in grads[1].items():
        scale = max(float(gr.abs().max()), 1e-8)
        torch.testing.assert_close(grads[0][name] / scale, gr / scale, rtol=0, atol=1e-4, msg=name)


def test_gst_learns_saves_loads_safely_and_predicts_in_the_observation(tmp_path):
    data = record(RecordConfig(worlds=6, steps=160, stride=2, seed=5), str(tmp_path / "d.npz"))
    assert data["valid"].any() and set(data) == {"pos", "seen", "future", "valid", "world"}
    from crowdbench.predictors.training import recorded_crowd
    from crowdbench.worlds.digest import crowd_digest

    assert recorded_crowd(str(tmp_path / "d.npz")) == crowd_digest()  # the crowd travels into the provenance
    m = train(data, str(tmp_path / "run"), PredictorTrainConfig(epochs=3, batch_size=32), quiet=True,
              crowd=recorded_crowd(str(tmp_path / "d.npz")))
    hist = __import__("json").loads((tmp_path / "run" / "history.json").read_text())["history"]
    assert hist["nll"][-1] < hist["nll"][0]
    ckpt = checkpoints.load(tmp_path / "run" / "gst.pt", "gst")  # weights_only
    assert ckpt["ade"] == m["ade"] and m["const_vel_ade"] > 0 and ckpt["crowd"] == crowd_digest()
    rows = compare(data, str(tmp_path / "run" / "gst.pt"))
    assert set(rows) == {"gst", "const_vel"} and all(np.isfinite(v).all() for v in rows.values())
    w = _world()
    ob = make_observation("predicted", w.config, predictor="gst", checkpoint=str(tmp_path / "run" / "gst.pt"))
    assert isinstance(ob.predictor, GSTPredictor)
    for _ in range(3):
        o = ob.build(w)
        w.step(np.zeros((3, 2)))
    assert np.isfinite(o["humans"]).all() and o["mask"].any()


def test_a_new_episode_at_the_same_step_count_is_a_new_track():
    """Episodes that end on their first step restart at step 0 again: the predictions must follow the new crowd
    (before the fix they extrapolated the previous episode's positions, parked padding at 10 km included)."""
    from crowdbench.training.shards import Shard, ShardSpec

    spec = ShardSpec(make_config(humans_range=(2, 30)), 6, "circle_crossing", "responsive_orca", {}, "predicted",
                     {"predictor": "const_vel"})
    shard = Shard(spec, [np.random.SeedSequence(i) for i in range(6)])
    for _ in range(4):
        obs = shard.reset_all(0.0).obs  # every world restarts; step counters read 0 each time
        seen = obs["mask"] > 0.5
        pred = obs["humans"][..., 2:].reshape(6, 30, 5, 2)
        assert seen.any()
        np.testing.assert_allclose(pred[seen], np.repeat(obs["humans"][..., None, :2], 5, axis=2)[seen], atol=1e-5)


def test_cli_records_trains_and_compares(tmp_path, capsys):
    from crowdbench.cli import main

    data = str(tmp_path / "d.npz")
    assert main(["predictor", "record", "--out", data, "--worlds", "3", "--steps", "60", "--stride", "2"]) == 0
    assert main(["predictor", "train", "--data", data, "--out", str(tmp_path / "run"), "--epochs", "1"]) == 0
    assert "held-out ADE" in capsys.readouterr().out
    assert main(["predictor", "compare", "--data", data, "--checkpoint", str(tmp_path / "run" / "gst.pt"),
                 "--json", str(tmp_path / "c.json")]) == 0
    assert "const_vel" in capsys.readouterr().out and (tmp_path / "c.json").exists()
    assert main(["predictor", "train"]) == 2
    assert "--data is required" in capsys.readouterr().err
