"""Value-based training (CrowdNav's CADRL and SARL): where it lives and the pieces it shares.

CrowdNav trains its value networks in two phases — imitation of a demonstrator (the ORCA robot) with discounted
returns as regression targets, then TD learning with an ε-greedy one-step look-ahead, a target network and a replay
memory. The networks and the look-ahead policy of each method go in its own sub-package of
:mod:`crowdbench.policies` (as ``h2int/`` does); the training loop goes here, beside the PPO path, reusing the
batched worlds (:class:`~crowdbench.worlds.CrowdWorld`), :func:`~crowdbench.evaluation.run_episodes` and the
checkpoint format (:mod:`crowdbench.checkpoints`). This module holds the two pieces both phases need.
"""

from __future__ import annotations

import numpy as np


def discounted_returns(rewards: np.ndarray, gamma: np.ndarray | float) -> np.ndarray:
    """Return-to-go of one episode: ``G_t = r_t + γ_t G_{t+1}`` for rewards ``(T,)`` and per-step discount
    ``gamma`` (scalar or ``(T,)``; CrowdNav discounts by γ^{Δt·v_pref}). Shape ``(T,)``."""
    rewards = np.asarray(rewards, dtype=np.float64)
    g = np.broadcast_to(np.asarray(gamma, dtype=np.float64), rewards.shape)
    out = np.empty_like(rewards)
    acc = 0.0
    for t in range(len(rewards) - 1, -1, -1):
        acc = rewards[t] + g[t] * acc
        out[t] = acc
    return out


class ReplayMemory:
    """Fixed-capacity ring buffer of (state, target) pairs, as CrowdNav's ``ReplayMemory``: once full, new items
    overwrite the oldest.

    Args:
        capacity: Items kept (CrowdNav: 100,000).
        shapes: Per-item shape of each stored field, e.g. ``{"state": (N, 13), "value": ()}``.
    """

    def __init__(self, capacity: int, shapes: dict[str, tuple[int, ...]]) -> None:
        if not isinstance(capacity, int) or capacity < 1:
            raise ValueError(f"capacity={capacity!r}; valid choices: an integer ≥ 1")
        self.capacity = capacity
        self.data = {k: np.zeros((capacity, *s), np.float32) for k, s in shapes.items()}
        self.size = 0
        self.head = 0

    def __len__(self) -> int:
        return self.size

    def push(self, **items: np.ndarray) -> None:
        """Append a batch: every field ``(k, *shape)``, the same ``k``; the oldest items are overwritten."""
        if set(items) != set(self.data):
            raise ValueError(f"push: fields {sorted(items)}; valid choices: exactly {sorted(self.data)}")
        k = len(next(iter(items.values())))
        idx = (self.head + np.arange(k)) % self.capacity
        for name, value in items.items():
            self.data[name][idx] = value
        self.head = int((self.head + k) % self.capacity)
        self.size = min(self.size + k, self.capacity)

    def sample(self, batch: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
        """``batch`` items drawn uniformly with replacement (``rng``: the caller's generator)."""
        if self.size == 0:
            raise ValueError("sample: the memory is empty")
        idx = rng.integers(0, self.size, batch)
        return {k: v[idx] for k, v in self.data.items()}
