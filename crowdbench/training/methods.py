"""The contract between a learned method and the generic PPO training path, and the registry of such methods.

A method (H²INT, DS-RNN, AIG-GST) says what its network is and how it is evaluated; everything else — the batched
worlds, the rollout in the world processes, the per-thread PPO update, the curriculum, checkpoints and exact resume,
progress and plots — is :mod:`crowdbench.training`'s. A method's descriptor names its binding
(:class:`crowdbench.policies.Method` with ``trainer="ppo"``, ``training="my_pkg.training:MyMethod"``), after which
``crowdbench train mine`` trains it; :data:`PPO_METHODS` resolves those bindings by name (and still takes a direct
``PPO_METHODS.register(name, cls)`` or the entry-point group ``crowdbench.ppo_methods``). Value-based methods (CADRL,
SARL: imitation, then TD learning) do not use PPO; their training lives beside this one
(:mod:`crowdbench.training.value`).
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from typing import Any, ClassVar

from crowdbench.policies import METHODS
from crowdbench.registry import Registry


class PPOMethod(ABC):
    """A learned robot policy trained by :class:`~crowdbench.training.trainer.Trainer`.

    Class attributes:
        name: Registry name (also the ``method`` field of its checkpoints).
        model_config: Frozen dataclass of the architecture (every field documented); stored in checkpoints.
        actor_class: The network, a plain-torch :class:`~crowdbench.policies.nets.RecurrentTrunkActor` subclass
            (training wraps it for rsl-rl: :func:`~crowdbench.training.models.rsl_rl_actor`).
        observation: Robot observation the actor reads (``relative``, ``relative_by_id`` or ``full_state``); the
            training worlds and quick evaluations build it.
    """

    name: ClassVar[str]
    model_config: ClassVar[type]
    actor_class: ClassVar[type]
    observation: ClassVar[str] = "relative"
    train_defaults: ClassVar[dict[str, Any]] = {}
    """:class:`~crowdbench.training.config.TrainConfig` fields of the method's own recipe (applied by
    :meth:`TrainConfig.for_method <crowdbench.training.config.TrainConfig.for_method>` and ``crowdbench train``)."""

    variants: ClassVar[dict[str, dict[str, Any]]] = {}
    """Named architectures as :attr:`model_config` field overrides (``crowdbench train METHOD --variant NAME``); a
    method without any takes ``--variant`` as its config's own ``variant`` field (H²INT's ablations)."""

    default_variant: ClassVar[str | None] = None
    """The variant a run gets when it names none (``TrainConfig(model=None)``, ``crowdbench train`` without
    ``--variant``); ``None``: :attr:`model_config`'s own defaults."""

    def variant_model(self, name: str | None) -> dict[str, Any]:
        """The ``model`` fields of variant ``name`` (``None``: of :attr:`default_variant`)."""
        if name is None:
            return {} if self.default_variant is None else self.variant_model(self.default_variant)
        if not self.variants:
            return {"variant": name}
        if name not in self.variants:
            raise ValueError(f"--variant {name!r} for {self.name}; valid choices: {', '.join(self.variants)}")
        return dict(self.variants[name])

    def model_overrides(self, specs: list[str]) -> dict[str, Any]:
        """``FIELD=VALUE`` strings (``crowdbench train --model``) → :attr:`model_config` fields, each value parsed
        by its field's default type (``int``, ``float``, ``bool``, ``str``, or a comma-separated tuple such as
        ``head_dims=128,128``)."""
        fields = {f.name: f for f in dataclasses.fields(self.model_config)}
        out: dict[str, Any] = {}
        for spec in specs:
            name, sep, text = spec.partition("=")
            name = name.strip()
            if not sep or name not in fields:
                raise ValueError(f"--model {spec!r} for {self.name}: expected FIELD=VALUE with FIELD one of "
                                 f"{', '.join(fields)}")
            default = fields[name].default
            kind = type(default) if default is not dataclasses.MISSING else str
            try:
                if kind is tuple:
                    inner = type(default[0]) if default else int
                    out[name] = tuple(inner(v) for v in text.split(",") if v.strip())
                elif kind is bool:
                    if text.lower() not in ("true", "false", "1", "0"):
                        raise ValueError(text)
                    out[name] = text.lower() in ("true", "1")
                else:
                    out[name] = kind(text)
            except ValueError:
                raise ValueError(f"--model {spec!r} for {self.name}: {name} takes a {kind.__name__} value "
                                 f"(default {default!r})") from None
        return out

    def observation_name(self, model: Any) -> str:
        """The observation builder that architecture ``model`` reads (default: :attr:`observation`)."""
        return self.observation

    def observation_kwargs(self, model: Any) -> dict[str, Any]:
        """Options of the :attr:`observation` builder for architecture ``model`` (default: none)."""
        return {}

    @abstractmethod
    def actor_cfg(self, model: Any) -> dict[str, Any]:
        """Keyword arguments of :attr:`actor_class` for architecture ``model``."""

    @abstractmethod
    def critic_cfg(self, model: Any) -> dict[str, Any]:
        """Keyword arguments of the value head (:class:`~crowdbench.training.models.SharedTrunkCritic`)."""

    @abstractmethod
    def policy(self, config: Any, actor: Any) -> Any:
        """The deterministic :class:`~crowdbench.policies.RobotPolicy` of a live ``actor`` (quick evaluations)."""

    def label(self, model: Any) -> str:
        """Short name of a run's architecture (plots, default run folder): the method, and the most specific variant
        it matches (the most fields) unless that is the first (default) one."""
        def matches(fields: dict[str, Any]) -> bool:
            return all(getattr(model, k) == (tuple(v) if isinstance(v, list) else v) for k, v in fields.items())

        named = list(self.variants.items())[1:]
        matching = [(len(fields), name) for name, fields in named if matches(fields)]
        return f"{self.name}-{max(matching)[1]}" if matching else self.name


PPO_METHODS: Registry[PPOMethod] = Registry("PPO method", "crowdbench.ppo_methods")
"""The PPO bindings by method name: every registered method with ``trainer="ppo"`` (its ``training``)."""
PPO_METHODS.derive(METHODS, lambda m: m.training if m.trainer == "ppo" else None)
