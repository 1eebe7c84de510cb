"""How ``crowdbench train dsrnn`` builds DS-RNN: its PPO method binding and recipe
(:class:`~crowdbench.training.methods.PPOMethod`).

The recipe is the original's (CrowdNav_DSRNN ``crowd_nav/configs/config.py``, ``pytorchBaselines``): Adam at a fixed
4e-5, 5 epochs, clip 0.2, gradient norm 0.5, no entropy bonus, γ 0.99, λ 0.95, value loss weight 0.5 on its
½·squared error (0.25 on rsl-rl's squared error), mini-batches of 180 transitions (12 processes × 30 steps in 2
mini-batches there; 192 worlds × 30 steps in 32 mini-batches of 6 worlds here — the same 180 transitions per
gradient step). No responsiveness curriculum (H²INT's contribution): the crowd stays at ρ = 0 (``rho_min``), the
original's invisible robot. Rewards are crowdbench's paper reward (the original's, without its one-step lag), scaled
by ``reward_scale`` as for H²INT.
"""

from __future__ import annotations

from typing import Any, ClassVar

from crowdbench.policies.dsrnn.model import DSRNNActor, DSRNNConfig
from crowdbench.training.methods import PPOMethod

SMALL = {"edge_embed": 32, "edge_rnn": 64, "attention": 32, "robot_dims": (3, 32), "edge_out": 32, "node_rnn": 64,
         "latent": 64, "head_dims": (64, 64)}


class DSRNNMethod(PPOMethod):
    """DS-RNN (Liu et al. 2021)."""

    name = "dsrnn"
    model_config = DSRNNConfig
    actor_class = DSRNNActor
    observation = "relative_by_id"
    train_defaults: ClassVar[dict[str, Any]] = {
        "learning_rate": 4e-5, "schedule": "fixed", "epochs": 5, "clip": 0.2, "max_grad_norm": 0.5,
        "entropy_coef": 0.0, "gamma": 0.99, "lam": 0.95, "value_loss_coef": 0.25, "num_envs": 192,
        "steps_per_env": 30, "mini_batches": 32, "anneal": False, "rho_min": 0.0}

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

    def actor_cfg(self, model: DSRNNConfig) -> dict[str, Any]:
        return model.actor_kwargs()

    def critic_cfg(self, model: DSRNNConfig) -> dict[str, Any]:
        return {"hidden_dims": list(model.head_dims), "activation": "tanh"}

    def policy(self, config: Any, actor: DSRNNActor) -> Any:
        from crowdbench.policies.dsrnn.policy import DSRNNPolicy

        return DSRNNPolicy(config, actor=actor)
