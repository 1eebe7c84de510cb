"""Write ``tests/data/orca_rvo2_large.npz``: Python-RVO2 runs of large crowds, with and without obstacles.

    PYTHONPATH=. python tests/data/make_rvo2_references.py     # needs ``import rvo2`` (see benchmarks/bench_peers.py)

Scenarios (parameters as ``tests/data/README.md``'s, radius 0.31 m: time step 0.25 s, neighbour distance 10 m,
10 neighbours, time horizons 5 s, max speed 1 m/s; goal = −start; before every step each agent's preferred velocity
is ``crowdbench.humans.preferred_velocity`` of its position as RVO2 reports it):

* ``lattice-200``, ``lattice-1000`` — ``crowdbench.bench.bench_crowd(n, 1, "grid")``, 20 steps: states 0–3 and 20;
* ``pillars-200`` (spacing 3 m, 364 obstacle vertices after RVO2's splits: crowdbench's edge scan) and
  ``pillars-1000`` (spacing 4 m, 964 vertices: the obstacle tree) — ``benchmarks/bench_orca_obstacles.py``'s
  ``pillar_hall``, every state of 20 and 10 steps.

Per scenario ``<name>/start``, ``<name>/steps`` (the indices of the stored states), ``<name>/pos``, ``<name>/vel``
(float32, as RVO2 reports them), ``<name>/agent_nb`` and ``<name>/obst_nb`` (int16, -1 padded: each agent's agent
and obstacle neighbours in RVO2's order during the steps from states 0, 1 and 2), and for the pillar halls
``<name>/polygons`` (float64 vertex rows, ``<name>/polygon_sizes``).
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np

from crowdbench.bench import bench_crowd
from crowdbench.humans import preferred_velocity

HERE = Path(__file__).resolve().parent
PARAMS = {"time_step": 0.25, "neighbor_dist": 10.0, "max_neighbors": 10, "time_horizon": 5.0,
          "time_horizon_obst": 5.0, "radius": 0.31, "max_speed": 1.0}


def pillar_hall(n: int, spacing: float):
    spec = importlib.util.spec_from_file_location("bench_orca_obstacles",
                                                  HERE.parents[1] / "benchmarks" / "bench_orca_obstacles.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.pillar_hall(n, spacing)


def run(start: np.ndarray, polys: list, steps: int, keep: list[int]) -> dict[str, np.ndarray]:
    import rvo2

    p = PARAMS
    sim = rvo2.PyRVOSimulator(p["time_step"], p["neighbor_dist"], p["max_neighbors"], p["time_horizon"],
                              p["time_horizon_obst"], p["radius"], p["max_speed"])
    n = len(start)
    for q in start:
        sim.addAgent((float(q[0]), float(q[1])))
    for poly in polys:
        sim.addObstacle([(float(x), float(y)) for x, y in poly])
    sim.processObstacles()
    pos, vel, agent_nb, obst_nb = [], [], [], []
    for k in range(steps + 1):
        here = np.array([sim.getAgentPosition(i) for i in range(n)])
        if k in keep:
            pos.append(here)
            vel.append(np.array([sim.getAgentVelocity(i) for i in range(n)]))
        if k == steps:
            break
        pref = preferred_velocity(here, -start, np.ones(n), p["time_step"])
        for i in range(n):
            sim.setAgentPrefVelocity(i, (float(pref[i, 0]), float(pref[i, 1])))
        sim.doStep()
        if k < 3:
            a = [[sim.getAgentAgentNeighbor(i, j) for j in range(sim.getAgentNumAgentNeighbors(i))] for i in range(n)]
            o = [[sim.getAgentObstacleNeighbor(i, j) for j in range(sim.getAgentNumObstacleNeighbors(i))]
                 for i in range(n)]
            agent_nb.append(a)
            obst_nb.append(o)

    def pad(lists: list[list[list[int]]]) -> np.ndarray:
        width = max([1] + [len(x) for step in lists for x in step])
        out = np.full((len(lists), n, width), -1, np.int16)
        for s, step in enumerate(lists):
            for i, x in enumerate(step):
                out[s, i, : len(x)] = x
        return out

    return {"start": start, "steps": np.asarray(keep), "pos": np.asarray(pos, np.float32),
            "vel": np.asarray(vel, np.float32), "agent_nb": pad(agent_nb), "obst_nb": pad(obst_nb)}


def main() -> None:
    out: dict[str, np.ndarray] = {"params": np.asarray(json.dumps(PARAMS))}
    for n in (200, 1000):
        for k, v in run(bench_crowd(n, 1, "grid")[0], [], 20, [0, 1, 2, 3, 20]).items():
            out[f"lattice-{n}/{k}"] = v
    for n, spacing, steps in ((200, 3.0, 20), (1000, 4.0, 10)):
        start, polys = pillar_hall(n, spacing)
        for k, v in run(start, polys, steps, list(range(steps + 1))).items():
            out[f"pillars-{n}/{k}"] = v
        out[f"pillars-{n}/polygons"] = np.concatenate([np.asarray(q, np.float64) for q in polys])
        out[f"pillars-{n}/polygon_sizes"] = np.asarray([len(q) for q in polys])
    np.savez_compressed(HERE / "orca_rvo2_large.npz", **out)


if __name__ == "__main__":
    main()
