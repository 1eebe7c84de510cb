"""``crowdbench leaderboard verify``: stored cells re-evaluated and compared bit for bit — identical when nothing
changed, every changed field named when something did; and the shipped board's cheap cells reproduce exactly."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from crowdbench import leaderboard
from crowdbench.cli import main
from crowdbench.leaderboard.cells import cell_key
from crowdbench.leaderboard.run import cpu_model
from crowdbench.leaderboard.verify import compare, same

BOARD = Path(__file__).resolve().parents[1] / "leaderboards"
"""The shipped board (the repository's)."""


def _suite() -> leaderboard.Suite:
    return leaderboard.Suite(name="t", episodes=4, tables=("II",), worlds=4, counterfactual=False)


def test_values_compare_exactly_with_nan_equal_to_nan_and_timing_left_out():
    assert same(math.nan, math.nan) and same({"a": [1.0, math.nan]}, {"a": [1.0, math.nan]})
    assert not same(0.97, 0.9700000000000001) and not same(1, 1.0) and not same({"a": 1}, {"b": 1})
    stored = {"result": {"success_rate": 0.97, "ped_delay": math.nan, "wall_s": 8.9, "ci": {"s": [0.9, 1.0]}}}
    now = {"result": {"success_rate": 0.97, "ped_delay": math.nan, "wall_s": 9.4, "ci": {"s": (0.9, 1.0)}}}
    assert compare(stored, now) == {}  # tuples are lists once stored; the wall-clock time may differ
    now["result"]["ci"] = {"s": (0.9, 0.99)}
    now["result"]["success_rate"] = 0.96
    assert compare(stored, now) == {"result.ci": ({"s": [0.9, 1.0]}, {"s": [0.9, 0.99]}),
                                    "result.success_rate": (0.97, 0.96)}
    assert set(compare(stored, {"error": "RuntimeError: x"})) == {"result", "error"}


def test_identical_then_each_kind_of_change_is_reported(tmp_path):
    out, s = str(tmp_path), _suite()
    entries = [leaderboard.ENTRIES["orca"]]
    leaderboard.run_suite(s, entries, out)
    cells = [cell_key(c) for c in s.grid()]
    verdicts = leaderboard.verify_cells(s, entries, out, workers=2)
    assert [(v.cell, v.status) for v in verdicts] == [(k, "identical") for k in cells]
    assert [v.cpu for v in verdicts] == [(cpu_model(), cpu_model())] * len(cells)
    assert all(v.seconds >= 0 for v in verdicts)  # stored to 0.1 s: a 4-episode ORCA cell can round to 0.0

    store = tmp_path / "cells" / "orca"
    cell = json.loads((store / f"{cells[0]}.json").read_text())
    cell["result"]["success_rate"] += 0.002  # a number this checkout does not compute
    (store / f"{cells[0]}.json").write_text(json.dumps(cell))
    cell = json.loads((store / f"{cells[1]}.json").read_text())
    cell["fingerprint"]["code"] = "0" * 16  # made by other code of the policy: run would remake it
    (store / f"{cells[1]}.json").write_text(json.dumps(cell))
    (store / f"{cells[2]}.json").unlink()
    v = {v.cell: v for v in leaderboard.verify_cells(s, entries, out)}
    assert v[cells[0]].status == "differs" and list(v[cells[0]].differences) == ["result.success_rate"]
    assert v[cells[1]].status == "stale" and v[cells[1]].differences["code"][0] == "0" * 16
    assert v[cells[2]].status == "missing"

    with pytest.raises(ValueError, match="--cells II-n-40: not cells of suite 't'; valid choices: II-n-10"):
        leaderboard.verify_cells(s, entries, out, cells=["II-n-40"])
    with pytest.raises(ValueError, match="--backend 'dask'; valid choices: local, ray"):
        leaderboard.verify_cells(s, entries, out, backend="dask")


def test_cli_exit_status_says_whether_every_cell_is_identical(tmp_path, capsys):
    out = str(tmp_path)
    common = ["--suite", "quick", "--episodes", "3", "--methods", "orca", "--out", out]
    assert main(["leaderboard", "run", *common]) == 0
    first = cell_key(leaderboard.load_suite("quick").grid()[0])
    capsys.readouterr()
    args = ["leaderboard", "verify", *common, "--cells", first]
    assert main(args) == 0
    assert "1 of 1 stored cells identical" in capsys.readouterr().out
    path = tmp_path / "cells" / "orca" / f"{first}.json"
    cell = json.loads(path.read_text())
    cell["result"]["collision_rate"] = 0.5
    path.write_text(json.dumps(cell))
    assert main(args) == 1
    text = capsys.readouterr().out
    assert f"| orca | {first} | differs | result.collision_rate: 0.5 → " in text
    assert f"not identical: orca {first} (differs)" in text


@pytest.mark.parametrize("method", ["orca", "h2int"])
def test_the_shipped_boards_cells_reproduce_bit_for_bit(method):
    """The board's stored numbers are what this checkout computes: a change to shared code the fingerprint does not
    name (kernels, observation builders, network blocks) that alters a result fails here. Continuous metrics may
    differ in the last bits between CPUs (vectorised transcendental functions, a learned policy's products):
    skipped where the cell was made on another."""
    paper = leaderboard.load_suite("paper")
    stored = json.loads((BOARD / "cells" / method / "I-medium.json").read_text())
    if stored.get("cpu") != cpu_model():
        pytest.skip(f"the cell was made on {stored.get('cpu')}, this is {cpu_model()}")
    [v] = leaderboard.verify_cells(paper, [leaderboard.ENTRIES[method]], str(BOARD), cells=["I-medium"])
    assert v.status == "identical", v.differences
