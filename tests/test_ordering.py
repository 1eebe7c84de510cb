"""The paper's orderings against the board's (`crowdbench leaderboard paper`'s first section)."""

from __future__ import annotations

import json

from crowdbench.leaderboard import ordering, paper
from crowdbench.leaderboard.compare import MAIN_KEYS as SETTINGS


def _store(root, entry, successes, scenario="crowd", n=500):
    folder = root / "cells" / entry
    folder.mkdir(parents=True, exist_ok=True)
    for key, k in zip(SETTINGS, successes, strict=True):
        fp = {"scenario": scenario, "seed": 0, "episodes": n, "suite": "s"}
        (folder / f"{key}.json").write_text(json.dumps({"fingerprint": fp, "result": {"success_rate": k / n,
                                                                                      "episodes": n}}))


PAPER = {"fast": {"I": (90, 90, 90), "II": (90, 90, 90), "III": (90, 90, 90)},
         "slow": {"I": (80, 80, 80), "II": (80, 80, 80), "III": (95, 95, 95)},
         "plan": {"I": (50, 50, 50), "II": (50, 50, 50), "III": (50, 50, 50)},
         "gone": {"I": (1, 1, 1), "II": (1, 1, 1), "III": (1, 1, 1)}}


def test_counts_seed_means_paper_order_and_differences(tmp_path):
    # fast: two seeds, 400 and 460 of 500 everywhere (mean 86 %); slow: one seed, 450 (90 %) — above fast's mean in
    # every setting although fast's seed 1 is above it; plan: 250 everywhere but Table II N = 30 (470)
    _store(tmp_path, "fast", [400] * 15)
    _store(tmp_path, "fast-seed1", [460] * 15)
    _store(tmp_path, "slow", [450] * 15)
    _store(tmp_path, "plan", [250] * 5 + [470] + [250] * 9)
    res = ordering.orderings(tmp_path, PAPER, scenario="crowd")
    assert [(m, s) for m, s, _ in res["methods"]] == [("slow", ["slow"]), ("fast", ["fast", "fast-seed1"]),
                                                      ("plan", ["plan"])]
    assert res["skipped"] == [("gone", "no stored cells")]
    p = res["pairs"]["slow", "fast"]
    assert p.keys == ordering.PAPER_KEYS and p.ours == (9, 0) and p.paper == (3, 6) and p.differs
    # seed pairs apart: 90 % against 80 % (slow ahead, in all 9), against 92 % (overlapping)
    assert (p.apart, p.pairs) == ((9, 0), 18)
    assert res["pairs"]["fast", "slow"].ours == (0, 9) and res["pairs"]["fast", "slow"].apart == (0, 9)
    q = res["pairs"]["fast", "plan"]
    assert q.ours == (8, 1) and q.paper == (9, 0) and not q.differs
    assert [m for m, _ in res["paper_order"]] == ["fast", "slow", "plan"]
    text = ordering.markdown(res, planners=frozenset({"plan"}))
    assert "| **slow** (1 seed, mean 90.0) | — | 9 / 3 | 8 / 9 |" in text
    assert "| **fast** (2 seeds, mean 86.0) | 0 / 6 | — | 8 / 9 |" in text
    assert "| **plan** (planner, mean 54.9) |" in text
    assert "- **slow** against **fast**: board above in 9, below in 0 of 9 (apart 9 / 0 of 18" in text
    assert "against **plan**" not in text  # same majority order as the paper's
    assert "board slow 90.0 > fast 86.0 > plan 54.9; paper fast 90.0 > slow 85.0 > plan 50.0" in text


def test_cells_of_another_crowd_are_left_out_with_the_reason(tmp_path):
    _store(tmp_path, "fast", [400] * 15)
    _store(tmp_path, "slow", [450] * 15, scenario="old")
    res = ordering.orderings(tmp_path, PAPER, scenario="crowd")
    assert [m for m, _, _ in res["methods"]] == ["fast"] and res["pairs"] == {}
    assert any(name == "slow" and "made on crowd 'old'" in why for name, why in res["skipped"])
    assert "- Not compared: slow (" in ordering.markdown(res)


def test_the_paper_report_opens_with_the_orderings_of_the_shipped_board(tmp_path):
    text = paper.report("leaderboards", str(tmp_path / "PAPER.md"))
    head = text.split("## aig_gst")[0]
    assert "## The paper's orderings, over training seeds" in head
    res = ordering.orderings("leaderboards", paper.paper_rates())
    assert res["pairs"]["h2int", "orca"].ours == (9, 0)  # H²INT above the ORCA robot in every paper setting
    assert res["pairs"]["h2int", "orca"].paper == (9, 0)
