"""The H²INT network (§Methodology): the encoder as the paper writes it, and the rsl-rl actor that trains it.

Tokens: the robot vector w̃ = [px, py, r, gx, gy, v_pref, θ, vx, vy] (9-d) → MLP → φ_r, and each observed pedestrian's
relative position (Δx, Δy) → shared MLP → φ_e. Every token gets a type embedding (robot / edge) and a learned
positional embedding whose *position is the token's rank in the distance-sorted sequence* (0 = robot, 1 = nearest
pedestrian, ...). Two gated Transformer stages follow — pre-LayerNorm, GRU-style gates (Parisotto et al., GTrXL)
after attention and after the FFN, attention masked so padded or unseen pedestrians never contribute — then the robot
token z = X⁽²⁾₀ feeds a GRU whose state h_t is shared by the actor head (mean of a Gaussian with fixed diagonal
covariance) and the value head.

Variants (same code path): ``h2int`` (2 gated stages), ``flat`` (1 stage), ``meanpool`` (attention replaced by the
mean of the valid tokens), ``standard`` (plain residual connections instead of gates).

Two implementations of the encoder, one function: :meth:`H2INTEncoder.forward` is the eager reference (padded
tokens, plain PyTorch; the export path and the test oracle), :meth:`H2INTEncoder.packed` the fast path used for
training, rollouts and evaluation (valid tokens only, :mod:`._kernels.packed`), tested equal to it, forward and
gradients, for every variant. The actor is a plain-torch :class:`~crowdbench.policies.nets.RecurrentTrunkActor`
(training wraps it for rsl-rl: :func:`crowdbench.training.models.rsl_rl_actor`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import torch
import torch.nn as nn

from crowdbench.policies.h2int._kernels.packed import packed_encode
from crowdbench.policies.nets import RecurrentTrunkActor, RunningNorm, check_action_std, gaussian_cfg

VARIANTS = ("h2int", "flat", "meanpool", "standard")
EDGE_SCALE = 5.0
"""Relative positions are divided by this (the sensing range) before the edge MLP [m]."""


class GRUGate(nn.Module):
    """GTrXL gate: g(x, y) = (1 − z)⊙x + z⊙tanh(W_g y + U_g (r⊙x)), r, z = σ(...); bias makes it start near x."""

    def __init__(self, d: int, bias: float = 2.0) -> None:
        super().__init__()
        self.w = nn.Linear(d, 3 * d, bias=False)
        self.u = nn.Linear(d, 2 * d, bias=False)
        self.ug = nn.Linear(d, d, bias=False)
        self.bg = nn.Parameter(torch.full((d,), bias))

    def forward(self, x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
        wr, wz, wg = self.w(y).chunk(3, dim=-1)
        ur, uz = self.u(x).chunk(2, dim=-1)
        r = torch.sigmoid(wr + ur)
        z = torch.sigmoid(wz + uz - self.bg)
        h = torch.tanh(wg + self.ug(r * x))
        return (1 - z) * x + z * h


class Stage(nn.Module):
    """One encoder stage: Y = Gate₁(X, MHA(LN(X))), X' = Gate₂(Y, FFN(LN(Y))) (plain residuals for ``standard``;
    masked mean pooling instead of attention for ``meanpool``)."""

    def __init__(self, d: int, heads: int, ffn: int, gated: bool, attention: bool) -> None:
        super().__init__()
        self.heads, self.gated, self.attention = heads, gated, attention
        self.ln1, self.ln2 = nn.LayerNorm(d), nn.LayerNorm(d)
        self.qkv = nn.Linear(d, 3 * d)
        self.out = nn.Linear(d, d)
        self.ffn = nn.Sequential(nn.Linear(d, ffn), nn.GELU(), nn.Linear(ffn, d))
        if gated:
            self.gate1, self.gate2 = GRUGate(d), GRUGate(d)

    def mix(self, x: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
        """Masked multi-head self-attention (or masked mean pooling) over tokens ``x`` ``(B, S, d)``, ``valid``
        ``(B, S)`` bool → ``(B, S, d)``. Invalid tokens never contribute as keys (the robot token is always valid,
        so no softmax row is empty)."""
        B, S, d = x.shape
        h = self.heads
        q, k, v = self.qkv(x).chunk(3, dim=-1)
        if not self.attention:  # meanpool: every token receives the mean of the valid tokens' values
            m = valid.to(v.dtype).unsqueeze(-1)
            return self.out((v * m).sum(1, keepdim=True) / m.sum(1, keepdim=True)).expand(B, S, d)
        q, k, v = (t.view(B, S, h, d // h).transpose(1, 2) for t in (q, k, v))  # (B, h, S, d_h)
        scores = q @ k.transpose(-1, -2) * (d // h) ** -0.5
        p = torch.softmax(scores.masked_fill(~valid[:, None, None, :], float("-inf")), -1)
        return self.out((p @ v).transpose(1, 2).reshape(B, S, d))

    def forward(self, x: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
        """``x`` ``(B, S, d)``, ``valid`` ``(B, S)`` → ``(B, S, d)``."""
        a = self.mix(self.ln1(x), valid)
        y = self.gate1(x, a) if self.gated else x + a
        f = self.ffn(self.ln2(y))
        return self.gate2(y, f) if self.gated else y + f


class H2INTEncoder(nn.Module):
    """Robot vector ``(B, 9)`` + edges ``(B, N, 2)`` [m] + validity ``(B, N)`` bool → context z ``(B, d)``.

    Args:
        n_max: Observation slots N_max (the positional embedding has ``n_max + 1`` entries).
        variant: One of :data:`VARIANTS`.
        d_model, heads, ffn: Token width, attention heads, feed-forward width.
    """

    def __init__(self, n_max: int, variant: str = "h2int", d_model: int = 32, heads: int = 4, ffn: int = 64):
        super().__init__()
        if variant not in VARIANTS:
            raise ValueError(f"variant={variant!r}; valid choices: {', '.join(VARIANTS)}")
        self.edge_scale = EDGE_SCALE
        self.robot_norm = RunningNorm(9)
        self.robot_mlp = nn.Sequential(nn.Linear(9, d_model), nn.ReLU(), nn.Linear(d_model, d_model))
        self.edge_mlp = nn.Sequential(nn.Linear(2, d_model), nn.ReLU(), nn.Linear(d_model, d_model))
        self.type_emb = nn.Embedding(2, d_model)
        self.pos_emb = nn.Embedding(n_max + 1, d_model)
        self.stages = nn.ModuleList(Stage(d_model, heads, ffn, gated=variant != "standard",
                                          attention=variant != "meanpool")
                                    for _ in range(1 if variant == "flat" else 2))
        self.final_ln = nn.LayerNorm(d_model)

    def forward(self, robot: torch.Tensor, edges: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
        """The reference: padded tokens, every stage over every token, z = the robot token's final output."""
        B, n = valid.shape
        phi_r = self.robot_mlp(self.robot_norm(robot)).unsqueeze(1)
        phi_e = self.edge_mlp(edges / self.edge_scale)
        types = torch.cat([torch.zeros(1, dtype=torch.long), torch.ones(n, dtype=torch.long)])
        x = torch.cat([phi_r, phi_e], 1) + self.type_emb(types) + self.pos_emb(torch.arange(n + 1))
        tok_valid = torch.cat([valid.new_ones((B, 1)), valid], 1)  # the robot token is always valid
        for stage in self.stages:
            x = stage(x, tok_valid)
        return self.final_ln(x[:, 0])

    def packed(self, robot: torch.Tensor, edges: torch.Tensor, valid: torch.Tensor) -> torch.Tensor:
        """The same function on packed tokens (:func:`._kernels.packed.packed_encode`): the fast path, used for
        training, rollouts and evaluation; differentiable."""
        return packed_encode(self, robot, edges, valid)


@dataclass(frozen=True)
class H2INTConfig:
    """The H²INT architecture (stored in checkpoints as ``model``)."""

    variant: str = "h2int"
    """``h2int`` (2 gated stages), ``flat`` (1 stage), ``meanpool`` (mean pooling for attention), ``standard``
    (plain residuals for the gates)."""
    d_model: int = 32
    """Token width d."""
    heads: int = 4
    """Attention heads."""
    ffn: int = 64
    """Feed-forward width of each stage."""
    gru_hidden: int = 64
    """GRU state size (the latent both heads read)."""
    head_dims: tuple[int, ...] = (64,)
    """Hidden layers of the action and value heads."""
    action_std: float = 0.3
    """Fixed standard deviation of the Gaussian policy [m/s]."""

    def __post_init__(self) -> None:
        if self.variant not in VARIANTS:
            raise ValueError(f"variant={self.variant!r}; valid choices: {', '.join(VARIANTS)}")
        for name in ("d_model", "heads", "ffn", "gru_hidden"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                raise ValueError(f"{name}={getattr(self, name)!r}; valid choices: an integer ≥ 1")
        if self.d_model % self.heads:
            raise ValueError(f"heads={self.heads}; valid choices: a divisor of d_model={self.d_model}")
        check_action_std(self.action_std)
        object.__setattr__(self, "head_dims", tuple(int(h) for h in self.head_dims))

    def actor_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :class:`H2INTActor` (and of its rsl-rl adapter's ``actor`` config)."""
        return {"variant": self.variant, "d_model": self.d_model, "heads": self.heads, "ffn": self.ffn,
                "gru_hidden": self.gru_hidden, "hidden_dims": list(self.head_dims),
                "distribution_cfg": gaussian_cfg(self.action_std, learn_std=False)}


class H2INTActor(RecurrentTrunkActor):
    """H²INT actor: encoder → GRU → MLP head → Gaussian mean (fixed covariance via ``distribution_cfg``).

    Observation groups: ``robot`` ``(·, 9)``, ``humans`` ``(·, N_max, 2)``, ``mask`` ``(·, N_max)`` (1 = valid).
    """

    obs_keys = ("robot", "humans", "mask")

    def __init__(self, obs: Mapping[str, torch.Tensor], output_dim: int, variant: str = "h2int", d_model: int = 32,
                 heads: int = 4, ffn: int = 64, gru_hidden: int = 64, hidden_dims: tuple[int, ...] | list[int] = (64,),
                 activation: str = "elu", distribution_cfg: dict | None = None) -> None:
        super().__init__(obs, output_dim, d_model, gru_hidden, hidden_dims, activation, distribution_cfg)
        self.slots = obs["humans"].shape[-2]
        self.encoder = H2INTEncoder(obs["humans"].shape[-2], variant, d_model, heads, ffn)

    def encode_samples(self, obs):
        return self.encoder.packed(obs["robot"], obs["humans"], obs["mask"] > 0.5)

    def work(self, obs):
        return (obs["mask"] > 0.5).sum(-1) + 1  # tokens per sample

    def update_normalization(self, obs: Mapping[str, torch.Tensor]) -> None:
        if self.training:
            self.encoder.robot_norm.update(obs["robot"])


def build_actor(model: H2INTConfig, n_max: int) -> H2INTActor:
    """An untrained actor of architecture ``model`` for ``n_max`` observation slots."""
    obs = {"robot": torch.zeros(1, 9), "humans": torch.zeros(1, n_max, 2), "mask": torch.zeros(1, n_max)}
    return H2INTActor(obs, 2, **model.actor_kwargs())
