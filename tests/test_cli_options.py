"""`crowdbench train`'s options are the training configs' fields: one per field (a documented few excepted), with
the field's docstring as help, its annotation as type; what is set reaches the config, the rest keeps its default."""

from __future__ import annotations

import argparse
import dataclasses
import os
from typing import Literal

import pytest

from crowdbench.cli import main, options
from crowdbench.cli import train as train_cli
from crowdbench.training.config import TrainConfig
from crowdbench.training.value import ValueTrainConfig


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="crowdbench")
    train_cli.add_parsers(parser.add_subparsers(dest="command"))
    return parser


def _train_flags() -> set[str]:
    sub = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))
    return {s for a in sub.choices["train"]._actions for s in a.option_strings}


def test_every_config_field_has_an_option_and_every_option_a_field():
    fields = {f.name for cls in (TrainConfig, ValueTrainConfig) for f in dataclasses.fields(cls)}
    opts = {o.field: o.flag for o in train_cli.train_options()}
    assert set(opts) == fields - set(train_cli.CONFIG_EXCLUDED)
    assert set(train_cli.CONFIG_EXCLUDED) <= fields  # no stale exclusion
    flags = _train_flags()
    assert set(opts.values()) <= flags
    not_fields = {"--help", "-h", "--variant", "--model", "--seeds", "--backend", "--seed-workers", "--ray-address",
                  "--out", "--resume", "--init"}
    negated = {f"--no-{o.flag[2:]}" for o in train_cli.train_options() if o.kind is bool}
    assert flags - set(opts.values()) - negated == not_fields


def test_the_flags_of_before_the_generation_are_all_there():
    before = {"--variant", "--model", "--seed", "--seeds", "--backend", "--seed-workers", "--ray-address", "--out",
              "--resume", "--init", "--iterations", "--minutes", "--until-success", "--envs", "--threads",
              "--env-processes", "--epochs", "--mini-batches", "--reward-scale", "--learning-rate", "--schedule",
              "--anneal", "--no-anneal", "--worlds", "--il-episodes", "--rl-episodes", "--sensing", "--free-space",
              "--no-free-space"}
    assert before <= _train_flags()


def test_help_is_the_docstrings_first_sentence_and_minutes_is_the_total_budget():
    by_field = {o.field: o for o in train_cli.train_options()}
    assert by_field["epochs"].help == "PPO: PPO epochs per iteration (default 4)"
    assert by_field["il_episodes"].help == "value methods: Demonstration episodes of the ORCA robot (default 3000)"
    assert "PPO: default 0.99; value methods: default 0.9" in by_field["gamma"].help
    minutes = by_field["minutes"].help
    assert "total wall-clock budget" in minutes and "a resumed run counting its earlier minutes" in minutes
    assert options.first_sentence("Uses :data:`~a.b.NAME` and ``x``. More.") == "Uses NAME and x"
    assert options.first_sentence(":attr:`the text <a.b>` here, e.g. this") == "the text here, e.g. this"


def test_types_come_from_the_annotations():
    @dataclasses.dataclass(frozen=True)
    class Demo:
        n: int = 1
        """Count."""
        mode: Literal["a", "b"] = "a"
        """Mode."""
        on: bool = False
        """Switch."""
        span: tuple[int, int] = (1, 2)
        """Low and high."""
        notes: dict = dataclasses.field(default_factory=dict)
        """Free-form."""

    with pytest.raises(TypeError, match="'notes': no command-line option"):
        options.add_options(argparse.ArgumentParser(), options.config_options([Demo]))
    opts = options.config_options([Demo], exclude=("notes",))
    parser = argparse.ArgumentParser()
    options.add_options(parser, opts)
    args = parser.parse_args(["--n", "3", "--mode", "b", "--no-on", "--span", "4,5"])
    assert options.given(args, opts) == {"n": 3, "mode": "b", "on": False, "span": (4, 5)}
    assert options.given(parser.parse_args([]), opts) == {}
    for bad in (["--mode", "c"], ["--span", "4"], ["--span", "x,y"], ["--n", "1.5"]):
        with pytest.raises(SystemExit):
            parser.parse_args(bad)


def test_a_bad_comma_list_names_the_field_and_the_valid_choices(capsys):
    with pytest.raises(SystemExit):
        main(["train", "h2int", "--humans-range", "10"])
    assert "humans_range='10'; valid choices: 2 comma-separated int values" in capsys.readouterr().err


def test_set_fields_reach_the_config_and_unset_ones_keep_the_recipe(monkeypatch):
    import crowdbench.training.trainer as trainer_mod

    seen = []

    def fake_train(cfg, out, resume=None, init=None):
        seen.append(cfg)
        raise SystemExit(0)

    monkeypatch.setattr(trainer_mod, "train", fake_train)
    with pytest.raises(SystemExit):
        main(["train", "dsrnn", "--humans-range", "5,12", "--gamma", "0.95", "--no-anneal", "--envs", "64",
              "--out", "runs/never"])
    (cfg,) = seen
    assert (cfg.humans_range, cfg.gamma, cfg.anneal, cfg.num_envs) == ((5, 12), 0.95, False, 64)
    assert cfg.learning_rate == 4e-5 and cfg.seed == 0  # DS-RNN's recipe and the default seed


def test_value_options_reach_the_value_config(monkeypatch):
    import crowdbench.training.value as value_mod

    seen = []

    def fake_train_value(cfg, out, resume=None):
        seen.append(cfg)
        raise SystemExit(0)

    monkeypatch.setattr(value_mod, "train_value", fake_train_value)
    with pytest.raises(SystemExit):
        main(["train", "cadrl", "--rho-range", "0.1,0.5", "--free-space", "--sensing", "velocities", "--seed", "3",
              "--out", "runs/never"])
    (cfg,) = seen
    assert (cfg.rho_range, cfg.free_space, cfg.sensing, cfg.seed) == ((0.1, 0.5), True, "velocities", 3)
    assert cfg.il_episodes == 3000


def test_a_value_run_at_another_tier_gets_a_folder_of_its_own(monkeypatch):
    """Without ``--out`` a ``velocities`` run writes ``runs/sarl-velocities-seedS``, never the ``positions`` run's
    ``runs/sarl-seedS``."""
    import crowdbench.training.value as value_mod

    outs = []

    def fake_train_value(cfg, out, resume=None):
        outs.append(out)
        raise SystemExit(0)

    monkeypatch.setattr(value_mod, "train_value", fake_train_value)
    for argv in (["--sensing", "velocities", "--seed", "2"], ["--seed", "2"]):
        with pytest.raises(SystemExit):
            main(["train", "sarl", *argv])
    assert outs == [os.path.join("runs", "sarl-velocities-seed2"), os.path.join("runs", "sarl-seed2")]


def test_resumed_runs_refuse_every_non_budget_field(capsys):
    assert main(["train", "h2int", "--resume", "runs/x", "--gamma", "0.9", "--no-anneal"]) == 2
    err = capsys.readouterr().err
    assert "--no-anneal, --gamma: a resumed run keeps its configuration" in err
    assert main(["train", "sarl", "--resume", "runs/x", "--rl-episodes", "5"]) == 2
    assert "--rl-episodes: a resumed run keeps its configuration" in capsys.readouterr().err
    assert main(["train", "sarl", "--steps-per-env", "5"]) == 2
    assert "--steps-per-env: options of the PPO methods, not of sarl" in capsys.readouterr().err
