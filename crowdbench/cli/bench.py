"""``crowdbench bench``: throughput figures of the simulator, the ORCA kernel, training and H²INT inference.

Figures (medians of repeated runs, with the spread = max − min):

* ``env_steps_per_s[N][batch]`` — circle crossing with latent-responsive ORCA pedestrians, world + pedestrian model
  + robot observation, constant robot action, one core; each repeat times 200 consecutive steps (one 50 s episode
  length, so the congested crossing phase and goal renewals are included, not just the cheap first steps);
* ``pettingzoo_steps_per_s[N]`` — one world through ``crowdbench.parallel_env`` (ORCA pedestrians, every agent's
  observation and info built, robot heading for its goal), one core, 3 × 2,000 ``env.step`` calls, with resets
  ``excluded`` from and ``included`` in the timing (the issue-18 comparison with CrowdNav: README, "Speed");
* ``orca_agent_steps_per_s[N]`` — the ORCA kernel alone, 64 worlds of N agents, one core;
* ``train_steps_per_s`` — H²INT PPO training end to end (rollout + update), default configuration (both cores:
  two world processes that act and step, two threads in the update), 10 iterations from scratch after 2 warm-up
  iterations, evaluations off; ``train_steps_per_s_1_core`` — the same pinned to one core (one process, one thread);
  ``train_steps_per_s_by_method`` — the same for DS-RNN and AIG-GST with their own recipes at the original widths
  (``--variant original``; their ``small`` default trains 3–7× faster, README), 3 iterations;
* ``h2int_inference_ms`` — one decision for one robot (encoder + GRU + head), CPU, one thread;
* ``decision_ms[policy]`` — one decision of *every registered robot policy* in a 20-pedestrian crossing (policies
  registered later, e.g. look-ahead baselines, get their figure automatically).

Writes ``benchmarks/RESULTS.md`` and ``benchmarks/throughput.png`` (steps/s against N and against batch size).
"""

from __future__ import annotations

import contextlib
import inspect
import json
import os
import platform
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from crowdbench.leaderboard.provenance import cpu_model
from crowdbench.policies import POLICIES, REFERENCE_METHOD, make_policy, trained_by
from crowdbench.training.methods import PPO_METHODS

TARGETS = {"pettingzoo_steps_per_s N=5 (resets excluded)": 32_000,
           "pettingzoo_steps_per_s N=10 (resets excluded)": 12_000,
           "pettingzoo_steps_per_s N=20 (resets excluded)": 4_000,
           "env_steps_per_s N=20 batch=64": 10_000, "orca_agent_steps_per_s N=20": 2_500_000,
           "train_steps_per_s": 5_000, f"{REFERENCE_METHOD}_inference_ms": 1.0}
INFERENCE = f"{REFERENCE_METHOD}_inference_ms"
"""Key of the reference method's inference figure (:func:`h2int_inference_ms`)."""


def machine() -> dict[str, Any]:
    """CPU model, cores and library versions."""
    cpu = cpu_model()
    import numba
    import pymunk
    import torch

    import crowdbench

    return {"cpu": cpu, "logical_cores": os.cpu_count(), "python": platform.python_version(),
            "numpy": np.__version__, "numba": numba.__version__, "pymunk": pymunk.version, "torch": torch.__version__,
            "crowdbench": crowdbench.__version__}


def _stats(samples: list[float]) -> dict[str, float]:
    return {"median": float(statistics.median(samples)), "spread": float(max(samples) - min(samples)),
            "runs": len(samples)}


def one_core() -> contextlib.AbstractContextManager:
    """Context manager pinning this process to one core (where the OS allows it)."""
    @contextlib.contextmanager
    def pin():
        try:
            before = os.sched_getaffinity(0)
            os.sched_setaffinity(0, {min(before)})
        except (AttributeError, OSError):
            before = None
        try:
            yield
        finally:
            if before is not None:
                os.sched_setaffinity(0, before)

    return pin()


def _repeat(fn: Callable[[], float], repeats: int) -> dict[str, float]:
    return _stats([fn() for _ in range(repeats)])


def env_steps_per_s(n: int, batch: int, steps: int, repeats: int) -> dict[str, float]:
    from crowdbench.config import WorldConfig
    from crowdbench.robots import make_observation
    from crowdbench.worlds import CrowdWorld

    w = CrowdWorld(WorldConfig(num_humans=n, time_limit=1e9), batch, "circle_crossing", "responsive_orca")
    obs = make_observation("relative", w.config)
    action = np.tile([0.0, 0.5], (batch, 1))
    w.step(action)

    def run() -> float:
        t = time.perf_counter()
        for _ in range(steps):
            w.step(action)
            obs.build(w)
        return steps * batch / (time.perf_counter() - t)

    return _repeat(run, repeats)


def pettingzoo_steps_per_s(n: int, steps: int, repeats: int, resets: bool,
                           layout: Any = "circle_crossing") -> dict[str, float]:
    """One world through ``crowdbench.parallel_env`` (defaults: circle crossing, ORCA pedestrians, every agent's
    observation and info built; no pedestrian reward, like for like with CrowdNav): the robot heads for its goal at
    full speed (computed from its observation, outside the timer), pedestrians are model-driven. Each repeat times
    ``steps`` calls of ``env.step``; a finished episode is followed by ``reset`` — inside the timer when
    ``resets``, outside otherwise (as CrowdNav's figures are quoted both ways). ``layout``: a layout name or
    instance (e.g. ``CircleCrossing(radius=40)`` for a crowd too large for the default circle)."""
    import crowdbench

    env = crowdbench.parallel_env(layout=layout, num_humans=n, human_reward="none")  # no pedestrian rewards

    def action(obs: dict) -> dict[str, np.ndarray]:
        r = obs["robot"]["robot"]
        d = r[3:5] - r[0:2]
        return {"robot": d / max(float(np.hypot(*d)), 1e-9)}

    obs, _ = env.reset(seed=0)
    for _ in range(20):  # warm-up (compiled kernels)
        obs, *_ = env.step(action(obs))

    def run(seed: int) -> float:
        obs, _ = env.reset(seed=seed)
        elapsed, episodes = 0.0, seed
        for _ in range(steps):
            a = action(obs)
            t = time.perf_counter()
            obs, _, term, trunc, _ = env.step(a)
            if term["robot"] or trunc["robot"]:
                if resets:
                    obs, _ = env.reset(seed=episodes + 1000)
                    elapsed += time.perf_counter() - t
                else:
                    elapsed += time.perf_counter() - t
                    obs, _ = env.reset(seed=episodes + 1000)
                episodes += 1
            else:
                elapsed += time.perf_counter() - t
        return steps / elapsed

    return _stats([run(r) for r in range(repeats)])


def crowd_control_steps_per_s(n: int, worlds: int, steps: int, repeats: int) -> dict[str, dict[str, float]]:
    """Steps per second with every pedestrian driven from outside (random normalised actions, the multi-agent
    testbed) against the same crowd driven by ORCA, in alternation: ``worlds == 1`` through
    ``crowdbench.parallel_env(robot=None)``, else the batched :class:`~crowdbench.envs.marl.CrowdMARLEnv`
    (``step(None)``: the model drives) — observations and rewards built alike (figures: env steps/s, one world;
    world steps/s × worlds, batched)."""
    import crowdbench
    from crowdbench.envs.marl import CrowdMARLEnv

    rng = np.random.default_rng(0)
    if worlds == 1:
        env = crowdbench.parallel_env(num_humans=n, robot=None, time_limit=1e9)
        env.reset(seed=0)
        acts = [{f"human_{i}": rng.uniform(-1, 1, 2) for i in range(n)} for _ in range(steps)]

        def run(driven: bool) -> float:
            env.reset(seed=0)
            t = time.perf_counter()
            for k in range(steps):
                env.step(acts[k] if driven else {})
            return steps / (time.perf_counter() - t)
    else:
        marl = CrowdMARLEnv(num_worlds=worlds, num_humans=n, robot=None, device=None, time_limit=1e9)
        acts = rng.uniform(-1, 1, (steps, worlds, n, 2))

        def run(driven: bool) -> float:
            marl.reset(seed=0)
            t = time.perf_counter()
            for k in range(steps):
                marl.step(acts[k] if driven else None)
            return steps * worlds / (time.perf_counter() - t)

    run(True), run(False)  # warm-up (compiled kernels)
    out: dict[str, list[float]] = {"driven": [], "model": []}
    for _ in range(repeats):  # alternated, so drift hits both alike
        out["driven"].append(run(True))
        out["model"].append(run(False))
    return {k: _stats(v) for k, v in out.items()}


def bench_crowd(n: int, worlds: int, crowd: str = "circle") -> np.ndarray:
    """Start positions ``(worlds, n, 2)`` [m] of the ORCA scaling crowds (goal = −start, through the centre):
    ``circle`` — a ring of radius max(4, 0.8·n/2π·1.3) m, ±0.3 m jitter (people overlap from n ≈ 100);
    ``grid`` — a square lattice of 1.2 m pitch centred on the origin, ±0.2 m jitter: nobody overlaps at the start."""
    rng = np.random.default_rng(0)
    if crowd == "circle":
        radius = max(4.0, n * 0.8 / (2 * np.pi) * 1.3)
        ang = rng.uniform(0, 2 * np.pi, (worlds, n))
        return radius * np.stack([np.cos(ang), np.sin(ang)], -1) + rng.uniform(-0.3, 0.3, (worlds, n, 2))
    if crowd == "grid":
        side = int(np.ceil(np.sqrt(n)))
        xy = np.stack(np.meshgrid(np.arange(side), np.arange(side)), -1).reshape(-1, 2)[:n] * 1.2
        return (xy - xy.mean(0))[None] + rng.uniform(-0.2, 0.2, (worlds, n, 2))
    raise ValueError(f"crowd={crowd!r}; valid choices: circle, grid")


@dataclass(frozen=True)
class ORCABenchParams:
    """The ORCA scaling benchmarks' agent parameters (this module's, ``benchmarks/bench_orca_rvo2.py``'s and
    ``benchmarks/bench_orca_obstacles.py``'s; every agent alike)."""

    dt: float = 0.25
    """Time step [s]."""
    neighbor_dist: float = 10.0
    """Neighbour distance [m]."""
    max_neighbors: int = 10
    """Neighbours per agent [-]."""
    horizon: float = 5.0
    """Time horizon, for agents and for obstacles [s]."""
    radius: float = 0.31
    """Radius [m]."""
    max_speed: float = 1.0
    """Largest speed, also the preferred speed [m/s]."""

    def batch_args(self, worlds: int, n: int) -> tuple[np.ndarray, ...]:
        """``orca_batch``'s per-agent arguments from ``radius`` to ``ignore`` for ``worlds`` × ``n`` agents, every
        agent active and controlled, none ignored."""
        f = np.ones((worlds, n))
        return (self.radius * f, self.max_speed * f, self.neighbor_dist * f, np.full((worlds, n), self.max_neighbors,
                np.int64), self.horizon * f, self.horizon * f, f > 0, f > 0, np.full((worlds, n), -1, np.int64))

    def simulator_args(self) -> tuple[float, float, int, float, float, float, float]:
        """``PyRVOSimulator(timeStep, neighborDist, maxNeighbors, timeHorizon, timeHorizonObst, radius, maxSpeed)``'s
        arguments (RVO2's and crowdbench's drop-in alike)."""
        return (self.dt, self.neighbor_dist, self.max_neighbors, self.horizon, self.horizon, self.radius,
                self.max_speed)


ORCA_BENCH = ORCABenchParams()


def orca_agent_steps_per_s(n: int, worlds: int, steps: int, repeats: int, crowd: str = "circle"
                           ) -> dict[str, float]:
    """ORCA agent-steps per second of the compiled kernel alone on :func:`bench_crowd` ``crowd`` (parameters
    :data:`ORCA_BENCH`: neighbour distance 10 m, 10 neighbours, radius 0.31 m, speed 1 m/s, dt 0.25 s)."""
    from crowdbench.humans import preferred_velocity
    from crowdbench.humans.orca_kernel import build_obstacles, orca_batch

    P = ORCA_BENCH
    pos = bench_crowd(n, worlds, crowd)
    goal, vel, f = -pos, np.zeros_like(pos), np.full((worlds, n), P.max_speed)
    args = P.batch_args(worlds, n)
    obst, out = build_obstacles([]), np.empty_like(pos)
    orca_batch(pos, vel, preferred_velocity(pos, goal, f, P.dt), *args, *obst, P.dt, out)
    samples = []
    for _ in range(repeats):
        elapsed = 0.0
        for _ in range(steps):
            pref = preferred_velocity(pos, goal, f, P.dt)
            t = time.perf_counter()
            orca_batch(pos, vel, pref, *args, *obst, P.dt, out)
            elapsed += time.perf_counter() - t
            vel = out.copy()
            pos = pos + vel * P.dt
        samples.append(steps * worlds * n / elapsed)
    return _stats(samples)


def train_steps_per_s(iterations: int, repeats: int, threads: int = 2, env_processes: int = 2,
                      method: str = REFERENCE_METHOD, variant: str | None = None) -> dict[str, float]:
    """Env steps per second of ``crowdbench train METHOD``'s loop (rollout + PPO update, evaluations off), the
    method's recipe and ``variant`` (``None``: its default) apart from the speed settings given."""
    import tempfile

    from crowdbench.training.config import TrainConfig
    from crowdbench.training.trainer import Trainer

    model = PPO_METHODS.get(method)().variant_model(variant)
    samples = []
    for r in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            cfg = TrainConfig.for_method(method, model=model, iterations=iterations + 2, eval_every=0,
                                         checkpoint_every=10**6, seed=r, threads=threads, env_processes=env_processes)
            tr = Trainer(cfg, tmp, quiet=True)
            try:
                tr.train(stop_at=2)  # warm-up (numba compilation, allocator)
                steps0, t = tr.env_steps, time.perf_counter()
                tr.train()
                samples.append((tr.env_steps - steps0) / (time.perf_counter() - t))
            finally:
                tr.close()
    return _stats(samples)


def h2int_inference_ms(repeats: int, checkpoint: str | None = None,
                       method: str = REFERENCE_METHOD) -> dict[str, float]:
    """One decision of the reference method's shipped (or ``checkpoint``) policy for one robot, 12 pedestrians in
    view, one thread [ms]: the ``{REFERENCE_METHOD}_inference_ms`` figure."""
    import torch

    from crowdbench.config import WorldConfig

    torch.set_num_threads(1)
    policy = make_policy(method, WorldConfig(), **({"checkpoint": checkpoint} if checkpoint else {}))
    rng = np.random.default_rng(0)
    k = 12  # pedestrians in view
    obs = {"robot": rng.normal(size=(1, 9)).astype(np.float32),
           "humans": np.zeros((1, 30, 2), np.float32), "mask": np.zeros((1, 30), np.float32)}
    obs["humans"][0, :k] = rng.normal(scale=2, size=(k, 2))
    obs["mask"][0, :k] = 1
    return _act_ms(policy, obs, repeats)


def _act_ms(policy: Any, obs: dict[str, np.ndarray], repeats: int, calls: int = 200) -> dict[str, float]:
    """Milliseconds per ``policy.act(obs)``: 20 warm-up calls, then ``repeats`` timings of ``calls`` calls each."""
    for _ in range(20):
        policy.act(obs)

    def timed() -> float:
        t = time.perf_counter()
        for _ in range(calls):
            policy.act(obs)
        return (time.perf_counter() - t) / calls * 1e3

    return _repeat(timed, repeats)


def decision_ms(policy_name: str, repeats: int, num_humans: int = 20, threads: int = 1,
                **policy_kwargs: Any) -> dict[str, float]:
    """One decision of a registered robot policy for one robot [ms]: circle crossing, ``num_humans`` latent-responsive
    pedestrians after 20 steps (a realistic crowd around the robot), the policy's own observation, ``threads`` torch
    threads (restored afterwards)."""
    import torch

    from crowdbench.config import WorldConfig
    from crowdbench.robots import make_observation
    from crowdbench.worlds import CrowdWorld

    before = torch.get_num_threads()
    torch.set_num_threads(threads)
    try:
        cfg = WorldConfig(num_humans=num_humans)
        policy = make_policy(policy_name, cfg, **policy_kwargs)
        world = CrowdWorld(cfg, 1, "circle_crossing", "responsive_orca", {"responsiveness": 0.5})
        world.reset(seeds=[0])
        for _ in range(20):
            world.step(np.zeros((1, 2)))
        obs = make_observation(policy.observation, cfg, **policy.observation_kwargs).build(world)
        return _act_ms(policy, obs, repeats)
    finally:
        torch.set_num_threads(before)


def decision_ms_all(repeats: int, threads: int = 1) -> dict[str, Any]:
    """:func:`decision_ms` of every registered robot policy with ``threads`` torch threads — a policy added to the
    registry (or through the ``crowdbench.policies`` entry point) gets its figure without touching this module.
    Policies that cannot be built with default arguments are reported with the reason."""
    out: dict[str, Any] = {}
    for name in POLICIES.names():
        try:
            out[name] = decision_ms(name, repeats, threads=threads)
        except Exception as e:  # noqa: BLE001 - reported, the other figures still run
            out[name] = {"skipped": f"{type(e).__name__}: {e}"}
    for name in POLICIES.names():  # a look-ahead's cost grows with the pedestrians sensed: also the worst case
        if "skipped" not in out[name] and "sensing_range" in inspect.signature(POLICIES.get(name)).parameters:
            out[f"{name}, all sensed"] = decision_ms(name, repeats, threads=threads, sensing_range=1e9)
    return out


def all_cores() -> int:
    """The cores this process may run on (its affinity where the OS reports one)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def run(quick: bool = False) -> dict[str, Any]:
    """All figures; ``quick`` uses fewer steps and repeats (for smoke tests and CI)."""
    rep = 3 if quick else 7
    res: dict[str, Any] = {"machine": machine(), "quick": quick, "env_steps_per_s": {}, "orca_agent_steps_per_s": {},
                           "pettingzoo_steps_per_s": {}}
    with one_core():
        for n in (5, 10, 20):
            steps = 100 if quick else 2000
            res["pettingzoo_steps_per_s"][str(n)] = {
                "excluded": pettingzoo_steps_per_s(n, steps, 3, resets=False),
                "included": pettingzoo_steps_per_s(n, steps, 3, resets=True)}
        for n in (10, 20, 30, 50):
            res["env_steps_per_s"][str(n)] = {
                "1": env_steps_per_s(n, 1, 20 if quick else 200, rep),
                "64": env_steps_per_s(n, 64, 5 if quick else 200, rep)}
        for n in (20, 50, 200):
            res["orca_agent_steps_per_s"][str(n)] = orca_agent_steps_per_s(n, 64, (3 if quick else 20)
                                                                           if n == 200 else (10 if quick else 60), rep)
        res["orca_agent_steps_per_s_one_world"] = {
            crowd: {str(n): orca_agent_steps_per_s(n, 1, 5 if quick else 20, rep, crowd) for n in (200, 1000)}
            for crowd in ("circle", "grid")}
        res["crowd_control_steps_per_s"] = {
            "1": crowd_control_steps_per_s(20, 1, 100 if quick else 1000, rep),
            "64": crowd_control_steps_per_s(20, 64, 5 if quick else 100, rep)}
        res[INFERENCE] = h2int_inference_ms(rep)
        res["decision_ms"] = decision_ms_all(rep)
    # a robot's computer gives its planner every core: the same decisions (bitwise for CADRL and SARL, tested),
    # the products split across threads
    cores = all_cores()
    res["decision_ms_all_cores"] = {"threads": cores, **decision_ms_all(rep, cores)}
    res["train_steps_per_s"] = train_steps_per_s(2 if quick else 10, 1 if quick else 3)
    with one_core():
        res["train_steps_per_s_1_core"] = train_steps_per_s(2 if quick else 10, 1 if quick else 3, 1, 1)
    res["train_steps_per_s_by_method"] = {}
    for method in trained_by("ppo"):  # the other PPO methods' own recipes (baselines: 192 worlds × 30 steps)
        if method == REFERENCE_METHOD:
            continue
        try:
            variant = "original" if "original" in PPO_METHODS.get(method).variants else None
            res["train_steps_per_s_by_method"][method] = train_steps_per_s(1 if quick else 3, 1, method=method,
                                                                               variant=variant)
        except Exception as e:  # noqa: BLE001 - reported (e.g. no shipped predictor yet), the rest still runs
            res["train_steps_per_s_by_method"][method] = {"skipped": f"{type(e).__name__}: {e}"}
    return res


def results_markdown(res: dict[str, Any]) -> str:
    m = res["machine"]
    lines = ["# Benchmark results", "", f"`crowdbench bench{' --quick' if res['quick'] else ''}` on {m['cpu']}, "
             f"{m['logical_cores']} logical cores; Python {m['python']}, numpy {m['numpy']}, numba {m['numba']}, "
             f"pymunk {m['pymunk']}, torch {m['torch']}. Medians (spread = max − min); one core unless stated.", "",
             "| figure | N | batch | median | spread |", "|---|---|---|---|---|"]
    for n, by_r in res.get("pettingzoo_steps_per_s", {}).items():
        for resets, s in by_r.items():
            lines.append(f"| pettingzoo_steps_per_s (one world, resets {resets}) | {n} | 1 | {s['median']:,.0f} | "
                         f"{s['spread']:,.0f} |")
    for n, by_b in res["env_steps_per_s"].items():
        for b, s in by_b.items():
            lines.append(f"| env_steps_per_s | {n} | {b} | {s['median']:,.0f} | {s['spread']:,.0f} |")
    for n, s in res["orca_agent_steps_per_s"].items():
        lines.append(f"| orca_agent_steps_per_s | {n} | 64 | {s['median']:,.0f} | {s['spread']:,.0f} |")
    s = res["train_steps_per_s"]
    lines.append(f"| train_steps_per_s (2 cores: 2 threads, 2 env processes) | 10–30 | 256 | {s['median']:,.0f} | "
                 f"{s['spread']:,.0f} |")
    if "train_steps_per_s_1_core" in res:
        s = res["train_steps_per_s_1_core"]
        lines.append(f"| train_steps_per_s (1 core: 1 thread, 1 env process) | 10–30 | 256 | {s['median']:,.0f} | "
                     f"{s['spread']:,.0f} |")
    for method, s in res.get("train_steps_per_s_by_method", {}).items():
        figure = f"{s['median']:,.0f} | {s['spread']:,.0f}" if "median" in s else f"skipped: {s['skipped']} |"
        lines.append(f"| train_steps_per_s ({method}, original widths, its recipe, 2 cores) | 10–30 | 192 | {figure} |")
    s = res[INFERENCE]
    lines.append(f"| {INFERENCE} | 12 seen | 1 | {s['median']:.3f} | {s['spread']:.3f} |")
    by_cores = dict(res.get("decision_ms_all_cores", {}))
    threads = by_cores.pop("threads", None)
    for suffix, figures in (("", res.get("decision_ms", {})), (f", {threads} threads", by_cores)):
        for name, s in figures.items():
            label = f"| decision_ms ({name}{suffix}) | 20 | 1 |"
            lines.append(f"{label} {s['median']:.3f} | {s['spread']:.3f} |" if "median" in s
                         else f"{label} skipped: {s['skipped']} | |")
    lines += ["", "Targets: " + "; ".join(f"{k} {'≤' if 'ms' in k else '≥'} {v:,}" for k, v in TARGETS.items()), ""]
    return "\n".join(lines)


def plot(res: dict[str, Any], path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crowdbench.io import atomic_path

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), dpi=100)
    ns = [int(n) for n in res["env_steps_per_s"]]
    for b, style in (("64", "o-"), ("1", "s--")):
        axes[0].plot(ns, [res["env_steps_per_s"][str(n)][b]["median"] for n in ns], style, label=f"batch {b}")
    axes[0].set(xlabel="pedestrians N", ylabel="env steps / s (one core)", yscale="log",
                title="circle crossing, latent-responsive ORCA")
    axes[0].legend()
    batches = [1, 8, 16, 32, 64, 128, 256] if not res.get("quick") else [1, 16, 64]
    rates = [env_steps_per_s(20, b, 200 if not res.get("quick") else 5, 3)["median"] for b in batches]
    axes[1].plot(batches, rates, "o-")
    axes[1].set(xlabel="worlds stepped together", ylabel="env steps / s (one core)", xscale="log", yscale="log",
                title="N = 20")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    with atomic_path(path, suffix=".png") as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)


def main(quick: bool = False, json_path: str | None = None, out_dir: str = "benchmarks") -> dict[str, Any]:
    from crowdbench.io import write_text

    res = run(quick)
    md = results_markdown(res)
    print(md)
    os.makedirs(out_dir, exist_ok=True)
    write_text(os.path.join(out_dir, "RESULTS.md"), md)
    with one_core():
        plot(res, os.path.join(out_dir, "throughput.png"))
    if json_path:
        write_text(json_path, json.dumps(res, indent=2) + "\n")
    return res
