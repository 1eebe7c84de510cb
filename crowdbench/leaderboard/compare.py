"""Two methods over their training seeds, cell by cell, from the stored cells (runs nothing): each method's mean
success, the difference, and how many pairs of seeds (one of each method) have Wilson 95 % intervals that do not
overlap, either way — the figures behind the claims page's "which of the paper's claims hold".

A method is a family of board entries: ``LABEL`` stands for the stored entries ``LABEL`` and ``LABEL-seed<k>``
(``OUT/cells/<slug>/``), or name them, comma-separated (``LABEL,``: that entry alone). Only cells made on the same
crowds are compared: every compared cell of a setting must share the fingerprint's ``scenario``, ``seed``,
``episodes`` and ``suite``, and the scenario must be the current crowd's
(:func:`~crowdbench.leaderboard.cells.scenario_digest`)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from crowdbench.leaderboard.entries import seed_names
from crowdbench.metrics import wilson

MAIN_KEYS = ("I-high", "I-medium", "I-low", "II-n-10", "II-n-20", "II-n-30",
             *(f"III-{layout}-{regime}" for layout in ("intersection", "split-flow", "random-wander")
               for regime in ("high", "medium", "low")))
"""The 15 cells of Tables I–III (the paper's claims are about these)."""
POOLED = {f"III-pooled-{regime}": tuple(f"III-{layout}-{regime}" for layout in ("intersection", "split-flow",
                                                                               "random-wander"))
          for regime in ("high", "medium", "low")}
"""Table III pooled over its three layouts per response regime (the paper's presentation): successes and episodes
summed."""
LIKE_FOR_LIKE = ("scenario", "seed", "episodes", "suite")
"""Fingerprint fields every compared cell of a setting must share."""


@dataclass(frozen=True)
class Rate:
    """A success count ``k`` of ``n`` episodes, with its Wilson 95 % interval."""

    k: int
    n: int

    @property
    def rate(self) -> float:
        return self.k / self.n

    @property
    def interval(self) -> tuple[float, float]:
        return wilson(self.k, self.n)


def apart(a: Rate, b: Rate) -> int:
    """+1 when ``a``'s interval lies wholly above ``b``'s, −1 when wholly below, 0 when they overlap."""
    (alo, ahi), (blo, bhi) = a.interval, b.interval
    return 1 if alo > bhi else -1 if ahi < blo else 0


def family(root: Path, spec: str) -> list[str]:
    """The stored entries of a method: ``LABEL`` → ``LABEL`` and its ``LABEL-seed<k>`` (seed order), or an explicit
    comma-separated list (``LABEL,`` is that entry alone); each must have a folder under ``root``
    (``OUT/cells``)."""
    names = [s.strip() for s in spec.split(",") if s.strip()]
    stored = sorted(p.name for p in root.iterdir() if p.is_dir()) if root.is_dir() else []
    if "," not in spec:  # a label: the family; "LABEL," is the entry alone
        names += [n for _, n in seed_names(names[0], stored)]
    missing = [n for n in names if n not in stored]
    if not names or missing:
        what = ", ".join(missing) if missing else repr(spec)
        raise ValueError(f"method {spec!r}: no stored cells for {what} under {root}; valid choices: "
                         f"{', '.join(stored) or 'none'}")
    return names


def _read(root: Path, entry: str, key: str) -> tuple[Rate, dict[str, Any]] | None:
    try:
        d = json.loads((root / entry / f"{key}.json").read_text())
        r = d["result"]
    except (OSError, ValueError, KeyError):
        return None
    return Rate(round(r["success_rate"] * r["episodes"]), r["episodes"]), d.get("fingerprint") or {}


def stored_keys(root: Path, entries: list[str]) -> tuple[str, ...]:
    """The settings to compare in ``root`` (``OUT/cells``): Tables I–III and Table III pooled, then every other cell
    stored for all of ``entries`` (e.g. Table IV's, or another suite's such as ``shift``'s Table V), sorted."""
    common = set.intersection(*({f.stem for f in (root / e).glob("*.json")} for e in entries))
    return (*MAIN_KEYS, *POOLED, *sorted(common - set(MAIN_KEYS)))


def compare(out: str | Path, a: str, b: str, keys: tuple[str, ...] | None = None,
            scenario: str | None = None) -> dict[str, Any]:
    """Methods ``a`` and ``b`` (:func:`family` specs) in the cells ``keys`` of the leaderboard folder ``out``
    (default: :func:`stored_keys`).

    Returns ``{"a": [entries], "b": [entries], "rows": [...]}``, a row per setting both methods have at every seed:
    ``key``, ``a`` and ``b`` (the :class:`Rate` of each seed), ``mean_a``, ``mean_b`` (mean success over seeds, in
    [0, 1]) and ``pairs`` (:func:`apart` of every (a seed, b seed) pair). ``scenario``: the crowd digest the cells
    must have been made on (default: the current crowd's)."""
    from crowdbench.leaderboard.cells import scenario_digest

    root = Path(out) / "cells"
    fa, fb = family(root, a), family(root, b)
    keys = stored_keys(root, [*fa, *fb]) if keys is None else keys
    scenario = scenario or scenario_digest()
    rows = []
    for key in keys:
        parts = POOLED.get(key, (key,))
        rates: dict[str, Rate] = {}
        seen: dict[str, tuple[str, Any]] = {}
        for entry in (*fa, *fb):
            got = [_read(root, entry, p) for p in parts]
            if any(g is None for g in got):
                break
            for part, (_, fp) in zip(parts, got, strict=True):
                for field in LIKE_FOR_LIKE:
                    value = fp.get(field)
                    first = seen.setdefault(field, (f"{entry}/{part}", value))
                    if value != first[1]:
                        raise ValueError(f"{key}: fingerprint field {field!r} differs between {first[0]} "
                                         f"({first[1]!r}) and {entry}/{part} ({value!r}); compare cells of one suite")
                if fp.get("scenario") != scenario:
                    raise ValueError(f"{entry}/{part}: made on crowd {fp.get('scenario')!r}, not the current "
                                     f"{scenario!r}; re-run it (crowdbench leaderboard run)")
            rates[entry] = Rate(sum(g[0].k for g in got), sum(g[0].n for g in got))
        else:
            ra, rb = [rates[e] for e in fa], [rates[e] for e in fb]
            rows.append({"key": key, "a": ra, "b": rb, "mean_a": sum(r.rate for r in ra) / len(ra),
                         "mean_b": sum(r.rate for r in rb) / len(rb), "pairs": [apart(x, y) for x in ra for y in rb]})
    return {"a": fa, "b": fb, "rows": rows}


def summary(result: dict[str, Any], keys: tuple[str, ...] | None = MAIN_KEYS) -> dict[str, int]:
    """Counts over the settings ``keys`` (default: the 15 of Tables I–III; ``None``: every compared setting): where
    ``a``'s mean is above, equal to or below ``b``'s (to 0.1 point), and the seed pairs with intervals apart either
    way, of how many."""
    rows = [r for r in result["rows"] if keys is None or r["key"] in keys]
    diff = [round(100 * (r["mean_a"] - r["mean_b"]), 1) for r in rows]
    pairs = [p for r in rows for p in r["pairs"]]
    return {"settings": len(rows), "above": sum(d > 0 for d in diff), "equal": sum(d == 0 for d in diff),
            "below": sum(d < 0 for d in diff), "pairs": len(pairs), "a_apart": pairs.count(1),
            "b_apart": pairs.count(-1), "a_apart_settings": sum(1 in r["pairs"] for r in rows),
            "b_apart_settings": sum(-1 in r["pairs"] for r in rows)}


def markdown(result: dict[str, Any]) -> str:
    """The comparison as a markdown table and a summary sentence."""
    fa, fb = result["a"], result["b"]
    a, b = fa[0], fb[0]
    out = [f"**{a}** ({len(fa)} seed{'s' * (len(fa) > 1)}: {', '.join(fa)}) against **{b}** ({len(fb)} "
           f"seed{'s' * (len(fb) > 1)}: {', '.join(fb)}); success [%], mean over seeds; *apart*: pairs of seeds (one "
           f"of each) whose Wilson 95 % intervals do not overlap, {a} ahead / {b} ahead, of {len(fa) * len(fb)}.", "",
           f"| setting | {a} | {b} | {a} − {b} | apart |", "|---|---|---|---|---|"]
    for r in result["rows"]:
        seeds_a = " · ".join(f"{100 * x.rate:.1f}" for x in r["a"])
        seeds_b = " · ".join(f"{100 * x.rate:.1f}" for x in r["b"])
        out.append(f"| {r['key']} | {100 * r['mean_a']:.1f} ({seeds_a}) | {100 * r['mean_b']:.1f} ({seeds_b}) | "
                   f"{100 * (r['mean_a'] - r['mean_b']):+.1f} | {r['pairs'].count(1)} / {r['pairs'].count(-1)} |")
    s, where = summary(result), "of Tables I–III"
    if not s["settings"]:  # another suite's board (e.g. Table V): every setting compared
        s, where = summary(result, keys=None), "compared"
    if s["settings"]:
        out += ["", f"Over the {s['settings']} settings {where}: {a}'s mean above {b}'s in {s['above']}, equal "
                    f"in {s['equal']}, below in {s['below']}; seed pairs apart: {a} ahead in {s['a_apart']} (in "
                    f"{s['a_apart_settings']} settings), {b} ahead in {s['b_apart']} (in {s['b_apart_settings']} "
                    f"settings), of {s['pairs']}."]
    return "\n".join(out)
