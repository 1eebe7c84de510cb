"""Robot policies: the plug-in contract, the registry, the classic baselines and the learned methods.

Layout: :mod:`~crowdbench.policies.base` (contract + registry) and :mod:`~crowdbench.policies.classic` (``linear``,
``orca``, ``social_force``: numpy only) here; each learned method is a sub-package (``h2int/``: model, policy wrapper,
export, private ``_kernels/``; ``value/``: CADRL and SARL; ``dsrnn/``: DS-RNN; ``aig/``: AIG-GST). Learned methods
are registered by ``"module:Class"`` string and imported on first use, so ``import crowdbench.policies`` and the
classic baselines never import torch.
"""

from __future__ import annotations

from crowdbench.policies.base import POLICIES, RobotPolicy, make_policy, register
from crowdbench.policies.classic import LinearPolicy, ORCAPolicy, SocialForcePolicy

register("h2int", "crowdbench.policies.h2int.policy:H2INTPolicy")
register("cadrl", "crowdbench.policies.value.policy:CADRLPolicy")
register("sarl", "crowdbench.policies.value.policy:SARLPolicy")
register("dsrnn", "crowdbench.policies.dsrnn.policy:DSRNNPolicy")
register("aig_gst", "crowdbench.policies.aig.policy:AIGPolicy")

__all__ = ["POLICIES", "LinearPolicy", "ORCAPolicy", "RobotPolicy", "SocialForcePolicy", "make_policy", "register"]
