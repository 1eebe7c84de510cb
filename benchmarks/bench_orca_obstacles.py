"""ORCA among many obstacles, crowdbench's kernel against RVO2, alternated: µs per agent-step as obstacles grow.

    PYTHONPATH=. python benchmarks/bench_orca_obstacles.py [--n 200 1000] [--spacing 12 6 3] [--rounds 3]
                                                           [--steps 20] [--no-rvo2]

The scene (:func:`pillar_hall`): a square hall of side ``1.2·sqrt(2N) + 4`` m (walls: one closed polygon seen from
inside), square pillars of side 0.5 m on a lattice of ``spacing`` m centred on the origin, and ``N`` people on a
jittered 1.2 m lattice clear of the pillars (≥ 0.4 m gap), each walking to its mirror image through the centre
(clear too: the scene is symmetric). Parameters as ``bench_orca_rvo2.py`` (neighbour distance 10 m, 10 neighbours,
time horizons 5 s, radius 0.31 m, max speed 1 m/s, dt 0.25 s), one world. Each round times ``--steps`` steps from
the start of crowdbench's ``orca_batch`` + the position update and of Python-RVO2's ``doStep`` (when installed), in
process CPU time, alternated. Prints the obstacle vertices after RVO2's splits, µs per agent-step (median over
rounds), the speed ratio crowdbench / RVO2 of every round, and how far apart crowdbench's and RVO2's people are
after the steps (float64 against float32: ORCA's discontinuities amplify rounding).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from crowdbench.bench import ORCA_BENCH
from crowdbench.humans import preferred_velocity
from crowdbench.humans.orca_kernel import build_obstacles, orca_batch

DT, RADIUS = ORCA_BENCH.dt, ORCA_BENCH.radius


def pillar_hall(n: int, spacing: float, seed: int = 0) -> tuple[np.ndarray, list[list[tuple[float, float]]]]:
    """Start positions ``(n, 2)`` [m] and obstacle polygons (counter-clockwise pillars, clockwise hall walls)."""
    half = 0.6 * np.sqrt(2 * n) + 2.0
    k = int(half // spacing)
    centres = np.arange(-k, k + 1) * spacing
    polys: list[list[tuple[float, float]]] = [[(-half, -half), (-half, half), (half, half), (half, -half)]]
    s = 0.25
    for cx in centres:
        for cy in centres:
            polys.append([(cx - s, cy - s), (cx + s, cy - s), (cx + s, cy + s), (cx - s, cy + s)])
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(2 * n))) + 4
    g = (np.arange(side) - (side - 1) / 2) * 1.2
    pts = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2) + rng.uniform(-0.15, 0.15, (side * side, 2))
    clear = np.abs(pts).max(1) < half - 1.0
    gap = np.abs(pts[:, None, :] - np.stack(np.meshgrid(centres, centres), -1).reshape(1, -1, 2)).max(2).min(1)
    pts = pts[clear & (gap > s + RADIUS + 0.4)]
    pts = pts[np.argsort(np.hypot(*pts.T), kind="stable")][:n]
    if len(pts) < n:
        raise ValueError(f"n: only {len(pts)} people fit the hall at spacing {spacing}")
    return pts, polys


def ours(start: np.ndarray, polys, steps: int) -> tuple[float, np.ndarray]:
    """(µs per agent-step, final positions) of ``orca_batch`` + the position update."""
    n = len(start)
    f = np.full((1, n), ORCA_BENCH.max_speed)
    args = ORCA_BENCH.batch_args(1, n)
    obst = build_obstacles(polys)
    pos, vel, out, goal = start[None].copy(), np.zeros((1, n, 2)), np.empty((1, n, 2)), -start[None]
    elapsed = 0.0
    for _ in range(steps):
        pref = preferred_velocity(pos, goal, f, DT)
        t = time.process_time()
        orca_batch(pos, vel, pref, *args, *obst, DT, out)
        vel, out = out, vel
        pos += vel * DT
        elapsed += time.process_time() - t
    return elapsed / (steps * n) * 1e6, pos[0]


def rvo2_run(start: np.ndarray, polys, steps: int) -> tuple[float, np.ndarray]:
    """(µs per agent-step, final positions) of Python-RVO2's ``doStep``."""
    import rvo2

    n = len(start)
    sim = rvo2.PyRVOSimulator(*ORCA_BENCH.simulator_args())
    for p in start:
        sim.addAgent((float(p[0]), float(p[1])))
    for poly in polys:
        sim.addObstacle([(float(x), float(y)) for x, y in poly])
    sim.processObstacles()
    elapsed = 0.0
    for _ in range(steps):
        here = np.array([sim.getAgentPosition(i) for i in range(n)])
        pref = preferred_velocity(here, -start, np.full(n, ORCA_BENCH.max_speed), DT)
        for i in range(n):
            sim.setAgentPrefVelocity(i, (float(pref[i, 0]), float(pref[i, 1])))
        t = time.process_time()
        sim.doStep()
        elapsed += time.process_time() - t
    return elapsed / (steps * n) * 1e6, np.array([sim.getAgentPosition(i) for i in range(n)])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, nargs="+", default=[200, 1000])
    p.add_argument("--spacing", type=float, nargs="+", default=[12.0, 6.0, 3.0])
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--steps", type=int, default=20)
    p.add_argument("--no-rvo2", action="store_true", help="leave Python-RVO2 out")
    a = p.parse_args()
    use_rvo2 = not a.no_rvo2
    if use_rvo2:
        try:
            import rvo2  # noqa: F401
        except ImportError:
            use_rvo2 = False
    print("| N | pillar spacing [m] | V | µs per agent-step crowdbench · RVO2 | crowdbench / RVO2 (speed) | "
          "max gap to RVO2 [m] |")
    print("|---:|---:|---:|---|---|---:|")
    for n in a.n:
        for spacing in a.spacing:
            start, polys = pillar_hall(n, spacing)
            V = len(build_obstacles(polys)[0])
            ours(start, polys, 2)  # compile, warm
            res: dict[str, list[float]] = {"ours": [], "rvo2": []}
            gap = float("nan")
            for _ in range(a.rounds):
                t, end = ours(start, polys, a.steps)
                res["ours"].append(t)
                if use_rvo2:
                    t, end_rvo2 = rvo2_run(start, polys, a.steps)
                    res["rvo2"].append(t)
                    gap = float(np.abs(end - end_rvo2).max())
            med = {k: statistics.median(v) if v else float("nan") for k, v in res.items()}
            vs = " ".join(f"{r / o:.2f}" for r, o in zip(res["rvo2"], res["ours"], strict=True)) or "—"
            print(f"| {n} | {spacing:g} | {V} | {med['ours']:.2f} · {med['rvo2']:.2f} | {vs} | {gap:.1e} |",
                  flush=True)


if __name__ == "__main__":
    main()
