"""Data-parallel evaluation of a per-sample network on CPU threads, forward *and* backward.

PyTorch's intra-op threads barely help the H²INT encoder: its matrices are small (d = 32, a few hundred rows per
attention batch), and the autograd engine runs a CPU graph's backward on one thread. Samples are independent, so
:func:`parallel_map` splits the batch across a thread pool, each thread running the network on its share with one
intra-op thread; most kernels release the GIL, so two cores give close to 2×.

With gradients enabled the shares are wrapped in one autograd :class:`~torch.autograd.Function`: its forward builds
each share's graph inside its thread, its backward runs ``torch.autograd.grad`` of every share in its thread and sums
the parameter gradients — the same gradients as a single-threaded pass up to float summation order.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor

import torch
import torch.nn as nn

_POOLS: dict[int, ThreadPoolExecutor] = {}
_LOCK = threading.Lock()


def pool(threads: int) -> ThreadPoolExecutor:
    """The process's pool of ``threads`` worker threads (one intra-op torch thread each), created once."""
    with _LOCK:
        if threads not in _POOLS:
            _POOLS[threads] = ThreadPoolExecutor(threads, thread_name_prefix="crowdbench-dp",
                                                 initializer=torch.set_num_threads, initargs=(1,))
        return _POOLS[threads]


Fn = Callable[[int], torch.Tensor]
"""``fn(k) → (len(shares[k]), D)``: the network (using its own parameters) on share ``k``'s samples."""


class _Shares(torch.autograd.Function):
    """Forward: every share's graph built in its thread (the parameters are leaves of those graphs). Backward: every
    share's ``autograd.grad`` in its thread, summed, handed back as the parameters' gradients."""

    @staticmethod
    def forward(ctx, fn: Fn, shares: Sequence[torch.Tensor], n: int,  # type: ignore[override]
                *params: torch.Tensor) -> torch.Tensor:
        def run(k: int) -> torch.Tensor:
            with torch.enable_grad():
                return fn(k)

        outs = list(pool(len(shares)).map(run, range(len(shares))))
        ctx.outs, ctx.shares, ctx.params = outs, shares, params
        return _assemble(shares, [o.detach() for o in outs], n)

    @staticmethod
    def backward(ctx, gz: torch.Tensor):  # type: ignore[override]
        params = ctx.params

        def grad(k: int) -> Sequence[torch.Tensor | None]:
            return torch.autograd.grad(ctx.outs[k], params, gz[ctx.shares[k]], allow_unused=True)

        parts = list(pool(len(ctx.shares)).map(grad, range(len(ctx.shares))))
        ctx.outs = ctx.params = None
        return (None, None, None, *[_sum(g) for g in zip(*parts, strict=True)])


def _assemble(shares: Sequence[torch.Tensor], outs: Sequence[torch.Tensor], n: int) -> torch.Tensor:
    z = outs[0].new_empty((n, outs[0].shape[-1]))
    for idx, out in zip(shares, outs, strict=True):
        z[idx] = out
    return z


def _sum(gs: Sequence[torch.Tensor | None]) -> torch.Tensor | None:
    present = [g for g in gs if g is not None]
    if not present:
        return None
    total = present[0]
    for g in present[1:]:
        total = total + g
    return total


def parallel_map(params: nn.Module | Sequence[torch.Tensor], fn: Fn, shares: Sequence[torch.Tensor],
                 n: int) -> torch.Tensor:
    """Evaluate ``fn(k)`` for every share ``k`` in its own thread and assemble the ``(n, D)`` result, share ``k``'s
    rows going to the indices ``shares[k]`` (the shares partition ``range(n)``); differentiable w.r.t. ``params`` (a
    module's parameters, or a list) when grad mode is on."""
    params = [p for p in (params.parameters() if isinstance(params, nn.Module) else params) if p.requires_grad]
    if torch.is_grad_enabled() and params:
        return _Shares.apply(fn, list(shares), n, *params)
    inference = torch.is_inference_mode_enabled()

    def run(k: int) -> torch.Tensor:
        with torch.inference_mode(inference), torch.no_grad():
            return fn(k)

    return _assemble(shares, list(pool(len(shares)).map(run, range(len(shares)))), n)


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
    unpadded, are exactly its environments' ``(T, ·)`` columns of the unpadded mini-batch.
    """
    T = masks.shape[0]
    lengths = masks.sum(0)
    env_of = torch.div(torch.cumsum(lengths, 0) - lengths, T, rounding_mode="floor")  # (J,)
    n_env = int(env_of[-1]) + 1 if env_of.numel() else 0
    owner = balanced_owners(torch.zeros(n_env, dtype=torch.float64).index_add_(0, env_of, cost.double()), threads)
    traj_owner = owner[env_of]
    return ([torch.nonzero(traj_owner == k).squeeze(1) for k in range(threads)],
            [torch.nonzero(owner == k).squeeze(1) for k in range(threads)])
