"""What the wheel ships: weights-only checkpoints (no resumable state), every data file covered by ``pyproject.toml``'s
package-data, and a package small enough for a wheel of at most 12 MB."""

from __future__ import annotations

import fnmatch
import tomllib
from pathlib import Path

import pytest
import torch

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "crowdbench"
CHECKPOINT_FILES = sorted(p for p in PACKAGE.glob("**/checkpoints/**/*")
                          if p.is_file() and "__pycache__" not in p.parts)
MAX_CHECKPOINT_BYTES = 1_000_000
"""A shipped checkpoint's size limit [bytes]: the largest weights-only file (AIG-GST) is 0.77 MB; a resumable state
of the same run (optimiser, history) is 2.4 MB."""
MAX_PACKAGE_BYTES = 12_000_000
"""The wheel's budget [bytes] (issue 43), checked on the uncompressed package files it is made of."""
RESUMABLE_STATE = ("optimizer", "memory", "target", "torch_rng", "rng", "env", "evals", "learning_rate")
"""Keys only a run's resumable state has (:data:`crowdbench.training.ship.TRAINING_STATE`, less ``history``: the
learned crowd's file keeps its 60-row log)."""
NOT_RESHIPPED = {"crowdbench/humans/checkpoints/learned_crowd.pt":
                 "its bytes' SHA-256 is part of the shift suite's digest (stored Table V cells); it holds no training "
                 "state"}
"""Shipped checkpoints without a ``shipped`` provenance record, and why."""


def _optimiser_paths(obj, where=""):
    if isinstance(obj, dict):
        return ([where or "<top>"] if "param_groups" in obj else []) + [
            p for k, v in obj.items() for p in _optimiser_paths(v, f"{where}.{k}")]
    if isinstance(obj, list | tuple):
        return [p for i, v in enumerate(obj) for p in _optimiser_paths(v, f"{where}[{i}]")]
    return []


def test_there_are_checkpoints_to_check():
    assert len([p for p in CHECKPOINT_FILES if p.suffix == ".pt"]) >= 20


@pytest.mark.parametrize("path", CHECKPOINT_FILES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_a_shipped_checkpoint_is_weights_only_and_small(path):
    rel = str(path.relative_to(ROOT))
    assert path.stat().st_size <= MAX_CHECKPOINT_BYTES, f"{rel}: {path.stat().st_size:,} bytes"
    ckpt = torch.load(path, map_location="cpu", weights_only=True)
    assert isinstance(ckpt, dict) and ckpt.get("format") == "crowdbench.checkpoint/2", rel
    assert not set(ckpt) & set(RESUMABLE_STATE), f"{rel} holds a training state: {set(ckpt) & set(RESUMABLE_STATE)}"
    assert not _optimiser_paths(ckpt), f"{rel} holds an optimiser state at {_optimiser_paths(ckpt)}"
    if rel in NOT_RESHIPPED:
        return
    prov = ckpt.get("shipped")
    assert isinstance(prov, dict), f"{rel} was not written by `crowdbench ship`"
    assert prov["method"] == ckpt["method"] and len(prov["source_sha256"]) == 64 and prov["budget"] | prov["counters"]


def _package_data() -> dict[str, list[str]]:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]


def _matches(rel: str, pattern: str) -> bool:
    """setuptools' glob: ``*`` within one path segment."""
    a, b = rel.split("/"), pattern.split("/")
    return len(a) == len(b) and all(fnmatch.fnmatchcase(x, y) for x, y in zip(a, b, strict=True))


def _owner(path: Path) -> Path:
    """The package (folder with ``__init__.py``) a data file belongs to."""
    folder = path.parent
    while not (folder / "__init__.py").exists():
        folder = folder.parent
    return folder


def _shipped_files() -> list[Path]:
    """The files a wheel holds: modules and the package data ``pyproject.toml`` names."""
    data = _package_data()
    out = []
    for path in PACKAGE.rglob("*"):
        if not path.is_file() or "__pycache__" in path.parts:
            continue
        owner = _owner(path)
        name = ".".join(owner.relative_to(ROOT).parts)
        rel = path.relative_to(owner).as_posix()
        if path.suffix == ".py" or any(_matches(rel, p) for p in data.get(name, [])):
            out.append(path)
    return out


def test_package_data_covers_every_checkpoint_and_data_file():
    shipped = set(_shipped_files())
    missing = [str(p.relative_to(ROOT)) for p in PACKAGE.rglob("*")
               if p.is_file() and "__pycache__" not in p.parts and p not in shipped]
    assert not missing, f"not in pyproject.toml's package-data: {missing}"


def test_the_package_fits_a_wheel_of_12_mb():
    total = sum(p.stat().st_size for p in _shipped_files())
    assert total <= MAX_PACKAGE_BYTES, f"{total:,} bytes of package files"
