"""The concourse's world step at scale: CrowdNav++'s every-neighbour ORCA rule against RVO2's cap of 10 neighbours.

    PYTHONPATH=. python benchmarks/bench_concourse_orca.py [--n 500 1000] [--rounds 2] [--steps 10]

One world (``CrowdWorld``, layout ``concourse``, ``responsive_orca`` pedestrians), the robot at rest, no observations
built; radii 0.2–0.3 m above 500 people (the hall's capacity). Per round and setting a fresh world from seed 0, three
warm-up steps, then ``--steps`` steps timed in process CPU time; settings alternate within each round. Prints ms per
world step and µs per agent-step for ``max_neighbors`` None (CrowdNav++: every agent within 5–10 m) and 10.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from crowdbench.config import make_config
from crowdbench.worlds import CrowdWorld


def step_ms(n: int, max_neighbors: int | None, steps: int) -> float:
    """CPU milliseconds per world step of a fresh concourse world of ``n`` pedestrians."""
    kw = {"human_radius_range": (0.2, 0.3)} if n > 500 else {}
    world = CrowdWorld(make_config(num_humans=n, **kw), 1, "concourse", "responsive_orca",
                       {"max_neighbors": max_neighbors})
    world.reset(seeds=[0])
    for _ in range(3):
        world.step(np.zeros((1, 2)))
    t = time.process_time()
    for _ in range(steps):
        world.step(np.zeros((1, 2)))
    return (time.process_time() - t) / steps * 1e3


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, nargs="+", default=[500, 1000])
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--steps", type=int, default=10)
    a = p.parse_args()
    print("| N | max_neighbors | ms per world step (per round) | µs per agent-step (min) |")
    print("|---:|---|---|---:|")
    for n in a.n:
        res: dict[int | None, list[float]] = {None: [], 10: []}
        for _ in range(a.rounds):
            for mn in res:
                res[mn].append(step_ms(n, mn, a.steps))
        for mn, v in res.items():
            print(f"| {n} | {mn} | {' '.join(f'{x:.2f}' for x in v)} | {min(v) / n * 1e3:.2f} |", flush=True)


if __name__ == "__main__":
    main()
