"""One world through the PettingZoo API: env-steps/s at N = 5 / 10 / 20 and where a step's time goes.

    python benchmarks/bench_pettingzoo.py [--quick]

One core (pinned). ``crowdbench.parallel_env`` with its defaults (circle crossing, ORCA pedestrians, every agent's
observation and info built); the robot heads for its goal at full speed, its action computed outside the timer.
Each repeat times 2,000 ``env.step`` calls (medians of 3, spread = max − min); a finished episode is reset outside
the timer ("resets excluded") or inside it ("included") — CrowdNav's figures in the README are quoted both ways
(``benchmarks/bench_peers.py`` measures CrowdNav and RVO2 on the same machine).

The breakdown times the parts of a step separately, in µs per step: the world (pedestrian model, motion kernel,
outcome kernel, goal renewal), the observations of every agent, the rest of the adapter (reward/termination/info
dicts), and the pymunk synchronisation alone (one position write per world) against what stepping pymunk itself
would cost (velocity write, ``cpSpaceStep``, position read).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from common import machine, pin_one_core, time_it

import crowdbench
from crowdbench.bench import pettingzoo_steps_per_s


def breakdown(n: int, steps: int) -> dict[str, float]:
    """µs per ``env.step`` spent in the world, in the observation builders and in the rest of the adapter (the
    first two timed by wrapping them on the instance, ≈ 0.2 µs of timer overhead each)."""
    env = crowdbench.parallel_env(num_humans=n)
    w = env.world
    spent = {"world": 0.0, "observations": 0.0}

    def timed(name, fn):
        def call(*args, **kwargs):
            t = time.perf_counter()
            out = fn(*args, **kwargs)
            spent[name] += time.perf_counter() - t
            return out
        return call

    w.step = timed("world", w.step)
    env._observations = timed("observations", env._observations)
    obs, _ = env.reset(seed=0)
    spent["observations"] = 0.0
    total, episodes = 0.0, 0
    for _ in range(steps):
        r = obs["robot"]["robot"]
        d = r[3:5] - r[0:2]
        a = {"robot": d / max(float(np.hypot(*d)), 1e-9)}
        t = time.perf_counter()
        obs, _, term, trunc, _ = env.step(a)
        total += time.perf_counter() - t
        if term["robot"] or trunc["robot"]:
            episodes += 1
            before = spent["observations"]
            obs, _ = env.reset(seed=episodes)
            spent["observations"] = before
    out = {k: v / steps * 1e6 for k, v in spent.items()}
    out["adapter rest"] = total / steps * 1e6 - out["world"] - out["observations"]
    sync, _ = time_it(lambda: w.physics.sync(w.pos), number=2000)
    out["of the world: pymunk sync (position write)"] = sync * 1e6
    space = w.space(0)

    def pymunk_step() -> None:
        for body, v in zip(space.agent_bodies, w.vel[0].tolist(), strict=True):
            body.velocity = v
        space.step(w.dt)
        for body, p in zip(space.agent_bodies, w.pos[0].tolist(), strict=True):
            body.position = p

    full, _ = time_it(pymunk_step, number=2000)
    out["for scale: stepping pymunk through its Python API"] = full * 1e6
    return out


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true")
    args = p.parse_args()
    pin_one_core()
    steps = 200 if args.quick else 2000
    print(f"machine: {machine()}; pinned to 1 core")
    print(f"\n{'N':>3} {'resets excluded':>22} {'resets included':>22}   env-steps/s, median [spread]")
    for n in (5, 10, 20):
        ex = pettingzoo_steps_per_s(n, steps, 3, resets=False)
        inc = pettingzoo_steps_per_s(n, steps, 3, resets=True)
        print(f"{n:>3} {ex['median']:>14,.0f} [{ex['spread']:>5,.0f}] {inc['median']:>14,.0f} [{inc['spread']:>5,.0f}]")
    print("\nwhere a step goes, µs per step (one pass each; the parts are timed separately)")
    for n in (5, 20):
        parts = breakdown(n, steps)
        print(f"  N = {n}: " + "; ".join(f"{k} {v:.1f}" for k, v in parts.items()))


if __name__ == "__main__":
    main()
