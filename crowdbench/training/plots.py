"""Training-run figures and tables: one run's curve, several runs compared (``crowdbench curves``)."""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from crowdbench.io import atomic_path


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


def plot_evals(history_files: list[str], path: str, bar: float = 0.95) -> None:
    """Quick-evaluation success of several runs against env steps and against wall-clock minutes: one colour per
    architecture, PPO schedule (epochs × mini-batches, learning rate) and curriculum, one line style per seed, the
    bar dotted."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = _load_runs(history_files)
    schedules = sorted({_colour_key(r["config"]) for r in runs}, key=lambda k: (k[0], -k[1], -k[2], *map(str, k[3:])))
    seeds = sorted({r["config"]["seed"] for r in runs})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    styles = ["-", "--", ":", "-."]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), dpi=100)
    for r in runs:
        cfg, evals = r["config"], r["evals"]
        kw = {"color": colours[schedules.index(_colour_key(cfg)) % len(colours)],
              "linestyle": styles[seeds.index(cfg["seed"]) % len(styles)], "marker": "o", "markersize": 2.5,
              "label": _run_label(cfg)}
        succ = [e["success_rate"] for e in evals]
        axes[0].plot([e["env_steps"] / 1e6 for e in evals], succ, **kw)
        axes[1].plot([e["time"] / 60 for e in evals], succ, **kw)
    axes[0].set(xlabel="environment steps [M]", ylabel="quick-eval success (N = 20, ρ = 0.5)", ylim=(0, 1.02))
    axes[1].set(xlabel="wall-clock [min] (each run's own cores)", ylim=(0, 1.02))
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


def _colour_key(cfg: dict[str, Any]) -> tuple[Any, ...]:
    """What one colour stands for: architecture, epochs, mini-batches, learning rate and schedule, policy noise,
    curriculum."""
    return (_architecture(cfg), *_schedule(cfg), cfg.get("learning_rate"), cfg.get("schedule"), _noise(cfg),
            cfg.get("anneal", True))


def _noise(cfg: dict[str, Any]) -> str:
    """``" std S fixed"`` for a run whose model keeps its policy std fixed (``learn_std=False``), else ``""``."""
    model = cfg.get("model") or {}
    return f" std {model.get('action_std', 1.0):g} fixed" if model.get("learn_std") is False else ""


def _architecture(cfg: dict[str, Any]) -> str:
    """A saved run's architecture: H²INT's ``variant``, else the method with its named variant
    (:meth:`PPOMethod.label <crowdbench.training.methods.PPOMethod.label>`, e.g. ``dsrnn-small``)."""
    from crowdbench.policies.recurrent import stored_config
    from crowdbench.training.methods import PPO_METHODS

    model = cfg.get("model") or {}
    if cfg.get("variant") or model.get("variant"):
        return cfg.get("variant") or model["variant"]
    method = cfg.get("method", "?")
    try:
        m = PPO_METHODS.get(method)()
        return m.label(stored_config(m.model_config, {"model": model}))
    except (ValueError, TypeError):  # a method or field this version does not know
        return method


def _run_label(cfg: dict[str, Any]) -> str:
    epochs, mini_batches = _schedule(cfg)
    name = _architecture(cfg)
    lr = (f" lr {cfg['learning_rate']:g} {cfg.get('schedule', 'adaptive')}" if "learning_rate" in cfg else "")
    return (f"{name} {epochs}×{mini_batches}{lr}{_noise(cfg)} seed {cfg['seed']}"
            f"{' (ρ annealed)' if cfg.get('anneal', True) else ' (no annealing, ρ = 0)'}")


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


def plot_value_curve(history: dict[str, list], evals: list[dict], path: str, title: str = "") -> None:
    """CADRL/SARL run: success of the demonstration and TD-learning episodes (moving average over 500) and the
    quick greedy evaluations against episodes; ε on a second axis."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4), dpi=100)
    ph = np.asarray(history["phase"])
    ax2 = ax.twinx()
    phases = (("il", "tab:gray", "ORCA demonstrations"), ("rl", "tab:blue", "TD learning (ε-greedy)"))
    for phase, colour, label in phases:
        sel = ph == phase
        if not sel.any():
            continue
        ep = np.asarray(history["episode"])[sel]
        succ = np.asarray(history["success"], dtype=float)[sel]
        k = max(1, int(round(500 / max(np.median(np.diff(ep)) if len(ep) > 1 else 1, 1))))
        smooth = np.convolve(np.nan_to_num(succ), np.ones(k) / k, mode="valid") if len(succ) >= k else succ
        ax.plot(ep[len(ep) - len(smooth):], smooth, color=colour, label=f"{label}, success")
        if phase == "rl":
            ax2.plot(ep, np.asarray(history["epsilon"])[sel], "--", color="tab:orange", label="ε")
    rl_evals = [e for e in evals if e["phase"] in ("rl", "done")]
    if rl_evals:
        ax.plot([e["episode"] for e in rl_evals], [e["success_rate"] for e in rl_evals], "o-", color="tab:green",
                label="greedy eval (N=20, ρ=0.5; episode 0 = after imitation)")
    ax.set_xlabel("episode (of each phase)")
    ax.set_ylabel("success rate")
    ax.set_ylim(0, 1.02)
    ax.grid(alpha=0.3)
    ax2.set_ylabel("exploration ε")
    ax2.set_ylim(0, 1.02)
    lines, lines2 = ax.get_legend_handles_labels(), ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], loc="lower right", fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
