"""DS-RNN as a crowdbench robot policy: a trained checkpoint (``crowdbench train dsrnn``) driving the robot.

Deterministic (the Gaussian's mean), one recurrent state per world (edge, per-pedestrian and node GRUs), on the
``relative_by_id`` observation (slot j = pedestrian j).
"""

from __future__ import annotations

import os
from functools import partial
from typing import Any

from crowdbench.config import WorldConfig
from crowdbench.policies.base import register
from crowdbench.policies.dsrnn.model import DSRNNActor, DSRNNConfig, build_actor
from crowdbench.policies.recurrent import RecurrentActorPolicy, stored_config
from crowdbench.policies.recurrent import load_actor as load_recurrent

METHOD = "dsrnn"


def load_actor(checkpoint: str | os.PathLike | None = None) -> tuple[DSRNNActor, dict[str, Any]]:
    """The actor of a checkpoint (path or shipped name; ``None``: the shipped ``dsrnn``) in eval mode, and the
    checkpoint's metadata."""
    actor, _, meta = load_recurrent(METHOD, checkpoint, partial(stored_config, DSRNNConfig), build_actor)
    return actor, meta


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
        self.observation = actor.dsrnn.observation  # by pedestrian ID, or nearest first (DSRNNConfig.slots)
