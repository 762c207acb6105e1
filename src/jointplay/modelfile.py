"""Reading model files (YAML, JSON, TOML: the same keys) into a validated Model.

Every problem becomes one ``ModelError`` that names the file, the entry
(``joints[1] 'l2': length``) and the fix; nothing here lets a traceback out.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

import yaml
from pydantic import ValidationError

from .errors import ModelError
from .joints import JOINT_TYPES
from .model import Body, EntryError, FunctionalPoint, Load, Model, suggest

#: Accepted keys per section, for "did you mean" suggestions.
_SECTION_KEYS = {
    "top": set(Model.model_fields) - {"schema_version"} | {"schema"},
    "bodies": set(Body.model_fields),
    "loads": set(Load.model_fields),
    "points": set(FunctionalPoint.model_fields),
}


class _StrictLoader(yaml.SafeLoader):
    """A YAML loader that refuses duplicate keys instead of keeping the last one."""


def _mapping(loader: _StrictLoader, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
    seen: dict[Any, Any] = {}
    for key_node, value_node in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if key in seen:
            mark = key_node.start_mark
            raise yaml.constructor.ConstructorError(
                None, None, f"duplicate key {key!r} (line {mark.line + 1})", mark
            )
        seen[key] = loader.construct_object(value_node, deep=deep)
    return seen


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping)


def load(path: str | Path) -> Model:
    """Read and validate a model file (``.yaml``/``.yml``, ``.json`` or ``.toml``)."""
    path = Path(path)
    source = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ModelError("no such file; check the path", source=source) from None
    except IsADirectoryError:
        raise ModelError("this is a folder, not a model file", source=source) from None
    except UnicodeDecodeError as exc:
        raise ModelError(f"not a text file ({exc.reason})", source=source) from None
    except OSError as exc:
        raise ModelError(f"cannot read the file ({exc.strerror})", source=source) from None
    data = parse_text(text, path.suffix.lower(), source)
    return model_from_dict(data, source=source)


def parse_text(text: str, suffix: str, source: str) -> Any:
    try:
        if suffix == ".json":
            return json.loads(text)
        if suffix == ".toml":
            return tomllib.loads(text)
        return yaml.load(text, Loader=_StrictLoader)
    except json.JSONDecodeError as exc:
        raise ModelError(
            f"not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}", source=source
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ModelError(f"not valid TOML: {exc}", source=source) from None
    except yaml.YAMLError as exc:
        where = ""
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        if mark is not None:
            where = f" at line {mark.line + 1}, column {mark.column + 1}"
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ModelError(f"not valid YAML{where}: {problem}", source=source) from None
    except RecursionError:
        raise ModelError("the file is nested too deeply to be a model", source=source) from None


def model_from_dict(data: Any, *, source: str = "<model>") -> Model:
    """Validate a plain dict (as read from a model file) into a ``Model``."""
    if not isinstance(data, dict):
        kind = "empty" if data is None else f"a {type(data).__name__}"
        raise ModelError(
            f"expected a mapping with 'bodies', 'joints' and 'loads', but the file is {kind}",
            source=source,
        )
    try:
        return Model.model_validate(data)
    except ValidationError as exc:
        raise _to_model_error(exc, data, source) from None
    except RecursionError:
        raise ModelError("the model is nested too deeply", source=source) from None


def _to_model_error(exc: ValidationError, data: dict[str, Any], source: str) -> ModelError:
    errors = exc.errors(include_url=False)
    # Report the first problem only: one clear paragraph beats a wall of text.
    err = errors[0]
    original = (err.get("ctx") or {}).get("error")
    if isinstance(original, EntryError):
        problem = original.problem
        if not problem.endswith((".", "?")):
            problem += "."
        return ModelError(problem, source=source, entry=original.entry)
    loc = list(err["loc"])
    entry, field_path = _entry(loc, data)
    problem = _problem(err, loc, data)
    more = f" ({len(errors) - 1} more problem(s) after this one)" if len(errors) > 1 else ""
    where = ": ".join(p for p in (entry, field_path) if p)
    return ModelError(problem + more, source=source, entry=where or None)


def _entry(loc: list[Any], data: dict[str, Any]) -> tuple[str, str]:
    """Split a pydantic location into ('joints[1] 'l2'', 'clearance')."""
    if len(loc) >= 3 and loc[0] == "load_cases" and isinstance(loc[2], int):
        return f"load_cases.{loc[1]}[{loc[2]}]", _join_loc(loc[3:])
    sections = ("bodies", "joints", "loads", "points")
    if len(loc) >= 2 and loc[0] in sections and isinstance(loc[1], int):
        section, index = loc[0], loc[1]
        rest = loc[2:]
        if section == "joints" and rest and isinstance(rest[0], str) and rest[0] in JOINT_TYPES:
            rest = rest[1:]  # the discriminator tag pydantic inserts
        name = ""
        items = data.get(section)
        if isinstance(items, list) and index < len(items) and isinstance(items[index], dict):
            item_name = items[index].get("name")
            if isinstance(item_name, str):
                name = f" '{item_name}'"
        return f"{section}[{index}]{name}", _join_loc(rest)
    return "", _join_loc(loc)


def _join_loc(parts: list[Any]) -> str:
    """``['a', 0, 'b']`` -> ``a[0].b``."""
    out = ""
    for part in parts:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _problem(err: Any, loc: list[Any], data: dict[str, Any]) -> str:
    kind = err["type"]
    ctx = err.get("ctx") or {}
    if kind == "extra_forbidden":
        key = str(loc[-1])
        allowed = _allowed_keys(loc, data)
        hint = suggest(key, allowed) if allowed else ""
        listing = f" Allowed keys here: {', '.join(sorted(allowed))}." if allowed else ""
        return f"unknown key '{key}'.{hint}{listing}"
    if kind == "missing":
        return f"the key '{loc[-1]}' is required here; add it"
    if kind == "union_tag_invalid":
        tag = str(ctx.get("tag"))
        return (
            f"unknown joint type '{tag}'.{suggest(tag, JOINT_TYPES)} "
            f"Known types: {', '.join(sorted(JOINT_TYPES))}"
        )
    if kind == "union_tag_not_found":
        return f"the joint needs a 'type'; one of: {', '.join(sorted(JOINT_TYPES))}"
    if kind == "literal_error" and loc == ["schema"]:
        return (
            f"this is schema version 1; got {err.get('input')!r}. Write 'schema: 1' or leave it out"
        )
    if kind in ("too_short",) and loc and loc[0] in ("bodies", "joints"):
        return f"expected at least one entry in '{loc[0]}'"
    if kind in ("tuple_type", "list_type") and loc and loc[0] in ("bodies", "joints", "loads"):
        return f"expected a list of entries, got {type(err.get('input')).__name__}"
    if kind == "model_type" or kind == "model_attributes_type":
        return f"expected a mapping of keys (name: ..., ...), got {err.get('input')!r}"
    if kind == "dict_type":
        return f"expected a mapping (NAME: [...], ...), got {type(err.get('input')).__name__}"
    if kind == "string_type":
        return f"expected a text name, got {err.get('input')!r}"
    if kind == "bool_type":
        return f"expected true or false, got {err.get('input')!r}"
    message = str(err["msg"])
    return message.removeprefix("Value error, ").removeprefix("Assertion failed, ")


def _allowed_keys(loc: list[Any], data: dict[str, Any]) -> set[str]:
    if len(loc) == 1:
        return _SECTION_KEYS["top"]
    section = loc[0]
    if section == "joints" and len(loc) >= 3:
        tag = loc[2] if isinstance(loc[2], str) and loc[2] in JOINT_TYPES else None
        if tag is not None:
            return set(JOINT_TYPES[tag].model_fields)
    if section in _SECTION_KEYS and len(loc) == 3:
        return _SECTION_KEYS[section]
    if section == "load_cases" and len(loc) == 4:
        return _SECTION_KEYS["loads"]
    return set()
