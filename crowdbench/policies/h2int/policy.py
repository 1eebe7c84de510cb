"""H²INT as a crowdbench robot policy: a trained checkpoint (``crowdbench train h2int``) driving the robot.

Deterministic (the Gaussian's mean), one GRU state per world, the packed encoder (:meth:`H2INTEncoder.packed
<crowdbench.policies.h2int.model.H2INTEncoder.packed>`) under ``torch.inference_mode``
(:class:`~crowdbench.policies.recurrent.RecurrentActorPolicy`).
"""

from __future__ import annotations

import os
from typing import Any

from crowdbench.config import WorldConfig
from crowdbench.policies.base import register
from crowdbench.policies.h2int.model import H2INTActor, H2INTConfig, build_actor
from crowdbench.policies.recurrent import RecurrentActorPolicy
from crowdbench.policies.recurrent import load_actor as load_recurrent

METHOD = "h2int"


def model_config(ckpt: dict[str, Any]) -> H2INTConfig:
    """The architecture stored in a checkpoint."""
    return H2INTConfig(**ckpt["model"])


def load_actor(checkpoint: str | os.PathLike | None = None) -> tuple[H2INTActor, dict[str, Any]]:
    """The actor of a checkpoint (path, shipped name such as ``"meanpool"``, or ``None`` for the shipped H²INT) in
    eval mode, and the checkpoint's metadata (variant, iteration, env steps, seed, path)."""
    actor, cfg, meta = load_recurrent(METHOD, checkpoint, model_config, build_actor)
    return actor, {**meta, "variant": cfg.variant}


@register(METHOD)
class H2INTPolicy(RecurrentActorPolicy):
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
        meta: dict[str, Any] = {}
        if actor is None:
            actor, meta = load_actor(checkpoint)
        super().__init__(config, actor, actor.encoder.pos_emb.num_embeddings - 1, meta)
