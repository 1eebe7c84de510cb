"""Export a trained H²INT checkpoint as a deterministic recurrent policy (TorchScript, ONNX).

The exported module is the eager reference encoder (:meth:`H2INTEncoder.forward
<crowdbench.policies.h2int.model.H2INTEncoder.forward>`), the GRU and the action head: ``(robot (B, 9), humans
(B, N, 2), mask (B, N), h_in (1, B, H)) → (action (B, 2), h_out (1, B, H))``.
"""

from __future__ import annotations

import copy
import os
import warnings

import torch
import torch.nn as nn

from crowdbench.io import atomic_path
from crowdbench.policies.h2int.model import H2INTActor
from crowdbench.policies.h2int.policy import load_actor


class H2INTExport(nn.Module):
    """Deterministic recurrent policy (a copy of the actor's encoder, GRU and head)."""

    input_names = ["robot", "humans", "mask", "h_in"]
    output_names = ["action", "h_out"]

    def __init__(self, actor: H2INTActor) -> None:
        super().__init__()
        self.encoder = copy.deepcopy(actor.encoder)
        self.gru = copy.deepcopy(actor.rnn.rnn)
        self.mlp = copy.deepcopy(actor.mlp)
        self.hidden_size = self.gru.hidden_size
        self.n_max = int(actor.encoder.pos_emb.num_embeddings - 1)

    def forward(self, robot: torch.Tensor, humans: torch.Tensor, mask: torch.Tensor, h_in: torch.Tensor):
        z = self.encoder(robot, humans, mask > 0.5)
        out, h_out = self.gru(z.unsqueeze(0), h_in)
        return self.mlp(out.squeeze(0)), h_out

    def get_dummy_inputs(self, batch: int = 2) -> tuple[torch.Tensor, ...]:
        """Example inputs (batch 2: torch.export would specialise a batch of 1 into a constant)."""
        return (torch.zeros(batch, 9), torch.zeros(batch, self.n_max, 2), torch.ones(batch, self.n_max),
                torch.zeros(1, batch, self.hidden_size))


def export_module(checkpoint: str | None) -> H2INTExport:
    """The deterministic export module of a checkpoint (path or shipped name; eval mode)."""
    return H2INTExport(load_actor(checkpoint)[0]).eval()


def export_torchscript(checkpoint: str | None, path: str) -> str:
    """TorchScript file with ``forward(robot, humans, mask, h_in) -> (action, h_out)``."""
    with warnings.catch_warnings():  # TorchScript is deprecated in torch 2.13 but still what many deployments load
        warnings.simplefilter("ignore", DeprecationWarning)
        scripted = torch.jit.script(export_module(checkpoint))
    with atomic_path(path, suffix=".pt") as tmp:
        scripted.save(tmp)
    return path


def export_onnx(checkpoint: str | None, path: str) -> str:
    """ONNX file (opset 18) with inputs ``robot, humans, mask, h_in`` and outputs ``action, h_out`` (dynamic batch).

    torch's exporter may write the weights beside it as ``<path>.data``; ship both files.
    """
    module = export_module(checkpoint)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    batch = torch.export.Dim("batch", min=1, max=4096)
    torch.onnx.export(module, module.get_dummy_inputs(), path, input_names=module.input_names,
                      output_names=module.output_names, opset_version=18,
                      dynamic_shapes={"robot": {0: batch}, "humans": {0: batch}, "mask": {0: batch},
                                      "h_in": {1: batch}})
    return path
