"""Rollouts in which the world processes compute the robot's actions themselves — the one rollout path.

Every world process (:class:`~crowdbench.training.shards.Shard`) holds a :class:`RolloutPolicy` — a copy of the
actor and the critic's value head, refreshed from a :class:`PolicySnapshot` (their state dicts) before every
rollout — and the recurrent state of its own worlds; each step it *acts and then steps* its worlds without waiting
for anyone, so on two cores the network and the physics overlap instead of taking turns. The training process only
hands out, per step and group, the Gaussian noise and the curriculum's current ρ, and files the transitions into
rsl-rl's storage (:func:`store_step`: what ``PPO.act`` + ``PPO.process_env_step`` would record).

The numbers do not depend on how the worlds are split: the noise of the whole rollout is drawn at its start from the
training process's torch generator, ``randn(steps, num_envs, A)``, and action = mean + std · noise, so any number of
world processes (``processes=1`` runs the same code in this process) gives the same transitions up to float
rounding (tested).
"""

from __future__ import annotations

import pickle
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
import torch
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict
from torch.distributions import Normal

from crowdbench.policies.nets import RecurrentTrunkActor
from crowdbench.training.models import SharedTrunkCritic, rsl_rl_actor
from crowdbench.training.ppo import gaussian_std


def build_models(actor_class: type[RecurrentTrunkActor], actor_cfg: dict[str, Any], critic_cfg: dict[str, Any],
                 shapes: dict[str, tuple[int, ...]], num_actions: int) -> tuple[RecurrentTrunkActor, SharedTrunkCritic]:
    """A fresh actor (the rsl-rl adapter of the plain network class ``actor_class``) and critic (observation groups
    of per-sample ``shapes``); picklable through ``partial``."""
    obs = TensorDict({k: torch.zeros(1, *s) for k, s in shapes.items()}, batch_size=[1])
    groups = {"actor": list(actor_class.obs_keys), "critic": list(actor_class.obs_keys)}
    actor = rsl_rl_actor(actor_class)(obs, groups, "actor", num_actions, **actor_cfg)
    return actor, SharedTrunkCritic(obs, groups, "critic", 1, actor=actor, **critic_cfg)


@dataclass
class PolicySnapshot:
    """The policy as it is now, for a world process: how to build the networks and their weights."""

    build: Callable[[], tuple[RecurrentTrunkActor, SharedTrunkCritic]]
    """Module-level function or ``functools.partial`` of one (pickled by reference, also under ``spawn``)."""
    actor: dict[str, torch.Tensor]
    critic: dict[str, torch.Tensor]

    @classmethod
    def of(cls, alg: Any, build: Callable[[], tuple[RecurrentTrunkActor, SharedTrunkCritic]]) -> PolicySnapshot:
        return cls(build, alg.actor.state_dict(), alg.critic.state_dict())


class RolloutPolicy:
    """The stochastic policy and value function, for one batch of worlds (the recurrent state ``(1, n, H)`` is
    kept by the caller)."""

    def __init__(self, snapshot: PolicySnapshot) -> None:
        # fork_rng: building initialises parameters, which must not draw from the trainer's stream (in-process shard)
        with torch.random.fork_rng(), torch.inference_mode(False), torch.no_grad():
            self.actor, self.critic = snapshot.build()
        self.actor.eval()
        self.load(snapshot)

    def load(self, snapshot: PolicySnapshot) -> None:
        """Take the snapshot's weights."""
        with torch.inference_mode(False), torch.no_grad():
            self.actor.load_state_dict(snapshot.actor)
            self.critic.load_state_dict(snapshot.critic)
            self.std = gaussian_std(self.actor.distribution).detach().clone()

    def initial_state(self, n: int) -> np.ndarray:
        return np.zeros((1, n, self.actor.state_size), np.float32)

    def act(self, obs: dict[str, np.ndarray], state: np.ndarray, noise: np.ndarray
            ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Actions ``(n, A)`` (float64, for the worlds) for observations ``obs`` (arrays ``(n, ...)``), recurrent
        ``state`` ``(1, n, H)`` and standard-normal ``noise`` ``(n, A)``; the transition record (state before
        acting, actions, values, log-probabilities, mean, std) and the next state. Arrays, not tensors: they cross
        process boundaries as plain bytes."""
        actor = self.actor
        with torch.inference_mode():
            z = actor.encode({k: torch.from_numpy(obs[k]) for k in actor.obs_keys})
            latent, nxt = actor.step(z, torch.from_numpy(state))
            mean = actor.mlp(latent)
            std = self.std.expand_as(mean)
            actions = mean + std * torch.from_numpy(noise)
            record = {"hidden": state, "actions": actions.numpy(), "values": actor.value_head()(latent).numpy(),
                      "logp": Normal(mean, std).log_prob(actions).sum(-1).numpy(), "mean": mean.numpy(),
                      "std": std.numpy()}
        return actions.numpy().astype(np.float64), record, nxt.numpy()


def snapshot_builder(alg: Any, cfg: dict[str, Any], obs: TensorDict, num_actions: int
                     ) -> Callable[[], tuple[RecurrentTrunkActor, SharedTrunkCritic]]:
    """The picklable network builder of a trainer's rsl-rl config (``cfg["actor"]``, ``cfg["critic"]``)."""
    actor_cfg = {k: v for k, v in cfg["actor"].items() if k != "class_name"}
    critic_cfg = {k: v for k, v in cfg["critic"].items() if k != "class_name"}
    net_class = type(alg.actor).net_class  # the plain network class: the adapter class is not picklable
    shapes = {k: tuple(obs[k].shape[1:]) for k in net_class.obs_keys}
    return partial(build_models, net_class, actor_cfg, critic_cfg, shapes, num_actions)


def store_step(alg: Any, parts: list[dict[str, Any]]) -> float:
    """rsl-rl's ``act`` + ``process_env_step`` record of one step of every world, assembled from the groups'
    ``parts`` in world order (each: ``obs``, ``hidden`` state before acting, ``actions``, ``values``, ``logp``,
    ``dist`` = (mean, std), ``rewards``, ``dones``, ``time_outs``); returns the step's mean reward."""
    cat = torch.cat
    t = RolloutStorage.Transition()
    t.observations = cat([p["obs"] for p in parts], 0)
    t.actions = cat([p["actions"] for p in parts])
    t.values = cat([p["values"] for p in parts])
    t.actions_log_prob = cat([p["logp"] for p in parts])
    t.distribution_params = tuple(cat(ps) for ps in zip(*(p["dist"] for p in parts), strict=True))
    h = cat([p["hidden"] for p in parts], 1)
    t.hidden_states = (h, h)  # the critic's state is the actor's (shared trunk)
    rewards = cat([p["rewards"] for p in parts])
    t.rewards = rewards.clone()
    t.dones = cat([p["dones"] for p in parts])
    time_outs = cat([p["time_outs"] for p in parts])
    t.rewards += alg.gamma * torch.squeeze(t.values * time_outs.unsqueeze(1), 1)  # bootstrapping on time-outs
    alg.storage.add_transition(t)
    return float(rewards.mean())


def collect(alg: Any, env: Any, obs: TensorDict, steps: int, snapshot: PolicySnapshot
            ) -> tuple[TensorDict, dict, list[float]]:
    """Fill ``alg.storage`` with ``steps`` transitions per world, the worlds' processes acting with ``snapshot``
    (module docstring). Returns the observations after the last step, the last step's ``extras`` and every step's
    mean reward; leaves the actor's recurrent state at the worlds' (for ``compute_returns``)."""
    groups = env.groups
    blob = pickle.dumps(snapshot)  # plain bytes: torch's multiprocessing reducers would move tensors to shared memory
    env.worlds.call("set_policy", [(snapshot if env.worlds.conns[k] is None else blob,) for k in range(len(groups))])
    noise = torch.randn(steps, env.num_envs, env.num_actions).numpy()
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
