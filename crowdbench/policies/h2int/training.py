"""How ``crowdbench train h2int`` builds H²INT: its PPO method binding
(:class:`~crowdbench.training.methods.PPOMethod`)."""

from __future__ import annotations

from crowdbench.policies.h2int import NAME
from crowdbench.policies.h2int.model import H2INTActor, H2INTConfig
from crowdbench.policies.h2int.policy import H2INTPolicy
from crowdbench.policies.recurrent_training import RecurrentPPOMethod


class H2INTMethod(RecurrentPPOMethod):
    """H²INT and its ablations (``H2INTConfig.variant``)."""

    name = NAME
    model_config = H2INTConfig
    actor_class = H2INTActor
    policy_class = H2INTPolicy
    observation = "relative"

    def label(self, model: H2INTConfig) -> str:
        return model.variant
