"""The command line: demo writes a GIF and reports an outcome; evaluate prints and writes the paper's metrics."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
from PIL import Image

from crowdbench.cli import main
from crowdbench.evaluation import Episode, run_episodes, summarize
from crowdbench.policies import make_policy


def test_demo_writes_gif(tmp_path, capsys):
    gif = tmp_path / "demo.gif"
    assert main(["demo", "--humans", "5", "--seed", "1", "--gif", str(gif)]) == 0
    out = capsys.readouterr().out
    assert "outcome=" in out
    img = Image.open(gif)
    assert img.n_frames > 5


def test_evaluate_json(tmp_path, capsys):
    path = tmp_path / "res.json"
    assert main(["evaluate", "--episodes", "8", "--humans", "5", "--policy", "orca", "--json", str(path)]) == 0
    res = json.loads(path.read_text())
    s = res["summary"]
    assert s["episodes"] == 8
    assert abs(s["success_rate"] + s["collision_rate"] + s["timeout_rate"] - 1) < 1e-9


def test_bad_model_is_one_clear_error(capsys):
    assert main(["demo", "--human-model", "nope"]) == 2
    assert "unknown pedestrian model 'nope'; valid choices" in capsys.readouterr().err


def test_evaluation_independent_of_batch_size():
    pol = make_policy("orca")
    a = run_episodes(pol, 6, seed=4, num_worlds=1, num_humans=8)
    b = run_episodes(pol, 6, seed=4, num_worlds=6, num_humans=8)
    np.testing.assert_equal([dataclasses.astuple(e) for e in a], [dataclasses.astuple(e) for e in b])  # NaN == NaN


def test_summarize_by_hand():
    eps = [Episode(0, "success", 10.0, 12.0, 1.0), Episode(1, "collision", 3.0, 3.0, 0.5),
           Episode(2, "success", 14.0, 13.0, 1.0), Episode(3, "timeout", 50.0, 20.0, 0.2)]
    s = summarize(eps)
    assert (s["success_rate"], s["collision_rate"], s["timeout_rate"]) == (0.5, 0.25, 0.25)
    assert s["nav_time"] == 12.0 and s["path_length"] == 12.5 and abs(s["delta_v"] - 0.675) < 1e-12


def test_social_force_robot_beats_walking_blind():
    """Sanity of the SF baseline: among non-reactive pedestrians it collides less than driving straight."""
    sf = summarize(run_episodes(make_policy("social_force"), 40, seed=0, num_humans=10, human_model="linear"))
    lin = summarize(run_episodes(make_policy("linear"), 40, seed=0, num_humans=10, human_model="linear"))
    assert sf["collision_rate"] < lin["collision_rate"]


def test_demo_runs_a_named_checkpoint_and_refuses_one_for_a_policy_without(tmp_path, capsys):
    gif = tmp_path / "demo.gif"
    argv = ["demo", "--policy", "h2int", "--checkpoint", "h2int-seed2", "--humans", "5", "--gif", str(gif)]
    assert main(argv) == 0
    assert "policy=h2int" in capsys.readouterr().out and gif.exists()
    assert main(["demo", "--policy", "orca", "--checkpoint", "h2int", "--gif", str(gif)]) == 2
    assert "--checkpoint: policy 'orca' takes no checkpoint" in capsys.readouterr().err
