"""H²INT: the two-stage gated Transformer policy of the paper.

* :mod:`.model` — the network (eager reference encoder, packed fast path, plain-torch actor) and
  :class:`H2INTConfig`;
* :mod:`.policy` — :class:`H2INTPolicy`, the registered robot policy ``h2int`` (a trained checkpoint);
* :mod:`.training` — how ``crowdbench train h2int`` builds it (the PPO method binding);
* :mod:`.export` — TorchScript / ONNX export of the eager reference;
* ``_kernels/`` — the packed encoder's private kernels; ``checkpoints/`` — the shipped checkpoints (package data).

Importing this package registers the method (:data:`METHOD`) and imports no torch; the classes below load on first
access.
"""

from __future__ import annotations

from importlib import import_module
from pathlib import Path
from typing import Any

from crowdbench.policies.method import BoardEntry, Method, register_method

NAME = "h2int"
METHOD = register_method(Method(
    NAME, f"{__name__}.policy:H2INTPolicy", trainer="ppo", training=f"{__name__}.training:H2INTMethod",
    checkpoints=Path(__file__).resolve().parent / "checkpoints", export=f"{__name__}.export",
    entries=(BoardEntry(NAME, (("checkpoint", NAME),)),
             *(BoardEntry(f"{NAME}-{v}", (("checkpoint", v),), "ablation") for v in ("flat", "meanpool", "standard"))),
    paper={"I": (99, 97, 94), "II": (98, 95, 88), "III": (99, 93, 91)},
    description="the paper's gated Transformer + GRU, PPO with the responsiveness curriculum"))
"""H²INT and its ablations (shipped checkpoints ``flat``, ``meanpool``, ``standard``: ablation rows)."""

_LAZY = {"VARIANTS": "model", "H2INTActor": "model", "H2INTConfig": "model", "H2INTEncoder": "model",
         "H2INTPolicy": "policy"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["METHOD", "VARIANTS", "H2INTActor", "H2INTConfig", "H2INTEncoder", "H2INTPolicy"]
