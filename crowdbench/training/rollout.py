"""Rollout collection for rsl-rl PPO, pipelined across world groups.

With the worlds in ``K ≥ 2`` worker processes (:class:`~crowdbench.training.vecenv.CrowdVecEnv` ``processes=K``),
the policy acts on one group while the other groups step: group k's step t runs while this process computes the
actions of group k + 1 — on 2 cores the environment and the network overlap instead of taking turns. The transitions
written to rsl-rl's storage are exactly those of ``alg.act`` / ``env.step`` / ``alg.process_env_step`` on the whole
batch (observations, actions, values, log-probabilities, distribution parameters, recurrent states before acting,
rewards with time-out bootstrapping, dones); only the order in which groups are computed differs, so the network sees
smaller batches (float rounding) and a curriculum change takes effect one group later.

With one group it is the plain synchronous loop.
"""

from __future__ import annotations

from typing import Any

import torch
from rsl_rl.storage import RolloutStorage
from tensordict import TensorDict

from crowdbench.training.vecenv import CrowdVecEnv


def collect(alg: Any, env: CrowdVecEnv, obs: TensorDict, steps: int, worker_acting: bool = False
            ) -> tuple[TensorDict, dict, list[float]]:
    """Fill ``alg.storage`` with ``steps`` transitions per world (inside ``torch.inference_mode``).

    ``worker_acting``: the world processes compute the actions (:mod:`crowdbench.training.acting`, where the actor
    supports it). Returns the observations after the last step, the last step's ``extras`` and the mean reward of
    every step.
    """
    if worker_acting:
        from crowdbench.training import acting  # (acting builds on this module)

        if acting.supported(alg.actor):
            return acting.collect_worker_acting(alg, env, obs, steps)
    if len(env.groups) == 1:
        rewards: list[float] = []
        extras: dict = {}
        for _ in range(steps):
            actions = alg.act(obs)
            obs, rew, dones, extras = env.step(actions)
            alg.process_env_step(obs, rew, dones, extras)
            rewards.append(float(rew.mean()))
        return obs, extras, rewards
    return _Pipeline(alg, env).run(obs, steps)


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


class _Pipeline:
    def __init__(self, alg: Any, env: CrowdVecEnv) -> None:
        self.alg, self.env = alg, env
        self.actor, self.critic, self.rnn = alg.actor, alg.critic, alg.actor.rnn
        self.groups = env.groups

    def _act(self, k: int, obs: TensorDict) -> dict[str, Any]:
        """``alg.act`` on group ``k``: the full recurrent state is sliced in and written back."""
        full = self.rnn.hidden_state
        sl = self.groups[k]
        h = full[:, sl].clone()
        self.rnn.hidden_state = h
        actions = self.actor(obs, stochastic_output=True).detach()
        values = self.critic(obs).detach()  # reuses the actor's latent for this observation object
        part = {"obs": obs, "hidden": h, "actions": actions, "values": values,
                "logp": self.actor.get_output_log_prob(actions).detach(),
                "dist": tuple(p.detach() for p in self.actor.output_distribution_params)}
        full[:, sl] = self.rnn.hidden_state
        self.rnn.hidden_state = full
        return part

    def _add(self, parts: list[dict[str, Any]], results: list[tuple]) -> float:
        """``alg.process_env_step`` for one full step assembled from the groups; returns its mean reward."""
        return store_step(self.alg, [{**p, "rewards": r[0], "dones": r[1], "time_outs": r[2]}
                                     for p, r in zip(parts, results, strict=True)])

    def _finish(self, k: int, obs: list[TensorDict], results: list) -> dict:
        o, rew, dones, extras = self.env.step_wait(k)
        obs[k] = o
        results[k] = (rew, dones, extras["time_outs"])
        if dones.any():  # zero the recurrent state of finished episodes before the group acts again
            view = self.rnn.hidden_state[:, self.groups[k]]
            view[:, dones] = 0.0
        return extras

    def run(self, obs_full: TensorDict, steps: int) -> tuple[TensorDict, dict, list[float]]:
        K = len(self.groups)
        if self.rnn.hidden_state is None:
            self.rnn.hidden_state = torch.zeros(1, self.env.num_envs, self.rnn.rnn.hidden_size)
        obs = [obs_full[sl] for sl in self.groups]
        prev: list[dict[str, Any]] = []
        results: list = [None] * K
        rewards: list[float] = []
        extras: dict = {}
        for t in range(steps):
            cur: list[dict[str, Any]] = []
            for k in range(K):
                if t:
                    extras = self._finish(k, obs, results)
                cur.append(self._act(k, obs[k]))
                self.env.step_async(k, cur[k]["actions"])
            if t:
                rewards.append(self._add(prev, results))
            prev = cur
        for k in range(K):
            extras = self._finish(k, obs, results)
        rewards.append(self._add(prev, results))
        return torch.cat(obs, 0), extras, rewards
