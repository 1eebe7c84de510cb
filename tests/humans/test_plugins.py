"""Pedestrian-model plug-ins: registry, error message, a third-party package found through its entry point."""

from __future__ import annotations

import sys
import textwrap

import numpy as np
import pytest

import crowdbench
from crowdbench.humans import HUMAN_MODELS, HumanModel, make, register


class Standstill(HumanModel):
    """A user model defined outside the package: nobody moves."""

    def step(self, state, rngs):
        return np.zeros_like(state.positions)


def test_user_model_by_name_through_public_api():
    register("standstill_test", Standstill, overwrite=True)
    env = crowdbench.parallel_env(num_humans=5, human_model="standstill_test")
    env.reset(seed=0)
    before = env.world.pos[0, 1:].copy()
    env.step({"robot": np.zeros(2)})
    np.testing.assert_array_equal(env.world.pos[0, 1:], before)


def test_unknown_model_lists_valid_names():
    with pytest.raises(ValueError, match="unknown pedestrian model 'nope'; valid choices: .*orca.*social_force"):
        make("nope")


def test_third_party_entry_point(tmp_path, monkeypatch):
    pkg = tmp_path / "theirpkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(textwrap.dedent("""
        import numpy as np
        from crowdbench.humans import HumanModel

        class Drift(HumanModel):
            def __init__(self, speed=0.5):
                self.speed = speed
            def step(self, state, rngs):
                v = np.zeros_like(state.positions)
                v[..., 0] = self.speed
                return v
    """))
    dist = tmp_path / "theirpkg-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: theirpkg\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[crowdbench.humans]\ndrift = theirpkg:Drift\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert "drift" in HUMAN_MODELS.names()
    env = crowdbench.parallel_env(num_humans=3, human_model="drift", human_model_kwargs={"speed": 0.4})
    env.reset(seed=1)
    before = env.world.pos[0, 1:].copy()
    env.step({"robot": np.zeros(2)})
    np.testing.assert_allclose(env.world.pos[0, 1:, 0] - before[:, 0], 0.1)
    sys.modules.pop("theirpkg", None)
