"""Shared helpers for the benchmark scripts: single-core pinning, timing, machine description."""

from __future__ import annotations

import contextlib
import os
import platform
import statistics
import time
from collections.abc import Callable

import numpy as np

from crowdbench.humans import HumanModel


def pin_one_core() -> None:
    """Run on one core (as the targets are stated) where the OS allows it."""
    with contextlib.suppress(AttributeError, OSError):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    import numba
    import pymunk

    return (f"{cpu}; {os.cpu_count()} logical cores; Python {platform.python_version()}; numpy {np.__version__}; "
            f"numba {numba.__version__}; pymunk {pymunk.version}")


def time_it(fn: Callable[[], object], repeats: int = 7, number: int = 1) -> tuple[float, float]:
    """Median and spread (max - min) in seconds per call over ``repeats`` runs of ``number`` calls."""
    samples = []
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(number):
            fn()
        samples.append((time.perf_counter() - t) / number)
    return statistics.median(samples), max(samples) - min(samples)


class ConstantVelocity(HumanModel):
    """Zero-cost pedestrian model (returns a precomputed velocity array) to time the world without a model."""

    def bind(self, num_worlds, num_humans, obstacles, time_step):
        super().bind(num_worlds, num_humans, obstacles, time_step)
        rng = np.random.default_rng(0)
        self.v = rng.uniform(-0.7, 0.7, (num_worlds, num_humans, 2))

    def step(self, state, rngs):
        return self.v
