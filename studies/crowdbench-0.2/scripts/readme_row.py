"""Print a method's README row (Tables I and II, Table III pooled per ρ, Table I timeouts) from ``leaderboards/M.json``.

Usage: ``python studies/crowdbench-0.2/scripts/readme_row.py sarl``.
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict


def row(slug: str) -> str:
    with open(f"leaderboards/{slug}.json") as f:
        res = json.load(f)["results"]
    by = {(r["table"], r["row"], r.get("layout")): r for r in res}
    t1 = [by[("I", k, "circle_crossing")] for k in ("High", "Medium", "Low")]
    t2 = [by[("II", k, "circle_crossing")] for k in ("N=10", "N=20", "N=30")]
    pooled: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0])
    for r in res:
        if r["table"] == "III":
            regime = r["row"].split()[-1]  # "intersection High" → High
            pooled[regime][0] += r["success_rate"] * r["episodes"]
            pooled[regime][1] += r["episodes"]
    t3 = [pooled[k][0] / pooled[k][1] for k in ("High", "Medium", "Low")]

    def pct(xs: list[float]) -> str:
        return " / ".join(f"{100 * x:.1f}" for x in xs)

    return (f"| {slug} | {pct([r['success_rate'] for r in t1])} | {pct([r['success_rate'] for r in t2])} | "
            f"{pct(t3)} | {pct([r['timeout_rate'] for r in t1])} |")


if __name__ == "__main__":
    for slug in sys.argv[1:]:
        print(row(slug))
