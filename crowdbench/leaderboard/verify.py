"""Verification: re-evaluate stored cells and compare every number with the stored one, bit for bit.

A stored cell is reused while its fingerprint matches (:mod:`~crowdbench.leaderboard.cells`); the fingerprint names
the policy's own files, its checkpoint, the scenario's settings and the crowdbench version, but not every line of
shared code a policy runs (the networks' building blocks, the compiled kernels, the observation builders). Verifying
recomputes a cell under its fingerprint and compares the result (and the check-seed result) field by field: equal
floats, NaN equal to NaN, the wall-clock time left out. A cell that differs was made by other code or on another
instruction set (``cpu`` is shown beside it: a learned policy's closed loop can differ in the last bits between
CPUs) — either way the stored number is not what this checkout computes, and ``crowdbench leaderboard run --force``
remakes it.

Statuses: ``identical``; ``differs`` (the fields that do); ``stale`` (the fingerprint no longer matches: ``run``
would recompute it anyway; not re-evaluated); ``missing`` (not stored, or unreadable); ``error`` (the
re-evaluation raised).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

from crowdbench.leaderboard.cells import cell_key, fingerprint
from crowdbench.leaderboard.entries import Entry
from crowdbench.leaderboard.run import check_backend, execute
from crowdbench.leaderboard.store import CellStore
from crowdbench.leaderboard.suite import Suite

IGNORED = ("wall_s",)
"""Result fields that may differ between two evaluations of the same cell (timing)."""


@dataclass
class Verdict:
    """The outcome of verifying one stored cell."""

    label: str
    """The entry's label (its board row)."""
    cell: str
    """The cell's key (``<table>-<row>``)."""
    status: str
    """``identical``, ``differs``, ``stale``, ``missing`` or ``error``."""
    differences: dict[str, tuple[Any, Any]] = field(default_factory=dict)
    """``part.field`` → (stored, now) for every field that differs (``differs``), or fingerprint key → (stored, now)
    (``stale``)."""
    cpu: tuple[str | None, str | None] = (None, None)
    """The CPU that made the stored cell and this one."""
    seconds: float = 0.0
    """Wall-clock time of the re-evaluation [s], to 0.1 s (a cell quicker than 0.05 s shows 0.0)."""


def same(a: Any, b: Any) -> bool:
    """Equality of stored values, NaN equal to NaN, recursing into lists and dicts."""
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    return type(a) is type(b) and a == b


def compare(stored: dict[str, Any], now: dict[str, Any]) -> dict[str, tuple[Any, Any]]:
    """The fields of a cell outcome's ``result`` and ``check`` that differ between ``stored`` and ``now`` (``error``
    too, if either has one): ``"result.success_rate"`` → (stored, now); :data:`IGNORED` fields left out. The stored
    side is read back from JSON, so ``now`` is round-tripped through JSON first (tuples become lists)."""
    now = json.loads(json.dumps(now))
    out: dict[str, tuple[Any, Any]] = {}
    for part in ("result", "check", "error"):
        a, b = stored.get(part), now.get(part)
        if not (isinstance(a, dict) and isinstance(b, dict)):
            if not same(a, b):
                out[part] = (a, b)
            continue
        for k in sorted(set(a) | set(b)):
            if k not in IGNORED and not same(a.get(k), b.get(k)):
                out[f"{part}.{k}"] = (a.get(k), b.get(k))
    return out


def verify_cells(suite: Suite, entries: list[Entry], out: str, cells: list[str] | None = None, workers: int = 1,
                 backend: str = "local", ray_address: str | None = None) -> list[Verdict]:
    """Re-evaluate the stored cells ``cells`` (keys; ``None``: every cell of the suite) of each entry under ``out``
    and compare them with the stored outcomes; returns one :class:`Verdict` per (entry, cell), in order."""
    check_backend(backend, workers)
    keys = {cell_key(c): c for c in suite.grid()}
    unknown = [k for k in cells or () if k not in keys]
    if unknown:
        raise ValueError(f"--cells {','.join(unknown)}: not cells of suite {suite.name!r}; valid choices: "
                         f"{', '.join(keys)}")
    chosen = [keys[k] for k in cells] if cells else list(keys.values())
    store = CellStore(out)
    verdicts: dict[tuple[str, str], Verdict] = {}
    todo, saved = [], {}
    for e in entries:
        fp = fingerprint(e, suite)
        for c in chosen:
            key = (e.label, cell_key(c))
            stored = store.read(e, c)
            if stored is None:
                verdicts[key] = Verdict(*key, "missing")
                continue
            old = stored.get("fingerprint", {})
            if old != fp:
                verdicts[key] = Verdict(*key, "stale", {k: (old.get(k), fp[k]) for k in fp if old.get(k) != fp[k]})
                continue
            saved[key] = stored
            todo.append((e, c, suite))
    for (e, c, _), outcome in execute(todo, workers, backend, ray_address):
        key = (e.label, cell_key(c))
        stored = saved[key]
        diff = compare(stored, outcome)
        status = "error" if "error" in outcome else "differs" if diff else "identical"
        seconds = float(outcome.get("result", outcome).get("wall_s", 0.0))
        verdicts[key] = Verdict(*key, status, diff, (stored.get("cpu"), outcome.get("cpu")), seconds)
    return [verdicts[(e.label, cell_key(c))] for e in entries for c in chosen]


def markdown(verdicts: list[Verdict]) -> str:
    """A table of verdicts: entry, cell, status, what differs (at most three fields), CPUs (stored → now)."""
    lines = ["| entry | cell | status | differences | cpu (stored → now) |", "|---|---|---|---|---|"]
    for v in verdicts:
        shown = "; ".join(f"{k}: {a!r} → {b!r}" for k, (a, b) in list(v.differences.items())[:3])
        more = len(v.differences) - 3
        shown += f"; {more} more" if more > 0 else ""
        cpu = f"{v.cpu[0]} → {v.cpu[1]}" if v.cpu[1] else ""
        lines.append(f"| {v.label} | {v.cell} | {v.status} | {shown} | {cpu} |")
    return "\n".join(lines)
