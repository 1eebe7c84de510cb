"""Grouping samples by crowd size so that a set encoder spends little work on padding.

Observations list pedestrians sorted by distance with the padding at the end, so a sample's cost in the encoder is
set by its *last valid column* ``c`` (``c + 1`` tokens with the robot's). A group of samples runs trimmed to its
largest ``c``. :func:`partition` splits samples sorted by ``c`` into contiguous groups minimising

    Σ_groups (max c in group + 1) × (samples in group) + overhead × (number of groups),

by dynamic programming over the distinct values of ``c`` (at most ``N_max + 1``; ≈ 0.2 ms per call with the histogram).
Equal-size groups, the previous scheme, let the rare sample that sees 20+ pedestrians pad a quarter of the batch to
its size: on a 2,048-sample training mini-batch four equal groups cost 8.3 tokens per sample, this partition 6.8,
for 6.5 needed.
"""

from __future__ import annotations

import numba as nb
import numpy as np
import torch

TRAIN_OVERHEAD = 256.0
"""Fixed cost of one more group with gradients, in tokens. On one thread 16–256 measured the same; with the two
data-parallel threads (whose Python glue contends for the GIL) 256 was 12–15 % faster than 64 on 1,024- and
2,048-sample mini-batches."""
INFERENCE_OVERHEAD = 128.0
"""The same without gradients (per-token work is a third, per-call overhead about the same); 96–192 measured
equally on 128- and 256-sample rollout batches, one group (no bucketing) 25–40 % slower."""


@nb.njit(cache=True)
def _partition(hist: np.ndarray, max_groups: int, overhead: float) -> np.ndarray:  # pragma: no cover - numba
    values = np.nonzero(hist)[0]
    V = len(values)
    cum = np.zeros(V + 1, dtype=np.int64)
    for j in range(V):
        cum[j + 1] = cum[j] + hist[values[j]]
    G = min(max_groups, V)
    best = np.full((G + 1, V + 1), np.inf)
    arg = np.zeros((G + 1, V + 1), dtype=np.int64)
    best[0, 0] = 0.0
    for g in range(1, G + 1):
        for j in range(1, V + 1):
            width = values[j - 1] + 1.0
            for i in range(g - 1, j):
                c = best[g - 1, i] + width * (cum[j] - cum[i]) + overhead
                if c < best[g, j]:
                    best[g, j] = c
                    arg[g, j] = i
    g_best = 1
    for g in range(2, G + 1):
        if best[g, V] < best[g_best, V]:
            g_best = g
    sizes = np.zeros(g_best, dtype=np.int64)
    j = V
    for g in range(g_best, 0, -1):
        i = arg[g, j]
        sizes[g - 1] = cum[j] - cum[i]
        j = i
    return sizes


def partition(last: torch.Tensor, max_groups: int = 8, overhead: float = TRAIN_OVERHEAD) -> list[int]:
    """Group sizes for samples sorted by ``last`` (ascending ``(B,)`` ints ≥ 0, the last valid column + 1 — 0 for a
    sample that sees nobody): contiguous, summing to ``B``, at most ``max_groups`` of them, minimising the cost in
    the module docstring. An empty batch gives ``[]``."""
    if last.numel() == 0:
        return []
    if max_groups < 1:
        raise ValueError(f"max_groups={max_groups}; valid choices: an integer ≥ 1")
    hist = np.bincount(last.numpy(), minlength=1).astype(np.int64)
    return _partition(hist, max_groups, float(overhead)).tolist()


def last_column(valid: torch.Tensor) -> torch.Tensor:
    """``valid`` ``(B, N)`` bool → ``(B,)`` the 1-based index of each row's last valid column (0: none valid)."""
    cols = torch.arange(1, valid.shape[1] + 1, device=valid.device)
    return (valid.long() * cols).amax(1) if valid.shape[1] else valid.new_zeros(valid.shape[0], dtype=torch.long)
