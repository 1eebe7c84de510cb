"""Command-line options built from configuration dataclasses: one option per field, so a field's type and its
attribute docstring are the option's single source of truth.

* the flag: ``--field-name`` (or a documented override), for a field of any of the given dataclasses;
* the help: the first sentence of the field's docstring, then its default (per dataclass where they differ);
* the type: from the annotation — ``int``, ``float``, ``str``, ``Literal[...]`` (choices), ``bool``
  (``--x/--no-x``), ``tuple[T, ...]`` (a comma list, e.g. ``10,30``);
* every option defaults to ``None``: :func:`given` returns the fields set on the command line only, so a
  dataclass's own default (or a method's recipe) applies to the rest.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import inspect
import re
import textwrap
import typing
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class FieldOption:
    """A command-line option for a dataclass field (of one or more of the dataclasses it was built from)."""

    field: str
    """The field's name (the ``argparse`` destination)."""
    flag: str
    """The option, e.g. ``--mini-batches``."""
    kind: Any
    """The field's annotation (resolved)."""
    help: str
    owners: tuple[type, ...]
    """The dataclasses that have this field."""

    def shown(self, value: Any = None) -> str:
        """The flag as given (``--no-x`` for a false boolean); with no value, both forms of a boolean."""
        if self.kind is bool:
            stem = self.flag[2:]
            return f"--{stem}/--no-{stem}" if value is None else (self.flag if value else f"--no-{stem}")
        return self.flag


def field_docs(cls: type) -> dict[str, str]:
    """The attribute docstrings of a dataclass (the string literal right after each field), by field name."""
    tree = ast.parse(textwrap.dedent(inspect.getsource(cls)))
    body = tree.body[0].body  # type: ignore[attr-defined]
    docs = {}
    for node, after in zip(body, body[1:], strict=False):
        if (isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name) and isinstance(after, ast.Expr)
                and isinstance(after.value, ast.Constant) and isinstance(after.value.value, str)):
            docs[node.target.id] = after.value.value
    return docs


def first_sentence(doc: str) -> str:
    """The first sentence of a docstring as plain text (reST roles and literals unwrapped)."""
    text = " ".join(doc.split())
    text = re.sub(r":\w+:`([^`<]*?)\s*<[^`]*>`", r"\1", text)  # :attr:`text <target>` → text
    text = re.sub(r":\w+:`(~?)([^`]*)`", lambda m: m.group(2).rsplit(".", 1)[-1] if m.group(1) else m.group(2), text)
    text = text.replace("``", "")
    parts = re.split(r"(?<=[.!?])\s+(?=[A-Z(])", text, maxsplit=1)
    return parts[0].rstrip(".")


def _tuple_parser(field: str, item: type, size: int | None) -> Callable[[str], tuple]:
    def parse(text: str) -> tuple:
        try:
            values = tuple(item(s.strip()) for s in text.split(",") if s.strip())
        except ValueError:
            values = ()
        if not values or (size is not None and len(values) != size):
            what = f"{size} " if size else ""
            raise argparse.ArgumentTypeError(f"{field}={text!r}; valid choices: {what}comma-separated "
                                             f"{item.__name__} values, e.g. {','.join(['1'] * (size or 2))}")
        return values
    return parse


def _shape(field: str, kind: Any) -> dict[str, Any]:
    """``add_argument`` keywords for a field's annotation; a TypeError for annotations no option can carry."""
    origin, args = typing.get_origin(kind), typing.get_args(kind)
    if kind is bool:
        return {"action": argparse.BooleanOptionalAction}
    if kind in (int, float, str):
        return {"type": kind, "metavar": {int: "N", float: "X", str: "TEXT"}[kind]}
    if origin is typing.Literal:
        return {"type": type(args[0]), "choices": args}
    if origin is tuple and args and all(a in (int, float, str) for a in args if a is not Ellipsis):
        size = None if Ellipsis in args else len(args)
        return {"type": _tuple_parser(field, args[0], size), "metavar": ",".join(["V"] * (size or 2))
                + ("" if size else ",...")}
    raise TypeError(f"field {field!r}: no command-line option for annotation {kind!r}; exclude the field")


def config_options(configs: Sequence[type], exclude: Sequence[str] = (), flags: dict[str, str] | None = None,
                   labels: dict[type, str] | None = None) -> list[FieldOption]:
    """One option per field of ``configs`` (first dataclass first, in field order) but those in ``exclude``;
    ``flags`` renames options (field → flag without ``--``). A field in several dataclasses is one option; its help
    is the first dataclass's docstring, prefixed with the owner's label (``labels``) when only one of several
    dataclasses has it, and its default is given per owner where they differ."""
    out: dict[str, FieldOption] = {}
    labels = labels or {}
    fields = {cls: {f.name: f for f in dataclasses.fields(cls)} for cls in configs}
    for cls in configs:
        hints, docs = typing.get_type_hints(cls, include_extras=False), field_docs(cls)
        for name in fields[cls]:
            if name in exclude or name in out:
                continue
            owners = tuple(c for c in configs if name in fields[c])
            kind = hints[name]
            for other in owners[1:]:
                if typing.get_type_hints(other)[name] != kind:
                    raise TypeError(f"field {name!r}: {cls.__name__} and {other.__name__} annotate it differently")
            if name not in docs:
                raise TypeError(f"field {cls.__name__}.{name} has no docstring (an option's help text)")
            defaults = {c: fields[c][name].default for c in owners}
            if len(set(map(repr, defaults.values()))) == 1:
                default = f"default {_show(defaults[cls])}"
            else:
                default = "; ".join(f"{labels.get(c, c.__name__)}: default {_show(v)}" for c, v in defaults.items())
            prefix = f"{labels[cls]}: " if len(owners) < len(configs) and cls in labels else ""
            text = f"{prefix}{first_sentence(docs[name])} ({default})".replace("%", "%%")
            flag = "--" + (flags or {}).get(name, name.replace("_", "-"))
            out[name] = FieldOption(name, flag, kind, text, owners)
    return list(out.values())


def _show(value: Any) -> str:
    if isinstance(value, tuple):
        return ",".join(map(str, value))
    return "none" if value is dataclasses.MISSING else str(value)


def add_options(parser: argparse.ArgumentParser | argparse._ArgumentGroup, options: Sequence[FieldOption]) -> None:
    """Add ``options`` to ``parser`` (every default ``None``: :func:`given` tells what was set)."""
    for opt in options:
        parser.add_argument(opt.flag, dest=opt.field, default=None, help=opt.help, **_shape(opt.field, opt.kind))


def given(args: argparse.Namespace, options: Sequence[FieldOption]) -> dict[str, Any]:
    """The fields set on the command line (option → value), in option order."""
    return {o.field: getattr(args, o.field) for o in options if getattr(args, o.field, None) is not None}
