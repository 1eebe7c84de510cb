"""``crowdbench ship``: a run's resumable state → the weights-only checkpoint that ships as package data.

A run keeps its resumable state outside the package (``runs/X/last.pt``: networks, optimiser, RNG, replay memory,
curriculum, per-iteration history). What ships (``<descriptor's checkpoints folder>/<name>.pt``) is what acting,
evaluating, exporting and fine-tuning (``--init``) need, and where it came from:

* the weights — the actor (observation normaliser included) and the critic of a PPO run (the critic is a few per
  cent of the file; ``--init`` starts from it), a value method's network, the predictor's, the learned crowd's;
* the architecture (``model``), the training configuration (``train_config``), the counters (``iteration``,
  ``env_steps``, ``episodes``, ``epochs``: :func:`crowdbench.checkpoints.training_budget` reads them) and the crowd
  digest, as the run wrote them;
* ``shipped``: the provenance (:func:`provenance`) — method, seed, the crowdbench versions that trained and shipped
  it, counters, crowd digest, the source file's SHA-256 and size, the final quick evaluation, a summary of the
  history, the git commit of the shipping code if any.

Dropped (:data:`TRAINING_STATE`): optimiser, learning rate, RNG states, replay memory, target network, curriculum and
episode streams, history and evaluations. A shipped file is refused by ``--resume``
(:func:`crowdbench.checkpoints.require_resumable`). Weights are copied bit for bit (same dtype), so a shipped
checkpoint acts exactly as its source.
"""

from __future__ import annotations

import os
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from crowdbench import __version__, checkpoints

TRAINING_STATE = ("optimizer", "learning_rate", "env", "torch_rng", "rng", "memory", "target", "epoch", "clock",
                  "history", "evals")
"""Keys of a resumable state that a shipped checkpoint leaves out (PPO trainer, value trainer, learned crowd)."""
COUNTERS = ("iteration", "env_steps", "episodes", "epochs", "elapsed_s")
"""Training counters recorded in the provenance when the source has them (iterations, env steps, RL episodes,
predictor epochs, wall-clock seconds)."""
PREDICTOR_FIGURES = ("ade", "fde", "const_vel_ade", "const_vel_fde")
"""A predictor checkpoint's held-out figures [m]: its final evaluation."""


@dataclass(frozen=True)
class Shipped:
    """What :func:`ship` wrote.

    Args:
        path: The shipped checkpoint.
        source: The checkpoint it was made from.
        bytes_before: Size of ``source`` [bytes].
        bytes_after: Size of ``path`` [bytes].
        dropped: Training-state keys left out (:data:`TRAINING_STATE`), in the source's order.
    """

    path: str
    source: str
    bytes_before: int
    bytes_after: int
    dropped: tuple[str, ...]

    def line(self) -> str:
        """One line for the command line: where, the size before → after, what was left out."""
        what = f"; dropped {', '.join(self.dropped)}" if self.dropped else "; nothing to drop"
        return (f"shipped {self.source} → {self.path}: {self.bytes_before:,} → {self.bytes_after:,} bytes "
                f"({self.bytes_after / max(self.bytes_before, 1):.0%}){what}")


def _register_folders() -> None:
    """Populate :data:`crowdbench.checkpoints.FOLDERS`: every robot method's descriptor folder, the predictor's and
    the learned crowd's (registered here: the pedestrian models sit below the checkpoint layer)."""
    import crowdbench.policies  # noqa: F401 - derives the robot methods' folders
    import crowdbench.predictors  # noqa: F401 - registers the predictor's folder
    from crowdbench.humans.learned import CHECKPOINT

    if "learned_crowd" not in checkpoints.FOLDERS.names():
        checkpoints.FOLDERS.register("learned_crowd", CHECKPOINT.parent)


def source_of(run: str | os.PathLike) -> str:
    """The checkpoint to ship from ``run``: a file as given; a run folder's ``last.pt``, else its only ``*.pt`` (a
    predictor's ``gst.pt``, a learned crowd's ``learned_crowd.pt``).

    Raises:
        ValueError: a folder without ``last.pt`` and not exactly one ``*.pt``.
    """
    path = os.fspath(run)
    if not os.path.isdir(path):
        return path
    if os.path.exists(os.path.join(path, "last.pt")):
        return os.path.join(path, "last.pt")
    found = sorted(p for p in os.listdir(path) if p.endswith(".pt"))
    if len(found) != 1:
        raise ValueError(f"ship: run folder {path!r} has no last.pt and {len(found)} *.pt files ({', '.join(found)});"
                         " valid choices: a run folder with last.pt, or a checkpoint file")
    return os.path.join(path, found[0])


def git_commit(where: str | os.PathLike | None = None) -> str | None:
    """The git commit (40 hex) of the work tree holding ``where`` (default: this package's code), or ``None`` outside
    git (an installed wheel) or without git."""
    folder = os.fspath(where or Path(__file__).resolve().parents[1])
    try:
        out = subprocess.run(["git", "-C", folder, "rev-parse", "HEAD"], capture_output=True, text=True, timeout=10,
                             check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    commit = out.stdout.strip()
    return commit if out.returncode == 0 and len(commit) == 40 else None


def _final(history: Any) -> dict[str, Any] | None:
    """The last row of a history: a dict of per-iteration lists (PPO, value trainer) or a list of row dicts."""
    if isinstance(history, dict):
        return {k: v[-1] for k, v in history.items() if isinstance(v, list) and v}
    if isinstance(history, list) and history and isinstance(history[-1], dict):
        return dict(history[-1])
    return None


def summary(ckpt: dict[str, Any]) -> dict[str, Any]:
    """A small summary of a resumable state's history (rows, the final row, number of quick evaluations)."""
    history, evals = ckpt.get("history"), ckpt.get("evals")
    rows = len(history.get("iteration", history.get("episode", []))) if isinstance(history, dict) else (
        len(history) if isinstance(history, list) else 0)
    return {"history_rows": rows, "final": _final(history), "evals": len(evals) if isinstance(evals, list) else 0}


def final_eval(ckpt: dict[str, Any]) -> dict[str, Any] | None:
    """The final quick-evaluation figures: the last of a run's ``evals`` (success, collision, timeout rates, ...),
    a predictor's held-out ADE / FDE [m], a learned crowd's last logged row; ``None`` if the source has none."""
    evals = ckpt.get("evals")
    if isinstance(evals, list) and evals:
        return dict(evals[-1])
    figures = {k: ckpt[k] for k in PREDICTOR_FIGURES if k in ckpt}
    if figures:
        return figures
    history = ckpt.get("history")
    return _final(history) if isinstance(history, list) else None


def provenance(ckpt: dict[str, Any], source: str, sha256: str, size: int, commit: str | None) -> dict[str, Any]:
    """The ``shipped`` record of a checkpoint made from ``ckpt`` (read from ``source``: ``size`` bytes, SHA-256
    ``sha256``), with the git ``commit`` of the shipping code."""
    return {
        "method": ckpt.get("method"), "seed": ckpt.get("seed"), "trained_with": ckpt.get("crowdbench_version"),
        "shipped_with": __version__, "crowd": ckpt.get("crowd"), "budget": checkpoints.training_budget(ckpt),
        "counters": {k: ckpt[k] for k in COUNTERS if k in ckpt}, "source": source, "source_sha256": sha256,
        "source_bytes": size, "git_commit": commit, "eval": final_eval(ckpt), "summary": summary(ckpt),
    }


def _optimiser_keys(obj: Any, where: str = "") -> list[str]:
    """Paths of optimiser states (dicts with ``param_groups``) anywhere inside ``obj``."""
    if isinstance(obj, dict):
        here = [where or "<top>"] if "param_groups" in obj else []
        return here + [p for k, v in obj.items() for p in _optimiser_keys(v, f"{where}.{k}".lstrip("."))]
    if isinstance(obj, list | tuple):
        return [p for i, v in enumerate(obj) for p in _optimiser_keys(v, f"{where}[{i}]")]
    return []


def weights_only(ckpt: dict[str, Any], source: str, sha256: str, size: int,
                 commit: str | None = None) -> tuple[dict[str, Any], tuple[str, ...]]:
    """``ckpt`` without its training state (:data:`TRAINING_STATE`) and with its ``shipped`` provenance; the keys
    dropped. A checkpoint already shipped keeps the provenance it has (shipping is idempotent).

    Raises:
        ValueError: an optimiser state left under a key not in :data:`TRAINING_STATE` (naming it).
    """
    dropped = tuple(k for k in ckpt if k in TRAINING_STATE)
    out = {k: v for k, v in ckpt.items() if k not in TRAINING_STATE}
    if "shipped" not in out:
        out["shipped"] = provenance(ckpt, source, sha256, size, commit)
    left = _optimiser_keys(out)
    if left:
        raise ValueError(f"ship: {source!r} holds an optimiser state under {', '.join(left)}; valid choices: "
                         f"checkpoints whose training state is under {', '.join(TRAINING_STATE)}")
    return out, dropped


def _check_name(name: str) -> str:
    stem = name[:-3] if name.endswith(".pt") else name
    if not stem or os.sep in stem or "/" in stem or stem.startswith(".") or stem in ("last", "policy"):
        raise ValueError(f"ship --name {name!r}; valid choices: a file name without folder, not last/policy, "
                         "e.g. METHOD or METHOD-seed1")
    return stem


def ship(run: str | os.PathLike, name: str | None = None, *, method: str | None = None,
         out: str | os.PathLike | None = None) -> Shipped:
    """Write the weights-only checkpoint of ``run`` (a run folder or a checkpoint file; :func:`source_of`).

    Args:
        run: Run folder (``last.pt`` in it) or checkpoint file; may be a shipped file itself (converted in place
            when ``out`` is the same path).
        name: Shipped name (file stem): written to ``<the method's checkpoints folder>/<name>.pt``
            (:func:`crowdbench.checkpoints.folder_of`, from the method's descriptor). Needed unless ``out`` is given.
        method: Expected method; the source must hold it (default: whatever it holds).
        out: Write here instead of the method's folder (e.g. to inspect it first).

    Returns:
        What was written, with the sizes before and after [bytes].

    Raises:
        ValueError: unreadable source, another method than ``method``, a bad ``name``, no folder for the method.
    """
    source = source_of(run)
    ckpt = checkpoints.load(source)  # weights_only=True; format checked
    held = ckpt.get("method")
    if method is not None and held != method:
        raise ValueError(f"ship --method {method!r}: {source!r} holds method {held!r}; valid choices: {held} (or "
                         "leave --method out)")
    if out is None:
        if name is None:
            raise ValueError("ship: --name is required (the shipped file's name, e.g. METHOD-seed1) unless --out "
                             "is given")
        _register_folders()
        known = checkpoints.FOLDERS.names()
        if held not in known:
            raise ValueError(f"ship: no checkpoint folder for method {held!r}; valid choices: {', '.join(known)} "
                             "(or --out PATH)")
        out = checkpoints.folder_of(held) / f"{_check_name(name)}.pt"
    size = os.path.getsize(source)
    shown = os.path.relpath(source) if not os.path.relpath(source).startswith("..") else os.path.abspath(source)
    shipped, dropped = weights_only(ckpt, shown, checkpoints.file_sha256(source), size, git_commit())
    path = checkpoints.save(shipped, out)
    checkpoints.load(path, held)  # reads back with weights_only=True
    return Shipped(os.fspath(path), source, size, os.path.getsize(path), dropped)


__all__ = ["COUNTERS", "TRAINING_STATE", "Shipped", "final_eval", "git_commit", "provenance", "ship", "source_of",
           "summary", "weights_only"]
