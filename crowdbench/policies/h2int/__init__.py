"""H²INT: the two-stage gated Transformer policy of the paper.

* :mod:`.model` — the network (eager reference encoder, packed fast path, rsl-rl actor) and :class:`H2INTConfig`;
* :mod:`.policy` — :class:`H2INTPolicy`, the registered robot policy ``"h2int"`` (a trained checkpoint);
* :mod:`.training` — how ``crowdbench train h2int`` builds it (the PPO method binding);
* :mod:`.export` — TorchScript / ONNX export of the eager reference;
* ``_kernels/`` — the packed encoder's private kernels; ``checkpoints/`` — the shipped checkpoints (package data).
"""

from __future__ import annotations

from crowdbench.policies.h2int.model import VARIANTS, H2INTActor, H2INTConfig, H2INTEncoder
from crowdbench.policies.h2int.policy import H2INTPolicy

__all__ = ["VARIANTS", "H2INTActor", "H2INTConfig", "H2INTEncoder", "H2INTPolicy"]
