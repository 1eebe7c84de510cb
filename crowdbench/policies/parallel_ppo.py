"""rsl-rl's PPO update with each mini-batch's forward pass, losses and backward pass run per thread.

rsl-rl's ``PPO.update`` runs the network, the PPO losses and ``loss.backward()`` on one thread; splitting only the
encoder across threads (:meth:`H2INTActor.packed_encode <crowdbench.policies.h2int_net.H2INTActor.packed_encode>`)
leaves the GRU, the heads, the losses and the autograd plumbing on one core, twice per mini-batch. Here every thread
takes its share of the mini-batch's environments (equal token counts,
:func:`~crowdbench.policies.parallel.trajectory_shares`) through the network, the PPO losses and
``torch.autograd.grad`` in one go; the main thread sums the shares' gradients (in share order: deterministic), adapts
the learning rate from the KL divergence, clips and steps — exactly the steps of ``rsl_rl.algorithms.PPO.update``
(rsl-rl 5.5), whose losses are means over the mini-batch and therefore sums of per-share sums over its size. Equal to
rsl-rl's update to float rounding (tested). Measured in training: the threads hold 92–94 % of the update's time.

Covers what crowdbench trains: recurrent shared-trunk actor/critic, Gaussian policy with a state-independent std,
no RND, no symmetry, no mixed precision, one process, advantages normalised per rollout. :func:`applies` says when.
"""

from __future__ import annotations

from functools import partial
from typing import Any

import torch
import torch.nn as nn
from rsl_rl.modules.distribution import GaussianDistribution
from torch.distributions import Normal

from crowdbench.policies.parallel import pool, trajectory_shares


def applies(alg: Any) -> bool:
    """Whether :func:`update` reproduces ``PPO.update`` for this algorithm object."""
    actor = alg.actor
    dist = getattr(actor, "distribution", None)
    return (getattr(actor, "threads", 1) > 1 and getattr(actor, "_critic_head", None) is not None
            and type(dist) is GaussianDistribution and not alg.rnd and not alg.symmetry
            and not alg.use_mixed_precision and not alg.is_multi_gpu and not alg.normalize_advantage_per_mini_batch)


def _std(dist: GaussianDistribution) -> torch.Tensor:
    """The distribution's standard deviation ``(A,)``, as ``GaussianDistribution.update`` computes it."""
    if dist.std_type == "scalar":
        return dist.std_param.clamp(dist.std_range[0], dist.std_range[1])
    return torch.exp(dist.log_std_param.clamp(dist.log_std_range[0], dist.log_std_range[1]))


def update(alg: Any) -> dict[str, float]:
    """One PPO update over ``alg.storage`` (``num_learning_epochs`` × ``num_mini_batches`` recurrent mini-batches);
    returns the mean value loss, surrogate loss and entropy, as ``PPO.update`` does."""
    actor, critic = alg.actor, alg.critic
    threads = actor.threads
    params = [p for g in alg.optimizer.param_groups for p in g["params"] if p.requires_grad]
    totals = {"value": 0.0, "surrogate": 0.0, "entropy": 0.0}
    for batch in alg.storage.recurrent_mini_batch_generator(alg.num_mini_batches, alg.num_learning_epochs):
        masks, obs = batch.masks, batch.observations
        T, n = masks.shape[0], batch.actions.shape[1]
        tokens = ((obs["mask"] > 0.5).sum(-1) + 1) * masks  # (T, J): the encoder's work
        trajs, envs = trajectory_shares(masks, tokens.sum(0), threads)
        count = float(T * n)
        results = list(pool(threads).map(partial(_share, alg, params, batch, count), trajs, envs))
        if alg.desired_kl is not None and alg.schedule == "adaptive":
            mean = batch.actions.new_empty((T, n, batch.actions.shape[2]))
            for e, r in zip(envs, results, strict=True):
                mean[:, e] = r[0]
            with torch.inference_mode():
                std = _std(actor.distribution).expand_as(mean)
                kl_mean = torch.mean(actor.get_kl_divergence(batch.old_distribution_params, (mean, std)))
                if kl_mean > alg.desired_kl * 2.0:
                    alg.learning_rate = max(1e-5, alg.learning_rate / 1.5)
                elif alg.desired_kl / 2.0 > kl_mean > 0.0:
                    alg.learning_rate = min(1e-2, alg.learning_rate * 1.5)
                for group in alg.optimizer.param_groups:
                    group["lr"] = alg.learning_rate
        for i, p in enumerate(params):
            gs = [r[2][i] for r in results if r[2][i] is not None]
            p.grad = None if not gs else (gs[0] if len(gs) == 1 else torch.stack(gs).sum(0))
        nn.utils.clip_grad_norm_(actor.parameters(), alg.max_grad_norm)
        nn.utils.clip_grad_norm_(critic.parameters(), alg.max_grad_norm)
        alg.optimizer.step()
        for key, idx in (("surrogate", 0), ("value", 1), ("entropy", 2)):
            totals[key] += sum(r[1][idx] for r in results) / count
    obs = alg.storage.observations.flatten(0, 1)
    actor.update_normalization(obs)
    critic.update_normalization(obs)
    updates = alg.num_learning_epochs * alg.num_mini_batches
    alg.storage.clear()
    return {k: v / updates for k, v in totals.items()}


def _share(alg: Any, params: list[torch.Tensor], batch: Any, count: float, j: torch.Tensor, e: torch.Tensor
           ) -> tuple[torch.Tensor, list[float], tuple[torch.Tensor | None, ...]]:
    """One thread's part of a mini-batch: trajectories ``j`` (the worlds ``e``) through the network and the PPO
    losses (sums over the share, divided by the mini-batch's ``count`` samples), and the loss's gradients. Returns
    the share's policy means ``(T, b, A)``, its (surrogate, value, entropy) sums and the gradients."""
    actor, obs, masks = alg.actor, batch.observations, batch.masks
    with torch.enable_grad():
        sub = {key: obs[key][:, j] for key in ("robot", "humans", "mask")}
        latent = actor.trunk(sub, masks[:, j], batch.hidden_states[0][:, j], threads=1)  # (T, b, H)
        mean, values = actor.mlp(latent), actor._critic_head(latent)
        dist = Normal(mean, _std(actor.distribution))
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
