"""AIG-GST (Liu et al. 2023): the attention-graph baseline with a trajectory predictor (see :mod:`.model`).

Importing this package registers the method (:data:`METHOD`) and imports no torch.
"""

from __future__ import annotations

from pathlib import Path

from crowdbench.policies.method import BoardEntry, Method, register_method

NAME = "aig_gst"
METHOD = register_method(Method(
    NAME, f"{__name__}.policy:AIGPolicy", trainer="ppo", training=f"{__name__}.training:AIGMethod",
    checkpoints=Path(__file__).resolve().parent / "checkpoints", entries=(BoardEntry(NAME, (("checkpoint", NAME),)),),
    paper={"I": (92, 86, 82), "II": (95, 89, 70), "III": (91, 86, 83)},
    description="AIG-GST (Liu et al. 2023): attention graph on predicted trajectories, PPO"))

__all__ = ["METHOD"]
