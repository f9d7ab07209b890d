"""How config keys read to a user: one-line messages for invalid input and the help lines of the ``--set`` keys.

Functions here take the root model (:class:`moor_env.scene_schema.SceneConfig`) as an argument and read the key tree
from the pydantic models themselves: field names for "did you mean" suggestions, bounds and units for help.
"""

from __future__ import annotations

import re
import types
import typing
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ValidationError

from moor_env.errors import MISSING, ConfigError, closest, did_you_mean

BOUND_ERRORS = ("greater_than", "less_than", "greater_than_equal", "less_than_equal")


def field_kind(annotation: Any) -> tuple[str, Any] | None:
    """How a field nests: ``("model", cls)``, ``("dict", value annotation)`` for named entries,
    ``("seq", item annotation)`` for a tuple of entries, or None for a plain value."""
    if isinstance(annotation, types.UnionType) or typing.get_origin(annotation) is typing.Union:
        inner = [a for a in typing.get_args(annotation) if a is not type(None)]
        return field_kind(inner[0]) if len(inner) == 1 else None
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return ("model", annotation)
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin is dict:
        return ("dict", args[1])
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis and field_kind(args[0]) is not None:
        return ("seq", args[0])
    return None


def unknown_part(root: type[BaseModel], parts: list[Any], data: Any) -> tuple[int, list[str]] | None:
    """Follow the key path ``parts`` through the models under ``root`` (and, for named entries such as
    ``materials``, through the entries of ``data``): None if every part is known, else the index of the first
    unknown part and the names known at that place (empty where the path goes below a plain value)."""
    kind: Any = ("model", root)
    node = data
    for i, part in enumerate(parts):
        if kind is None:
            return i, []
        if kind[0] == "model":
            if part not in kind[1].model_fields:
                return i, list(kind[1].model_fields)
            kind = field_kind(kind[1].model_fields[part].annotation)
        elif kind[0] == "dict":
            names = list(node) if isinstance(node, dict) else []
            if part not in names:
                return i, names
            kind = field_kind(kind[1])
        else:
            kind = field_kind(kind[1])
        if isinstance(node, dict):
            node = node.get(part)
        elif isinstance(node, list) and isinstance(part, int) and part < len(node):
            node = node[part]
        else:
            node = None
    return None


def unknown_key_error(root: type[BaseModel], key: str, parts: list[str], value: Any, data: Any,
                      top_level_names: list[str]) -> ConfigError | None:
    """The error for a ``--set`` key whose path ``parts`` does not exist under ``root``, with the nearest known
    name; ``top_level_names`` are the extra names accepted as the first part (the shortcuts). None if it exists."""
    unknown = unknown_part(root, parts, data)
    if unknown is None:
        return None
    i, names = unknown
    if i == 0:
        return ConfigError(key, value, "a --set shortcut or a dotted path into the scene (see moor-env drop --help)",
                           did_you_mean(parts[0], [*top_level_names, *names]))
    where = ".".join(parts[:i])
    if not names:
        return ConfigError(key, value, "a dotted path into the scene", f"'{where}' is a value, not a section")
    return ConfigError(key, value, f"a key of {where}: " + ", ".join(names),
                       did_you_mean(parts[i], names, prefix=where + "."))


def validation_error(root: type[BaseModel], exc: ValidationError, data: dict[str, Any]) -> ConfigError:
    """One :class:`ConfigError` for a pydantic error: an unknown key first (with the nearest known name and the
    required keys it leaves missing), else the first error with its allowed range."""
    errors = exc.errors()
    extra = [e for e in errors if e["type"] == "extra_forbidden"]
    err = extra[0] if extra else errors[0]
    loc = ".".join(str(p) for p in err["loc"])
    value = err.get("input")
    if isinstance(value, dict):
        value = "{...}"
    if extra:
        parent = ".".join(str(p) for p in err["loc"][:-1])
        unknown = unknown_part(root, list(err["loc"]), data)
        names = unknown[1] if unknown is not None else []
        prefix = parent + "." if parent else ""
        near = closest(str(err["loc"][-1]), names)
        missing = [".".join(str(p) for p in e["loc"]) for e in errors if e["type"] == "missing"]
        hint = f"did you mean {prefix}{near}?" if near else ""
        if near and prefix + near in missing:
            missing.remove(prefix + near)
            hint = f"did you mean {prefix}{near}? it is required and missing"
        if missing:
            hint += ("; " if hint else "") + "required and missing: " + ", ".join(missing)
        return ConfigError(loc, value, "a key of " + (parent or "the scene") + ": " + ", ".join(names), hint)
    if err["type"] == "missing":
        field = field_at(root, list(err["loc"]))
        allowed = _allowed(str(err["loc"][-1]), field) if field is not None else ""
        return ConfigError(loc, MISSING, allowed or "a value", "a required key")
    if err["type"] == "literal_error" and isinstance(value, str):
        choices = re.findall(r"'([^']*)'", str((err.get("ctx") or {}).get("expected", "")))
        return ConfigError(loc, value, format_range(err), did_you_mean(value, choices))
    reason = "" if err["type"] in BOUND_ERRORS or err["type"].startswith(("float", "int", "bool")) else err["msg"]
    return ConfigError(loc or "scene", value, format_range(err), reason)


def field_at(root: type[BaseModel], loc: list[Any]) -> Any:
    """The pydantic field at the key path ``loc`` under ``root`` (through named entries and list items), or None
    where the path leaves the models."""
    kind: Any = ("model", root)
    for part in loc[:-1]:
        if kind is None:
            return None
        fields = kind[1].model_fields if kind[0] == "model" else None
        if fields is not None and part not in fields:
            return None
        kind = field_kind(fields[part].annotation if fields is not None else kind[1])
    if kind is None or kind[0] != "model":
        return None
    return kind[1].model_fields.get(loc[-1])


def _allowed(name: str, field: Any) -> str:
    """A field's allowed range with its unit, or its choices, in words ("" where it has neither)."""
    unit, bounds = _unit_and_range(name, field)
    if unit == "[choice]":
        return "one of " + bounds.replace("|", ", ")
    if bounds and unit not in ("[-]", "[integer]", "[name]"):
        return f"{bounds} {unit[1:-1]}"
    return bounds


def format_range(err: dict[str, Any]) -> str:
    """The allowed range or set of a pydantic error, in words."""
    ctx = err.get("ctx") or {}
    bounds = [f"{sym} {ctx[name]}" for name, sym in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<="))
              if name in ctx]
    if bounds:
        return " and ".join(bounds)
    if "expected" in ctx:
        return f"one of {ctx['expected']}"
    if err["type"].startswith(("float", "int", "bool")):
        return "a " + {"f": "number", "i": "whole number", "b": "boolean"}[err["type"][0]]
    if err["type"] == "missing":
        return "a value (required)"
    return err.get("msg", "a valid value")


def yaml_error_text(exc: yaml.YAMLError) -> str:
    """``line L, column C: problem`` of a YAML error, on one line."""
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    text = f"line {mark.line + 1}, column {mark.column + 1}: {problem}" if mark is not None else problem
    context, context_mark = getattr(exc, "context", None), getattr(exc, "context_mark", None)
    if context and context_mark is not None and context_mark.line != getattr(mark, "line", None):
        text += f", {context} at line {context_mark.line + 1}, column {context_mark.column + 1}"
    return text


def key_help_lines(root: type[BaseModel], shortcuts: dict[str, str]) -> list[str]:
    """One line per shortcut: its name, unit or type, allowed range or choices and the dotted path it sets."""
    rows = []
    for short, path in shortcuts.items():
        parts = path.split(".")
        kind: Any = ("model", root)
        for part in parts[:-1]:
            kind = field_kind(kind[1].model_fields[part].annotation if kind[0] == "model" else kind[1])
        field = kind[1].model_fields[parts[-1]]
        rows.append((short, *_unit_and_range(parts[-1], field), path))
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    return [f"{a:{widths[0]}s}  {b:{widths[1]}s}  {c:{widths[2]}s}  {d}".rstrip() for a, b, c, d in rows]


def _unit_and_range(name: str, field: Any) -> tuple[str, str]:
    annotation = field.annotation
    if isinstance(annotation, types.UnionType) or typing.get_origin(annotation) is typing.Union:
        annotation = next(a for a in typing.get_args(annotation) if a is not type(None))
    if typing.get_origin(annotation) is Literal:
        return "[choice]", "|".join(str(a) for a in typing.get_args(annotation))
    syms = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
    bounds = " and ".join(f"{syms[k]} {getattr(m, k):g}" for m in field.metadata for k in syms if hasattr(m, k))
    for suffix, unit in (("_m_s", "m/s"), ("_deg", "deg"), ("_m", "m"), ("_s", "s")):
        if name.endswith(suffix):
            return f"[{unit}]", bounds
    return {int: "[integer]", str: "[name]"}.get(annotation, "[-]"), bounds
