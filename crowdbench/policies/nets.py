"""Plain-torch building blocks of the learned robot policies, and the recurrent shared-trunk actor they build on.

Running, loading or exporting a policy needs only these (no rsl-rl, no :mod:`crowdbench.training`); training wraps
the same modules in rsl-rl's model interface (:func:`crowdbench.training.models.rsl_rl_actor`). The modules mirror the
layout of rsl-rl 5's (``MLPModel``: ``distribution``, ``mlp``; ``RNN``: ``rnn``; ``EmpiricalNormalization``:
``_mean``, ``_var``, ``_std``, ``count``) parameter for parameter and in the same order, so every checkpoint written
by either loads into the other and an optimiser's state lines up.

* :class:`RecurrentTrunkActor` — ``encode_samples(obs) → z`` ``(n, z_dim)`` (the method's own encoder, abstract),
  a recurrence (:class:`RecurrentCell`: one GRU) → latent ``(n, H)``, an MLP head → the Gaussian policy's mean;
  the state-independent standard deviation is :class:`GaussianStd`. The value head (training) reads the same latent.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import torch
from torch import nn

ACTIVATIONS: dict[str, type[nn.Module]] = {"elu": nn.ELU, "selu": nn.SELU, "relu": nn.ReLU, "crelu": nn.CELU,
                                           "lrelu": nn.LeakyReLU, "tanh": nn.Tanh, "sigmoid": nn.Sigmoid,
                                           "softplus": nn.Softplus, "gelu": nn.GELU, "swish": nn.SiLU,
                                           "mish": nn.Mish, "identity": nn.Identity}
"""Activation names of the heads (rsl-rl's)."""
STD_RANGE = (1e-6, 1e6)
"""Clamp of the policy's standard deviation [m/s] (rsl-rl's ``GaussianDistribution`` default)."""


def check_action_std(action_std: float) -> None:
    """One clear error for a non-positive policy standard deviation (each PPO config's ``__post_init__``)."""
    if not (isinstance(action_std, int | float) and action_std > 0):
        raise ValueError(f"action_std={action_std!r}; valid choices: a positive float [m/s]")


def gaussian_cfg(init_std: float, learn_std: bool) -> dict[str, Any]:
    """The ``distribution_cfg`` of a state-independent Gaussian policy: standard deviation ``init_std`` [m/s],
    learned by PPO or kept fixed (rsl-rl's format; every PPO method's actor takes it)."""
    return {"class_name": "GaussianDistribution", "init_std": init_std, "learn_std": learn_std}


def mlp(input_dim: int, output_dim: int, hidden_dims: Sequence[int], activation: str = "elu") -> nn.Sequential:
    """Linear layers with ``activation`` between them, the last one linear (rsl-rl's ``MLP`` layout: modules
    ``0, 1, 2, ...``)."""
    if activation not in ACTIVATIONS:
        raise ValueError(f"activation={activation!r}; valid choices: {', '.join(ACTIVATIONS)}")
    act = ACTIVATIONS[activation]()
    dims = [input_dim, *hidden_dims]
    layers: list[nn.Module] = []
    for a, b in zip(dims[:-1], dims[1:], strict=True):
        layers += [nn.Linear(a, b), act]
    return nn.Sequential(*layers, nn.Linear(dims[-1], output_dim))


def unpad_trajectories(trajectories: torch.Tensor, masks: torch.Tensor) -> torch.Tensor:
    """The valid steps of padded trajectories ``(T, B, ...)`` under ``masks`` ``(T, B)``, as rsl-rl's recurrent
    update expects them back (``rsl_rl.utils.unpad_trajectories``)."""
    valid = trajectories.transpose(1, 0)[masks.transpose(1, 0)]
    return valid.view(-1, trajectories.shape[0], *trajectories.shape[2:]).transpose(1, 0)


class RunningNorm(nn.Module):
    """Normalisation by a running mean and standard deviation, updated in training mode (rsl-rl's
    ``EmpiricalNormalization``: same buffers, same update).

    Args:
        shape: Shape of one sample.
        eps: Added to the standard deviation.
    """

    def __init__(self, shape: int | tuple[int, ...], eps: float = 1e-2) -> None:
        super().__init__()
        self.eps = eps
        self.register_buffer("_mean", torch.zeros(shape).unsqueeze(0))
        self.register_buffer("_var", torch.ones(shape).unsqueeze(0))
        self.register_buffer("_std", torch.ones(shape).unsqueeze(0))
        self.register_buffer("count", torch.tensor(0, dtype=torch.long))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return (x - self._mean) / (self._std + self.eps)

    @torch.jit.unused
    def update(self, x: torch.Tensor) -> None:
        """Fold the batch ``x`` ``(n, *shape)`` into the statistics (training mode only)."""
        if not self.training:
            return
        count_x = torch.tensor(x.shape[0], dtype=self.count.dtype, device=self.count.device)
        var_x = torch.var(x, dim=0, unbiased=False, keepdim=True)
        mean_x = torch.mean(x, dim=0, keepdim=True)
        self.count += count_x
        rate = count_x / self.count
        delta_mean = mean_x - self._mean
        self._mean += rate * delta_mean
        self._var += rate * (var_x - self._var + delta_mean * (mean_x - self._mean))
        self._std = torch.sqrt(self._var)


class GaussianStd(nn.Module):
    """The state-independent standard deviation ``(A,)`` of a Gaussian policy, learned or fixed [m/s]."""

    def __init__(self, output_dim: int, init_std: float = 1.0, learn_std: bool = True) -> None:
        super().__init__()
        self.std_param = nn.Parameter(init_std * torch.ones(output_dim), requires_grad=learn_std)

    @property
    def std(self) -> torch.Tensor:
        """The clamped standard deviation ``(A,)`` (:data:`STD_RANGE`)."""
        return self.std_param.clamp(*STD_RANGE)


def gaussian_std_module(output_dim: int, distribution_cfg: dict[str, Any] | None) -> GaussianStd | None:
    """The :class:`GaussianStd` of a :func:`gaussian_cfg` (``None``: a deterministic head)."""
    if distribution_cfg is None:
        return None
    cfg = dict(distribution_cfg)
    if cfg.pop("class_name", "GaussianDistribution") != "GaussianDistribution" or set(cfg) - {"init_std", "learn_std"}:
        raise ValueError(f"distribution_cfg={distribution_cfg!r}; valid choices: gaussian_cfg(init_std, learn_std)")
    return GaussianStd(output_dim, **cfg)


class CarriedState(nn.Module):
    """A recurrence that carries its state between rollout steps in :attr:`hidden_state` ``(1, n, ·)`` (``None``:
    zeros on the next step), with rsl-rl's ``reset`` and ``detach_hidden_state``."""

    hidden_state: torch.Tensor | None = None

    def reset(self, dones: torch.Tensor | None = None, hidden_state: torch.Tensor | None = None) -> None:
        """All states (to ``hidden_state`` or none), or zero those of the worlds where ``dones == 1``."""
        if dones is None:
            self.hidden_state = hidden_state
        elif self.hidden_state is not None:
            if hidden_state is not None:
                raise NotImplementedError("resetting done worlds to a given hidden state")
            self.hidden_state[..., dones == 1, :] = 0.0

    def detach_hidden_state(self, dones: torch.Tensor | None = None) -> None:
        """Cut the state's gradient history (all worlds, or those where ``dones == 1``)."""
        if self.hidden_state is not None:
            if dones is None:
                self.hidden_state = self.hidden_state.detach()
            else:
                self.hidden_state[..., dones == 1, :] = self.hidden_state[..., dones == 1, :].detach()


class RecurrentCell(CarriedState):
    """One GRU layer with a carried state: ``forward(z, masks, hidden_state)`` steps the internal state on ``(n, ·)``
    inputs (rollouts) or runs padded trajectories ``(T, B, ·)`` from stored states (the update). rsl-rl's ``RNN``
    interface; the GRU is :attr:`rnn`."""

    def __init__(self, input_size: int, hidden_size: int) -> None:
        super().__init__()
        self.rnn = nn.GRU(input_size=input_size, hidden_size=hidden_size, num_layers=1)
        self.hidden_state: torch.Tensor | None = None

    def forward(self, input: torch.Tensor, masks: torch.Tensor | None = None,  # noqa: A002 - rsl-rl's name
                hidden_state: torch.Tensor | None = None) -> torch.Tensor:
        if masks is not None:
            if hidden_state is None:
                raise ValueError("RecurrentCell: the update needs the stored initial hidden states")
            out, _ = self.rnn(input, hidden_state)
            return unpad_trajectories(out, masks)
        out, self.hidden_state = self.rnn(input.unsqueeze(0), self.hidden_state)
        return out

class RecurrentTrunkActor(nn.Module):
    """Encoder → recurrence → MLP head → the Gaussian policy's mean (see the module docstring).

    A method subclasses it: sets :attr:`obs_keys`, implements :meth:`encode_samples`, and may replace the
    recurrence (:meth:`make_rnn`, :meth:`step`, :attr:`state_size`).

    Args:
        obs: An example observation, ``obs[k]`` ``(1, ...)`` for ``k`` in :attr:`obs_keys` (shapes only).
        output_dim: Action dimension A.
        z_dim: Width of the encoder's output.
        gru_hidden: Recurrent latent size H (what the heads read).
        hidden_dims, activation: The action head's hidden layers and activation.
        distribution_cfg: The policy noise (:func:`gaussian_cfg`); ``None``: deterministic.
    """

    is_recurrent: ClassVar[bool] = True
    obs_keys: ClassVar[tuple[str, ...]] = ()
    """Observation groups :meth:`encode_samples` reads (each ``(n, ...)``)."""

    def __init__(self, obs: Mapping[str, torch.Tensor], output_dim: int, z_dim: int, gru_hidden: int,
                 hidden_dims: Sequence[int] = (64,), activation: str = "elu",
                 distribution_cfg: dict[str, Any] | None = None) -> None:
        super().__init__()
        self.latent_dim = gru_hidden
        self.z_dim = z_dim
        # registration order = rsl-rl MLPModel's, then the trunk's: checkpoints' and optimisers' parameter order
        self.distribution = gaussian_std_module(output_dim, distribution_cfg)
        self.mlp = mlp(gru_hidden, output_dim, hidden_dims, activation)
        self.rnn = self.make_rnn(z_dim, gru_hidden)
        self._cache: tuple[Any, torch.Tensor] | None = None

    def make_rnn(self, z_dim: int, latent: int) -> nn.Module:
        """The recurrence from the encoder output ``z_dim`` to the latent: one GRU (:class:`RecurrentCell`); a method
        with another recurrence returns a module with the same interface (``forward(z, masks, hidden_state)``,
        ``reset``, ``hidden_state``, ``detach_hidden_state``)."""
        return RecurrentCell(z_dim, latent)

    @abstractmethod
    def encode_samples(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """The encoder on independent samples: ``obs[k]`` ``(n, ...)`` for ``k`` in :attr:`obs_keys` →
        ``(n, z_dim)``."""

    def encode(self, obs: Mapping[str, torch.Tensor], masks: torch.Tensor | None = None) -> torch.Tensor:
        """Encoder output for every step: ``(n, z_dim)`` in rollouts, ``(T, B, z_dim)`` for padded trajectories
        (``masks`` ``(T, B)``: only the valid entries are encoded; padding stays zero)."""
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
        """One recurrent step with an explicit state: encoder outputs ``(n, z_dim)``, state ``(1, n, state_size)``
        → latent ``(n, H)``, next state."""
        out, nxt = self.rnn.rnn(z.unsqueeze(0), state)
        return out.squeeze(0), nxt

    def forward(self, obs: Mapping[str, torch.Tensor], masks: torch.Tensor | None = None,
                hidden_state: torch.Tensor | None = None) -> torch.Tensor:
        """The Gaussian's mean: ``(n, A)`` stepping the module's own recurrent state, or ``(T, B, A)`` over padded
        trajectories (:meth:`trunk`)."""
        return self.mlp(self.trunk(obs, masks, hidden_state))

    def act(self, obs: Mapping[str, torch.Tensor], state: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The deterministic action (the Gaussian's mean) ``(n, A)`` and the next state, from observations ``obs``
        ``(n, ...)`` and the recurrent ``state`` ``(1, n, state_size)``."""
        latent, nxt = self.step(self.encode_samples({k: obs[k] for k in self.obs_keys}), state)
        return self.mlp(latent), nxt

    def work(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        """Relative cost of encoding each sample of ``obs`` (leading dims ``(T, B)``), used to give a training
        update's threads equal shares; default: equal."""
        return torch.ones(obs[self.obs_keys[0]].shape[:2])

    def trunk(self, obs: Mapping[str, torch.Tensor], masks: torch.Tensor | None = None,
              hidden_state: torch.Tensor | None = None) -> torch.Tensor:
        """The shared latent: ``(n, H)`` stepping the module's own recurrent state, or ``(T, B, H)`` over padded
        trajectories from ``hidden_state`` ``(1, B, H)``."""
        return self.rnn(self.encode(obs, masks), masks, hidden_state).squeeze(0)

    def value_head(self) -> nn.Module:
        """The value MLP on the latent (set by training's critic; a reference, not a submodule)."""
        head = self.__dict__.get("_value_head")
        if head is None:
            raise RuntimeError("no value head was built on this actor (crowdbench.training's critic sets it)")
        return head

    def update_normalization(self, obs: Mapping[str, torch.Tensor]) -> None:
        """Update the encoder's observation statistics, if it keeps any (override; training mode)."""
