"""DS-RNN as a crowdbench robot policy: a trained checkpoint (``crowdbench train dsrnn``) driving the robot.

Deterministic (the Gaussian's mean), one recurrent state per world (edge, per-pedestrian and node GRUs), on the
``relative_by_id`` observation (slot j = pedestrian j) or, with ``DSRNNConfig.slots="nearest"``, ``relative``.
"""

from __future__ import annotations

import os
from typing import Any

from crowdbench.config import WorldConfig
from crowdbench.policies.dsrnn import NAME
from crowdbench.policies.dsrnn.model import DSRNNActor, DSRNNConfig, build_actor
from crowdbench.policies.recurrent import TrainedRecurrentPolicy


def load_actor(checkpoint: str | os.PathLike | None = None) -> tuple[DSRNNActor, dict[str, Any]]:
    """The actor of a checkpoint (path or shipped name; ``None``: the shipped ``dsrnn``) in eval mode, and the
    checkpoint's metadata."""
    return DSRNNPolicy.load_actor(checkpoint)


class DSRNNPolicy(TrainedRecurrentPolicy):
    """The trained DS-RNN policy (arguments: :class:`~crowdbench.policies.recurrent.TrainedRecurrentPolicy`)."""

    observation = "relative_by_id"
    method = NAME
    model_config = DSRNNConfig
    build_actor = staticmethod(build_actor)

    def __init__(self, config: WorldConfig | None = None, checkpoint: str | None = None,
                 actor: DSRNNActor | None = None) -> None:
        super().__init__(config, checkpoint, actor)
        self.observation = self.actor.dsrnn.observation  # by pedestrian ID, or nearest first (DSRNNConfig.slots)
