"""Robot policies: the plug-in contract, the registries, the classic baselines and the learned methods.

Layout: :mod:`~crowdbench.policies.base` (policy contract + registry), :mod:`~crowdbench.policies.method` (method
descriptors: a method's policy, training, checkpoints, board rows, sensing — registered once) and
:mod:`~crowdbench.policies.classic` (``linear``, ``orca``, ``social_force``: numpy only) here;
:mod:`~crowdbench.policies.nets` and :mod:`~crowdbench.policies.recurrent` (the plain-torch recurrent networks and
their robot policy); each learned method is a sub-package whose ``__init__`` registers its :class:`Method`
(``h2int/``: model, policy wrapper, export, private ``_kernels/``; ``value/``: CADRL and SARL; ``dsrnn/``: DS-RNN;
``aig/``: AIG-GST). Their code is named by ``"module:attribute"`` strings and imported on first use, so
``import crowdbench.policies`` and the classic baselines never import torch.
"""

from __future__ import annotations

from importlib import import_module

from crowdbench import checkpoints
from crowdbench.policies.base import POLICIES, RobotPolicy, make_policy, register
from crowdbench.policies.classic import LinearPolicy, ORCAPolicy, SocialForcePolicy
from crowdbench.policies.method import (
    METHODS,
    TIERS,
    BoardEntry,
    Method,
    method_of,
    methods,
    register_method,
    trained_by,
)

POLICIES.derive(METHODS, lambda m: m.policy)  # a method's robot policy is registered with it
checkpoints.FOLDERS.derive(METHODS, lambda m: m.checkpoints)

PLANNERS = "ORCA (RVO2, CrowdNav++'s safety space) and Social Force planners: nothing trained"
register_method(Method("orca", ORCAPolicy, sensing=TIERS, description=PLANNERS,
                       entries=(BoardEntry("orca"), BoardEntry("orca-velocities", (("sensing", "velocities"),))),
                       paper={"I": (97, 91, 78), "II": (93, 69, 43), "III": (93, 89, 72)}))
register_method(Method("social_force", SocialForcePolicy, sensing=TIERS, description=PLANNERS,
                       entries=(BoardEntry("social_force"),),
                       paper={"I": (65, 46, 31), "II": (60, 27, 12), "III": (56, 35, 24)}))
register_method(Method("linear", LinearPolicy, description="straight to the goal, blind to the crowd (a bound)"))

DEFAULT_POLICY = "orca"
"""The robot policy of commands that are not told one (``crowdbench demo``, ``evaluate``)."""
REFERENCE_METHOD = "h2int"
"""The paper's own method: it heads the ablation tables and is the default of ``crowdbench tables``, ``panels``,
``export`` and training."""

for _package in ("h2int", "value", "dsrnn", "aig"):  # each registers its Method(s); this order is the board's
    import_module(f"{__name__}.{_package}")

__all__ = ["DEFAULT_POLICY", "METHODS", "POLICIES", "REFERENCE_METHOD", "BoardEntry", "LinearPolicy", "Method",
           "ORCAPolicy", "RobotPolicy", "SocialForcePolicy", "make_policy", "method_of", "methods", "register",
           "register_method", "trained_by"]
