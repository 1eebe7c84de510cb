"""rsl-rl's PPO with its update run per thread, for shared-trunk recurrent policies.

Mirrors ``rsl_rl.algorithms.PPO`` of **rsl-rl-lib 5.5.1** (the version pinned in ``pyproject.toml``). Overrides, each
for a measured reason:

* :meth:`SharedTrunkPPO.update` — rsl-rl runs a mini-batch's forward pass, losses and ``loss.backward()`` on one
  thread. Here every thread takes its share of the mini-batch's environments (equal encoder work,
  :func:`~crowdbench.training.threads.trajectory_shares`) through the network, the PPO losses and
  ``torch.autograd.grad``; the main thread sums the shares' gradients in share order (deterministic), adapts the
  learning rate from the KL divergence, clips and steps — exactly the steps of ``PPO.update``, whose losses are means
  over the mini-batch and therefore sums of per-share sums over its size. Equal to ``PPO.update`` to float rounding
  for 1 and 2 threads (tested); with 1 thread it is the same code, inline.
* :meth:`SharedTrunkPPO.construct_algorithm` — builds the critic on the actor's trunk
  (:class:`~crowdbench.training.models.SharedTrunkCritic`; the actor is the rsl-rl adapter of the method's plain
  network, :func:`~crowdbench.training.models.rsl_rl_actor`) and uses ``torch.optim.Adam(fused=True)`` (one kernel per
  step: 0.25 against 1.15 ms here; same parameters, same order, same ``state_dict`` layout as rsl-rl's optimiser).

Covers what crowdbench trains — a recurrent shared-trunk actor/critic, a Gaussian policy with state-independent std,
advantages normalised per rollout, one process — and refuses other settings (RND, symmetry, mixed precision,
multi-GPU, per-mini-batch advantage normalisation) with a clear error at construction.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import torch
import torch.nn as nn
from rsl_rl.algorithms import PPO
from rsl_rl.modules.distribution import GaussianDistribution
from torch.distributions import Normal

from crowdbench.policies.nets import RecurrentTrunkActor
from crowdbench.training.models import SharedTrunkCritic, is_rsl_rl_actor, rsl_rl_actor
from crowdbench.training.threads import pool, trajectory_shares


def gaussian_std(dist: GaussianDistribution) -> torch.Tensor:
    """The standard deviation ``(A,)`` of a state-independent rsl-rl Gaussian, as ``GaussianDistribution.update``
    computes it — without building (and sharing between threads) the distribution's own ``Normal``. Reads the
    distribution's parameters (``std_type``, ``std_param`` / ``log_std_param``, ranges: rsl-rl 5.5.1), checked
    against ``dist.std`` by :func:`check_gaussian`."""
    if dist.std_type == "scalar":
        return dist.std_param.clamp(dist.std_range[0], dist.std_range[1])
    return torch.exp(dist.log_std_param.clamp(dist.log_std_range[0], dist.log_std_range[1]))


def check_gaussian(dist: Any) -> None:
    """Raise ``ValueError`` unless ``dist`` is a state-independent rsl-rl Gaussian that :func:`gaussian_std` reads
    correctly (guards against an rsl-rl whose distribution changed shape)."""
    if type(dist) is not GaussianDistribution:
        raise ValueError(f"actor distribution {type(dist).__name__}; valid choices: GaussianDistribution")
    with torch.no_grad():
        dist.update(torch.zeros(1, dist.input_dim))
        if not torch.equal(dist.std[0], gaussian_std(dist)):
            raise ValueError("rsl-rl's GaussianDistribution changed: gaussian_std no longer reproduces its std")


class SharedTrunkPPO(PPO):
    """rsl-rl PPO for a :class:`RecurrentTrunkActor` and its :class:`SharedTrunkCritic` (module docstring)."""

    threads: int = 1
    """Threads the update splits each mini-batch across (set by the trainer)."""

    def update(self) -> dict[str, float]:
        """One PPO update over the storage (``num_learning_epochs`` × ``num_mini_batches`` recurrent mini-batches);
        returns the mean value loss, surrogate loss and entropy, as ``PPO.update`` does."""
        actor, critic, threads = self.actor, self.critic, self.threads
        params = [p for g in self.optimizer.param_groups for p in g["params"] if p.requires_grad]
        totals = {"value": 0.0, "surrogate": 0.0, "entropy": 0.0}
        for batch in self.storage.recurrent_mini_batch_generator(self.num_mini_batches, self.num_learning_epochs):
            masks = batch.masks
            T, n = masks.shape[0], batch.actions.shape[1]
            trajs, envs = trajectory_shares(masks, (actor.work(batch.observations) * masks).sum(0), threads)
            count = float(T * n)
            share = partial(_share, self, params, batch, count)
            results = (list(pool(threads).map(share, trajs, envs)) if len(trajs) > 1
                       else [share(trajs[0], envs[0])])
            if self.desired_kl is not None and self.schedule == "adaptive":
                mean = batch.actions.new_empty((T, n, batch.actions.shape[2]))
                for e, r in zip(envs, results, strict=True):
                    mean[:, e] = r[0]
                with torch.inference_mode():
                    std = gaussian_std(actor.distribution).expand_as(mean)
                    kl_mean = torch.mean(actor.get_kl_divergence(batch.old_distribution_params, (mean, std)))
                    if kl_mean > self.desired_kl * 2.0:
                        self.learning_rate = max(1e-5, self.learning_rate / 1.5)
                    elif self.desired_kl / 2.0 > kl_mean > 0.0:
                        self.learning_rate = min(1e-2, self.learning_rate * 1.5)
                    for group in self.optimizer.param_groups:
                        group["lr"] = self.learning_rate
            for i, p in enumerate(params):
                gs = [r[2][i] for r in results if r[2][i] is not None]
                p.grad = None if not gs else (gs[0] if len(gs) == 1 else torch.stack(gs).sum(0))
            nn.utils.clip_grad_norm_(actor.parameters(), self.max_grad_norm)
            nn.utils.clip_grad_norm_(critic.parameters(), self.max_grad_norm)
            self.optimizer.step()
            for key, idx in (("surrogate", 0), ("value", 1), ("entropy", 2)):
                totals[key] += sum(r[1][idx] for r in results) / count
        obs = self.storage.observations.flatten(0, 1)
        actor.update_normalization(obs)
        critic.update_normalization(obs)
        updates = self.num_learning_epochs * self.num_mini_batches
        self.storage.clear()
        return {k: v / updates for k, v in totals.items()}

    @staticmethod
    def construct_algorithm(obs, env, cfg, device) -> SharedTrunkPPO:
        """rsl-rl's hook (``OnPolicyRunner``): the actor class from ``cfg["actor"]``, the critic on its trunk, the
        rollout storage, and fused Adam."""
        from rsl_rl.storage import RolloutStorage
        from rsl_rl.utils import resolve_class, resolve_obs_groups

        alg_class, alg_cfg = resolve_class(cfg["algorithm"])
        actor_class, actor_cfg = resolve_class(cfg["actor"])
        _, critic_cfg = resolve_class(cfg["critic"])
        cfg["obs_groups"] = resolve_obs_groups(obs, cfg["obs_groups"], ["actor", "critic"])
        alg_cfg.pop("share_cnn_encoders", None)
        for key in ("rnd_cfg", "symmetry_cfg"):
            if alg_cfg.get(key):
                raise ValueError(f"SharedTrunkPPO: {key} is not supported; valid choices: None")
        for key in ("use_mixed_precision", "normalize_advantage_per_mini_batch"):
            if alg_cfg.get(key):
                raise ValueError(f"SharedTrunkPPO: {key}=True is not supported; valid choices: False")
        if not (isinstance(actor_class, type) and issubclass(actor_class, RecurrentTrunkActor)):
            raise ValueError(f"SharedTrunkPPO: actor {actor_class!r}; valid choices: a RecurrentTrunkActor")
        if not is_rsl_rl_actor(actor_class):  # a plain network class: its rsl-rl adapter
            actor_class = rsl_rl_actor(actor_class)
        actor = actor_class(obs, cfg["obs_groups"], "actor", env.num_actions, **actor_cfg).to(device)
        check_gaussian(actor.distribution)
        critic = SharedTrunkCritic(obs, cfg["obs_groups"], "critic", 1, actor=actor, **critic_cfg).to(device)
        storage = RolloutStorage("rl", env.num_envs, cfg["num_steps_per_env"], obs, [env.num_actions], device)
        alg = alg_class(actor, critic, storage, device=device, **alg_cfg, multi_gpu_cfg=cfg["multi_gpu"])
        if alg.is_multi_gpu:
            raise ValueError("SharedTrunkPPO: multi-GPU training is not supported; valid choices: one process")
        alg.optimizer = torch.optim.Adam([p for g in alg.optimizer.param_groups for p in g["params"]],
                                         lr=alg.learning_rate, fused=True)
        return alg


def _share(alg: SharedTrunkPPO, params: list[torch.Tensor], batch: Any, count: float, j: torch.Tensor,
           e: torch.Tensor) -> tuple[torch.Tensor, list[float], tuple[torch.Tensor | None, ...]]:
    """One thread's part of a mini-batch: trajectories ``j`` (the worlds ``e``) through the network and the PPO
    losses (sums over the share, divided by the mini-batch's ``count`` samples), and the loss's gradients. Returns
    the share's policy means ``(T, b, A)``, its (surrogate, value, entropy) sums and the gradients."""
    actor, obs, masks = alg.actor, batch.observations, batch.masks
    with torch.enable_grad():
        sub = {key: obs[key][:, j] for key in actor.obs_keys}
        latent = actor.trunk(sub, masks[:, j], batch.hidden_states[0][:, j])  # (T, b, H)
        mean, values = actor.mlp(latent), actor.value_head()(latent)
        dist = Normal(mean, gaussian_std(actor.distribution))
        logp = dist.log_prob(batch.actions[:, e]).sum(-1)
        ratio = torch.exp(logp - batch.old_actions_log_prob[:, e, 0])
        adv = batch.advantages[:, e, 0]
        surrogate = torch.max(-adv * ratio, -adv * ratio.clamp(1.0 - alg.clip_param, 1.0 + alg.clip_param))
        old_v, returns = batch.values[:, e], batch.returns[:, e]
        if alg.use_clipped_value_loss:
            clipped = old_v + (values - old_v).clamp(-alg.clip_param, alg.clip_param)
            value = torch.max((values - returns).pow(2), (clipped - returns).pow(2))
        else:
            value = (returns - values).pow(2)
        entropy = dist.entropy().sum(-1)
        s, v, h = surrogate.sum(), value.sum(), entropy.sum()
        loss = (s + alg.value_loss_coef * v - alg.entropy_coef * h) / count
        grads = torch.autograd.grad(loss, params, allow_unused=True)
    return mean.detach(), [float(s.detach()), float(v.detach()), float(h.detach())], grads
