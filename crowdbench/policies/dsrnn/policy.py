"""DS-RNN as a crowdbench robot policy: a trained checkpoint (``crowdbench train dsrnn``) driving the robot.

Deterministic (the Gaussian's mean), one recurrent state per world (edge, per-pedestrian and node GRUs), on the
``relative_by_id`` observation (slot j = pedestrian j).
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import torch

from crowdbench import checkpoints
from crowdbench.config import WorldConfig
from crowdbench.policies.base import RobotPolicy, register
from crowdbench.policies.dsrnn.model import DSRNNActor, DSRNNConfig, build_actor

METHOD = "dsrnn"


def load_actor(checkpoint: str | os.PathLike | None = None) -> tuple[DSRNNActor, dict[str, Any]]:
    """The actor of a checkpoint (path or shipped name; ``None``: the shipped ``dsrnn``) in eval mode, and the
    checkpoint's metadata."""
    path = checkpoints.resolve(METHOD, checkpoint)
    ckpt = checkpoints.load(path, METHOD)
    model = {k: tuple(v) if isinstance(v, list) else v for k, v in dict(ckpt["model"]).items()}
    actor = build_actor(DSRNNConfig(**model), int(ckpt["n_max"]))
    actor.load_state_dict(ckpt["actor"])
    meta = {k: ckpt.get(k) for k in ("iteration", "env_steps", "seed")}
    return actor.eval(), {**meta, "path": path}


@register(METHOD)
class DSRNNPolicy(RobotPolicy):
    """The trained DS-RNN policy.

    Args:
        config: World configuration (``max_humans_observed`` must equal the checkpoint's slot count).
        checkpoint: Path or shipped name (default: the shipped ``dsrnn``).
        actor: Alternatively a live :class:`~crowdbench.policies.dsrnn.model.DSRNNActor` (evaluation during
            training).
    """

    observation = "relative_by_id"

    def __init__(self, config: WorldConfig | None = None, checkpoint: str | None = None,
                 actor: DSRNNActor | None = None) -> None:
        super().__init__(config)
        self.meta: dict[str, Any] = {}
        if actor is None:
            actor, self.meta = load_actor(checkpoint)
        if actor.slots != self.config.max_humans_observed:
            raise ValueError(f"max_humans_observed={self.config.max_humans_observed} but the checkpoint was trained "
                             f"with {actor.slots} pedestrian slots")
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
        x = {k: torch.as_tensor(obs[k], dtype=torch.float32) for k in ("robot", "humans", "mask")}
        n = len(x["robot"])
        if self.hidden is None or self.hidden.shape[1] != n:
            self.hidden = torch.zeros(1, n, self.actor.state_size)
        latent, self.hidden = self.actor.step(self.actor.encode_samples(x), self.hidden)
        return self.actor.mlp(latent).numpy().astype(np.float64)
