"""Invariants over random layouts, crowd sizes N ∈ [0, 50], seeds and every pedestrian model: no NaN or inf, speeds
within each agent's limit, nobody leaves the walled arena."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from crowdbench.config import make_config
from crowdbench.humans import HUMAN_MODELS
from crowdbench.humans.learned import CHECKPOINT
from crowdbench.worlds import LAYOUTS, CrowdWorld

BUILT_IN_MODELS = tuple(m for m in HUMAN_MODELS.names()  # at collection, before any test registers a plug-in
                        if m != "learned_crowd" or CHECKPOINT.exists())
RECORDED = ("eth", "hotel", "univ", "zara1", "zara2")
"""The replay models replay these scenes' people (any other layout is one clear error, tested elsewhere)."""


def _fits(fn) -> bool:
    """Run a constructor or reset; False when the layout cannot fit the crowd for these seeds (a clear
    ``ValueError`` naming ``num_humans`` is the correct answer, tested elsewhere)."""
    try:
        fn()
    except ValueError as e:
        if "cannot fit" not in str(e):
            raise
        return False
    return True


@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
@given(layout=st.sampled_from(LAYOUTS.names()), n=st.integers(0, 50), seed=st.integers(0, 2**31 - 1),
       model=st.sampled_from(BUILT_IN_MODELS), speed=st.floats(0.5, 2.0))
def test_state_stays_finite_bounded_and_inside_the_arena(layout, n, seed, model, speed):
    if model in ("replay", "reactive_replay") and layout not in RECORDED:
        layout = RECORDED[seed % len(RECORDED)]
    worlds = []
    if not _fits(lambda: worlds.append(CrowdWorld(make_config(num_humans=n, arena_walls=True, robot_v_pref=speed),
                                                  3, layout, model))):
        return
    w = worlds[0]
    if not _fits(lambda: w.reset(seeds=[seed, seed + 1, seed + 2])):
        return
    rng = np.random.default_rng(seed)
    half = w.layout.half_size
    for _ in range(80):
        r = w.step(rng.uniform(-3, 3, (3, 2)))  # wild robot commands: clipped to v_pref
        act = w.active
        assert np.isfinite(w.pos[act]).all() and np.isfinite(w.vel[act]).all() and np.isfinite(r.reward).all()
        assert (np.linalg.norm(w.vel, axis=-1)[act] <= w.v_pref[act] + 1e-9).all()
        assert (np.abs(w.pos[act]) <= half + 1e-6).all(), "an agent left the walled arena"
        done = r.terminated | r.truncated
        seeds = [int(s) for s in rng.integers(0, 2**31, done.sum())]
        if done.any() and not _fits(lambda done=done, seeds=seeds: w.reset(seeds=seeds, mask=done)):
            return
