"""Recorded crowds: the ETH/UCY pedestrian datasets (:mod:`crowdbench.datasets.ethucy`)."""

from __future__ import annotations

from crowdbench.datasets.ethucy import RECORDINGS, SCENES, load_recording, scene_recordings, tracks

__all__ = ["RECORDINGS", "SCENES", "load_recording", "scene_recordings", "tracks"]
