"""The store: finished cells under ``OUT/cells/<entry>/<cell>.json``, each with the fingerprint it was computed
under (:func:`crowdbench.leaderboard.cells.fingerprint`), written atomically the moment the cell finishes. A run
that is killed loses only the cells in flight; the next run reuses every stored cell whose fingerprint matches."""

from __future__ import annotations

import json
import os
from typing import Any

from crowdbench.io import write_text
from crowdbench.leaderboard.cells import cell_key
from crowdbench.leaderboard.entries import Entry
from crowdbench.leaderboard.suite import Cell


class CellStore:
    """Finished cells under ``out/cells/<entry slug>/<table>-<row>.json`` (atomic writes)."""

    def __init__(self, out: str) -> None:
        self.root = os.path.join(out, "cells")

    def path(self, entry: Entry, cell: Cell) -> str:
        return os.path.join(self.root, entry.slug, f"{cell_key(cell)}.json")

    def read(self, entry: Entry, cell: Cell) -> dict[str, Any] | None:
        """The stored file as it is (fingerprint, outcome, ``cpu``), whatever it was computed under; ``None`` when
        there is none or it cannot be read."""
        try:
            with open(self.path(entry, cell)) as f:
                return json.load(f)
        except (FileNotFoundError, json.JSONDecodeError):
            return None

    def get(self, entry: Entry, cell: Cell, fp: dict[str, Any]) -> dict[str, Any] | None:
        """The stored outcome if computed under ``fp`` (errors are not reused: they are retried)."""
        saved = self.read(entry, cell)
        if saved is None or saved.get("fingerprint") != fp or "result" not in saved:
            return None
        return saved

    def put(self, entry: Entry, cell: Cell, fp: dict[str, Any], outcome: dict[str, Any]) -> None:
        """Store ``outcome`` (``{"result": …}`` or ``{"error": …}``, with ``cpu``) under ``fp``, atomically."""
        write_text(self.path(entry, cell), json.dumps({"fingerprint": fp, **outcome}, indent=1) + "\n")
