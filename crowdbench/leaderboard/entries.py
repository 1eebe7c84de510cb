"""Entries: the rows of the board — a label, a registered robot policy and its arguments (shipped methods, their
training seeds, or ``--add LABEL=POLICY[@CHECKPOINT]``). With the suite's grid they make the cells to run."""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass
from typing import Any

from crowdbench import checkpoints
from crowdbench.policies import POLICIES, methods
from crowdbench.worlds.digest import crowd_digest


@dataclass(frozen=True)
class Entry:
    """One leaderboard row: a display label, a registered robot policy and its keyword arguments."""

    label: str
    policy: str
    kwargs: tuple[tuple[str, Any], ...] = ()
    group: str = "main"
    """``main`` (the methods compared in Tables I–III), ``seeds:LABEL`` (other training seeds of the main entry
    ``LABEL``; plain ``seeds`` = of the reference method) or ``ablation`` (its variants)."""

    @property
    def slug(self) -> str:
        """File stem of this entry's results in the leaderboard folder."""
        return "".join(ch if ch.isalnum() or ch in "-_" else "-" for ch in self.label.lower()).strip("-")

    def policy_kwargs(self) -> dict[str, Any]:
        return dict(self.kwargs)


def method_entries() -> tuple[Entry, ...]:
    """Every registered method's leaderboard rows (:attr:`crowdbench.policies.Method.entries`), the main rows
    first, each group in registration order."""
    rows = [Entry(e.label, m.name, e.kwargs, e.group) for m in methods() for e in m.entries]
    return tuple(sorted(rows, key=lambda e: e.group != "main"))  # stable


METHODS: tuple[Entry, ...] = method_entries()
"""The leaderboard's methods (those registered when this module is imported; :func:`method_entries` for a later
registration); a learned one appears once a checkpoint trained on the current crowd ships. Rows at another sensing
tier than ``positions`` (the ``sensing`` argument) get their own section of the board."""


def trained_crowd(path: str) -> str | None:
    """The crowd digest (:func:`~crowdbench.worlds.digest.crowd_digest`) a checkpoint records it was trained on;
    None for checkpoints that do not say (trained before crowds were recorded)."""
    return _trained_crowd(path, checkpoints.file_sha256(path))


@functools.lru_cache(maxsize=256)
def _trained_crowd(path: str, sha256: str) -> str | None:
    import torch

    ckpt = torch.load(path, map_location="cpu", weights_only=True)
    return ckpt.get("crowd") if isinstance(ckpt, dict) else None


STALE: dict[str, str] = {}
"""Shipped learned entries left off the board (label → why): their checkpoint was trained on another crowd."""


def seed_names(name: str, names: list[str]) -> list[tuple[int, str]]:
    """The other training seeds of ``name`` among ``names``: ``(k, "<name>-seed<k>")`` in seed order."""
    return sorted((int(m[1]), n) for n in names if (m := re.fullmatch(rf"{re.escape(name)}-seed(\d+)", n)))


OTHER_TIERS = ("velocities", "full")
"""Sensing tiers a main entry's checkpoint may also ship at: ``<name>-<tier>`` (and its seeds
``<name>-<tier>-seed<k>``) is the row ``<label>-<tier>`` — e.g. ``sarl-velocities``, SARL trained and run with
true velocities — shown in the board's section of that tier beside the ``positions`` row."""


def shipped_entries(methods: tuple[Entry, ...] = METHODS) -> dict[str, Entry]:
    """``methods`` whose checkpoint is shipped and was trained on the current crowd (a learned method appears once
    such a checkpoint lands; the others are listed in :data:`STALE`), each main or ablation entry followed by its
    other shipped training seeds (checkpoints ``<name>-seed<k>``, group ``seeds:<label>``); a main entry's
    checkpoints at another sensing tier (:data:`OTHER_TIERS`: ``<name>-<tier>``, their seeds
    ``<name>-<tier>-seed<k>``) follow as the rows ``<label>-<tier>`` and their seeds."""
    out: dict[str, Entry] = {}
    current = crowd_digest()

    def add(e: Entry, ckpt: str | None, names: list[str]) -> None:
        if ckpt and ckpt not in names:
            return
        if ckpt and trained_crowd(checkpoints.resolve(e.policy, ckpt)) != current:
            STALE[e.label] = ("trained on crowdbench's former crowd, not on the current CrowdNav++ one; back once "
                              "retrained (`crowdbench train`)")
            return
        out[e.slug] = e
        if e.group in ("main", "ablation") and ckpt:
            for k, name in seed_names(ckpt, names):
                if trained_crowd(checkpoints.resolve(e.policy, name)) != current:
                    continue
                seed_entry = Entry(f"{e.label}-seed{k}", e.policy, (("checkpoint", name),), f"seeds:{e.label}")
                out[seed_entry.slug] = seed_entry

    for e in methods:
        ckpt = e.policy_kwargs().get("checkpoint")
        names = checkpoints.shipped_names(e.policy) if ckpt else []
        add(e, ckpt, names)
        if e.group == "main" and ckpt:
            for tier in OTHER_TIERS:
                add(Entry(f"{e.label}-{tier}", e.policy, (("checkpoint", f"{ckpt}-{tier}"),)), f"{ckpt}-{tier}",
                    names)
    return out


ENTRIES: dict[str, Entry] = shipped_entries()
"""The shipped leaderboard's rows (of the methods registered at import; :func:`board_entries` for the current)."""


def board_entries() -> dict[str, Entry]:
    """The shipped leaderboard's rows of every method registered now (plug-ins registered after this module was
    imported included)."""
    return shipped_entries(method_entries())


def parse_entry(spec: str) -> Entry:
    """``LABEL=POLICY`` or ``LABEL=POLICY@CHECKPOINT`` (a policy registered in :data:`~crowdbench.policies.POLICIES`,
    e.g. through the ``crowdbench.policies`` entry point) → :class:`Entry`."""
    if "=" not in spec:
        raise ValueError(f"--add {spec!r}: expected LABEL=POLICY or LABEL=POLICY@CHECKPOINT")
    label, rest = (s.strip() for s in spec.split("=", 1))
    policy, _, ckpt = rest.partition("@")
    if policy not in POLICIES.names():
        raise ValueError(f"--add {spec!r}: unknown policy {policy!r}; valid choices: {', '.join(POLICIES.names())}")
    return Entry(label, policy, (("checkpoint", ckpt),) if ckpt else ())

