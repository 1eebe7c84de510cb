"""The batched crowd world and its layouts."""

from __future__ import annotations

from crowdbench.worlds.layouts import LAYOUTS, Layout, make_layout
from crowdbench.worlds.world import COLLISION, OUTCOMES, REWARD_TERMS, RUNNING, SUCCESS, TIMEOUT, CrowdWorld, StepResult

__all__ = ["COLLISION", "LAYOUTS", "OUTCOMES", "REWARD_TERMS", "RUNNING", "SUCCESS", "TIMEOUT", "CrowdWorld", "Layout",
           "StepResult", "make_layout"]
