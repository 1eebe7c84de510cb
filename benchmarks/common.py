"""Shared helpers for the benchmark scripts: single-core pinning, timing, machine description."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

import numpy as np

from crowdbench.bench import machine as bench_machine
from crowdbench.bench import one_core
from crowdbench.humans import HumanModel


def pin_one_core() -> None:
    """Run the rest of the script on one core (as the targets are stated)."""
    one_core().__enter__()


def machine() -> str:
    m = bench_machine()
    return (f"{m['cpu']}; {m['logical_cores']} logical cores; Python {m['python']}; numpy {m['numpy']}; "
            f"numba {m['numba']}; pymunk {m['pymunk']}")


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
