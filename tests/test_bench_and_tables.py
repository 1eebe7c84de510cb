"""Smoke tests of the bench and tables commands' building blocks (figures are measured by `crowdbench bench`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from crowdbench import bench, leaderboard
from crowdbench.leaderboard import entries as _entries  # noqa: F401 - leaderboard.entries, patched below
from crowdbench.worlds.digest import crowd_digest


def test_bench_figures_are_positive_and_formatted():
    env = bench.env_steps_per_s(10, 4, steps=3, repeats=2)
    orca = bench.orca_agent_steps_per_s(20, 4, steps=2, repeats=2)
    inf = bench.h2int_inference_ms(repeats=2)
    assert env["median"] > 0 and orca["median"] > 0 and inf["median"] > 0 and env["runs"] == 2
    res = {"machine": bench.machine(), "quick": True, "env_steps_per_s": {"10": {"1": env, "64": env}},
           "orca_agent_steps_per_s": {"20": orca}, "train_steps_per_s": env, "h2int_inference_ms": inf}
    res["decision_ms"] = {"orca": bench.decision_ms("orca", 2), "broken": {"skipped": "ValueError: x"}}
    assert res["decision_ms"]["orca"]["median"] > 0
    res["decision_ms_all_cores"] = {"threads": 2, "orca": bench.decision_ms("orca", 2, threads=2)}
    md = bench.results_markdown(res)
    assert "decision_ms (orca)" in md and "skipped: ValueError" in md and "decision_ms (orca, 2 threads)" in md
    assert "env_steps_per_s" in md and "h2int_inference_ms" in md and res["machine"]["logical_cores"] >= 1


def test_paper_grid():
    grid = leaderboard.grid()
    assert len(grid) == 3 + 3 + 9
    assert {c.rho for c in grid if c.table == "I"} == {0.7, 0.5, 0.3}
    assert {(c.humans, c.rho) for c in grid if c.table == "II"} == {(10, 0.0), (20, 0.0), (30, 0.0)}
    assert all(c.humans == 30 for c in grid if c.table == "III")


def test_tables_for_a_baseline(tmp_path):
    res = leaderboard.evaluate_cells("orca", leaderboard.grid(("II",))[:1], episodes=4, progress=False)
    assert res[0]["episodes"] == 4 and res[0]["humans"] == 10
    leaderboard.save(res, str(tmp_path / "r.json"), str(tmp_path / "r.md"), {"episodes": 4})
    assert "| II | N=10 | orca |" in (tmp_path / "r.md").read_text()


def test_leaderboard_entry_errors():
    with pytest.raises(ValueError, match="valid choices"):
        leaderboard.parse_entry("x=no_such_policy")
    with pytest.raises(ValueError, match="LABEL=POLICY"):
        leaderboard.parse_entry("orca")


def test_table_iii_pooled_rows_by_hand():
    def cell(layout, regime, succ, time):
        return {"policy": "p", "table": "III", "row": f"{layout} {regime}", "layout": layout, "humans": 30,
                "responsiveness": 0.5, "seed": 0, "episodes": 100, "success_rate": succ, "collision_rate": 1 - succ,
                "timeout_rate": 0.0, "nav_time": time, "path_length": time, "delta_v": 1.0}

    rows = [cell("intersection", "Medium", 0.9, 10.0), cell("split_flow", "Medium", 0.6, 20.0),
            cell("random_wander", "Medium", 0.3, 40.0)]
    pooled = [r for r in leaderboard.with_pooled(rows) if r["row"].startswith("pooled")]
    assert len(pooled) == 1 and pooled[0]["row"] == "pooled Medium" and pooled[0]["episodes"] == 300
    assert pooled[0]["success_rate"] == pytest.approx(0.6)
    assert pooled[0]["nav_time"] == pytest.approx((90 * 10 + 60 * 20 + 30 * 40) / 180)  # over successful episodes
    from crowdbench.metrics import wilson

    assert pooled[0]["ci"]["success_rate"] == list(wilson(180, 300))  # pooled counts: 90 + 60 + 30 of 300
    md = leaderboard.leaderboard_markdown({"p": rows})
    assert "pooled Medium" in md and "**60.0** (54–65) / 40.0 / 0.0 · 18.3 s |" in md


def test_best_is_bold_only_where_intervals_do_not_overlap():
    from crowdbench.metrics import wilson

    def row(k, n=500):
        return [{"policy": "x", "table": "I", "row": "High", "success_rate": k / n, "collision_rate": 1 - k / n,
                 "timeout_rate": 0.0, "nav_time": 10.0, "ci": {"success_rate": list(wilson(k, n))}}]

    clear = leaderboard.leaderboard_markdown({"a": row(490), "b": row(440)})
    assert "**98.0**" in clear
    close = leaderboard.leaderboard_markdown({"a": row(490), "b": row(485)})
    assert "**" not in close.split("### ")[1]  # 98.0 vs 97.0: the intervals overlap, no winner


def test_seed_rows_report_mean_and_spread():
    def rows(p):
        return [{"policy": "x", "table": "I", "row": "High", "success_rate": p, "collision_rate": 1 - p,
                 "timeout_rate": 0.0, "nav_time": 10.0}]

    md = leaderboard.leaderboard_markdown({"h2int": rows(0.9), "h2int-seed1": rows(0.8), "h2int-seed2": rows(0.95)},
                                          {"h2int": "main", "h2int-seed1": "seeds", "h2int-seed2": "seeds"})
    assert "## h2int across training seeds" in md and "| mean [spread], 3 seeds | 88.3 [15.0] |" in md
    assert "### Every method over its training seeds" not in leaderboard.leaderboard_markdown({"h2int": rows(0.9)})


def test_the_main_section_gives_every_method_over_its_seeds():
    def rows(table_i, pooled):
        return [{"policy": "x", "table": "I", "row": "High", "success_rate": table_i, "collision_rate": 0.0,
                 "timeout_rate": 1 - table_i, "nav_time": 10.0},
                {"policy": "x", "table": "III", "row": "pooled High", "success_rate": pooled, "collision_rate": 0.0,
                 "timeout_rate": 1 - pooled, "nav_time": 10.0},
                {"policy": "x", "table": "III", "row": "split_flow High", "success_rate": 0.0, "collision_rate": 0.0,
                 "timeout_rate": 1.0, "nav_time": 10.0}]

    board = {"orca": rows(0.9, 0.7), "cadrl": rows(0.7, 0.3), "cadrl-seed1": rows(0.9, 0.4),
             "cadrl-seed2": rows(0.8, 0.5), "h2int": rows(0.95, 0.9), "h2int-seed1": rows(0.85, 0.8),
             "dsrnn": rows(0.5, 0.2)}
    groups = {"orca": "main", "cadrl": "main", "h2int": "main", "cadrl-seed1": "seeds:cadrl",
              "cadrl-seed2": "seeds:cadrl", "h2int-seed1": "seeds", "dsrnn": "main"}
    md = leaderboard.leaderboard_markdown(board, groups, planners=frozenset({"orca"}))
    section = md.split("### Every method over its training seeds")[1].split("##")[0]
    assert "| method | seeds | Table I High | Table III pooled High |" in section  # per-layout cells left out
    assert "| orca | — | 90.0 | 70.0 |" in section  # one row: its own value; a planner has no seeds
    assert "| dsrnn | 1 | 50.0 | 20.0 |" in section  # one training seed, said as such
    assert "| cadrl | 3 | 80.0 [20.0] | 40.0 [20.0] |" in section
    assert "| h2int | 2 | 90.0 [10.0] | 85.0 [10.0] |" in section  # plain "seeds" group = the reference's


def test_the_over_seeds_table_gives_each_methods_training_budget():
    """With budgets, every method's training per seed stands beside its success: env steps (a range when its seeds
    differ), RL episodes for value methods, "—" for a planner or when a seed's budget is unknown."""
    def rows(p):
        return [{"policy": "x", "table": "I", "row": "High", "success_rate": p, "collision_rate": 1 - p,
                 "timeout_rate": 0.0, "nav_time": 10.0}]

    board = {"orca": rows(0.9), "dsrnn": rows(0.7), "dsrnn-seed1": rows(0.9), "aig_gst": rows(0.8),
             "aig_gst-seed1": rows(0.7), "sarl": rows(0.95), "cadrl": rows(0.6)}
    groups = {"orca": "main", "dsrnn": "main", "aig_gst": "main", "sarl": "main", "cadrl": "main",
              "dsrnn-seed1": "seeds:dsrnn", "aig_gst-seed1": "seeds:aig_gst"}
    budgets = {"dsrnn": {"env_steps": 28_339_200}, "dsrnn-seed1": {"env_steps": 5_852_160},
               "aig_gst": {"env_steps": 5_852_160}, "aig_gst-seed1": {"env_steps": 5_852_160},
               "sarl": {"episodes": 10_000}}
    md = leaderboard.leaderboard_markdown(board, groups, planners=frozenset({"orca"}), budgets=budgets)
    section = md.split("### Every method over its training seeds")[1].split("##")[0]
    assert "| method | seeds | training per seed | Table I High |" in section
    assert "| orca | — | — | 90.0 |" in section
    assert "| dsrnn | 2 | 5.9–28.3 M steps | 80.0 [20.0] |" in section
    assert "| aig_gst | 2 | 5.9 M steps | 75.0 [10.0] |" in section
    assert "| sarl | 1 | 10,000 episodes | 95.0 |" in section and "| cadrl | 1 | — | 60.0 |" in section


def test_ablations_get_their_training_seeds_and_a_figure_with_seed_spread(tmp_path, monkeypatch):
    from crowdbench import checkpoints

    shipped = ["h2int", "h2int-seed2", "flat", "flat-seed1", "flat-seed2", "meanpool", "standard"]
    monkeypatch.setattr(checkpoints, "shipped_names", lambda method: shipped if method == "h2int" else [])
    monkeypatch.setattr(leaderboard.entries, "trained_crowd", lambda path: crowd_digest())  # as if retrained
    entries = leaderboard.shipped_entries()
    assert entries["h2int-flat-seed1"].group == "seeds:h2int-flat"
    assert entries["h2int-flat-seed2"].policy_kwargs() == {"checkpoint": "flat-seed2"}
    assert "h2int-meanpool-seed1" not in entries and entries["h2int-seed2"].group == "seeds:h2int"

    def rows(p):
        return [{"policy": "x", "table": "I", "row": "High", "responsiveness": 0.7, "humans": 20,
                 "success_rate": p, "collision_rate": 1 - p, "timeout_rate": 0.0, "nav_time": 10.0,
                 "ci": {"success_rate": [p - 0.02, p + 0.02]}}]

    board = {"h2int": rows(0.9), "h2int-flat": rows(0.7), "h2int-flat-seed1": rows(0.6), "h2int-flat-seed2": rows(0.8)}
    groups = {"h2int": "main", "h2int-flat": "ablation", "h2int-flat-seed1": "seeds:h2int-flat",
              "h2int-flat-seed2": "seeds:h2int-flat"}
    md = leaderboard.leaderboard_markdown(board, groups)
    assert "## h2int-flat across training seeds" in md and "| mean [spread], 3 seeds | 70.0 [20.0] |" in md
    section = md.split("### Ablations over their training seeds")[1].split("##")[0]  # the ablation question
    assert "| h2int | 1 | 90.0 |" in section and "| h2int-flat | 3 | 70.0 [20.0] |" in section
    leaderboard.plot_board(board, str(tmp_path / "ablation.png"), groups, rows="ablation")
    assert (tmp_path / "ablation.png").stat().st_size > 10_000


def test_trajectory_panels_are_drawn(tmp_path):
    from crowdbench.cli.panels import episode, plot
    from crowdbench.policies import make_policy

    ep = episode(make_policy("orca"), "intersection", 6, seed=1, responsiveness=0.5)
    assert ep["pos"].shape[1] == 7 and ep["outcome"] in ("success", "collision", "timeout")
    assert abs(np.linalg.norm(ep["goal"] - ep["pos"][0, 0])) >= 8.0  # a random crossing, ≥ 8 m long
    out = plot("orca", str(tmp_path / "p.png"), humans=6, layouts=("circle_crossing", "split_flow"))
    assert Path(out).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("name", ["cadrl", "sarl"])
def test_value_policies_decide_bitwise_alike_on_one_and_two_threads(name):
    """``decision_ms_all_cores`` times the same policy: the look-ahead's products split over threads give the same
    actions, bit for bit, over a seeded episode (`benchmarks/bench_decision.py`: 2.0 → 1.7 ms per SARL decision on
    a 2-core machine)."""
    import torch

    from crowdbench.config import WorldConfig
    from crowdbench.policies import make_policy
    from crowdbench.robots import make_observation
    from crowdbench.worlds import CrowdWorld

    cfg = WorldConfig(num_humans=20)
    policy = make_policy(name, cfg)
    world = CrowdWorld(cfg, 1, "circle_crossing", "responsive_orca", {"responsiveness": 0.5})
    world.reset(seeds=[3])
    build = make_observation(policy.observation, cfg, **policy.observation_kwargs).build
    before = torch.get_num_threads()
    try:
        for _ in range(30):
            obs = build(world)
            torch.set_num_threads(1)
            one = policy.act(obs)
            torch.set_num_threads(2)
            np.testing.assert_array_equal(policy.act(obs), one)
            world.step(one)
    finally:
        torch.set_num_threads(before)


def test_a_methods_checkpoints_at_another_sensing_tier_become_rows_of_that_tier(monkeypatch):
    """``sarl-velocities`` (and its seeds) shipped beside ``sarl`` are the rows ``sarl-velocities``,
    ``sarl-velocities-seed<k>``; a tier checkpoint trained on another crowd stays off the board."""
    from crowdbench import checkpoints

    shipped = {"sarl": ["sarl", "sarl-seed1", "sarl-velocities", "sarl-velocities-seed1", "sarl-velocities-seed2"],
               "cadrl": ["cadrl", "cadrl-full"]}
    monkeypatch.setattr(checkpoints, "shipped_names", lambda method: shipped.get(method, []))
    monkeypatch.setattr(leaderboard.entries, "trained_crowd",
                        lambda path: "old" if path.endswith("cadrl-full.pt") else crowd_digest())
    monkeypatch.setattr(leaderboard.entries, "STALE", {})
    entries = leaderboard.shipped_entries()
    assert entries["sarl-velocities"].policy_kwargs() == {"checkpoint": "sarl-velocities"}
    assert entries["sarl-velocities"].group == "main"
    assert entries["sarl-velocities-seed2"].group == "seeds:sarl-velocities"
    assert entries["sarl-seed1"].group == "seeds:sarl" and "sarl-velocities-seed1" not in [
        e.label for e in entries.values() if e.group == "seeds:sarl"]
    assert "cadrl-full" not in entries and "cadrl-full" in leaderboard.entries.STALE
    assert "cadrl-velocities" not in entries and "cadrl-velocities" not in leaderboard.entries.STALE  # not shipped


def test_the_velocities_section_says_what_true_velocities_are_worth(tmp_path):
    """Each method with rows at both tiers gets its seed means side by side and their difference; the figure draws
    the other tier dashed."""
    def rows(p):
        return [{"policy": "x", "table": "I", "row": "High", "responsiveness": 0.7, "humans": 20,
                 "success_rate": p, "collision_rate": 1 - p, "timeout_rate": 0.0, "nav_time": 10.0,
                 "ci": {"success_rate": [p - 0.02, p + 0.02]}}]

    board = {"orca": rows(0.9), "orca-velocities": rows(0.95), "sarl": rows(0.8), "sarl-seed1": rows(0.9),
             "sarl-velocities": rows(0.96), "sarl-velocities-seed1": rows(0.94), "cadrl": rows(0.5)}
    groups = {"orca": "main", "orca-velocities": "main", "sarl": "main", "sarl-seed1": "seeds:sarl",
              "sarl-velocities": "main", "sarl-velocities-seed1": "seeds:sarl-velocities", "cadrl": "main"}
    sensing = {lb: "velocities" if "velocities" in lb else "positions" for lb in board}
    md = leaderboard.leaderboard_markdown(board, groups, planners=frozenset({"orca", "orca-velocities"}),
                                          sensing=sensing)
    main = md.split("## Rows at `sensing=velocities`")[0]
    assert "| sarl-velocities |" not in main and "| sarl |" in main  # not ranked with the positions rows
    section = md.split("### What `sensing=velocities` is worth")[1]
    assert "| setting | orca (—) | sarl (2 / 2) |" in section and "cadrl" not in section
    assert "| Table I High | 90.0 → 95.0 (+5.0) | 85.0 → 95.0 (+10.0) |" in section
    assert "is worth" not in leaderboard.leaderboard_markdown({"sarl": rows(0.8)}, {"sarl": "main"})
    leaderboard.plot_board(board, str(tmp_path / "success.png"), groups, sensing=sensing)
    assert (tmp_path / "success.png").stat().st_size > 10_000
