"""Several training seeds at once: ``crowdbench train METHOD --seeds 0,1,2 [--backend local|ray]``.

Each seed is the same ``crowdbench train`` command with ``--seed S --out OUT/seedS`` — a run of its own, in its own
process (local worker processes, or Ray tasks on this machine or an existing cluster with ``--ray-address``). A
seed's run depends on its command alone, so the results equal training the seeds one by one (tested), whatever the
backend or the number of workers.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

BACKENDS = ("local", "ray")
_DROP = {"--seeds": 1, "--backend": 1, "--ray-address": 1, "--seed-workers": 1, "--seed": 1, "--out": 1}


def seed_commands(argv: Sequence[str], seeds: Sequence[int], out: str) -> list[list[str]]:
    """The per-seed command lines: ``argv`` (``crowdbench`` arguments) without the multi-seed options, ``--seed`` and
    ``--out``, plus ``--seed S --out OUT/seedS``."""
    base: list[str] = []
    skip = 0
    for token in argv:
        if skip:
            skip -= 1
            continue
        name = token.split("=", 1)[0]
        if name in _DROP:
            skip = 0 if "=" in token else _DROP[name]
            continue
        base.append(token)
    return [[*base, "--seed", str(s), "--out", os.path.join(out, f"seed{s}")] for s in seeds]


def _run(argv: list[str]) -> int:
    from crowdbench.cli import main

    return main(argv)


def run_seeds(commands: list[list[str]], backend: str = "local", workers: int | None = None,
              ray_address: str | None = None) -> list[int]:
    """Run every command (``_run``) on ``backend``; returns their exit codes in order."""
    if backend not in BACKENDS:
        raise ValueError(f"--backend {backend!r}; valid choices: {', '.join(BACKENDS)}")
    if backend == "ray":
        try:
            import ray
        except ImportError:
            raise ValueError("--backend ray needs Ray: pip install 'crowdbench[ray]'") from None
        ray.init(address=ray_address, ignore_reinit_error=True)
        task = ray.remote(num_cpus=1)(_run)
        return list(ray.get([task.remote(c) for c in commands]))
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    ctx = mp.get_context("spawn")  # a fresh interpreter per seed, as a separate command would be
    with ProcessPoolExecutor(max_workers=workers or min(len(commands), os.cpu_count() or 1), mp_context=ctx) as pool:
        return list(pool.map(_run, commands))
