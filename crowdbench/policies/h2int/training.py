"""How ``crowdbench train h2int`` builds H²INT: its PPO method binding
(:class:`~crowdbench.training.methods.PPOMethod`)."""

from __future__ import annotations

from typing import Any

from crowdbench.policies.h2int.model import H2INTActor, H2INTConfig
from crowdbench.policies.h2int.policy import H2INTPolicy
from crowdbench.training.methods import PPOMethod


class H2INTMethod(PPOMethod):
    """H²INT and its ablations (``H2INTConfig.variant``)."""

    name = "h2int"
    model_config = H2INTConfig
    actor_class = H2INTActor
    observation = "relative"

    def actor_cfg(self, model: H2INTConfig) -> dict[str, Any]:
        return model.actor_kwargs()

    def critic_cfg(self, model: H2INTConfig) -> dict[str, Any]:
        return {"hidden_dims": list(model.head_dims)}

    def policy(self, config: Any, actor: H2INTActor) -> H2INTPolicy:
        return H2INTPolicy(config, actor=actor)

    def label(self, model: H2INTConfig) -> str:
        return model.variant
