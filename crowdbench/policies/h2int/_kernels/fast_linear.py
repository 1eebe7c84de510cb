"""``y = x Wᵀ + b`` through oneDNN where it is faster than PyTorch's default BLAS, with its own backward.

PyTorch's CPU wheels multiply float32 matrices with MKL, which on AMD processors takes a generic AVX2 code path: on
this project's AMD EPYC (AVX-512) a ``(8000, 32) × (32, 96)`` product runs at ≈ 85 GFLOP/s. The oneDNN primitive
that PyTorch's own compiler uses for linear layers (``torch.ops.mkldnn._linear_pointwise``) picks its kernels by
instruction set and runs the same products at ≈ 190 GFLOP/s, with bit-identical results in our measurements. It
computes the forward product and the input gradient ``dy W`` here; the weight gradient ``dyᵀ x`` (a long reduction)
was not faster through it and stays with ``torch.mm``.

The operator is private to PyTorch: it is quarantined here, behind :func:`linear`, and used only where a probe found
it present and equal to ``F.linear`` on a test product (verified on torch 2.13.0 CPU). Everywhere else — and when
:func:`use_onednn` turns it off (tests do, to exercise the fallback) or the environment sets
``CROWDBENCH_PURE_TORCH=1`` — :func:`linear` is ``F.linear``. Products under :data:`ROWS_QUANTUM` rows always take
``F.linear``: there oneDNN gains nothing and the padding would cost (one robot's decision: 0.89 → 0.37 ms).
"""

from __future__ import annotations

import os

import torch
import torch.nn.functional as F  # noqa: N812 - the PyTorch convention

ROWS_QUANTUM = 256
"""oneDNN compiles a kernel for every new row count (≈ 7 ms each; then cached, 1,024 entries): row counts are padded
up to a multiple of this, so a training run meets a few dozen shapes per layer, not thousands."""


def _lp(x: torch.Tensor, w: torch.Tensor, b: torch.Tensor | None) -> torch.Tensor:
    """``x wᵀ + b`` through oneDNN, ``x`` ``(M, in)`` contiguous; the rows padded to :data:`ROWS_QUANTUM` (the
    padding rows' outputs are computed from uninitialised memory and dropped: rows are independent)."""
    m = x.shape[0]
    mp = -(-m // ROWS_QUANTUM) * ROWS_QUANTUM
    if mp != m:
        xp = x.new_empty((mp, x.shape[1]))
        xp[:m] = x
        return torch.ops.mkldnn._linear_pointwise(xp, w, b, "none", [None], "")[:m]
    return torch.ops.mkldnn._linear_pointwise(x, w, b, "none", [None], "")


def _probe() -> bool:
    try:
        g = torch.Generator().manual_seed(0)
        x, w, b = (torch.randn(s, generator=g) for s in ((37, 16), (24, 16), (24,)))
        return bool(torch.allclose(_lp(x, w, b), F.linear(x, w, b), rtol=1e-5, atol=1e-5))
    except Exception:  # noqa: BLE001 - any failure means: not usable here
        return False


_state = {"enabled": os.environ.get("CROWDBENCH_PURE_TORCH", "") not in ("1", "true", "yes"), "probed": None}


def use_onednn(enabled: bool) -> bool:
    """Allow (``True``) or forbid the oneDNN path; returns the previous setting."""
    before = _state["enabled"]
    _state["enabled"] = bool(enabled)
    return bool(before)


def onednn_active() -> bool:
    """Whether :func:`linear` currently uses oneDNN for large products (allowed, present and probed equal)."""
    if not _state["enabled"]:
        return False
    if _state["probed"] is None:
        _state["probed"] = bool(torch.backends.mkldnn.is_available()) and _probe()
    return bool(_state["probed"])


def padded_rows(n: int) -> int:
    """Row count to allocate for ``n`` token rows: large arrays are rounded up to a multiple of
    :data:`ROWS_QUANTUM` when oneDNN is in use (its kernels are compiled per row count), else ``n``."""
    if n < ROWS_QUANTUM or not onednn_active():
        return n
    return -(-n // ROWS_QUANTUM) * ROWS_QUANTUM


class _Linear(torch.autograd.Function):
    @staticmethod
    def forward(ctx, x: torch.Tensor, w: torch.Tensor, b: torch.Tensor | None) -> torch.Tensor:  # type: ignore[override]
        x = x.contiguous()
        ctx.save_for_backward(x, w)
        ctx.has_b = b is not None
        return _lp(x, w.detach(), None if b is None else b.detach())

    @staticmethod
    def backward(ctx, dy: torch.Tensor):  # type: ignore[override]
        x, w = ctx.saved_tensors
        dy = dy.contiguous()
        dx = _lp(dy, w.detach().t().contiguous(), None) if ctx.needs_input_grad[0] else None
        dw = dy.t() @ x if ctx.needs_input_grad[1] else None
        db = dy.sum(0) if ctx.has_b and ctx.needs_input_grad[2] else None
        return dx, dw, db


def linear(x: torch.Tensor, w: torch.Tensor, b: torch.Tensor | None = None) -> torch.Tensor:
    """``F.linear(x, w, b)`` for float32 ``x`` ``(T, in)``, ``w`` ``(out, in)``, ``b`` ``(out,)`` → ``(T, out)``;
    differentiable. Other ranks or dtypes go to ``F.linear``."""
    if (x.dim() != 2 or x.dtype != torch.float32 or x.shape[0] < ROWS_QUANTUM or not w.is_contiguous()
            or not onednn_active()):  # a strided weight costs oneDNN ≈ 190 ms per call
        return F.linear(x, w, b)
    if torch.is_grad_enabled() and (x.requires_grad or w.requires_grad or (b is not None and b.requires_grad)):
        return _Linear.apply(x, w, b)
    return _lp(x.contiguous(), w.detach(), None if b is None else b.detach())
