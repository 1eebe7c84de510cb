"""Trajectory predictors: where will the pedestrians the robot sees be in the next steps (AIG-GST's spatial edges).

* :mod:`.base` — the plug-in contract (:class:`Predictor`, registry :data:`PREDICTORS`), the robot's :class:`Track`
  of what it has seen, and the ``const_vel`` and ``truth`` predictors;
* :mod:`.gst` — the learned GST-style predictor (``gst``; torch, imported on first use);
* :mod:`.training` — recording crowdbench's own crowds and training the learned predictor
  (``crowdbench predictor record|train``);
* :mod:`.observation` — the ``predicted`` robot observation (current and predicted relative positions).
"""

from pathlib import Path

from crowdbench import checkpoints
from crowdbench.predictors.base import PREDICTORS, ConstantVelocity, GroundTruth, Predictor, Track, make_predictor

PREDICTORS.register("gst", "crowdbench.predictors.gst:GSTPredictor")
checkpoints.FOLDERS.register("gst", Path(__file__).resolve().parent / "checkpoints")  # the shipped gst.pt

__all__ = ["PREDICTORS", "ConstantVelocity", "GroundTruth", "Predictor", "Track", "make_predictor"]
