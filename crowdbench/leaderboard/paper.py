"""The paper's published success rates, and a report of every board cell against them.

The report reads stored cells only (``OUT/cells/<entry>/<cell>.json``): it never runs an evaluation and never
changes a default. Nothing in crowdbench is chosen to match these numbers — they are set beside ours, out of
sample, so that a reader sees where the two agree and where they do not (``crowdbench leaderboard paper``).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from crowdbench.io import write_text
from crowdbench.leaderboard import ordering
from crowdbench.metrics import wilson
from crowdbench.policies import methods


def paper_rates() -> dict[str, dict[str, tuple[int, int, int]]]:
    """Success rates r_s [%] of the paper's Tables I–III per method (:attr:`crowdbench.policies.Method.paper`, from
    ``h2int.tex``): Table I — circle crossing, N = 20, ρ = 0.7 / 0.5 / 0.3; Table II — ρ = 0, N = 10 / 20 / 30;
    Table III — the three unseen layouts pooled, N = 30, ρ = 0.7 / 0.5 / 0.3."""
    return {m.name: dict(m.paper) for m in methods() if m.paper}


PAPER: dict[str, dict[str, tuple[int, int, int]]] = paper_rates()
"""The paper's success rates of the methods registered at import (:func:`paper_rates`)."""
ROWS = {"I": ("High", "Medium", "Low"), "II": ("N=10", "N=20", "N=30"),
        "III": ("pooled High", "pooled Medium", "pooled Low")}
"""The board's row labels in the order of :data:`PAPER`'s triples."""
LAYOUTS_III = ("intersection", "split_flow", "random_wander")


def _rate(cells: list[dict[str, Any]]) -> tuple[float, float, float, int]:
    """Pooled success rate of summary rows (equal weight per episode) and its Wilson 95 % interval: (r, lo, hi, n)."""
    n = sum(c["episodes"] for c in cells)
    k = round(sum(c["success_rate"] * c["episodes"] for c in cells))
    lo, hi = wilson(k, n)
    return k / n, lo, hi, n


def _cells_of(folder: Path) -> dict[str, dict[str, Any]]:
    """``cell key → stored outcome`` of one entry's cell folder."""
    out = {}
    for p in sorted(folder.glob("*.json")):
        try:
            out[p.stem] = json.loads(p.read_text())
        except (OSError, ValueError):
            continue
    return out


def _paper_method(fp: dict[str, Any]) -> str | None:
    """The paper row of a stored cell's fingerprint: its policy, when it is one of the paper's methods with its own
    (or one of its training seeds') checkpoint — ablations and outside checkpoints have none."""
    policy = fp.get("policy")
    if policy not in paper_rates():
        return None
    ckpt = (fp.get("kwargs") or {}).get("checkpoint")
    if ckpt is None:
        return policy
    stem = Path(str(ckpt)).stem
    return policy if stem == policy or stem.startswith(f"{policy}-seed") else None


def compare(out: str) -> list[dict[str, Any]]:
    """Every stored board cell of a paper method beside the paper's number: dicts with ``entry``, ``method``,
    ``sensing``, ``table``, ``row``, ``paper``, ``ours`` (r, lo, hi, n), ``check`` (same, or None) and ``agree``
    (whether the two evaluation ranges' intervals overlap; None without a check)."""
    rows: list[dict[str, Any]] = []
    root = Path(out) / "cells"
    for folder in sorted(p for p in root.glob("*") if p.is_dir()):
        cells = {k: v for k, v in _cells_of(folder).items() if "result" in v}
        if not cells:
            continue
        fp = next(iter(cells.values()))["fingerprint"]
        method = _paper_method(fp)
        if method is None:
            continue
        rates = paper_rates()[method]
        for table, labels in ROWS.items():
            if table not in rates:
                continue
            for i, label in enumerate(labels):
                if table == "III":
                    regime = label.split()[1].lower()
                    keys = [f"III-{lay.replace('_', '-')}-{regime}" for lay in LAYOUTS_III]
                else:
                    keys = [f"{table}-{''.join(ch if ch.isalnum() else '-' for ch in label.lower())}"]
                if not all(k in cells for k in keys):
                    continue
                ours = _rate([cells[k]["result"] for k in keys])
                checks = [cells[k].get("check") for k in keys]
                check = _rate(checks) if all(checks) else None
                agree = None if check is None else not (ours[2] < check[1] or check[2] < ours[1])
                rows.append({"entry": folder.name, "method": method, "sensing": fp.get("sensing", "?"),
                             "table": table, "row": label, "paper": rates[table][i], "ours": ours,
                             "check": check, "agree": agree, "scenario": fp.get("scenario")})
    return rows


def markdown(rows: list[dict[str, Any]], orders: str = "") -> str:
    """The comparison as markdown: ``orders`` (a section, e.g. :func:`crowdbench.leaderboard.ordering.markdown`),
    one table per entry, then the cells whose two evaluation ranges disagree."""
    def pct(r: tuple[float, float, float, int] | None) -> str:
        return "—" if r is None else f"{100 * r[0]:.1f} [{100 * r[1]:.0f}, {100 * r[2]:.0f}]"

    out = ["# The board against the paper", "",
           "Success r_s [%] of every stored cell (evaluation seed range of the suite, Wilson 95 % interval) beside "
           "the paper's Tables I–III; Table III pooled over its three layouts as the paper reports it. *check*: the "
           "same cell on a disjoint seed range (out of sample). Nothing was tuned to these numbers. Regenerate with "
           "`crowdbench leaderboard paper`.", ""]
    if orders:
        out += [orders]
    by_entry: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        by_entry.setdefault(r["entry"], []).append(r)
    for entry, rs in by_entry.items():
        out += [f"## {entry} (paper row: {rs[0]['method']}, sensing={rs[0]['sensing']})", "",
                "| table | setting | paper | ours | ours − paper | check | ranges agree |",
                "|---|---|---|---|---|---|---|"]
        for r in rs:
            diff = 100 * r["ours"][0] - r["paper"]
            agree = "—" if r["agree"] is None else ("yes" if r["agree"] else "**no**")
            out.append(f"| {r['table']} | {r['row']} | {r['paper']} | {pct(r['ours'])} | {diff:+.1f} | "
                       f"{pct(r['check'])} | {agree} |")
        diffs = [100 * r["ours"][0] - r["paper"] for r in rs]
        out += ["", f"Mean difference {sum(diffs) / len(diffs):+.1f} points, mean |difference| "
                f"{sum(abs(d) for d in diffs) / len(diffs):.1f} over {len(rs)} cells.", ""]
    bad = [r for r in rows if r["agree"] is False]
    out += ["## Where the two evaluation ranges disagree", ""]
    out += ([f"- {r['entry']} · Table {r['table']} {r['row']}: {pct(r['ours'])} against {pct(r['check'])}"
             for r in bad] or ["Nowhere: every cell's two intervals overlap."])
    return "\n".join(out) + "\n"


def report(out: str, path: str | None = None) -> str:
    """Write :func:`markdown` of :func:`compare` and of the orderings (:mod:`crowdbench.leaderboard.ordering`) to
    ``path`` (default ``OUT/PAPER.md``) and return it."""
    planners = frozenset(m.name for m in methods() if m.trainer is None)
    orders = ordering.markdown(ordering.orderings(out, paper_rates()), planners)
    text = markdown(compare(out), orders)
    write_text(path or os.path.join(out, "PAPER.md"), text)
    return text
