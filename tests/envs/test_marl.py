"""The batched multi-agent interface: shapes, auto-reset, the model skipped for driven pedestrians, torch."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from crowdbench.envs.marl import CrowdMARLEnv


def test_batched_pedestrians_are_driven_as_asked_and_worlds_auto_reset():
    env = CrowdMARLEnv(num_worlds=4, num_humans=6, robot=None, max_cycles=20, device=None)
    obs = env.reset(seed=0)
    assert obs.shape == (4, 6, 9 + 6 * 30) and env.num_agents == 6
    w = env.world
    before, vmax = w.pos[:, 1:].copy(), w.v_pref[:, 1:].copy()
    a = np.zeros((4, 6, 2))
    a[..., 0] = 1.0  # east at full speed
    obs, rew, done, info = env.step(a)
    np.testing.assert_allclose(w.pos[:, 1:] - before, np.stack([vmax * 0.25, 0 * vmax], -1), atol=1e-12)
    assert rew.shape == (4, 6) and set(info["reward_terms"]) == {"progress", "goal", "collision", "intrusion",
                                                                 "time"}
    dones = [done]
    for _ in range(25):
        obs, rew, done, info = env.step(a)
        dones.append(done)
    assert np.array(dones)[19].all() and w.steps.max() <= 20  # every world ended at 20 steps and restarted


def test_model_is_not_stepped_when_everyone_is_driven(monkeypatch):
    env = CrowdMARLEnv(num_worlds=2, num_humans=5, robot=None, device=None)
    env.reset(seed=1)
    calls = []
    real = env.world.human_model.step
    monkeypatch.setattr(env.world.human_model, "step", lambda *a: calls.append(1) or real(*a))
    env.step(np.zeros((2, 5, 2)))
    assert not calls
    env.step(None)  # nobody driven: the model walks them
    assert calls


def test_robot_agent_and_torch_tensors():
    env = CrowdMARLEnv(num_worlds=3, num_humans=4, robot="agent")
    obs = env.reset(seed=0)
    assert isinstance(obs, torch.Tensor) and obs.shape == (3, 5, 9 + 6 * 30)
    obs, rew, done, info = env.step(torch.zeros(3, 5, 2))
    assert rew.shape == (3, 5) and done.shape == (3,)
    with pytest.raises(ValueError, match=r"expected \(num_worlds, num_agents, 2\) = \(3, 5, 2\)"):
        env.step(torch.zeros(3, 4, 2))
    with pytest.raises(ValueError, match=r"numbers in \[-1, 1\]"):
        env.step(torch.full((3, 5, 2), 2.0))


def test_every_world_episode_gets_a_fresh_seed():
    env = CrowdMARLEnv(num_worlds=3, num_humans=4, robot=None, max_cycles=5, device=None, seed=10)
    used: list[int] = []
    real = env.world.reset
    env.world.reset = lambda seeds=None, mask=None: (used.extend(seeds), real(seeds=seeds, mask=mask))[1]
    env.reset()
    for _ in range(23):
        env.step(np.zeros((3, 4, 2)))
    assert len(used) == len(set(used)) > 3 and sorted(used)[:3] == [10, 11, 12]
    assert all((s - 10) % 3 in (0, 1, 2) for s in used)
