"""Dense crowds at scale: the PettingZoo world's step, cell grid against brute force, N = 100 … 1,000.

    taskset -c 1 python benchmarks/bench_scale.py [--steps 40] [--repeats 3] [--sizes 100 200 500 1000]

One world of ``crowdbench.parallel_env(layout="concourse", num_humans=N)`` (ORCA pedestrians; radii U(0.2, 0.3) m
at N ≥ 1,000, as the layout asks; ``human_radius_range`` goes to the world through ``parallel_env``'s keyword
options), the robot at rest (zero action), every agent's observation, reward and info built each step. Per repeat
the same episode (reset with the same seed, outside the timer) is timed for ``--steps`` steps with the world's
kernels on the grid (``world.grid_min`` = :data:`crowdbench.spatial.GRID_MIN`, "new") and then by brute force
(``grid_min`` above N, "old"), in alternation; both produce the same bits, so both time the same states. Figures:
medians over repeats of wall time per step (``perf_counter``) and process CPU time per step (``process_time``:
what this process used, whatever else the machine runs), and the wall time per agent-step (N + 1 agents). The ORCA
pedestrians find their neighbours on their own grid (above 64 agents) in both columns.

Memory: bytes per agent of the world's state — the sum of ``nbytes`` of every numpy array held by the world, its
pedestrian model and its physics mirror whose leading dimensions are (worlds, agents) or (worlds, pedestrians)
(positions, velocities, goals, radii, speeds, headings, flags, spawn counts, the model's per-agent parameters and
scratch), divided by worlds × agents (arrays not per agent — obstacles, per-world counters — are left out).

Social Force: its ``step`` (the pedestrians' velocities, numpy, every pair: the model has no cut-off) on the
concourse crowd, in µs per agent-step.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import crowdbench
from crowdbench.config import WorldConfig
from crowdbench.spatial import GRID_MIN
from crowdbench.worlds import CrowdWorld

BRUTE_FORCE = np.iinfo(np.int64).max


def world_options(n: int) -> dict:
    """The concourse's radii for 1,000 people and more (smaller, so that they fit)."""
    return {"human_radius_range": (0.2, 0.3)} if n >= 1000 else {}


def timed_steps(env, grid_min: int, seed: int, steps: int) -> tuple[float, float]:
    """Wall and CPU seconds per step over ``steps`` steps of the episode ``seed`` (reset outside the timer)."""
    env.world.grid_min = grid_min
    env.reset(seed=seed)
    action = {"robot": np.zeros(2)}
    wall = cpu = 0.0
    for _ in range(steps):
        if not env.agents:
            env.reset(seed=seed + 1)
        t, c = time.perf_counter(), time.process_time()
        env.step(action)
        wall += time.perf_counter() - t
        cpu += time.process_time() - c
    return wall / steps, cpu / steps


def per_agent_bytes(world) -> tuple[float, list[str]]:
    """Bytes per agent of the world's per-agent arrays (module docstring) and their names."""
    B, A, H = world.num_worlds, world.num_agents, world.num_humans
    total, names = 0, []
    for owner, prefix in ((world, "world"), (world.human_model, "model"), (world.physics, "physics")):
        for name, value in vars(owner).items():
            if isinstance(value, np.ndarray) and value.ndim >= 2 and value.shape[0] == B and \
                    value.shape[1] in (A, H):
                total += value.nbytes
                names.append(f"{prefix}.{name}")
    mirror = getattr(world.physics, "mirror", None)
    if isinstance(mirror, np.ndarray) and "physics.mirror" not in names:
        total += mirror.nbytes
        names.append("physics.mirror")
    return total / (B * A), names


def social_force_us(n: int, steps: int) -> float:
    """Social Force's ``step`` in µs per agent-step on the concourse crowd of ``n``."""
    w = CrowdWorld(WorldConfig(num_humans=n, **world_options(n)), 1, "concourse", "social_force")
    w.reset(seeds=[0])
    model = w.human_model
    model.step(w.crowd_state(), w.model_rngs)
    samples = []
    for _ in range(3):
        t = time.perf_counter()
        for _ in range(steps):
            model.step(w.crowd_state(), w.model_rngs)
        samples.append((time.perf_counter() - t) / steps)
    return statistics.median(samples) / n * 1e6


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=40)
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--sizes", type=int, nargs="+", default=[100, 200, 500, 1000])
    a = p.parse_args()
    warm = crowdbench.parallel_env(layout="concourse", num_humans=200, seed=0)
    for g in (GRID_MIN, BRUTE_FORCE):  # compile (or load) every kernel on both paths
        timed_steps(warm, g, 0, 3)
    print(f"PettingZoo concourse, one world, every agent's observation; {a.steps} steps × {a.repeats} repeats, "
          f"medians; grid above {GRID_MIN} agents")
    print(f"{'N':>5} | {'old ms/step':>11} {'new ms/step':>11} {'ratio':>6} | {'old CPU ms':>10} {'new CPU ms':>10} | "
          f"{'old µs/agent-step':>17} {'new µs/agent-step':>17} | {'B/agent':>7}")
    for n in a.sizes:
        env = crowdbench.parallel_env(layout="concourse", num_humans=n, seed=0, **world_options(n))
        timed_steps(env, GRID_MIN, 0, 2)
        old, new = [], []
        for r in range(a.repeats):
            new.append(timed_steps(env, GRID_MIN, r, a.steps))
            old.append(timed_steps(env, BRUTE_FORCE, r, a.steps))
        ow, oc = (statistics.median(x) for x in zip(*old, strict=True))
        nw, nc = (statistics.median(x) for x in zip(*new, strict=True))
        agents = n + 1
        per_agent, names = per_agent_bytes(env.world)
        print(f"{n:>5} | {ow * 1e3:>11.3f} {nw * 1e3:>11.3f} {ow / nw:>5.2f}× | {oc * 1e3:>10.3f} {nc * 1e3:>10.3f} | "
              f"{ow / agents * 1e6:>17.2f} {nw / agents * 1e6:>17.2f} | {per_agent:>7.0f}")
    print(f"bytes per agent: sum of nbytes of {', '.join(names)} / (worlds × agents)")
    print("Social Force step (numpy, all pairs, no cut-off):",
          ", ".join(f"N = {n}: {social_force_us(n, max(2, a.steps // 4)):.1f} µs/agent-step" for n in a.sizes))


if __name__ == "__main__":
    main()
