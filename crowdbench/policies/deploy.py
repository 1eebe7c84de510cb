"""Deployment helpers: export the trained recurrent policy (ONNX, TorchScript) and turn its planar velocity command
into bounded (v, ω) for a differential-drive base, as the paper's robot does."""

from __future__ import annotations

import math
import os

import numpy as np
import torch

from crowdbench.io import atomic_path
from crowdbench.policies.h2int import build_actor, load_checkpoint
from crowdbench.policies.h2int_net import H2INTExport


def export_module(checkpoint: str) -> H2INTExport:
    """The deterministic export module of a checkpoint (eval mode)."""
    ckpt = load_checkpoint(checkpoint)
    actor = build_actor(ckpt["model"], int(ckpt["n_max"]))
    actor.load_state_dict(ckpt["actor"])
    return H2INTExport(actor).eval()


def export_torchscript(checkpoint: str, path: str) -> str:
    """TorchScript file with ``forward(robot, humans, mask, h_in) -> (action, h_out)``."""
    scripted = torch.jit.script(export_module(checkpoint))
    with atomic_path(path, suffix=".pt") as tmp:
        scripted.save(tmp)
    return path


def export_onnx(checkpoint: str, path: str) -> str:
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


def planar_to_unicycle(velocity: np.ndarray, heading: np.ndarray, v_max: float = 1.0,
                       w_max: float = math.pi / 2, turn_gain: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Convert planar velocity commands ``(..., 2)`` [m/s, world frame] and robot headings ``(...)`` [rad] into
    bounded (v [m/s], ω [rad/s]) for a differential-drive base.

    The command is expressed in the robot frame; ω = clip(turn_gain · heading error, ±w_max) turns toward it and
    v = clip(|cmd| · max(cos(heading error), 0), 0, v_max) drives only the part of it along the current heading (a
    command behind the robot makes it turn on the spot).
    """
    velocity = np.asarray(velocity, dtype=np.float64)
    heading = np.asarray(heading, dtype=np.float64)
    speed = np.hypot(velocity[..., 0], velocity[..., 1])
    err = np.arctan2(velocity[..., 1], velocity[..., 0]) - heading
    err = (err + np.pi) % (2 * np.pi) - np.pi
    err = np.where(speed > 1e-9, err, 0.0)
    w = np.clip(turn_gain * err, -w_max, w_max)
    v = np.clip(speed * np.maximum(np.cos(err), 0.0), 0.0, v_max)
    return v, w
