"""Multi-head attention within variable-size token sets ("ragged" batches), forward and backward in numba.

The H²INT encoder attends within each sample's own tokens — the robot and the 0–20 pedestrians it sees — and so do
AIG-GST's pedestrian self-attention and the GST predictor's spatial layer. Packing only the valid tokens of all
samples into one ``(T, d)`` array (sample ``b`` owns rows ``offsets[b]:offsets[b+1]``) removes all padding, and lets
every linear layer run as one large matrix product. What remains is the attention core, a few thousand
multiply-adds per sample over 8-dimensional heads: PyTorch's scaled-dot-product kernels spend ≈ 10 µs per sample on
it (blocking and dispatch built for long sequences); these loops ≈ 1 µs.

Queries are either every token (``robot_only=False``) or only each sample's first token (``robot_only=True``, the
H²INT last stage), one query row per sample in that case.

Three entry points, one kernel: :func:`ragged_attention` (queries, keys and values as three tensors),
:func:`ragged_attention_qkv` (one ``(T, 3d)`` projection ``[q | k | v]``, as an attention layer's fused input
projection makes it) and :func:`ragged_attention_kv` (queries apart, ``(T, 2d)`` ``[k | v]``). The packed forms
return one gradient for the packed tensor, its blocks side by side, where autograd would zero-fill a full-width
gradient for each block it was sliced into and sum them; the numbers are the same bit for bit (tested). The kernel
reads contiguous ``(·, d)`` blocks: on column views of the packed array its compiled sums round differently.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
import torch

_FM = {"reassoc", "contract"}  # vectorised sums (the order differs from PyTorch's anyway)


@nb.njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _forward(q, k, v, offsets, robot_only, heads, probs, out):  # pragma: no cover - numba
    """Queries ``q`` ``(Q, d)``, keys and values ``k``, ``v`` ``(T, d)``; writes ``out`` ``(Q, d)`` and the attention
    weights ``probs`` (flat: per query row and head, ``S_b`` weights, in sample order)."""
    d = k.shape[1]
    dh = d // heads
    scale = np.float32(1.0 / math.sqrt(dh))
    B = offsets.shape[0] - 1
    qi = 0
    pp = 0
    for b in range(B):
        o0 = offsets[b]
        S = offsets[b + 1] - o0
        nq = 1 if robot_only else S
        for _ in range(nq):
            for h in range(heads):
                c0 = h * dh
                m = np.float32(-3.0e38)
                for j in range(S):
                    s = np.float32(0.0)
                    for c in range(dh):
                        s += q[qi, c0 + c] * k[o0 + j, c0 + c]
                    s *= scale
                    probs[pp + j] = s
                    m = max(m, s)
                tot = np.float32(0.0)
                for j in range(S):
                    e = np.float32(math.exp(probs[pp + j] - m))
                    probs[pp + j] = e
                    tot += e
                inv = np.float32(1.0) / tot
                for c in range(dh):
                    out[qi, c0 + c] = 0.0
                for j in range(S):
                    p = probs[pp + j] * inv
                    probs[pp + j] = p
                    for c in range(dh):
                        out[qi, c0 + c] += p * v[o0 + j, c0 + c]
                pp += S
            qi += 1


@nb.njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _backward(q, k, v, offsets, robot_only, heads, probs, gout, gq, gk, gv):  # pragma: no cover - numba
    """Gradients of ``Σ gout ⊙ out`` into gq ``(Q, d)``, gk, gv ``(T, d)`` (zero-initialised by the caller)."""
    d = k.shape[1]
    dh = d // heads
    scale = np.float32(1.0 / math.sqrt(dh))
    B = offsets.shape[0] - 1
    dp = np.empty(64, np.float32)
    qi = 0
    pp = 0
    for b in range(B):
        o0 = offsets[b]
        S = offsets[b + 1] - o0
        if dp.shape[0] < S:
            dp = np.empty(S, np.float32)
        nq = 1 if robot_only else S
        for _ in range(nq):
            for h in range(heads):
                c0 = h * dh
                s_all = np.float32(0.0)
                for j in range(S):
                    p = probs[pp + j]
                    s = np.float32(0.0)
                    for c in range(dh):
                        g = gout[qi, c0 + c]
                        s += g * v[o0 + j, c0 + c]
                        gv[o0 + j, c0 + c] += p * g
                    dp[j] = s
                    s_all += p * s
                for j in range(S):
                    ds = probs[pp + j] * (dp[j] - s_all) * scale
                    for c in range(dh):
                        gq[qi, c0 + c] += ds * k[o0 + j, c0 + c]
                        gk[o0 + j, c0 + c] += ds * q[qi, c0 + c]
                pp += S
            qi += 1


def _blocks(tensors: tuple[torch.Tensor, ...], d: int) -> list[np.ndarray]:
    """The ``(·, d)`` column blocks of ``tensors`` in order (q, k, v), each a C-contiguous array."""
    out = []
    for t in tensors:
        a = t.detach().numpy()
        out += [np.ascontiguousarray(a[:, i:i + d]) for i in range(0, a.shape[1], d)]
    return out


def _run(q: np.ndarray, k: np.ndarray, v: np.ndarray, offsets: np.ndarray, robot_only: bool,
         heads: int) -> tuple[np.ndarray, np.ndarray]:
    """The forward kernel on contiguous blocks; returns ``(out, probs)``."""
    sizes = np.diff(offsets)
    probs = np.empty(int(heads * (sizes.sum() if robot_only else (sizes * sizes).sum())), np.float32)
    out = np.empty_like(q)
    out[offsets.shape[0] - 1 if robot_only else offsets[-1]:] = 0.0  # rows past the samples' (padding)
    _forward(q, k, v, offsets, robot_only, heads, probs, out)
    return out, probs


class RaggedAttention(torch.autograd.Function):
    """``out = softmax(q kᵀ / √d_h) v`` per head within each sample's rows, ``q``, ``k``, ``v`` the ``(·, d)`` column
    blocks of ``tensors`` in order (three tensors, ``[q | k | v]``, or ``q`` and ``[k | v]``); one gradient per
    tensor. See the module docstring."""

    @staticmethod
    def forward(ctx, d: int, offsets: np.ndarray, robot_only: bool, heads: int,  # type: ignore[override]
                *tensors: torch.Tensor) -> torch.Tensor:
        q, k, v = _blocks(tensors, d)
        out, probs = _run(q, k, v, offsets, robot_only, heads)
        ctx.saved = (q, k, v, offsets, robot_only, heads, probs, [t.shape[1] // d for t in tensors])
        return torch.from_numpy(out)

    @staticmethod
    def backward(ctx, gout: torch.Tensor):  # type: ignore[override]
        q, k, v, offsets, robot_only, heads, probs, per_tensor = ctx.saved
        grads = [np.zeros_like(q), np.zeros_like(k), np.zeros_like(v)]
        _backward(q, k, v, offsets, robot_only, heads, probs, gout.contiguous().numpy(), *grads)
        ctx.saved = None
        out, i = [], 0
        for n in per_tensor:  # each tensor's blocks side by side
            out.append(torch.from_numpy(grads[i] if n == 1 else np.concatenate(grads[i:i + n], axis=1)))
            i += n
        return (None,) * 4 + tuple(out)


def _attend(tensors: tuple[torch.Tensor, ...], d: int, offsets: np.ndarray, robot_only: bool,
            heads: int) -> torch.Tensor:
    """Differentiable when any of ``tensors`` needs a gradient, else the forward kernel alone."""
    if torch.is_grad_enabled() and any(t.requires_grad for t in tensors):
        return RaggedAttention.apply(d, offsets, robot_only, heads, *tensors)
    return torch.from_numpy(_run(*_blocks(tensors, d), offsets, robot_only, heads)[0])


def row_offsets(counts: torch.Tensor) -> np.ndarray:
    """Row boundaries ``(B + 1,)`` int64 of samples owning ``counts`` ``(B,)`` consecutive packed rows each (the
    ``offsets`` of :func:`ragged_attention`)."""
    offsets = np.zeros(counts.shape[0] + 1, np.int64)
    np.cumsum(counts.numpy(), out=offsets[1:])
    return offsets


def ragged_attention(q: torch.Tensor, k: torch.Tensor, v: torch.Tensor, offsets: np.ndarray, robot_only: bool,
                     heads: int) -> torch.Tensor:
    """Attention within each sample's token rows: ``q`` ``(T, d)`` (or ``(B, d)`` when ``robot_only``), ``k``, ``v``
    ``(T, d)``, ``offsets`` ``(B + 1,)`` int64 row boundaries → ``(rows of q, d)``. Differentiable."""
    return _attend((q, k, v), k.shape[1], offsets, robot_only, heads)


def ragged_attention_qkv(qkv: torch.Tensor, offsets: np.ndarray, heads: int) -> torch.Tensor:
    """:func:`ragged_attention` of every token (``robot_only=False``) on the blocks of ``qkv`` ``(T, 3d)`` =
    ``[q | k | v]`` → ``(T, d)``; one gradient for ``qkv``. Differentiable."""
    return _attend((qkv,), qkv.shape[1] // 3, offsets, False, heads)


def ragged_attention_kv(q: torch.Tensor, kv: torch.Tensor, offsets: np.ndarray, robot_only: bool,
                        heads: int) -> torch.Tensor:
    """:func:`ragged_attention` with keys and values the blocks of ``kv`` ``(T, 2d)`` = ``[k | v]``; one gradient for
    ``kv``. Differentiable."""
    return _attend((q, kv), q.shape[1], offsets, robot_only, heads)
