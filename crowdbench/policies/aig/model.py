"""AIG-GST (Liu et al. 2023, "Intention Aware Robot Crowd Navigation with Attention-Based Interaction Graph"), as in
Shuijing725/CrowdNav_Prediction_AttnGraph ``rl/networks/selfAttn_srnn_temp_node.py``.

Per step, from the ``predicted`` observation (pedestrians in view, nearest first, each with its current and 5
predicted positions relative to the robot — :mod:`crowdbench.predictors.observation`):

* **robot**: [v_x, v_y ‖ p_x, p_y, r, g_x, g_y, v_pref, θ] → Linear(9→256)+ReLU;
* **human–human attention**: spatial edges (12) → Linear(12→128)+ReLU → Linear(128→512)+ReLU, separate q/k/v
  Linear(512→512), ``nn.MultiheadAttention(512, 8)`` with a key-padding mask (pedestrians not in view), then
  Linear(512→256)+ReLU;
* **robot–human attention**: Linear(256→64) on the robot embedding (query) and on each pedestrian's (keys), dot
  products scaled by ``slots / √64`` (the original's ``num_edges / √attention_size``), softmax over those in view,
  the weighted sum of the pedestrian embeddings (256) — nothing attended when nobody is in view (the original
  attends a padded dummy then);
* **node**: [robot 256 → Linear(→64)+ReLU ‖ attended 256 → Linear(→64)+ReLU] → GRU(128→128) → Linear(128→256),
  the latent of the actor and critic heads (256→256→256, tanh), as DS-RNN.

The encoder (everything before the GRU) is :meth:`AIGActor.encode_samples`, so the generic trunk
(:class:`~crowdbench.policies.nets.RecurrentTrunkActor`) trains it; only the GRU's output layer is added
(:class:`GRUWithOutput`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import torch
import torch.nn.functional as F  # noqa: N812 - the usual alias
from torch import nn

from crowdbench.nn.ragged import ragged_attention_qkv, row_offsets
from crowdbench.policies.nets import RecurrentCell, RecurrentTrunkActor, check_action_std, gaussian_cfg


@dataclass(frozen=True)
class AIGConfig:
    """AIG-GST's architecture (the original's sizes) and the predictor its observation runs."""

    robot_embed: int = 256
    """Robot embedding width (Linear(9→·)+ReLU) [-]."""
    edge_dims: tuple[int, ...] = (128, 512)
    """Spatial-edge embedding 12 → … (ReLU after each); the last is the self-attention width [-]."""
    heads: int = 8
    """Human–human attention heads [-]."""
    human_embed: int = 256
    """Width after the self-attention (Linear(·)+ReLU) [-]."""
    attention: int = 64
    """Robot–human attention projection width [-]."""
    node_embed: int = 64
    """Robot and attended-edge embeddings into the node GRU, each [-]."""
    node_rnn: int = 128
    """Node GRU state size [-]."""
    latent: int = 256
    """Node output width (the latent the heads read) [-]."""
    head_dims: tuple[int, ...] = (256, 256)
    """Hidden widths of the actor and critic heads (tanh) [-]."""
    action_std: float = 1.0
    """Initial standard deviation of the Gaussian policy (state-independent) [m/s]."""
    learn_std: bool = True
    """Whether PPO learns the standard deviation (the original) or keeps it at :attr:`action_std` (the shipped
    DS-RNN's recipe: ``--model learn_std=false --model action_std=0.3``)."""
    predictor: str = "gst"
    """Trajectory predictor of the ``predicted`` observation: ``gst`` (learned), ``const_vel`` or ``truth``."""
    predictor_checkpoint: str = "gst-crowdnavpp"
    """The ``gst`` predictor's checkpoint (path or shipped name): by default the one trained on the CrowdNav++
    crowd; the checkpoints trained on crowdbench 0.2's crowd keep ``gst`` (that crowd's) in their stored config."""

    def __post_init__(self) -> None:
        check_action_std(self.action_std)

    def actor_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :class:`AIGActor` (and of its rsl-rl adapter's ``actor`` config)."""
        return {"config": self, "hidden_dims": list(self.head_dims), "activation": "tanh",
                "distribution_cfg": gaussian_cfg(self.action_std, self.learn_std)}

    def observation_kwargs(self) -> dict[str, Any]:
        """Options of the ``predicted`` observation this network reads."""
        if self.predictor == "gst":
            return {"predictor": "gst", "checkpoint": self.predictor_checkpoint}
        return {"predictor": self.predictor}


class GRUWithOutput(RecurrentCell):
    """A one-layer GRU followed by a Linear output layer (AIG-GST's node RNN: GRU(128→128) → Linear(128→256)).
    Same interface as :class:`~crowdbench.policies.nets.RecurrentCell`; the carried state is the GRU's."""

    def __init__(self, input_size: int, hidden_size: int, output_size: int) -> None:
        super().__init__(input_size, hidden_size)
        self.out = nn.Linear(hidden_size, output_size)

    def forward(self, input: torch.Tensor, masks: torch.Tensor | None = None,  # noqa: A002 - rsl-rl's name
                hidden_state: torch.Tensor | None = None) -> torch.Tensor:
        return self.out(super().forward(input, masks, hidden_state))


class AIGActor(RecurrentTrunkActor):
    """AIG-GST actor: the attention encoder → node GRU → tanh MLP head → Gaussian mean.

    Observation groups (``predicted``): ``robot`` ``(·, 9)``, ``humans`` ``(·, N_max, 12)`` nearest first, ``mask``
    ``(·, N_max)``.
    """

    obs_keys = ("robot", "humans", "mask")

    def __init__(self, obs: Mapping[str, torch.Tensor], output_dim: int, config: AIGConfig | None = None,
                 hidden_dims: tuple[int, ...] | list[int] = (256, 256), activation: str = "tanh",
                 distribution_cfg: dict | None = None) -> None:
        self.aig = cfg = config or AIGConfig()
        self.slots, self.edge_dim = obs["humans"].shape[-2], obs["humans"].shape[-1]
        super().__init__(obs, output_dim, 2 * cfg.node_embed, cfg.latent, hidden_dims, activation, distribution_cfg)
        width = cfg.edge_dims[-1]
        self.robot_embed = nn.Sequential(nn.Linear(9, cfg.robot_embed), nn.ReLU())
        dims = (self.edge_dim, *cfg.edge_dims)
        self.edge_embed = nn.Sequential(*[m for a, b in zip(dims[:-1], dims[1:], strict=True)
                                          for m in (nn.Linear(a, b), nn.ReLU())])
        self.q, self.k, self.v = (nn.Linear(width, width) for _ in range(3))
        self.self_attn = nn.MultiheadAttention(width, cfg.heads, batch_first=True)
        self.human_out = nn.Sequential(nn.Linear(width, cfg.human_embed), nn.ReLU())
        self.query = nn.Linear(cfg.robot_embed, cfg.attention)
        self.key = nn.Linear(cfg.human_embed, cfg.attention)
        self.robot_node = nn.Sequential(nn.Linear(cfg.robot_embed, cfg.node_embed), nn.ReLU())
        self.edge_node = nn.Sequential(nn.Linear(cfg.human_embed, cfg.node_embed), nn.ReLU())

    def make_rnn(self, z_dim: int, latent: int) -> nn.Module:
        return GRUWithOutput(z_dim, self.aig.node_rnn, latent)

    @property
    def state_size(self) -> int:
        return self.aig.node_rnn

    def step(self, z: torch.Tensor, state: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        out, nxt = self.rnn.rnn(z.unsqueeze(0), state)
        return self.rnn.out(out.squeeze(0)), nxt

    def encode_samples(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """The node GRU's input ``(n, 128)`` from ``robot`` ``(n, 9)``, ``humans`` ``(n, N_max, 12)`` and ``mask``
        ``(n, N_max)`` (nearest first).

        The pedestrians in view are packed into ``(P, ·)`` rows (row ``b`` of the batch owning ``offsets[b]:
        offsets[b+1]``): every per-pedestrian product runs once over the ``P`` rows, the self-attention within each
        row's pedestrians (:func:`crowdbench.nn.ragged.ragged_attention_qkv`), the robot–pedestrian softmax per segment;
        the original's two consecutive linear maps per attention input (``self.q`` then the attention's own input
        projection) run as one product of the two (the same function; its gradient reaches both). Equal to
        :meth:`encode_samples_reference` (the original's padded layout) up to rounding (tested)."""
        return self._encode(obs, self._pool_packed)

    def encode_samples_reference(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """:meth:`encode_samples` as the original writes it (plain modules on the padded ``(rows, k)`` layout)."""
        return self._encode(obs, self._pool_padded)

    def _encode(self, obs: Mapping[str, torch.Tensor],
                pool: Callable[[torch.Tensor, torch.Tensor, torch.Tensor], torch.Tensor]) -> torch.Tensor:
        """Robot embedding, the crowd pooled by ``pool(humans (R, k, 12), in view (R, k), robot embedding (R, ·))``
        → ``(R, human_embed)`` on the ``R`` rows with someone in view (``k``: the batch's most in view), the node
        inputs."""
        robot, mask = obs["robot"], obs["mask"] > 0.5
        n = robot.shape[0]
        r = self.robot_embed(torch.cat([robot[:, 7:9], robot[:, :7]], -1))
        attended = r.new_zeros(n, self.aig.human_embed)
        k = int(mask.sum(-1).max()) if n else 0
        rows = mask[:, 0]  # someone in view (nearest first)
        if k:
            pooled = pool(obs["humans"][rows, :k], mask[rows, :k], r[rows])
            attended = attended.index_put((rows.nonzero().squeeze(-1),), pooled)
        return torch.cat([self.robot_node(r), self.edge_node(attended)], -1)

    def _pool_packed(self, humans: torch.Tensor, m: torch.Tensor, r: torch.Tensor) -> torch.Tensor:
        counts = m.sum(-1)  # (R,) pedestrians in view per row, nearest first
        offsets = row_offsets(counts)  # row b owns packed rows offsets[b]:offsets[b+1]
        e = self.edge_embed(humans[m])  # (P, W) packed
        qkv = self._qkv(e)  # (P, 3W)
        z = ragged_attention_qkv(qkv, offsets, self.self_attn.num_heads)
        h = self.human_out(self.self_attn.out_proj(z))  # (P, human_embed)
        seg = torch.repeat_interleave(torch.arange(len(counts)), counts)  # (P,) each pedestrian's row
        score = (self.key(h) * self.query(r).index_select(0, seg)).sum(-1)
        score = score * (self.slots / math.sqrt(self.aig.attention))  # (P,)
        top = score.new_full((len(counts),), -torch.inf).scatter_reduce(0, seg, score.detach(), "amax")
        w = torch.exp(score - top.index_select(0, seg))
        w = w / w.new_zeros(len(counts)).index_add(0, seg, w).index_select(0, seg)  # softmax within each row
        return h.new_zeros(len(counts), h.shape[-1]).index_add(0, seg, w.unsqueeze(-1) * h)

    def _pool_padded(self, humans: torch.Tensor, m: torch.Tensor, r: torch.Tensor) -> torch.Tensor:
        e = self.edge_embed(humans)
        z, _ = self.self_attn(self.q(e), self.k(e), self.v(e), key_padding_mask=~m, need_weights=False)
        h = self.human_out(z)
        score = (self.key(h) @ self.query(r).unsqueeze(-1)).squeeze(-1)
        score = score * (self.slots / math.sqrt(self.aig.attention))
        w = torch.softmax(score.masked_fill(~m, -torch.inf), dim=-1)
        return (w.unsqueeze(-1) * h).sum(1)

    def _qkv(self, e: torch.Tensor) -> torch.Tensor:
        """The attention inputs ``(P, 3W)`` of pedestrian embeddings ``e`` ``(P, W)``: the attention's input
        projection after ``self.q`` / ``self.k`` / ``self.v``, as one map ``in_proj ∘ q`` (``W³`` products each, once)
        when there are more pedestrians than the width ``W``, else the two maps in turn."""
        W = e.shape[-1]
        win, bin_ = self.self_attn.in_proj_weight.view(3, W, W), self.self_attn.in_proj_bias.view(3, W)
        wq = torch.stack([self.q.weight, self.k.weight, self.v.weight])  # (3, W, W)
        bq = torch.stack([self.q.bias, self.k.bias, self.v.bias])
        if e.shape[0] <= W:
            first = torch.baddbmm(bq.unsqueeze(1), e.expand(3, -1, -1), wq.transpose(1, 2))  # (3, P, W)
            return torch.baddbmm(bin_.unsqueeze(1), first, win.transpose(1, 2)).permute(1, 0, 2).reshape(-1, 3 * W)
        weight = (win @ wq).reshape(3 * W, W)
        bias = ((win @ bq.unsqueeze(-1)).squeeze(-1) + bin_).reshape(3 * W)
        return F.linear(e, weight, bias)

    def work(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """Encoding cost grows with the pedestrians in view (quadratically in the self-attention)."""
        return 1.0 + obs["mask"].sum(-1).float().square() / 16.0


def build_actor(model: AIGConfig, n_max: int, horizon: int = 5) -> AIGActor:
    """An untrained actor of architecture ``model`` for ``n_max`` observation slots."""
    obs = {"robot": torch.zeros(1, 9), "humans": torch.zeros(1, n_max, 2 + 2 * horizon), "mask": torch.zeros(1, n_max)}
    return AIGActor(obs, 2, **model.actor_kwargs())
