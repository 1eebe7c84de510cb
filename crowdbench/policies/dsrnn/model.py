"""DS-RNN (Liu et al. 2021, "Decentralized Structural-RNN for Robot Crowd Navigation with Deep Reinforcement
Learning"), as in Shuijing725/CrowdNav_DSRNN @91fb53c ``pytorchBaselines/a2c_ppo_acktr/srnn_model.py``.

The crowd is a graph whose edges carry their own recurrent state:

* **temporal edge** (the robot's own motion): its velocity → Linear(2→64)+ReLU → GRU(64→256);
* **spatial edges** (one per pedestrian slot): the pedestrian's position relative to the robot → Linear(2→64)+ReLU
  → GRU(64→256), weights shared by all slots, one hidden state per slot — so a slot must hold the same person from
  step to step: the policy reads the ``relative_by_id`` observation (slot j = pedestrian j, masked while outside the
  5 m sensing range);
* **attention**: Linear(256→64) on the temporal state (query) and on each spatial state (keys), dot products scaled
  by ``slots / √64`` (the original's ``num_edges / √attention_size``), softmax over the slots in view (none in view:
  nothing attended), the weighted sum of the spatial states;
* **node**: robot [p_x, p_y, r, g_x, g_y, v_pref, θ] → Linear(7→3) → Linear(3→64)+ReLU, the edges
  [temporal ‖ attended] → Linear(512→64)+ReLU, both into GRU(128→128) → Linear(128→256) = the latent the actor and
  critic heads (256→256→256, tanh) read.

:class:`DSRNNCore` keeps all of it as one flat recurrent state per world, ``256 + slots·256 + 128`` values, behind
the interface of :class:`~crowdbench.policies.nets.RecurrentCell` (rollout steps with an internal state; padded
trajectories from stored initial states in the update), so :class:`DSRNNActor` trains through
:mod:`crowdbench.training` like H²INT.
**Partial observability** (the original saw every human; here the robot senses 5 m): a slot's spatial state is
updated only while its pedestrian is in view and kept as it was while out of view (zero until first seen; the
attention ignores it meanwhile). Stepping every slot on a zero input instead made a default training iteration 2.5×
slower (most pedestrians are out of view), for a state that carries no observation.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import torch
from torch import nn

from crowdbench.policies.nets import (
    CarriedState,
    RecurrentTrunkActor,
    check_action_std,
    gaussian_cfg,
    unpad_trajectories,
)

ROBOT_NODE = 7
"""Robot node features: the first 7 of the robot vector [p_x, p_y, r, g_x, g_y, v_pref, θ]."""
SLOT_ORDERS = {"by_id": "relative_by_id", "nearest": "relative"}
""":attr:`DSRNNConfig.slots` → the observation it reads."""
DUMMY = 15.0
"""Relative position [m] (both axes) of an unseen slot with ``slots="nearest"`` (CrowdNav++'s dummy human)."""


@dataclass(frozen=True)
class DSRNNConfig:
    """DS-RNN's architecture (the original's sizes)."""

    edge_embed: int = 64
    """Edge input embedding width [-]."""
    edge_rnn: int = 256
    """Temporal and spatial edge GRU state size [-]."""
    attention: int = 64
    """Attention projection width [-]."""
    robot_dims: tuple[int, ...] = (3, 64)
    """Robot node embedding 7 → … (ReLU after the last) [-]."""
    edge_out: int = 64
    """Width of the edge features [temporal ‖ attended] → … (ReLU) [-]."""
    node_rnn: int = 128
    """Node GRU state size [-]."""
    latent: int = 256
    """Node output width (the latent the heads read) [-]."""
    head_dims: tuple[int, ...] = (256, 256)
    """Hidden widths of the actor and critic heads (tanh) [-]."""
    action_std: float = 1.0
    """Initial standard deviation of the Gaussian policy (state-independent; log-std 0) [m/s]."""
    learn_std: bool = True
    """Whether PPO learns the standard deviation (the original) or keeps it at :attr:`action_std` (H²INT's fixed
    covariance: ``--model learn_std=false --model action_std=0.3``)."""
    slots: str = "by_id"
    """What a spatial-edge slot holds. ``by_id``: pedestrian j (the ``relative_by_id`` observation), stepped only
    while in view, unseen slots masked out of the attention (CrowdNav_DSRNN's one state per person).
    ``nearest``: CrowdNav++'s DS-RNN baseline (``sort_humans``): the ``relative`` observation, nearest first;
    unseen slots hold a dummy at (15, 15) m, every slot is stepped and attended."""

    def __post_init__(self) -> None:
        if self.slots not in SLOT_ORDERS:
            raise ValueError(f"slots={self.slots!r}; valid choices: {', '.join(SLOT_ORDERS)}")
        check_action_std(self.action_std)

    @property
    def observation(self) -> str:
        """The robot observation this architecture reads."""
        return SLOT_ORDERS[self.slots]

    def actor_kwargs(self) -> dict[str, Any]:
        """Keyword arguments of :class:`DSRNNActor` (and of its rsl-rl adapter's ``actor`` config)."""
        return {"config": self, "hidden_dims": list(self.head_dims), "activation": "tanh",
                "distribution_cfg": gaussian_cfg(self.action_std, self.learn_std)}


class DSRNNCore(CarriedState):
    """DS-RNN's recurrence behind :class:`~crowdbench.policies.nets.RecurrentCell`'s interface (module docstring).

    Input per step: the flat observation ``(n, 9 + 3·slots)`` = robot vector (9) ‖ relative positions
    ``(slots, 2)`` flattened ‖ mask ``(slots,)``. Output: the latent ``(n, latent)``; state ``(1, n, state_dim)``.
    """

    def __init__(self, cfg: DSRNNConfig, slots: int) -> None:
        super().__init__()
        self.cfg, self.slots = cfg, slots
        E, R, N = cfg.edge_embed, cfg.edge_rnn, cfg.node_rnn
        self.temporal_embed = nn.Sequential(nn.Linear(2, E), nn.ReLU())
        self.spatial_embed = nn.Sequential(nn.Linear(2, E), nn.ReLU())
        self.temporal_rnn = nn.GRUCell(E, R)
        self.spatial_rnn = nn.GRUCell(E, R)
        self.query = nn.Linear(R, cfg.attention)
        self.key = nn.Linear(R, cfg.attention)
        dims = (ROBOT_NODE, *cfg.robot_dims)
        layers: list[nn.Module] = [nn.Linear(a, b) for a, b in zip(dims[:-1], dims[1:], strict=True)]
        self.robot_embed = nn.Sequential(*layers, nn.ReLU())
        self.edge_features = nn.Sequential(nn.Linear(2 * R, cfg.edge_out), nn.ReLU())
        self.node_rnn = nn.GRUCell(cfg.robot_dims[-1] + cfg.edge_out, N)
        self.node_out = nn.Linear(N, cfg.latent)
        self.state_dim = R + slots * R + N
        self.hidden_state: torch.Tensor | None = None

    def cell(self, x: torch.Tensor, h: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """One step: observations ``(n, 9 + 3·slots)``, states ``(n, state_dim)`` → latents ``(n, latent)``, new
        states (:meth:`split` / :meth:`join` around :meth:`step_parts`)."""
        out, parts = self.step_parts(x, self.split(h))
        return out, self.join(parts)

    def split(self, h: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """The state ``(n, state_dim)`` as its parts: temporal edge ``(n, R)``, spatial edges ``(n·slots, R)``, node
        ``(n, N)``."""
        R, K = self.cfg.edge_rnn, self.slots
        return h[:, :R], h[:, R:R + K * R].reshape(h.shape[0] * K, R), h[:, R + K * R:]

    def join(self, parts: tuple[torch.Tensor, torch.Tensor, torch.Tensor]) -> torch.Tensor:
        """:meth:`split`'s inverse: ``(n, state_dim)``."""
        ht, hs, hn = parts
        return torch.cat([ht, hs.reshape(ht.shape[0], -1), hn], -1)

    def step_parts(self, x: torch.Tensor, parts: tuple[torch.Tensor, torch.Tensor, torch.Tensor]
                   ) -> tuple[torch.Tensor, tuple[torch.Tensor, torch.Tensor, torch.Tensor]]:
        """One step on the state's parts (:meth:`split`): the update carries them from step to step as they are,
        so that no step joins and re-slices the whole state (nor zero-fills its gradient for each slice)."""
        n, K = x.shape[0], self.slots
        robot, rel, mask = x[:, :9], x[:, 9:9 + 2 * K].reshape(n, K, 2), x[:, 9 + 2 * K:] > 0.5
        if self.cfg.slots == "nearest":  # CrowdNav++: unseen slots are a far dummy, stepped and attended like the rest
            rel = torch.where(mask.unsqueeze(-1), rel, DUMMY)
            mask = torch.ones_like(mask)
        ht, hs, hn = parts
        ht = self.temporal_rnn(self.temporal_embed(robot[:, 7:9]), ht)
        seen = mask.reshape(n * K)
        hs = hs.clone()
        hs[seen] = self.spatial_rnn(self.spatial_embed(rel.reshape(n * K, 2)[seen]), hs[seen])  # in view only
        hk = hs.reshape(n, K, -1)
        score = (self.key(hk) @ self.query(ht).unsqueeze(-1)).squeeze(-1) * (K / math.sqrt(self.cfg.attention))
        weights = torch.softmax(score.masked_fill(~mask, -torch.inf), dim=-1)
        weights = torch.where(mask.any(-1, keepdim=True), weights, 0.0)  # nobody in view: nothing attended
        attended = (weights.unsqueeze(-1) * hk).sum(1)
        edges = self.edge_features(torch.cat([ht, attended], -1))
        hn = self.node_rnn(torch.cat([self.robot_embed(robot[:, :ROBOT_NODE]), edges], -1), hn)
        return self.node_out(hn), (ht, hs, hn)

    def forward(self, x: torch.Tensor, masks: torch.Tensor | None = None,
                hidden_state: torch.Tensor | None = None) -> torch.Tensor:
        """Rollout: ``x`` ``(n, ·)`` → ``(1, n, latent)`` from the internal state. Update: padded trajectories
        ``x`` ``(T, B, ·)`` with ``masks`` ``(T, B)`` from ``hidden_state`` ``(1, B, state_dim)`` → the valid steps
        ``(T, n_valid, latent)`` (:func:`~crowdbench.policies.nets.unpad_trajectories`)."""
        if masks is None:
            h = self.hidden_state[0] if self.hidden_state is not None else x.new_zeros(x.shape[0], self.state_dim)
            out, h = self.cell(x, h)
            self.hidden_state = h.unsqueeze(0)
            return out.unsqueeze(0)
        if hidden_state is None:
            raise ValueError("DSRNNCore: the update needs the stored initial hidden states")
        parts, outs = self.split(hidden_state[0]), []
        for t in range(x.shape[0]):
            out, parts = self.step_parts(x[t], parts)
            outs.append(out)
        return unpad_trajectories(torch.stack(outs), masks)


class DSRNNActor(RecurrentTrunkActor):
    """DS-RNN actor: the graph recurrence → tanh MLP head → Gaussian mean (learned state-independent std).

    Observation groups (``relative_by_id``): ``robot`` ``(·, 9)``, ``humans`` ``(·, N_max, 2)`` with slot j =
    pedestrian j, ``mask`` ``(·, N_max)``.
    """

    obs_keys = ("robot", "humans", "mask")

    def __init__(self, obs: Mapping[str, torch.Tensor], output_dim: int, config: DSRNNConfig | None = None,
                 hidden_dims: tuple[int, ...] | list[int] = (256, 256), activation: str = "tanh",
                 distribution_cfg: dict | None = None) -> None:
        self.dsrnn = config = config or DSRNNConfig()
        self.slots = obs["humans"].shape[-2]
        super().__init__(obs, output_dim, 9 + 3 * self.slots, config.latent, hidden_dims, activation, distribution_cfg)

    def make_rnn(self, z_dim: int, latent: int) -> nn.Module:
        return DSRNNCore(self.dsrnn, self.slots)

    @property
    def state_size(self) -> int:
        return self.rnn.state_dim

    def step(self, z: torch.Tensor, state: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        latent, h = self.rnn.cell(z, state[0])
        return latent, h.unsqueeze(0)

    def encode_samples(self, obs):
        """The flat per-step input of :class:`DSRNNCore`: robot ‖ positions ‖ mask ``(n, 9 + 3·slots)``."""
        n = obs["robot"].shape[0]
        return torch.cat([obs["robot"], obs["humans"].reshape(n, -1), obs["mask"]], -1)


def build_actor(model: DSRNNConfig, n_max: int) -> DSRNNActor:
    """An untrained actor of architecture ``model`` for ``n_max`` observation slots."""
    obs = {"robot": torch.zeros(1, 9), "humans": torch.zeros(1, n_max, 2), "mask": torch.zeros(1, n_max)}
    return DSRNNActor(obs, 2, **model.actor_kwargs())
