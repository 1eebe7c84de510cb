"""Soak test: many env steps through the PettingZoo env and the training VecEnv; memory growth and step-time drift.

    python benchmarks/soak.py [--steps 1000000] [--humans 20] [--json soak.json]

PettingZoo: one ``parallel_env`` (latent-responsive ORCA crowd, ρ = 0.5), random robot actions, every agent's
observation built, episodes reset as they end (resets included in the timing). VecEnv: the training environment
(256 worlds, 10–30 pedestrians, one process) with random actions, same-step auto-reset. For each: resident memory
(VmRSS) after a warm-up and at the end of each tenth of the run, and each tenth's step rate; drift compares the last
tenth's rate with the first's, and growth is split into the first and second half (allocator warm-up saturates, a
leak keeps growing). ``--fixed-attributes`` gives every pedestrian the same radius and speed (no per-episode draws,
so no pymunk shape updates on reset) to isolate that path. Not a CI test.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np
from common import machine, pin_one_core


def rss_mib() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def soak(step_fn, steps: int, per_call: int) -> dict:
    """Call ``step_fn`` until ``steps`` env steps (``per_call`` each); each tenth's rate and end RSS."""
    calls = max(steps // per_call, 10)
    tenth = max(calls // 10, 2)
    for _ in range(min(tenth, 50)):  # warm-up: caches, numba, allocator
        step_fn()
    rss0 = rss_mib()
    tenths = []
    t0 = time.perf_counter()
    for _ in range(10):
        t = time.perf_counter()
        for _ in range(tenth):
            step_fn()
        rate = tenth * per_call / (time.perf_counter() - t)
        tenths.append({"steps_per_s": round(rate), "rss_mib": round(rss_mib(), 1)})
    total = time.perf_counter() - t0
    rates = [x["steps_per_s"] for x in tenths]
    rss_mid, rss1 = tenths[4]["rss_mib"], tenths[-1]["rss_mib"]
    return {"env_steps": 10 * tenth * per_call, "seconds": round(total, 1),
            "steps_per_s": round(10 * tenth * per_call / total), "first_tenth_steps_per_s": rates[0],
            "last_tenth_steps_per_s": rates[-1], "drift_pct": round(100 * (rates[-1] / rates[0] - 1), 1),
            "median_tenth_steps_per_s": round(statistics.median(rates)), "rss_after_warmup_mib": round(rss0, 1),
            "rss_end_mib": rss1, "rss_growth_mib": round(rss1 - rss0, 1),
            "rss_growth_first_half_mib": round(rss_mid - rss0, 1),
            "rss_growth_second_half_mib": round(rss1 - rss_mid, 1),
            "tenths": tenths}


def pettingzoo(steps: int, humans: int, fixed_attributes: bool = False) -> dict:
    import crowdbench

    fixed = {"human_radius_range": None, "human_v_pref_range": None} if fixed_attributes else {}
    env = crowdbench.parallel_env(num_humans=humans, human_model="responsive_orca",
                                  human_model_kwargs={"responsiveness": 0.5}, **fixed)
    rng = np.random.default_rng(0)
    env.reset(seed=0)
    episode = [0]

    def step():
        env.step({"robot": rng.uniform(-1, 1, 2)})
        if not env.agents:
            episode[0] += 1
            env.reset(seed=episode[0])

    out = soak(step, steps, 1)
    return {**out, "episodes": episode[0]}


def vecenv(steps: int) -> dict:
    import torch

    from crowdbench.training.vecenv import CrowdVecEnv

    torch.set_num_threads(1)
    env = CrowdVecEnv(256, seed=0, humans_range=(10, 30), processes=1)
    gen = torch.Generator().manual_seed(0)

    def step():
        env.step(torch.rand(256, 2, generator=gen) * 2 - 1)

    try:
        return soak(step, steps, 256)
    finally:
        env.close()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--steps", type=int, default=1_000_000)
    p.add_argument("--humans", type=int, default=20)
    p.add_argument("--json", default=None)
    p.add_argument("--fixed-attributes", action="store_true", help="PettingZoo run without per-episode size draws")
    p.add_argument("--only", choices=["pettingzoo", "vecenv"], default=None)
    args = p.parse_args()
    pin_one_core()
    print(machine())
    res = {}
    if args.only in (None, "pettingzoo"):
        res["pettingzoo"] = pettingzoo(args.steps, args.humans, args.fixed_attributes)
    if args.only in (None, "vecenv"):
        res["vecenv"] = vecenv(args.steps)
    for name, r in res.items():
        print(f"{name:>10}: {r['env_steps']:,} env steps in {r['seconds']} s ({r['steps_per_s']:,}/s); step rate "
              f"first → last tenth {r['first_tenth_steps_per_s']:,} → {r['last_tenth_steps_per_s']:,}/s "
              f"({r['drift_pct']:+.1f} %), median tenth {r['median_tenth_steps_per_s']:,}/s; RSS "
              f"{r['rss_after_warmup_mib']} → {r['rss_end_mib']} MiB ({r['rss_growth_first_half_mib']:+.1f} MiB in the "
              f"first half, {r['rss_growth_second_half_mib']:+.1f} in the second)")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=2)


if __name__ == "__main__":
    main()
