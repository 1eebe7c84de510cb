"""The paper's evaluation grid, regenerated for any registered robot policy.

Cells (500 episodes each by default, latent-responsive ORCA pedestrians, δ = 0.2):

* Table I — circle crossing, 20 pedestrians, ρ ∈ {0.7 High, 0.5 Medium, 0.3 Low};
* Table II — circle crossing, ρ = 0 (non-responsive regime), N ∈ {10, 20, 30};
* Table III — unseen layouts (intersection, split flow, random wander), 30 pedestrians, ρ ∈ {0.7, 0.5, 0.3};
* Table IV — real crowds: the five ETH/UCY scenes, recorded people replayed blind to the robot (``replay``) or
  avoiding it and rejoining their paths (``reactive_replay``), slots for the scene's peak crowd;
* Table V — crowd-model shift: circle crossing, 20 pedestrians of each model of :data:`SHIFT_MODELS` (every
  method was trained among latent-responsive ORCA pedestrians).

Each cell uses evaluation seed S (episode k ↔ world seed S + k), so every policy meets exactly the same crowds.
"""

from __future__ import annotations

import functools
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crowdbench import __version__, checkpoints
from crowdbench.evaluation import run_episodes, summarize
from crowdbench.io import atomic_path, write_text
from crowdbench.metrics import wilson
from crowdbench.policies import POLICIES, REFERENCE_METHOD, make_policy, methods
from crowdbench.worlds.digest import crowd_digest

REGIMES = {"High": 0.7, "Medium": 0.5, "Low": 0.3}


TABLES = ("I", "II", "III", "IV", "V")
SHIFT_MODELS = ("responsive_orca", "orca", "social_force", "learned_crowd")
"""Table V's crowds: the training crowd (latent-responsive ORCA, ρ = 0.5) and three others."""


@dataclass(frozen=True)
class Cell:
    """One evaluation setting: table, row label, layout, crowd size, mean responsiveness ρ and pedestrian model."""

    table: str
    row: str
    layout: str
    humans: int
    rho: float
    model: str = "responsive_orca"


def cells(tables: tuple[str, ...] = ("I", "II", "III")) -> list[Cell]:
    """The grid of the requested tables."""
    from crowdbench.worlds.recorded import PEAK

    out: list[Cell] = []
    if "I" in tables:
        out += [Cell("I", name, "circle_crossing", 20, rho) for name, rho in REGIMES.items()]
    if "II" in tables:
        out += [Cell("II", f"N={n}", "circle_crossing", n, 0.0) for n in (10, 20, 30)]
    if "III" in tables:
        out += [Cell("III", f"{lay} {name}", lay, 30, rho) for lay in ("intersection", "split_flow", "random_wander")
                for name, rho in REGIMES.items()]
    if "V" in tables:
        out += [Cell("V", m if m != "responsive_orca" else "responsive_orca ρ=0.5", "circle_crossing", 20,
                     0.5 if m == "responsive_orca" else 0.0, m) for m in SHIFT_MODELS]
    if "IV" in tables:
        out += [Cell("IV", f"{scene} {model}", scene, peak, 0.0, model) for scene, peak in PEAK.items()
                for model in ("replay", "reactive_replay")]
    return out


def evaluate_cells(policy_name: str, grid: list[Cell], episodes: int = 500, seed: int = 0, num_worlds: int = 100,
                   policy_kwargs: dict | None = None, progress: bool = True, label: str | None = None,
                   layout_kwargs: dict | None = None, model_kwargs: dict | None = None,
                   world_options: dict | None = None, counterfactual: bool = True) -> list[dict[str, Any]]:
    """Run every cell for one policy; returns one summary dict per cell (``policy`` = ``label`` or the name; the
    metrics of :func:`crowdbench.metrics.summarize`). ``layout_kwargs``, ``model_kwargs`` (latent-responsive ORCA) and
    ``world_options`` (:class:`WorldConfig` fields) change the scenario from its defaults (studies do);
    ``counterfactual`` runs the robot-absent twin for the pedestrians' delay."""
    from crowdbench.worlds import make_layout

    results = []
    t_start = time.time()
    for k, c in enumerate(grid, 1):
        t = time.time()
        policy = make_policy(policy_name, **(policy_kwargs or {}))
        kwargs = {"responsiveness": c.rho, **(model_kwargs or {})} if c.model == "responsive_orca" else {}
        eps = run_episodes(policy, episodes, seed=seed, num_worlds=num_worlds,
                           layout=make_layout(c.layout, **(layout_kwargs or {})), num_humans=c.humans,
                           human_model=c.model, human_model_kwargs=kwargs,
                           counterfactual=counterfactual, **(world_options or {}))
        s = summarize(eps)
        results.append({"policy": label or policy_name, "table": c.table, "row": c.row, "layout": c.layout,
                        "humans": c.humans, "responsiveness": c.rho, "human_model": c.model, "seed": seed, **s,
                        "wall_s": round(time.time() - t, 1)})
        if progress:
            eta = (time.time() - t_start) / k * (len(grid) - k)
            print(f"[{k}/{len(grid)}] Table {c.table:<3} {c.row:<26} success {s['success_rate']:.3f} collision "
                  f"{s['collision_rate']:.3f} timeout {s['timeout_rate']:.3f} time {s['nav_time']:.2f} path "
                  f"{s['path_length']:.2f} dv {s['delta_v']:.2f} | ETA {eta / 60:.1f} min", flush=True)
    return results


def with_pooled(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """``results`` plus Table III pooled over its layouts per response regime (the paper's presentation): rows
    ``pooled High`` etc. — rates averaged over the layouts (equal episodes each), navigation time and path length
    averaged over all successful episodes, Δv over all episodes."""
    out = list(results)
    for regime in REGIMES:
        rows = [r for r in results if r["table"] == "III" and r["row"].endswith(f" {regime}")
                and not r["row"].startswith("pooled")]
        if len(rows) < 2 or any("error" in r for r in rows):
            continue
        wins = [r["success_rate"] * r["episodes"] for r in rows]
        total = sum(wins)

        def by_success(key: str, rows=rows, wins=wins, total=total) -> float:
            return sum(w * r[key] for w, r in zip(wins, rows, strict=True) if w) / total if total else math.nan

        n = sum(r["episodes"] for r in rows)
        rates = ("success_rate", "collision_rate", "timeout_rate")
        ci = {k: list(wilson(round(sum(r[k] * r["episodes"] for r in rows)), n)) for k in rates}
        out.append({**{k: rows[0][k] for k in ("policy", "humans", "responsiveness", "seed")},
                    "table": "III", "row": f"pooled {regime}", "layout": "+".join(r["layout"] for r in rows),
                    "episodes": n,
                    **{k: sum(r[k] for r in rows) / len(rows) for k in (*rates, "delta_v")},
                    "nav_time": by_success("nav_time"), "path_length": by_success("path_length"),
                    **{k: sum(r[k] for r in rows) / len(rows) for k in SOCIAL if k in rows[0]},
                    "ci": ci, "wall_s": sum(r.get("wall_s", 0.0) for r in rows)})
    return out


SOCIAL = ("min_distance", "personal_space", "min_ttc", "jerk", "spl", "irregularity", "unaware_share", "ped_delay")
"""Social metrics (:mod:`crowdbench.metrics`) shown in the per-method files."""


def _ci(r: dict[str, Any], key: str, scale: float = 1.0, digits: int = 1) -> str:
    lo, hi = r.get("ci", {}).get(key, (math.nan, math.nan))
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return ""
    return f" ({scale * lo:.{digits}f}–{scale * hi:.{digits}f})"


def markdown(results: list[dict[str, Any]]) -> str:
    """One method's cells: the paper's six with 95 % intervals (Wilson for rates, bootstrap for means), then the
    social metrics (:mod:`crowdbench.metrics`: min distance [m], personal-space compliance [%], min TTC [s], jerk
    [m/s³], SPL, irregularity [rad], share of close encounters with unaware pedestrians [%], pedestrian delay [%])."""
    lines = ["| table | setting | policy | r_s % | r_c % | r_t % | t_s [s] | l_p [m] | Δv [m/s] | d_min | PS % | "
             "TTC | jerk | SPL | irr. | unaware % | delay % |", "|---|" * 1 + "---|" * 17]

    def f(r: dict[str, Any], key: str, scale: float = 1.0, digits: int = 2) -> str:
        v = r.get(key, math.nan)
        return f"{scale * v:.{digits}f}" if v is not None and math.isfinite(v) else "—"

    for r in with_pooled(results):
        if "error" in r:
            lines.append(f"| {r['table']} | {r['row']} | {r['policy']} | error: {r['error']} |" + " |" * 16)
            continue
        lines.append(f"| {r['table']} | {r['row']} | {r['policy']} | {100 * r['success_rate']:.1f}"
                     f"{_ci(r, 'success_rate', 100)} | {100 * r['collision_rate']:.1f} | "
                     f"{100 * r['timeout_rate']:.1f} | {f(r, 'nav_time')}{_ci(r, 'nav_time', 1, 2)} | "
                     f"{f(r, 'path_length')} | {f(r, 'delta_v')} | {f(r, 'min_distance')} | "
                     f"{f(r, 'personal_space', 100, 1)} | {f(r, 'min_ttc')} | {f(r, 'jerk', 1, 1)} | {f(r, 'spl')} | "
                     f"{f(r, 'irregularity')} | {f(r, 'unaware_share', 100, 1)} | {f(r, 'ped_delay', 100, 1)} |")
    return "\n".join(lines) + "\n"


def save(results: list[dict[str, Any]], json_path: str | None, md_path: str | None, meta: dict[str, Any]) -> None:
    if json_path:
        write_text(json_path, json.dumps({"meta": meta, "results": results}, indent=2) + "\n")
    if md_path:
        write_text(md_path, markdown(results))


def legend_label(label: str, n_seeds: int, trained: bool = True) -> str:
    """A figure's legend entry: a learned method names its training-seed count, a planner (nothing trained) none."""
    return f"{label} ({n_seeds} seed{'s' if n_seeds > 1 else ''})" if trained else label


def plot_board(board: dict[str, list[dict[str, Any]]], path: str, groups: dict[str, str] | None = None,
               rows: str = "main", reference: str = REFERENCE_METHOD, planners: frozenset[str] = frozenset()) -> None:
    """Success against the response regime ρ (Table I, N = 20) and against crowd size N (Table II, ρ = 0), one line
    per method of group ``rows`` (``main``; or ``ablation``, headed by ``reference``: the paper's ablation figure).
    A method with several training seeds (entries of group ``seeds:<label>``) is drawn at the seeds' mean, with error
    bars from the lowest to the highest seed and a band enveloping the seeds' Wilson 95 % intervals; one seed: its
    interval. The legend gives each learned method's seed count; ``planners`` (labels with no checkpoint) get none."""
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
            (line,) = ax.plot(xs, mean, "o-", label=legend_label(label, n_seeds, label not in planners))
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


# ---------------------------------------------------------------------------------------------------- leaderboard
@dataclass(frozen=True)
class Entry:
    """One leaderboard row: a display label, a registered robot policy and its keyword arguments."""

    label: str
    policy: str
    kwargs: tuple[tuple[str, Any], ...] = ()
    group: str = "main"
    """``main`` (the methods compared in Tables I–III), ``seeds:LABEL`` (other training seeds of the main entry
    ``LABEL``; plain ``seeds`` = of the reference method) or ``ablation`` (its variants)."""

    @property
    def slug(self) -> str:
        """File stem of this entry's results in the leaderboard folder."""
        return "".join(ch if ch.isalnum() or ch in "-_" else "-" for ch in self.label.lower()).strip("-")

    def policy_kwargs(self) -> dict[str, Any]:
        return dict(self.kwargs)


def method_entries() -> tuple[Entry, ...]:
    """Every registered method's leaderboard rows (:attr:`crowdbench.policies.Method.entries`), the main rows
    first, each group in registration order."""
    rows = [Entry(e.label, m.name, e.kwargs, e.group) for m in methods() for e in m.entries]
    return tuple(sorted(rows, key=lambda e: e.group != "main"))  # stable


METHODS: tuple[Entry, ...] = method_entries()
"""The leaderboard's methods (those registered when this module is imported; :func:`method_entries` for a later
registration); a learned one appears once a checkpoint trained on the current crowd ships. Rows at another sensing
tier than ``positions`` (the ``sensing`` argument) get their own section of the board."""


def trained_crowd(path: str) -> str | None:
    """The crowd digest (:func:`~crowdbench.worlds.digest.crowd_digest`) a checkpoint records it was trained on;
    None for checkpoints that do not say (trained before crowds were recorded)."""
    return _trained_crowd(path, checkpoints.file_sha256(path))


@functools.lru_cache(maxsize=256)
def _trained_crowd(path: str, sha256: str) -> str | None:
    import torch

    ckpt = torch.load(path, map_location="cpu", weights_only=True)
    return ckpt.get("crowd") if isinstance(ckpt, dict) else None


STALE: dict[str, str] = {}
"""Shipped learned entries left off the board (label → why): their checkpoint was trained on another crowd."""


def shipped_entries(methods: tuple[Entry, ...] = METHODS) -> dict[str, Entry]:
    """``methods`` whose checkpoint is shipped and was trained on the current crowd (a learned method appears once
    such a checkpoint lands; the others are listed in :data:`STALE`), each main or ablation entry followed by its
    other shipped training seeds (checkpoints ``<name>-seed<k>``, group ``seeds:<label>``)."""
    import re


    out: dict[str, Entry] = {}
    current = crowd_digest()
    for e in methods:
        ckpt = e.policy_kwargs().get("checkpoint")
        names = checkpoints.shipped_names(e.policy) if ckpt else []
        if ckpt and ckpt not in names:
            continue
        if ckpt and trained_crowd(checkpoints.resolve(e.policy, ckpt)) != current:
            STALE[e.label] = ("trained on crowdbench's former crowd, not on the current CrowdNav++ one; back once "
                              "retrained (`crowdbench train`)")
            continue
        out[e.slug] = e
        if e.group in ("main", "ablation") and ckpt:
            seeds = sorted((int(m[1]), n) for n in names if (m := re.fullmatch(rf"{re.escape(ckpt)}-seed(\d+)", n)))
            for k, name in seeds:
                if trained_crowd(checkpoints.resolve(e.policy, name)) != current:
                    continue
                seed_entry = Entry(f"{e.label}-seed{k}", e.policy, (("checkpoint", name),), f"seeds:{e.label}")
                out[seed_entry.slug] = seed_entry
    return out


ENTRIES: dict[str, Entry] = shipped_entries()
"""The shipped leaderboard's rows (of the methods registered at import; :func:`board_entries` for the current)."""


def board_entries() -> dict[str, Entry]:
    """The shipped leaderboard's rows of every method registered now (plug-ins registered after this module was
    imported included)."""
    return shipped_entries(method_entries())


def parse_entry(spec: str) -> Entry:
    """``LABEL=POLICY`` or ``LABEL=POLICY@CHECKPOINT`` (a policy registered in :data:`~crowdbench.policies.POLICIES`,
    e.g. through the ``crowdbench.policies`` entry point) → :class:`Entry`."""
    if "=" not in spec:
        raise ValueError(f"--add {spec!r}: expected LABEL=POLICY or LABEL=POLICY@CHECKPOINT")
    label, rest = (s.strip() for s in spec.split("=", 1))
    policy, _, ckpt = rest.partition("@")
    if policy not in POLICIES.names():
        raise ValueError(f"--add {spec!r}: unknown policy {policy!r}; valid choices: {', '.join(POLICIES.names())}")
    return Entry(label, policy, (("checkpoint", ckpt),) if ckpt else ())


def scenario_digest(tables: tuple[str, ...] = ("I", "II", "III")) -> str:
    """SHA-256 (16 hex digits) of everything that defines the crowds of the grid (:func:`~crowdbench.worlds.digest.
    crowd_digest` over its layouts and pedestrian models) — a cached result is stale when the scenario changes."""
    grid = cells(tables)
    return crowd_digest(tuple(sorted({c.layout for c in grid})), tuple(sorted({c.model for c in grid})))


def policy_code(policy: str) -> str:
    """SHA-256 (16 hex digits) of the source a registered robot policy runs: the file defining its class and every
    base class (outside the standard library and torch), plus every ``.py`` file of a method sub-package
    (``crowdbench/policies/<method>/``) among them — a plug-in's own files included. A stored cell is stale once
    any of them changes."""
    import hashlib
    import inspect


    factory = POLICIES.get(policy)
    files: set[Path] = set()
    for cls in inspect.getmro(factory) if inspect.isclass(factory) else (factory,):
        if getattr(cls, "__module__", "").split(".")[0] in ("builtins", "abc", "typing", "torch", "collections"):
            continue
        try:
            src = inspect.getsourcefile(cls)
        except TypeError:
            continue
        if src is None:
            continue
        path = Path(src).resolve()
        files.add(path)
        pkg = Path(__file__).resolve().parent / "policies"
        if path.parent.parent == pkg:  # a method sub-package: all of it
            files.update(path.parent.glob("*.py"))
    h = hashlib.sha256()
    for path in sorted(files):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def entry_sensing(entry: Entry) -> str:
    """The sensing tier of an entry's policy (built with its arguments: a checkpoint may set it)."""
    return make_policy(entry.policy, **entry.policy_kwargs()).sensing


def _fingerprint(entry: Entry, episodes: int, seed: int) -> dict[str, Any]:
    """What a cached result must match to be reused: policy, arguments, sensing tier, checkpoint contents, the
    policy's source (:func:`policy_code`), the crowdbench version, episodes, seed, and the scenario
    (:func:`scenario_digest`)."""
    import os


    kwargs = entry.policy_kwargs()
    digest = None
    ckpt = kwargs.get("checkpoint")
    if ckpt:
        ckpt = checkpoints.resolve(entry.policy, ckpt)  # a path, or the name of a shipped checkpoint
    if ckpt and os.path.exists(ckpt):
        digest = checkpoints.file_sha256(ckpt)
    shown = {k: (v if k != "checkpoint" or not os.path.exists(v) else os.path.relpath(v)) for k, v in kwargs.items()}

    return {"policy": entry.policy, "kwargs": shown, "sensing": entry_sensing(entry), "checkpoint_sha256": digest,
            "code": policy_code(entry.policy), "crowdbench": __version__, "episodes": episodes, "seed": seed,
            "scenario": scenario_digest()}


TABLE_TITLES = {"I": "Table I — response regimes (circle crossing, N = 20)",
                "II": "Table II — crowd size (circle crossing, non-responsive ρ = 0)",
                "III": "Table III — unseen layouts (N = 30; trained on circle crossing only; pooled = the three "
                       "layouts together, the paper's presentation)",
                "V": "Table V — crowd-model shift (circle crossing, N = 20; the learned methods were trained among "
                     "latent-responsive ORCA pedestrians)",
                "IV": "Table IV — real crowds (ETH/UCY test recordings, slots for each scene's peak crowd; replay: "
                      "people as recorded, blind to the robot; reactive_replay: they avoid the robot, then rejoin "
                      "their paths); PS = personal-space compliance [%]"}


def _clear_best(rows: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The row with the highest success rate if its Wilson interval lies above every other row's, else None."""
    rows = [r for r in rows if "error" not in r]
    if not rows:
        return None
    top = max(rows, key=lambda r: r["success_rate"])
    lo = top.get("ci", {}).get("success_rate", (math.nan,))[0]
    others = [r.get("ci", {}).get("success_rate", (math.nan, math.nan))[1] for r in rows if r is not top]
    return top if all(lo > hi for hi in others) else None


def leaderboard_markdown(board: dict[str, list[dict[str, Any]]], groups: dict[str, str] | None = None,
                         episodes: int | None = None, seed: int | None = None,
                         reference: str | None = REFERENCE_METHOD, suite: str | None = None,
                         planners: frozenset[str] = frozenset(),
                         budgets: dict[str, dict[str, int]] | None = None,
                         sensing: dict[str, str] | None = None, missing: dict[str, str] | None = None) -> str:
    """The paper's tables with one row per method: success / collision / timeout [%], navigation time [s] per
    setting; the best success of each setting in bold. Ablation entries get their own tables, headed by the
    ``reference`` method's row when it is on the board. ``planners`` (labels with no checkpoint) get no seed count;
    ``budgets`` (:func:`training_budgets`) adds each method's training per seed to the over-seeds tables.
    ``sensing`` (label → tier): only ``positions`` rows are ranked together; rows at ``velocities`` and ``full``
    get sections of their own. ``missing`` (label → reason): shipped methods left off the board, and why."""
    groups = groups or {}
    tier = {lb: (sensing or {}).get(lb, "positions") for lb in board}
    out = ["# crowdbench leaderboard", ""]
    if episodes is not None:
        via = f"Suite `{suite}`: " if suite else ""
        out += [f"{via}{episodes} episodes per cell, evaluation seed {seed} (episode k ↔ world seed {seed} + k: every "
                "method meets the same crowds). Cells: success r_s (its Wilson 95 % interval) / collision r_c / "
                "timeout r_t [%], navigation time t_s [s] of successful episodes. **Bold**: the best success of a "
                "setting, only where its interval does not overlap any other method's. Regenerate with "
                "`crowdbench leaderboard run`; the per-method files hold the intervals of every column, path length, "
                "Δv and the social metrics.", ""]
    by_reason: dict[str, list[str]] = {}
    for lb, why in (missing or {}).items():
        by_reason.setdefault(why, []).append(f"`{lb}`")
    out += [f"**Not on the board** ({why}): {', '.join(lbs)}.\n" for why, lbs in by_reason.items()]
    out += ["Every robot here senses the same thing — `sensing=positions`: the relative positions of the pedestrians "
            "within 5 m (surface distance), each step; methods that need velocities estimate them from those "
            "positions. Rows given more (`velocities`: true velocities and radii; `full`: everyone, privileged) "
            "have sections of their own below and are not ranked with the rest.", ""]
    board = {lb: with_pooled(rows) for lb, rows in board.items()}
    extra = {t: [lb for lb in board if tier[lb] == t] for t in ("velocities", "full")}
    extra = {t: lbs for t, lbs in extra.items() if lbs}
    for lbs in extra.values():
        for lb in lbs:
            groups = {**groups, lb: f"sensing:{tier[lb]}"}

    def family(g: str) -> str:
        return g.split(":", 1)[1] if ":" in g else (reference or "")

    seed_groups = sorted({g for g in groups.values() if g == "seeds" or g.startswith("seeds:")},
                         key=lambda g: (family(g) != reference, family(g)))
    for group in ("main", *seed_groups, "ablation", *(f"sensing:{t}" for t in extra)):
        labels = [lb for lb in board if groups.get(lb, "main") == group]
        if not labels:
            continue
        head = family(group) if group.startswith("seeds") else reference
        if group != "main" and not group.startswith("sensing") and head in board and head not in labels:
            labels.insert(0, head)
        if group == "ablation":
            out += ["## Ablations", ""]
        if group.startswith("sensing"):
            t = group.split(":", 1)[1]
            out += [f"## Rows at `sensing={t}` (not ranked with the rest)", "",
                    ("True velocities and radii of the pedestrians in range (CrowdNav's observable state): against "
                     "the same method's `positions` row above, what true velocities are worth." if t == "velocities"
                     else "Privileged: every pedestrian, any range, true velocities and radii — for debugging."), ""]
        if group.startswith("seeds"):
            out += [f"## {head} across training seeds", "",
                    f"Every shipped training seed of {head} on the same crowds; the last row gives the mean "
                    "success and, in brackets, its spread (max − min) over the seeds.", ""]
        for table in TABLES:
            settings = []
            for lb in labels:
                for r in board[lb]:
                    if r["table"] == table and r["row"] not in settings:
                        settings.append(r["row"])
            if not settings:
                continue
            best = {s: _clear_best([r for lb in labels for r in board[lb] if r["table"] == table and r["row"] == s])
                    for s in settings}
            out += [f"### {TABLE_TITLES[table]}", "", "| method | " + " | ".join(settings) + " |",
                    "|---|" + "---|" * len(settings)]
            for lb in labels:
                by_row = {r["row"]: r for r in board[lb] if r["table"] == table}
                cellsx = []
                for s in settings:
                    r = by_row.get(s)
                    if r is None:
                        cellsx.append("—")
                        continue
                    if "error" in r:
                        cellsx.append("error")
                        continue
                    succ = f"{100 * r['success_rate']:.1f}"
                    if r is best[s]:
                        succ = f"**{succ}**"
                    ps = (f" · PS {100 * r['personal_space']:.0f}" if table == "IV" and "personal_space" in r
                          else "")
                    cellsx.append(f"{succ}{_ci(r, 'success_rate', 100, 0)} / {100 * r['collision_rate']:.1f} / "
                                  f"{100 * r['timeout_rate']:.1f} · " + (f"{r['nav_time']:.1f} s"
                                                                           if math.isfinite(r["nav_time"]) else "—")
                                  + ps)
                out.append(f"| {lb} | " + " | ".join(cellsx) + " |")
            if group.startswith("seeds"):
                stats = [_mean_spread(board, labels, table, s_) for s_ in settings]
                out.append(f"| mean [spread], {len(labels)} seeds | " + " | ".join(stats) + " |")
            out.append("")
        if group in ("main", "ablation"):
            families = {lb: [lb, *(x for x in board if groups.get(x, "main").startswith("seeds")
                                   and family(groups[x]) == lb)] for lb in labels}
            out += _over_seeds(board, families, planners, ablations=group == "ablation", budgets=budgets)
    return "\n".join(out)


def _mean_spread(board: dict[str, list[dict[str, Any]]], labels: list[str], table: str, row: str) -> str:
    """``"mean [max − min]"`` of the success rates [%] of ``labels`` in one setting (one value: just it)."""
    vals = [100 * r["success_rate"] for lb in labels for r in board[lb]
            if r["table"] == table and r["row"] == row and "error" not in r]
    if not vals:
        return "—"
    return f"{vals[0]:.1f}" if len(vals) == 1 else f"{sum(vals) / len(vals):.1f} [{max(vals) - min(vals):.1f}]"


def training_budgets(fingerprints: dict[str, dict[str, Any]]) -> dict[str, dict[str, int]]:
    """Each label's training budget (:func:`crowdbench.checkpoints.training_budget`), read from its checkpoint when
    the file on disk is the one its fingerprint names (same SHA-256); labels without a checkpoint, or whose file is
    missing or differs, are left out."""
    out = {}
    for label, fp in fingerprints.items():
        name, sha = (fp.get("kwargs") or {}).get("checkpoint"), fp.get("checkpoint_sha256")
        if not name or not sha:
            continue
        try:
            path = checkpoints.resolve(fp["policy"], name)
            if checkpoints.file_sha256(path) != sha:
                continue
            out[label] = checkpoints.training_budget(checkpoints.load(path, fp["policy"]))
        except (OSError, ValueError, KeyError):
            continue
    return out


def _budget_cell(budgets: list[dict[str, int]]) -> str:
    """``"29.5 M steps"``, ``"5.9–28.3 M steps"`` (the range over seeds) or ``"10,000 episodes"``; "—" unless every
    seed's budget is known."""
    for key, unit in (("env_steps", "M steps"), ("episodes", "episodes")):
        if budgets and all(key in b for b in budgets):
            vals = sorted(b[key] for b in budgets)
            lo, hi = ((f"{v / 1e6:.1f}" if key == "env_steps" else f"{v:,}") for v in (vals[0], vals[-1]))
            return f"{lo} {unit}" if lo == hi else f"{lo}–{hi} {unit}"
    return "—"


def _over_seeds(board: dict[str, list[dict[str, Any]]], families: dict[str, list[str]],
                planners: frozenset[str] = frozenset(), ablations: bool = False,
                budgets: dict[str, dict[str, int]] | None = None) -> list[str]:
    """The main methods' (or, with ``ablations``, the reference's and its ablations') headline settings (Tables I,
    II and III pooled) as mean success [spread] over each method's training seeds (``families``: main label → its
    seed labels, itself first); nothing when no method has several. The seed count is "—" for ``planners``
    (nothing trained). With ``budgets`` (label → :func:`crowdbench.checkpoints.training_budget`), a column gives
    each method's training per seed: env steps (PPO), or RL episodes (value methods)."""
    if all(len(f) < 2 for f in families.values()):
        return []
    settings = sorted(dict.fromkeys((r["table"], r["row"]) for lb in families for r in board[lb]
                                    if r["table"] != "III" or r["row"].startswith("pooled")),
                      key=lambda s: TABLES.index(s[0]))  # stable: each table's settings in board order
    intro = ("The paper's ablation question over training seeds: mean success [%] of the reference and each "
             "ablation over its shipped training seeds and, in brackets, the spread (max − min). The tables above "
             "show seed 0 of each." if ablations else
             "Mean success [%] over every shipped training seed of a method and, in brackets, its spread (max − min); "
             "a method with one row (one training seed, or a planner that is not trained) shows that row's value. "
             "The tables above show each learned method's default checkpoint; its seeds have their own tables below.")
    if budgets is not None:
        intro += (" *Training per seed*: the env steps of a PPO method (a fine-tune's counting those of the run it "
                  "started from) or the reinforcement-learning episodes of a value method, read from the "
                  "checkpoints — methods trained on different budgets are not compared like for like.")
    title = "### Ablations over their training seeds" if ablations else "### Every method over its training seeds"
    budget_head = ("training per seed | ", "---|") if budgets is not None else ("", "")
    out = [title, "", intro,
           "", f"| method | seeds | {budget_head[0]}" + " | ".join(f"Table {t} {row}" for t, row in settings) + " |",
           f"|---|---|{budget_head[1]}" + "---|" * len(settings)]
    for lb, fam in families.items():
        cells_ = [_mean_spread(board, fam, t, row) for t, row in settings]
        if budgets is not None:
            cells_.insert(0, "—" if lb in planners else _budget_cell([budgets.get(x, {}) for x in fam]))
        out.append(f"| {lb} | {'—' if lb in planners else len(fam)} | " + " | ".join(cells_) + " |")
    return [*out, ""]
