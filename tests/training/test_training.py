"""Training smoke test: tiny train → checkpoint → exact resume → evaluate; exports match PyTorch; curriculum;
checkpoints are safe to load and old ones fail clearly."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from crowdbench import checkpoints
from crowdbench.cli import main
from crowdbench.policies.h2int import H2INTPolicy
from crowdbench.policies.h2int.export import export_module, export_onnx, export_torchscript
from crowdbench.robots.deploy import planar_to_unicycle
from crowdbench.training.config import TrainConfig
from crowdbench.training.curriculum import Curriculum
from crowdbench.training.trainer import train


def load_checkpoint(path):
    return checkpoints.load(path, "h2int")


def tiny(**kw) -> TrainConfig:
    model = {"d_model": 16, "heads": 2, "ffn": 16, "gru_hidden": 16, "head_dims": (16,), **kw.pop("model", {})}
    base = dict(num_envs=8, steps_per_env=8, mini_batches=2, epochs=1, model=model, humans_range=(2, 5),
                checkpoint_every=2, eval_every=2, eval_episodes=4, window=8)
    base.update(kw)
    return TrainConfig(**base)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    straight = train(tiny(iterations=4), str(root / "straight"), quiet=True)
    train(tiny(iterations=2), str(root / "split"), quiet=True)
    resumed = train(tiny(iterations=4), str(root / "split"), resume=str(root / "split"), quiet=True)
    return root, straight, resumed


def test_resume_continues_exactly(runs):
    _, straight, resumed = runs
    assert resumed.iteration == straight.iteration == 4
    a, b = straight.alg.actor.state_dict(), resumed.alg.actor.state_dict()
    for k in a:
        torch.testing.assert_close(a[k], b[k], rtol=0, atol=0)
    assert straight.history["mean_reward"] == resumed.history["mean_reward"]
    assert straight.env.curriculum.state_dict() == resumed.env.curriculum.state_dict()


def test_runs_saved_before_the_noise_column_resume_with_it_filled_from_there_on(runs, tmp_path):
    """A checkpoint whose history has no ``action_std`` (older runs, e.g. the in-progress states) resumes: the
    column gets ``None`` for its past iterations and the fixed std (0.3) from there on."""
    root, _, _ = runs
    ckpt = torch.load(root / "split" / "last.pt", weights_only=True)
    assert ckpt["history"]["action_std"] == [pytest.approx(0.3)] * 4
    del ckpt["history"]["action_std"]
    torch.save(ckpt, tmp_path / "old.pt")
    resumed = train(tiny(iterations=5), str(tmp_path / "run"), resume=str(tmp_path / "old.pt"), quiet=True)
    assert resumed.history["action_std"] == [None] * 4 + [pytest.approx(0.3)]


def test_checkpoint_loads_weights_only_and_has_artifacts(runs):
    root, _, _ = runs
    ckpt = load_checkpoint(root / "straight" / "last.pt")  # weights_only=True inside
    assert ckpt["iteration"] == 4 and ckpt["model"]["variant"] == "h2int" and ckpt["seed"] == 0
    assert ckpt["method"] == "h2int" and ckpt["format"] == checkpoints.FORMAT and ckpt["crowdbench_version"]
    assert (root / "straight" / "curve.png").stat().st_size > 1000
    assert (root / "straight" / "history.json").exists()
    assert any((root / "straight" / "tb").iterdir())


def test_evaluate_checkpoint_from_cli(runs, tmp_path, capsys):
    root, _, _ = runs
    out = tmp_path / "e.json"
    code = main(["evaluate", "--policy", "h2int", "--checkpoint", str(root / "straight" / "last.pt"), "--episodes",
                 "4", "--humans", "5", "--responsiveness", "0.5", "--json", str(out)])
    assert code == 0 and out.exists()
    assert "success_rate" in capsys.readouterr().out


def test_exports_match_pytorch(runs, tmp_path):
    root, _, _ = runs
    path = str(root / "straight" / "last.pt")
    policy = H2INTPolicy(checkpoint=path)
    module = export_module(path)
    scripted = torch.jit.load(export_torchscript(path, str(tmp_path / "policy.pt")))
    rng = np.random.default_rng(0)
    B, n = 3, 30
    h_ts = torch.zeros(1, B, module.hidden_size)
    onnx_path = export_onnx(path, str(tmp_path / "policy.onnx"))
    try:
        import onnxruntime as ort

        sess = ort.InferenceSession(onnx_path)
    except ImportError:  # optional dependency
        sess = None
    h_ox = np.zeros((1, B, module.hidden_size), np.float32)
    for _ in range(50):
        robot = rng.normal(size=(B, 9)).astype(np.float32)
        humans = rng.normal(scale=3, size=(B, n, 2)).astype(np.float32)
        mask = (rng.random((B, n)) < 0.3).astype(np.float32)
        ref = policy.act({"robot": robot, "humans": humans, "mask": mask})
        with torch.no_grad():
            a_ts, h_ts = scripted(torch.from_numpy(robot), torch.from_numpy(humans), torch.from_numpy(mask), h_ts)
        np.testing.assert_allclose(a_ts.numpy(), ref, atol=1e-5)
        if sess is not None:
            a_ox, h_ox = sess.run(None, {"robot": robot, "humans": humans, "mask": mask, "h_in": h_ox})
            np.testing.assert_allclose(a_ox, ref, atol=1e-5)


def test_planar_to_unicycle_bounds():
    v, w = planar_to_unicycle(np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, 0.0]]), np.zeros(4),
                              v_max=0.8, w_max=1.0)
    np.testing.assert_allclose(v, [0.8, 0.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.abs(w), [0.0, 1.0, 1.0, 0.0], atol=1e-12)  # behind: turn on the spot, max rate


def test_curriculum_lowers_rho_only_after_window_and_cooldown():
    c = Curriculum(window=10, cooldown=10, eta=0.9)
    assert not c.record(np.ones(9, bool), 9)  # window not full
    assert c.record(np.ones(1, bool), 10) and c.rho == pytest.approx(0.7)
    assert not c.record(np.ones(9, bool), 19)  # cooldown: window refilled at the new ρ first
    assert c.record(np.ones(1, bool), 20) and c.rho == pytest.approx(0.6)
    assert not c.record(np.zeros(10, bool), 30)  # success below η: no change
    fixed = Curriculum(enabled=False, window=2, cooldown=2)
    assert not fixed.record(np.ones(5, bool), 5) and fixed.rho == 0.8


def test_no_anneal_trains_at_final_difficulty(tmp_path):
    tr = train(tiny(iterations=1, anneal=False, eval_every=0, env_processes=1), str(tmp_path / "fixed"), quiet=True)
    assert tr.env.curriculum.rho == 0.0 and not tr.env.curriculum.enabled
    assert tr.env.worlds.world.human_model.responsiveness == 0.0


def test_until_success_stops_at_the_first_evaluation_that_reaches_it(tmp_path, monkeypatch):
    from crowdbench.training.trainer import Trainer

    rates = iter([0.5, 0.97, 1.0])
    monkeypatch.setattr(Trainer, "evaluate", lambda self, episodes: {"success_rate": next(rates),
                                                                      "collision_rate": 0.0, "timeout_rate": 0.0})
    trainer = train(tiny(iterations=10, until_success=0.95), str(tmp_path / "run"), quiet=True)
    assert trainer.iteration == 4  # evaluations at 2 (50 %) and 4 (97 %): stopped there, not at 10
    assert [e["success_rate"] for e in trainer.evals] == [0.5, 0.97]
    assert load_checkpoint(str(tmp_path / "run" / "last.pt"))["iteration"] == 4
    with pytest.raises(ValueError, match="until_success"):
        tiny(until_success=1.5)
    with pytest.raises(ValueError, match="eval_every"):
        tiny(until_success=0.9, eval_every=0)


def test_runs_table_reports_when_the_bar_was_first_reached(runs):
    from crowdbench.training.plots import runs_table

    root, _, _ = runs
    histories = [str(root / "straight" / "history.json"), str(root / "split" / "history.json")]
    always = runs_table(histories, bar=0.0).splitlines()
    assert len(always) == 4 and all("iteration 2 |" in row for row in always[2:])  # first evaluation: iteration 2
    assert "1×2 lr 0.0003 adaptive seed 0 (ρ annealed)" in always[2]  # schedule, learning rate, seed, curriculum
    never = runs_table(histories, bar=1.01).splitlines()
    assert all("not reached" in row for row in never[2:])


def test_curves_command_plots_and_tabulates_runs(runs, tmp_path, capsys):
    root, _, _ = runs
    histories = [str(root / "straight" / "history.json"), str(root / "split" / "history.json")]
    for flag in ([], ["--evals"]):
        out = tmp_path / f"c{len(flag)}.png"
        assert main(["curves", *histories, "--out", str(out), "--table", "0.0", *flag]) == 0
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    printed = capsys.readouterr().out
    assert printed.count("| h2int 1×2 lr 0.0003 adaptive seed 0 (ρ annealed) | iteration 2 |") == 4  # two runs, twice


def test_old_format_checkpoints_are_refused_and_weights_only_files_do_not_resume(tmp_path, capsys):
    """The previous H²INT format (`crowdbench.h2int/1`) is one clear error; a checkpoint without its training state
    evaluates but cannot be resumed."""
    old = tmp_path / "old.pt"
    torch.save({"format": "crowdbench.h2int/1", "model": {}, "actor": {}}, old)
    with pytest.raises(ValueError, match="older crowdbench .*'crowdbench.h2int/1'.*reads only 'crowdbench.checkp"):
        H2INTPolicy(checkpoint=str(old))
    ckpt = torch.load(checkpoints.shipped("h2int", "meanpool"), weights_only=True)
    weights = tmp_path / "weights.pt"
    torch.save({k: v for k, v in ckpt.items() if k not in ("train_config", "shipped")}, weights)  # a bare weights file
    policy = H2INTPolicy(checkpoint=str(weights))
    assert policy.meta["variant"] == "meanpool"
    obs = {"robot": np.zeros((2, 9), np.float32), "humans": np.ones((2, 30, 2), np.float32),
           "mask": np.ones((2, 30), np.float32)}
    assert np.isfinite(policy.act(obs)).all()
    code = main(["train", "h2int", "--resume", str(weights), "--out", str(tmp_path / "r"), "--iterations", "1"])
    assert code == 2 and "no training state; it cannot be resumed" in capsys.readouterr().err


@pytest.mark.parametrize("method", ["h2int", "cadrl", "sarl"])
def test_checkpoint_that_would_run_code_is_refused(tmp_path, capsys, method):
    import os
    import pickle

    marker = tmp_path / "ran"

    class Evil:
        def __reduce__(self):
            return (os.system, (f"touch {marker}",))

    path = tmp_path / "evil.pt"
    with open(path, "wb") as f:
        pickle.dump({"format": checkpoints.FORMAT, "method": method, "payload": Evil()}, f)
    assert main(["evaluate", method, "--checkpoint", str(path), "--episodes", "1"]) == 2
    err = capsys.readouterr().err
    assert "refused" in err and "run code" in err and not marker.exists()


def test_checkpoint_errors_name_the_problem(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        checkpoints.load(tmp_path / "nope.pt")
    torch.save({"format": "something/9"}, tmp_path / "other.pt")
    with pytest.raises(ValueError, match="not a crowdbench checkpoint"):
        checkpoints.load(tmp_path / "other.pt")
    torch.save({"format": checkpoints.FORMAT, "method": "sarl"}, tmp_path / "sarl.pt")
    with pytest.raises(ValueError, match="holds method 'sarl', not 'h2int'"):
        checkpoints.load(tmp_path / "sarl.pt", "h2int")


def test_train_config_is_frozen_strict_and_round_trips():
    import dataclasses

    cfg = tiny(model={"variant": "meanpool"})
    assert TrainConfig.from_dict(cfg.to_dict()) == cfg
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.seed = 3
    with pytest.raises(ValueError, match=r"unknown keys \['packed'\]"):
        TrainConfig.from_dict({**cfg.to_dict(), "packed": True})
    with pytest.raises(ValueError, match="variant='nope'; valid choices: h2int, flat, meanpool, standard"):
        tiny(model={"variant": "nope"})
    with pytest.raises(ValueError, match="unknown PPO method 'nope'; valid choices: aig_gst, dsrnn, h2int"):
        TrainConfig(method="nope")
    import inspect

    lines = inspect.getsource(TrainConfig).splitlines()
    for f in dataclasses.fields(TrainConfig):  # every field is followed by its docstring
        i = next(k for k, line in enumerate(lines) if line.startswith(f"    {f.name}: "))
        assert lines[i + 1].strip().startswith('"""'), f.name


def test_model_overrides_parse_by_field_type_and_reject_bad_input(capsys):
    """`crowdbench train --model FIELD=VALUE`: typed values over the variant's; unknown fields, unparsable values,
    value methods and resumed runs get one clear error."""
    from crowdbench.policies.h2int.training import H2INTMethod

    method = H2INTMethod()
    got = method.model_overrides(["d_model=64", "head_dims=128,64", "action_std=0.2", "variant=flat"])
    assert got == {"d_model": 64, "head_dims": (128, 64), "action_std": 0.2, "variant": "flat"}
    cfg = TrainConfig.for_method("h2int", model=got)
    assert (cfg.model.d_model, cfg.model.head_dims, cfg.model.gru_hidden) == (64, (128, 64), 64)
    with pytest.raises(ValueError, match="FIELD one of variant, d_model"):
        method.model_overrides(["width=3"])
    with pytest.raises(ValueError, match="d_model takes a int value"):
        method.model_overrides(["d_model=wide"])
    assert main(["train", "h2int", "--model", "d_model=33"]) == 2  # 33 is no multiple of 4 heads
    assert "heads=4; valid choices: a divisor of d_model=33" in capsys.readouterr().err
    assert main(["train", "cadrl", "--model", "d_model=64"]) == 2
    assert "--model: options of the PPO methods" in capsys.readouterr().err
    assert main(["train", "h2int", "--resume", "runs/x", "--model", "d_model=64"]) == 2
    assert "keeps its architecture" in capsys.readouterr().err


@pytest.mark.parametrize("method", ["h2int", "dsrnn", "aig_gst"])
@pytest.mark.parametrize("std", ["0", "-0.3"])
def test_a_non_positive_policy_std_is_one_clear_error_before_training(method, std, capsys):
    """`--model action_std=S` with S ≤ 0 stops at the config, naming the field and the valid range, for every PPO
    method (not deep inside rsl-rl's Gaussian)."""
    assert main(["train", method, "--model", f"action_std={std}", "--out", "runs/never"]) == 2
    assert f"action_std={float(std)!r}; valid choices: a positive float [m/s]" in capsys.readouterr().err


def configs_of_new_runs(monkeypatch, argvs: list[list[str]]) -> list:
    """The TrainConfig `crowdbench train ARGV --out runs/never` builds for each of ``argvs`` (training replaced)."""
    import crowdbench.training.trainer as trainer_mod

    seen = []

    def fake_train(cfg, out, resume=None, init=None):
        seen.append(cfg)
        raise SystemExit(0)

    monkeypatch.setattr(trainer_mod, "train", fake_train)
    for argv in argvs:
        with pytest.raises(SystemExit):
            main(["train", *argv, "--out", "runs/never"])
    return seen


def test_reward_scale_option_sets_new_runs_and_is_refused_on_resume(capsys, monkeypatch):
    """`--reward-scale` reaches a new run's TrainConfig; a resumed run keeps its configuration, so it and the other
    schedule options get one clear error there naming what may change."""
    (cfg,) = configs_of_new_runs(monkeypatch, [["dsrnn", "--variant", "small", "--reward-scale", "1.0"]])
    assert cfg.reward_scale == 1.0 and cfg.method == "dsrnn"
    assert main(["train", "h2int", "--reward-scale", "0"]) == 2
    assert "reward_scale=0.0; valid choices: a positive number" in capsys.readouterr().err
    assert main(["train", "h2int", "--resume", "runs/x", "--reward-scale", "1", "--epochs", "2"]) == 2
    err = capsys.readouterr().err
    assert "--epochs, --reward-scale: a resumed run keeps its configuration" in err and "--minutes" in err
    assert main(["train", "sarl", "--reward-scale", "1"]) == 2
    assert "--reward-scale: options of the PPO methods" in capsys.readouterr().err


def test_anneal_option_overrides_the_methods_curriculum_default(capsys, monkeypatch):
    """DS-RNN trains at ρ = 0 by default (the originals' invisible robot); `--anneal` gives it H²INT's curriculum,
    `--no-anneal` takes H²INT's away, nothing keeps each method's own; resumed runs and value methods refuse both."""
    seen = configs_of_new_runs(monkeypatch, [["dsrnn"], ["dsrnn", "--anneal"], ["h2int"], ["h2int", "--no-anneal"]])
    assert [c.anneal for c in seen] == [False, True, True, False]
    assert seen[1].rho_init == 0.8 and seen[1].learning_rate == 4e-5  # the curriculum, DS-RNN's own PPO recipe
    assert main(["train", "dsrnn", "--resume", "runs/x", "--anneal"]) == 2
    assert "--anneal: a resumed run keeps its configuration" in capsys.readouterr().err
    assert main(["train", "cadrl", "--no-anneal"]) == 2
    assert "--anneal/--no-anneal: options of the PPO methods" in capsys.readouterr().err


def test_learning_rate_options_override_the_methods_recipe_on_new_runs_only(capsys, monkeypatch):
    seen = configs_of_new_runs(monkeypatch, [["dsrnn"], ["dsrnn", "--learning-rate", "3e-4", "--schedule", "adaptive"]])
    assert [(c.learning_rate, c.schedule) for c in seen] == [(4e-5, "fixed"), (3e-4, "adaptive")]
    assert main(["train", "dsrnn", "--resume", "runs/x", "--learning-rate", "1e-3"]) == 2
    assert "--learning-rate: a resumed run keeps its configuration" in capsys.readouterr().err


def test_recurrent_baselines_train_their_small_widths_unless_told_otherwise(monkeypatch):
    """`crowdbench train dsrnn|aig_gst` builds the `small` widths (the shipped ones); `--variant original` the
    original's, and `--model` refines whichever variant is named (or the default)."""
    from crowdbench.policies.aig.model import AIGConfig
    from crowdbench.policies.dsrnn.model import DSRNNConfig

    seen = configs_of_new_runs(monkeypatch, [["dsrnn"], ["dsrnn", "--variant", "original"], ["aig_gst"],
                                             ["dsrnn", "--model", "latent=32"], ["h2int"]])
    assert seen[0].model.edge_rnn == 64 and seen[1].model == DSRNNConfig() and seen[1].model.edge_rnn == 256
    assert seen[2].model.robot_embed == 64 and AIGConfig().robot_embed == 256
    assert seen[3].model.latent == 32 and seen[3].model.edge_rnn == 64
    assert seen[4].model.variant == "h2int"


def test_curve_labels_name_the_recipe_that_differs():
    """`crowdbench curves` labels tell apart runs that differ only in schedule or in a fixed policy noise."""
    from crowdbench.training.plots import _colour_key, _run_label

    base = {"method": "dsrnn", "seed": 0, "epochs": 4, "mini_batches": 4, "learning_rate": 3e-4,
            "schedule": "adaptive", "anneal": False, "model": {"edge_rnn": 64, "learn_std": True}}
    fixed = {**base, "model": {"edge_rnn": 64, "learn_std": False, "action_std": 0.3}}
    assert "std" not in _run_label(base) and "lr 0.0003 adaptive std 0.3 fixed seed 0" in _run_label(fixed)
    assert _colour_key(base) != _colour_key(fixed)


def test_init_starts_a_new_run_from_another_runs_weights_with_its_own_noise(runs, tmp_path, capsys):
    """`--init` (fine-tuning): a new run takes a saved run's actor and critic — not its policy noise, optimiser,
    counters or history —, records where they came from (kept through a resume), and refuses another architecture,
    another method, or being combined with `--resume`."""
    import hashlib

    from crowdbench.training.ppo import gaussian_std
    from crowdbench.training.trainer import Trainer, resume_config

    root, straight, _ = runs
    src = root / "straight" / "last.pt"
    tr = Trainer(tiny(model={"action_std": 0.15}), str(tmp_path / "probe"), quiet=True)
    try:
        tr.warm_start(str(src))
        theirs, mine = straight.alg.actor.state_dict(), tr.alg.actor.state_dict()
        for k in theirs:
            if not k.startswith("distribution."):
                torch.testing.assert_close(mine[k], theirs[k], rtol=0, atol=0)
        for k, v in straight.alg.critic.state_dict().items():
            torch.testing.assert_close(tr.alg.critic.state_dict()[k], v, rtol=0, atol=0)
        assert torch.allclose(gaussian_std(tr.alg.actor.distribution), torch.tensor(0.15))
        assert tr.iteration == 0 and tr.history["iteration"] == [] and tr.alg.optimizer.state_dict()["state"] == {}
        assert tr.cfg.init["iteration"] == 4 and tr.cfg.init["sha256"] == hashlib.sha256(src.read_bytes()).hexdigest()
    finally:
        tr.close()
    with pytest.raises(ValueError, match=r"architecture differs in \['d_model'\]"):
        wide = Trainer(tiny(model={"d_model": 32}), str(tmp_path / "wide"), quiet=True)
        try:
            wide.warm_start(str(src))
        finally:
            wide.close()

    out = tmp_path / "ft"
    ft = train(tiny(iterations=2, model={"action_std": 0.15}), str(out), init=str(src), quiet=True)
    saved = torch.load(out / "last.pt", weights_only=True)
    assert saved["train_config"]["init"] == ft.cfg.init and saved["iteration"] == 2
    # its training budget counts the start's env steps too, and a fine-tune of the fine-tune counts all three runs
    from crowdbench.checkpoints import training_budget

    src_steps = torch.load(src, weights_only=True)["env_steps"]
    assert training_budget(saved) == {"env_steps": src_steps + saved["env_steps"]}
    ft2 = train(tiny(iterations=1, model={"action_std": 0.1}), str(tmp_path / "ft2"), init=str(out / "last.pt"),
                quiet=True)
    ft2.close()
    again = torch.load(tmp_path / "ft2" / "last.pt", weights_only=True)
    assert training_budget(again) == {"env_steps": src_steps + saved["env_steps"] + again["env_steps"]}
    resumed = train(resume_config(str(out / "last.pt"), iterations=3), str(out), resume=str(out), quiet=True)
    assert resumed.cfg.init == ft.cfg.init and resumed.history["action_std"] == [pytest.approx(0.15)] * 3

    assert main(["train", "h2int", "--resume", "runs/x", "--init", "runs/y"]) == 2
    assert "--init, --resume: a resumed run already has its weights" in capsys.readouterr().err
    assert main(["train", "sarl", "--init", "runs/y"]) == 2
    assert "--init" in capsys.readouterr().err


def test_ship_keeps_weights_config_and_provenance_and_the_shipped_file_acts_inits_and_exports(runs, tmp_path, capsys):
    """`crowdbench ship RUN`: the run's weights (bit for bit), configuration, counters and provenance, without
    optimiser, RNG, curriculum or history; it acts as its source, exports, starts a new run with `--init` exactly as
    the run's last.pt does, and `--resume` refuses it with one error."""
    from crowdbench.training.ship import TRAINING_STATE
    from crowdbench.training.trainer import Trainer

    root, straight, _ = runs
    src, out = root / "straight" / "last.pt", tmp_path / "shipped.pt"
    assert main(["ship", str(root / "straight"), "--out", str(out), "--method", "h2int"]) == 0
    printed = capsys.readouterr().out
    assert f"{src.stat().st_size:,} → {out.stat().st_size:,} bytes" in printed
    assert "dropped optimizer, learning_rate, env, torch_rng, history, evals" in printed
    full, ckpt = checkpoints.load(src, "h2int"), checkpoints.load(out, "h2int")
    assert not set(ckpt) & set(TRAINING_STATE) and out.stat().st_size < src.stat().st_size
    for key in ("model", "train_config", "n_max", "seed", "iteration", "env_steps", "crowd", "crowdbench_version"):
        assert ckpt[key] == full[key], key
    for part in ("actor", "critic"):
        assert ckpt[part].keys() == full[part].keys()
        for k, v in full[part].items():
            assert torch.equal(ckpt[part][k], v) and ckpt[part][k].dtype == v.dtype, (part, k)
    prov = ckpt["shipped"]
    assert prov["source_sha256"] == checkpoints.file_sha256(src) and prov["source_bytes"] == src.stat().st_size
    assert repr(prov["eval"]) == repr(full["evals"][-1]) and prov["eval"]["iteration"] == 4  # NaN-safe equality
    assert prov["budget"] == checkpoints.training_budget(ckpt) == {"env_steps": straight.env_steps}
    assert prov["summary"]["history_rows"] == 4 and prov["summary"]["evals"] == 2
    assert prov["summary"]["final"]["iteration"] == 4 and prov["crowd"] == full["crowd"] is not None
    assert prov["method"] == "h2int" and prov["seed"] == 0 and prov["counters"]["iteration"] == 4

    obs = {"robot": np.linspace(-1, 1, 18, dtype=np.float32).reshape(2, 9),
           "humans": np.linspace(-3, 3, 120, dtype=np.float32).reshape(2, 30, 2), "mask": np.ones((2, 30), np.float32)}
    np.testing.assert_array_equal(H2INTPolicy(checkpoint=str(out)).act(obs), H2INTPolicy(checkpoint=str(src)).act(obs))
    assert torch.jit.load(export_torchscript(str(out), str(tmp_path / "policy.pt"))) is not None

    code = main(["train", "h2int", "--resume", str(out), "--out", str(tmp_path / "r"), "--iterations", "5"])
    assert code == 2
    assert "a shipped weights-only checkpoint cannot resume; train from runs/…/last.pt" in capsys.readouterr().err
    from_run, from_shipped = (Trainer(tiny(), str(tmp_path / name), quiet=True) for name in ("a", "b"))
    try:
        from_run.warm_start(str(src))
        from_shipped.warm_start(str(out))
        for a, b in ((from_run.alg.actor, from_shipped.alg.actor), (from_run.alg.critic, from_shipped.alg.critic)):
            for k, v in a.state_dict().items():
                torch.testing.assert_close(b.state_dict()[k], v, rtol=0, atol=0)
        assert from_shipped.cfg.init["total_env_steps"] == from_run.cfg.init["total_env_steps"] == straight.env_steps
        assert from_shipped.cfg.init["sha256"] == checkpoints.file_sha256(out)
    finally:
        from_run.close()
        from_shipped.close()
