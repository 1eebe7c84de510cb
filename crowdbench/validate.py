"""Type checks of typed configs: every field of a dataclass against its annotation, one clear error naming the field
and what it accepts — before a bad value travels into numpy and fails somewhere deep.

``check_fields(self)`` is called first thing in the ``__post_init__`` of the public configs (world, reward, ORCA,
training, suites); range checks follow in each class. Floats must be finite (NaN or ±inf in a config is a mistake:
an unlimited range is a large number), integers are integers (not bools, not floats), tuples have their length.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from typing import Any

import numpy as np


def _describe(hint: Any) -> str:
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is type(None):
        return "None"
    if origin in (typing.Union, types.UnionType):
        return " or ".join(_describe(a) for a in args)
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return f"a tuple of {_describe(args[0])}"
        return "(" + ", ".join(_describe(a) for a in args) + ")"
    if hint is float:
        return "a finite number"
    if hint is int:
        return "an integer"
    if hint is bool:
        return "True or False"
    if hint is str:
        return "a string"
    if origin is dict or hint is dict:
        return "a dict"
    return getattr(hint, "__name__", str(hint))


def matches(value: Any, hint: Any) -> bool:
    """Whether ``value`` fits the type annotation ``hint`` (Any, None, bool, int, float, str, unions, tuples,
    dicts, dataclasses; anything else is accepted)."""
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is Any:
        return True
    if hint is type(None):
        return value is None
    if origin in (typing.Union, types.UnionType):
        return any(matches(value, a) for a in args)
    if hint is bool:
        return isinstance(value, (bool, np.bool_))
    if hint is int:
        return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    if hint is float:
        ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
        return ok and math.isfinite(value)
    if hint is str:
        return isinstance(value, str)
    if origin is tuple:
        if not isinstance(value, (tuple, list)):
            return False
        if len(args) == 2 and args[1] is Ellipsis:
            return all(matches(v, args[0]) for v in value)
        return len(value) == len(args) and all(matches(v, a) for v, a in zip(value, args, strict=True))
    if origin is dict or hint is dict:
        return isinstance(value, dict)
    if dataclasses.is_dataclass(hint):
        return isinstance(value, hint)
    return True


def check_fields(obj: Any) -> None:
    """Raise ``ValueError`` for the first field of the dataclass instance ``obj`` whose value does not fit its
    annotation: ``Class.field=value; valid choices: …``."""
    hints = typing.get_type_hints(type(obj))
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if not matches(value, hints[f.name]):
            raise ValueError(f"{type(obj).__name__}.{f.name}={value!r}; valid choices: {_describe(hints[f.name])}")


def check_call(factory: Any, kwargs: dict[str, Any], owner: str) -> None:
    """Check keyword arguments against ``factory``'s signature and annotations before calling it: an unknown name
    (when it takes no ``**kwargs``) or a value that does not fit its annotation is one ``ValueError`` naming
    ``owner``, the argument and what it accepts."""
    import inspect

    target = factory.__init__ if inspect.isclass(factory) else factory
    if target is object.__init__:  # a class without its own constructor takes no arguments
        if kwargs:
            raise ValueError(f"{owner}: unknown argument {next(iter(kwargs))!r}; valid choices: none (it takes no "
                             "arguments)")
        return
    try:
        sig = inspect.signature(target)
        hints = typing.get_type_hints(target)
    except (TypeError, ValueError, NameError):  # builtins, unresolvable annotations: let the call decide
        return
    params = {n: p for n, p in sig.parameters.items() if n != "self"}
    open_ended = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    named = [n for n, p in params.items() if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD,
                                                           inspect.Parameter.KEYWORD_ONLY)]
    for name, value in kwargs.items():
        if name not in named:
            if open_ended:
                continue
            raise ValueError(f"{owner}: unknown argument {name!r}; valid choices: {', '.join(named) or 'none'}")
        if name in hints and not matches(value, hints[name]):
            raise ValueError(f"{owner}: {name}={value!r}; valid choices: {_describe(hints[name])}")
