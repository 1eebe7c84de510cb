"""The GTrXL gate of ``model.GRUGate`` with its elementwise work fused, forward and backward.

    r = σ(W_r y + U_r x),  z = σ(W_z y + U_z x − b_g),  ĥ = tanh(W_g y + U_g (r ⊙ x)),  g(x, y) = (1 − z) ⊙ x + z ⊙ ĥ

In PyTorch this is four matrix products and about a dozen elementwise kernels forward (twenty backward), each
streaming a ``(T, d)`` array through memory. Here the four products stay PyTorch matrix products and everything
between them is one numba loop per phase (the products through
:mod:`.fast_linear`) (two forward, two backward). σ and tanh use rational approximations
(Eigen's ``generic_fast_tanh_float``, absolute error ≤ 4e-7, tested), which vectorise. Used by
:mod:`.packed` on token arrays ``(T, d)``.
"""

from __future__ import annotations

import numba as nb
import numpy as np
import torch
import torch.nn as nn

from crowdbench.policies.h2int._kernels.fast_linear import linear

_FM = {"reassoc", "contract", "nsz"}
_F = np.float32
_CLAMP = _F(7.99881172180175781)
_A1, _A3, _A5, _A7 = _F(4.89352455891786e-03), _F(6.37261928875436e-04), _F(1.48572235717979e-05), _F(
    5.12229709037114e-08)
_A9, _A11, _A13 = _F(-8.60467152213735e-11), _F(2.00018790482477e-13), _F(-2.76076847742355e-16)
_B0, _B2, _B4, _B6 = _F(4.89352518554385e-03), _F(2.26843463243900e-03), _F(1.18534705686654e-04), _F(
    1.19825839466702e-06)
_HALF, _ONE = _F(0.5), _F(1.0)


@nb.njit(inline="always", fastmath=_FM, error_model="numpy")
def _tanh(v):  # pragma: no cover - numba
    x = min(max(v, -_CLAMP), _CLAMP)
    x2 = x * x
    p = ((((((_A13 * x2 + _A11) * x2 + _A9) * x2 + _A7) * x2 + _A5) * x2 + _A3) * x2 + _A1) * x
    q = ((_B6 * x2 + _B4) * x2 + _B2) * x2 + _B0
    return p / q


@nb.njit(inline="always", fastmath=_FM, error_model="numpy")
def _sigmoid(v):  # pragma: no cover - numba
    return _HALF + _HALF * _tanh(_HALF * v)


@nb.njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _fwd_rz(wv, uv, x, bg, r, z, rx):  # pragma: no cover - numba
    """r, z and r ⊙ x from ``wv = W y`` ``(T, 3d)``, ``uv = U x`` ``(T, 2d)``."""
    T, d = x.shape
    for t in range(T):
        for i in range(d):
            ri = _sigmoid(wv[t, i] + uv[t, i])
            r[t, i] = ri
            z[t, i] = _sigmoid(wv[t, d + i] + uv[t, d + i] - bg[i])
            rx[t, i] = ri * x[t, i]


@nb.njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _fwd_out(wv, ug, z, x, hc, out):  # pragma: no cover - numba
    """ĥ and the gate's output from ``ug = U_g (r ⊙ x)``."""
    T, d = x.shape
    for t in range(T):
        for i in range(d):
            h = _tanh(wv[t, 2 * d + i] + ug[t, i])
            hc[t, i] = h
            zi = z[t, i]
            out[t, i] = (_ONE - zi) * x[t, i] + zi * h


@nb.njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _bwd_out(gout, z, hc, x, dx, dwv, duv):  # pragma: no cover - numba
    """From d out: dx (direct path), d pre-tanh into ``dwv[:, 2d:]``, d pre-z into ``dwv[:, d:2d]``, ``duv[:, d:]``."""
    T, d = x.shape
    for t in range(T):
        for i in range(d):
            g, zi, h = gout[t, i], z[t, i], hc[t, i]
            dx[t, i] = g * (_ONE - zi)
            dwv[t, 2 * d + i] = g * zi * (_ONE - h * h)
            dpz = g * (h - x[t, i]) * zi * (_ONE - zi)
            dwv[t, d + i] = dpz
            duv[t, d + i] = dpz


@nb.njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _bwd_r(drx, x, r, dx, dwv, duv):  # pragma: no cover - numba
    """From d(r ⊙ x): dx += d·r, d pre-r into ``dwv[:, :d]`` and ``duv[:, :d]``."""
    T, d = x.shape
    for t in range(T):
        for i in range(d):
            g, ri = drx[t, i], r[t, i]
            dx[t, i] += g * ri
            dpr = g * x[t, i] * ri * (_ONE - ri)
            dwv[t, i] = dpr
            duv[t, i] = dpr


def _np(t: torch.Tensor) -> np.ndarray:
    return t.detach().contiguous().numpy()


def _forward(x: torch.Tensor, y: torch.Tensor, w: torch.Tensor, wb: torch.Tensor | None, u: torch.Tensor,
             ug: torch.Tensor, bg: torch.Tensor) -> tuple[torch.Tensor, ...]:
    x, y = x.detach().contiguous(), y.detach().contiguous()
    wv = linear(y, w.detach(), None if wb is None else wb.detach())
    uv = linear(x, u.detach())
    xn = x.numpy()
    r, z, rx = np.empty_like(xn), np.empty_like(xn), np.empty_like(xn)
    _fwd_rz(wv.numpy(), uv.numpy(), xn, _np(bg), r, z, rx)
    ugv = linear(torch.from_numpy(rx), ug.detach())
    hc, out = np.empty_like(xn), np.empty_like(xn)
    _fwd_out(wv.numpy(), ugv.numpy(), z, xn, hc, out)
    return torch.from_numpy(out), x, y, torch.from_numpy(r), torch.from_numpy(z), torch.from_numpy(rx), \
        torch.from_numpy(hc)


class FusedGate(torch.autograd.Function):
    """``g(x, y)`` with the weights ``w`` ``(3d, d_y)`` (and optional bias ``wb`` ``(3d,)`` of ``W y``), ``u``
    ``(2d, d)``, ``ug`` ``(d, d)`` and bias ``bg`` ``(d,)`` of a ``GRUGate``; ``x`` ``(T, d)``, ``y`` ``(T, d_y)``."""

    @staticmethod
    def forward(ctx, x, y, w, wb, u, ug, bg):  # type: ignore[override]
        out, *saved = _forward(x, y, w, wb, u, ug, bg)
        ctx.save_for_backward(*saved, w, u, ug)
        ctx.has_wb = wb is not None
        return out

    @staticmethod
    def backward(ctx, gout):  # type: ignore[override]
        x, y, r, z, rx, hc, w, u, ug = ctx.saved_tensors
        T, d = x.shape
        dx = np.empty((T, d), np.float32)
        dwv = np.empty((T, 3 * d), np.float32)
        duv = np.empty((T, 2 * d), np.float32)
        _bwd_out(_np(gout), z.numpy(), hc.numpy(), x.numpy(), dx, dwv, duv)
        dph = torch.from_numpy(dwv[:, 2 * d:])
        drx = linear(dph.contiguous(), ug.detach().t().contiguous())
        d_ug = dph.T @ rx
        _bwd_r(drx.numpy(), x.numpy(), r.numpy(), dx, dwv, duv)
        dwv_t, duv_t = torch.from_numpy(dwv), torch.from_numpy(duv)
        dy = linear(dwv_t, w.detach().t().contiguous())
        dx_t = torch.from_numpy(dx).add_(linear(duv_t, u.detach().t().contiguous()))
        d_wb = dwv_t.sum(0) if ctx.has_wb else None
        return dx_t, dy, dwv_t.T @ y, d_wb, duv_t.T @ x, d_ug, -duv_t[:, d:].sum(0)


def fused_gate(gate: nn.Module, x: torch.Tensor, y: torch.Tensor, proj: nn.Linear | None = None) -> torch.Tensor:
    """``gate(x, y)`` for a ``model.GRUGate`` on ``(T, d)`` tokens, or ``gate(x, proj(y))`` with ``proj`` folded
    into the gate's ``W`` (``W (P y + p) = (W P) y + W p``: one ``(T, d) × (d, d)`` product fewer, forward and
    backward); differentiable."""
    w, wb = gate.w.weight, None
    if proj is not None:
        w, wb = w @ proj.weight, w @ proj.bias
    params = (w, wb, gate.u.weight, gate.ug.weight, gate.bg)
    if torch.is_grad_enabled() and (x.requires_grad or y.requires_grad or
                                    any(p is not None and p.requires_grad for p in params)):
        return FusedGate.apply(x, y, *params)
    return _forward(x, y, *params)[0]
