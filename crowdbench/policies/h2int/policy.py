"""H²INT as a crowdbench robot policy: a trained checkpoint (``crowdbench train h2int``) driving the robot.

Deterministic (the Gaussian's mean), one GRU state per world, the packed encoder (:meth:`H2INTEncoder.packed
<crowdbench.policies.h2int.model.H2INTEncoder.packed>`) under ``torch.inference_mode``
(:class:`~crowdbench.policies.recurrent.TrainedRecurrentPolicy`).
"""

from __future__ import annotations

import os
from typing import Any

from crowdbench.policies.h2int import NAME
from crowdbench.policies.h2int.model import H2INTActor, H2INTConfig, build_actor
from crowdbench.policies.recurrent import TrainedRecurrentPolicy


def model_config(ckpt: dict[str, Any]) -> H2INTConfig:
    """The architecture stored in a checkpoint."""
    return H2INTConfig(**ckpt["model"])


def load_actor(checkpoint: str | os.PathLike | None = None) -> tuple[H2INTActor, dict[str, Any]]:
    """The actor of a checkpoint (path, shipped name such as ``"meanpool"``, or ``None`` for the shipped H²INT) in
    eval mode, and the checkpoint's metadata (variant, iteration, env steps, seed, path)."""
    return H2INTPolicy.load_actor(checkpoint)


class H2INTPolicy(TrainedRecurrentPolicy):
    """The trained H²INT policy.

    Args:
        config: World configuration (``max_humans_observed`` must equal the checkpoint's N_max).
        checkpoint: Path, or the name of a shipped checkpoint (``h2int``, ``flat``, ``meanpool``, ``standard``);
            default: the shipped ``h2int``.
        actor: Alternatively, a live :class:`~crowdbench.policies.h2int.model.H2INTActor` (evaluation during
            training).
    """

    observation = "relative"
    method = NAME
    model_config = H2INTConfig
    build_actor = staticmethod(build_actor)

    @classmethod
    def describe(cls, model: H2INTConfig) -> dict[str, Any]:
        return {"variant": model.variant}
