"""Cells: a cell is one entry (a board row) on one setting of the suite's grid, the unit of work and of storage;
this module holds its key and **all of its fingerprint** — what a stored cell must match to be reused.

The fingerprint (:func:`fingerprint`) names the policy, its arguments, its sensing tier, the checkpoint's SHA-256,
the digest of the policy's source files (:func:`policy_code`), the crowdbench version, the episodes and the seed,
the scenario (:func:`scenario_digest`), the suite's settings (:func:`suite_digest`), the worlds per batch and
whether the robot-absent twin runs. Its keys and their order are those of the stored cells in ``leaderboards/``.
"""

from __future__ import annotations

import hashlib
import inspect
import json
import os
from pathlib import Path
from typing import Any

from crowdbench import __version__, checkpoints
from crowdbench.leaderboard.entries import Entry
from crowdbench.leaderboard.suite import Cell, Suite, grid
from crowdbench.policies import POLICIES, make_policy
from crowdbench.worlds.digest import crowd_digest

POLICIES_DIR = Path(__file__).resolve().parents[1] / "policies"
"""Where the method sub-packages live (``crowdbench/policies/<method>/``): all of one is the method's code."""


def cell_key(cell: Cell) -> str:
    """The file stem of a stored cell: ``<table>-<row>`` with the row lower-cased and non-alphanumerics as ``-``."""
    row = "".join(ch if ch.isalnum() else "-" for ch in cell.row.lower())
    return f"{cell.table}-{row}"


def scenario_digest(tables: tuple[str, ...] = ("I", "II", "III")) -> str:
    """SHA-256 (16 hex digits) of everything that defines the crowds of the grid (:func:`~crowdbench.worlds.digest.
    crowd_digest` over its layouts and pedestrian models) — a cached result is stale when the scenario changes."""
    cells = grid(tables)
    return crowd_digest(tuple(sorted({c.layout for c in cells})), tuple(sorted({c.model for c in cells})))


def suite_digest(suite: Suite) -> str:
    """SHA-256 (16 hex digits) of what a suite's numbers depend on: its settings (name and description aside)
    and the scenario of its tables (:func:`scenario_digest`)."""
    d = {k: v for k, v in suite.to_dict().items() if k not in ("name", "description")}
    text = json.dumps(d, sort_keys=True) + scenario_digest(suite.tables)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def policy_code(policy: str) -> str:
    """SHA-256 (16 hex digits) of the source a registered robot policy runs: the file defining its class and every
    base class (outside the standard library and torch), plus every ``.py`` file of a method sub-package
    (``crowdbench/policies/<method>/``) among them — a plug-in's own files included. A stored cell is stale once
    any of them changes."""
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
        if path.parent.parent == POLICIES_DIR:  # a method sub-package: all of it
            files.update(path.parent.glob("*.py"))
    h = hashlib.sha256()
    for path in sorted(files):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def entry_sensing(entry: Entry) -> str:
    """The sensing tier of an entry's policy (built with its arguments: a checkpoint may set it)."""
    return make_policy(entry.policy, **entry.policy_kwargs()).sensing


def fingerprint(entry: Entry, suite: Suite) -> dict[str, Any]:
    """What a stored cell of ``entry`` on ``suite`` must match to be reused (every cell of an entry on a suite
    shares it; the cell's own setting is its key, :func:`cell_key`)."""
    kwargs = entry.policy_kwargs()
    digest = None
    ckpt = kwargs.get("checkpoint")
    if ckpt:
        ckpt = checkpoints.resolve(entry.policy, ckpt)  # a path, or the name of a shipped checkpoint
    if ckpt and os.path.exists(ckpt):
        digest = checkpoints.file_sha256(ckpt)
    shown = {k: (v if k != "checkpoint" or not os.path.exists(v) else os.path.relpath(v)) for k, v in kwargs.items()}
    return {"policy": entry.policy, "kwargs": shown, "sensing": entry_sensing(entry), "checkpoint_sha256": digest,
            "code": policy_code(entry.policy), "crowdbench": __version__, "episodes": suite.episodes,
            "seed": suite.seed, "scenario": scenario_digest(), "suite": suite_digest(suite), "worlds": suite.worlds,
            "counterfactual": suite.counterfactual}


FINGERPRINT_KEYS = ("policy", "kwargs", "sensing", "checkpoint_sha256", "code", "crowdbench", "episodes", "seed",
                    "scenario", "suite", "worlds", "counterfactual")
"""The fingerprint's keys in their stored order."""
