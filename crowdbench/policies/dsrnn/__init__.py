"""DS-RNN (Liu et al. 2021): the graph-recurrent baseline of the paper's tables (see :mod:`.model`).

Importing this package registers the method (:data:`METHOD`) and imports no torch.
"""

from __future__ import annotations

from pathlib import Path

from crowdbench.policies.method import BoardEntry, Method, register_method

NAME = "dsrnn"
METHOD = register_method(Method(
    NAME, f"{__name__}.policy:DSRNNPolicy", trainer="ppo", training=f"{__name__}.training:DSRNNMethod",
    checkpoints=Path(__file__).resolve().parent / "checkpoints", entries=(BoardEntry(NAME, (("checkpoint", NAME),)),),
    paper={"I": (91, 81, 72), "II": (89, 81, 45), "III": (76, 73, 55)},
    description="DS-RNN (Liu et al. 2021): per-pedestrian edge GRUs and attention, PPO"))

__all__ = ["METHOD"]
