"""H²INT as a crowdbench robot policy: loads a checkpoint written by ``crowdbench train h2int``.

Checkpoints are plain dicts of tensors and built-in types, loadable with ``torch.load(weights_only=True)``:
``{"format": "crowdbench.h2int/1", "model": {...architecture...}, "actor": state_dict, ...}``.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import torch
from tensordict import TensorDict

from crowdbench.config import WorldConfig
from crowdbench.policies.base import RobotPolicy, register
from crowdbench.policies.h2int_net import H2INTActor, H2INTExport, script

FORMAT = "crowdbench.h2int/1"
SCRIPT_BELOW = 64
"""Batches smaller than this run through TorchScript (per-call overhead), larger ones through the eager encoder."""
DEFAULT_CHECKPOINT = os.path.normpath(os.path.join(os.path.dirname(__file__), "..", "..", "leaderboards", "checkpoints",
                                                  "h2int.pt"))
"""The shipped checkpoint (present in a source checkout / editable install)."""


def build_actor(model_cfg: dict[str, Any], n_max: int) -> H2INTActor:
    """An untrained actor with the architecture described by ``model_cfg`` (as stored in checkpoints)."""
    obs = TensorDict({"robot": torch.zeros(1, 9), "humans": torch.zeros(1, n_max, 2), "mask": torch.zeros(1, n_max)},
                     batch_size=[1])
    groups = {"actor": ["robot"], "critic": ["robot"]}
    cfg = dict(model_cfg)
    return H2INTActor(obs, groups, "actor", 2, **cfg)


def load_checkpoint(path: str | os.PathLike) -> dict[str, Any]:
    """Load and validate a crowdbench H²INT checkpoint (``weights_only=True``: safe for files from others)."""
    if not os.path.exists(path):
        raise ValueError(f"checkpoint {os.fspath(path)!r} not found; train one with `crowdbench train h2int` or pass "
                         "--checkpoint PATH (the shipped one lives in leaderboards/checkpoints/ of a source checkout)")
    ckpt = torch.load(os.fspath(path), map_location="cpu", weights_only=True)
    if not isinstance(ckpt, dict) or ckpt.get("format") != FORMAT:
        raise ValueError(f"checkpoint {os.fspath(path)!r} is not a {FORMAT} file (format={ckpt.get('format')!r})")
    return ckpt


@register("h2int")
class H2INTPolicy(RobotPolicy):
    """The trained H²INT policy (deterministic: the Gaussian's mean). Keeps one GRU state per world.

    Args:
        config: World configuration (``max_humans_observed`` must equal the checkpoint's N_max).
        checkpoint: Path of a checkpoint; default: the shipped ``leaderboards/checkpoints/h2int.pt``.
        actor: Alternatively, a live :class:`H2INTActor` (used for evaluation during training).
    """

    observation = "relative"

    def __init__(self, config: WorldConfig | None = None, checkpoint: str | None = None,
                 actor: H2INTActor | None = None) -> None:
        super().__init__(config)
        if actor is None:
            ckpt = load_checkpoint(checkpoint or DEFAULT_CHECKPOINT)
            actor = build_actor(ckpt["model"], int(ckpt["n_max"]))
            actor.load_state_dict(ckpt["actor"])
            self.meta = {k: ckpt.get(k) for k in ("variant", "iteration", "env_steps", "seed")}
        n_max = actor.encoder.pos_emb.num_embeddings - 1
        if n_max != self.config.max_humans_observed:
            raise ValueError(f"max_humans_observed={self.config.max_humans_observed} but the checkpoint was trained "
                             f"with N_max={n_max}")
        self.actor = actor.eval()
        self.hidden: torch.Tensor | None = None
        self._script: torch.jit.ScriptModule | None = None

    def _scripted(self) -> torch.jit.ScriptModule:
        """The frozen TorchScript module used for small batches (one robot: ~3× less per-call overhead than eager
        PyTorch; same outputs to 1e-5). Batches of 64+ worlds use the eager, bucketed encoder."""
        if self._script is None:
            self._script = script(H2INTExport(self.actor, trim=True).eval(), freeze=True)
        return self._script

    @torch.inference_mode()
    def reset(self, done: np.ndarray | None = None) -> None:
        if done is None or self.hidden is None:
            self.hidden = None
        else:
            self.hidden[:, torch.from_numpy(np.asarray(done, dtype=bool))] = 0.0

    @torch.inference_mode()
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        robot = torch.as_tensor(obs["robot"], dtype=torch.float32)
        edges = torch.as_tensor(obs["humans"], dtype=torch.float32)
        mask = torch.as_tensor(obs["mask"], dtype=torch.float32)
        if self.hidden is None or self.hidden.shape[1] != len(robot):
            self.hidden = torch.zeros(1, len(robot), self.actor.rnn.rnn.hidden_size)
        if len(robot) < SCRIPT_BELOW:
            mean, self.hidden = self._scripted()(robot, edges, mask, self.hidden)
            return mean.numpy().astype(np.float64)
        z = self.actor.bucketed(robot, edges, mask > 0.5)
        out, self.hidden = self.actor.rnn.rnn(z.unsqueeze(0), self.hidden)
        mean = self.actor.mlp(out.squeeze(0))
        return mean.numpy().astype(np.float64)
