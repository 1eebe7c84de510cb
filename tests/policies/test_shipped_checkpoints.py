"""Every shipped checkpoint still loads and gives the same actions as when the fixture was recorded.

``tests/data/checkpoint_actions.npz`` holds, per shipped robot-policy checkpoint, the actions of 6 steps in 3 seeded
crossings (10 pedestrians, latent-responsive ORCA at ρ = 0.5, the robot driven by the policy itself: recurrent states
carried), and the pedestrian positions of the shipped ``learned_crowd`` after 6 steps; the GST predictor runs inside
AIG-GST's ``predicted`` observation. Regenerate (only after a deliberate change of a network's numbers) with
``python tests/policies/test_shipped_checkpoints.py``; after shipping or replacing one checkpoint, record only its
entry with ``python tests/policies/test_shipped_checkpoints.py METHOD/NAME`` (e.g. ``sarl/sarl-seed1``): every other
entry stays as recorded.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

FIXTURE = Path(__file__).resolve().parents[1] / "data" / "checkpoint_actions.npz"
WORLDS, STEPS, HUMANS = 3, 6, 10


def shipped() -> list[tuple[str, str]]:
    """(method, checkpoint name) of every shipped robot-policy checkpoint."""
    from crowdbench import checkpoints
    from crowdbench.policies import METHODS

    return [(m, n) for m in METHODS.names() for n in checkpoints.shipped_names(m)]


def shipped_keys() -> set[str]:
    """The fixture's entry ``METHOD/NAME`` of every shipped robot-policy checkpoint."""
    return {f"{m}/{n}" for m, n in shipped()}


def robot_actions(method: str, name: str) -> np.ndarray:
    """Actions ``(STEPS, WORLDS, 2)`` of shipped checkpoint ``name`` of ``method`` driving the robot."""
    from crowdbench.config import WorldConfig
    from crowdbench.policies import make_policy
    from crowdbench.robots import make_observation
    from crowdbench.worlds import CrowdWorld

    cfg = WorldConfig(num_humans=HUMANS)
    policy = make_policy(method, cfg, checkpoint=name)
    world = CrowdWorld(cfg, WORLDS, "circle_crossing", "responsive_orca", {"responsiveness": 0.5})
    world.reset(seeds=list(range(WORLDS)))
    obs = make_observation(policy.observation, cfg, **policy.observation_kwargs)
    out = []
    for _ in range(STEPS):
        action = np.asarray(policy.act(obs.build(world)), np.float64)
        out.append(action)
        world.step(action)
    return np.stack(out)


def learned_crowd_positions() -> np.ndarray:
    """Pedestrian positions ``(WORLDS, HUMANS, 2)`` after ``STEPS`` steps of the shipped ``learned_crowd``."""
    from crowdbench.config import WorldConfig
    from crowdbench.worlds import CrowdWorld

    world = CrowdWorld(WorldConfig(num_humans=HUMANS), WORLDS, "circle_crossing", "learned_crowd")
    world.reset(seeds=list(range(WORLDS)))
    for _ in range(STEPS):
        world.step(np.zeros((WORLDS, 2)))
    return np.asarray(world.pos[:, 1:], np.float64)


def record() -> dict[str, np.ndarray]:
    out = {f"{m}/{n}": robot_actions(m, n) for m, n in shipped()}
    out["humans/learned_crowd"] = learned_crowd_positions()
    return out


@pytest.mark.parametrize(("method", "name"), shipped())
def test_shipped_checkpoint_gives_the_recorded_actions(method, name):
    expected = np.load(FIXTURE)
    assert f"{method}/{name}" in expected.files, f"no recorded actions for {method}/{name}: regenerate the fixture"
    np.testing.assert_allclose(robot_actions(method, name), expected[f"{method}/{name}"], rtol=1e-5, atol=1e-6)


def test_learned_crowd_gives_the_recorded_positions():
    np.testing.assert_allclose(learned_crowd_positions(), np.load(FIXTURE)["humans/learned_crowd"], rtol=1e-6,
                               atol=1e-7)


def test_every_shipped_checkpoint_has_recorded_actions():
    recorded = {k for k in np.load(FIXTURE).files if not k.startswith("humans/")}
    assert recorded == shipped_keys()


def write(entries: dict[str, np.ndarray]) -> None:
    """Write the fixture atomically (:func:`crowdbench.io.atomic_path`)."""
    from crowdbench.io import atomic_path

    with atomic_path(FIXTURE) as tmp:
        np.savez_compressed(tmp, **entries)


def rerecord(keys: list[str]) -> dict[str, np.ndarray]:
    """The fixture with the entries ``keys`` (``METHOD/NAME`` of shipped checkpoints) recorded anew."""
    valid = shipped_keys()
    entries = dict(np.load(FIXTURE))
    for key in keys:
        if key not in valid:
            raise SystemExit(f"entry={key!r}: not a shipped checkpoint; valid choices: {', '.join(sorted(valid))}")
        method, name = key.split("/")
        entries[key] = robot_actions(method, name)
    return entries


if __name__ == "__main__":
    import sys

    write(rerecord(sys.argv[1:]) if len(sys.argv) > 1 else record())
    print(f"wrote {FIXTURE}")
