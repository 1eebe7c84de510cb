"""AIG-GST as a crowdbench robot policy: a trained checkpoint (``crowdbench train aig_gst``) driving the robot.

Deterministic (the Gaussian's mean), one node-GRU state per world, on the ``predicted`` observation with the
predictor the checkpoint was trained with (:attr:`AIGPolicy.observation_kwargs`).
"""

from __future__ import annotations

import os
from functools import partial
from typing import Any

from crowdbench.config import WorldConfig
from crowdbench.policies.aig.model import AIGActor, AIGConfig, build_actor
from crowdbench.policies.base import register
from crowdbench.policies.recurrent import RecurrentActorPolicy, stored_config
from crowdbench.policies.recurrent import load_actor as load_recurrent

METHOD = "aig_gst"


def load_actor(checkpoint: str | os.PathLike | None = None) -> tuple[AIGActor, dict[str, Any]]:
    """The actor of a checkpoint (path or shipped name; ``None``: the shipped ``aig_gst``) in eval mode, and the
    checkpoint's metadata."""
    actor, _, meta = load_recurrent(METHOD, checkpoint, partial(stored_config, AIGConfig), build_actor)
    return actor, meta


@register(METHOD)
class AIGPolicy(RecurrentActorPolicy):
    """The trained AIG-GST policy.

    Args:
        config: World configuration (``max_humans_observed`` must equal the checkpoint's slot count).
        checkpoint: Path or shipped name (default: the shipped ``aig_gst``).
        actor: Alternatively a live :class:`~crowdbench.policies.aig.model.AIGActor` (evaluation during training).
    """

    observation = "predicted"

    def __init__(self, config: WorldConfig | None = None, checkpoint: str | None = None,
                 actor: AIGActor | None = None) -> None:
        meta: dict[str, Any] = {}
        if actor is None:
            actor, meta = load_actor(checkpoint)
        self.model_config = actor.aig
        super().__init__(config, actor, actor.slots, meta)

    @property
    def observation_kwargs(self) -> dict[str, Any]:
        return self.model_config.observation_kwargs()
