"""Rollouts in which the world processes compute the robot's actions themselves.

In the pipelined rollout (:mod:`crowdbench.training.rollout`) the training process computes every action: each step,
each group of worlds waits for the network in the training process, then the training process waits for the worlds.
On two cores that ping-pong leaves a quarter of the CPU idle, and the network, interleaved with the other work of
the training process, runs ≈ 1.5× slower per call than back to back (measured: 3.0 against 2.0 ms of CPU time for a
128-world batch).

Here every world process holds a copy of the policy (:class:`RolloutPolicy`: the actor's encoder, GRU, head and
Gaussian, and the critic's value head — pickled with their current weights before every rollout) and the recurrent
state of its own worlds, and each step *acts and then steps* its worlds without waiting for anyone. The encoder runs
as one numba kernel (:mod:`crowdbench.policies.fused_infer`), which loses less to the physics step evicting the
caches than PyTorch's operators do. The training process only hands out, per step and group, the Gaussian noise and
the curriculum's current ρ, and files the transitions into rsl-rl's storage
(:func:`~crowdbench.training.rollout.store_step`, shared with the pipelined rollout).

The numbers do not depend on how the worlds are split: the noise of the whole rollout is drawn at its start from the
training process's torch generator, ``randn(steps, num_envs, 2)``, and action = mean + std · noise, so any number of
world processes (or none: ``processes=1`` runs the same code in this process) gives the same transitions up to float
rounding (tested). They are not the numbers of :func:`~crowdbench.training.rollout.collect`'s other paths, which
sample group by group from the same generator — hence the ``TrainConfig.worker_acting`` switch, off for checkpoints
saved before it existed, so that they resume bit for bit.
"""

from __future__ import annotations

import pickle
from typing import Any

import numpy as np
import torch
import torch.nn as nn
from tensordict import TensorDict

from crowdbench.policies import fused_infer, packed
from crowdbench.training.rollout import store_step


def supported(actor: nn.Module) -> bool:
    """Worker-side acting covers the packed configurations (``packed`` on, an attention variant): the world
    processes encode with :mod:`crowdbench.policies.fused_infer`."""
    return bool(actor.packed) and packed.supported(actor.encoder) and fused_infer.supported(actor.encoder)


class RolloutPolicy(nn.Module):
    """The stochastic policy and value function of an ``H2INTActor`` / ``H2INTCritic`` pair, for one batch of worlds.

    Holds the actor's and critic's own modules (by reference: no copy in this process; pickling sends a snapshot).
    The recurrent state ``(1, n, H)`` is kept by the caller (:class:`~crowdbench.training.shards.Shard`).
    """

    def __init__(self, actor: nn.Module, critic: nn.Module) -> None:
        super().__init__()
        self.encoder, self.gru, self.mlp = actor.encoder, actor.rnn.rnn, actor.mlp
        self.distribution, self.value = actor.distribution, critic.mlp

    def initial_state(self, n: int) -> np.ndarray:
        return np.zeros((1, n, self.gru.hidden_size), np.float32)

    def reset_state(self, state: np.ndarray, done: np.ndarray) -> np.ndarray:
        """Zero the state of worlds whose episode ended (``done`` ``(n,)`` bool)."""
        state[:, done] = 0.0
        return state

    def act(self, obs: dict[str, np.ndarray], state: np.ndarray, noise: np.ndarray
            ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Actions ``(n, 2)`` (float64, for the worlds) for observations ``obs`` (the ``robot`` / ``humans`` /
        ``mask`` arrays of :class:`~crowdbench.robots.observations.RelativeObservation`), recurrent ``state``
        ``(1, n, H)`` and standard-normal ``noise`` ``(n, 2)``; the transition record (state before acting, actions,
        values, log-probabilities, mean, std) and the next state. Arrays, not tensors: they cross process
        boundaries as plain bytes."""
        with torch.inference_mode():
            robot, humans = torch.from_numpy(obs["robot"]), torch.from_numpy(obs["humans"])
            valid = torch.from_numpy(obs["mask"]) > 0.5
            z = fused_infer.encode(self.encoder, robot, humans, valid)
            out, nxt = self.gru(z.unsqueeze(0), torch.from_numpy(state))
            latent = out.squeeze(0)
            self.distribution.update(self.mlp(latent))
            dist = self.distribution
            actions = dist.mean + dist.std * torch.from_numpy(noise)
            record = {"hidden": state, "actions": actions.numpy(), "values": self.value(latent).numpy(),
                      "logp": dist.log_prob(actions).numpy(), "mean": dist.mean.numpy(), "std": dist.std.numpy()}
        return actions.numpy().astype(np.float64), record, nxt.numpy()

    def snapshot(self) -> bytes:
        """The policy with its current weights, pickled (for a world process)."""
        self.distribution._distribution = None  # the last update's, possibly part of an autograd graph
        return pickle.dumps(self)


def collect_worker_acting(alg: Any, env: Any, obs: TensorDict, steps: int) -> tuple[TensorDict, dict, list[float]]:
    """Fill ``alg.storage`` with ``steps`` transitions per world, the worlds' processes acting (module docstring).
    Returns the observations after the last step, the last step's ``extras`` and every step's mean reward; leaves
    the actor's recurrent state at the worlds' (for ``compute_returns``)."""
    groups = env.groups
    policy = RolloutPolicy(alg.actor, alg.critic)
    env.worlds.call("set_policy", [(policy if env.worlds.conns[k] is None else policy.snapshot(),)
                                   for k in range(len(groups))])
    noise = torch.randn(steps, env.num_envs, 2).numpy()
    current = [obs[sl] for sl in groups]
    for k, sl in enumerate(groups):
        env.act_async(k, noise[0, sl])
    rewards: list[float] = []
    extras: dict = {}
    state: list[np.ndarray] = [np.empty(0)] * len(groups)
    for t in range(steps):
        parts = []
        for k, sl in enumerate(groups):
            o, rew, dones, extras, record, state[k] = env.act_wait(k)
            if t + 1 < steps:
                env.act_async(k, noise[t + 1, sl])
            part = {key: torch.from_numpy(v) for key, v in record.items()}
            part["dist"] = (part.pop("mean"), part.pop("std"))
            parts.append({**part, "obs": current[k], "rewards": rew, "dones": dones, "time_outs": extras["time_outs"]})
            current[k] = o
        rewards.append(store_step(alg, parts))
    alg.actor.rnn.hidden_state = torch.from_numpy(np.concatenate(state, 1))
    return torch.cat(current, 0), extras, rewards
