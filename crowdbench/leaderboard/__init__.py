"""The leaderboard, one module per step of the data's path through a run:

1. :mod:`~crowdbench.leaderboard.suite` — a suite's TOML file → the grid of cells (``suites/*.toml`` ship here);
2. :mod:`~crowdbench.leaderboard.entries` — the board's rows: shipped methods, their seeds, ``LABEL=POLICY``;
3. :mod:`~crowdbench.leaderboard.cells` — one entry on one cell: its key and all of its fingerprint;
4. :mod:`~crowdbench.leaderboard.store` — stored cells at ``OUT/cells/<entry>/<cell>.json``, reused while the
   fingerprint matches;
5. :mod:`~crowdbench.leaderboard.run` — the cells not stored, in this process, local workers or Ray tasks, faults
   isolated per cell;
6. :mod:`~crowdbench.leaderboard.report` — tables, ``LEADERBOARD.md``, :mod:`~crowdbench.leaderboard.figures`, and
   :mod:`~crowdbench.leaderboard.paper` (the board beside the paper's numbers);
7. :mod:`~crowdbench.leaderboard.verify` — stored cells re-evaluated and compared bit for bit.
8. :mod:`~crowdbench.leaderboard.compare` — two methods over their training seeds, setting by setting, from the
   stored cells; :mod:`~crowdbench.leaderboard.ordering` — every two methods with a paper row, the board's order
   beside the paper's (the head of ``PAPER.md``).

The names below are importable from the package itself (loaded on first use: importing the package is cheap).
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "suite": ("REGIMES", "SHIFT_MODELS", "SUITES_DIR", "TABLES", "Cell", "Suite", "grid", "load_suite", "suite_names"),
    "entries": ("ENTRIES", "METHODS", "STALE", "Entry", "board_entries", "method_entries", "parse_entry",
                "shipped_entries", "trained_crowd"),
    "cells": ("cell_key", "entry_sensing", "fingerprint", "policy_code", "scenario_digest", "suite_digest"),
    "store": ("CellStore",),
    "run": ("BACKENDS", "cpu_model", "evaluate_cells", "execute", "print_progress", "provenance", "run_cell",
            "run_suite"),
    "verify": ("Verdict", "verify_cells"),
    "report": ("SOCIAL", "TABLE_TITLES", "gather", "leaderboard_markdown", "markdown", "save", "training_budgets",
               "with_pooled", "write_board"),
    "figures": ("legend_label", "plot_board", "plot_trends"),
}
_WHERE = {name: module for module, names in _EXPORTS.items() for name in names}
__all__ = sorted(_WHERE)


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(f"{__name__}.{_WHERE[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
