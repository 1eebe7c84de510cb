"""rsl-rl models for recurrent policies whose actor and critic share one trunk.

The paper's H²INT (and CrowdNav++'s DS-RNN and AIG-GST, which share a recurrent trunk too) compute one latent per
step — an encoder of the crowd, then a GRU — and read both the Gaussian action mean and the value from it. rsl-rl 5
keeps actor and critic as two modules, each with its own ``get_latent``; here:

* :class:`RecurrentTrunkActor` — ``encode_samples(obs) → z`` ``(n, z_dim)`` (the method's own encoder, abstract),
  a GRU (rsl-rl's :class:`~rsl_rl.modules.RNN`) → latent ``(n, H)``, rsl-rl's MLP head → Gaussian mean;
* :class:`SharedTrunkCritic` — a value MLP on the same latent. It holds a (non-registered) reference to the actor and
  reuses the actor's latent for the same observation object (PPO always calls the actor first), computing it through
  the shared trunk otherwise; its only parameters are the value head's.

A new PPO method subclasses :class:`RecurrentTrunkActor` (implements :meth:`~RecurrentTrunkActor.encode_samples`,
sets :attr:`~RecurrentTrunkActor.obs_keys`) and trains through :mod:`crowdbench.training` unchanged; a method whose
recurrence is not "encoder, then one GRU" returns its own recurrent module from
:meth:`~RecurrentTrunkActor.make_rnn` (DS-RNN: :mod:`crowdbench.policies.dsrnn.model`).
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping
from typing import Any, ClassVar

import torch
import torch.nn as nn
from rsl_rl.models import MLPModel
from rsl_rl.modules import RNN
from tensordict import TensorDict


def check_action_std(action_std: float) -> None:
    """One clear error for a non-positive policy standard deviation (each PPO config's ``__post_init__``, so a
    config that exists is valid and :func:`gaussian_cfg` need not check again)."""
    if not (isinstance(action_std, int | float) and action_std > 0):
        raise ValueError(f"action_std={action_std!r}; valid choices: a positive float [m/s]")


def gaussian_cfg(init_std: float, learn_std: bool) -> dict[str, Any]:
    """rsl-rl's ``distribution_cfg`` of a state-independent Gaussian policy: standard deviation ``init_std``
    [m/s], learned by PPO or kept fixed (every PPO method's actor uses it)."""
    return {"class_name": "GaussianDistribution", "init_std": init_std, "learn_std": learn_std}


class RecurrentTrunkActor(MLPModel):
    """rsl-rl actor: encoder → GRU → MLP head → Gaussian mean (see the module docstring).

    Args:
        obs, obs_groups, obs_set, output_dim: As for :class:`rsl_rl.models.MLPModel`.
        z_dim: Width of the encoder's output.
        gru_hidden: GRU state size H (= the latent the heads read).
        hidden_dims, activation, distribution_cfg: The action head, as for :class:`rsl_rl.models.MLPModel`.
    """

    is_recurrent = True
    obs_keys: ClassVar[tuple[str, ...]] = ()
    """Observation groups :meth:`encode_samples` reads (each ``(n, ...)``)."""

    def __init__(self, obs: TensorDict, obs_groups: dict, obs_set: str, output_dim: int, z_dim: int,
                 gru_hidden: int, hidden_dims: tuple[int, ...] | list[int] = (64,), activation: str = "elu",
                 distribution_cfg: dict | None = None) -> None:
        self.latent_dim = gru_hidden
        self.z_dim = z_dim
        super().__init__(obs, obs_groups, obs_set, output_dim, hidden_dims, activation, False, distribution_cfg)
        self.rnn = self.make_rnn(z_dim, gru_hidden)
        self._cache: tuple[Any, torch.Tensor] | None = None

    def make_rnn(self, z_dim: int, latent: int) -> nn.Module:
        """The recurrence from the encoder output ``z_dim`` to the latent: one GRU (``rsl_rl.modules.RNN``); a
        method with another recurrence returns a module with the same interface (``forward(z, masks,
        hidden_state)``, ``reset``, ``hidden_state``, ``detach_hidden_state``)."""
        return RNN(z_dim, latent, 1, "gru")

    @abstractmethod
    def encode_samples(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """The encoder on independent samples: ``obs[k]`` ``(n, ...)`` for ``k`` in :attr:`obs_keys` →
        ``(n, z_dim)``."""

    def encode(self, obs: Mapping[str, torch.Tensor], masks: torch.Tensor | None = None) -> torch.Tensor:
        """Encoder output for every step: ``(n, z_dim)`` in rollouts, ``(T, B, z_dim)`` for rsl-rl's padded
        trajectories (``masks`` ``(T, B)``: only the valid entries are encoded; padding stays zero)."""
        if masks is None:
            return self.encode_samples({k: obs[k] for k in self.obs_keys})
        first = obs[self.obs_keys[0]]
        z = first.new_zeros((*masks.shape, self.z_dim))
        z[masks] = self.encode_samples({k: obs[k][masks] for k in self.obs_keys})
        return z

    @property
    def state_size(self) -> int:
        """Width of the recurrent state carried between steps, ``(1, n, state_size)``."""
        return self.rnn.rnn.hidden_size

    def step(self, z: torch.Tensor, state: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """One recurrent step with an explicit state (world processes keep their own): encoder outputs ``(n,
        z_dim)``, state ``(1, n, state_size)`` → latent ``(n, H)``, next state."""
        out, nxt = self.rnn.rnn(z.unsqueeze(0), state)
        return out.squeeze(0), nxt

    def work(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """Relative cost of encoding each sample of ``obs`` (leading dims ``(T, B)``), used to give the update's
        threads equal shares; default: equal."""
        return torch.ones(obs[self.obs_keys[0]].shape[:2])

    def trunk(self, obs: Mapping[str, torch.Tensor], masks: torch.Tensor | None = None,
              hidden_state: torch.Tensor | None = None) -> torch.Tensor:
        """The shared latent: ``(n, H)`` stepping the actor's own recurrent state, or ``(T, B, H)`` over padded
        trajectories from ``hidden_state`` ``(1, B, H)``."""
        return self.rnn(self.encode(obs, masks), masks, hidden_state).squeeze(0)

    def value_head(self) -> nn.Module:
        """The critic's value MLP (set by :class:`SharedTrunkCritic`; a reference, not a submodule)."""
        head = self.__dict__.get("_value_head")
        if head is None:
            raise RuntimeError("no SharedTrunkCritic was built on this actor")
        return head

    # ---- rsl-rl's MLPModel hooks
    def _get_obs_dim(self, obs, obs_groups, obs_set):
        return list(self.obs_keys), 0

    def _get_latent_dim(self) -> int:
        return self.latent_dim

    def get_latent(self, obs, masks=None, hidden_state=None):
        latent = self.trunk(obs, masks, hidden_state)
        self._cache = (obs, latent)
        return latent

    def reset(self, dones=None, hidden_state=None) -> None:
        self.rnn.reset(dones, hidden_state)

    def get_hidden_state(self):
        return self.rnn.hidden_state

    def detach_hidden_state(self, dones=None) -> None:
        self.rnn.detach_hidden_state(dones)

    def update_normalization(self, obs: TensorDict) -> None:
        """Update the encoder's observation statistics, if it keeps any (override)."""


class SharedTrunkCritic(MLPModel):
    """Value head on a :class:`RecurrentTrunkActor`'s latent (see the module docstring)."""

    is_recurrent = True

    def __init__(self, obs: TensorDict, obs_groups: dict, obs_set: str, output_dim: int, actor: RecurrentTrunkActor,
                 hidden_dims: tuple[int, ...] | list[int] = (64,), activation: str = "elu") -> None:
        self.latent_dim = actor.latent_dim
        self.obs_keys = actor.obs_keys
        super().__init__(obs, obs_groups, obs_set, output_dim, hidden_dims, activation, False, None)
        object.__setattr__(self, "_actor", actor)  # a reference, not a submodule: parameters are not duplicated
        actor.__dict__["_value_head"] = self.mlp

    def _get_obs_dim(self, obs, obs_groups, obs_set):
        return list(self.obs_keys), 0

    def _get_latent_dim(self) -> int:
        return self.latent_dim

    def get_latent(self, obs, masks=None, hidden_state=None):
        cache = self._actor._cache
        if cache is not None and cache[0] is obs:
            return cache[1]
        return self._actor.trunk(obs, masks, hidden_state)

    def reset(self, dones=None, hidden_state=None) -> None:
        if dones is None and hidden_state is not None:  # compute_returns restores the shared state
            self._actor.rnn.reset(None, hidden_state)

    def get_hidden_state(self):
        return self._actor.rnn.hidden_state

    def update_normalization(self, obs: TensorDict) -> None:
        pass
