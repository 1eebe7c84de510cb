"""The H²INT network (§Methodology) as rsl-rl 5 models, plus its export module.

Tokens: the robot vector w̃ = [px, py, r, gx, gy, v_pref, θ, vx, vy] (9-d) → MLP → φ_r, and each observed pedestrian's
relative position (Δx, Δy) → shared MLP → φ_e. Every token gets a type embedding (robot / edge) and a learned
positional embedding whose *position is the token's rank in the distance-sorted sequence* (0 = robot, 1 = nearest
pedestrian, ...). Two gated Transformer stages follow — pre-LayerNorm, GRU-style gates (Parisotto et al., GTrXL)
after attention and after the FFN, attention masked so padded or unseen pedestrians never contribute — then the robot
token z = X⁽²⁾₀ feeds a GRU whose state h_t is shared by the actor head (mean of a Gaussian with fixed diagonal
covariance) and the value head.

Variants (same code path): ``h2int`` (2 gated stages), ``flat`` (1 stage), ``meanpool`` (attention replaced by the
mean of the valid tokens), ``standard`` (plain residual connections instead of gates).

rsl-rl keeps actor and critic as two modules; to share the trunk as the paper does, :class:`H2INTCritic` holds a
(non-registered) reference to the actor and reuses the actor's latent for the same observation object (PPO always
calls the actor first), computing it through the shared trunk otherwise.
"""

from __future__ import annotations

import torch
import torch.nn as nn
import torch.nn.functional as F  # noqa: N812 - the PyTorch convention
from rsl_rl.algorithms import PPO
from rsl_rl.models import MLPModel
from rsl_rl.modules import RNN, EmpiricalNormalization
from tensordict import TensorDict

from crowdbench.policies import packed, parallel_ppo
from crowdbench.policies.buckets import INFERENCE_OVERHEAD, TRAIN_OVERHEAD, last_column, partition
from crowdbench.policies.parallel import parallel_map

VARIANTS = ("h2int", "flat", "meanpool", "standard")
EDGE_SCALE = 5.0
"""Relative positions are divided by this (the sensing range) before the edge MLP [m]."""


def script(module: nn.Module, freeze: bool = False) -> torch.jit.ScriptModule:
    """``torch.jit.script(module)`` (then ``torch.jit.freeze`` if ``freeze``) without the deprecation warnings:
    TorchScript is deprecated in torch 2.13 but is still the fastest way here to run these small networks without
    Python overhead."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        scripted = torch.jit.script(module)
        return torch.jit.freeze(scripted) if freeze else scripted


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
    """One encoder stage: Y = Gate₁(X, MHA(LN(X))), X' = Gate₂(Y, FFN(LN(Y))) (plain residuals for ``standard``).

    ``robot_only=True`` (used for the last stage) returns only the robot token's output ``(B, d)``: every other
    token's output would be discarded, so only its keys and values are computed — the same result at about half the
    cost of the stage.
    """

    __constants__ = ["heads", "gated", "attention"]  # TorchScript: branches on them are resolved at compile time

    def __init__(self, d: int, heads: int, ffn: int, gated: bool, attention: bool) -> None:
        super().__init__()
        self.heads, self.gated, self.attention = heads, gated, attention
        self.ln1, self.ln2 = nn.LayerNorm(d), nn.LayerNorm(d)
        self.qkv = nn.Linear(d, 3 * d)
        self.out = nn.Linear(d, d)
        self.ffn = nn.Sequential(nn.Linear(d, ffn), nn.GELU(), nn.Linear(ffn, d))
        if gated:
            self.gate1, self.gate2 = GRUGate(d), GRUGate(d)

    def mix(self, x: torch.Tensor, valid: torch.Tensor, robot_only: bool = False) -> torch.Tensor:
        """Masked multi-head self-attention (or masked mean pooling) over tokens ``x`` ``(B, S, d)``, ``valid``
        ``(B, S)`` → ``(B, S, d)``, or ``(B, 1, d)`` (the robot token's) when ``robot_only``."""
        B, S, d = x.shape
        h, w, b = self.heads, self.qkv.weight, self.qkv.bias
        kv = F.linear(x, w[d:], b[d:])
        k, v = kv[..., :d], kv[..., d:]
        if not self.attention:  # meanpool: every token receives the mean of the valid tokens' values
            m = valid.to(v.dtype).unsqueeze(-1)
            pooled = self.out((v * m).sum(1, keepdim=True) / m.sum(1, keepdim=True))
            return pooled if robot_only else pooled.expand(B, S, d)
        # keys of padded / unseen pedestrians never contribute (the robot key is always valid: no empty rows)
        if robot_only:  # one query per sample: elementwise products beat SDPA's tiny kernels 1.1-2.1x
            q = F.linear(x[:, 0], w[:d], b[:d]).view(B, 1, h, d // h)
            kh, vh = k.view(B, S, h, d // h), v.view(B, S, h, d // h)
            scores = (kh * q).sum(-1) * (float(d // h) ** -0.5)  # (B, S, h)
            p = torch.softmax(scores.masked_fill(~valid.unsqueeze(-1), float("-inf")), 1)
            return self.out((p.unsqueeze(-1) * vh).sum(1).reshape(B, 1, d))
        q = F.linear(x, w[:d], b[:d]).view(B, S, h, d // h).transpose(1, 2)
        k = k.view(B, S, h, d // h).transpose(1, 2)
        v = v.view(B, S, h, d // h).transpose(1, 2)
        att = F.scaled_dot_product_attention(q, k, v, attn_mask=valid[:, None, None, :])
        return self.out(att.transpose(1, 2).reshape(B, S, d))

    def forward(self, x: torch.Tensor, valid: torch.Tensor, robot_only: bool = False) -> torch.Tensor:
        """``x`` ``(B, S, d)`` → ``(B, S, d)``, or the robot token's output ``(B, d)`` when ``robot_only``."""
        a = self.mix(self.ln1(x), valid, robot_only)
        if robot_only:
            x, a = x[:, 0], a[:, 0]
        y = self.gate1(x, a) if self.gated else x + a
        f = self.ffn(self.ln2(y))
        return self.gate2(y, f) if self.gated else y + f


class H2INTEncoder(nn.Module):
    """Robot vector ``(B, 9)`` + edges ``(B, N, 2)`` + validity ``(B, N)`` bool → context z ``(B, d)``."""

    def __init__(self, n_max: int, variant: str = "h2int", d_model: int = 32, heads: int = 4, ffn: int = 64):
        super().__init__()
        if variant not in VARIANTS:
            raise ValueError(f"variant={variant!r}; valid choices: {', '.join(VARIANTS)}")
        self.edge_scale = EDGE_SCALE
        self.robot_norm = EmpiricalNormalization(9)
        self.robot_mlp = nn.Sequential(nn.Linear(9, d_model), nn.ReLU(), nn.Linear(d_model, d_model))
        self.edge_mlp = nn.Sequential(nn.Linear(2, d_model), nn.ReLU(), nn.Linear(d_model, d_model))
        self.type_emb = nn.Embedding(2, d_model)
        self.pos_emb = nn.Embedding(n_max + 1, d_model)
        n_stages = 1 if variant == "flat" else 2
        self.n_stages = n_stages
        self.stages = nn.ModuleList(Stage(d_model, heads, ffn, gated=variant != "standard",
                                          attention=variant != "meanpool") for _ in range(n_stages))
        self.final_ln = nn.LayerNorm(d_model)
        self.register_buffer("types", torch.cat([torch.zeros(1, dtype=torch.long),
                                                 torch.ones(n_max, dtype=torch.long)]), persistent=False)
        self.register_buffer("positions", torch.arange(n_max + 1), persistent=False)

    def forward(self, robot: torch.Tensor, edges: torch.Tensor, valid: torch.Tensor, trim: bool = False):
        """``trim=True`` drops the trailing token columns that are invalid for the whole batch (observations are
        sorted by distance, so padding sits at the end): the output is unchanged, the cost drops with the crowd seen."""
        n = edges.shape[1]
        if trim:
            cols = torch.arange(1, n + 1, device=valid.device)
            n = int((valid.long() * cols).max()) if valid.numel() else 0  # last valid column + 1
            edges, valid = edges[:, :n], valid[:, :n]
        phi_r = self.robot_mlp(self.robot_norm(robot)).unsqueeze(1)
        phi_e = self.edge_mlp(edges / self.edge_scale)
        x = torch.cat([phi_r, phi_e], 1) + self.type_emb(self.types[: n + 1]) + self.pos_emb(self.positions[: n + 1])
        tok_valid = torch.cat([valid.new_ones((valid.shape[0], 1)), valid], 1)  # the robot token is always valid
        for i, stage in enumerate(self.stages):  # the last stage computes the robot token only: x → (B, d)
            x = stage(x, tok_valid, i == self.n_stages - 1)
        return self.final_ln(x)


class H2INTActor(MLPModel):
    """rsl-rl actor: encoder → GRU → MLP head → Gaussian mean (fixed covariance via ``distribution_cfg``).

    Observation groups: ``robot`` ``(·, 9)``, ``humans`` ``(·, N_max, 2)``, ``mask`` ``(·, N_max)`` (1 = valid).
    """

    is_recurrent = True

    def __init__(self, obs: TensorDict, obs_groups: dict, obs_set: str, output_dim: int, variant: str = "h2int",
                 d_model: int = 32, heads: int = 4, ffn: int = 64, gru_hidden: int = 64,
                 hidden_dims: tuple[int, ...] | list[int] = (64,), activation: str = "elu",
                 distribution_cfg: dict | None = None, obs_normalization: bool = False) -> None:
        self.latent_dim = gru_hidden
        super().__init__(obs, obs_groups, obs_set, output_dim, hidden_dims, activation, False, distribution_cfg)
        n_max = obs["humans"].shape[-2]
        self.encoder = H2INTEncoder(n_max, variant, d_model, heads, ffn)
        self.rnn = RNN(d_model, gru_hidden, 1, "gru")
        self._cache: tuple | None = None
        self._critic_head: nn.Module | None = None  # the critic's value MLP (a reference, not a submodule)
        self.threads = 1
        """CPU threads the encoder splits a batch across (set by the trainer; not saved)."""
        self.packed = False
        """Encode through :mod:`crowdbench.policies.packed` (valid tokens only, ragged attention) instead of
        :meth:`bucketed` — ≈ 2× faster forward + backward; equal to float rounding. The trainer turns it on;
        evaluation keeps the bucketed path, so published results reproduce bit for bit. Not saved."""
        # the compiled encoder and its buffers (a plain tuple, not a registered submodule: checkpoints keep their keys)
        self._scripted: tuple[nn.Module, list[tuple[torch.Tensor, nn.Module, str]]] | None = None

    def _get_obs_dim(self, obs, obs_groups, obs_set):
        return ["robot", "humans", "mask"], 9

    def _get_latent_dim(self) -> int:
        return self.latent_dim

    def bucketed(self, robot: torch.Tensor, edges: torch.Tensor, valid: torch.Tensor, max_groups: int = 8,
                 threads: int | None = None):
        """Encode samples grouped by how many pedestrians they see, each group trimmed to its own maximum: exact
        (samples are independent), and most samples see few pedestrians, so little attention is spent on padding.
        The groups are chosen to minimise padded tokens plus a per-call overhead
        (:func:`crowdbench.policies.buckets.partition`). With ``self.threads > 1`` the samples are dealt round-robin
        (in that order, so the shares cost the same) to that many threads, forward and backward
        (:mod:`crowdbench.policies.parallel`); ``threads`` overrides that count."""
        if robot.shape[0] < 64:
            return self.encoder(robot, edges, valid, trim=True)
        if torch.is_inference_mode_enabled():  # no_grad instead (see scripted_encoder); the result is used as usual
            with torch.inference_mode(False), torch.no_grad():
                return self.bucketed(robot, edges, valid, max_groups, threads)
        last = last_column(valid)
        order = torch.argsort(last, stable=True)
        overhead = TRAIN_OVERHEAD if torch.is_grad_enabled() else INFERENCE_OVERHEAD

        encoder = self.scripted_encoder()

        def encode(idx: torch.Tensor) -> torch.Tensor:  # idx: sample indices sorted by last column
            sizes = partition(last[idx], max_groups, overhead)
            return torch.cat([encoder(robot[i], edges[i], valid[i], True) for i in idx.split(sizes)])

        shares = self._thread_shares(order, threads)
        if shares:
            return parallel_map(self.encoder, lambda k: encode(shares[k]), shares, robot.shape[0])
        out = robot.new_empty((robot.shape[0], self.encoder.final_ln.normalized_shape[0]))
        out[order] = encode(order)
        return out

    def packed_encode(self, robot: torch.Tensor, edges: torch.Tensor, valid: torch.Tensor,
                      threads: int | None = None) -> torch.Tensor:
        """:func:`crowdbench.policies.packed.packed_encode` on ``self.threads`` threads (samples dealt round-robin in
        order of crowd size, so the shares cost the same; forward and backward, :mod:`crowdbench.policies.parallel`).
        """
        enc = self.encoder
        shares = self._thread_shares(torch.argsort(valid.sum(1), stable=True), threads)
        if shares:
            def encode(k: int) -> torch.Tensor:
                i = shares[k]
                return packed.packed_encode(enc, robot[i], edges[i], valid[i])
            return parallel_map(enc, encode, shares, robot.shape[0])
        return packed.packed_encode(enc, robot, edges, valid)

    def _thread_shares(self, order: torch.Tensor, threads: int | None = None) -> list[torch.Tensor] | None:
        """Samples in ``order`` (ascending cost) dealt round-robin to ``threads`` (default ``self.threads``) shares,
        or ``None`` to stay on one thread: always for one thread, and for inference batches below ~1000 samples (the
        hand-off costs more than it saves, and rollouts share the cores with the world processes)."""
        n, threads = order.shape[0], self.threads if threads is None else threads
        if threads > 1 and n >= (64 * threads if torch.is_grad_enabled() else 1024):
            return [order[k::threads] for k in range(threads)]
        return None

    def scripted_encoder(self) -> nn.Module:
        """The encoder compiled with TorchScript (the eager one where TorchScript is unavailable). Same outputs and
        gradients (tested); ~1.7× faster on a rollout step's small batches, and it runs without Python's GIL, so the
        data-parallel threads' forward passes overlap. It shares the parameters (the optimiser updates them in
        place); buffers that the normaliser replaces rather than updates are copied in before each use. Never run
        it under ``torch.inference_mode`` (see :meth:`bucketed`): its graph executor would keep inference tensors
        that autograd later refuses."""
        if self._scripted is None:
            try:
                scripted = script(self.encoder)
                owners = dict(self.encoder.named_modules())
                pairs = []
                for name, buf in scripted.named_buffers():  # (scripted buffer, owning submodule, attribute)
                    path, _, attr = name.rpartition(".")
                    pairs.append((buf, owners[path], attr))
            except Exception:  # noqa: BLE001 - a torch without TorchScript: stay eager
                scripted, pairs = self.encoder, []
            self._scripted = (scripted, pairs)
        scripted, pairs = self._scripted
        for buf, owner, attr in pairs:
            mine = owner._buffers[attr]
            if buf is not mine:
                buf.copy_(mine)
        return scripted

    def encode(self, obs: TensorDict | dict[str, torch.Tensor], masks: torch.Tensor | None = None,
               threads: int | None = None) -> torch.Tensor:
        """Context z for every step: ``(N, d)`` in rollouts, ``(T, B, d)`` for padded trajectories (only the valid
        entries are encoded; padding stays zero). ``threads`` overrides ``self.threads``."""
        robot, edges, valid = obs["robot"], obs["humans"], obs["mask"] > 0.5
        encode = self.packed_encode if self.packed and packed.supported(self.encoder) else self.bucketed
        if masks is None:
            return encode(robot, edges, valid, threads=threads)
        z = robot.new_zeros((*masks.shape, self.encoder.final_ln.normalized_shape[0]))
        z[masks] = encode(robot[masks], edges[masks], valid[masks], threads=threads)
        return z

    def trunk(self, obs: TensorDict | dict[str, torch.Tensor], masks: torch.Tensor | None = None, hidden_state=None,
              threads: int | None = None) -> torch.Tensor:
        return self.rnn(self.encode(obs, masks, threads), masks, hidden_state).squeeze(0)

    def get_latent(self, obs, masks=None, hidden_state=None):
        latent = self.trunk(obs, masks, hidden_state)
        self._cache = (obs, latent)
        return latent

    def reset(self, dones=None, hidden_state=None) -> None:
        self.rnn.reset(dones, hidden_state)

    def get_hidden_state(self):
        return self.rnn.hidden_state

    def detach_hidden_state(self, dones=None) -> None:
        self.rnn.detach_hidden_state(dones)

    def update_normalization(self, obs: TensorDict) -> None:
        if self.training:
            self.encoder.robot_norm.update(obs["robot"])

    def as_jit(self) -> nn.Module:
        return H2INTExport(self)

    def as_onnx(self, verbose: bool = False) -> nn.Module:
        return H2INTExport(self)


class H2INTCritic(MLPModel):
    """Value head on the actor's shared trunk (see the module docstring)."""

    is_recurrent = True

    def __init__(self, obs: TensorDict, obs_groups: dict, obs_set: str, output_dim: int, actor: H2INTActor,
                 hidden_dims: tuple[int, ...] | list[int] = (64,), activation: str = "elu", **_: object) -> None:
        self.latent_dim = actor.latent_dim
        super().__init__(obs, obs_groups, obs_set, output_dim, hidden_dims, activation, False, None)
        object.__setattr__(self, "_actor", actor)  # a reference, not a submodule: parameters are not duplicated
        object.__setattr__(actor, "_critic_head", self.mlp)  # for crowdbench.policies.parallel_ppo

    def _get_obs_dim(self, obs, obs_groups, obs_set):
        return ["robot", "humans", "mask"], 9

    def _get_latent_dim(self) -> int:
        return self.latent_dim

    def get_latent(self, obs, masks=None, hidden_state=None):
        cache = self._actor._cache
        if cache is not None and cache[0] is obs:
            return cache[1]
        return self._actor.trunk(obs, masks, hidden_state)

    def reset(self, dones=None, hidden_state=None) -> None:
        if dones is None and hidden_state is not None:  # compute_returns restores the shared state
            self._actor.rnn.reset(None, hidden_state)

    def get_hidden_state(self):
        return self._actor.rnn.hidden_state

    def update_normalization(self, obs: TensorDict) -> None:
        pass


class SharedTrunkPPO(PPO):
    """rsl-rl PPO whose critic is an :class:`H2INTCritic` on the actor's trunk. With ``parallel_update`` set (the
    trainer sets it) and the actor on several threads, :meth:`update` runs whole mini-batches — forward, losses,
    backward — per thread (:mod:`crowdbench.policies.parallel_ppo`)."""

    parallel_update = False

    def update(self) -> dict[str, float]:
        if self.parallel_update and parallel_ppo.applies(self):
            return parallel_ppo.update(self)
        return super().update()

    @staticmethod
    def construct_algorithm(obs, env, cfg, device):
        from rsl_rl.storage import RolloutStorage
        from rsl_rl.utils import resolve_class, resolve_obs_groups

        alg_class, alg_cfg = resolve_class(cfg["algorithm"])
        _, actor_cfg = resolve_class(cfg["actor"])
        _, critic_cfg = resolve_class(cfg["critic"])
        cfg["obs_groups"] = resolve_obs_groups(obs, cfg["obs_groups"], ["actor", "critic"])
        alg_cfg.pop("share_cnn_encoders", None)
        actor = H2INTActor(obs, cfg["obs_groups"], "actor", env.num_actions, **actor_cfg).to(device)
        critic = H2INTCritic(obs, cfg["obs_groups"], "critic", 1, actor=actor, **critic_cfg).to(device)
        storage = RolloutStorage("rl", env.num_envs, cfg["num_steps_per_env"], obs, [env.num_actions], device)
        return alg_class(actor, critic, storage, device=device, **alg_cfg, multi_gpu_cfg=cfg["multi_gpu"])


class H2INTExport(nn.Module):
    """Deterministic recurrent policy for TorchScript/ONNX: ``(robot (B, 9), humans (B, N, 2), mask (B, N),
    h_in (1, B, H)) → (action (B, 2), h_out (1, B, H))``."""

    def __init__(self, actor: H2INTActor, trim: bool = False) -> None:
        """``trim=True`` skips token columns invalid for the whole batch (data-dependent shapes: for TorchScript
        inference, not for ONNX export)."""
        super().__init__()
        import copy

        self.trim = trim
        self.encoder = copy.deepcopy(actor.encoder)
        self.gru = copy.deepcopy(actor.rnn.rnn)
        self.mlp = copy.deepcopy(actor.mlp)
        self.hidden_size = self.gru.hidden_size
        self.n_max = int(actor.encoder.pos_emb.num_embeddings - 1)

    def forward(self, robot: torch.Tensor, humans: torch.Tensor, mask: torch.Tensor, h_in: torch.Tensor):
        z = self.encoder(robot, humans, mask > 0.5, self.trim)
        out, h_out = self.gru(z.unsqueeze(0), h_in)
        return self.mlp(out.squeeze(0)), h_out

    def get_dummy_inputs(self, batch: int = 2) -> tuple[torch.Tensor, ...]:
        """Example inputs (batch 2: torch.export would specialise a batch of 1 into a constant)."""
        return (torch.zeros(batch, 9), torch.zeros(batch, self.n_max, 2), torch.ones(batch, self.n_max),
                torch.zeros(1, batch, self.hidden_size))

    input_names = ["robot", "humans", "mask", "h_in"]
    output_names = ["action", "h_out"]
