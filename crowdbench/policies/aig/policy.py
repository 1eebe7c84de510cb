"""AIG-GST as a crowdbench robot policy: a trained checkpoint (``crowdbench train aig_gst``) driving the robot.

Deterministic (the Gaussian's mean), one node-GRU state per world, on the ``predicted`` observation with the
predictor the checkpoint was trained with (:attr:`AIGPolicy.observation_kwargs`).
"""

from __future__ import annotations

import os
from typing import Any

from crowdbench.policies.aig import NAME
from crowdbench.policies.aig.model import AIGActor, AIGConfig, build_actor
from crowdbench.policies.recurrent import TrainedRecurrentPolicy


def load_actor(checkpoint: str | os.PathLike | None = None) -> tuple[AIGActor, dict[str, Any]]:
    """The actor of a checkpoint (path or shipped name; ``None``: the shipped ``aig_gst``) in eval mode, and the
    checkpoint's metadata."""
    return AIGPolicy.load_actor(checkpoint)


class AIGPolicy(TrainedRecurrentPolicy):
    """The trained AIG-GST policy (arguments: :class:`~crowdbench.policies.recurrent.TrainedRecurrentPolicy`)."""

    observation = "predicted"
    method = NAME
    model_config = AIGConfig
    build_actor = staticmethod(build_actor)

    @property
    def observation_kwargs(self) -> dict[str, Any]:
        return self.actor.aig.observation_kwargs()
