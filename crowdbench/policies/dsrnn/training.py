"""How ``crowdbench train dsrnn`` builds DS-RNN: its PPO method binding and recipe
(:class:`~crowdbench.training.methods.PPOMethod`).

The recipe is the original's (CrowdNav_DSRNN ``crowd_nav/configs/config.py``, ``pytorchBaselines``):
:data:`~crowdbench.policies.recurrent_training.CROWDNAV_RECIPE`. Rewards are crowdbench's paper reward (the
original's, without its one-step lag), scaled by ``reward_scale`` as for H²INT.
"""

from __future__ import annotations

from typing import Any, ClassVar

from crowdbench.policies.dsrnn import NAME
from crowdbench.policies.dsrnn.model import DSRNNActor, DSRNNConfig
from crowdbench.policies.dsrnn.policy import DSRNNPolicy
from crowdbench.policies.recurrent_training import CROWDNAV_RECIPE, RecurrentPPOMethod

SMALL = {"edge_embed": 32, "edge_rnn": 64, "attention": 32, "robot_dims": (3, 32), "edge_out": 32, "node_rnn": 64,
         "latent": 64, "head_dims": (64, 64)}


class DSRNNMethod(RecurrentPPOMethod):
    """DS-RNN (Liu et al. 2021)."""

    name = NAME
    model_config = DSRNNConfig
    actor_class = DSRNNActor
    policy_class = DSRNNPolicy
    observation = "relative_by_id"
    head_activation = "tanh"
    train_defaults: ClassVar[dict[str, Any]] = CROWDNAV_RECIPE

    default_variant = "small"
    """The issue's rule: the original widths cannot plateau within ~3 h on the 2-core machine (README, both curves),
    so the largest width that does is the default; ``--variant original`` keeps the original's."""
    variants: ClassVar[dict[str, dict[str, Any]]] = {
        "original": {},
        "small": SMALL,
        "small_nearest": {**SMALL, "slots": "nearest"}}
    """``small``: edge GRUs 64 instead of 256, latent and heads 64 (0.08 M parameters instead of 0.83 M): 553
    against 193 env steps/s of training on one core of this machine (README). ``small_nearest``: the same widths with
    CrowdNav++'s slot handling (:attr:`DSRNNConfig.slots`)."""

    def observation_name(self, model: DSRNNConfig) -> str:
        return model.observation
