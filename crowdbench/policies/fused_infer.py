"""The H²INT encoder's forward pass as one numba kernel, for inference in the world processes.

When the world processes compute the robot's actions (:mod:`crowdbench.training.acting`), every step runs the
encoder on 128 worlds right after the physics step, whose pymunk, ORCA and numpy code has pushed the encoder's code
and buffers out of the caches. The packed PyTorch encoder (:mod:`crowdbench.policies.packed`: about sixty operator
calls, a few MB of intermediate arrays) pays for that dearly. :func:`encode` computes the same function (same
parameters, float32, equal to rounding: tested) sample by sample in one compiled loop whose working set — one
sample's ≤ 31 tokens and the ≈ 80 kB of weights — stays in L1/L2. Measured on the 2-core reference machine, 128
worlds with 8 tokens each: back to back the kernel is slower than the PyTorch operators (2.8 against 2.0 ms: its
small matrix products are not register-blocked), inside the world processes' loop it is faster (the world process's
act-and-step CPU time per rollout fell from 0.39 to 0.35 s).

No gradients: the PPO update keeps :mod:`crowdbench.policies.packed` with autograd. Supports the attention variants
(``h2int``, ``flat``, ``standard``) with exact GELU (:func:`supported`). GELU uses Eigen's rational ``erf`` for float
(a few ulp), σ and tanh the rational approximations of :mod:`crowdbench.policies.fused_gate`.
"""

from __future__ import annotations

import math
import weakref

import numba as nb
import numpy as np
import torch
import torch.nn as nn

from crowdbench.policies.fused_gate import _sigmoid, _tanh

_FM = {"reassoc", "contract", "nsz"}
_F = np.float32
_ERF_A = tuple(_F(a) for a in (-2.72614225801306e-10, 2.77068142495902e-08, -2.10102402082508e-06,
                                -5.69250639462346e-05, -7.34990630326855e-04, -2.95459980854025e-03,
                                -1.60960333262415e-02))
_ERF_B = tuple(_F(b) for b in (-1.45660718464996e-05, -2.13374055278905e-04, -1.68282697438203e-03,
                                -7.37332916720468e-03, -1.42647390514189e-02))
_A13, _A11, _A9, _A7, _A5, _A3, _A1 = _ERF_A
_B8, _B6, _B4, _B2, _B0 = _ERF_B
_FOUR, _HALF, _ONE, _RSQRT2 = _F(4.0), _F(0.5), _F(1.0), _F(1.0 / math.sqrt(2.0))
STAGE_PARAMS = 20
"""Parameters per stage in the packed buffer (see :func:`_tensors`)."""


@nb.njit(inline="always", fastmath=_FM, error_model="numpy")
def _gelu(v):  # pragma: no cover - numba
    """0.5 v (1 + erf(v / √2)) with Eigen's ``generic_fast_erf_float``."""
    x = min(max(v * _RSQRT2, -_FOUR), _FOUR)
    x2 = x * x
    p = ((((((_A13 * x2 + _A11) * x2 + _A9) * x2 + _A7) * x2 + _A5) * x2 + _A3) * x2 + _A1) * x
    q = (((_B8 * x2 + _B6) * x2 + _B4) * x2 + _B2) * x2 + _B0
    return _HALF * v * (_ONE + p / q)


@nb.njit(inline="always", fastmath=_FM, error_model="numpy")
def _lin(x, rows, w, b, y):  # pragma: no cover - numba
    """``y[:rows] = x[:rows] @ w + b`` for ``w`` ``(in, out)``."""
    n_in, n_out = w.shape
    for t in range(rows):
        for j in range(n_out):
            y[t, j] = b[j]
        for k in range(n_in):
            xk = x[t, k]
            for j in range(n_out):
                y[t, j] += xk * w[k, j]


@nb.njit(inline="always", fastmath=_FM, error_model="numpy")
def _ln(x, rows, w, b, eps, y):  # pragma: no cover - numba
    """Layer norm of each of the first ``rows`` rows (biased variance, as PyTorch)."""
    d = x.shape[1]
    for t in range(rows):
        m = _F(0.0)
        for i in range(d):
            m += x[t, i]
        m /= d
        v = _F(0.0)
        for i in range(d):
            c = x[t, i] - m
            v += c * c
        inv = _ONE / np.float32(math.sqrt(v / d + eps))
        for i in range(d):
            y[t, i] = (x[t, i] - m) * inv * w[i] + b[i]


@nb.njit(inline="always", fastmath=_FM, error_model="numpy")
def _gate(x, yv, rows, w, u, ug, bg, zero, gw, gu, gg, out):  # pragma: no cover - numba
    """GTrXL gate ``g(x, yv)`` of ``h2int_net.GRUGate`` on the first ``rows`` rows into ``out`` (not aliasing
    ``x``); ``gw``, ``gu``, ``gg``: scratch."""
    d = x.shape[1]
    _lin(yv, rows, w, zero, gw)  # W y: (r, z, g) parts
    _lin(x, rows, u, zero, gu)  # U x: (r, z) parts
    for t in range(rows):
        for i in range(d):
            out[t, i] = _sigmoid(gw[t, i] + gu[t, i]) * x[t, i]  # r ⊙ x (out is free until the end)
    _lin(out, rows, ug, zero, gg)
    for t in range(rows):
        for i in range(d):
            z = _sigmoid(gw[t, d + i] + gu[t, d + i] - bg[i])
            out[t, i] = (_ONE - z) * x[t, i] + z * _tanh(gw[t, 2 * d + i] + gg[t, i])


@nb.njit(inline="always", fastmath=_FM, error_model="numpy")
def _residual(x, yv, rows, gated, w, u, ug, bg, zero, gw, gu, gg, out):  # pragma: no cover - numba
    """A stage's residual connection on the first ``rows`` rows into ``out``: the GTrXL gate ``g(x, yv)`` when
    ``gated`` (weights ``w``, ``u``, ``ug``, ``bg``; unused otherwise), else ``x + yv``."""
    if gated:
        _gate(x, yv, rows, w, u, ug, bg, zero, gw, gu, gg, out)
        return
    for t in range(rows):
        for i in range(x.shape[1]):
            out[t, i] = x[t, i] + yv[t, i]


@nb.njit(cache=True, nogil=True, fastmath=_FM, error_model="numpy")
def _encode(robot, edges, valid, buf, offs, shapes, d, heads, ffn, n_stages, gated, edge_scale, norm_eps, ln_eps,
            out):  # pragma: no cover - numba
    """See :func:`encode`; ``buf`` holds every parameter (``offs``, ``shapes``: where each, in :func:`_tensors`
    order)."""
    def p(i):  # parameter i as a (rows, cols) view of buf
        return buf[offs[i]:offs[i] + shapes[i, 0] * shapes[i, 1]].reshape((shapes[i, 0], shapes[i, 1]))

    B, N = valid.shape
    smax = N + 1
    dh = d // heads
    scale = _F(1.0 / math.sqrt(dh))
    x = np.empty((smax, d), np.float32)
    h = np.empty((smax, d), np.float32)
    y = np.empty((smax, d), np.float32)
    a = np.empty((smax, d), np.float32)
    att = np.empty((smax, d), np.float32)
    qkv = np.empty((smax, 3 * d), np.float32)
    gw = np.empty((smax, 3 * d), np.float32)
    gu = np.empty((smax, 2 * d), np.float32)
    f1 = np.empty((smax, ffn), np.float32)
    f = np.empty((smax, d), np.float32)
    gg = np.empty((smax, d), np.float32)
    zero = np.zeros(3 * d, np.float32)
    t1 = np.empty((1, d), np.float32)
    inp = np.empty((1, 9), np.float32)
    sc = np.empty(smax, np.float32)
    mean, std = p(0), p(1)
    rw1, rb1, rw2, rb2 = p(2), p(3), p(4), p(5)
    ew1, eb1, ew2, eb2 = p(6), p(7), p(8), p(9)
    temb, pemb, fw, fb = p(10), p(11), p(12), p(13)
    for b in range(B):
        # tokens: robot, then the valid pedestrians in column order
        for i in range(9):
            inp[0, i] = (robot[b, i] - mean[0, i]) / (std[0, i] + norm_eps)
        _lin(inp, 1, rw1, rb1[0], t1)
        for i in range(d):
            t1[0, i] = max(t1[0, i], _F(0.0))
        _lin(t1, 1, rw2, rb2[0], x)
        for i in range(d):
            x[0, i] += temb[0, i] + pemb[0, i]
        S = 1
        for c in range(N):
            if not valid[b, c]:
                continue
            inp[0, 0] = edges[b, c, 0] / edge_scale
            inp[0, 1] = edges[b, c, 1] / edge_scale
            for i in range(d):
                v = eb1[0, i] + inp[0, 0] * ew1[0, i] + inp[0, 1] * ew1[1, i]
                t1[0, i] = max(v, _F(0.0))
            for i in range(d):
                v = eb2[0, i] + temb[1, i] + pemb[c + 1, i]
                for k in range(d):
                    v += t1[0, k] * ew2[k, i]
                x[S, i] = v
            S += 1
        for st in range(n_stages):
            base = 14 + st * STAGE_PARAMS
            robot_only = st == n_stages - 1
            nq = 1 if robot_only else S
            _ln(x, S, p(base)[0], p(base + 1)[0], ln_eps, h)
            _lin(h, S, p(base + 2), p(base + 3)[0], qkv)
            for qi in range(nq):  # attention of query row qi over the sample's S tokens
                for hd in range(heads):
                    c0 = hd * dh
                    m = _F(-3.0e38)
                    for j in range(S):
                        s = _F(0.0)
                        for c in range(dh):
                            s += qkv[qi, c0 + c] * qkv[j, d + c0 + c]
                        s *= scale
                        sc[j] = s
                        m = max(m, s)
                    tot = _F(0.0)
                    for j in range(S):
                        e = np.float32(math.exp(sc[j] - m))
                        sc[j] = e
                        tot += e
                    inv = _ONE / tot
                    for c in range(dh):
                        acc = _F(0.0)
                        for j in range(S):
                            acc += sc[j] * qkv[j, 2 * d + c0 + c]
                        att[qi, c0 + c] = acc * inv
            _lin(att, nq, p(base + 4), p(base + 5)[0], a)
            _residual(x, a, nq, gated, p(base + 6), p(base + 7), p(base + 8), p(base + 9)[0], zero, gw, gu, gg, y)
            _ln(y, nq, p(base + 10)[0], p(base + 11)[0], ln_eps, h)
            _lin(h, nq, p(base + 12), p(base + 13)[0], f1)
            for t in range(nq):
                for i in range(ffn):
                    f1[t, i] = _gelu(f1[t, i])
            _lin(f1, nq, p(base + 14), p(base + 15)[0], f)
            _residual(y, f, nq, gated, p(base + 16), p(base + 17), p(base + 18), p(base + 19)[0], zero, gw, gu, gg,
                      x)
        _ln(x, 1, fw[0], fb[0], ln_eps, h)
        for i in range(d):
            out[b, i] = h[0, i]


def _tensors(enc: nn.Module) -> list[torch.Tensor]:
    """The encoder's parameters in the kernel's order, as 2-D ``(rows, cols)`` tensors; weights transposed to
    ``(in, out)``."""
    def lin(m: nn.Linear) -> list[torch.Tensor]:
        return [m.weight.t(), m.bias[None]]

    dummy = torch.zeros(1, 1)
    out = [enc.robot_norm._mean.reshape(1, -1), enc.robot_norm._std.reshape(1, -1),
           *lin(enc.robot_mlp[0]), *lin(enc.robot_mlp[2]), *lin(enc.edge_mlp[0]), *lin(enc.edge_mlp[2]),
           enc.type_emb.weight, enc.pos_emb.weight, enc.final_ln.weight[None], enc.final_ln.bias[None]]
    for st in enc.stages:
        gates = []
        for g in ((st.gate1, st.gate2) if st.gated else (None, None)):
            gates.append([g.w.weight.t(), g.u.weight.t(), g.ug.weight.t(), g.bg[None]] if g is not None
                         else [dummy] * 4)
        out += [st.ln1.weight[None], st.ln1.bias[None], *lin(st.qkv), *lin(st.out), *gates[0],
                st.ln2.weight[None], st.ln2.bias[None], *lin(st.ffn[0]), *lin(st.ffn[2]), *gates[1]]
    return out


_PACKED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _packed(enc: nn.Module) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The parameters in one float32 buffer, re-packed whenever one of them changed (optimiser steps and normaliser
    updates modify them in place, which bumps their version counters)."""
    ts = [t for t in enc.parameters()] + [t for t in enc.buffers()]
    key = tuple((t.data_ptr(), t._version) for t in ts)
    hit = _PACKED.get(enc)
    if hit is not None and hit[0] == key:
        return hit[1]
    with torch.no_grad():
        parts = [t.detach().float().contiguous() for t in _tensors(enc)]
        shapes = np.array([p.shape for p in parts], dtype=np.int64)
        sizes = shapes[:, 0] * shapes[:, 1]
        offs = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
        buf = torch.cat([p.reshape(-1) for p in parts]).numpy()
    _PACKED[enc] = (key, (buf, offs, shapes))
    return buf, offs, shapes


def supported(enc: nn.Module) -> bool:
    """The attention variants with the default activations (``h2int``, ``flat``, ``standard``)."""
    st = enc.stages[0]
    return bool(st.attention) and isinstance(st.ffn[1], nn.GELU) and st.ffn[1].approximate == "none"


def encode(enc: nn.Module, robot: torch.Tensor, edges: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
    """``enc(robot, edges, valid)`` without gradients: ``robot`` ``(B, 9)``, ``edges`` ``(B, N, 2)`` [m], ``valid``
    ``(B, N)`` bool → context ``(B, d)`` (see the module docstring)."""
    buf, offs, shapes = _packed(enc)
    st = enc.stages[0]
    d = enc.final_ln.normalized_shape[0]
    out = np.empty((robot.shape[0], d), np.float32)
    _encode(robot.detach().float().contiguous().numpy(), edges.detach().float().contiguous().numpy(),
            valid.contiguous().numpy(), buf, offs, shapes, d, st.heads, st.ffn[0].out_features, len(enc.stages),
            st.gated, np.float32(enc.edge_scale), np.float32(enc.robot_norm.eps), np.float32(st.ln1.eps), out)
    return torch.from_numpy(out)
