"""ORCA, crowdbench's kernel against RVO2, alternated run by run in one process: agent-steps per CPU second.

    PYTHONPATH=. python benchmarks/bench_orca_rvo2.py [--rounds 5] [--n 20 50 100 200 500 1000] [--worlds 1 64]
                                                      [--crowds circle grid] [--target 100000] [--api batch]
                                                      [--json out.json] [--plot scaling.png]
    PYTHONPATH=. python benchmarks/bench_orca_rvo2.py --from-json out.json --plot scaling.png   # plot only

Needs Python-RVO2 (``import rvo2``) in the interpreter, built ``-O2`` as ``benchmarks/bench_peers.py`` describes.
For each crowd (``crowdbench.bench.bench_crowd``: ``circle`` — people on a ring, overlapping from N ≈ 100, crossing
through its centre; ``grid`` — a jittered lattice, nobody overlapping), world count and N, each round times one run
of crowdbench's ``orca_batch`` (all worlds in one call, one thread) and then one run of RVO2 (one
``PyRVOSimulator`` per world, ``doStep`` on each in turn), on the same crowd with the same parameters (neighbour
distance 10 m, 10 neighbours, time horizons 5 s, radius 0.31 m, max speed 1 m/s, dt 0.25 s; start velocity 0).
A run is ``episodes`` × ``steps`` steps, each episode from the start state, so that every run does the same work:
``steps`` = 20 (fewer for large batches), ``episodes`` such that a run has about ``--target`` agent-steps. Before
every step the preferred velocities (``crowdbench.humans.preferred_velocity`` toward the goal = −start, speed 1)
are set outside the timer; only ``orca_batch`` + the position update in numpy (crowdbench; with ``--api advance``
``orca_advance``, both in one call; with ``--api facade`` the drop-in ``crowdbench.humans.orca.PyRVOSimulator``'s
``doStep``, driven exactly as RVO2) and ``doStep`` (RVO2, which
updates positions itself) are timed, in process CPU time (``time.process_time``), pinned to one core.

Prints per configuration the median agent-steps/s of each and the ratio crowdbench / RVO2 of every round;
``--plot`` draws the scaling figure (agent-steps/s against N, one panel per crowd).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import statistics
import time

import numpy as np

from crowdbench.bench import ORCA_BENCH, bench_crowd
from crowdbench.humans import preferred_velocity
from crowdbench.humans.orca_kernel import build_obstacles, orca_advance, orca_batch
from crowdbench.io import atomic_path

DT = ORCA_BENCH.dt


def plan(n: int, worlds: int, target: int) -> tuple[int, int]:
    """(episodes, steps) of one run: about ``target`` agent-steps."""
    steps = int(max(2, min(20, target // (n * worlds))))
    return int(max(1, round(target / (steps * n * worlds)))), steps


def crowdbench_run(start: np.ndarray, episodes: int, steps: int, kernel=orca_batch) -> float:
    """Agent-steps per CPU second of ``kernel`` (``orca_batch``'s signature) on ``start`` ``(B, N, 2)``."""
    B, N = start.shape[:2]
    f = np.full((B, N), ORCA_BENCH.max_speed)
    args = ORCA_BENCH.batch_args(B, N)
    obst, goal = build_obstacles([]), -start
    elapsed = 0.0
    for _ in range(episodes):
        pos, vel = start.copy(), np.zeros_like(start)
        out = np.empty_like(start)
        for _ in range(steps):
            pref = preferred_velocity(pos, goal, f, DT)
            t = time.process_time()
            kernel(pos, vel, pref, *args, *obst, DT, out)
            vel, out = out, vel
            pos += vel * DT
            elapsed += time.process_time() - t
    return episodes * steps * B * N / elapsed


def crowdbench_advance_run(start: np.ndarray, episodes: int, steps: int) -> float:
    """Agent-steps per CPU second of ``orca_advance`` (RVO2's ``doStep``: velocities and positions in one call, agent
    arrays in blocks) on ``start`` ``(B, N, 2)``."""
    B, N = start.shape[:2]
    f = np.full((B, N), ORCA_BENCH.max_speed)
    a = ORCA_BENCH.batch_args(B, N)  # radius, max_speed, neighbor_dist, max_neighbors, horizons, active, ..., ignore
    flt, ints, flags = np.stack([a[0], a[1], a[2], a[4], a[5]]), np.stack([a[3], a[8]]), np.stack([a[6], a[7]])
    obst, goal = build_obstacles([]), -start
    elapsed = 0.0
    for _ in range(episodes):
        vec = np.zeros((4, B, N, 2))
        vec[0] = start
        for _ in range(steps):
            vec[2] = preferred_velocity(vec[0], goal, f, DT)
            t = time.process_time()
            orca_advance(vec, flt, ints, flags, *obst, DT)
            elapsed += time.process_time() - t
    return episodes * steps * B * N / elapsed


def rvo2_run(start: np.ndarray, episodes: int, steps: int, simulator: type | None = None) -> float:
    """Agent-steps per CPU second of Python-RVO2's ``doStep`` on ``start`` ``(B, N, 2)``, one simulator per world
    (``simulator``: another class with its API, e.g. crowdbench's drop-in ``PyRVOSimulator``)."""
    import rvo2

    simulator = simulator or rvo2.PyRVOSimulator
    B, N = start.shape[:2]
    goal, f = -start, np.full(N, ORCA_BENCH.max_speed)
    elapsed = 0.0
    for _ in range(episodes):
        sims = []
        for w in range(B):
            sim = simulator(*ORCA_BENCH.simulator_args())
            for i in range(N):
                sim.addAgent((float(start[w, i, 0]), float(start[w, i, 1])))
            sim.processObstacles()
            sims.append(sim)
        for _ in range(steps):
            for w, sim in enumerate(sims):
                p = np.array([sim.getAgentPosition(i) for i in range(N)])
                pref = preferred_velocity(p, goal[w], f, DT)
                for i in range(N):
                    sim.setAgentPrefVelocity(i, (float(pref[i, 0]), float(pref[i, 1])))
            t = time.process_time()
            for sim in sims:
                sim.doStep()
            elapsed += time.process_time() - t
    return episodes * steps * B * N / elapsed


def compare(n: int, worlds: int, crowd: str, rounds: int, target: int, api: str = "batch") -> dict:
    start = bench_crowd(n, worlds, crowd)
    episodes, steps = plan(n, worlds, target)
    ours, peer = [], []
    from crowdbench.humans.orca import PyRVOSimulator

    run = {"batch": crowdbench_run, "advance": crowdbench_advance_run,
           "facade": lambda *a: rvo2_run(*a, simulator=PyRVOSimulator)}[api]
    for _ in range(rounds):
        ours.append(run(start, episodes, steps))
        peer.append(rvo2_run(start, episodes, steps))
    ratios = [o / p for o, p in zip(ours, peer, strict=True)]
    return {"n": n, "worlds": worlds, "crowd": crowd, "episodes": episodes, "steps": steps,
            "crowdbench": statistics.median(ours), "rvo2": statistics.median(peer), "ratios": ratios}


def plot(rows: list[dict], path: str) -> None:
    """The scaling figure: median M agent-steps/s against N (log axis) of crowdbench (solid) and RVO2 (dashed, one
    simulator per world), per world count, one panel per crowd."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    crowds = sorted({r["crowd"] for r in rows})
    fig, axes = plt.subplots(1, len(crowds), figsize=(5 * len(crowds), 4), dpi=100, squeeze=False)
    names = {"circle": "ring (overlaps from N ≈ 100)", "grid": "jittered lattice (no overlaps)"}
    for ax, crowd in zip(axes[0], crowds, strict=True):
        mine = [r for r in rows if r["crowd"] == crowd]
        for worlds, colour in zip(sorted({r["worlds"] for r in mine}), ("C0", "C1", "C2", "C3"), strict=False):
            sel = sorted((r for r in mine if r["worlds"] == worlds), key=lambda r: r["n"])
            label = f"{worlds} world{'s' if worlds > 1 else ''}"
            ax.plot([r["n"] for r in sel], [r["crowdbench"] / 1e6 for r in sel], "o-", color=colour,
                    label=f"crowdbench, {label}")
            ax.plot([r["n"] for r in sel], [r["rvo2"] / 1e6 for r in sel], "s--", color=colour, alpha=0.7,
                    label=f"Python-RVO2, {label}")
        ax.set_xscale("log")
        ns = sorted({r["n"] for r in mine})
        ax.set_xticks(ns, [f"{n:,}" for n in ns])
        ax.minorticks_off()
        ax.set_ylim(bottom=0)
        ax.set_xlabel("people per world, N")
        ax.set_ylabel("M agent-steps per CPU second")
        ax.set_title(f"ORCA, {names.get(crowd, crowd)}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--n", type=int, nargs="+", default=[20, 50, 100, 200, 500, 1000])
    p.add_argument("--worlds", type=int, nargs="+", default=[1, 64])
    p.add_argument("--crowds", nargs="+", default=["circle", "grid"])
    p.add_argument("--target", type=int, default=100_000, help="agent-steps per run")
    p.add_argument("--api", choices=["batch", "advance", "facade"], default="batch",
                   help="crowdbench's side: orca_batch + the position update in numpy (batch), orca_advance "
                        "(RVO2's doStep in one call, arrays in blocks) or the drop-in PyRVOSimulator (facade)")
    p.add_argument("--json", help="also write the results here")
    p.add_argument("--plot", help="draw the scaling figure here (PNG)")
    p.add_argument("--from-json", help="read the results of an earlier --json run instead of measuring")
    a = p.parse_args()
    if a.from_json:
        with open(a.from_json) as f:
            rows = json.load(f)
        if a.plot:
            plot(rows, a.plot)
        return
    with contextlib.suppress(OSError):
        os.sched_setaffinity(0, {0})
    crowdbench_run(bench_crowd(100, 1), 1, 2)  # compile (or load the cache) outside the timer
    crowdbench_advance_run(bench_crowd(100, 1), 1, 2)
    rows = []
    print("| crowd | worlds | N | crowdbench M agent-steps/s | RVO2 M | crowdbench / RVO2 per round | median |")
    print("|---|---:|---:|---:|---:|---|---:|")
    for crowd in a.crowds:
        for worlds in a.worlds:
            for n in a.n:
                r = compare(n, worlds, crowd, a.rounds, a.target, a.api)
                rows.append(r)
                print(f"| {crowd} | {worlds} | {n} | {r['crowdbench'] / 1e6:.2f} | {r['rvo2'] / 1e6:.2f} | "
                      f"{' '.join(f'{x:.2f}' for x in r['ratios'])} | {statistics.median(r['ratios']):.2f} |",
                      flush=True)
    if a.json:
        with atomic_path(a.json) as tmp, open(tmp, "w") as f:
            json.dump(rows, f, indent=1)
    if a.plot:
        plot(rows, a.plot)


if __name__ == "__main__":
    main()
