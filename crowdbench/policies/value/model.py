"""CrowdNav's value networks: CADRL (Chen et al. 2017) and SARL (Chen et al. 2019), as in vita-epfl/CrowdNav
(``crowd_nav/policy/{cadrl,sarl}.py`` at 20d6780, ``configs/policy.config``).

Both map a batch of rotated joint states (:mod:`crowdbench.policies.value.lookahead`) to state values:

* input ``state`` ``(S, K, 13)`` — per state, ``K`` pedestrian slots of [robot d_g, v_pref, θ, r, v_x, v_y ‖
  pedestrian p_x, p_y, v_x, v_y, r, d, r + r_h] in the goal-aligned frame; ``mask`` ``(S, K)`` bool, valid slots
  first; every state has at least one valid slot (the look-ahead inserts a far dummy pedestrian when none is seen);
* output ``(S,)`` values.

``forward`` runs the per-pedestrian MLPs on the valid slots only (the fast path: states see 1–30 pedestrians);
``reference`` runs them on every slot and masks afterwards — the plain version of the paper's equations, the test
oracle of ``forward``.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

STATE_DIM = 13
"""Joint-state width: 6 robot values followed by 7 pedestrian values."""
SELF_DIM = 6


def run_mlp(seq: nn.Sequential | tuple[nn.Module, ...], x: torch.Tensor) -> torch.Tensor:
    """``seq(x)`` for 2-D ``x``, each Linear as the ``addmm`` that ``nn.Linear`` runs (bitwise the same, verified on
    Q-values and gradients, without the module call per layer); without autograd (look-ahead, evaluation)
    each ReLU runs in place on its layer's fresh output."""
    inplace = not torch.is_grad_enabled()
    for layer in seq:
        if isinstance(layer, nn.ReLU):
            x = x.relu_() if inplace else torch.relu(x)
        else:
            x = torch.addmm(layer.bias, x, layer.weight.t())
    return x


def mlp(dims: tuple[int, ...], last_relu: bool = False) -> nn.Sequential:
    """Linear layers ``dims[0] → … → dims[-1]`` with ReLU between them (and after the last if ``last_relu``), as
    CrowdNav's ``mlp``."""
    layers: list[nn.Module] = []
    for i in range(len(dims) - 1):
        layers.append(nn.Linear(dims[i], dims[i + 1]))
        if i < len(dims) - 2 or last_relu:
            layers.append(nn.ReLU())
    return nn.Sequential(*layers)


@dataclass(frozen=True)
class CADRLConfig:
    """CADRL's pairwise value network (CrowdNav ``[cadrl] mlp_dims = 150, 100, 100, 1``)."""

    mlp_dims: tuple[int, ...] = (150, 100, 100)
    """Hidden widths of the MLP 13 → … → 1."""


@dataclass(frozen=True)
class SARLConfig:
    """SARL's crowd value network (CrowdNav ``[sarl]`` with ``with_global_state = true``, ``with_om = false``)."""

    mlp1_dims: tuple[int, ...] = (150, 100)
    """Per-pedestrian embedding 13 → …, ReLU after the last layer too."""
    mlp2_dims: tuple[int, ...] = (100, 50)
    """Per-pedestrian feature from the embedding."""
    attention_dims: tuple[int, ...] = (100, 100)
    """Attention score MLP on [embedding ‖ mean embedding] → … → 1."""
    mlp3_dims: tuple[int, ...] = (150, 100, 100)
    """Value MLP on [6 robot values ‖ attended feature] → … → 1."""


class CADRLNet(nn.Module):
    """CADRL: value of a state = min over pedestrians of the pairwise value f(robot, pedestrian)."""

    def __init__(self, cfg: CADRLConfig | None = None) -> None:
        super().__init__()
        self.cfg = cfg = cfg or CADRLConfig()
        self.value = mlp((STATE_DIM, *cfg.mlp_dims, 1))

    def forward(self, state: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """Values ``(S,)`` of joint states ``(S, K, 13)`` with valid slots ``mask`` ``(S, K)``."""
        if bool(mask.all()):  # one robot's look-ahead: every slot holds a pedestrian
            S, K, _ = state.shape
            return run_mlp(self.value, state.reshape(S * K, -1)).view(S, K).amin(dim=1)
        pair = state.new_full(mask.shape, torch.inf)
        pair[mask] = run_mlp(self.value, state[mask]).squeeze(-1)
        return pair.amin(dim=1)

    def reference(self, state: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        pair = self.value(state).squeeze(-1)
        return torch.where(mask, pair, torch.inf).amin(dim=1)


class SARLNet(nn.Module):
    """SARL: pedestrians embedded, weighted by self-attention against the crowd's mean embedding, pooled, and
    valued together with the robot's own state."""

    def __init__(self, cfg: SARLConfig | None = None) -> None:
        super().__init__()
        self.cfg = cfg = cfg or SARLConfig()
        self.mlp1 = mlp((STATE_DIM, *cfg.mlp1_dims), last_relu=True)
        self.mlp2 = mlp((cfg.mlp1_dims[-1], *cfg.mlp2_dims))
        self.attention = mlp((2 * cfg.mlp1_dims[-1], *cfg.attention_dims, 1))
        # the score MLP after its first layer (that layer is split in forward); a plain tuple, not a submodule
        self._attention_rest: tuple[nn.Module, ...] = tuple(self.attention)[1:]
        self.mlp3 = mlp((SELF_DIM + cfg.mlp2_dims[-1], *cfg.mlp3_dims, 1))

    def _pool(self, state: torch.Tensor, score: torch.Tensor, feat: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """Masked softmax of the scores ``(S, K)``, attended feature, value MLP → ``(S,)``."""
        weights = torch.softmax(score.masked_fill(~mask, -torch.inf), dim=1)  # (S, K)
        pooled = (weights.unsqueeze(-1) * feat).sum(dim=1)
        return run_mlp(self.mlp3, torch.cat([state[:, 0, :SELF_DIM], pooled], dim=-1)).squeeze(-1)

    def forward(self, state: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """Values ``(S,)`` of joint states ``(S, K, 13)`` with valid slots ``mask`` ``(S, K)``."""
        S, K, _ = state.shape
        d = self.cfg.mlp1_dims[-1]
        # one robot's look-ahead fills every slot (K = the pedestrians it senses): the same arithmetic without the
        # gathers and scatters (13 % of a decision, bitwise equal)
        dense = bool(mask.all())

        def spread(x: torch.Tensor) -> torch.Tensor:  # per-pedestrian rows (R, ·) → (S, K, ·), zeros elsewhere
            if dense:
                return x.view(S, K, *x.shape[1:])
            out = x.new_zeros(S, K, *x.shape[1:])
            out[mask] = x
            return out

        rows = state.reshape(S * K, -1) if dense else state[mask]  # (R, 13): only the pedestrians that exist
        h = run_mlp(self.mlp1, rows)
        mean = spread(h).sum(dim=1) / mask.sum(dim=1, keepdim=True)
        # the score MLP's first layer on [h ‖ mean] = W_h·h + (W_g·mean + b): the mean's half once per state
        first = self.attention[0]
        w_h, w_g = first.weight[:, :d], first.weight[:, d:]
        per_state = nn.functional.linear(mean, w_g, first.bias)  # (S, A1)
        z = nn.functional.linear(h, w_h)
        if dense:  # broadcast over each state's K rows, in place (the same sums as the gather below)
            z.view(S, K, -1).add_(per_state.unsqueeze(1))
        else:
            z = z + per_state[torch.arange(S).unsqueeze(1).expand(S, K)[mask]]
        score = spread(run_mlp(self._attention_rest, z).squeeze(-1))
        return self._pool(state, score, spread(run_mlp(self.mlp2, h)), mask)

    def reference(self, state: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        emb = self.mlp1(state) * mask.unsqueeze(-1)
        mean = emb.sum(dim=1, keepdim=True) / mask.sum(dim=1, keepdim=True).unsqueeze(-1)
        score = self.attention(torch.cat([emb, mean.expand_as(emb)], dim=-1)).squeeze(-1)
        return self._pool(state, score, self.mlp2(emb), mask)


NETWORKS: dict[str, tuple[type, type]] = {"cadrl": (CADRLNet, CADRLConfig), "sarl": (SARLNet, SARLConfig)}
"""Method name → (network class, its config dataclass)."""


def build_net(method: str, model: dict | None = None) -> nn.Module:
    """The value network of ``method`` (``cadrl`` or ``sarl``) with architecture fields ``model`` (default: the
    paper's)."""
    if method not in NETWORKS:
        raise ValueError(f"method={method!r}; valid choices: {', '.join(NETWORKS)}")
    net_cls, cfg_cls = NETWORKS[method]
    fields = {k: tuple(v) for k, v in (model or {}).items()}
    valid = set(cfg_cls.__dataclass_fields__)
    bad = sorted(set(fields) - valid)
    if bad:
        raise ValueError(f"{method} model: unknown keys {bad}; valid choices: {', '.join(sorted(valid))}")
    return net_cls(cfg_cls(**fields))
