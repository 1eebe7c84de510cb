"""Pluggable pedestrian models: the contract, the registry and the shipped models."""

from __future__ import annotations

from crowdbench.humans.base import HUMAN_MODELS, CrowdState, HumanModel, Linear, make, preferred_velocity, register

__all__ = ["HUMAN_MODELS", "CrowdState", "HumanModel", "Linear", "make", "preferred_velocity", "register"]
