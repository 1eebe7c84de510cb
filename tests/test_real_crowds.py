"""Real crowds: the ETH/UCY package data equals the raw files, the ADE/FDE protocol, recorded-scene worlds and the
replay models."""

from __future__ import annotations

import hashlib
import json
import os

import numpy as np
import pytest

from crowdbench.cli import main
from crowdbench.config import WorldConfig
from crowdbench.datasets import RECORDINGS, load_recording, scene_recordings
from crowdbench.datasets import validate as cv
from crowdbench.worlds import CrowdWorld

# SHA-256 of np.loadtxt(<Trajectron++>/experiments/pedestrians/raw/raw/all_data/<name>.txt, float64).tobytes(), the
# number of rows of raw/train/<name>_train.txt, and the last row of the recording (copied from the raw files)
RAW = {
    "biwi_eth": ("4b4aed12e3376b3af7f5572ddbbe01df", 3666, [12380.0, 367.0, 11.2, 8.44]),
    "biwi_hotel": ("c847ae42dcff811a7ecc6a14dd11bcd0", 4946, [18060.0, 420.0, 3.62, -5.63]),
    "crowds_zara01": ("c8e867a71dafe55216bbc3b3dc8f5283", 4307, [9010.0, 148.0, 0.21909417912, 5.996088808]),
    "crowds_zara02": ("9886670107129bc2e5089e33a1f93915", 7621, [10520.0, 204.0, 9.1594415709, 4.2505310329]),
    "crowds_zara03": ("51474e06e362cdf928d87957dfbbb7b5", 3708, [7530.0, 137.0, 12.4115484448, 5.55313621973]),
    "students001": ("8b8c68806ec1227459d1add8995edb26", 18353, [4430.0, 390.0, 10.4361229259, 6.05026458254]),
    "students003": ("30f2f163c5eee34e71b1370416802b26", 15641, [5400.0, 408.0, 13.4878670155, 11.1284678008]),
    "uni_examples": ("c9d699fed8d23e309bf2aed6b3c897d8", 2266, [7410.0, 118.0, 7.78720905614, 10.3459023176]),
}


@pytest.mark.parametrize("name", RECORDINGS)
def test_the_package_data_equals_the_raw_files(name):
    digest, train_rows, last = RAW[name]
    rows = load_recording(name)
    assert hashlib.sha256(np.ascontiguousarray(rows).tobytes()).hexdigest()[:32] == digest
    assert rows[-1].tolist() == last
    assert len(load_recording(name, "train")) == train_rows
    np.testing.assert_array_equal(np.concatenate([load_recording(name, "train"), load_recording(name, "val")]), rows)
    raw = os.environ.get("CROWDBENCH_ETHUCY_RAW")  # <Trajectron++>/experiments/pedestrians/raw, when at hand
    if raw:
        np.testing.assert_array_equal(rows, np.loadtxt(os.path.join(raw, "raw", "all_data", f"{name}.txt"), ndmin=2))


def test_leave_one_scene_out_splits():
    assert [n for n, _ in scene_recordings("univ", "test")] == ["students001", "students003"]
    train = [n for n, _ in scene_recordings("eth", "train")]
    assert "biwi_eth" not in train and len(train) == 7
    assert len(scene_recordings("univ", "val")) == 6
    with pytest.raises(ValueError, match="scene='ucy'; valid choices: eth, hotel, univ, zara1, zara2"):
        scene_recordings("ucy")


def _rows(tracks: dict[int, list[tuple[int, float, float]]]) -> np.ndarray:
    return np.array(sorted((10.0 * f, float(p), x, y) for p, pts in tracks.items() for f, x, y in pts))


def test_windows_need_twenty_consecutive_frames_and_const_vel_extrapolates():
    walker = [(f, 0.5 * f, 1.0) for f in range(25)]  # 25 frames at 1.25 m/s: 6 windows
    gappy = [(f, 0.0, 0.3 * f) for f in range(30) if f != 12]  # a missing frame: windows 13–29 only → none
    traj, window = cv.samples(_rows({1: walker, 2: gappy}))
    assert len(traj) == 6 and (window == np.arange(6)).all()
    np.testing.assert_allclose(cv.const_vel(traj[:, :8]), traj[:, 8:])  # a straight walk: no error
    curved = traj.copy()
    curved[:, 8:, 1] += 0.1 * np.arange(1, 13)
    pred = cv.const_vel(curved[:, :8])
    err = np.linalg.norm(pred - curved[:, 8:], axis=-1)
    np.testing.assert_allclose(err.mean(axis=1), 0.1 * np.arange(1, 13).mean())


def test_crowd_validate_writes_every_scene_with_sample_counts(tmp_path):
    out = tmp_path / "cv.json"
    assert main(["crowd-validate", "--models", "const_vel,orca", "--scenes", "zara1,hotel", "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    assert set(res) == {"zara1", "hotel"} and set(res["zara1"]) == {"const_vel", "orca"}
    assert res["zara1"]["const_vel"]["samples"] == res["zara1"]["orca"]["samples"] > 1000
    assert 0.2 < res["zara1"]["const_vel"]["ade"] < res["zara1"]["const_vel"]["fde"] < 2.0
    assert main(["crowd-validate", "--models", "teleport"]) == 2  # one clear error naming the valid models


def _world(model, humans=20, **config):
    return CrowdWorld(WorldConfig(num_humans=humans, **config), 2, "zara1", model)


def test_replay_moves_people_exactly_as_recorded_and_caps_the_slots():
    w = _world("replay")
    m = w.human_model
    for _ in range(80):
        w.step(np.zeros((2, 2)))
        b, k = np.arange(2), np.minimum(m._k, m.steps - 1)
        here = m._present[b, k]
        np.testing.assert_allclose(w.pos[:, 1:][here], m._pos[b, k][here], atol=1e-9)
        assert (w.active[:, 1:] == here).all()
    capped = _world("replay", humans=3)
    assert capped.human_model.dropped.sum() > 0 and capped.active[:, 1:].sum(axis=1).max() <= 3


def test_reactive_replay_follows_its_recording_unless_the_robot_comes_near():
    def deviation(robot_visible):
        w = _world("reactive_replay", robot_visible=robot_visible)
        m, dev = w.human_model, 0.0
        for _ in range(80):
            w.step(np.zeros((2, 2)))  # the robot stands in the scene
            b, k = np.arange(2), np.minimum(m._k, m.steps - 1)
            here = m._present[b, k] & (m._placed == m._who[b, k])
            dev = max(dev, float(np.abs(w.pos[:, 1:][here] - m._pos[b, k][here]).max(initial=0.0)))
        return dev

    assert deviation(False) < 1e-9
    assert deviation(True) > 0.1


def test_replay_needs_a_recorded_scene():
    with pytest.raises(ValueError, match="human_model='replay' replays recorded people; valid layouts: eth"):
        CrowdWorld(WorldConfig(num_humans=5), 1, "circle_crossing", "replay")


def test_evaluate_runs_on_a_real_crowd(tmp_path):
    for model in ("replay", "reactive_replay"):
        out = tmp_path / f"{model}.json"
        assert main(["evaluate", "orca", "--layout", "zara1", "--human-model", model, "--episodes", "4",
                     "--worlds", "4", "--json", str(out)]) == 0
        assert 0.0 <= json.loads(out.read_text())["summary"]["success_rate"] <= 1.0
