"""The value-based training pieces: discounted returns by hand, the replay memory's ring behaviour."""

from __future__ import annotations

import numpy as np
import pytest

from crowdbench.training.value import ReplayMemory, discounted_returns


def test_discounted_returns_by_hand():
    np.testing.assert_allclose(discounted_returns([0.0, 0.0, 1.0], 0.5), [0.25, 0.5, 1.0])
    np.testing.assert_allclose(discounted_returns([1.0, -1.0], np.array([0.9, 0.1])), [1.0 - 0.9, -1.0])


def test_replay_memory_overwrites_the_oldest_and_samples_what_it_holds():
    mem = ReplayMemory(5, {"state": (2,), "value": ()})
    mem.push(state=np.arange(8).reshape(4, 2), value=np.arange(4))
    mem.push(state=np.full((3, 2), 9), value=np.array([10, 11, 12]))
    assert len(mem) == 5
    assert sorted(mem.data["value"].tolist()) == [2, 3, 10, 11, 12]  # 0 and 1 were overwritten
    batch = mem.sample(200, np.random.default_rng(0))
    assert set(batch["value"].tolist()) == {2, 3, 10, 11, 12} and batch["state"].shape == (200, 2)
    with pytest.raises(ValueError, match="exactly"):
        mem.push(state=np.zeros((1, 2)))
    with pytest.raises(ValueError, match="capacity"):
        ReplayMemory(0, {})
