"""The board's figures: success against the response regime and the crowd size (``success.png``, ``ablation.png``),
and the trends of ``crowdbench tables`` result files."""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from crowdbench.io import atomic_path
from crowdbench.policies import REFERENCE_METHOD


def legend_label(label: str, n_seeds: int, trained: bool = True) -> str:
    """A figure's legend entry: a learned method names its training-seed count, a planner (nothing trained) none."""
    return f"{label} ({n_seeds} seed{'s' if n_seeds > 1 else ''})" if trained else label


def plot_board(board: dict[str, list[dict[str, Any]]], path: str, groups: dict[str, str] | None = None,
               rows: str = "main", reference: str = REFERENCE_METHOD, planners: frozenset[str] = frozenset(),
               sensing: dict[str, str] | None = None) -> None:
    """Success against the response regime ρ (Table I, N = 20) and against crowd size N (Table II, ρ = 0), one line
    per method of group ``rows`` (``main``; or ``ablation``, headed by ``reference``: the paper's ablation figure).
    A method with several training seeds (entries of group ``seeds:<label>``) is drawn at the seeds' mean, with error
    bars from the lowest to the highest seed and a band enveloping the seeds' Wilson 95 % intervals; one seed: its
    interval. The legend gives each learned method's seed count; ``planners`` (labels with no checkpoint) get none.
    Methods at another sensing tier than ``positions`` (``sensing``: label → tier) are drawn dashed, their tier in the
    legend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = groups or {}
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), dpi=100, sharey=True)
    specs = (("I", "responsiveness", "mean responsiveness ρ (Table I, N = 20)"),
             ("II", "humans", "pedestrians N (Table II, ρ = 0)"))
    heads = [lb for lb in board if groups.get(lb, "main") == rows]
    if rows != "main" and reference in board and reference not in heads:
        heads.insert(0, reference)
    for ax, (table, key, xlabel) in zip(axes, specs, strict=True):
        for label in heads:
            family = [label] + [lb for lb, g in groups.items() if g == f"seeds:{label}" and lb in board]
            pts: dict[float, list[tuple[float, float, float]]] = {}
            for lb in family:
                for r in board[lb]:
                    if r["table"] == table and "error" not in r:
                        lo, hi = r.get("ci", {}).get("success_rate", (r["success_rate"],) * 2)
                        pts.setdefault(r[key], []).append((r["success_rate"], lo, hi))
            if not pts:
                continue
            xs = sorted(pts)
            mean = [100 * np.mean([p[0] for p in pts[x]]) for x in xs]
            lo = [100 * min(p[1] for p in pts[x]) for x in xs]
            hi = [100 * max(p[2] for p in pts[x]) for x in xs]
            n_seeds = len(family)
            tier = (sensing or {}).get(label, "positions")
            name = legend_label(label, n_seeds, label not in planners)
            (line,) = ax.plot(xs, mean, "o-" if tier == "positions" else "o--",
                              label=name if tier == "positions" or tier in label else f"{name} [{tier}]")
            ax.fill_between(xs, lo, hi, color=line.get_color(), alpha=0.15)
            if n_seeds > 1:
                low = [100 * min(p[0] for p in pts[x]) for x in xs]
                high = [100 * max(p[0] for p in pts[x]) for x in xs]
                ax.errorbar(xs, mean, yerr=[np.subtract(mean, low), np.subtract(high, mean)], fmt="none",
                            ecolor=line.get_color(), capsize=3)
        ticks = sorted({r[key] for rows in board.values() for r in rows if r["table"] == table})
        ax.set_xticks(ticks)
        ax.set_xlabel(xlabel)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("success rate [%] (band: 95 % interval;\nbars: seed range)")
    axes[0].invert_xaxis()  # harder to the right: less responsive
    axes[1].legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def plot_trends(result_files: list[str], path: str) -> None:
    """Success rate per policy across Table I regimes and Table II crowd sizes (the paper's ablation figure)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6), dpi=100, sharey=True)
    for f in result_files:
        with open(f) as fh:
            res = json.load(fh)["results"]
        name = res[0]["policy"]
        for ax, table in zip(axes, ("I", "II"), strict=True):
            rows = [r for r in res if r["table"] == table]
            ax.plot([r["row"] for r in rows], [100 * r["success_rate"] for r in rows], "o-", label=name)
    axes[0].set(title="Table I: response regime (N = 20)", ylabel="success rate [%]")
    axes[1].set(title="Table II: crowd size (ρ = 0)")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)
