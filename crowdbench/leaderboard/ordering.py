"""The paper's orderings against the board's: for every two methods with a paper row, in how many of the paper's
nine settings (Table I's three regimes, Table II's three crowd sizes, Table III pooled per regime) one is above the
other — on the board (mean success over the method's shipped training seeds, from the stored cells) and in the
paper (its published numbers). Runs nothing; part of ``crowdbench leaderboard paper``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from crowdbench.leaderboard.compare import MAIN_KEYS, POOLED, compare, family, summary

PAPER_KEYS = (*MAIN_KEYS[:6], *POOLED)
"""The board's settings in the order of the paper's triples (``Method.paper``: ``I``, ``II``, ``III``)."""


@dataclass(frozen=True)
class Pair:
    """Methods ``a`` and ``b`` over the settings both have at every seed (``keys``): where ``a``'s seed mean is
    above / below ``b``'s (to 0.1 point; ``ours``), the seed pairs with Wilson intervals apart either way (``apart``:
    ``a`` ahead, ``b`` ahead, of ``pairs``), and the paper's counts on the same settings (``paper``: above, below)."""

    a: str
    b: str
    keys: tuple[str, ...]
    ours: tuple[int, int]
    apart: tuple[int, int]
    pairs: int
    paper: tuple[int, int]

    @staticmethod
    def _sign(c: tuple[int, int]) -> int:
        return (c[0] > c[1]) - (c[0] < c[1])

    @property
    def differs(self) -> bool:
        """Whether the majority order over the settings differs between the board and the paper (a tie on either
        side counts as an order of its own)."""
        return self._sign(self.ours) != self._sign(self.paper)


def _paper_values(rates: dict[str, tuple[int, int, int]]) -> dict[str, int]:
    """A paper row as ``setting → success [%]`` over :data:`PAPER_KEYS`."""
    return {k: rates[t][i] for t, ks in (("I", PAPER_KEYS[:3]), ("II", PAPER_KEYS[3:6]), ("III", PAPER_KEYS[6:]))
            if t in rates for i, k in enumerate(ks)}


def orderings(out: str | Path, paper: dict[str, dict[str, tuple[int, int, int]]],
              scenario: str | None = None) -> dict[str, Any]:
    """Every two methods of ``paper`` (name → its Tables I–III triples) that have stored cells under ``out``.

    Returns ``{"methods": [(name, seeds, mean)], "pairs": {(a, b): Pair}, "skipped": [(what, reason)],
    "paper_order": [(name, mean)], "settings": [key]}``: the methods (``seeds``: their entries) in the order of their
    mean success (in [0, 1]) over ``settings`` — those every method has —, highest first; a :class:`Pair` for each
    ordered pair; what was left out and why (a method without stored cells, or with cells of another crowd or of
    mixed suites; two methods whose cells differ in seeds or episodes); the paper's means [%] over ``settings``,
    highest first. ``scenario``: the crowd digest the cells must have been made on (default: the current crowd's)."""
    root = Path(out) / "cells"
    fams: dict[str, list[str]] = {}
    skipped: list[tuple[str, str]] = []
    for name in paper:
        try:
            fams[name] = family(root, name)
        except ValueError:
            skipped.append((name, "no stored cells"))
            continue
        try:
            compare(out, name, name, keys=PAPER_KEYS, scenario=scenario)  # its own cells: one crowd, one suite
        except ValueError as e:
            fams.pop(name)
            skipped.append((name, str(e)))
    results: dict[tuple[str, str], dict[str, Any]] = {}
    for i, a in enumerate(fams):
        for b in list(fams)[i + 1:]:
            try:
                results[a, b] = compare(out, a, b, keys=PAPER_KEYS, scenario=scenario)
            except ValueError as e:
                skipped.append((f"{a} against {b}", str(e)))
    means: dict[str, dict[str, float]] = {m: {} for m in fams}
    for (a, b), res in results.items():
        for r in res["rows"]:
            means[a][r["key"]], means[b][r["key"]] = r["mean_a"], r["mean_b"]
    common = [k for k in PAPER_KEYS if all(k in means[m] for m in fams)]
    order = sorted(fams, key=lambda m: -sum(means[m].get(k, 0.0) for k in common))
    pairs: dict[tuple[str, str], Pair] = {}
    for (a, b), res in results.items():
        keys = tuple(r["key"] for r in res["rows"])
        s = summary(res, keys=PAPER_KEYS)
        pa, pb = _paper_values(paper[a]), _paper_values(paper[b])
        pdiff = [pa[k] - pb[k] for k in keys if k in pa and k in pb]
        fwd = Pair(a, b, keys, (s["above"], s["below"]), (s["a_apart"], s["b_apart"]), s["pairs"],
                   (sum(d > 0 for d in pdiff), sum(d < 0 for d in pdiff)))
        pairs[a, b] = fwd
        pairs[b, a] = Pair(b, a, keys, fwd.ours[::-1], fwd.apart[::-1], fwd.pairs, fwd.paper[::-1])
    paper_mean = {m: sum(_paper_values(paper[m]).get(k, 0) for k in common) / max(len(common), 1) for m in fams}
    return {"methods": [(m, fams[m], sum(means[m].get(k, 0.0) for k in common) / max(len(common), 1))
                        for m in order], "pairs": pairs, "skipped": skipped,
            "paper_order": sorted(paper_mean.items(), key=lambda kv: -kv[1]), "settings": common}


def markdown(result: dict[str, Any], planners: frozenset[str] = frozenset()) -> str:
    """The orderings as markdown: a matrix of counts (board / paper) and the pairs whose order differs;
    ``planners``: methods that are not trained (labelled so, not by their number of seeds)."""
    methods = result["methods"]
    pairs: dict[tuple[str, str], Pair] = result["pairs"]
    out = ["## The paper's orderings, over training seeds", "",
           "For every two methods with a paper row: in how many of the paper's 9 settings (Table I's three "
           "regimes, Table II's three crowd sizes, Table III pooled per regime) the row's success is above the "
           "column's — *board*: the mean over the method's training seeds on the board (more than 0.1 point "
           "apart), *paper*: its published numbers. Methods in the order of their board mean over the settings.", ""]
    if not methods:
        return "\n".join([*out, "No method with a paper row has stored cells.", ""])
    names = [m for m, _, _ in methods]
    out += [f"| board / paper | {' | '.join(names)} |", "|---|" + "---|" * len(names)]
    for m, seeds, mean in methods:
        cells = ["—" if m == n else (f"{pairs[m, n].ours[0]} / {pairs[m, n].paper[0]}" if (m, n) in pairs else "")
                 for n in names]
        what = "planner" if m in planners else f"{len(seeds)} seed{'s' * (len(seeds) > 1)}"
        out.append(f"| **{m}** ({what}, mean {100 * mean:.1f}) | "
                   f"{' | '.join(cells)} |")
    n = len(result["settings"])
    board = " > ".join(f"{m} {100 * v:.1f}" for m, _, v in methods)
    paper = " > ".join(f"{m} {v:.1f}" for m, v in result["paper_order"])
    out += ["", f"Ranked by the mean over the {n} settings every method has: board {board}; paper {paper}."]
    differ = sorted((p for (a, b), p in pairs.items() if names.index(a) < names.index(b) and p.differs),
                    key=lambda p: (names.index(p.a), names.index(p.b)))
    out += ["", "Where the board's order differs from the paper's (majority of the settings; *apart*: seed pairs "
                "with Wilson 95 % intervals that do not overlap, either way):", ""]
    for p in differ:
        out.append(f"- **{p.a}** against **{p.b}**: board above in {p.ours[0]}, below in {p.ours[1]} of {len(p.keys)} "
                   f"(apart {p.apart[0]} / {p.apart[1]} of {p.pairs} seed pairs); paper above in {p.paper[0]}, "
                   f"below in {p.paper[1]}.")
    if not differ:
        out.append("- Nowhere.")
    for name, why in result["skipped"]:
        out.append(f"- Not compared: {name} ({why}).")
    return "\n".join(out) + "\n"
