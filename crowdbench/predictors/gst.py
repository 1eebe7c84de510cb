"""A GST-style learned trajectory predictor: spatial Transformer over the pedestrians in view at each step, a temporal
LSTM per pedestrian, bivariate-Gaussian outputs rolled out autoregressively (after Huang et al. 2021, the predictor
of CrowdNav++'s AIG-GST; CrowdNav_Prediction_AttnGraph ``gst_updated/``).

Per step ``t`` every pedestrian ``i`` present is a token ``[p_i − o, p_i(t) − p_i(t−1)]`` (position relative to the
scene origin ``o`` — the robot's current position — and its last displacement, zero when the previous step was not
seen) → Linear(4→E)+ReLU → one pre-LayerNorm Transformer layer (E, 8 heads, masked to the pedestrians present at
``t``) → LSTMCell(E→L), whose state is updated only while the pedestrian is present. After the ``T`` observed
steps, ``K`` steps are decoded: Linear(L→5) gives the change of displacement (so an untrained head predicts constant
velocity), the standard deviations and the correlation of the next displacement; the mean becomes the next token
(all pedestrians predicted together, so they interact in the rollout). Trained by the negative log-likelihood of the
true positions under the accumulated Gaussians (:mod:`crowdbench.predictors.training`).

Departure from GST: attention is dense and masked, not GST's Gumbel-sampled sparse graph; the rollout uses the mean,
not samples. Defaults are CrowdNav++'s sizes (embedding 64, 8 heads, 1 layer, LSTM 64).
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F  # noqa: N812 - the usual alias
from torch import nn

from crowdbench.nn.ragged import ragged_attention_qkv, row_offsets
from crowdbench.predictors.base import HORIZON, OBSERVED, PREDICTORS, Predictor, Track

METHOD = "gst"
DEFAULT_CHECKPOINT = "gst-crowdnavpp"
"""The shipped predictor a ``gst`` predictor loads by default: trained on scenes of the default (CrowdNav++) crowd;
``gst`` is the one trained on crowdbench 0.2's crowd, kept for the checkpoints trained with it."""
SCALE = 5.0
"""Positions are divided by this before embedding (the sensing range) [m]."""


@dataclass(frozen=True)
class GSTConfig:
    """The predictor's architecture."""

    embed: int = 64
    """Token width E [-]."""
    heads: int = 8
    """Attention heads [-]."""
    layers: int = 1
    """Transformer layers per step [-]."""
    lstm: int = 64
    """Temporal LSTM state size L [-]."""
    observed: int = OBSERVED
    """Observed steps T (the current one included) [-]."""
    horizon: int = HORIZON
    """Predicted steps K [-]."""


class GSTModel(nn.Module):
    """``forward(pos, seen)``: observed positions ``(n, T, A, 2)`` [m, scene frame] and presence ``(n, T, A)`` →
    Gaussian parameters of the ``K`` future positions: mean ``(n, A, K, 2)`` [m], std ``(n, A, K, 2)`` [m],
    correlation ``(n, A, K)``."""

    def __init__(self, cfg: GSTConfig | None = None) -> None:
        super().__init__()
        self.cfg = cfg = cfg or GSTConfig()
        self.embed = nn.Sequential(nn.Linear(4, cfg.embed), nn.ReLU())
        layer = nn.TransformerEncoderLayer(cfg.embed, cfg.heads, 2 * cfg.embed, dropout=0.0, batch_first=True,
                                           norm_first=True)
        self.spatial = nn.TransformerEncoder(layer, cfg.layers, enable_nested_tensor=False)
        self.temporal = nn.LSTMCell(cfg.embed, cfg.lstm)
        self.head = nn.Linear(cfg.lstm, 5)

    def _attend(self, x: torch.Tensor, offsets: np.ndarray) -> torch.Tensor:
        """One pre-LayerNorm Transformer layer (the weights of ``self.spatial``) on the packed tokens ``x`` ``(P, E)``,
        scene ``b`` owning rows ``offsets[b]:offsets[b+1]``: attention within each scene's rows
        (:func:`~crowdbench.nn.ragged.ragged_attention_qkv`), every other product on the ``P`` tokens at once."""
        for layer in self.spatial.layers:
            attn = layer.self_attn
            E = x.shape[-1]
            h = F.layer_norm(x, (E,), layer.norm1.weight, layer.norm1.bias, layer.norm1.eps)
            qkv = F.linear(h, attn.in_proj_weight, attn.in_proj_bias)  # (P, 3E)
            o = ragged_attention_qkv(qkv, offsets, attn.num_heads)
            x = x + F.linear(o, attn.out_proj.weight, attn.out_proj.bias)
            h = F.layer_norm(x, (E,), layer.norm2.weight, layer.norm2.bias, layer.norm2.eps)
            x = x + layer.linear2(F.relu(layer.linear1(h)))
        return x

    def _step(self, pos: torch.Tensor, disp: torch.Tensor, present: torch.Tensor,
              hc: tuple[torch.Tensor, torch.Tensor]) -> tuple[torch.Tensor, torch.Tensor]:
        """One observed or decoded step on the pedestrians ``present`` ``(n, A)``: tokens of ``pos``, ``disp``
        ``(n, A, 2)`` → spatial layer → LSTM cell; the states ``hc`` ``(n·A, L)`` of absent slots stay."""
        n, A, _ = pos.shape
        idx = present.reshape(-1).nonzero().squeeze(-1)
        if idx.numel() == 0:
            return hc
        x = self.embed(torch.cat([pos.reshape(n * A, 2).index_select(0, idx) / SCALE,
                                  disp.reshape(n * A, 2).index_select(0, idx)], -1))
        z = self._attend(x, row_offsets(present.sum(-1)))
        h, c = self.temporal(z, (hc[0].index_select(0, idx), hc[1].index_select(0, idx)))
        return hc[0].index_copy(0, idx, h), hc[1].index_copy(0, idx, c)

    def _step_reference(self, pos: torch.Tensor, disp: torch.Tensor, present: torch.Tensor,
                        hc: tuple[torch.Tensor, torch.Tensor]) -> tuple[torch.Tensor, torch.Tensor]:
        """:meth:`_step` in plain torch modules on every slot (the reference the packed step is tested against)."""
        n, A, _ = pos.shape
        tokens = self.embed(torch.cat([pos / SCALE, disp], -1))
        pad = ~present
        pad[:, 0] &= present.any(-1)  # a scene with nobody present attends to slot 0 (its output is unused)
        z = self.spatial(tokens, src_key_padding_mask=pad).reshape(n * A, -1)
        h, c = self.temporal(z, hc)
        keep = present.reshape(n * A, 1)
        return torch.where(keep, h, hc[0]), torch.where(keep, c, hc[1])

    def forward(self, pos: torch.Tensor, seen: torch.Tensor, reference: bool = False
                ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """``reference``: every slot through the plain modules (:meth:`_step_reference`) instead of the packed
        step; equal up to rounding (tested)."""
        step_fn = self._step_reference if reference else self._step
        n, T, A, _ = pos.shape
        pos = torch.where(seen.unsqueeze(-1), pos, 0.0)  # what was not seen is not an input (padding may be far away)
        h = pos.new_zeros(n * A, self.cfg.lstm)
        hc = (h, h)
        disp = pos.new_zeros(n, A, 2)
        for t in range(T):
            prev_ok = seen[:, t] & seen[:, t - 1] if t else torch.zeros_like(seen[:, 0])
            disp = torch.where(prev_ok.unsqueeze(-1), pos[:, t] - pos[:, t - 1 if t else 0], 0.0)
            hc = step_fn(pos[:, t], disp, seen[:, t], hc)
        now = seen[:, -1]
        last, step = pos[:, -1], disp
        means, stds, rhos = [], [], []
        var = pos.new_zeros(n, A, 2)
        for k in range(self.cfg.horizon):
            out = self.head(hc[0]).view(n, A, 5)
            step, sd = step + out[..., :2], torch.exp(out[..., 2:4].clamp(-6.0, 3.0))  # a change of displacement
            last = last + step
            var = var + sd.square()  # the displacements' variances accumulate along the rollout
            means.append(last)
            stds.append(var.sqrt())
            rhos.append(torch.tanh(out[..., 4]) * 0.95)
            if k + 1 < self.cfg.horizon:  # the last decoded state feeds nothing
                hc = step_fn(last, step, now, hc)
        return torch.stack(means, 2), torch.stack(stds, 2), torch.stack(rhos, 2)


def gaussian_nll(mean: torch.Tensor, std: torch.Tensor, rho: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Negative log-likelihood of ``target`` ``(..., 2)`` under bivariate Gaussians (``mean`` ``(..., 2)``, ``std``
    ``(..., 2)``, correlation ``rho`` ``(...)``), per entry ``(...)`` [nats]."""
    z = (target - mean) / std
    one = 1.0 - rho.square()
    quad = (z[..., 0].square() + z[..., 1].square() - 2.0 * rho * z[..., 0] * z[..., 1]) / one
    return 0.5 * quad + torch.log(std[..., 0] * std[..., 1]) + 0.5 * torch.log(one) + math.log(2.0 * math.pi)


@PREDICTORS.register(METHOD)
class GSTPredictor(Predictor):
    """The learned predictor as a :class:`~crowdbench.predictors.base.Predictor` (means, batched over worlds; torch
    inference, one pass per call).

    Args:
        checkpoint: Path or shipped name (default: :data:`DEFAULT_CHECKPOINT`, trained by ``crowdbench predictor
            train``).
        model: Alternatively a live :class:`GSTModel`.
    """

    def __init__(self, checkpoint: str | os.PathLike | None = None, model: GSTModel | None = None) -> None:
        self.meta: dict[str, Any] = {}
        if model is None:
            model, self.meta = load_model(checkpoint)
        self.model = model.eval()
        self.horizon = model.cfg.horizon

    @torch.inference_mode()
    def predict(self, track: Track, world) -> np.ndarray:
        B, T, H, _ = track.pos.shape
        out = track.pos[:, -1, :, None, :].repeat(self.horizon, axis=2)
        now = track.seen[:, -1]
        rows = np.flatnonzero(now.any(-1))
        if len(rows) == 0:
            return out
        k = int(now[rows].sum(-1).max())
        order = np.argsort(~now[rows], axis=-1, kind="stable")[:, :k]  # the slots seen now first
        pos = np.take_along_axis(track.pos[rows], order[:, None, :, None], axis=2)
        seen = np.take_along_axis(track.seen[rows], order[:, None, :], axis=2)
        origin = world.pos[rows, 0][:, None, None, :]
        mean, _, _ = self.model(torch.as_tensor(pos - origin, dtype=torch.float32), torch.as_tensor(seen))
        full = out[rows]
        np.put_along_axis(full, order[:, :, None, None], mean.numpy().astype(np.float64) + origin, axis=1)
        out[rows] = np.where(now[rows][..., None, None], full, out[rows])  # slots not seen now stay put
        return out


def load_model(checkpoint: str | os.PathLike | None = None) -> tuple[GSTModel, dict[str, Any]]:
    """The model of a predictor checkpoint (path or shipped name; ``None``: :data:`DEFAULT_CHECKPOINT`) and its
    metadata."""
    from crowdbench import checkpoints

    path = checkpoints.resolve(METHOD, DEFAULT_CHECKPOINT if checkpoint is None else checkpoint)
    ckpt = checkpoints.load(path, METHOD)
    model = GSTModel(GSTConfig(**ckpt["model"]))
    model.load_state_dict(ckpt["net"])
    return model.eval(), {**{k: ckpt.get(k) for k in ("seed", "epochs", "ade", "fde")}, "path": path}


def model_config_dict(cfg: GSTConfig) -> dict[str, Any]:
    return asdict(cfg)
