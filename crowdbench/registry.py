"""A tiny name → factory registry shared by every plug-in point (layouts, pedestrian models, observations...).

Third-party packages register through a Python entry-point group, e.g. in their ``pyproject.toml``::

    [project.entry-points."crowdbench.humans"]
    theirs = "their_pkg.models:TheirModel"

after which ``crowdbench.humans.make("theirs")`` (and ``parallel_env(human_model="theirs")``) resolve it by name.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from importlib.metadata import entry_points
from typing import Any, Generic, TypeVar

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
        self._factories: dict[str, Callable[..., T] | str] = {}
        self._derived: list[tuple[Registry, Callable[[Any], Callable[..., T] | str | None]]] = []

    def derive(self, source: Registry, factory_of: Callable[[Any], Callable[..., T] | str | None]) -> None:
        """Also resolve every name of registry ``source`` whose object gives a factory through ``factory_of``
        (``None``: not one of these): a method descriptor registered once supplies its robot policy, its training
        binding, ... to the registries of those (:mod:`crowdbench.policies.method`)."""
        self._derived.append((source, factory_of))

    def _derived_factories(self) -> dict[str, Callable[..., T] | str]:
        out: dict[str, Callable[..., T] | str] = {}
        for source, factory_of in self._derived:
            for name in source.names():
                factory = factory_of(source.get(name))
                if factory is not None:
                    out.setdefault(name, factory)
        return out

    def register(self, name: str, factory: Callable[..., T] | str | None = None, *, overwrite: bool = False):
        """Register ``factory`` under ``name``; usable as ``register("x", F)`` or as a decorator ``@register("x")``.

        ``factory`` may also be a ``"package.module:attribute"`` string, imported on first use: a plug-in whose
        module pulls in heavy libraries (torch) costs nothing until it is asked for by name.
        """

        def _add(f: Callable[..., T] | str) -> Callable[..., T] | str:
            old = self._factories.get(name)
            same = old is f or (isinstance(old, str) and not isinstance(f, str)
                                and old == f"{f.__module__}:{f.__qualname__}")  # the lazy entry, now imported
            if not overwrite and old is not None and not same:
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
        return sorted(set(self._factories) | {ep.name for ep in entry_points(group=self.group)}
                      | set(self._derived_factories() if self._derived else ()))

    def get(self, name: str) -> Callable[..., T]:
        """Return the factory for ``name``; raise ``ValueError`` naming the valid choices if unknown."""
        if name not in self._factories and self._derived:
            derived = self._derived_factories().get(name)
            if derived is not None:
                self._factories[name] = derived
        if name not in self._factories and not self._load_entry_point(name):
            raise ValueError(f"unknown {self.kind} {name!r}; valid choices: {', '.join(self.names())}")
        factory = self._factories[name]
        if isinstance(factory, str):  # lazy "module:attribute"; importing it may register the object itself
            module, _, attr = factory.partition(":")
            obj = getattr(importlib.import_module(module), attr)
            self._factories[name] = factory = obj
        return factory

    def make(self, name: str, **kwargs) -> T:
        """Instantiate ``name`` with ``kwargs`` (checked against the factory's signature and annotations first: an
        unknown argument or a value of the wrong type is one ``ValueError`` naming it)."""
        from crowdbench.validate import check_call

        if not isinstance(name, str):
            raise ValueError(f"{self.kind} name {name!r}; valid choices: {', '.join(self.names())}")
        factory = self.get(name)
        check_call(factory, kwargs, f"{self.kind} {name!r}")
        return factory(**kwargs)

    def __contains__(self, name: str) -> bool:
        return name in self.names()
