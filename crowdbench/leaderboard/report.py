"""The report: the stored cells as tables — each entry's ``OUT/<slug>.json|md``, ``OUT/LEADERBOARD.md`` (the paper's
tables with one row per method) and the figures (:mod:`crowdbench.leaderboard.figures`). The comparison with the
paper's published numbers is :mod:`crowdbench.leaderboard.paper`."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

from crowdbench import checkpoints
from crowdbench.io import write_text
from crowdbench.leaderboard.cells import cell_key, suite_digest
from crowdbench.leaderboard.entries import STALE, Entry, method_entries
from crowdbench.leaderboard.figures import plot_board
from crowdbench.leaderboard.suite import REGIMES, TABLES, Suite
from crowdbench.metrics import wilson
from crowdbench.policies import REFERENCE_METHOD


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

    def family(g: str) -> str:
        return g.split(":", 1)[1] if ":" in g else (reference or "")

    seeds_of = {lb: [lb, *(x for x in board if groups.get(x, "main").startswith("seeds")
                           and family(groups[x]) == lb)]
                for lb in board if groups.get(lb, "main") in ("main", "ablation")}  # each head → its seeds
    extra = {t: [lb for lb in board if tier[lb] == t] for t in ("velocities", "full")}
    extra = {t: lbs for t, lbs in extra.items() if lbs}
    for lbs in extra.values():
        for lb in lbs:
            groups = {**groups, lb: f"sensing:{tier[lb]}"}

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
            out += _over_seeds(board, {lb: seeds_of[lb] for lb in labels}, planners, ablations=group == "ablation",
                               budgets=budgets)
        if group.startswith("sensing"):
            t = group.split(":", 1)[1]
            pairs = {lb[: -len(t) - 1]: lb for lb in labels if lb in seeds_of and lb.endswith(f"-{t}")}
            pairs = {base: lb for base, lb in pairs.items() if base in seeds_of and tier[base] == "positions"}
            out += _tier_worth(board, {b: seeds_of[b] for b in pairs}, {b: seeds_of[lb] for b, lb in pairs.items()},
                               t, planners)
    return "\n".join(out)


def _tier_worth(board: dict[str, list[dict[str, Any]]], base: dict[str, list[str]], other: dict[str, list[str]],
                tier: str, planners: frozenset[str] = frozenset()) -> list[str]:
    """What sensing at ``tier`` is worth: for each method with rows at both tiers (``base``: its ``positions``
    family, main label → its training seeds' labels, itself first; ``other``: the same method's family at
    ``tier``), the mean success [%] over each family's seeds in the headline settings (Tables I, II and III pooled),
    ``positions → tier (difference in points)``; nothing when no method has both."""
    if not base:
        return []
    settings = sorted(dict.fromkeys((r["table"], r["row"]) for fam in (*base.values(), *other.values())
                                    for lb in fam for r in board[lb]
                                    if r["table"] != "III" or r["row"].startswith("pooled")),
                      key=lambda s: TABLES.index(s[0]))

    def mean(fam: list[str], table: str, row: str) -> float | None:
        vals = [100 * r["success_rate"] for lb in fam for r in board[lb]
                if r["table"] == table and r["row"] == row and "error" not in r]
        return sum(vals) / len(vals) if len(vals) == len(fam) else None

    out = [f"### What `sensing={tier}` is worth", "",
           f"Mean success [%] over each method's shipped training seeds at `sensing=positions` → at `sensing={tier}` "
           "(the same method given the richer input, a learned one trained with it too), and in brackets the "
           f"difference in points. Each method's seeds are counted as positions / {tier} (— for a planner: nothing "
           "trained).", "",
           "| setting | " + " | ".join(f"{name} ({'—' if name in planners else f'{len(fam)} / {len(other[name])}'})"
                                      for name, fam in base.items()) + " |",
           "|---|" + "---|" * len(base)]
    for t, row in settings:
        cells_ = []
        for name, fam in base.items():
            a, b = mean(fam, t, row), mean(other[name], t, row)
            cells_.append("—" if a is None or b is None else f"{a:.1f} → {b:.1f} ({b - a:+.1f})")
        out.append(f"| Table {t} {row} | " + " | ".join(cells_) + " |")
    return [*out, ""]


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


# ---------------------------------------------------------------------------------------------------- the board
def write_board(out: str, suite: Suite, entries: list[Entry], outcomes: dict[tuple[str, str], dict[str, Any]],
                fps: dict[str, dict[str, Any]], info: dict[str, Any]) -> dict[str, list[dict[str, Any]]]:
    """Write each entry's ``OUT/<slug>.json|md`` (results, fingerprint, provenance ``info``, wall time) from the
    cells' ``outcomes`` (``(label, cell key) → stored outcome``), ``OUT/LEADERBOARD.md`` and the figures
    (``success.png``; ``ablation.png`` when ablations are on the board); returns the result rows by label (an
    errored cell is a row with ``error``)."""
    grid = suite.grid()
    board: dict[str, list[dict[str, Any]]] = {}
    for e in entries:
        rows = []
        for c in grid:
            o = outcomes[(e.label, cell_key(c))]
            rows.append(o["result"] if "result" in o else
                        {"policy": e.label, "table": c.table, "row": c.row, "layout": c.layout, "humans": c.humans,
                         "responsiveness": c.rho, "seed": suite.seed, "error": o["error"]})
        board[e.label] = rows
        checks = [outcomes[(e.label, cell_key(c))].get("check") for c in grid]
        cpus = sorted({outcomes[(e.label, cell_key(c))].get("cpu") or "unrecorded" for c in grid})
        meta = {"fingerprint": fps[e.label], "label": e.label, "group": e.group, "suite": suite.to_dict(),
                "suite_digest": suite_digest(suite), "episodes": suite.episodes, "seed": suite.seed,
                "wall_s": round(sum(r.get("wall_s", 0.0) for r in rows), 1),
                "provenance": {**info, "cell_cpus": cpus}}
        doc: dict[str, Any] = {"meta": meta, "results": rows}
        if any(checks):
            doc["checks"] = [c for c in checks if c]
        write_text(os.path.join(out, f"{e.slug}.json"), json.dumps(doc, indent=2) + "\n")
        write_text(os.path.join(out, f"{e.slug}.md"), markdown(rows))
    everyone, groups, planners, every_fp = gather(out, suite, board, {e.label: e.group for e in entries},
                                                  {e.label: fps[e.label] for e in entries}, only=True)

    write_text(os.path.join(out, "LEADERBOARD.md"),
               leaderboard_markdown(everyone, groups, suite.episodes, suite.seed, suite=suite.name,
                                    planners=planners, budgets=training_budgets(every_fp),
                                    sensing={lb: fp.get("sensing", "positions") for lb, fp in every_fp.items()},
                                    missing={lb: why for lb, why in STALE.items() if lb not in everyone}))
    if {"I", "II"} & set(suite.tables):
        plot_board(everyone, os.path.join(out, "success.png"), groups, planners=planners,
                   sensing={lb: fp.get("sensing", "positions") for lb, fp in every_fp.items()})
        if "ablation" in groups.values():
            plot_board(everyone, os.path.join(out, "ablation.png"), groups, rows="ablation", planners=planners)
    return board




def gather(out: str, suite: Suite, board: dict[str, list[dict[str, Any]]], groups: dict[str, str],
           fingerprints: dict[str, dict[str, Any]], only: bool = False
           ) -> tuple[dict[str, list[dict[str, Any]]], dict[str, str], frozenset[str], dict[str, dict[str, Any]]]:
    """The run's ``board`` plus (unless ``only``: ``LEADERBOARD.md`` shows the methods asked for) every other method
    file in ``out`` scored on the same suite (same digest); in leaderboard order
    (:data:`~crowdbench.leaderboard.entries.METHODS`, each method's other training seeds after it, then the rest by
    label). Returns rows, groups, the planners (labels whose fingerprint has no checkpoint) and every label's
    fingerprint (``fingerprints`` for the run's entries, the stored one otherwise)."""
    rows, groups, fingerprints = {}, dict(groups), dict(fingerprints)
    for path in sorted(Path(out).glob("*.json")):
        try:
            d = json.loads(path.read_text())
        except (OSError, ValueError):
            continue
        meta = d.get("meta") if isinstance(d, dict) else None
        if only and isinstance(meta, dict) and meta.get("label") not in board:
            continue
        if isinstance(meta, dict) and meta.get("suite_digest") == suite_digest(suite) and "label" in meta:
            rows[meta["label"]] = d["results"]
            groups.setdefault(meta["label"], meta.get("group", "main"))
            fingerprints.setdefault(meta["label"], meta.get("fingerprint") or {})
    rows.update(board)
    order = [m.label for m in method_entries()]

    def key(label: str) -> tuple[int, int, str]:
        group = groups.get(label, "main")
        base = (group.split(":", 1)[1] if ":" in group else REFERENCE_METHOD) if group.startswith("seeds") else label
        return (order.index(base) if base in order else len(order), base != label, label)

    planners = frozenset(lb for lb in rows if not fingerprints.get(lb, {}).get("checkpoint_sha256"))
    return {lb: rows[lb] for lb in sorted(rows, key=key)}, groups, planners, fingerprints

