"""The leaderboard (:mod:`crowdbench.leaderboard`): suites, stored cells reused, faults isolated per cell,
kill-and-resume, workers and backends give identical results."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from crowdbench import leaderboard
from crowdbench.humans import HUMAN_MODELS
from crowdbench.leaderboard import run as runner
from crowdbench.policies import POLICIES, RobotPolicy


def suite(**kw) -> leaderboard.Suite:
    base = dict(name="t", episodes=4, tables=("II",), worlds=4, counterfactual=False)
    base.update(kw)
    return leaderboard.Suite(**base)


def stable(path) -> dict:
    """A method file without its timing and provenance fields."""
    d = json.loads(path.read_text())
    d["meta"].pop("provenance"), d["meta"].pop("wall_s")
    for r in d["results"]:
        r.pop("wall_s", None)
    return d


class Still(RobotPolicy):
    def act(self, obs):
        return np.zeros((len(obs["robot"]), 2))


class Flaky(RobotPolicy):
    """Fails only in the 30-pedestrian cell; NaN in the 20-pedestrian one."""

    observation = "full_state"  # every pedestrian, so the mask counts the crowd

    def act(self, obs):
        n = int(obs["mask"].sum(axis=1).max())
        if n > 20:
            raise RuntimeError("no room for thirty")
        return np.full((len(obs["robot"]), 2), np.nan if n > 10 else 0.0)


@pytest.fixture
def users_policies():
    POLICIES.register("still_for_test", Still)
    POLICIES.register("flaky_for_test", Flaky)
    yield
    POLICIES._factories.pop("still_for_test", None)
    POLICIES._factories.pop("flaky_for_test", None)


def test_shipped_suites_load_and_bad_suites_are_one_clear_error(tmp_path):
    paper = leaderboard.load_suite("paper")
    assert paper.episodes == 500 and len(paper.grid()) == 25 and paper.counterfactual  # Tables I–III and IV
    assert paper.check_seed == 100000
    assert leaderboard.load_suite("quick", episodes=7).episodes == 7
    bad = tmp_path / "bad.toml"
    bad.write_text('episodes = 5\ntabels = ["I"]\n')
    with pytest.raises(ValueError, match=r"unknown keys \['tabels'\]; valid choices"):
        leaderboard.load_suite(str(bad))
    with pytest.raises(ValueError, match="valid choices: paper, quick, shift"):
        leaderboard.load_suite("nope")
    with pytest.raises(ValueError, match="tables"):
        suite(tables=("VI",))
    with pytest.raises(ValueError, match="rows"):
        suite(rows=("II/N=11",))
    assert [c.row for c in suite(rows=("II/N=20",)).grid()] == ["N=20"]


def test_cells_are_stored_reused_and_faults_stay_in_their_cell(tmp_path, users_policies, monkeypatch):
    entries = [leaderboard.ENTRIES["orca"], leaderboard.parse_entry("Standing still=still_for_test"),
               leaderboard.parse_entry("flaky=flaky_for_test")]
    board = leaderboard.run_suite(suite(), entries, str(tmp_path))
    assert [r["success_rate"] for r in board["Standing still"]] == [0.0] * 3  # never reaches the goal
    flaky = {r["row"]: r for r in board["flaky"]}
    assert flaky["N=10"]["success_rate"] == 0.0  # the healthy cell completed
    assert "NaN or inf" in flaky["N=20"]["error"] and "Flaky" in flaky["N=20"]["error"]
    assert flaky["N=30"]["error"] == "RuntimeError: no room for thirty"
    md = (tmp_path / "LEADERBOARD.md").read_text()
    assert "| flaky |" in md and "error" in md and "| Standing still |" in md
    assert len(list((tmp_path / "cells").rglob("*.json"))) == 9
    meta = json.loads((tmp_path / "orca.json").read_text())["meta"]
    assert meta["provenance"]["packages"]["numpy"] and meta["suite_digest"] == leaderboard.suite_digest(suite())
    from crowdbench.bench import cpu_model

    cpu = cpu_model()
    assert cpu and meta["provenance"]["cpu"] == cpu and meta["provenance"]["cell_cpus"] == [cpu]
    cell_file = tmp_path / "cells" / "orca" / "II-n-10.json"
    assert json.loads(cell_file.read_text())["cpu"] == cpu  # each cell names the CPU it ran on

    calls = []
    real = leaderboard.run_cell
    monkeypatch.setattr(runner, "run_cell", lambda *a: calls.append(a[1].row) or real(*a))
    again = leaderboard.run_suite(suite(), entries, str(tmp_path))
    assert sorted(calls) == ["N=20", "N=30"]  # only the failed cells are retried
    assert json.dumps(again["orca"]) == json.dumps(board["orca"])
    saved = json.loads(cell_file.read_text())
    saved.pop("cpu")  # a cell stored before CPUs were recorded is reused and marked as such
    cell_file.write_text(json.dumps(saved))
    leaderboard.run_suite(suite(), entries[:1], str(tmp_path))
    meta = json.loads((tmp_path / "orca.json").read_text())["meta"]
    assert meta["provenance"]["cell_cpus"] == sorted([cpu, "unrecorded"])
    calls.clear()
    leaderboard.run_suite(suite(episodes=5), entries[:1], str(tmp_path))
    assert len(calls) == 3  # another budget is another fingerprint


def test_figure_legends_give_seed_counts_to_learned_methods_only(tmp_path):
    entries = [leaderboard.ENTRIES["orca"], leaderboard.Entry("h2int", "h2int", (("checkpoint", "h2int"),))]
    leaderboard.run_suite(suite(rows=("II/N=10",)), entries, str(tmp_path))
    fps = {"h2int": leaderboard.fingerprint(entries[1], suite(rows=("II/N=10",)))}
    rows, groups, planners, _ = leaderboard.gather(str(tmp_path), suite(rows=("II/N=10",)), {}, {}, fps)
    assert list(rows) == ["orca", "h2int"] and planners == {"orca"}  # orca's from its stored file
    assert leaderboard.legend_label("orca", 1, trained=False) == "orca"
    assert leaderboard.legend_label("h2int", 1) == "h2int (1 seed)"
    assert leaderboard.legend_label("h2int", 3) == "h2int (3 seeds)"


def test_a_failing_pedestrian_model_is_reported_by_name(tmp_path, monkeypatch):
    from crowdbench.humans.base import PedestrianModelError
    from crowdbench.worlds import CrowdWorld

    world = CrowdWorld(num_worlds=1, human_model="linear")
    monkeypatch.setattr(world.human_model, "step", lambda state, rngs: np.full((1, world.num_humans, 2), np.inf))
    with pytest.raises(PedestrianModelError, match="pedestrian model Linear returned NaN or inf"):
        world.step(np.zeros((1, 2)))
    assert "linear" in HUMAN_MODELS.names()


def test_workers_give_identical_files(tmp_path):
    entries = [leaderboard.ENTRIES["orca"], leaderboard.ENTRIES["social_force"]]
    leaderboard.run_suite(suite(), entries, str(tmp_path / "one"))
    leaderboard.run_suite(suite(), entries, str(tmp_path / "two"), workers=2)
    for name in ("orca.json", "social_force.json"):
        assert stable(tmp_path / "one" / name) == stable(tmp_path / "two" / name)
    assert (tmp_path / "one" / "LEADERBOARD.md").read_text() == (tmp_path / "two" / "LEADERBOARD.md").read_text()
    # one method at a time, then both: the stored cells are reused and the board is the same; a run shows the methods
    # asked for only
    leaderboard.run_suite(suite(), entries[1:], str(tmp_path / "three"))
    leaderboard.run_suite(suite(), entries[:1], str(tmp_path / "three"))
    assert "| social_force |" not in (tmp_path / "three" / "LEADERBOARD.md").read_text()
    lines: list[str] = []
    leaderboard.run_suite(suite(), entries, str(tmp_path / "three"), progress=lines.append)
    assert "6 stored, 0 to run" in lines[0]
    assert (tmp_path / "three" / "LEADERBOARD.md").read_text() == (tmp_path / "one" / "LEADERBOARD.md").read_text()


def test_a_killed_run_resumes_without_losing_or_recomputing_a_cell(tmp_path):
    toml = tmp_path / "s.toml"
    toml.write_text('episodes = 24\ntables = ["II"]\nworlds = 8\ncounterfactual = false\n')
    cmd = [sys.executable, "-m", "crowdbench.cli", "leaderboard", "run", "--suite", str(toml), "--methods",
           "orca,social_force,linear", "--out"]
    proc = subprocess.Popen([*cmd, str(tmp_path / "killed")], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    cells_dir = tmp_path / "killed" / "cells"
    deadline = time.time() + 300
    while time.time() < deadline and len(list(cells_dir.rglob("*.json"))) < 3 and proc.poll() is None:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    before = {p: p.stat().st_mtime_ns for p in cells_dir.rglob("*.json")}
    assert 3 <= len(before) < 9, "the run should have been killed mid-way"
    out = subprocess.run([*cmd, str(tmp_path / "killed")], capture_output=True, text=True, check=True).stdout
    assert f"{len(before)} stored, {9 - len(before)} to run" in out
    assert all(p.stat().st_mtime_ns == t for p, t in before.items())  # nothing finished was recomputed
    subprocess.run([*cmd, str(tmp_path / "straight")], capture_output=True, check=True)
    for name in ("orca.json", "social_force.json", "linear.json"):
        assert stable(tmp_path / "killed" / name) == stable(tmp_path / "straight" / name)
    board = [(tmp_path / run / "LEADERBOARD.md").read_text() for run in ("killed", "straight")]
    assert board[0] == board[1]


@pytest.mark.slow
def test_ray_backend_equals_local(tmp_path):
    pytest.importorskip("ray")
    entries = [leaderboard.ENTRIES["orca"], leaderboard.ENTRIES["social_force"]]
    quick = leaderboard.load_suite("quick", episodes=6)
    leaderboard.run_suite(quick, entries, str(tmp_path / "local"), workers=2)
    leaderboard.run_suite(quick, entries, str(tmp_path / "ray"), workers=2, backend="ray")
    for name in ("orca.json", "social_force.json"):
        assert stable(tmp_path / "local" / name) == stable(tmp_path / "ray" / name)


def test_cli_leaderboard_list_and_errors(capsys):
    from crowdbench.cli import main

    assert main(["leaderboard", "list"]) == 0
    out = capsys.readouterr().out
    assert "orca" in out and "quick" in out and "shipped checkpoints" in out
    assert main(["leaderboard", "run", "--suite", "quick", "--methods", "nope"]) == 2
    assert "--methods: unknown 'nope'" in capsys.readouterr().err
    assert main(["leaderboard", "run", "--suite", "quick", "--methods", "orca", "--backend", "spark"]) == 2
    assert "valid choices: local, ray" in capsys.readouterr().err
    assert os.path.exists(leaderboard.SUITES_DIR / "paper.toml")


def test_render_writes_one_episode_of_any_policy(tmp_path, capsys):
    from PIL import Image

    from crowdbench.cli import main

    out = tmp_path / "episode.gif"
    assert main(["render", "social_force", "--layout", "split_flow", "--humans", "6", "--seed", "3",
                 "--out", str(out)]) == 0
    frames = Image.open(out).n_frames
    assert frames >= 2 and f"frames={frames}" in capsys.readouterr().out


def test_an_edited_outside_policy_is_re_evaluated_and_an_unchanged_one_reused(tmp_path, monkeypatch):
    """Stored cells are trusted only while the policy's code is the same (its source file is in the fingerprint);
    LEADERBOARD.md shows the methods asked for."""
    import importlib.util
    import sys

    from crowdbench.policies import POLICIES

    src = tmp_path / "my_planner.py"

    def load(speed: float):
        src.write_text("import numpy as np\nfrom crowdbench.policies.base import RobotPolicy\n\n\n"
                       "class Mine(RobotPolicy):\n    def act(self, obs):\n"
                       "        r = obs['robot']\n        d = r[:, 3:5] - r[:, 0:2]\n"
                       f"        return {speed} * d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)\n")
        spec = importlib.util.spec_from_file_location("my_planner", src)
        mod = importlib.util.module_from_spec(spec)
        monkeypatch.setitem(sys.modules, "my_planner", mod)
        spec.loader.exec_module(mod)
        POLICIES.register("mine_tmp", mod.Mine, overwrite=True)

    monkeypatch.setattr(POLICIES, "_factories", dict(POLICIES._factories))
    s = suite(rows=("II/N=10",), episodes=6, worlds=6)
    entries = [leaderboard.Entry("mine_tmp", "mine_tmp")]
    out = str(tmp_path / "board")
    lines: list[str] = []
    load(1.0)
    first = leaderboard.run_suite(s, entries, out, progress=lines.append)["mine_tmp"][0]
    load(1.0)  # unchanged source: nothing re-evaluated
    lines.clear()
    leaderboard.run_suite(s, entries, out, progress=lines.append)
    assert "1 stored, 0 to run" in lines[0]
    load(0.3)  # edited: the cell is re-evaluated and the row shows the edited policy
    lines.clear()
    second = leaderboard.run_suite(s, entries, out, progress=lines.append)["mine_tmp"][0]
    assert "0 stored, 1 to run" in lines[0]
    assert second["nav_time"] != first["nav_time"] or second["success_rate"] != first["success_rate"]
    board = (tmp_path / "board" / "LEADERBOARD.md").read_text()
    assert "| mine_tmp |" in board
    leaderboard.run_suite(s, [leaderboard.ENTRIES["orca"]], out)
    board = (tmp_path / "board" / "LEADERBOARD.md").read_text()
    assert "| orca |" in board and "mine_tmp" not in board  # the methods asked for


@pytest.mark.slow
def test_training_seeds_in_parallel_equals_training_them_one_by_one(tmp_path):
    """``crowdbench train METHOD --seeds 0,1`` (worker processes) writes the same weights as the two commands."""
    import torch

    from crowdbench.cli import main

    tiny = ["--il-episodes", "4", "--rl-episodes", "4", "--worlds", "2"]
    assert main(["train", "cadrl", "--seeds", "0,1", "--out", str(tmp_path / "multi"), *tiny]) == 0
    for s in (0, 1):
        assert main(["train", "cadrl", "--seed", str(s), "--out", str(tmp_path / f"one{s}"), *tiny]) == 0
        a = torch.load(tmp_path / "multi" / f"seed{s}" / "policy.pt", weights_only=True)["net"]
        b = torch.load(tmp_path / f"one{s}" / "policy.pt", weights_only=True)["net"]
        assert a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)
    a0 = torch.load(tmp_path / "multi" / "seed0" / "policy.pt", weights_only=True)["net"]
    a1 = torch.load(tmp_path / "multi" / "seed1" / "policy.pt", weights_only=True)["net"]
    assert any(not torch.equal(a0[k], a1[k]) for k in a0)  # different seeds, different runs


def test_seed_commands_repeat_the_command_per_seed():
    from crowdbench.training.seeds import seed_commands

    cmds = seed_commands(["train", "h2int", "--seeds", "0,2", "--backend=local", "--out", "runs/x", "--minutes", "9"],
                         [0, 2], "runs/x")
    assert cmds == [["train", "h2int", "--minutes", "9", "--seed", "0", "--out", "runs/x/seed0"],
                    ["train", "h2int", "--minutes", "9", "--seed", "2", "--out", "runs/x/seed2"]]


def test_a_policy_reading_full_state_runs_in_its_own_section(tmp_path, monkeypatch):
    """An outside policy that declares ``observation = "full_state"`` keeps working: it runs, its cells record
    ``sensing=full``, and the board shows it in the privileged section, not ranked with the positions rows."""
    import numpy as np

    from crowdbench.policies import POLICIES
    from crowdbench.policies.base import RobotPolicy

    class Omniscient(RobotPolicy):
        observation = "full_state"

        def act(self, obs):
            r = obs["robot"]
            d = r[:, 3:5] - r[:, 0:2]
            return d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)

    monkeypatch.setattr(POLICIES, "_factories", dict(POLICIES._factories))
    POLICIES.register("omniscient_tmp", Omniscient)
    s = suite(rows=("II/N=10",), episodes=4, worlds=4)
    entries = [leaderboard.ENTRIES["orca"], leaderboard.parse_entry("omni=omniscient_tmp")]
    leaderboard.run_suite(s, entries, str(tmp_path))
    cell = json.loads((tmp_path / "cells" / "omni" / "II-n-10.json").read_text())
    assert cell["fingerprint"]["sensing"] == "full"
    md = (tmp_path / "LEADERBOARD.md").read_text()
    ranked, privileged = md.split("## Rows at `sensing=full`")
    assert "| omni |" not in ranked and "| omni |" in privileged and "| orca |" in ranked
