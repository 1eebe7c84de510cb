"""`crowdbench ship` beyond the PPO run (tests/training/test_training.py): a value run, the predictor's file, bad
input, idempotence, and a training state hidden under an unexpected key."""

from __future__ import annotations

import re

import pytest
import torch

from crowdbench import checkpoints
from crowdbench.cli import main
from crowdbench.training.ship import TRAINING_STATE, ship
from crowdbench.training.value import ValueTrainConfig, ValueTrainer


@pytest.fixture
def value_run(tmp_path):
    """An untrained CADRL run folder (``last.pt`` with memory and optimiser, ``policy.pt``)."""
    cfg = ValueTrainConfig(method="cadrl", il_episodes=8, il_epochs=2, rl_episodes=8, worlds=4, capacity=500,
                           humans_range=(2, 5), eval_every=0)
    ValueTrainer(cfg, str(tmp_path / "run"), quiet=True).save(figure=False)
    return tmp_path / "run"


def test_a_value_run_ships_as_its_policy_file_plus_provenance_and_cannot_resume(value_run, tmp_path, capsys):
    shipped = ship(value_run, out=tmp_path / "cadrl.pt")
    assert shipped.source.endswith("last.pt") and shipped.bytes_after < shipped.bytes_before
    assert {"optimizer", "memory", "target", "rng", "torch_rng", "history"} <= set(shipped.dropped)
    ckpt, policy = checkpoints.load(shipped.path, "cadrl"), checkpoints.load(value_run / "policy.pt", "cadrl")
    assert set(ckpt) - {"shipped"} == set(policy) and not set(ckpt) & set(TRAINING_STATE)
    for k, v in policy["net"].items():
        assert torch.equal(ckpt["net"][k], v), k
    prov = ckpt["shipped"]
    assert prov["budget"] == {"episodes": 0} and prov["counters"]["episodes"] == 0 and prov["method"] == "cadrl"
    assert prov["source_sha256"] == checkpoints.file_sha256(value_run / "last.pt") and prov["eval"] is None
    assert main(["train", "cadrl", "--resume", shipped.path]) == 2
    assert "a shipped weights-only checkpoint cannot resume; train from runs/…/last.pt" in capsys.readouterr().err
    assert main(["train", "cadrl", "--resume", str(value_run / "policy.pt")]) == 2  # a bare policy file neither
    assert "no training state ('memory')" in capsys.readouterr().err


def test_ship_writes_name_into_the_methods_folder_and_is_idempotent(value_run, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(checkpoints, "folder_of", lambda method: tmp_path / "pkg" / method)
    assert main(["ship", str(value_run), "--name", "cadrl-seed7"]) == 0
    path = tmp_path / "pkg" / "cadrl" / "cadrl-seed7.pt"
    assert f"→ {path}: " in capsys.readouterr().out
    first = checkpoints.load(path, "cadrl")["shipped"]
    again = ship(path, out=tmp_path / "again.pt")  # shipping a shipped file keeps its provenance
    assert again.dropped == () and checkpoints.load(again.path)["shipped"] == first


def test_the_predictor_ships_with_its_held_out_figures(tmp_path):
    shipped = ship(checkpoints.shipped("gst", "gst"), out=tmp_path / "gst.pt")
    prov = checkpoints.load(shipped.path, "gst")["shipped"]
    assert set(prov["eval"]) == {"ade", "fde", "const_vel_ade", "const_vel_fde"} and prov["counters"]["epochs"] == 15


@pytest.mark.parametrize(("argv", "message"), [
    (["--method", "sarl", "--out", "x.pt"], "ship --method 'sarl': .* holds method 'cadrl'; valid choices: cadrl"),
    ([], "--name is required"),
    (["--name", "a/b"], "ship --name 'a/b'; valid choices: a file name without folder"),
    (["--name", "last"], "ship --name 'last'; valid choices"),
])
def test_bad_input_is_one_clear_error(value_run, tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(checkpoints, "folder_of", lambda method: tmp_path / "pkg" / method)
    assert main(["ship", str(value_run), *argv]) == 2
    assert re.search(message, capsys.readouterr().err)
    assert not (tmp_path / "pkg").exists() and not (tmp_path / "x.pt").exists()


def test_an_optimiser_state_under_another_key_is_refused(value_run, tmp_path):
    ckpt = checkpoints.load(value_run / "last.pt")
    ckpt["extra"] = {"opt": ckpt["optimizer"]}
    torch.save(ckpt, tmp_path / "odd.pt")
    with pytest.raises(ValueError, match=r"holds an optimiser state under extra\.opt"):
        ship(tmp_path / "odd.pt", out=tmp_path / "out.pt")
    assert not (tmp_path / "out.pt").exists()
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match=r"has no last.pt and 0 \*.pt files"):
        ship(tmp_path / "empty", out=tmp_path / "out.pt")
