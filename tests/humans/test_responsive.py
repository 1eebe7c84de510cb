"""Latent-responsive ORCA: limits match ORCA exactly, debouncing, long-run response share, hidden from the robot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from crowdbench.config import WorldConfig
from crowdbench.humans import ResponsiveORCA
from crowdbench.humans.responsive import latent_step_reference
from crowdbench.worlds import CrowdWorld


def rollout(model, kwargs, robot_visible=True, steps=160, B=4, n=20):
    w = CrowdWorld(WorldConfig(num_humans=n, robot_visible=robot_visible, time_limit=1e9), B, "circle_crossing",
                   model, kwargs)
    rng = np.random.default_rng(0)
    traj, xi = [], []
    for _ in range(steps):
        w.step(rng.uniform(-1, 1, (B, 2)))
        traj.append(w.pos[:, 1:].copy())
        xi.append(w.human_model.info().get("xi", np.zeros(1)).copy())
    return np.array(traj), np.array(xi)


def test_rho_zero_is_orca_without_robot():
    a, xi = rollout("responsive_orca", {"responsiveness": 0.0, "spread": 0.0})
    b, _ = rollout("orca", {}, robot_visible=False)
    np.testing.assert_array_equal(a, b)
    assert not xi.any()


def test_rho_one_full_view_is_orca_with_visible_robot():
    kw = {"responsiveness": 1.0, "spread": 0.0, "fov": 2 * math.pi, "sensing_range": 1e9}
    a, xi = rollout("responsive_orca", kw)
    b, _ = rollout("orca", {})
    np.testing.assert_array_equal(a, b)
    assert xi.all()


def test_default_rho_zero_still_draws_small_rho_i():
    """The paper's formula: ρ = 0, δ = 0.2 → ρᵢ ~ U(0, 0.2)."""
    w = CrowdWorld(WorldConfig(num_humans=30), 8, "circle_crossing", "responsive_orca", {"responsiveness": 0.0})
    rho = w.human_model.info()["rho_i"]
    assert rho.min() >= 0 and rho.max() <= 0.2 and rho.max() > 0.1


def test_robot_matters_when_responsive():
    a, _ = rollout("responsive_orca", {"responsiveness": 0.9})
    b, _ = rollout("orca", {}, robot_visible=False)
    assert np.abs(a - b).max() > 0.1


@pytest.mark.parametrize("K", [2, 3, 5])
def test_xi_never_flips_faster_than_K(K):
    _, xi = rollout("responsive_orca", {"responsiveness": 0.5, "debounce": K}, steps=300)
    flips = np.diff(xi.astype(int), axis=0) != 0  # (T-1, B, H)
    for b in range(xi.shape[1]):
        for h in range(xi.shape[2]):
            t = np.flatnonzero(flips[:, b, h])
            if len(t) > 1:
                assert np.diff(t).min() >= K


def _direct_chain(rho, visible, K, T, seed=0):
    """Drive the model's latent-state update directly with a chosen visibility pattern (no ORCA)."""
    m = ResponsiveORCA(responsiveness=rho, spread=0.0 if np.isscalar(rho) else 0.0, debounce=K)
    B, H = visible.shape
    m.bind(B, H, (), 0.25)
    rngs = [np.random.default_rng(seed + b) for b in range(B)]

    class S:  # the minimal state robot_ignored needs
        robot_visible = True

    m.reset(np.arange(B), rngs, S)
    m.robot_in_view = lambda state: visible  # fixed visibility pattern
    share = np.zeros((B, H))
    for _ in range(T):  # the numpy statement of the latent step (the compiled one is tested equal to it)
        latent_step_reference(m, S, np.stack([r.random(H) for r in rngs]))
        share += m.xi
    return share / T, m


def test_long_run_share_K1_equals_rho_times_visible():
    rng = np.random.default_rng(1)
    visible = rng.random((8, 50)) < 0.6
    share, m = _direct_chain(0.3, visible, K=1, T=4000)
    expected = (m.rho_i * visible).mean()
    assert share.mean() == pytest.approx(expected, abs=0.01)  # tolerance: 0.01 absolute over 400 chains × 4000 steps


@pytest.mark.parametrize("p", [0.5, 0.7])
def test_long_run_share_debounced_matches_stationary_formula(p):
    K = 3
    share, _ = _direct_chain(p, np.ones((8, 50), bool), K=K, T=4000)
    e0 = (1 - p**K) / ((1 - p) * p**K)
    q = 1 - p
    e1 = (1 - q**K) / ((1 - q) * q**K)
    assert share.mean() == pytest.approx(e1 / (e0 + e1), abs=0.02)


def test_invisible_robot_is_never_responded_to():
    _, xi = rollout("responsive_orca", {"responsiveness": 1.0, "spread": 0.0}, robot_visible=False)
    assert not xi.any()


def test_latent_state_not_in_robot_observation():
    from crowdbench import parallel_env

    env = parallel_env(num_humans=10, human_model="responsive_orca")
    obs, infos = env.reset(seed=0)
    assert set(obs["robot"]) == {"robot", "humans", "mask"}
    assert obs["robot"]["humans"].shape[-1] == 2  # positions only: no velocity, no ξ
    assert set(infos["robot"]["crowd"]) == {"rho_i", "robot_in_view", "xi"}


def test_set_responsiveness_validates():
    m = ResponsiveORCA()
    with pytest.raises(ValueError, match="responsiveness must be in"):
        m.set_responsiveness(1.5)
