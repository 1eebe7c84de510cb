"""Method descriptors: everything crowdbench needs to know about a robot method, registered once.

A *method* is a robot policy with what goes with it — how it is trained, where its shipped checkpoints live, which
leaderboard rows it contributes, the sensing tiers it runs at, the paper's numbers for it. The core (command line,
leaderboard, bench, paper report, training) iterates over :data:`METHODS` and names no method; adding one — inside
crowdbench or from another package — is one :class:`Method`::

    from crowdbench.policies import Method, BoardEntry, register_method

    register_method(Method(
        name="mine",                                   # robot-policy name and the checkpoints' ``method``
        policy="my_pkg.policy:MyPolicy",               # the RobotPolicy ("module:attribute", imported on first use)
        training="my_pkg.training:MyMethod",           # a crowdbench.training PPOMethod (trainer "ppo")
        checkpoints="/path/to/my_pkg/checkpoints",     # shipped checkpoints <name>.pt (default one: mine.pt)
        entries=(BoardEntry("mine", (("checkpoint", "mine"),)),),   # leaderboard rows
    ))

or, from a package's ``pyproject.toml``, the entry-point group ``crowdbench.methods``
(``mine = "my_pkg.method:METHOD"``, a :class:`Method`). The descriptor registers the robot policy
(:data:`~crowdbench.policies.POLICIES`) and the training binding; nothing else needs a line.

This module imports neither torch nor the methods' code: ``"module:attribute"`` strings are resolved on first use.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from crowdbench.registry import Registry

TRAINERS = ("ppo", "value")
"""How a method is trained: ``ppo`` (:mod:`crowdbench.training`'s generic PPO path; :attr:`Method.training` names a
``PPOMethod``), ``value`` (imitation then TD learning, :mod:`crowdbench.training.value`)."""
TIERS = ("positions", "velocities", "full")
"""Sensing tiers (:mod:`crowdbench.robots.observations`); ``positions`` is the board's."""
TABLES = ("I", "II", "III")
"""The paper's tables that :attr:`Method.paper` gives success rates for."""


@dataclass(frozen=True)
class BoardEntry:
    """One leaderboard row a method contributes (the method's robot policy with these arguments).

    Args:
        label: Display label, unique on the board (its file stem is the slug of it).
        kwargs: Keyword arguments of the policy, e.g. ``(("checkpoint", "flat"),)`` (a shipped name or path).
        group: ``main`` (compared in Tables I–III) or ``ablation`` (variants of the reference method).
    """

    label: str
    kwargs: tuple[tuple[str, Any], ...] = ()
    group: str = "main"

    def __post_init__(self) -> None:
        if self.group not in ("main", "ablation"):
            raise ValueError(f"BoardEntry {self.label!r}: group={self.group!r}; valid choices: main, ablation")


@dataclass(frozen=True)
class Method:
    """A robot method (module docstring). Every field but ``name`` and ``policy`` is optional.

    Args:
        name: Registry name: the robot policy's name, the ``method`` its checkpoints record, the CLI's METHOD.
        policy: The :class:`~crowdbench.policies.RobotPolicy` factory, or its ``"module:attribute"``.
        trainer: How crowdbench trains it (one of :data:`TRAINERS`); ``None``: it is not trained (a planner) or
            trained elsewhere.
        training: With ``trainer="ppo"``: the ``crowdbench.training.methods.PPOMethod`` subclass, or its
            ``"module:attribute"``.
        checkpoints: Folder of its shipped checkpoints ``<name>.pt`` (the default one named like the method, further
            training seeds ``<name>-seed<k>.pt``); ``None``: it takes no checkpoint.
        entries: Its leaderboard rows (empty: it is not on the shipped board).
        sensing: Sensing tiers its policy can run at (``sensing=`` option); the first is its own.
        paper: The paper's success rates r_s [%] per table (:data:`TABLES`), three settings each, if the paper has a
            row for it (:mod:`crowdbench.paper`).
        export: ``"module"`` with ``export_torchscript(checkpoint, path)`` and ``export_onnx(checkpoint, path)``
            (``crowdbench export``), if it can be exported.
        description: One line for listings.
    """

    name: str
    policy: Callable[..., Any] | str
    trainer: str | None = None
    training: Callable[..., Any] | str | None = None
    checkpoints: str | os.PathLike | None = None
    entries: tuple[BoardEntry, ...] = ()
    sensing: tuple[str, ...] = ("positions",)
    paper: dict[str, tuple[int, int, int]] = field(default_factory=dict)
    export: str | None = None
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or ":" in self.name or "=" in self.name:
            raise ValueError(f"Method name={self.name!r}; valid choices: a non-empty name without ':' or '='")
        if self.trainer is not None and self.trainer not in TRAINERS:
            raise ValueError(f"Method {self.name!r}: trainer={self.trainer!r}; valid choices: {', '.join(TRAINERS)}, "
                             "or None")
        if (self.trainer == "ppo") != (self.training is not None):
            raise ValueError(f"Method {self.name!r}: training={self.training!r}; valid choices: a PPOMethod (or its "
                             "'module:attribute') exactly when trainer='ppo'")
        bad = [t for t in self.sensing if t not in TIERS]
        if not self.sensing or bad:
            raise ValueError(f"Method {self.name!r}: sensing={self.sensing!r}; valid choices: tiers among "
                             f"{', '.join(TIERS)}")
        for table, rates in self.paper.items():
            if table not in TABLES or len(rates) != 3:
                raise ValueError(f"Method {self.name!r}: paper[{table!r}]={rates!r}; valid choices: tables "
                                 f"{', '.join(TABLES)}, three success rates [%] each")
        if self.checkpoints is None and any(dict(e.kwargs).get("checkpoint") for e in self.entries):
            raise ValueError(f"Method {self.name!r}: its entries name checkpoints but checkpoints=None; valid "
                             "choices: the folder of its shipped checkpoints")
        object.__setattr__(self, "sensing", tuple(self.sensing))
        if self.checkpoints is not None:
            object.__setattr__(self, "checkpoints", Path(self.checkpoints))

    @property
    def takes_checkpoint(self) -> bool:
        """Whether the policy loads a checkpoint (``checkpoint=``)."""
        return self.checkpoints is not None


METHODS: Registry[Method] = Registry("method", "crowdbench.methods")
"""Every robot method, by name (:class:`Method` objects; the entry-point group ``crowdbench.methods``)."""


def register_method(method: Method, *, overwrite: bool = False) -> Method:
    """Register ``method`` (its robot policy and training binding come with it); returns it."""
    if not isinstance(method, Method):
        raise ValueError(f"register_method: {method!r}; valid choices: a crowdbench.policies.Method")
    METHODS.register(method.name, method, overwrite=overwrite)
    return method


def methods() -> list[Method]:
    """Every registered method, built-in ones in registration order, then plug-ins by name."""
    return [METHODS.get(name) for name in ordered_names()]


def ordered_names() -> list[str]:
    """:data:`METHODS`' names, in-process registrations first in their order, then entry points by name."""
    own = list(METHODS._factories)
    return own + [n for n in METHODS.names() if n not in own]


def method_of(name: str) -> Method:
    """The method ``name``; one ``ValueError`` naming the valid choices if unknown."""
    return METHODS.get(name)


def trained_by(trainer: str) -> list[str]:
    """Names of the methods crowdbench trains with ``trainer`` (one of :data:`TRAINERS`)."""
    if trainer not in TRAINERS:
        raise ValueError(f"trainer={trainer!r}; valid choices: {', '.join(TRAINERS)}")
    return [m.name for m in methods() if m.trainer == trainer]
