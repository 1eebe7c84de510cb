"""CrowdNav's value-based baselines, CADRL and SARL.

* :mod:`.model` — the value networks (:class:`CADRLNet`, :class:`SARLNet`) and their configs;
* :mod:`.lookahead` — joint states, the 81 actions, constant-velocity propagation and CrowdNav's reward, batched;
* :mod:`.policy` — the registered robot policies ``cadrl`` and ``sarl`` (greedy look-ahead on a checkpoint);
* ``checkpoints/`` — the shipped checkpoints (package data). Training: :mod:`crowdbench.training.value`.

Importing this package registers both methods and imports no torch.
"""

from __future__ import annotations

from pathlib import Path

from crowdbench.policies.method import TIERS, BoardEntry, Method, register_method

_HERE = Path(__file__).resolve().parent
CADRL = register_method(Method(
    "cadrl", f"{__name__}.policy:CADRLPolicy", trainer="value", checkpoints=_HERE / "checkpoints" / "cadrl",
    entries=(BoardEntry("cadrl", (("checkpoint", "cadrl"),)),), sensing=TIERS,
    paper={"I": (84, 71, 65), "II": (85, 61, 35), "III": (77, 68, 61)},
    description="CADRL (Chen et al. 2017): pairwise value network, one-step look-ahead"))
SARL = register_method(Method(
    "sarl", f"{__name__}.policy:SARLPolicy", trainer="value", checkpoints=_HERE / "checkpoints" / "sarl",
    entries=(BoardEntry("sarl", (("checkpoint", "sarl"),)),), sensing=TIERS,
    paper={"I": (88, 79, 73), "II": (93, 53, 45), "III": (85, 76, 70)},
    description="SARL (Chen et al. 2019): self-attention value network, one-step look-ahead"))

DEFAULT_VALUE_METHOD = SARL.name
"""What ``crowdbench.training.value.ValueTrainConfig`` trains unless told."""

__all__ = ["CADRL", "DEFAULT_VALUE_METHOD", "SARL"]
