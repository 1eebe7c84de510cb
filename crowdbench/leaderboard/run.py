"""Runs: every (entry, cell) of a suite not already stored, executed in this process, in local worker processes or
as Ray tasks, each stored as it finishes; then the report (:func:`crowdbench.leaderboard.report.write_board`).

* **Fault isolation**: a cell whose policy (or pedestrian model) raises, returns NaN/inf or the wrong shape is stored
  with its error; every other cell completes. The method's tables show ``error`` there.
* **Determinism**: a cell's numbers depend only on its fingerprint — not on the backend, the number of workers or
  the order — so local, multi-process and Ray runs give identical files (timing and provenance fields aside).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable
from typing import Any

from crowdbench.evaluation import run_episodes, summarize
from crowdbench.leaderboard.cells import cell_key, fingerprint
from crowdbench.leaderboard.entries import Entry
from crowdbench.leaderboard.provenance import cpu_model, provenance
from crowdbench.leaderboard.report import write_board
from crowdbench.leaderboard.store import CellStore
from crowdbench.leaderboard.suite import Cell, Suite
from crowdbench.policies import make_policy

BACKENDS = ("local", "ray")


def evaluate_cells(policy_name: str, grid: list[Cell], episodes: int = 500, seed: int = 0, num_worlds: int = 100,
                   policy_kwargs: dict | None = None, progress: bool = True, label: str | None = None,
                   layout_kwargs: dict | None = None, model_kwargs: dict | None = None,
                   world_options: dict | None = None, counterfactual: bool = True) -> list[dict[str, Any]]:
    """Run every cell for one policy; returns one summary dict per cell (``policy`` = ``label`` or the name; the
    metrics of :func:`crowdbench.metrics.summarize`). ``layout_kwargs``, ``model_kwargs`` (latent-responsive ORCA) and
    ``world_options`` (:class:`WorldConfig` fields) change the scenario from its defaults (studies do);
    ``counterfactual`` runs the robot-absent twin for the pedestrians' delay."""
    from crowdbench.worlds import make_layout

    results = []
    t_start = time.time()
    for k, c in enumerate(grid, 1):
        t = time.time()
        policy = make_policy(policy_name, **(policy_kwargs or {}))
        kwargs = {"responsiveness": c.rho, **(model_kwargs or {})} if c.model == "responsive_orca" else {}
        eps = run_episodes(policy, episodes, seed=seed, num_worlds=num_worlds,
                           layout=make_layout(c.layout, **(layout_kwargs or {})), num_humans=c.humans,
                           human_model=c.model, human_model_kwargs=kwargs,
                           counterfactual=counterfactual, **(world_options or {}))
        s = summarize(eps)
        results.append({"policy": label or policy_name, "table": c.table, "row": c.row, "layout": c.layout,
                        "humans": c.humans, "responsiveness": c.rho, "human_model": c.model, "seed": seed, **s,
                        "wall_s": round(time.time() - t, 1)})
        if progress:
            eta = (time.time() - t_start) / k * (len(grid) - k)
            print(f"[{k}/{len(grid)}] Table {c.table:<3} {c.row:<26} success {s['success_rate']:.3f} collision "
                  f"{s['collision_rate']:.3f} timeout {s['timeout_rate']:.3f} time {s['nav_time']:.2f} path "
                  f"{s['path_length']:.2f} dv {s['delta_v']:.2f} | ETA {eta / 60:.1f} min", flush=True)
    return results


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


def check_backend(backend: str, workers: int) -> None:
    """One clear error for a backend or worker count that :func:`execute` cannot use."""
    if backend not in BACKENDS:
        raise ValueError(f"--backend {backend!r}; valid choices: {', '.join(BACKENDS)}")
    if not isinstance(workers, int) or workers < 1:
        raise ValueError(f"--workers {workers!r}; valid choices: an integer ≥ 1")


def execute(tasks: list[Task], workers: int = 1, backend: str = "local",
            ray_address: str | None = None) -> Iterable[tuple[Task, dict[str, Any]]]:
    """:func:`run_cell` on every task — in this process (``workers`` 1), in local worker processes, or as Ray tasks
    — yielding ``(task, outcome)`` as each finishes."""
    check_backend(backend, workers)
    return _run_local(tasks, workers) if backend == "local" else _run_ray(tasks, workers, ray_address)


# ---------------------------------------------------------------------------------------------------- a run
def run_suite(suite: Suite, entries: list[Entry], out: str, workers: int = 1, backend: str = "local",
        ray_address: str | None = None, force: bool = False,
        progress: Callable[[str], None] | None = None) -> dict[str, list[dict[str, Any]]]:
    """Evaluate every entry on the suite's cells (reusing stored cells unless ``force``), storing each as it
    finishes, then write the report (:func:`~crowdbench.leaderboard.report.write_board`: each entry's
    ``OUT/<slug>.json|md``, ``OUT/LEADERBOARD.md`` and the figures); returns the result rows by label (an errored
    cell is a row with ``error``)."""
    labels = [e.label for e in entries]
    if len(set(labels)) != len(labels):
        raise ValueError(f"methods: duplicate labels {sorted({lb for lb in labels if labels.count(lb) > 1})}")
    check_backend(backend, workers)
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
    source = execute(todo, workers, backend, ray_address)
    for k, ((e, c, _), outcome) in enumerate(source, 1):
        store.put(e, c, fps[e.label], outcome)
        outcomes[(e.label, cell_key(c))] = outcome
        elapsed = time.time() - t0
        eta = elapsed / k * (len(todo) - k)
        what = (f"success {outcome['result']['success_rate']:.3f}" if "result" in outcome
                else f"ERROR {outcome['error']}")
        say(f"[{k}/{len(todo)}] {e.label} · Table {c.table} {c.row}: {what} | elapsed {elapsed / 60:.1f} min, "
            f"ETA {eta / 60:.1f} min")
    return write_board(out, suite, entries, outcomes, fps, provenance())


def print_progress(line: str) -> None:
    print(line, file=sys.stdout, flush=True)
