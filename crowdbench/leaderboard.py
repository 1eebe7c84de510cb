"""The paper's evaluation grid, regenerated for any registered robot policy.

Cells (500 episodes each by default, latent-responsive ORCA pedestrians, δ = 0.2):

* Table I — circle crossing, 20 pedestrians, ρ ∈ {0.7 High, 0.5 Medium, 0.3 Low};
* Table II — circle crossing, ρ = 0 (non-responsive regime), N ∈ {10, 20, 30};
* Table III — unseen layouts (intersection, split flow, random wander), 30 pedestrians, ρ ∈ {0.7, 0.5, 0.3}.

Each cell uses evaluation seed S (episode k ↔ world seed S + k), so every policy meets exactly the same crowds.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from typing import Any

from crowdbench.evaluation import run_episodes, summarize
from crowdbench.io import write_text
from crowdbench.policies import make_policy

REGIMES = {"High": 0.7, "Medium": 0.5, "Low": 0.3}


@dataclass(frozen=True)
class Cell:
    """One evaluation setting: table, row label, layout, crowd size and mean responsiveness ρ."""

    table: str
    row: str
    layout: str
    humans: int
    rho: float


def cells(tables: tuple[str, ...] = ("I", "II", "III")) -> list[Cell]:
    """The grid of the requested tables."""
    out: list[Cell] = []
    if "I" in tables:
        out += [Cell("I", name, "circle_crossing", 20, rho) for name, rho in REGIMES.items()]
    if "II" in tables:
        out += [Cell("II", f"N={n}", "circle_crossing", n, 0.0) for n in (10, 20, 30)]
    if "III" in tables:
        out += [Cell("III", f"{lay} {name}", lay, 30, rho) for lay in ("intersection", "split_flow", "random_wander")
                for name, rho in REGIMES.items()]
    return out


def evaluate_cells(policy_name: str, grid: list[Cell], episodes: int = 500, seed: int = 0, num_worlds: int = 100,
                   policy_kwargs: dict | None = None, progress: bool = True,
                   label: str | None = None) -> list[dict[str, Any]]:
    """Run every cell for one policy; returns one summary dict per cell (``policy`` = ``label`` or the name)."""
    results = []
    for c in grid:
        t = time.time()
        policy = make_policy(policy_name, **(policy_kwargs or {}))
        eps = run_episodes(policy, episodes, seed=seed, num_worlds=num_worlds, layout=c.layout, num_humans=c.humans,
                           human_model="responsive_orca", human_model_kwargs={"responsiveness": c.rho})
        s = summarize(eps)
        results.append({"policy": label or policy_name, "table": c.table, "row": c.row, "layout": c.layout,
                        "humans": c.humans, "responsiveness": c.rho, "seed": seed, **s,
                        "wall_s": round(time.time() - t, 1)})
        if progress:
            print(f"Table {c.table:<3} {c.row:<26} success {s['success_rate']:.3f} collision {s['collision_rate']:.3f}"
                  f" timeout {s['timeout_rate']:.3f} time {s['nav_time']:.2f} path {s['path_length']:.2f}"
                  f" dv {s['delta_v']:.2f}", flush=True)
    return results


def markdown(results: list[dict[str, Any]]) -> str:
    lines = ["| table | setting | policy | r_s % | r_c % | r_t % | t_s [s] | l_p [m] | Δv [m/s] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        lines.append(f"| {r['table']} | {r['row']} | {r['policy']} | {100 * r['success_rate']:.1f} | "
                     f"{100 * r['collision_rate']:.1f} | {100 * r['timeout_rate']:.1f} | {r['nav_time']:.2f} | "
                     f"{r['path_length']:.2f} | {r['delta_v']:.2f} |")
    return "\n".join(lines) + "\n"


def save(results: list[dict[str, Any]], json_path: str | None, md_path: str | None, meta: dict[str, Any]) -> None:
    if json_path:
        write_text(json_path, json.dumps({"meta": meta, "results": results}, indent=2) + "\n")
    if md_path:
        write_text(md_path, markdown(results))


def plot_trends(result_files: list[str], path: str) -> None:
    """Success rate per policy across Table I regimes and Table II crowd sizes (the paper's ablation figure)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crowdbench.io import atomic_path

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
