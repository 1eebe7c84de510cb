"""Pedestrians that learn: the training command, the shipped learned_crowd model, crowd statistics, Table V."""

from __future__ import annotations

import numpy as np
import pytest

import crowdbench
from crowdbench.humans.crowd_stats import crowd_stats
from crowdbench.humans.learned import CHECKPOINT, FEATURES, LearnedCrowd, features, to_world


def test_features_are_goal_aligned():
    """The same situation seen walking east or north gives the same features; actions rotate back."""
    me = np.array([[0, 0, 0.5, 0, 5, 0, 0.3, 1.0, 0], [0, 0, 0, 0.5, 0, 5, 0.3, 1.0, 0]], np.float32)
    nb = np.zeros((2, 8, 5), np.float32)
    nb[0, 0] = [1.0, 0.2, -0.4, 0, 0.4]
    nb[1, 0] = [-0.2, 1.0, 0, -0.4, 0.4]  # the first scene rotated by 90°
    mask = np.zeros((2, 8), np.float32)
    mask[:, 0] = 1
    f = features(me, nb, mask)
    assert f.shape == (2, FEATURES)
    np.testing.assert_allclose(f[0], f[1], atol=1e-6)
    np.testing.assert_allclose(to_world(np.array([[1.0, 0.0]]), me[1:].astype(np.float64)), [[0.0, 1.0]], atol=1e-12)


def test_train_crowd_writes_a_weights_only_model_that_drives_pedestrians(tmp_path):
    from crowdbench.training.crowd import CrowdTrainConfig, train

    train(CrowdTrainConfig(iterations=2, worlds=2, humans=5, steps_per_env=8), str(tmp_path), quiet=True)
    path = tmp_path / "learned_crowd.pt"
    import torch

    ckpt = torch.load(path, weights_only=True)
    assert ckpt["method"] == "learned_crowd" and "optimizer" not in ckpt and ckpt["train_config"]["seed"] == 0
    env = crowdbench.parallel_env(num_humans=5, robot=None, human_model="learned_crowd",
                                  human_model_kwargs={"checkpoint": str(path)}, max_cycles=5)
    env.reset(seed=0)
    while env.agents:
        env.step({})
    assert np.isfinite(env.world.pos).all()


@pytest.mark.skipif(not CHECKPOINT.exists(), reason="no shipped learned_crowd checkpoint")
def test_the_shipped_learned_crowd_is_a_crowd_worth_using():
    """Robot-free, 100 s, 20 pedestrians (the documented comparison): goal arrivals at least 0.8× ORCA's, contacts
    at most 2 × max(ORCA's, 10) — on seeds other than those the figures in the docs were measured on."""
    seeds = range(500, 503)
    orca, learned = crowd_stats("orca", seeds), crowd_stats("learned_crowd", seeds)
    assert learned["arrivals"] >= 0.8 * orca["arrivals"]
    assert learned["contact_steps_per_episode"] <= 2 * max(orca["contact_steps_per_episode"], 10)
    assert isinstance(crowdbench.humans.make("learned_crowd"), LearnedCrowd)


def test_crowd_stats_counts_arrivals_and_no_contacts_for_orca():
    s = crowd_stats("orca", range(1), num_humans=10, max_cycles=200)
    assert s["arrivals"] > 5 and s["contact_steps"] == 0


def test_table_five_is_the_crowd_model_shift():
    from crowdbench import leaderboard
    from crowdbench.leaderboard import load_suite

    grid = load_suite("shift").grid()
    assert [c.model for c in grid] == ["responsive_orca", "orca", "social_force", "learned_crowd"]
    assert {c.table for c in grid} == {"V"} and all(c.layout == "circle_crossing" for c in grid)
    assert "V" in leaderboard.TABLE_TITLES
