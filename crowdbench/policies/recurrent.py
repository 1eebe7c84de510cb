"""The robot policy of a trained recurrent PPO actor (H²INT, DS-RNN, AIG-GST): deterministic (the Gaussian's mean),
one recurrent state per world, under ``torch.inference_mode``. Imports torch (not rsl-rl, not
:mod:`crowdbench.training`): the learned methods' policy modules load it on first use.

* :func:`load_actor` — a method's plain-torch actor (:class:`~crowdbench.policies.nets.RecurrentTrunkActor`) from a
  checkpoint;
* :class:`RecurrentActorPolicy` — a live actor driving the robot;
* :class:`TrainedRecurrentPolicy` — what the methods share: ``checkpoint=`` (path or shipped name) or ``actor=`` (a
  live one, evaluation during training); a method sets :attr:`~TrainedRecurrentPolicy.method`,
  :attr:`~TrainedRecurrentPolicy.model_config` and :attr:`~TrainedRecurrentPolicy.build_actor`.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from functools import partial
from typing import Any, ClassVar

import numpy as np
import torch

from crowdbench import checkpoints
from crowdbench.config import WorldConfig
from crowdbench.policies.base import RobotPolicy
from crowdbench.policies.nets import RecurrentTrunkActor


def stored_config(cls: type, ckpt: dict[str, Any]) -> Any:
    """The architecture dataclass ``cls`` of a checkpoint's ``model`` fields (JSON lists back to tuples)."""
    return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in dict(ckpt["model"]).items()})


def load_actor(method: str, checkpoint: str | os.PathLike | None, model_config: Callable[[dict[str, Any]], Any],
               build_actor: Callable[[Any, int], RecurrentTrunkActor]) -> tuple[RecurrentTrunkActor, Any, dict]:
    """A recurrent PPO method's actor from a checkpoint (path, shipped name, or ``None``: the shipped one named like
    ``method``) in eval mode, its architecture (``model_config(ckpt)``) and metadata (iteration, env steps, seed,
    path)."""
    path = checkpoints.resolve(method, checkpoint)
    ckpt = checkpoints.load(path, method)
    cfg = model_config(ckpt)
    actor = build_actor(cfg, int(ckpt["n_max"]))
    actor.load_state_dict(ckpt["actor"])
    meta = {k: ckpt.get(k) for k in ("iteration", "env_steps", "seed")}
    return actor.eval(), cfg, {**meta, "path": path}


class RecurrentActorPolicy(RobotPolicy):
    """A :class:`~crowdbench.policies.nets.RecurrentTrunkActor` driving the robot: ``encode_samples`` → ``step``
    with each world's state → the head's mean action.

    Args:
        config: World configuration; ``max_humans_observed`` must equal the actor's ``slots``.
        actor: The actor (in eval mode from here on).
        slots: Pedestrian slots the actor was built for.
        meta: The checkpoint's metadata (kept as :attr:`meta`).
    """

    def __init__(self, config: WorldConfig | None, actor: RecurrentTrunkActor, slots: int,
                 meta: dict[str, Any] | None = None) -> None:
        super().__init__(config)
        if slots != self.config.max_humans_observed:
            raise ValueError(f"max_humans_observed={self.config.max_humans_observed} but the checkpoint was trained "
                             f"with N_max={slots}")
        self.meta = meta or {}
        self.actor = actor.eval()
        self.hidden: torch.Tensor | None = None

    @torch.inference_mode()
    def reset(self, done: np.ndarray | None = None) -> None:
        if done is None or self.hidden is None:
            self.hidden = None
        else:
            self.hidden[:, torch.from_numpy(np.asarray(done, dtype=bool))] = 0.0

    @torch.inference_mode()
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        x = {k: torch.as_tensor(obs[k], dtype=torch.float32) for k in self.actor.obs_keys}
        n = len(x[self.actor.obs_keys[0]])
        if self.hidden is None or self.hidden.shape[1] != n:
            self.hidden = torch.zeros(1, n, self.actor.state_size)
        action, self.hidden = self.actor.act(x, self.hidden)
        return action.numpy().astype(np.float64)


class TrainedRecurrentPolicy(RecurrentActorPolicy):
    """A recurrent PPO method's robot policy: a shipped or trained checkpoint, or a live actor.

    Args:
        config: World configuration (``max_humans_observed`` must equal the checkpoint's slot count).
        checkpoint: Path or shipped name (default: the shipped checkpoint named like the method).
        actor: Alternatively a live actor of :attr:`model_config`'s network (evaluation during training).
    """

    method: ClassVar[str]
    """The method's registry name (what its checkpoints record)."""
    model_config: ClassVar[type]
    """The architecture dataclass stored in its checkpoints (``model``)."""
    build_actor: ClassVar[Callable[[Any, int], RecurrentTrunkActor]]
    """``build_actor(model, n_max)``: an untrained actor (a ``staticmethod``)."""

    def __init__(self, config: WorldConfig | None = None, checkpoint: str | None = None,
                 actor: RecurrentTrunkActor | None = None) -> None:
        meta: dict[str, Any] = {}
        if actor is None:
            actor, meta = self.load_actor(checkpoint)
        super().__init__(config, actor, actor.slots, meta)

    @classmethod
    def load_actor(cls, checkpoint: str | os.PathLike | None = None) -> tuple[RecurrentTrunkActor, dict[str, Any]]:
        """The actor of a checkpoint (path or shipped name; ``None``: the method's shipped default) in eval mode, and
        the checkpoint's metadata (:meth:`describe` added)."""
        actor, cfg, meta = load_actor(cls.method, checkpoint, partial(stored_config, cls.model_config),
                                      cls.build_actor)
        return actor, {**meta, **cls.describe(cfg)}

    @classmethod
    def describe(cls, model: Any) -> dict[str, Any]:
        """Metadata of architecture ``model`` worth keeping with a loaded checkpoint (default: none)."""
        return {}
