"""Compare two leaderboard folders, timing and provenance fields aside (the reproducibility check of the
leaderboard: regenerate into a fresh folder, then compare with the published one).

    crowdbench leaderboard run --suite paper --force --out /tmp/regenerated
    python scripts/compare_leaderboards.py leaderboards /tmp/regenerated

Exit status 0 when every method file, every stored cell and LEADERBOARD.md agree; otherwise the differences are listed,
each differing cell with the CPU models that made the two copies (a cell records its CPU; learned policies' closed loops
turn the last-bit rounding differences between instruction sets into different episodes, so a difference between two
CPU models is expected, one on the same model is a reproducibility failure).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

VOLATILE = {"wall_s", "provenance", "cpu"}


def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items() if k not in VOLATILE}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x


def main(a: str, b: str) -> int:
    a_dir, b_dir = Path(a), Path(b)
    files = sorted({p.relative_to(b_dir) for p in b_dir.rglob("*.json")} & {p.relative_to(a_dir)
                                                                            for p in a_dir.rglob("*.json")})
    bad: list[tuple[str, str]] = []  # (file, where the two copies were made)
    for f in files:
        a_doc, b_doc = (json.loads((d / f).read_text()) for d in (a_dir, b_dir))
        if strip(a_doc) != strip(b_doc):
            cpus = [doc.get("cpu", "unrecorded") for doc in (a_doc, b_doc)]
            where = ("" if f.parts[0] != "cells" else f" (same CPU: {cpus[0]})" if cpus[0] == cpus[1]
                     else f" (CPUs {cpus[0]} → {cpus[1]})")
            bad.append((f.as_posix(), where))
    if (a_dir / "LEADERBOARD.md").read_text() != (b_dir / "LEADERBOARD.md").read_text():
        bad.append(("LEADERBOARD.md", ""))
    print(f"compared {len(files)} JSON files and LEADERBOARD.md: {'identical' if not bad else 'DIFFERENT'}")
    for f, where in bad:
        print(f"  differs: {f}{where}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
