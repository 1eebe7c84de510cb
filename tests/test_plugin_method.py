"""A method from outside the package trains, evaluates and joins the leaderboard without a line of crowdbench changed.

The toy method below — a tiny recurrent network, its PPO binding, its robot policy — is registered by one
:class:`crowdbench.policies.Method`, as a plug-in package would do (in code, or through the ``crowdbench.methods``
entry point). Then everything goes through crowdbench's own entry points: ``crowdbench train`` (2 PPO iterations),
``crowdbench evaluate``, ``crowdbench leaderboard run`` on a one-cell suite, ``crowdbench leaderboard list``.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import pytest
import torch
from torch import nn

from crowdbench.cli import main
from crowdbench.policies import METHODS, POLICIES, BoardEntry, Method, register_method
from crowdbench.policies.nets import RecurrentTrunkActor, gaussian_cfg
from crowdbench.policies.recurrent import TrainedRecurrentPolicy
from crowdbench.policies.recurrent_training import RecurrentPPOMethod

NAME = "toy_plugin"


@dataclass(frozen=True)
class ToyConfig:
    """The toy architecture."""

    width: int = 8
    """Encoder output and GRU width [-]."""
    head_dims: tuple[int, ...] = (8,)
    """Hidden widths of the action and value heads [-]."""
    action_std: float = 0.5
    """Standard deviation of the Gaussian policy [m/s]."""

    def actor_kwargs(self) -> dict[str, Any]:
        return {"width": self.width, "hidden_dims": list(self.head_dims),
                "distribution_cfg": gaussian_cfg(self.action_std, learn_std=False)}


class ToyActor(RecurrentTrunkActor):
    """Robot vector and the nearest pedestrian → Linear → GRU → head."""

    obs_keys = ("robot", "humans", "mask")

    def __init__(self, obs: Mapping[str, torch.Tensor], output_dim: int, width: int = 8,
                 hidden_dims: tuple[int, ...] | list[int] = (8,), distribution_cfg: dict | None = None) -> None:
        super().__init__(obs, output_dim, width, width, hidden_dims, "tanh", distribution_cfg)
        self.slots = obs["humans"].shape[-2]
        self.encoder = nn.Linear(9 + 2, width)

    def encode_samples(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        nearest = obs["humans"][:, 0] * obs["mask"][:, :1]
        return torch.tanh(self.encoder(torch.cat([obs["robot"], nearest], -1)))


def build_toy(model: ToyConfig, n_max: int) -> ToyActor:
    obs = {"robot": torch.zeros(1, 9), "humans": torch.zeros(1, n_max, 2), "mask": torch.zeros(1, n_max)}
    return ToyActor(obs, 2, **model.actor_kwargs())


class ToyPolicy(TrainedRecurrentPolicy):
    observation = "relative"
    method = NAME
    model_config = ToyConfig
    build_actor = staticmethod(build_toy)


class ToyMethod(RecurrentPPOMethod):
    name = NAME
    model_config = ToyConfig
    actor_class = ToyActor
    policy_class = ToyPolicy
    train_defaults = {"num_envs": 4, "steps_per_env": 4, "mini_batches": 2, "epochs": 1, "humans_range": (2, 3),
                      "env_processes": 1, "threads": 1, "eval_every": 0, "anneal": False}


@pytest.fixture
def toy_method(tmp_path) -> Iterator[Method]:
    """The toy method registered with ``tmp_path/shipped`` as its checkpoint folder (unregistered afterwards)."""
    method = register_method(Method(NAME, ToyPolicy, trainer="ppo", training=ToyMethod,
                                    checkpoints=tmp_path / "shipped",
                                    entries=(BoardEntry("toy", (("checkpoint", NAME),)),)))
    yield method
    for registry in (METHODS, POLICIES):
        registry._factories.pop(NAME, None)
    from crowdbench import checkpoints
    from crowdbench.training.methods import PPO_METHODS

    for registry in (checkpoints.FOLDERS, PPO_METHODS):
        registry._factories.pop(NAME, None)


def test_a_plugin_method_trains_evaluates_and_joins_the_board(toy_method, tmp_path, capsys):
    run = tmp_path / "run"
    assert main(["train", NAME, "--iterations", "2", "--out", str(run), "--seed", "1"]) == 0
    (tmp_path / "shipped").mkdir()
    shutil.copy(run / "last.pt", tmp_path / "shipped" / f"{NAME}.pt")  # "shipping" it: the method's folder

    assert main(["evaluate", NAME, "--episodes", "2", "--worlds", "2", "--humans", "3",
                 "--json", str(tmp_path / "eval.json")]) == 0
    summary = json.loads((tmp_path / "eval.json").read_text())["summary"]
    assert summary["episodes"] == 2 and 0.0 <= summary["success_rate"] <= 1.0

    suite = tmp_path / "tiny.toml"
    suite.write_text('episodes = 2\nworlds = 2\ntables = ["I"]\nrows = ["I/Medium"]\ncounterfactual = false\n')
    board = tmp_path / "board"
    capsys.readouterr()
    assert main(["leaderboard", "run", "--suite", str(suite), "--methods", "toy", "--out", str(board)]) == 0
    cell = json.loads(next((board / "cells" / "toy").glob("*.json")).read_text())
    assert cell["fingerprint"]["policy"] == NAME and cell["fingerprint"]["checkpoint_sha256"]
    assert 0.0 <= cell["result"]["success_rate"] <= 1.0
    assert "| toy |" in (board / "LEADERBOARD.md").read_text()

    assert main(["leaderboard", "list"]) == 0
    listing = capsys.readouterr().out
    assert any(line.split()[:1] == ["toy"] and "checkpoint " in line and line.endswith(f"{NAME}.pt")
               for line in listing.splitlines())
