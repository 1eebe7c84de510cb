"""Robot policies: the contract, the registry and the classic baselines."""

from __future__ import annotations

from crowdbench.policies.base import POLICIES, RobotPolicy, make_policy, register
from crowdbench.policies.classic import LinearPolicy, ORCAPolicy

__all__ = ["POLICIES", "LinearPolicy", "ORCAPolicy", "RobotPolicy", "make_policy", "register"]
