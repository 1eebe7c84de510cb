"""Worker threads for the PPO update, and how a recurrent mini-batch is split among them.

PyTorch's intra-op threads barely help these small networks (d = 32, a few hundred rows per product), and the
autograd engine runs a CPU graph's backward on one thread. Environments are independent, so the update
(:mod:`crowdbench.training.ppo`) hands each thread its share of a mini-batch's environments — forward, losses and
backward — with one intra-op thread each; most kernels release the GIL, so two cores give close to 2×.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import torch

_POOLS: dict[int, ThreadPoolExecutor] = {}
_LOCK = threading.Lock()


def pool(threads: int) -> ThreadPoolExecutor:
    """The process's pool of ``threads`` worker threads (one intra-op torch thread each), created once."""
    with _LOCK:
        if threads not in _POOLS:
            _POOLS[threads] = ThreadPoolExecutor(threads, thread_name_prefix="crowdbench-dp",
                                                 initializer=torch.set_num_threads, initargs=(1,))
        return _POOLS[threads]


def balanced_owners(cost: torch.Tensor, threads: int) -> torch.Tensor:
    """The share ``(n,)`` each of the items of ``cost`` ``(n,)`` goes to, so that the ``threads`` shares' total costs
    are nearly equal (greedy: costliest item to the lightest share). Deterministic (ties go to the lower share)."""
    owner = torch.empty(cost.shape[0], dtype=torch.long)
    load = [0.0] * threads
    for i in torch.argsort(cost, descending=True, stable=True).tolist():
        k = min(range(threads), key=load.__getitem__)
        owner[i] = k
        load[k] += float(cost[i])
    return owner


def trajectory_shares(masks: torch.Tensor, cost: torch.Tensor, threads: int
                      ) -> tuple[list[torch.Tensor], list[torch.Tensor]]:
    """Split an rsl-rl recurrent mini-batch by environment for ``threads`` threads.

    ``masks`` ``(T, J)``: validity of the padded trajectories (rsl-rl's ``split_and_pad_trajectories`` layout: each
    environment's trajectories consecutive, their lengths summing to ``T``); ``cost`` ``(J,)``: work per trajectory.
    Returns per share the trajectory columns and the environments (both ascending); the share's trajectories,
    unpadded, are exactly its environments' ``(T, ·)`` columns of the unpadded mini-batch. Shares that would hold
    no environment (more threads than the mini-batch has environments) are left out, so there may be fewer than
    ``threads``.
    """
    T = masks.shape[0]
    lengths = masks.sum(0)
    env_of = torch.div(torch.cumsum(lengths, 0) - lengths, T, rounding_mode="floor")  # (J,)
    n_env = int(env_of[-1]) + 1 if env_of.numel() else 0
    owner = balanced_owners(torch.zeros(n_env, dtype=torch.float64).index_add_(0, env_of, cost.double()), threads)
    traj_owner = owner[env_of]
    shares = [k for k in range(threads) if bool((owner == k).any())]
    return ([torch.nonzero(traj_owner == k).squeeze(1) for k in shares],
            [torch.nonzero(owner == k).squeeze(1) for k in shares])
