"""Leaderboard runs: suites, one task per (method, cell), every finished cell stored as it finishes, executed in this
process, in local worker processes or as Ray tasks.

* **Suites** are small TOML files (``crowdbench/suites/*.toml``: ``paper`` — Tables I–III, 500 episodes per cell,
  the published seed; ``quick`` — minutes, for trying a new policy). :func:`load_suite` validates them.
* **Cells are the unit of work and of storage**: ``OUT/cells/<method>/<table>-<row>.json``, written atomically the
  moment the cell finishes, with the fingerprint it was computed under (policy, arguments, checkpoint SHA-256,
  episodes, seed, suite and scenario digests). A run that is killed loses only the cells in flight; the next run
  reuses every stored cell whose fingerprint matches and computes the rest.
* **Fault isolation**: a cell whose policy (or pedestrian model) raises, returns NaN/inf or the wrong shape is stored
  with its error; every other cell completes. The method's tables show ``error`` there.
* **Determinism**: a cell's numbers depend only on its fingerprint — not on the backend, the number of workers or
  the order — so local, multi-process and Ray runs give identical files (timing and provenance fields aside).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import sys
import time
import tomllib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from crowdbench.bench import cpu_model
from crowdbench.io import write_text
from crowdbench.leaderboard import (
    STALE,
    TABLES,
    Cell,
    Entry,
    _fingerprint,
    cells,
    evaluate_cells,
    leaderboard_markdown,
    markdown,
    method_entries,
    plot_board,
    scenario_digest,
    training_budgets,
)
from crowdbench.policies import REFERENCE_METHOD
from crowdbench.validate import check_fields

SUITES_DIR = Path(__file__).resolve().parent / "suites"
BACKENDS = ("local", "ray")
PACKAGES = ("numpy", "torch", "pymunk", "numba", "pettingzoo", "gymnasium", "rsl-rl-lib")


@dataclass(frozen=True)
class Suite:
    """An evaluation suite (a TOML file in :data:`SUITES_DIR`, or any path)."""

    name: str
    """Short name (the file's stem for shipped suites)."""
    description: str = ""
    episodes: int = 500
    """Episodes per cell."""
    seed: int = 0
    """Evaluation seed: episode k of every cell runs world seed ``seed + k``."""
    check_seed: int | None = None
    """A second, disjoint evaluation seed range: every cell is evaluated there too and stored beside its result
    (``check``), out of sample — the two must agree within their intervals (``crowdbench leaderboard paper``
    reports where they do not). None: no check."""
    tables: tuple[str, ...] = ("I", "II", "III")
    """Which tables (their cells: :func:`crowdbench.leaderboard.cells`): the paper's I–III and IV, real crowds."""
    rows: tuple[str, ...] = ()
    """Optional subset of the tables' cells by ``TABLE/ROW`` (e.g. ``"III/split_flow Medium"``); empty = all."""
    worlds: int = 100
    """Worlds stepped together per cell."""
    counterfactual: bool = True
    """Run the robot-absent twin for the pedestrians' delay (doubles the crowd simulation)."""

    def __post_init__(self) -> None:
        check_fields(self)
        if not self.name:
            raise ValueError(f"suite name={self.name!r}; valid choices: a non-empty string")
        for key in ("episodes", "worlds"):
            if not isinstance(getattr(self, key), int) or getattr(self, key) < 1:
                raise ValueError(f"suite {self.name!r}: {key}={getattr(self, key)!r}; valid choices: an integer ≥ 1")
        if not isinstance(self.seed, int) or self.seed < 0:
            raise ValueError(f"suite {self.name!r}: seed={self.seed!r}; valid choices: an integer ≥ 0")
        if self.check_seed is not None and (not isinstance(self.check_seed, int)
                                            or abs(self.check_seed - self.seed) < self.episodes):
            raise ValueError(f"suite {self.name!r}: check_seed={self.check_seed!r}; valid choices: None or an integer "
                             f"at least episodes={self.episodes} away from seed={self.seed} (disjoint world seeds)")
        object.__setattr__(self, "tables", tuple(self.tables))
        object.__setattr__(self, "rows", tuple(self.rows))
        bad = [t for t in self.tables if t not in TABLES]
        if bad or not self.tables:
            raise ValueError(f"suite {self.name!r}: tables={list(self.tables)}; valid choices: a non-empty subset of "
                             f"{', '.join(TABLES)}")
        known = {f"{c.table}/{c.row}" for c in cells(self.tables)}
        unknown = sorted(set(self.rows) - known)
        if unknown:
            raise ValueError(f"suite {self.name!r}: rows {unknown} are not cells of tables {list(self.tables)}; "
                             f"valid choices: {', '.join(sorted(known))}")

    def grid(self) -> list[Cell]:
        return [c for c in cells(self.tables) if not self.rows or f"{c.table}/{c.row}" in self.rows]

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["tables"], d["rows"] = list(self.tables), list(self.rows)
        return d

    def digest(self) -> str:
        """SHA-256 (16 hex digits) of what the suite's numbers depend on: its settings (name and description aside)
        and the scenario (:func:`crowdbench.leaderboard.scenario_digest`)."""
        d = {k: v for k, v in self.to_dict().items() if k not in ("name", "description")}
        text = json.dumps(d, sort_keys=True) + scenario_digest(self.tables)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


def suite_names() -> list[str]:
    return sorted(p.stem for p in SUITES_DIR.glob("*.toml"))


def load_suite(name_or_path: str, **overrides: Any) -> Suite:
    """A shipped suite by name or a TOML file by path; ``overrides`` (e.g. ``episodes=50``) replace its fields.
    Unknown keys and bad values are one clear error."""
    path = Path(name_or_path)
    if not path.suffix:
        path = SUITES_DIR / f"{name_or_path}.toml"
        if not path.exists():
            raise ValueError(f"--suite {name_or_path!r}: no such suite; valid choices: {', '.join(suite_names())} "
                             "or a path to a .toml file")
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ValueError(f"--suite {str(path)!r}: file not found") from None
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"suite file {str(path)!r} is not valid TOML: {e}") from None
    data.setdefault("name", path.stem)
    data.update({k: v for k, v in overrides.items() if v is not None})
    fields = {f.name for f in dataclasses.fields(Suite)}
    unknown = sorted(set(data) - fields)
    if unknown:
        raise ValueError(f"suite {str(path)!r}: unknown keys {unknown}; valid choices: {', '.join(sorted(fields))}")
    return Suite(**data)


# ---------------------------------------------------------------------------------------------------- provenance
def provenance() -> dict[str, Any]:
    """Crowdbench version and commit, Python and package versions and CPU model of this run (the machine that wrote
    the file; each cell records the CPU it ran on, see :func:`run_cell`)."""
    import platform
    import subprocess
    from importlib import metadata

    from crowdbench import __version__

    root = Path(__file__).resolve().parent.parent
    commit = None
    if (root / ".git").exists():
        try:
            commit = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                                    timeout=10).stdout.strip() or None
        except (OSError, subprocess.SubprocessError):
            commit = None
    versions = {}
    for name in PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None

    return {"crowdbench": __version__, "commit": commit, "python": platform.python_version(), "cpu": cpu_model(),
            "packages": versions}


def fingerprint(entry: Entry, suite: Suite) -> dict[str, Any]:
    """What a stored cell must match to be reused."""
    fp = _fingerprint(entry, suite.episodes, suite.seed)
    return {**fp, "suite": suite.digest(), "worlds": suite.worlds, "counterfactual": suite.counterfactual}


# ---------------------------------------------------------------------------------------------------- one cell
def cell_key(cell: Cell) -> str:
    row = "".join(ch if ch.isalnum() else "-" for ch in cell.row.lower())
    return f"{cell.table}-{row}"


def run_cell(entry: Entry, cell: Cell, suite: Suite) -> dict[str, Any]:
    """Evaluate one cell, isolating faults: ``{"result": row, "cpu": model}`` or ``{"error": "Type: message", ...}``.
    ``cpu`` names the machine's CPU: a learned policy's closed loop can differ in the last bits between instruction
    sets (``docs/leaderboard/index.md``), and with Ray the cells of one method may run on different machines."""
    try:
        import torch

        torch.set_num_threads(1)
    except ImportError:  # pragma: no cover - torch is a dependency; classic policies do not need it
        pass
    t = time.time()
    try:
        row = evaluate_cells(entry.policy, [cell], suite.episodes, suite.seed, num_worlds=suite.worlds,
                             policy_kwargs=entry.policy_kwargs(), progress=False, label=entry.label,
                             counterfactual=suite.counterfactual)[0]
        out: dict[str, Any] = {"result": row, "cpu": cpu_model()}
        if suite.check_seed is not None:
            out["check"] = evaluate_cells(entry.policy, [cell], suite.episodes, suite.check_seed,
                                          num_worlds=suite.worlds, policy_kwargs=entry.policy_kwargs(),
                                          progress=False, label=entry.label, counterfactual=False)[0]
        return out
    except Exception as e:  # noqa: BLE001 - a failing cell is recorded, the run goes on
        msg = str(e).splitlines()[0] if str(e) else ""
        return {"error": f"{type(e).__name__}: {msg}", "wall_s": round(time.time() - t, 1), "cpu": cpu_model()}


class CellStore:
    """Finished cells under ``out/cells/<method>/<table>-<row>.json`` (atomic writes)."""

    def __init__(self, out: str) -> None:
        self.root = os.path.join(out, "cells")

    def path(self, entry: Entry, cell: Cell) -> str:
        return os.path.join(self.root, entry.slug, f"{cell_key(cell)}.json")

    def get(self, entry: Entry, cell: Cell, fp: dict[str, Any]) -> dict[str, Any] | None:
        """The stored outcome if computed under ``fp`` (errors are not reused: they are retried)."""
        try:
            with open(self.path(entry, cell)) as f:
                saved = json.load(f)
        except (FileNotFoundError, json.JSONDecodeError):
            return None
        if saved.get("fingerprint") != fp or "result" not in saved:
            return None
        return saved

    def put(self, entry: Entry, cell: Cell, fp: dict[str, Any], outcome: dict[str, Any]) -> None:
        write_text(self.path(entry, cell), json.dumps({"fingerprint": fp, **outcome}, indent=1) + "\n")


# ---------------------------------------------------------------------------------------------------- backends
Task = tuple[Entry, Cell, Suite]


def _run_local(tasks: list[Task], workers: int) -> Iterable[tuple[Task, dict[str, Any]]]:
    if workers <= 1 or len(tasks) <= 1:
        for task in tasks:
            yield task, run_cell(*task)
        return
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

    method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
    with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context(method)) as pool:
        futures = {pool.submit(run_cell, *task): task for task in tasks}
        for fut in as_completed(futures):
            yield futures[fut], fut.result()


def _run_ray(tasks: list[Task], workers: int, address: str | None) -> Iterable[tuple[Task, dict[str, Any]]]:
    try:
        import ray
    except ImportError:
        raise ValueError("--backend ray needs Ray: pip install 'crowdbench[ray]'") from None
    started = not ray.is_initialized()
    if started:
        kwargs: dict[str, Any] = {"address": address} if address else {"num_cpus": max(workers, 1)}
        ray.init(include_dashboard=False, log_to_driver=False, **kwargs)
    try:
        remote = ray.remote(num_cpus=1)(run_cell)
        refs = {remote.remote(*task): task for task in tasks}
        while refs:
            done, _ = ray.wait(list(refs), num_returns=1)
            yield refs.pop(done[0]), ray.get(done[0])
    finally:
        if started:
            ray.shutdown()


# ---------------------------------------------------------------------------------------------------- a run
def run(suite: Suite, entries: list[Entry], out: str, workers: int = 1, backend: str = "local",
        ray_address: str | None = None, force: bool = False,
        progress: Callable[[str], None] | None = None) -> dict[str, list[dict[str, Any]]]:
    """Evaluate every entry on the suite's cells (reusing stored cells unless ``force``), then write each entry's
    ``OUT/<slug>.json|md`` (results, fingerprint, provenance, wall time), ``OUT/LEADERBOARD.md`` and the figures
    (``success.png``; ``ablation.png`` when ablations are on the board); returns the
    result rows by label (an errored cell is a row with ``error``)."""
    if backend not in BACKENDS:
        raise ValueError(f"--backend {backend!r}; valid choices: {', '.join(BACKENDS)}")
    if not isinstance(workers, int) or workers < 1:
        raise ValueError(f"--workers {workers!r}; valid choices: an integer ≥ 1")
    labels = [e.label for e in entries]
    if len(set(labels)) != len(labels):
        raise ValueError(f"methods: duplicate labels {sorted({lb for lb in labels if labels.count(lb) > 1})}")
    store = CellStore(out)
    grid = suite.grid()
    fps = {e.label: fingerprint(e, suite) for e in entries}
    outcomes: dict[tuple[str, str], dict[str, Any]] = {}
    todo: list[Task] = []
    for e in entries:
        for c in grid:
            saved = None if force else store.get(e, c, fps[e.label])
            if saved is None:
                todo.append((e, c, suite))
            else:
                outcomes[(e.label, cell_key(c))] = saved
    say = progress or (lambda line: None)
    say(f"suite {suite.name}: {len(entries)} methods × {len(grid)} cells; {len(outcomes)} stored, "
        f"{len(todo)} to run ({suite.episodes} episodes each, backend {backend}, {workers} worker(s))")
    t0 = time.time()
    source = _run_local(todo, workers) if backend == "local" else _run_ray(todo, workers, ray_address)
    for k, ((e, c, _), outcome) in enumerate(source, 1):
        store.put(e, c, fps[e.label], outcome)
        outcomes[(e.label, cell_key(c))] = outcome
        elapsed = time.time() - t0
        eta = elapsed / k * (len(todo) - k)
        what = (f"success {outcome['result']['success_rate']:.3f}" if "result" in outcome
                else f"ERROR {outcome['error']}")
        say(f"[{k}/{len(todo)}] {e.label} · Table {c.table} {c.row}: {what} | elapsed {elapsed / 60:.1f} min, "
            f"ETA {eta / 60:.1f} min")
    board: dict[str, list[dict[str, Any]]] = {}
    info = provenance()
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
                "suite_digest": suite.digest(), "episodes": suite.episodes, "seed": suite.seed,
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
        plot_board(everyone, os.path.join(out, "success.png"), groups, planners=planners)
        if "ablation" in groups.values():
            plot_board(everyone, os.path.join(out, "ablation.png"), groups, rows="ablation", planners=planners)
    return board


def gather(out: str, suite: Suite, board: dict[str, list[dict[str, Any]]], groups: dict[str, str],
           fingerprints: dict[str, dict[str, Any]], only: bool = False
           ) -> tuple[dict[str, list[dict[str, Any]]], dict[str, str], frozenset[str], dict[str, dict[str, Any]]]:
    """The run's ``board`` plus (unless ``only``: ``LEADERBOARD.md`` shows the methods asked for) every other method
    file in ``out`` scored on the same suite (same digest); in leaderboard order (:data:`~crowdbench.leaderboard.
    METHODS`, each method's other training seeds after it, then the rest by label). Returns rows, groups, the
    planners (labels whose fingerprint has no checkpoint) and every label's fingerprint (``fingerprints`` for the
    run's entries, the stored one otherwise)."""
    rows, groups, fingerprints = {}, dict(groups), dict(fingerprints)
    for path in sorted(Path(out).glob("*.json")):
        try:
            d = json.loads(path.read_text())
        except (OSError, ValueError):
            continue
        meta = d.get("meta") if isinstance(d, dict) else None
        if only and isinstance(meta, dict) and meta.get("label") not in board:
            continue
        if isinstance(meta, dict) and meta.get("suite_digest") == suite.digest() and "label" in meta:
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


def print_progress(line: str) -> None:
    print(line, file=sys.stdout, flush=True)
