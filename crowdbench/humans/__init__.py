"""Pluggable pedestrian models: the contract, the registry and the shipped models.

Shipped: ``orca`` (RVO2-faithful), ``responsive_orca`` (the paper's latent-responsive crowd), ``social_force``
(CrowdNav++'s variant) and ``linear`` (non-reactive). Register your own with :func:`register` or the entry-point
group ``crowdbench.humans``.
"""

from __future__ import annotations

from crowdbench.humans.base import HUMAN_MODELS, CrowdState, HumanModel, Linear, make, preferred_velocity, register
from crowdbench.humans.orca import ORCA, ORCAParams, PyRVOSimulator
from crowdbench.humans.responsive import ResponsiveORCA
from crowdbench.humans.social_force import SocialForce

HUMAN_MODELS.register("replay", "crowdbench.humans.replay:Replay")  # recorded people (eth, hotel, univ, zara1, zara2)
HUMAN_MODELS.register("reactive_replay", "crowdbench.humans.replay:ReactiveReplay")
HUMAN_MODELS.register("learned_crowd", "crowdbench.humans.learned:LearnedCrowd")  # trained: crowdbench train-crowd

__all__ = ["HUMAN_MODELS", "ORCA", "ORCAParams", "CrowdState", "HumanModel", "Linear", "PyRVOSimulator",
           "ResponsiveORCA", "SocialForce", "make", "preferred_velocity", "register"]
