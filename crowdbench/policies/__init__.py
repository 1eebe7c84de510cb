"""Robot policies: the contract, the registry and the classic baselines."""

from __future__ import annotations

from crowdbench.policies.base import POLICIES, RobotPolicy, make_policy, register
from crowdbench.policies.classic import LinearPolicy, ORCAPolicy, SocialForcePolicy

__all__ = ["POLICIES", "LinearPolicy", "ORCAPolicy", "RobotPolicy", "SocialForcePolicy", "make_policy", "register"]

from crowdbench.policies.h2int import H2INTPolicy  # noqa: E402  (registers "h2int")

__all__ += ["H2INTPolicy"]
