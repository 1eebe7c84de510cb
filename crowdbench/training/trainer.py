"""``crowdbench train METHOD``: a PPO method (:mod:`crowdbench.training.methods`) trained with rsl-rl on the
latent-responsive crowd — responsiveness annealing, progress display, TensorBoard logs, atomic checkpoints and exact
resume.

One iteration: the world processes act and step (:func:`~crowdbench.training.rollout.collect`), rsl-rl computes the
returns, :class:`~crowdbench.training.ppo.SharedTrunkPPO` updates per thread.

Exact resume: every ``checkpoint_every`` iterations all worlds start fresh episodes and the GRU states are zeroed —
in an uninterrupted run as in a resumed one — and the checkpoint stores the networks, the optimiser (with the
adaptive learning rate), the curriculum, the episode-seed streams and torch's RNG state at that point. Resuming
therefore continues bit for bit as if the run had not stopped (tested).
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
import time
from typing import Any

import numpy as np
import torch
from rsl_rl.runners import OnPolicyRunner

from crowdbench import __version__, checkpoints
from crowdbench.io import write_text
from crowdbench.training.config import NOISE_FIELDS, RESUMABLE, TrainConfig
from crowdbench.training.curriculum import Curriculum
from crowdbench.training.malloc import keep_heap
from crowdbench.training.methods import PPO_METHODS, PPOMethod
from crowdbench.training.models import SharedTrunkCritic, rsl_rl_actor
from crowdbench.training.plots import plot_curve
from crowdbench.training.ppo import SharedTrunkPPO, gaussian_std
from crowdbench.training.rollout import PolicySnapshot, collect, snapshot_builder
from crowdbench.training.vecenv import CrowdVecEnv
from crowdbench.worlds.digest import crowd_digest


def rsl_cfg(cfg: TrainConfig, method: PPOMethod) -> dict[str, Any]:
    """rsl-rl's runner configuration of a run."""
    groups = [method.actor_class.obs_keys[0]]
    return {
        "num_steps_per_env": cfg.steps_per_env, "save_interval": 10**9,
        "obs_groups": {"actor": groups, "critic": groups},
        "algorithm": {"class_name": SharedTrunkPPO, "num_learning_epochs": cfg.epochs,
                      "num_mini_batches": cfg.mini_batches, "learning_rate": cfg.learning_rate,
                      "entropy_coef": cfg.entropy_coef, "schedule": cfg.schedule, "desired_kl": cfg.desired_kl,
                      "gamma": cfg.gamma, "lam": cfg.lam, "max_grad_norm": cfg.max_grad_norm,
                      "value_loss_coef": cfg.value_loss_coef, "clip_param": cfg.clip},
        "actor": {"class_name": rsl_rl_actor(method.actor_class), **method.actor_cfg(cfg.model)},
        "critic": {"class_name": SharedTrunkCritic, **method.critic_cfg(cfg.model)},
    }


class Trainer:
    """One training run in ``out`` (checkpoints, TensorBoard events, ``history.json``, ``curve.png``)."""

    def __init__(self, cfg: TrainConfig, out: str, quiet: bool = False) -> None:
        torch.set_num_threads(1)
        keep_heap()  # before the world processes fork (crowdbench.training.malloc)
        self.cfg, self.out, self.quiet = cfg, out, quiet
        self.method: PPOMethod = PPO_METHODS.get(cfg.method)()
        os.makedirs(out, exist_ok=True)
        torch.manual_seed(cfg.seed)
        # without annealing the crowd is at the final difficulty from the start (the paper's "abrupt, fixed" baseline)
        curriculum = Curriculum(rho_init=cfg.rho_init if cfg.anneal else cfg.rho_min, rho_min=cfg.rho_min,
                                delta=cfg.rho_delta, eta=cfg.eta, window=cfg.window, cooldown=cfg.window,
                                enabled=cfg.anneal)
        self.env = CrowdVecEnv(cfg.num_envs, seed=cfg.seed, curriculum=curriculum, humans_range=cfg.humans_range,
                               reward_scale=cfg.reward_scale, processes=cfg.env_processes,
                               observation=self.method.observation_name(cfg.model),
                               observation_kwargs=self.method.observation_kwargs(cfg.model))
        rcfg = rsl_cfg(cfg, self.method)
        self.runner = OnPolicyRunner(self.env, rcfg, log_dir=None)
        self.alg: SharedTrunkPPO = self.runner.alg
        self.alg.threads = cfg.threads
        self.build = snapshot_builder(self.alg, rcfg, self.env.get_observations(), self.env.num_actions)
        self.iteration = 0
        self.env_steps = 0
        self.elapsed = 0.0
        self.history: dict[str, list] = {k: [] for k in ("iteration", "env_steps", "time", "rho", "train_success",
                                                         "train_collision", "mean_reward", "steps_per_s",
                                                         "action_std")}
        self.evals: list[dict[str, Any]] = []
        self.writer = None

    # ------------------------------------------------------------------ checkpoints
    def checkpoint(self) -> dict[str, Any]:
        return {
            "format": checkpoints.FORMAT, "method": self.cfg.method, "crowdbench_version": __version__,
            "crowd": crowd_digest(), "model": self.cfg.to_dict()["model"], "n_max": self.env.config.max_humans_observed,
            "seed": self.cfg.seed, "train_config": self.cfg.to_dict(),
            "iteration": self.iteration, "env_steps": self.env_steps, "elapsed_s": self.elapsed,
            "actor": self.alg.actor.state_dict(), "critic": self.alg.critic.state_dict(),
            "optimizer": self.alg.optimizer.state_dict(), "learning_rate": float(self.alg.learning_rate),
            "env": self.env.state_dict(), "torch_rng": torch.get_rng_state(),
            "history": self.history, "evals": self.evals,
        }

    def save(self, name: str = "last.pt") -> str:
        return checkpoints.save(self.checkpoint(), os.path.join(self.out, name))

    def load(self, path: str) -> None:
        """Continue the run saved in ``path`` (same configuration apart from :data:`RESUMABLE` fields)."""
        ckpt = load_resumable(path)
        saved = TrainConfig.from_dict(ckpt["train_config"])
        mine = {k: v for k, v in self.cfg.to_dict().items() if k not in RESUMABLE}
        theirs = {k: v for k, v in saved.to_dict().items() if k not in RESUMABLE}
        if mine != theirs:
            diff = sorted(k for k in mine if mine[k] != theirs.get(k))
            raise ValueError(f"--resume: the checkpoint's configuration differs in {diff}; only {', '.join(RESUMABLE)} "
                             "may change when resuming")
        self.alg.actor.load_state_dict(ckpt["actor"])
        self.alg.critic.load_state_dict(ckpt["critic"])
        self.alg.optimizer.load_state_dict(ckpt["optimizer"])
        self.alg.learning_rate = ckpt["learning_rate"]
        for group in self.alg.optimizer.param_groups:
            group["lr"] = ckpt["learning_rate"]
        self.env.load_state_dict(ckpt["env"])
        torch.set_rng_state(ckpt["torch_rng"])
        self.iteration, self.env_steps, self.elapsed = ckpt["iteration"], ckpt["env_steps"], ckpt["elapsed_s"]
        self.history, self.evals = ckpt["history"], ckpt["evals"]
        self.history.setdefault("action_std", [None] * len(self.history["iteration"]))  # runs saved before it
        self._restart_episodes()

    def warm_start(self, path: str) -> None:
        """Start this new run from the network weights of the run saved in ``path`` (``--init``): actor and critic
        (observation normaliser included) are copied; the policy noise (:data:`NOISE_FIELDS`), optimiser, learning
        rate, curriculum, counters and history are this run's own. The architecture must match; the provenance goes
        into ``cfg.init``. Fine-tuning with another schedule or a smaller fixed std, say, is a new run this way,
        with its own curve, rather than a resume that changes its configuration half-way."""
        if self.iteration:
            raise ValueError("--init: only a new run starts from another run's weights")
        ckpt = load_resumable(path, "--init")
        theirs = TrainConfig.from_dict(ckpt["train_config"])
        if theirs.method != self.cfg.method:
            raise ValueError(f"--init: {path!r} is a {theirs.method} run, not {self.cfg.method}")
        mine_m, theirs_m = self.cfg.to_dict()["model"], theirs.to_dict()["model"]
        diff = sorted(k for k in mine_m if k not in NOISE_FIELDS and mine_m[k] != theirs_m.get(k))
        if diff:
            raise ValueError(f"--init: the checkpoint's architecture differs in {diff}; only {', '.join(NOISE_FIELDS)} "
                             "may differ (name its --variant/--model fields)")
        actor = dict(ckpt["actor"])
        for key, value in self.alg.actor.state_dict().items():
            if key.startswith("distribution."):  # the noise is the new run's (e.g. a smaller fixed std)
                actor[key] = value
        self.alg.actor.load_state_dict(actor)
        self.alg.critic.load_state_dict(ckpt["critic"])
        self.cfg = dataclasses.replace(self.cfg, init={
            "path": os.path.abspath(path), "sha256": checkpoints.file_sha256(path), "method": theirs.method,
            "seed": theirs.seed,
            "iteration": int(ckpt["iteration"]), "env_steps": int(ckpt["env_steps"]),
            "total_env_steps": checkpoints.training_budget(ckpt)["env_steps"]})

    def _restart_episodes(self) -> None:
        """Fresh episodes everywhere and zeroed GRU states (zeroed in place, not set to None: rsl-rl's storage
        skips a None state and would keep the previous iteration's step-0 state for the update)."""
        self.env.reset_all()
        with torch.inference_mode():
            self.alg.actor.reset(torch.ones(self.cfg.num_envs, dtype=torch.long))

    # ------------------------------------------------------------------ evaluation
    def evaluate(self, episodes: int, responsiveness: float = 0.5, num_humans: int = 20) -> dict[str, float]:
        """Quick deterministic evaluation of the current policy (circle crossing, fixed seeds)."""
        from crowdbench.evaluation import run_episodes, summarize

        with torch.random.fork_rng():  # building a network must not shift the training's random stream
            actor, _ = self.build()
        actor.load_state_dict(self.alg.actor.state_dict())
        policy = self.method.policy(self.env.config, actor)
        eps = run_episodes(policy, episodes, seed=10**6, num_worlds=min(episodes, 100), num_humans=num_humans,
                           human_model="responsive_orca", human_model_kwargs={"responsiveness": responsiveness})
        return summarize(eps)

    # ------------------------------------------------------------------ loop
    def _log(self, key: str, value: float) -> None:
        if self.writer is not None:
            self.writer.add_scalar(key, value, self.iteration)

    def train(self, stop_at: int | None = None) -> None:
        """Train until ``cfg.iterations`` (or iteration ``stop_at``), the wall-clock budget or ``until_success``."""
        from torch.utils.tensorboard import SummaryWriter

        cfg, alg, env = self.cfg, self.alg, self.env
        last = cfg.iterations if stop_at is None else min(stop_at, cfg.iterations)
        self.writer = SummaryWriter(os.path.join(self.out, "tb"), flush_secs=30)
        obs = env.get_observations()
        alg.train_mode()
        start_elapsed, t_start = self.elapsed, time.time()
        while self.iteration < last:
            t0 = time.time()
            with torch.inference_mode():
                obs, extras, rewards = collect(alg, env, obs, cfg.steps_per_env, PolicySnapshot.of(alg, self.build))
                alg.compute_returns(obs)
            t1 = time.time()
            losses = alg.update()
            t2 = time.time()
            self.iteration += 1
            n = cfg.num_envs * cfg.steps_per_env
            self.env_steps += n
            self.elapsed = start_elapsed + (time.time() - t_start)
            log = extras["log"]
            row = {"iteration": self.iteration, "env_steps": self.env_steps, "time": self.elapsed,
                   "rho": env.curriculum.rho, "train_success": log["Crowd/success_rate"],
                   "train_collision": log["Crowd/collision_rate"], "mean_reward": float(np.mean(rewards)),
                   "steps_per_s": n / (t2 - t0), "action_std": float(gaussian_std(alg.actor.distribution).mean())}
            for k, v in row.items():
                self.history[k].append(v)
            for k, v in log.items():
                self._log(k, v)
            for k, v in losses.items():
                self._log(f"Loss/{k}", v)
            self._log("Perf/steps_per_s", row["steps_per_s"])
            self._log("Perf/collect_s", t1 - t0)
            self._log("Perf/update_s", t2 - t1)
            self._log("Train/mean_step_reward", row["mean_reward"])
            if cfg.eval_every and self.iteration % cfg.eval_every == 0:
                s = self.evaluate(cfg.eval_episodes)
                self.evals.append({"iteration": self.iteration, "env_steps": self.env_steps, "time": self.elapsed,
                                   **s})
                for k in ("success_rate", "collision_rate", "timeout_rate"):
                    self._log(f"Eval/{k}", s[k])
            self._progress(row)
            reached = bool(cfg.until_success and self.evals and self.evals[-1]["iteration"] == self.iteration
                           and self.evals[-1]["success_rate"] >= cfg.until_success)
            done = (self.iteration >= last or (cfg.minutes and self.elapsed >= cfg.minutes * 60) or reached)
            if self.iteration % cfg.checkpoint_every == 0 or done:
                self.save("last.pt")  # before the restart: a resumed run replays the same restart from here
                self.write_artifacts()
                self._restart_episodes()
                obs = env.get_observations()
            if done:
                break
        self.writer.close()
        if not self.quiet:
            print()

    def close(self) -> None:
        """Stop the environment's worker processes."""
        self.env.close()

    def _progress(self, row: dict[str, Any]) -> None:
        if self.quiet:
            return
        cfg = self.cfg
        rate = self.env_steps / max(self.elapsed, 1e-9)
        left_its = cfg.iterations - self.iteration
        eta = left_its * cfg.num_envs * cfg.steps_per_env / max(rate, 1e-9)
        if cfg.minutes:
            eta = min(eta, max(cfg.minutes * 60 - self.elapsed, 0))
        ev = f" | eval {self.evals[-1]['success_rate']:.2f}" if self.evals else ""
        line = (f"it {self.iteration:4d}/{cfg.iterations} | success {row['train_success']:.2f} | ρ {row['rho']:.1f}"
                f"{ev} | {row['steps_per_s']:6.0f} steps/s | {self.env_steps / 1e6:5.2f} M steps | "
                f"elapsed {self.elapsed / 60:5.1f} min | ETA {eta / 60:5.1f} min")
        end = "\r" if sys.stdout.isatty() else "\n"
        print(line.ljust(120), end=end, flush=True)

    def write_artifacts(self) -> None:
        write_text(os.path.join(self.out, "history.json"),
                   json.dumps({"config": self.cfg.to_dict(), "history": self.history, "evals": self.evals}) + "\n")
        plot_curve(self.history, self.evals, os.path.join(self.out, "curve.png"),
                   title=f"{self.method.label(self.cfg.model)} (seed {self.cfg.seed})")


def load_resumable(path: str, option: str = "--resume") -> dict[str, Any]:
    """A checkpoint that today's training path can continue (``--resume``: a run's resumable state, not a shipped
    weights-only file) or start from (``--init``: any PPO checkpoint with its training configuration); one clear
    error, naming ``option``, otherwise."""
    ckpt = checkpoints.load(path)
    if option == "--resume" and "shipped" in ckpt:
        checkpoints.require_resumable(ckpt, path, "optimizer", option)
    if "train_config" not in ckpt:
        raise ValueError(f"{option}: {path!r} holds a policy's weights but no training state; it cannot be resumed "
                         f"(it evaluates: crowdbench evaluate {ckpt.get('method')} --checkpoint PATH). Start a new "
                         "run.")
    if option == "--resume":
        checkpoints.require_resumable(ckpt, path, "optimizer", option)
    return ckpt


def resume_config(path: str, **changes: Any) -> TrainConfig:
    """The configuration of the run saved in ``path`` with some :data:`RESUMABLE` fields changed."""
    bad = sorted(set(changes) - set(RESUMABLE))
    if bad:
        raise ValueError(f"--resume: {bad} cannot change; valid choices: {', '.join(RESUMABLE)}")
    cfg = TrainConfig.from_dict(load_resumable(path)["train_config"])
    return dataclasses.replace(cfg, **changes)


def check_start(resume: str | None, init: str | None) -> None:
    """One clear error for a run asked both to resume and to start from other weights."""
    if resume and init:
        raise ValueError("--init, --resume: a resumed run already has its weights; valid choices: one of them")


def train(cfg: TrainConfig, out: str, resume: str | None = None, quiet: bool = False,
          init: str | None = None) -> Trainer:
    """Train (or resume from ``resume``: a run folder or checkpoint; or start a new run from the weights of
    ``init``, :meth:`Trainer.warm_start`) and return the trainer; ``out/last.pt`` holds the final checkpoint."""
    check_start(resume, init)
    trainer = Trainer(cfg, out, quiet=quiet)
    try:
        if resume:
            trainer.load(checkpoints.run_checkpoint(resume))
        elif init:
            trainer.warm_start(checkpoints.run_checkpoint(init))
        trainer.train()
    finally:
        trainer.close()
    return trainer


__all__ = ["TrainConfig", "Trainer", "check_start", "resume_config", "rsl_cfg", "train"]
