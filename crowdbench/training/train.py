"""``crowdbench train h2int``: H²INT trained with rsl-rl PPO on the latent-responsive crowd, with the paper's
responsiveness annealing, progress display, TensorBoard logs, atomic checkpoints and exact resume.

Exact resume: every ``checkpoint_every`` iterations all worlds start fresh episodes and the GRU states are zeroed —
in an uninterrupted run as in a resumed one — and the checkpoint stores the networks, the optimiser (with the
adaptive learning rate), the curriculum, the episode-seed generator and torch's RNG state at that point. Resuming
therefore continues bit-for-bit as if the run had not stopped (tested).
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch
from rsl_rl.runners import OnPolicyRunner

from crowdbench.io import atomic_path, write_text
from crowdbench.policies.h2int import FORMAT, H2INTPolicy, build_actor, load_checkpoint
from crowdbench.policies.h2int_net import VARIANTS, H2INTActor, H2INTCritic, SharedTrunkPPO
from crowdbench.training.malloc import keep_heap
from crowdbench.training.rollout import collect
from crowdbench.training.vecenv import CrowdVecEnv, Curriculum


@dataclass
class TrainConfig:
    """Everything a training run depends on (saved in every checkpoint)."""

    variant: str = "h2int"
    """``h2int``, ``flat``, ``meanpool`` or ``standard``."""
    seed: int = 0
    num_envs: int = 256
    """Worlds stepped together."""
    steps_per_env: int = 32
    """Rollout length per iteration (transitions per iteration = num_envs × steps_per_env)."""
    iterations: int = 600
    """Upper bound on PPO iterations."""
    minutes: float = 0.0
    """Wall-clock budget in minutes (0 = none); training stops after the iteration that exceeds it."""
    humans_range: tuple[int, int] = (10, 30)
    """Pedestrians per training episode, drawn uniformly (covers the 10–30 of the paper's Table II)."""
    anneal: bool = True
    """Responsiveness annealing (False: ρ fixed at ``rho_min`` from the start, the paper's no-annealing baseline)."""
    rho_init: float = 0.8
    rho_min: float = 0.0
    rho_delta: float = 0.1
    eta: float = 0.9
    """Success rate over the curriculum window needed to lower ρ."""
    window: int = 200
    """Episodes in the curriculum's success window (and its cooldown)."""
    d_model: int = 32
    heads: int = 4
    ffn: int = 64
    gru_hidden: int = 64
    head_dims: tuple[int, ...] = (64,)
    action_std: float = 0.3
    """Fixed standard deviation of the Gaussian policy [m/s]."""
    learning_rate: float = 3e-4
    epochs: int = 4
    mini_batches: int = 4
    gamma: float = 0.99
    lam: float = 0.95
    desired_kl: float = 0.01
    reward_scale: float = 0.1
    """Training rewards are multiplied by this (same optimal policy): it keeps the shared trunk's value-loss
    gradients (returns of ±20 otherwise) from drowning the policy gradient under joint gradient clipping."""
    value_loss_coef: float = 0.5
    threads: int = 2
    """CPU threads the network's batches are split across, forward and backward, in rollouts and updates
    (:mod:`crowdbench.policies.parallel`). Deterministic for a given count; other counts differ in the last bits of
    the gradient sums."""
    env_processes: int = 2
    """1: the worlds step in the training process. k ≥ 2: k worker processes step k groups of worlds and, with
    ``worker_acting``, compute their actions (:mod:`crowdbench.training.acting`); without it, this process computes
    one group's actions while the others step (:mod:`crowdbench.training.rollout`). The same transitions either way,
    computed in another order (the network's batches differ, so results differ from ``1`` in the last bits)."""
    packed: bool = True
    """Encode packed tokens (:mod:`crowdbench.policies.packed`: valid tokens only, ragged attention) rather than
    padded groups; the same function to float rounding, ≈ 2× faster forward + backward. Checkpoints saved before this
    option resume with ``False``, bit for bit."""
    parallel_update: bool = True
    """PPO updates run each mini-batch's forward pass, losses and backward pass per thread
    (:mod:`crowdbench.policies.parallel_ppo`; needs ``threads`` ≥ 2), not only the network; the same update to float
    rounding. Checkpoints saved before this option resume with ``False``."""
    fused_adam: bool = True
    """Adam as one fused kernel per step (``torch.optim.Adam(fused=True)``: 0.25 against 1.15 ms per step here); the
    same update to float rounding. Checkpoints saved before this option resume with ``False``."""
    worker_acting: bool = True
    """The world processes compute the actions, each for its own worlds, from a copy of the policy sent before
    every rollout (:mod:`crowdbench.training.acting`) — the same numbers for any ``env_processes``; ``False``: this
    process computes them between the worlds' steps. Checkpoints saved before this option resume with ``False``."""
    checkpoint_every: int = 20
    eval_every: int = 20
    """Iterations between quick deterministic evaluations (circle crossing, 20 pedestrians, ρ = 0.5)."""
    eval_episodes: int = 100
    until_success: float = 0.0
    """Stop after the first quick evaluation whose success rate reaches this (0 = never; needs ``eval_every``)."""
    extra: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrainConfig:
        """The configuration saved in a checkpoint (older checkpoints' ``update_threads`` becomes ``threads``; their
        missing ``packed``, ``worker_acting``, ``fused_adam`` and ``parallel_update`` mean ``False``)."""
        d = dict(d)
        if "update_threads" in d:
            d["threads"] = d.pop("update_threads")
        d.setdefault("packed", False)  # saved before packed encoding existed: keep their exact resume
        d.setdefault("worker_acting", False)  # likewise
        d.setdefault("fused_adam", False)  # likewise
        d.setdefault("parallel_update", False)  # likewise
        for key in ("humans_range", "head_dims"):
            if key in d:
                d[key] = tuple(d[key])
        return cls(**d)

    def __post_init__(self) -> None:
        if self.variant not in VARIANTS:
            raise ValueError(f"variant={self.variant!r}; valid choices: {', '.join(VARIANTS)}")
        for name in ("num_envs", "steps_per_env", "epochs", "mini_batches", "threads", "env_processes"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name}={getattr(self, name)}; valid choices: an integer ≥ 1")
        if not 0.0 <= self.until_success <= 1.0:
            raise ValueError(f"until_success={self.until_success}; valid choices: a success rate in [0, 1] (0 = off)")
        if self.until_success and not self.eval_every:
            raise ValueError("until_success needs quick evaluations; valid choices: eval_every ≥ 1")
        if self.env_processes > self.num_envs:
            raise ValueError(f"env_processes={self.env_processes}; valid choices: 1 … num_envs ({self.num_envs})")
        if self.num_envs % self.mini_batches:
            raise ValueError(f"num_envs={self.num_envs} must be divisible by mini_batches={self.mini_batches} "
                             "(rsl-rl silently drops the remainder from recurrent updates)")

    def model_cfg(self) -> dict[str, Any]:
        return {"variant": self.variant, "d_model": self.d_model, "heads": self.heads, "ffn": self.ffn,
                "gru_hidden": self.gru_hidden, "hidden_dims": list(self.head_dims),
                "distribution_cfg": {"class_name": "GaussianDistribution", "init_std": self.action_std,
                                     "learn_std": False}}

    def rsl_cfg(self) -> dict[str, Any]:
        return {
            "num_steps_per_env": self.steps_per_env, "save_interval": 10**9,
            "obs_groups": {"actor": ["robot"], "critic": ["robot"]},
            "algorithm": {"class_name": SharedTrunkPPO, "num_learning_epochs": self.epochs,
                          "num_mini_batches": self.mini_batches, "learning_rate": self.learning_rate,
                          "entropy_coef": 0.0, "schedule": "adaptive", "desired_kl": self.desired_kl,
                          "gamma": self.gamma, "lam": self.lam, "max_grad_norm": 1.0,
                          "value_loss_coef": self.value_loss_coef, "clip_param": 0.2},
            "actor": {"class_name": H2INTActor, **self.model_cfg()},
            "critic": {"class_name": H2INTCritic, "hidden_dims": list(self.head_dims)},
        }


def _jsonable(cfg: TrainConfig) -> dict[str, Any]:
    return json.loads(json.dumps(dataclasses.asdict(cfg)))


class Trainer:
    """One training run in ``out`` (checkpoints, TensorBoard events, ``history.json``, ``curve.png``)."""

    def __init__(self, cfg: TrainConfig, out: str, quiet: bool = False) -> None:
        torch.set_num_threads(1)
        keep_heap()  # before the world processes fork (crowdbench.training.malloc)
        self.cfg, self.out, self.quiet = cfg, out, quiet
        os.makedirs(out, exist_ok=True)
        torch.manual_seed(cfg.seed)
        # without annealing the crowd is at the final difficulty from the start (the paper's "abrupt, fixed" baseline)
        curriculum = Curriculum(rho_init=cfg.rho_init if cfg.anneal else cfg.rho_min, rho_min=cfg.rho_min,
                                delta=cfg.rho_delta, eta=cfg.eta, window=cfg.window, cooldown=cfg.window,
                                enabled=cfg.anneal)
        self.env = CrowdVecEnv(cfg.num_envs, seed=cfg.seed, curriculum=curriculum, humans_range=cfg.humans_range,
                               reward_scale=cfg.reward_scale, processes=cfg.env_processes)
        self.runner = OnPolicyRunner(self.env, cfg.rsl_cfg(), log_dir=None)
        self.alg = self.runner.alg
        self.alg.actor.threads = cfg.threads
        self.alg.parallel_update = cfg.parallel_update
        if cfg.fused_adam:  # the same parameters in the same order as rsl-rl's optimiser: same state_dict layout
            self.alg.optimizer = torch.optim.Adam([p for g in self.alg.optimizer.param_groups for p in g["params"]],
                                                  lr=cfg.learning_rate, fused=True)
        self.alg.actor.packed = cfg.packed
        self.iteration = 0
        self.env_steps = 0
        self.elapsed = 0.0
        self.history: dict[str, list] = {k: [] for k in ("iteration", "env_steps", "time", "rho", "train_success",
                                                         "train_collision", "mean_reward", "steps_per_s")}
        self.evals: list[dict[str, Any]] = []
        self.writer = None

    # ------------------------------------------------------------------ checkpoints
    def checkpoint(self) -> dict[str, Any]:
        return {
            "format": FORMAT, "variant": self.cfg.variant, "seed": self.cfg.seed, "model": self.cfg.model_cfg(),
            "n_max": self.env.config.max_humans_observed, "train_config": _jsonable(self.cfg),
            "iteration": self.iteration, "env_steps": self.env_steps, "elapsed_s": self.elapsed,
            "actor": self.alg.actor.state_dict(), "critic": self.alg.critic.state_dict(),
            "optimizer": self.alg.optimizer.state_dict(), "learning_rate": float(self.alg.learning_rate),
            "env": self.env.state_dict(), "torch_rng": torch.get_rng_state(),
            "history": self.history, "evals": self.evals,
        }

    def save(self, name: str = "last.pt") -> str:
        path = os.path.join(self.out, name)
        with atomic_path(path, suffix=".pt") as tmp:
            torch.save(self.checkpoint(), tmp)
        return path

    def load(self, path: str) -> None:
        ckpt = load_checkpoint(path)
        if ckpt["train_config"]["variant"] != self.cfg.variant:
            raise ValueError(f"--resume: checkpoint variant {ckpt['train_config']['variant']!r} "
                             f"!= {self.cfg.variant!r}")
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
        self._restart_episodes()

    def _restart_episodes(self) -> None:
        """Fresh episodes everywhere and zeroed GRU states (zeroed in place, not set to None: rsl-rl's storage
        skips a None state and would keep the previous iteration's step-0 state for the update)."""
        self.env.reset_all()
        with torch.inference_mode():
            self.alg.actor.reset(torch.ones(self.cfg.num_envs, dtype=torch.long))

    # ------------------------------------------------------------------ evaluation
    def evaluate(self, episodes: int, responsiveness: float = 0.5, num_humans: int = 20) -> dict[str, float]:
        from crowdbench.evaluation import run_episodes, summarize

        with torch.random.fork_rng():  # building a network must not shift the training's random stream
            actor = build_actor(self.cfg.model_cfg(), self.env.config.max_humans_observed)
        actor.load_state_dict(self.alg.actor.state_dict())
        policy = H2INTPolicy(self.env.config, actor=actor)
        eps = run_episodes(policy, episodes, seed=10**6, num_worlds=min(episodes, 100), num_humans=num_humans,
                           human_model="responsive_orca", human_model_kwargs={"responsiveness": responsiveness})
        return summarize(eps)

    # ------------------------------------------------------------------ loop
    def _log(self, key: str, value: float) -> None:
        if self.writer is not None:
            self.writer.add_scalar(key, value, self.iteration)

    def train(self) -> None:
        from torch.utils.tensorboard import SummaryWriter

        cfg, alg, env = self.cfg, self.alg, self.env
        self.writer = SummaryWriter(os.path.join(self.out, "tb"), flush_secs=30)
        obs = env.get_observations()
        alg.train_mode()
        start_elapsed, t_start = self.elapsed, time.time()
        while self.iteration < cfg.iterations:
            t0 = time.time()
            with torch.inference_mode():
                obs, extras, rewards = collect(alg, env, obs, cfg.steps_per_env, cfg.worker_acting)
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
                   "steps_per_s": n / (t2 - t0)}
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
            done = (self.iteration >= cfg.iterations or (cfg.minutes and self.elapsed >= cfg.minutes * 60)
                    or reached)
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
                   json.dumps({"config": _jsonable(self.cfg), "history": self.history, "evals": self.evals}) + "\n")
        plot_curve(self.history, self.evals, os.path.join(self.out, "curve.png"), title=f"{self.cfg.variant} "
                   f"(seed {self.cfg.seed})")


def plot_curve(history: dict[str, list], evals: list[dict], path: str, title: str = "") -> None:
    """Training curve: training success rate and evaluation success vs env steps, ρ on a second axis."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4), dpi=100)
    steps = np.asarray(history["env_steps"]) / 1e6
    ax.plot(steps, history["train_success"], label="training success (last 200 episodes)", color="tab:blue")
    if evals:
        ax.plot([e["env_steps"] / 1e6 for e in evals], [e["success_rate"] for e in evals], "o-",
                label="eval success (N=20, ρ=0.5)", color="tab:green")
    ax.set_xlabel("environment steps [M]")
    ax.set_ylabel("success rate")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(steps, history["rho"], "--", color="tab:orange", label="ρ (curriculum)")
    ax2.set_ylabel("mean responsiveness ρ")
    ax2.set_ylim(0, 1.02)
    lines = ax.get_legend_handles_labels()
    lines2 = ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], loc="upper left", fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def train(cfg: TrainConfig, out: str, resume: str | None = None, quiet: bool = False) -> Trainer:
    """Train (or resume) and return the trainer; ``out/last.pt`` holds the final checkpoint."""
    trainer = Trainer(cfg, out, quiet=quiet)
    if resume:
        path = os.path.join(resume, "last.pt") if os.path.isdir(resume) else resume
        trainer.load(path)
    try:
        trainer.train()
    finally:
        trainer.close()
    return trainer


__all__ = ["TrainConfig", "Trainer", "plot_curve", "plot_evals", "plot_runs", "runs_table", "train"]


def plot_evals(history_files: list[str], path: str, bar: float = 0.95) -> None:
    """Quick-evaluation success of several runs against env steps and against wall-clock minutes: one colour per
    PPO schedule (epochs × mini-batches), one line style per seed, the bar dotted."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = _load_runs(history_files)
    schedules = sorted({_schedule(r["config"]) for r in runs}, key=lambda em: (-em[0], -em[1]))
    seeds = sorted({r["config"]["seed"] for r in runs})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    styles = ["-", "--", ":", "-."]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), dpi=100)
    for r in runs:
        cfg, evals = r["config"], r["evals"]
        kw = {"color": colours[schedules.index(_schedule(cfg)) % len(colours)],
              "linestyle": styles[seeds.index(cfg["seed"]) % len(styles)], "marker": "o", "markersize": 2.5,
              "label": _run_label(cfg)}
        succ = [e["success_rate"] for e in evals]
        axes[0].plot([e["env_steps"] / 1e6 for e in evals], succ, **kw)
        axes[1].plot([e["time"] / 60 for e in evals], succ, **kw)
    axes[0].set(xlabel="environment steps [M]", ylabel="quick-eval success (N = 20, ρ = 0.5)", ylim=(0, 1.02))
    axes[1].set(xlabel="wall-clock [min] (2 cores)", ylim=(0, 1.02))
    for ax in axes:
        ax.axhline(bar, color="grey", linestyle=":", linewidth=1)
        ax.grid(alpha=0.3)
    axes[1].legend(fontsize=7, loc="center right")
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def _load_runs(history_files: list[str]) -> list[dict[str, Any]]:
    """The ``history.json`` files written by :meth:`Trainer.write_artifacts`."""
    runs = []
    for f in history_files:
        with open(f) as fh:
            runs.append(json.load(fh))
    return runs


def _schedule(cfg: dict[str, Any]) -> tuple[int, int]:
    """(epochs, mini-batches) of a saved run configuration."""
    return cfg.get("epochs", 4), cfg.get("mini_batches", 4)


def _run_label(cfg: dict[str, Any]) -> str:
    epochs, mini_batches = _schedule(cfg)
    return (f"{cfg['variant']} {epochs}×{mini_batches} seed {cfg['seed']}"
            f"{'' if cfg.get('anneal', True) else ' (no annealing, ρ = 0)'}")


def runs_table(history_files: list[str], bar: float = 0.95) -> str:
    """Markdown table of training runs (``history.json`` files): when each first reached ``bar`` in the quick
    evaluation (iteration, env steps, wall-clock minutes) and how it ended."""
    lines = [f"| run | quick eval ≥ {100 * bar:.0f} % first at | env steps | minutes "
             "| end: iterations, last quick eval, ρ | mean env-steps/s |", "|---|---|---|---|---|---|"]
    for run in _load_runs(history_files):
        h, evals = run["history"], run["evals"]
        first = next((e for e in evals if e["success_rate"] >= bar), None)
        reached = ((f"iteration {first['iteration']}", f"{first['env_steps'] / 1e6:.2f} M", f"{first['time'] / 60:.1f}")
                   if first else ("not reached", "—", "—"))
        last = f"{100 * evals[-1]['success_rate']:.0f} %" if evals else "—"
        rate = h["env_steps"][-1] / max(h["time"][-1], 1e-9) if h["iteration"] else 0.0
        rho = h["rho"][-1] if h["rho"] else float("nan")
        end = f"{h['iteration'][-1] if h['iteration'] else 0}, {last}, ρ = {rho:.1f}"
        lines.append(f"| {_run_label(run['config'])} | {' | '.join(reached)} | {end} | {rate:,.0f} |")
    return "\n".join(lines)


def plot_runs(history_files: list[str], path: str) -> None:
    """Training success (last 200 episodes) and mean step reward of several runs against env steps (e.g. the
    paper's annealing-vs-fixed-difficulty figure), with each run's ρ schedule dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), dpi=100)
    for run in _load_runs(history_files):
        cfg, h = run["config"], run["history"]
        label = _run_label(cfg)
        steps = np.asarray(h["env_steps"]) / 1e6
        line = axes[0].plot(steps, h["train_success"], label=label)[0]
        axes[0].plot(steps, h["rho"], "--", color=line.get_color(), alpha=0.6)
        axes[1].plot(steps, np.asarray(h["mean_reward"]) / cfg.get("reward_scale", 1.0), label=label)
    axes[0].set(xlabel="environment steps [M]", ylabel="training success / ρ (dashed)", ylim=(0, 1.02))
    axes[1].set(xlabel="environment steps [M]", ylabel="mean reward per step")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
