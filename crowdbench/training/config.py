"""``TrainConfig``: everything a PPO training run depends on (frozen; saved in every checkpoint)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Literal

from crowdbench.policies import REFERENCE_METHOD
from crowdbench.training.methods import PPO_METHODS

RESUMABLE = ("iterations", "minutes", "until_success", "threads", "env_processes")
"""Fields a resumed run may change (budget and speed settings; the others are the run's identity)."""

NOISE_FIELDS = ("action_std", "learn_std")
"""Model fields of the policy noise: a run started from another's weights (``--init``) may set them anew, since
they shape exploration, not the network."""


@dataclass(frozen=True)
class TrainConfig:
    """A PPO training run (:class:`~crowdbench.training.trainer.Trainer`). Unknown keys are an error."""

    method: str = REFERENCE_METHOD
    """Registered PPO method (:data:`~crowdbench.training.methods.PPO_METHODS`)."""
    model: Any = None
    """The method's architecture config (its ``model_config`` dataclass, or a dict of its fields over that
    dataclass's defaults); default (``None``): the method's :attr:`default_variant
    <crowdbench.training.methods.PPOMethod.default_variant>` (DS-RNN and AIG-GST: ``small``)."""
    seed: int = 0
    """Seeds the networks' initialisation, the policy noise and every world's episode-seed stream."""
    num_envs: int = 256
    """Worlds stepped together."""
    steps_per_env: int = 32
    """Rollout length per iteration (transitions per iteration = num_envs × steps_per_env)."""
    iterations: int = 600
    """Upper bound on PPO iterations (counted from the start of the run, across resumes)."""
    minutes: float = 0.0
    """The run's total wall-clock budget in minutes, a resumed run counting its earlier minutes (0 = none).
    Training stops after the iteration that exceeds it."""
    humans_range: tuple[int, int] = (10, 30)
    """Pedestrians per training episode, drawn uniformly (covers the 10–30 of the paper's Table II)."""
    anneal: bool = True
    """Responsiveness annealing (False: ρ fixed at ``rho_min`` from the start, the paper's no-annealing baseline)."""
    rho_init: float = 0.8
    """Mean crowd responsiveness ρ at the start of annealing."""
    rho_min: float = 0.0
    """Final ρ of the annealing."""
    rho_delta: float = 0.1
    """Step by which ρ is lowered."""
    eta: float = 0.9
    """Success rate over the curriculum window needed to lower ρ."""
    window: int = 200
    """Episodes in the curriculum's success window (and its cooldown)."""
    learning_rate: float = 3e-4
    """Initial Adam learning rate (then adapted to the KL target with ``schedule="adaptive"``)."""
    schedule: Literal["adaptive", "fixed"] = "adaptive"
    """Learning-rate schedule: ``adaptive`` (rsl-rl's KL-target rule) or ``fixed``."""
    epochs: int = 4
    """PPO epochs per iteration."""
    mini_batches: int = 4
    """Mini-batches per epoch (recurrent: split by world; ``num_envs`` must be divisible by it)."""
    gamma: float = 0.99
    """Discount factor per step."""
    lam: float = 0.95
    """GAE λ."""
    clip: float = 0.2
    """PPO ratio (and value) clipping."""
    desired_kl: float = 0.01
    """KL target of the adaptive learning rate."""
    max_grad_norm: float = 1.0
    """Gradient-norm clip (actor and critic parameters separately, as rsl-rl)."""
    reward_scale: float = 0.1
    """Training rewards are multiplied by this (same optimal policy): it keeps the shared trunk's value-loss
    gradients (returns of ±20 otherwise) from drowning the policy gradient under gradient clipping."""
    value_loss_coef: float = 0.5
    """Weight of the value loss."""
    entropy_coef: float = 0.0
    """Weight of the entropy bonus (0: the std is fixed)."""
    threads: int = 2
    """CPU threads the PPO update splits each mini-batch across (:mod:`crowdbench.training.ppo`). Deterministic
    for a given count; other counts differ in the last bits of the gradient sums."""
    env_processes: int = 2
    """Processes that step the worlds and compute their actions (:mod:`crowdbench.training.rollout`): 1 = this
    process. The same transitions for any count, up to float rounding."""
    checkpoint_every: int = 20
    """Iterations between checkpoints (``last.pt``; all worlds restart there, so resume is exact)."""
    eval_every: int = 20
    """Iterations between quick deterministic evaluations (circle crossing, 20 pedestrians, ρ = 0.5); 0 = none."""
    eval_episodes: int = 100
    """Episodes per quick evaluation."""
    until_success: float = 0.0
    """Stop after the first quick evaluation whose success rate reaches this (0 = never; needs ``eval_every``)."""
    init: dict[str, Any] | None = None
    """Where this run's network started (``crowdbench train --init``): ``None`` for fresh weights, else the
    provenance of the checkpoint whose weights it took (``path``, ``sha256``, ``method``, ``seed``, ``iteration``,
    ``env_steps``); set by :meth:`~crowdbench.training.trainer.Trainer.warm_start`, not by hand."""
    extra: dict[str, Any] = field(default_factory=dict)
    """Free-form notes stored with the run (not read by training)."""

    def __post_init__(self) -> None:
        method = PPO_METHODS.get(self.method)  # unknown method: one error naming the valid ones
        model = self.model
        if model is None:
            model = method.model_config(**method().variant_model(None))
        elif isinstance(model, dict):
            model = _strict(method.model_config, model, "model")
        elif not isinstance(model, method.model_config):
            kind = method.model_config.__name__
            raise ValueError(f"model={model!r}; valid choices: a {kind} or a dict of its fields")
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "humans_range", tuple(int(n) for n in self.humans_range))
        for name in ("num_envs", "steps_per_env", "iterations", "epochs", "mini_batches", "threads", "env_processes",
                     "checkpoint_every", "window", "eval_episodes"):
            if not isinstance(getattr(self, name), int) or getattr(self, name) < 1:
                raise ValueError(f"{name}={getattr(self, name)!r}; valid choices: an integer ≥ 1")
        if self.eval_every < 0:
            raise ValueError(f"eval_every={self.eval_every}; valid choices: an integer ≥ 0 (0 = no evaluations)")
        lo, hi = self.humans_range
        if len(self.humans_range) != 2 or not 0 <= lo <= hi:
            raise ValueError(f"humans_range={self.humans_range}; valid choices: (low, high) with 0 ≤ low ≤ high")
        for name in ("rho_init", "rho_min", "eta", "gamma", "lam", "until_success"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(f"{name}={getattr(self, name)}; valid choices: a number in [0, 1]")
        for name in ("learning_rate", "reward_scale", "clip", "max_grad_norm", "desired_kl"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name}={getattr(self, name)}; valid choices: a positive number")
        if self.schedule not in ("adaptive", "fixed"):
            raise ValueError(f"schedule={self.schedule!r}; valid choices: adaptive, fixed")
        if self.minutes < 0:
            raise ValueError(f"minutes={self.minutes}; valid choices: ≥ 0 (0 = no wall-clock budget)")
        if self.until_success and not self.eval_every:
            raise ValueError("until_success needs quick evaluations; valid choices: eval_every ≥ 1")
        if self.env_processes > self.num_envs:
            raise ValueError(f"env_processes={self.env_processes}; valid choices: 1 … num_envs ({self.num_envs})")
        if self.num_envs % self.mini_batches:
            raise ValueError(f"num_envs={self.num_envs} must be divisible by mini_batches={self.mini_batches} "
                             "(rsl-rl silently drops the remainder from recurrent updates)")

    @classmethod
    def for_method(cls, method: str, **overrides: Any) -> TrainConfig:
        """A run of ``method`` with its own training recipe (:attr:`PPOMethod.train_defaults
        <crowdbench.training.methods.PPOMethod.train_defaults>`, e.g. DS-RNN's PPO settings) under ``overrides``;
        ``TrainConfig(method=...)`` alone keeps this class's defaults (H²INT's)."""
        return cls(**{**PPO_METHODS.get(method).train_defaults, "method": method, **overrides})

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able dict (the ``model`` as a dict of its fields)."""
        d = dataclasses.asdict(self)
        d["humans_range"] = list(self.humans_range)
        d["model"] = {k: list(v) if isinstance(v, tuple) else v for k, v in d["model"].items()}
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrainConfig:
        """The inverse of :meth:`to_dict`; unknown keys are an error."""
        return _strict(cls, d, "train config")

    def replace(self, **changes: Any) -> TrainConfig:
        return dataclasses.replace(self, **changes)


def _strict(cls: type, d: dict[str, Any], what: str) -> Any:
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(d) - names)
    if unknown:
        raise ValueError(f"{what}: unknown keys {unknown}; valid choices: {', '.join(sorted(names))}")
    return cls(**d)
