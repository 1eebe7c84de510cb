"""Peer speed figures, measured like crowdbench's own: CrowdNav's ``CrowdSim`` and Python-RVO2 (``rvo2``).

Run with the *peer* interpreter (not crowdbench's venv), from the repository root::

    /tmp/rvo/venv/bin/python benchmarks/bench_peers.py [--quick] [--crowdnav /tmp/rvo/CrowdNav]

Pins itself to one core and prints one JSON dict:

* ``crowdnav_steps_per_s[N]`` (N = 5, 10, 20) — CrowdNav (vita-epfl/CrowdNav 20d6780) ``CrowdSim.step``, the
  counterpart of crowdbench's ``pettingzoo_steps_per_s`` (``crowdbench.bench.pettingzoo_steps_per_s``): its
  ``crowd_nav/configs/env.config`` unchanged apart from ``human_num`` (circle crossing, radius 4 m, ORCA humans,
  time step 0.25 s, time limit 25 s, robot *invisible* to the humans as in that file, holonomic robot),
  ``env.reset(phase="test")``; the robot's action is ``ActionXY`` toward its goal at ``v_pref`` (computed outside the
  timer). Each of 3 runs times 2,000 ``env.step`` calls (100 with ``--quick``) after 20 warm-up steps; a finished
  episode is followed by ``reset``, outside the timer (``excluded``) or inside it (``included``). ``episodes``: how
  the episodes of the ``included`` runs ended;
* ``crowdnav_reset_ms`` — median ``env.reset`` time at N = 20 (200 resets; 20 with ``--quick``);
* ``rvo2_agent_steps_per_s[N]`` (N = 20, 50, 200) — the counterpart of ``crowdbench.bench.orca_agent_steps_per_s``,
  same crowd (same generator, seed and draws: agents on a circle of radius max(4, N·0.8/(2π)·1.3) with ±0.3 m
  noise, antipodal goals), same parameters (neighborDist 10, maxNeighbors 10, timeHorizon 5, timeHorizonObst 5,
  radius 0.31, maxSpeed 1, time step 0.25), same step and repeat counts (7 repeats of 60 steps, 20 at N = 200;
  ``--quick``: 3 of 10, 3 at N = 200), state carried over between repeats: 64 independent ``PyRVOSimulator``s, one
  per world; each step sets every agent's preferred velocity (toward the goal at speed 1, slowing to land on it, as
  ``crowdbench.humans.preferred_velocity``) outside the timer, then times ``doStep`` on the 64 simulators in turn;
* ``build`` — compiler flags, peer commits, versions, CPU.

``--crowdnav-large N [--circle-radius M]`` measures only CrowdNav at N humans (``crowdnav_large``): the same
``env.config`` with ``human_num = N`` and, if given, ``circle_radius = M`` [m]. The first
``env.reset(phase="test", test_case=0)`` runs under a ``--reset-timeout`` (60 s): CrowdNav's circle-crossing
placement (``crowd_sim/envs/crowd_sim.py:155-176``) redraws a start until it is ``0.3 + 0.3 + discomfort_dist``
= 0.8 m from every start *and goal* already placed, without bound, so a crowd that cannot fit never returns (the
output says how many humans were placed). If it returns, ``env.step`` is timed as above (20 warm-up steps,
resets outside the timer) for ``--large-runs`` (3) runs of ``--large-steps`` (50) steps. The N = 200 figures in
``docs/speed.md`` (``benchmarks/peers-n200-results.json``)::

    /tmp/rvo/venv/bin/python benchmarks/bench_peers.py --crowdnav-large 200                    # 4 m: no reset
    /tmp/rvo/venv/bin/python benchmarks/bench_peers.py --crowdnav-large 200 --circle-radius 40 \
        --large-steps 100 --large-runs 3

Peer environment (what produced /tmp/rvo/venv; the package index is the machine's configured pip index)::

    mkdir -p /tmp/rvo/src /tmp/rvo/CrowdNav && cd /tmp/rvo
    python3.11 -m venv venv        # CPython 3.11.7 (pyenv)
    venv/bin/pip install "cython<3.1" numpy "gym==0.26.2" matplotlib setuptools wheel
    git --git-dir=/work/.mirror/sybrenstuvel+Python-RVO2/repo archive HEAD | tar -x -C src        # c2c46ba
    git --git-dir=/work/.mirror/vita-epfl+CrowdNav/repo archive HEAD | tar -x -C CrowdNav        # 20d6780
    cd src && sed -i "s/'-DCMAKE_CXX_FLAGS=-fPIC'/'-DCMAKE_CXX_FLAGS=-fPIC -O2'/; \\
        s/extra_compile_args=\\['-fPIC'\\]/extra_compile_args=['-fPIC', '-O2']/" setup.py
    ../venv/bin/pip install -v --no-build-isolation . && cd ..
    venv/bin/pip install --no-deps --no-build-isolation ./CrowdNav      # crowd_sim (+ crowd_nav, unused here)

Python-RVO2's setup.py configures RVO2 with ``cmake ../.. -DCMAKE_CXX_FLAGS=-fPIC`` and no build type, i.e. an
unoptimised (-O0) library; the edit above builds ``libRVO.a`` with ``-fPIC -O2`` (CMAKE_BUILD_TYPE empty) and the
Cython wrapper with Python's CFLAGS (``-DNDEBUG -g -fwrapv -O3 -Wall``) followed by ``-fPIC -O2`` (last wins: -O2);
gcc 12.2.0, no ``-march``. CrowdNav's other install requirements (torch, torchvision, scipy, gitpython) are not
needed by ``crowd_sim`` and are skipped. The env is built as ``CrowdSim()`` directly (as ``gym.make`` would, without
gym 0.26's checker wrappers); the robot gets crowd_sim's ``Linear`` policy, only for its holonomic kinematics and
``multiagent_training`` flag (``env.step`` never calls the robot's policy).
"""

from __future__ import annotations

import argparse
import configparser
import contextlib
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

PEERS = {"Python-RVO2": ("sybrenstuvel+Python-RVO2", "c2c46ba8d59556aa10faf03479293236efea154d"),
         "CrowdNav": ("vita-epfl+CrowdNav", "20d678085c06831e658a65b9e20c8bb6f6ecdc10")}
RVO2_BUILD = {"libRVO (cmake)": "-DCMAKE_CXX_FLAGS='-fPIC -O2', CMAKE_BUILD_TYPE empty",
              "rvo2 extension (setuptools)": "-DNDEBUG -g -fwrapv -O3 -Wall -fPIC -O2 (effective -O2)",
              "upstream default": "-DCMAKE_CXX_FLAGS=-fPIC only (unoptimised)"}


def _stats(samples: list[float]) -> dict[str, float]:
    return {"median": float(statistics.median(samples)), "spread": float(max(samples) - min(samples)),
            "runs": len(samples)}


def pin_one_core() -> int:
    """Pin to the lowest core allowed (core 0 unless started under ``taskset``)."""
    os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    return next(iter(os.sched_getaffinity(0)))


# --------------------------------------------------------------------------------------------------- CrowdNav


def make_crowdnav(n: int, crowdnav_dir: Path, circle_radius: float | None = None) -> Any:
    from crowd_sim.envs import CrowdSim
    from crowd_sim.envs.policy.linear import Linear
    from crowd_sim.envs.utils.robot import Robot

    cfg = configparser.RawConfigParser()
    path = crowdnav_dir / "crowd_nav" / "configs" / "env.config"
    if not cfg.read(path):
        raise SystemExit(f"CrowdNav's env.config not found at {path} (see --crowdnav)")
    cfg.set("sim", "human_num", str(n))
    if circle_radius is not None:
        cfg.set("sim", "circle_radius", repr(float(circle_radius)))
    env = CrowdSim()
    env.configure(cfg)
    robot = Robot(cfg, "robot")
    robot.set_policy(Linear())  # holonomic, multiagent_training = True; env.step does not call it
    env.set_robot(robot)
    return env


def _to_goal(env: Any) -> Any:
    from crowd_sim.envs.utils.action import ActionXY

    r = env.robot
    dx, dy = r.gx - r.px, r.gy - r.py
    s = r.v_pref / max(float(np.hypot(dx, dy)), 1e-9)
    return ActionXY(dx * s, dy * s)


def crowdnav_steps_per_s(n: int, steps: int, repeats: int, resets: bool, crowdnav_dir: Path,
                         outcomes: dict[str, int] | None = None,
                         circle_radius: float | None = None) -> dict[str, float]:
    env = make_crowdnav(n, crowdnav_dir, circle_radius)
    env.reset(phase="test", test_case=0)
    for _ in range(20):  # warm-up
        *_, done, _ = env.step(_to_goal(env))
        if done:
            env.reset(phase="test")

    def run(seed: int) -> float:
        env.reset(phase="test", test_case=seed)
        elapsed = 0.0
        for _ in range(steps):
            a = _to_goal(env)
            t = time.perf_counter()
            _, _, done, info = env.step(a)
            if done:
                if resets:
                    env.reset(phase="test")
                    elapsed += time.perf_counter() - t
                else:
                    elapsed += time.perf_counter() - t
                    env.reset(phase="test")
                if outcomes is not None:
                    outcomes[str(info)] = outcomes.get(str(info), 0) + 1
            else:
                elapsed += time.perf_counter() - t
        return steps / elapsed

    return _stats([run(r) for r in range(repeats)])


class _ResetTimeoutError(Exception):
    pass


def crowdnav_large(n: int, circle_radius: float | None, steps: int, repeats: int, reset_timeout: float,
                   crowdnav_dir: Path) -> dict[str, Any]:
    """CrowdNav at a large N: the first ``env.reset(phase="test", test_case=0)`` under a wall-clock limit of
    ``reset_timeout`` s (its rejection sampling loops without bound when the crowd cannot fit); if it returns,
    ``env.step`` timed as in :func:`crowdnav_steps_per_s` (20 warm-up steps, resets outside the timer)."""
    import signal

    def alarm(*_: Any) -> None:
        raise _ResetTimeoutError

    env = make_crowdnav(n, crowdnav_dir, circle_radius)
    out: dict[str, Any] = {"human_num": n, "circle_radius_m": env.circle_radius,
                           "discomfort_dist_m": env.discomfort_dist, "reset_timeout_s": reset_timeout}
    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, reset_timeout)
    t = time.perf_counter()
    try:
        env.reset(phase="test", test_case=0)
    except _ResetTimeoutError:
        out["reset"] = f"did not return within {reset_timeout:g} s ({len(env.humans)} of {n} humans placed)"
        return out
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    out["first_reset_s"] = time.perf_counter() - t
    outcomes: dict[str, int] = {}
    t = time.perf_counter()
    out["steps_per_s"] = crowdnav_steps_per_s(n, steps, repeats, False, crowdnav_dir, outcomes, circle_radius)
    out["steps_per_run"] = steps
    out["episodes"] = outcomes
    out["wall_s"] = time.perf_counter() - t
    return out


def crowdnav_reset_ms(n: int, resets: int, crowdnav_dir: Path) -> dict[str, float]:
    env = make_crowdnav(n, crowdnav_dir)
    samples = []
    for i in range(resets):
        t = time.perf_counter()
        env.reset(phase="test", test_case=i)
        samples.append((time.perf_counter() - t) * 1e3)
    return _stats(samples) | {"max": float(max(samples))}


# ------------------------------------------------------------------------------------------------ Python-RVO2


def _preferred_velocity(pos: np.ndarray, goal: np.ndarray, v_pref: float, dt: float) -> np.ndarray:
    """``crowdbench.humans.preferred_velocity``: toward the goal at v_pref, landing on it when within one step."""
    d = goal - pos
    dist = np.linalg.norm(d, axis=-1)
    scale = np.where(dist < v_pref * dt, 1.0 / dt, v_pref / np.maximum(dist, 1e-12))
    return d * scale[..., None]


def rvo2_agent_steps_per_s(n: int, worlds: int, steps: int, repeats: int) -> dict[str, float]:
    import rvo2

    rng = np.random.default_rng(0)  # the draws of crowdbench.bench.orca_agent_steps_per_s, in its order
    radius = max(4.0, n * 0.8 / (2 * np.pi) * 1.3)
    ang = rng.uniform(0, 2 * np.pi, (worlds, n))
    pos = radius * np.stack([np.cos(ang), np.sin(ang)], -1) + rng.uniform(-0.3, 0.3, (worlds, n, 2))
    goal = -pos
    sims = []
    for w in range(worlds):
        sim = rvo2.PyRVOSimulator(0.25, 10.0, 10, 5.0, 5.0, 0.31, 1.0)
        for i in range(n):
            sim.addAgent((float(pos[w, i, 0]), float(pos[w, i, 1])))
        sim.processObstacles()
        sims.append(sim)
    samples = []
    for _ in range(repeats):
        elapsed = 0.0
        for _ in range(steps):
            for w, sim in enumerate(sims):
                p = np.array([sim.getAgentPosition(i) for i in range(n)])
                pref = _preferred_velocity(p, goal[w], 1.0, 0.25)
                for i in range(n):
                    sim.setAgentPrefVelocity(i, (float(pref[i, 0]), float(pref[i, 1])))
            t = time.perf_counter()
            for sim in sims:
                sim.doStep()
            elapsed += time.perf_counter() - t
        samples.append(steps * worlds * n / elapsed)
    return _stats(samples)


# ------------------------------------------------------------------------------------------------------ build


def _version(module: str) -> str | None:
    with contextlib.suppress(Exception):
        return str(__import__(module).__version__)
    return None


def build_info(crowdnav_dir: Path) -> dict[str, Any]:
    import rvo2

    cpu = platform.machine()
    with contextlib.suppress(OSError, StopIteration), open("/proc/cpuinfo") as f:
        cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    commits: dict[str, Any] = {}
    for name, (mirror, expected) in PEERS.items():
        git_dir = Path("/work/.mirror") / mirror / "repo"
        found = None
        with contextlib.suppress(OSError, subprocess.SubprocessError):
            found = subprocess.run(["git", f"--git-dir={git_dir}", "rev-parse", "HEAD"], capture_output=True,
                                   text=True, check=True).stdout.strip()
        commits[name] = {"commit": expected, "mirror_head": found}
    flags: dict[str, Any] = dict(RVO2_BUILD)
    cmake_cache = Path("/tmp/rvo/src/build/RVO2/CMakeCache.txt")
    with contextlib.suppress(OSError):
        for line in cmake_cache.read_text().splitlines():
            if line.startswith(("CMAKE_CXX_FLAGS:", "CMAKE_BUILD_TYPE:")):
                flags[f"found in {cmake_cache}: {line.split(':')[0]}"] = line.split("=", 1)[1]
    compiler = None
    with contextlib.suppress(OSError, subprocess.SubprocessError, IndexError):
        compiler = subprocess.run(["gcc", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    return {"cpu": cpu, "logical_cores": os.cpu_count(), "python": platform.python_version(),
            "executable": sys.executable, "numpy": np.__version__, "gym": _version("gym"),
            "cython": _version("Cython"), "matplotlib": _version("matplotlib"), "rvo2": str(Path(rvo2.__file__)),
            "compiler": compiler, "flags": flags, "commits": commits,
            "crowdnav_dir": str(crowdnav_dir)}


def interleaved(n_env: tuple[int, ...], n_orca: tuple[int, ...], rounds: int, steps: int,
                crowdnav_dir: Path) -> dict[str, Any]:
    """CrowdNav and crowdbench (and RVO2 and crowdbench's ORCA kernel) measured alternately in this one process,
    one run each per round, so that the machine's slow and fast minutes hit both alike; per-round ratios."""
    from crowdbench.bench import orca_agent_steps_per_s, pettingzoo_steps_per_s

    out: dict[str, Any] = {"env_steps_per_s": {}, "orca_agent_steps_per_s": {}}
    for n in n_env:
        for resets in (False, True):
            peer, ours = [], []
            for _ in range(rounds):
                peer.append(crowdnav_steps_per_s(n, steps, 1, resets, crowdnav_dir)["median"])
                ours.append(pettingzoo_steps_per_s(n, steps, 1, resets)["median"])
            ratios = [o / c for o, c in zip(ours, peer, strict=True)]
            out["env_steps_per_s"][f"{n} resets {'included' if resets else 'excluded'}"] = {
                "crowdnav": _stats(peer), "crowdbench": _stats(ours), "ratio": _stats(ratios)}
    for n in n_orca:
        reps = 20 if n == 200 else 60
        peer, ours = [], []
        for _ in range(rounds):
            peer.append(rvo2_agent_steps_per_s(n, 64, reps, 1)["median"])
            ours.append(orca_agent_steps_per_s(n, 64, reps, 1)["median"])
        ratios = [o / c for o, c in zip(ours, peer, strict=True)]
        out["orca_agent_steps_per_s"][str(n)] = {"rvo2": _stats(peer), "crowdbench": _stats(ours),
                                                 "ratio": _stats(ratios)}
    return out


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--quick", action="store_true", help="fewer steps and repeats (smoke test)")
    p.add_argument("--interleaved", type=int, default=0, metavar="ROUNDS",
                   help="also alternate peer and crowdbench runs ROUNDS times in this process (needs crowdbench "
                        "installed in the peer interpreter: pip install --no-deps -e . plus pettingzoo, gymnasium, "
                        "pymunk, numba) and report per-round speed ratios")
    p.add_argument("--orca-only", action="store_true",
                   help="only the ORCA kernels (RVO2 against crowdbench's orca_batch), skipping CrowdNav's env")
    p.add_argument("--crowdnav", type=Path, default=Path("/tmp/rvo/CrowdNav"),
                   help="CrowdNav checkout (for crowd_nav/configs/env.config)")
    p.add_argument("--crowdnav-large", type=int, default=0, metavar="N",
                   help="only CrowdNav at N humans: whether reset returns, then env.step timed (see docstring)")
    p.add_argument("--circle-radius", type=float, default=None, metavar="M",
                   help="with --crowdnav-large: env.config's circle_radius [m] (default: the file's, 4 m)")
    p.add_argument("--large-steps", type=int, default=50, help="with --crowdnav-large: timed steps per run")
    p.add_argument("--large-runs", type=int, default=3, help="with --crowdnav-large: timed runs")
    p.add_argument("--reset-timeout", type=float, default=60.0, metavar="S",
                   help="with --crowdnav-large: give up on the first reset after S seconds")
    args = p.parse_args()
    core = pin_one_core()
    if args.crowdnav_large:
        res_large = {"pinned_core": core, "crowdnav_large": crowdnav_large(
            args.crowdnav_large, args.circle_radius, args.large_steps, args.large_runs, args.reset_timeout,
            args.crowdnav), "build": build_info(args.crowdnav)}
        print(json.dumps(res_large, indent=2))
        return
    quick = args.quick
    res: dict[str, Any] = {"quick": quick, "pinned_core": core, "crowdnav_steps_per_s": {}, "crowdnav_reset_ms": {},
                           "rvo2_agent_steps_per_s": {}}
    steps = 100 if quick else 2000
    for n in () if args.orca_only else (5, 10, 20):
        outcomes: dict[str, int] = {}
        res["crowdnav_steps_per_s"][str(n)] = {
            "excluded": crowdnav_steps_per_s(n, steps, 3, False, args.crowdnav),
            "included": crowdnav_steps_per_s(n, steps, 3, True, args.crowdnav, outcomes),
            "episodes": outcomes}
    if not args.orca_only:
        res["crowdnav_reset_ms"]["20"] = crowdnav_reset_ms(20, 20 if quick else 200, args.crowdnav)
    rep = 3 if quick else 7
    for n in (20, 50, 200):
        res["rvo2_agent_steps_per_s"][str(n)] = rvo2_agent_steps_per_s(
            n, 64, (3 if quick else 20) if n == 200 else (10 if quick else 60), rep)
    if args.interleaved:
        n_env = () if args.orca_only else (5, 10, 20)
        res["interleaved"] = interleaved(n_env, (20, 50, 200), args.interleaved, steps, args.crowdnav)
    res["build"] = build_info(args.crowdnav)
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
