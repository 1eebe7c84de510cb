"""DS-RNN as a crowdbench robot policy: a trained checkpoint (``crowdbench train dsrnn``) driving the robot.

Deterministic (the Gaussian's mean), one recurrent state per world (edge, per-pedestrian and node GRUs), on the
``relative_by_id`` observation (slot j = pedestrian j).
"""

from __future__ import annotations

import os
from typing import Any

from crowdbench import checkpoints
from crowdbench.config import WorldConfig
from crowdbench.policies.base import register
from crowdbench.policies.dsrnn.model import DSRNNActor, DSRNNConfig, build_actor
from crowdbench.policies.recurrent import RecurrentActorPolicy

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
class DSRNNPolicy(RecurrentActorPolicy):
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
        meta: dict[str, Any] = {}
        if actor is None:
            actor, meta = load_actor(checkpoint)
        super().__init__(config, actor, actor.slots, meta)
