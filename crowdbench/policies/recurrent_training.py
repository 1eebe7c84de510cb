"""What the recurrent PPO methods' training bindings share (H²INT, DS-RNN, AIG-GST): the actor and value head from
the architecture dataclass, the robot policy of a live actor, and the CrowdNav++ baselines' PPO recipe.

Imported only by :mod:`crowdbench.training` (through a method's ``training`` binding, :class:`crowdbench.policies.
Method`): it subclasses ``crowdbench.training.methods.PPOMethod``; running a policy never imports it.
"""

from __future__ import annotations

from typing import Any, ClassVar

from crowdbench.policies.recurrent import TrainedRecurrentPolicy
from crowdbench.training.methods import PPOMethod

CROWDNAV_RECIPE: dict[str, Any] = {
    "learning_rate": 4e-5, "schedule": "fixed", "epochs": 5, "clip": 0.2, "max_grad_norm": 0.5,
    "entropy_coef": 0.0, "gamma": 0.99, "lam": 0.95, "value_loss_coef": 0.25, "num_envs": 192,
    "steps_per_env": 30, "mini_batches": 32, "anneal": False, "rho_min": 0.0}
"""DS-RNN's and AIG-GST's PPO settings (CrowdNav_DSRNN / CrowdNav++ ``config.py``): Adam at a fixed 4e-5, 5 epochs,
clip 0.2, gradient norm 0.5, no entropy bonus, γ 0.99, λ 0.95, value loss weight 0.25 on rsl-rl's squared error (0.5
on the originals' ½·squared error), 192 worlds × 30 steps in 32 mini-batches of 6 worlds (180 transitions per
gradient step, as the originals' 12 processes × 30 steps in 2). No responsiveness curriculum (H²INT's
contribution): the crowd stays at ρ = 0, the originals' invisible robot."""


class RecurrentPPOMethod(PPOMethod):
    """A PPO method whose architecture dataclass (:attr:`~PPOMethod.model_config`) gives its actor's keyword
    arguments (``actor_kwargs()``) and head widths (``head_dims``), and whose robot policy is a
    :class:`~crowdbench.policies.recurrent.TrainedRecurrentPolicy`."""

    policy_class: ClassVar[type[TrainedRecurrentPolicy]]
    """The method's robot policy (built on a live actor for quick evaluations)."""
    head_activation: ClassVar[str] = "elu"
    """Activation of the value head (the action head's is the architecture's)."""

    def actor_cfg(self, model: Any) -> dict[str, Any]:
        return model.actor_kwargs()

    def critic_cfg(self, model: Any) -> dict[str, Any]:
        return {"hidden_dims": list(model.head_dims), "activation": self.head_activation}

    def policy(self, config: Any, actor: Any) -> TrainedRecurrentPolicy:
        return self.policy_class(config, actor=actor)
