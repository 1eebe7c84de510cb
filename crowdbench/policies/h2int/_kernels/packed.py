"""The H²INT encoder on *packed* tokens: only the valid ones, all samples concatenated.

``H2INTEncoder.forward`` (the reference) pads every sample to the batch's largest crowd. :func:`packed_encode`
computes the same function (same parameters, same result to float rounding) with every sample's tokens — the robot,
then the pedestrians it sees, in column order — stacked into one ``(T, d)`` array: the linear layers, layer norms,
gates and feed-forward blocks run once over all ``T`` tokens as large, efficient kernels, attention runs within
each sample's rows (:mod:`crowdbench.nn.ragged`), and mean pooling (the ``meanpool`` variant) is a segment mean. The
last stage computes the robot tokens only (every other token's output would be discarded). Differentiable through
ordinary autograd (the attention and the gates have their own backward).
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn as nn

from crowdbench.nn.ragged import ragged_attention_kv, ragged_attention_qkv
from crowdbench.policies.h2int._kernels.fast_linear import linear, padded_rows
from crowdbench.policies.h2int._kernels.fused_gate import fused_gate


def _apply(module: nn.Module, x: torch.Tensor) -> torch.Tensor:
    """``module(x)`` for a ``Linear`` or a ``Sequential`` of linears and activations, its linears through
    :func:`.fast_linear.linear`."""
    for m in module if isinstance(module, nn.Sequential) else (module,):
        x = linear(x, m.weight, m.bias) if isinstance(m, nn.Linear) else m(x)
    return x


def _mean_pool(v: torch.Tensor, seg: torch.Tensor, sizes: torch.Tensor, rows: torch.Tensor) -> torch.Tensor:
    """Mean of each sample's value rows: ``v`` ``(T', d)`` (rows past ``len(seg)`` are padding), ``seg`` ``(T,)`` the
    sample of each real row, ``sizes`` ``(B,)`` tokens per sample → the mean of sample ``rows[i]`` for each output
    row ``i``."""
    sums = v.new_zeros((sizes.shape[0], v.shape[1])).index_add_(0, seg, v[: seg.shape[0]])
    return (sums / sizes.unsqueeze(1).to(v.dtype))[rows]


def _stage(stage: nn.Module, x: torch.Tensor, offsets: np.ndarray, robot_rows: torch.Tensor,
           robot_only: bool, seg: torch.Tensor) -> torch.Tensor:
    """One encoder stage on packed tokens ``x`` ``(T, d)`` → ``(T, d)``, or ``(B, d)`` (robot tokens) when
    ``robot_only``; the same computation as ``model.Stage.forward``. ``seg`` ``(T_real,)``: each real row's sample
    (for mean pooling)."""
    d = x.shape[1]
    h = stage.ln1(x)
    w, b = stage.qkv.weight, stage.qkv.bias
    if not stage.attention:  # meanpool: every token receives the mean of its sample's values
        v = linear(h, w[2 * d:], b[2 * d:])
        sizes = torch.from_numpy(np.diff(offsets))
        if robot_only:
            x = x[robot_rows]
            rows = torch.arange(x.shape[0]) % sizes.shape[0]  # padding rows: sample 0's mean (dropped later)
        else:
            rows = torch.cat([seg, seg.new_zeros(x.shape[0] - seg.shape[0])])
        att = _mean_pool(v, seg, sizes, rows)
    elif robot_only:
        kv = linear(h, w[d:], b[d:])
        q = linear(h[robot_rows], w[:d], b[:d])
        x = x[robot_rows]
        att = ragged_attention_kv(q, kv, offsets, robot_only, stage.heads)
    else:
        qkv = linear(h, w, b)
        att = ragged_attention_qkv(qkv, offsets, stage.heads)
    # gated: the output projection only feeds the gate's W, so it is folded into it
    y = fused_gate(stage.gate1, x, att, stage.out) if stage.gated else x + _apply(stage.out, att)
    f = _apply(stage.ffn, stage.ln2(y))
    return fused_gate(stage.gate2, y, f) if stage.gated else y + f


def packed_encode(encoder: nn.Module, robot: torch.Tensor, edges: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
    """``encoder(robot, edges, valid)`` for ``robot`` ``(B, 9)``, ``edges`` ``(B, N, 2)`` [m], ``valid`` ``(B, N)``
    bool → context ``(B, d)``, on packed tokens (see the module docstring).

    The token array carries padding rows up to :func:`.fast_linear.padded_rows` (copies of token 0,
    never attended to; their outputs are dropped and their gradients are exactly zero), so the linear layers never
    copy their inputs to pad them."""
    B = robot.shape[0]
    b_idx, col = valid.nonzero(as_tuple=True)  # row-major: sample by sample, columns ascending
    E = b_idx.shape[0]
    counts = torch.bincount(b_idx, minlength=B) if E else b_idx.new_zeros(B)
    offsets_t = torch.zeros(B + 1, dtype=torch.long)
    torch.cumsum(counts + 1, 0, out=offsets_t[1:])
    robot_rows = offsets_t[:-1]
    edge_rows = torch.arange(E) + b_idx + 1  # every earlier sample adds one robot row
    order = torch.zeros(padded_rows(B + E), dtype=torch.long)  # packed row → row of cat([robot, edge tokens])
    order[robot_rows] = torch.arange(B)
    order[edge_rows] = torch.arange(B, B + E)
    robot_rows_p = torch.cat([robot_rows, robot_rows.new_zeros(padded_rows(B) - B)])  # padding: token 0 again

    phi_r = (_apply(encoder.robot_mlp, encoder.robot_norm(robot)) + encoder.type_emb.weight[0]
             + encoder.pos_emb.weight[0])
    phi_e = (_apply(encoder.edge_mlp, edges[b_idx, col] / encoder.edge_scale) + encoder.type_emb.weight[1]
             + encoder.pos_emb(col + 1))
    x = torch.cat([phi_r, phi_e])[order]
    offsets = offsets_t.numpy()
    seg = torch.repeat_interleave(torch.arange(B), counts + 1)
    n = len(encoder.stages)
    for i, stage in enumerate(encoder.stages):
        x = _stage(stage, x, offsets, robot_rows_p, i == n - 1, seg)
    return encoder.final_ln(x[:B])
