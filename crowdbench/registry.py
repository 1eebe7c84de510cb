"""A tiny name → factory registry shared by every plug-in point (layouts, pedestrian models, observations...).

Third-party packages register through a Python entry-point group, e.g. in their ``pyproject.toml``::

    [project.entry-points."crowdbench.humans"]
    theirs = "their_pkg.models:TheirModel"

after which ``crowdbench.humans.make("theirs")`` (and ``parallel_env(human_model="theirs")``) resolve it by name.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib.metadata import entry_points
from typing import Generic, TypeVar

T = TypeVar("T")


class Registry(Generic[T]):
    """Maps names to factories (classes or functions) returning ``T``.

    Args:
        kind: Human-readable name of what is registered ("pedestrian model", "layout", ...), used in errors.
        group: Entry-point group searched for names that are not registered in-process.

    """

    def __init__(self, kind: str, group: str) -> None:
        self.kind = kind
        self.group = group
        self._factories: dict[str, Callable[..., T]] = {}

    def register(self, name: str, factory: Callable[..., T] | None = None, *, overwrite: bool = False):
        """Register ``factory`` under ``name``; usable as ``register("x", F)`` or as a decorator ``@register("x")``."""

        def _add(f: Callable[..., T]) -> Callable[..., T]:
            if not overwrite and name in self._factories and self._factories[name] is not f:
                raise ValueError(f"{self.kind} {name!r} is already registered; pass overwrite=True to replace it")
            self._factories[name] = f
            return f

        return _add(factory) if factory is not None else _add

    def _load_entry_point(self, name: str) -> bool:
        for ep in entry_points(group=self.group):
            if ep.name == name:
                self._factories[name] = ep.load()
                return True
        return False

    def names(self) -> list[str]:
        """All registered names, including installed entry points (sorted)."""
        return sorted(set(self._factories) | {ep.name for ep in entry_points(group=self.group)})

    def get(self, name: str) -> Callable[..., T]:
        """Return the factory for ``name``; raise ``ValueError`` naming the valid choices if unknown."""
        if name not in self._factories and not self._load_entry_point(name):
            raise ValueError(f"unknown {self.kind} {name!r}; valid choices: {', '.join(self.names())}")
        return self._factories[name]

    def make(self, name: str, **kwargs) -> T:
        """Instantiate ``name`` with ``kwargs``."""
        return self.get(name)(**kwargs)

    def __contains__(self, name: str) -> bool:
        return name in self.names()
