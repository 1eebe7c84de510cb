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


def _pool(threads: int) -> ThreadPoolExecutor:
    with _LOCK:
        if threads not in _POOLS:
            _POOLS[threads] = ThreadPoolExecutor(threads, thread_name_prefix="crowdbench-dp",
                                                 initializer=torch.set_num_threads, initargs=(1,))
        return _POOLS[threads]


Fn = Callable[[torch.Tensor], torch.Tensor]
"""``fn(index) → (len(index), D)``: the network (using its own parameters) on the samples ``index``."""


class _Shares(torch.autograd.Function):
    """Forward: every share's graph built in its thread (the parameters are leaves of those graphs). Backward: every
    share's ``autograd.grad`` in its thread, summed, handed back as the parameters' gradients."""

    @staticmethod
    def forward(ctx, fn: Fn, shares: Sequence[torch.Tensor], n: int,  # type: ignore[override]
                *params: torch.Tensor) -> torch.Tensor:
        def run(idx: torch.Tensor) -> torch.Tensor:
            with torch.enable_grad():
                return fn(idx)

        outs = list(_pool(len(shares)).map(run, shares))
        ctx.outs, ctx.shares, ctx.params = outs, shares, params
        return _assemble(shares, [o.detach() for o in outs], n)

    @staticmethod
    def backward(ctx, gz: torch.Tensor):  # type: ignore[override]
        params = ctx.params

        def grad(k: int) -> Sequence[torch.Tensor | None]:
            return torch.autograd.grad(ctx.outs[k], params, gz[ctx.shares[k]], allow_unused=True)

        parts = list(_pool(len(ctx.shares)).map(grad, range(len(ctx.shares))))
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


def parallel_map(module: nn.Module, fn: Fn, shares: Sequence[torch.Tensor], n: int) -> torch.Tensor:
    """Evaluate ``fn`` on each index tensor of ``shares`` (a partition of ``range(n)``) in its own thread and
    assemble the ``(n, D)`` result; differentiable w.r.t. ``module``'s parameters when grad mode is on."""
    params = [p for p in module.parameters() if p.requires_grad]
    if torch.is_grad_enabled() and params:
        return _Shares.apply(fn, list(shares), n, *params)
    inference = torch.is_inference_mode_enabled()

    def run(idx: torch.Tensor) -> torch.Tensor:
        with torch.inference_mode(inference), torch.no_grad():
            return fn(idx)

    return _assemble(shares, list(_pool(len(shares)).map(run, shares)), n)
