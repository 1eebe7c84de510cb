"""`crowdbench leaderboard compare`: two methods over their training seeds from stored cells."""

from __future__ import annotations

import json

import pytest

from crowdbench.cli import main
from crowdbench.leaderboard import compare


def _store(root, entry, key, k, n=500, scenario="crowd", seed=0):
    folder = root / "cells" / entry
    folder.mkdir(parents=True, exist_ok=True)
    fp = {"scenario": scenario, "seed": seed, "episodes": n, "suite": "s"}
    (folder / f"{key}.json").write_text(json.dumps({"fingerprint": fp, "result": {"success_rate": k / n,
                                                                                  "episodes": n}}))


def _board(tmp_path):
    for entry, ks in {"m": (490, 450), "m-seed1": (480, 440), "m-seed3": (460, 430),
                      "other": (400, 460), "other-seed1": (485, 455)}.items():
        _store(tmp_path, entry, "I-high", ks[0])
        for layout in ("intersection", "split-flow", "random-wander"):
            _store(tmp_path, entry, f"III-{layout}-low", ks[1])
    _store(tmp_path, "m", "II-n-10", 500)  # one seed only: the setting is left out
    return tmp_path


def test_families_means_pooled_counts_and_intervals_apart(tmp_path):
    res = compare.compare(_board(tmp_path), "m", "other", scenario="crowd")
    assert res["a"] == ["m", "m-seed1", "m-seed3"] and res["b"] == ["other", "other-seed1"]
    rows = {r["key"]: r for r in res["rows"]}
    assert set(rows) == {"I-high", "III-intersection-low", "III-split-flow-low", "III-random-wander-low",
                         "III-pooled-low"}
    high = rows["I-high"]
    assert high["mean_a"] == pytest.approx(2.86 / 3) and high["mean_b"] == pytest.approx(0.885)
    # 98 / 96 / 92 % against 80 / 97 %: every m seed clear of 80 % (400 of 500); of 97 % only 92 %, below it
    # (Wilson intervals [89.3, 94.1] and [95.1, 98.2])
    assert high["pairs"] == [1, 0, 1, 0, 1, -1]
    pooled = rows["III-pooled-low"]
    assert pooled["a"][0] == compare.Rate(3 * 450, 1500)  # successes and episodes summed over the layouts
    s = compare.summary(res)
    assert (s["settings"], s["above"], s["below"], s["pairs"]) == (4, 1, 3, 24)
    assert (s["a_apart"], s["b_apart"], s["a_apart_settings"], s["b_apart_settings"]) == (3, 4, 1, 4)
    text = compare.markdown(res)
    assert "| I-high | 95.3 (98.0 · 96.0 · 92.0) | 88.5 (80.0 · 97.0) | +6.8 | 3 / 1 |" in text
    assert "Over the 4 settings of Tables I–III: m's mean above other's in 1" in text


def test_explicit_lists_and_refusals(tmp_path):
    _board(tmp_path)
    res = compare.compare(tmp_path, "m-seed1,m-seed3", "other", scenario="crowd")
    assert res["a"] == ["m-seed1", "m-seed3"] and res["b"] == ["other", "other-seed1"]
    assert compare.compare(tmp_path, "m,", "other", scenario="crowd")["a"] == ["m"]  # the entry alone
    with pytest.raises(ValueError, match="method 'nope': no stored cells for nope .*valid choices: m, m-seed1"):
        compare.compare(tmp_path, "nope", "m", scenario="crowd")
    with pytest.raises(ValueError, match="made on crowd 'crowd', not the current 'new'"):
        compare.compare(tmp_path, "m", "other", scenario="new")
    _store(tmp_path, "other-seed1", "I-high", 485, seed=7)
    with pytest.raises(ValueError, match="I-high: fingerprint field 'seed' differs between m/I-high"):
        compare.compare(tmp_path, "m", "other", scenario="crowd")


def test_the_command_prints_the_shipped_boards_comparison(capsys):
    """On the shipped board (made on the current crowd): H²INT's three seeds against SARL's."""
    assert main(["leaderboard", "compare", "h2int", "sarl"]) == 0
    out = capsys.readouterr().out
    assert "**h2int** (3 seeds: h2int, h2int-seed1, h2int-seed2) against **sarl** (3 seeds" in out
    keys = [line.split(" | ")[0][2:] for line in out.splitlines() if line.startswith("| I")]
    assert keys[:18] == [*compare.MAIN_KEYS, *compare.POOLED]  # Tables I–III and the 3 pooled, then Table IV's
    assert keys[18:] == sorted(keys[18:]) and "IV-univ-replay" in keys[18:]
    assert "Over the 15 settings of Tables I–III" in out


def test_another_suites_cells_are_compared_and_counted(tmp_path):
    """A board of another suite (Table V's settings only): every stored setting both methods have at every seed,
    sorted, counted over them all."""
    for entry, ks in {"m": (490, 300), "m-seed1": (495, 310), "other": (400, 305)}.items():
        _store(tmp_path, entry, "V-orca", ks[0])
        _store(tmp_path, entry, "V-social-force", ks[1])
    _store(tmp_path, "m", "V-learned-crowd", 450)  # one seed of one method: left out
    res = compare.compare(tmp_path, "m", "other", scenario="crowd")
    assert [r["key"] for r in res["rows"]] == ["V-orca", "V-social-force"]
    assert compare.summary(res)["settings"] == 0  # none of Tables I–III
    assert compare.summary(res, keys=None)["settings"] == 2
    text = compare.markdown(res)
    assert "Over the 2 settings compared: m's mean above other's in 1, equal in 1, below in 0" in text
