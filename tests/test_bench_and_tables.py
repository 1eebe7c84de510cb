"""Smoke tests of the bench and tables commands' building blocks (figures are measured by `crowdbench bench`)."""

from __future__ import annotations

import json

import pytest

from crowdbench import bench, leaderboard


def test_bench_figures_are_positive_and_formatted():
    env = bench.env_steps_per_s(10, 4, steps=3, repeats=2)
    orca = bench.orca_agent_steps_per_s(20, 4, steps=2, repeats=2)
    inf = bench.h2int_inference_ms(repeats=2)
    assert env["median"] > 0 and orca["median"] > 0 and inf["median"] > 0 and env["runs"] == 2
    res = {"machine": bench.machine(), "quick": True, "env_steps_per_s": {"10": {"1": env, "64": env}},
           "orca_agent_steps_per_s": {"20": orca}, "train_steps_per_s": env, "h2int_inference_ms": inf}
    res["decision_ms"] = {"orca": bench.decision_ms("orca", 2), "broken": {"skipped": "ValueError: x"}}
    assert res["decision_ms"]["orca"]["median"] > 0
    md = bench.results_markdown(res)
    assert "decision_ms (orca)" in md and "skipped: ValueError" in md
    assert "env_steps_per_s" in md and "h2int_inference_ms" in md and res["machine"]["logical_cores"] >= 1


def test_paper_grid():
    grid = leaderboard.cells()
    assert len(grid) == 3 + 3 + 9
    assert {c.rho for c in grid if c.table == "I"} == {0.7, 0.5, 0.3}
    assert {(c.humans, c.rho) for c in grid if c.table == "II"} == {(10, 0.0), (20, 0.0), (30, 0.0)}
    assert all(c.humans == 30 for c in grid if c.table == "III")


def test_tables_for_a_baseline(tmp_path):
    res = leaderboard.evaluate_cells("orca", leaderboard.cells(("II",))[:1], episodes=4, progress=False)
    assert res[0]["episodes"] == 4 and res[0]["humans"] == 10
    leaderboard.save(res, str(tmp_path / "r.json"), str(tmp_path / "r.md"), {"episodes": 4})
    assert "| II | N=10 | orca |" in (tmp_path / "r.md").read_text()


def test_leaderboard_runs_caches_and_ranks(tmp_path, monkeypatch):
    import numpy as np

    from crowdbench.policies import POLICIES, RobotPolicy

    class Still(RobotPolicy):  # a user's policy, registered for a leaderboard run
        def act(self, obs):
            return np.zeros((len(obs["robot"]), 2))

    POLICIES.register("still_for_test", Still)
    try:
        entries = [leaderboard.ENTRIES["orca"], leaderboard.parse_entry("Standing still=still_for_test")]
        board = leaderboard.run_leaderboard(entries, str(tmp_path), episodes=4, tables=("II",), progress=False)
        assert set(board) == {"orca", "Standing still"} and all(len(v) == 3 for v in board.values())
        assert all(r["success_rate"] == 0.0 for r in board["Standing still"])  # never reaches the goal
        md = (tmp_path / "LEADERBOARD.md").read_text()
        assert "| Standing still |" in md and "Table II" in md and "Table I —" not in md
        assert (tmp_path / "standing-still.json").exists()

        def boom(*a, **k):
            raise AssertionError("cached results should have been reused")

        monkeypatch.setattr(leaderboard, "evaluate_cells", boom)
        again = leaderboard.run_leaderboard(entries, str(tmp_path), episodes=4, tables=("II",), progress=False)
        assert json.dumps(again) == json.dumps(board)  # (NaN times of never-successful cells: compare as text)
        with pytest.raises(AssertionError, match="reused"):  # another budget is a new evaluation
            leaderboard.run_leaderboard(entries, str(tmp_path), episodes=5, tables=("II",), progress=False)
    finally:
        POLICIES._factories.pop("still_for_test", None)


def test_leaderboard_entry_errors():
    with pytest.raises(ValueError, match="valid choices"):
        leaderboard.parse_entry("x=no_such_policy")
    with pytest.raises(ValueError, match="LABEL=POLICY"):
        leaderboard.parse_entry("orca")
