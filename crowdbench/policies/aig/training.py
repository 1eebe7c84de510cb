"""How ``crowdbench train aig_gst`` builds AIG-GST: its PPO method binding and recipe
(:class:`~crowdbench.training.methods.PPOMethod`).

The recipe is DS-RNN's (:data:`~crowdbench.policies.recurrent_training.CROWDNAV_RECIPE`; CrowdNav++ trains both with
the same PPO settings, 16 processes instead of 12). The reward is crowdbench's paper reward plus the
prediction-intrusion penalty of the ``predicted`` observation
(:meth:`~crowdbench.predictors.observation.PredictedObservation.reward`), both scaled by ``reward_scale``.
"""

from __future__ import annotations

from typing import Any, ClassVar

from crowdbench.policies.aig import NAME
from crowdbench.policies.aig.model import AIGActor, AIGConfig
from crowdbench.policies.aig.policy import AIGPolicy
from crowdbench.policies.recurrent_training import CROWDNAV_RECIPE, RecurrentPPOMethod


class AIGMethod(RecurrentPPOMethod):
    """AIG-GST (Liu et al. 2023)."""

    name = NAME
    model_config = AIGConfig
    actor_class = AIGActor
    policy_class = AIGPolicy
    observation = "predicted"
    head_activation = "tanh"
    train_defaults: ClassVar[dict[str, Any]] = CROWDNAV_RECIPE

    default_variant = "small"
    """The issue's rule: the original widths cannot plateau within ~3 h on the 2-core machine (README, both curves),
    so the largest width that does is the default; ``--variant original`` keeps the original's."""
    variants: ClassVar[dict[str, dict[str, Any]]] = {
        "original": {},
        "small": {"robot_embed": 64, "edge_dims": (64, 128), "heads": 4, "human_embed": 64, "attention": 32,
                  "node_embed": 32, "node_rnn": 64, "latent": 64, "head_dims": (64, 64)}}
    """``small``: every width ÷ 4 (self-attention 128 × 4 heads, GRU 64; 0.18 M parameters instead of 2.37 M): 500
    against 75 env steps/s of training on one core of this machine (README)."""

    def observation_kwargs(self, model: AIGConfig) -> dict[str, Any]:
        return model.observation_kwargs()

    def label(self, model: AIGConfig) -> str:
        base = super().label(model)
        return base if model.predictor == "gst" else f"{base}-{model.predictor}"
