"""The rsl-rl adapter of the plain-torch recurrent actors: the same network, with rsl-rl's model interface.

The networks live in :mod:`crowdbench.policies.nets` (and each method's ``model.py``) and import neither rsl-rl nor
this package; running a trained policy needs nothing else. Training wraps them here:

* :func:`rsl_rl_actor` — the rsl-rl actor class of a :class:`~crowdbench.policies.nets.RecurrentTrunkActor`
  subclass: the same modules in the same order (so state dicts and optimiser states are the same), rsl-rl's
  ``MLPModel`` interface on top (``forward(obs, masks, hidden_state, stochastic_output)``, ``get_latent``,
  ``reset``, the output distribution), and the noise as rsl-rl's ``GaussianDistribution`` (the plain
  :class:`~crowdbench.policies.nets.GaussianStd` holds the same ``std_param``);
* :class:`SharedTrunkCritic` — a value MLP on the actor's latent. It holds a (non-registered) reference to the actor
  and reuses the actor's latent for the same observation object (PPO always calls the actor first), computing it
  through the shared trunk otherwise; its only parameters are the value head's.
"""

from __future__ import annotations

import functools
from typing import Any

import torch
from rsl_rl.models import MLPModel
from rsl_rl.utils import resolve_class
from tensordict import TensorDict

from crowdbench.policies.nets import RecurrentTrunkActor


class RslRlTrunkActor:
    """rsl-rl's ``MLPModel`` interface over a :class:`~crowdbench.policies.nets.RecurrentTrunkActor` (mixed in
    before it by :func:`rsl_rl_actor`; the constructor takes rsl-rl's arguments)."""

    net_class: type[RecurrentTrunkActor]
    """The plain network class this adapter wraps (picklable; the adapter class is built on demand)."""

    def __init__(self, obs: TensorDict, obs_groups: dict, obs_set: str, output_dim: int, **kwargs: Any) -> None:
        super().__init__(obs, output_dim, **kwargs)
        self.obs_groups = list(self.obs_keys)
        if self.distribution is not None:  # rsl-rl's Gaussian, the same parameter (same name, place and value)
            dist_class, dist_cfg = resolve_class(dict(kwargs["distribution_cfg"]))
            dist = dist_class(output_dim, **dist_cfg)
            with torch.no_grad():
                dist.std_param.copy_(self.distribution.std_param)
            self.distribution = dist

    def forward(self, obs: TensorDict, masks: torch.Tensor | None = None, hidden_state: Any = None,
                stochastic_output: bool = False) -> torch.Tensor:
        out = self.mlp(self.get_latent(obs, masks, hidden_state))
        if self.distribution is not None:
            if stochastic_output:
                self.distribution.update(out)
                return self.distribution.sample()
            return self.distribution.deterministic_output(out)
        return out

    def get_latent(self, obs: TensorDict, masks: torch.Tensor | None = None, hidden_state: Any = None
                   ) -> torch.Tensor:
        latent = self.trunk(obs, masks, hidden_state)
        self._cache = (obs, latent)
        return latent

    def reset(self, dones: torch.Tensor | None = None, hidden_state: Any = None) -> None:
        self.rnn.reset(dones, hidden_state)

    def get_hidden_state(self) -> Any:
        return self.rnn.hidden_state

    def detach_hidden_state(self, dones: torch.Tensor | None = None) -> None:
        self.rnn.detach_hidden_state(dones)

    @property
    def output_mean(self) -> torch.Tensor:
        return self.distribution.mean

    @property
    def output_std(self) -> torch.Tensor:
        return self.distribution.std

    @property
    def output_entropy(self) -> torch.Tensor:
        return self.distribution.entropy

    @property
    def output_distribution_params(self) -> tuple[torch.Tensor, ...]:
        return self.distribution.params

    def get_output_log_prob(self, outputs: torch.Tensor) -> torch.Tensor:
        return self.distribution.log_prob(outputs)

    def get_kl_divergence(self, old_params: tuple[torch.Tensor, ...], new_params: tuple[torch.Tensor, ...]
                          ) -> torch.Tensor:
        return self.distribution.kl_divergence(old_params, new_params)


@functools.cache
def rsl_rl_actor(net_class: type[RecurrentTrunkActor]) -> type:
    """The rsl-rl actor class of the plain network ``net_class`` (one class per network class)."""
    if not (isinstance(net_class, type) and issubclass(net_class, RecurrentTrunkActor)):
        raise ValueError(f"actor class {net_class!r}; valid choices: a crowdbench.policies.nets.RecurrentTrunkActor "
                         "subclass")
    return type(f"RslRl{net_class.__name__}", (RslRlTrunkActor, net_class),
                {"__module__": __name__, "__doc__": f"rsl-rl adapter of {net_class.__qualname__}.",
                 "net_class": net_class})


def is_rsl_rl_actor(cls: Any) -> bool:
    """Whether ``cls`` is an adapter class made by :func:`rsl_rl_actor`."""
    return isinstance(cls, type) and issubclass(cls, RslRlTrunkActor) and issubclass(cls, RecurrentTrunkActor)


class SharedTrunkCritic(MLPModel):
    """Value head on a :func:`rsl_rl_actor` actor's latent (see the module docstring)."""

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
