"""Shared helpers of the policy tests."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest


@pytest.fixture
def shipped_against_straight() -> Callable[..., tuple[dict[str, Any], dict[str, Any], dict[str, Any]]]:
    """``f(method, humans, episodes)`` → (the shipped ``method`` checkpoint loaded with ``weights_only=True``, its
    summary, the straight-driving robot's summary) on the same seeded crossings at ρ = 0.5 (two episodes per world)."""
    from crowdbench import checkpoints
    from crowdbench.evaluation import run_episodes, summarize
    from crowdbench.policies import make_policy

    def run(method: str, humans: int, episodes: int) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
        assert method in checkpoints.shipped_names(method)
        ckpt = checkpoints.load(checkpoints.shipped(method, method), method)
        kw = {"num_humans": humans, "human_model_kwargs": {"responsiveness": 0.5}, "seed": 0,
              "num_worlds": episodes // 2}
        return (ckpt, summarize(run_episodes(make_policy(method), episodes, **kw)),
                summarize(run_episodes(make_policy("linear"), episodes, **kw)))

    return run
