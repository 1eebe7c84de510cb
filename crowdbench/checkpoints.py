"""Checkpoint files: one format for every learned method, loaded safely.

A checkpoint is a plain dict of tensors and built-in types, written atomically with ``torch.save`` and read with
``torch.load(weights_only=True)`` — a file from someone else cannot run code when loaded::

    {"format": "crowdbench.checkpoint/2", "method": "<name>", "crowdbench_version": "0.2.0",
     "model": {...architecture config...}, "n_max": 30, "actor": state_dict, ...}

Training checkpoints (a run's ``last.pt``) add the critic, optimiser, environment and RNG state needed to resume
exactly (:mod:`crowdbench.training.trainer`). Shipped checkpoints (package data, written by ``crowdbench ship``:
:mod:`crowdbench.training.ship`) hold the weights, configuration and a ``shipped`` provenance record only, and cannot
resume (:func:`require_resumable`). Files of the previous H²INT format (``crowdbench.h2int/1``, crowdbench ≤ 0.2
before the training paths were consolidated) are refused with one error: no shipped checkpoint uses it any more.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from crowdbench.registry import Registry

FORMAT = "crowdbench.checkpoint/2"
SHIPPED = Path(__file__).resolve().parent / "policies"
"""Shipped checkpoints are package data; by default ``policies/<method>/checkpoints/<name>.pt``."""
FOLDERS: Registry[Path] = Registry("checkpoint folder", "crowdbench.checkpoint_folders")
"""Where the shipped checkpoints of a name live when not in the default folder: every robot method's
(:attr:`crowdbench.policies.Method.checkpoints`, derived from the method registry) and other owners' (the trajectory
predictor's, registered by :mod:`crowdbench.predictors`)."""


def folder_of(method: str) -> Path:
    """Where the shipped checkpoints of ``method`` live."""
    return FOLDERS.get(method) if method in FOLDERS.names() else SHIPPED / method / "checkpoints"


def shipped(method: str, name: str) -> str:
    """Path of the shipped checkpoint ``name`` (e.g. a method's default, named like it) of ``method``."""
    return os.fspath(folder_of(method) / f"{name}.pt")


def shipped_names(method: str) -> list[str]:
    """The shipped checkpoints of ``method`` (names without ``.pt``)."""
    folder = folder_of(method)
    return sorted(p.stem for p in folder.glob("*.pt")) if folder.is_dir() else []


def resolve(method: str, checkpoint: str | os.PathLike | None) -> str:
    """A checkpoint path from a path, the name of a shipped checkpoint of ``method``, or ``None`` (the method's
    default shipped checkpoint, named like the method)."""
    if checkpoint is None:
        return shipped(method, method)
    path = os.fspath(checkpoint)
    if not os.path.exists(path) and path in shipped_names(method):
        return shipped(method, path)
    return path


def run_checkpoint(path: str | os.PathLike) -> str:
    """The checkpoint to resume from: ``path/last.pt`` for a run folder, else ``path`` itself."""
    path = os.fspath(path)
    return os.path.join(path, "last.pt") if os.path.isdir(path) else path


def load(path: str | os.PathLike, method: str | None = None) -> dict[str, Any]:
    """Load and validate a checkpoint (``weights_only=True``); ``method`` checks what it holds.

    Raises:
        ValueError: missing file, not a crowdbench checkpoint, a file that would need to run code to load, or a
            checkpoint of another method — one line naming the problem and what was expected.
    """
    import pickle

    import torch

    path = os.fspath(path)
    if not os.path.exists(path):
        names = ", ".join(shipped_names(method)) if method else ""
        raise ValueError(f"checkpoint {path!r} not found; pass --checkpoint PATH or one of the shipped names "
                         f"({names or 'none'})")
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as e:
        raise ValueError(f"checkpoint {path!r} refused: it holds objects that would run code when loaded "
                         f"(torch.load weights_only=True: {str(e).splitlines()[0]})") from None
    except Exception as e:  # noqa: BLE001 - a corrupt or foreign file: one clear line
        raise ValueError(f"checkpoint {path!r} could not be read ({type(e).__name__}: {e})") from None
    fmt = ckpt.get("format") if isinstance(ckpt, dict) else None
    if isinstance(fmt, str) and fmt.startswith("crowdbench.") and fmt != FORMAT:
        raise ValueError(f"checkpoint {path!r} was written by an older crowdbench (format {fmt!r}); this version "
                         f"reads only {FORMAT!r}: retrain it with `crowdbench train`")
    if fmt != FORMAT:
        raise ValueError(f"checkpoint {path!r} is not a crowdbench checkpoint (format={fmt!r}; expected {FORMAT!r})")
    if method is not None and ckpt.get("method") != method:
        raise ValueError(f"checkpoint {path!r} holds method {ckpt.get('method')!r}, not {method!r}")
    return ckpt


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 (hex) of a checkpoint file's bytes: what fingerprints and ``--init`` provenance record."""
    import hashlib

    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def training_budget(ckpt: dict[str, Any]) -> dict[str, int]:
    """What a checkpoint's training consumed: ``{"env_steps": n}`` for a PPO run — its own env steps plus, when it
    started from another run's weights (``crowdbench train --init``), that run's as recorded in its config —,
    ``{"episodes": n}`` for a value method's (CADRL, SARL) reinforcement-learning episodes; ``{}`` when the checkpoint
    records neither."""
    if "env_steps" in ckpt:
        init = (ckpt.get("train_config") or {}).get("init") or {}
        before = init.get("total_env_steps", init.get("env_steps", 0))
        return {"env_steps": int(ckpt["env_steps"]) + int(before)}
    if "episodes" in ckpt:
        return {"episodes": int(ckpt["episodes"])}
    return {}


def require_resumable(ckpt: dict[str, Any], path: str | os.PathLike, state: str = "optimizer",
                      option: str = "--resume") -> None:
    """Check that ``ckpt`` (read from ``path``) is a run's resumable state: it holds ``state`` (the optimiser of a
    PPO run, the replay ``memory`` of a value run).

    Raises:
        ValueError: a shipped weights-only checkpoint, or a file without ``state`` — one line naming ``option``.
    """
    path = os.fspath(path)
    if "shipped" in ckpt:
        raise ValueError(f"{option}: {path!r}: a shipped weights-only checkpoint cannot resume; train from "
                         "runs/…/last.pt (the run's resumable state), or start a new run from these weights")
    if state not in ckpt:
        raise ValueError(f"{option}: {path!r} holds a policy's weights but no training state ({state!r}); it cannot "
                         "be resumed: resume from the run's last.pt, or start a new run")


def save(ckpt: dict[str, Any], path: str | os.PathLike) -> str:
    """Write ``ckpt`` atomically (temporary file + rename) with ``torch.save``; returns the path."""
    import torch

    from crowdbench.io import atomic_path

    with atomic_path(path, suffix=".pt") as tmp:
        torch.save(ckpt, tmp)
    return os.fspath(path)
