"""Evaluation time of a value-based policy (SARL by default) on one leaderboard cell, asking every world for a decision
against asking only the worlds still running (the batch's tail; ``RobotPolicy.stateless``), in alternation.

    python benchmarks/bench_value_eval.py [--policy sarl] [--episodes 100] [--worlds 50] [--humans 20] [--rounds 2]

Prints seconds per pass and whether both passes produced the same episodes (they must: a world's decision does not
depend on the other worlds in the batch). One thread; pause other work on the machine while it runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np
import torch

from crowdbench.evaluation import run_episodes
from crowdbench.policies import POLICIES


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--policy", default="sarl")
    p.add_argument("--episodes", type=int, default=100)
    p.add_argument("--worlds", type=int, default=50)
    p.add_argument("--humans", type=int, default=20)
    p.add_argument("--responsiveness", type=float, default=0.5)
    p.add_argument("--rounds", type=int, default=2)
    args = p.parse_args()
    torch.set_num_threads(1)
    cls = POLICIES.get(args.policy)

    class EveryWorld(cls):  # the previous behaviour: a decision for every world of the batch, finished or not
        stateless = False

    rows = {}
    for r in range(args.rounds):
        for label, policy in (("every world", EveryWorld()), ("running only", cls())):
            t = time.perf_counter()
            eps = run_episodes(policy, args.episodes, seed=0, num_worlds=args.worlds, num_humans=args.humans,
                               human_model_kwargs={"responsiveness": args.responsiveness})
            dt = time.perf_counter() - t
            rows[label] = [dataclasses.astuple(e) for e in eps]
            print(f"round {r + 1} | {label:>12}: {dt:6.1f} s ({args.episodes} episodes, {args.worlds} worlds, "
                  f"N = {args.humans})", flush=True)
    same = True
    try:
        np.testing.assert_equal(rows["every world"], rows["running only"])
    except AssertionError:
        same = False
    print(f"identical episodes: {same}")


if __name__ == "__main__":
    main()
