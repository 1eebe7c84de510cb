"""H²INT as a crowdbench robot policy: a trained checkpoint (``crowdbench train h2int``) driving the robot.

Deterministic (the Gaussian's mean), one GRU state per world, the packed encoder (:meth:`H2INTEncoder.packed
<crowdbench.policies.h2int.model.H2INTEncoder.packed>`) under ``torch.inference_mode``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import torch

from crowdbench import checkpoints
from crowdbench.config import WorldConfig
from crowdbench.policies.base import RobotPolicy, register
from crowdbench.policies.h2int.model import H2INTActor, H2INTConfig, build_actor

METHOD = "h2int"


def model_config(ckpt: dict[str, Any]) -> H2INTConfig:
    """The architecture stored in a checkpoint (current or legacy ``crowdbench.h2int/1`` layout)."""
    model = dict(ckpt["model"])
    if "hidden_dims" in model:  # legacy: the actor's keyword arguments
        model = {"variant": model["variant"], "d_model": model["d_model"], "heads": model["heads"],
                 "ffn": model["ffn"], "gru_hidden": model["gru_hidden"], "head_dims": tuple(model["hidden_dims"]),
                 "action_std": model["distribution_cfg"]["init_std"]}
    return H2INTConfig(**model)


def load_actor(checkpoint: str | os.PathLike | None = None) -> tuple[H2INTActor, dict[str, Any]]:
    """The actor of a checkpoint (path, shipped name such as ``"meanpool"``, or ``None`` for the shipped H²INT) in
    eval mode, and the checkpoint's metadata (variant, iteration, env steps, seed, path)."""
    path = checkpoints.resolve(METHOD, checkpoint)
    ckpt = checkpoints.load(path, METHOD)
    cfg = model_config(ckpt)
    actor = build_actor(cfg, int(ckpt["n_max"]))
    actor.load_state_dict(ckpt["actor"])
    meta = {k: ckpt.get(k) for k in ("iteration", "env_steps", "seed")}
    return actor.eval(), {**meta, "variant": cfg.variant, "path": path}


@register(METHOD)
class H2INTPolicy(RobotPolicy):
    """The trained H²INT policy.

    Args:
        config: World configuration (``max_humans_observed`` must equal the checkpoint's N_max).
        checkpoint: Path, or the name of a shipped checkpoint (``h2int``, ``flat``, ``meanpool``, ``standard``);
            default: the shipped ``h2int``.
        actor: Alternatively, a live :class:`~crowdbench.policies.h2int.model.H2INTActor` (evaluation during
            training).
    """

    observation = "relative"

    def __init__(self, config: WorldConfig | None = None, checkpoint: str | None = None,
                 actor: H2INTActor | None = None) -> None:
        super().__init__(config)
        self.meta: dict[str, Any] = {}
        if actor is None:
            actor, self.meta = load_actor(checkpoint)
        n_max = actor.encoder.pos_emb.num_embeddings - 1
        if n_max != self.config.max_humans_observed:
            raise ValueError(f"max_humans_observed={self.config.max_humans_observed} but the checkpoint was trained "
                             f"with N_max={n_max}")
        self.actor = actor.eval()
        self.hidden: torch.Tensor | None = None

    @torch.inference_mode()
    def reset(self, done: np.ndarray | None = None) -> None:
        if done is None or self.hidden is None:
            self.hidden = None
        else:
            self.hidden[:, torch.from_numpy(np.asarray(done, dtype=bool))] = 0.0

    @torch.inference_mode()
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        robot = torch.as_tensor(obs["robot"], dtype=torch.float32)
        edges = torch.as_tensor(obs["humans"], dtype=torch.float32)
        valid = torch.as_tensor(obs["mask"]) > 0.5
        if self.hidden is None or self.hidden.shape[1] != len(robot):
            self.hidden = torch.zeros(1, len(robot), self.actor.rnn.rnn.hidden_size)
        z = self.actor.encoder.packed(robot, edges, valid)
        out, self.hidden = self.actor.rnn.rnn(z.unsqueeze(0), self.hidden)
        return self.actor.mlp(out.squeeze(0)).numpy().astype(np.float64)
