"""Reading model files (YAML, JSON, TOML: the same keys) into a validated Model.

Every problem becomes one ``ModelError`` that names the file, the entry
(``joints[1] 'l2': length``) and the fix; nothing here lets a traceback out.
Hostile files are bounded before they are read in full: see ``MAX_FILE_BYTES``,
``MAX_NODES`` and ``MAX_DEPTH``.
"""

from __future__ import annotations

import codecs
import gc
import json
import os
import re
import tomllib
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any, cast, get_args

import yaml
from pydantic import BaseModel, ConfigDict, TypeAdapter, ValidationError

from jointplay.errors import ModelError
from jointplay.model.deviations import (
    Kind,
    MeasuredDeviation,
    SharedDeviation,
    mean_components,
    outside,
)
from jointplay.model.fields import Name, _vector
from jointplay.model.joints import JOINT_TYPES, Joint
from jointplay.model.mechanism import (
    Body,
    EntryError,
    EntryProblemsError,
    FunctionalPoint,
    Load,
    Model,
    Requirement,
    suggest,
    unknown_body,
    unknown_deviation_body,
    unknown_point,
    unknown_shared_deviation,
)
from jointplay.units import UnderflowError, read_number, shown

#: The largest model the solver is built and tested for: a string of 10,000
#: bodies, certified in seconds (tests/test_large.py, benchmarks/bench_scaling.py).
#: The reader's limits below follow from it, so that every model the solver
#: takes can be read, and a file far larger than any model is refused.
LARGEST_MODEL_BODIES = 10_000
#: Largest model file read, in bytes: 5 kB per body of the largest model
#: (50 MB). The 10,000-body string is 3.6 MB as YAML and 6.5 MB as indented
#: JSON, 11 MB in closed loops (three joints a body); the rest is room for
#: comments, outlines and load cases. A larger file is refused before it is read.
MAX_FILE_BYTES = 5_000 * LARGEST_MODEL_BODIES
#: Bytes read first, and checked for what is not text (NUL bytes, not UTF-8),
#: so that a binary file is refused at once; the rest is checked as it is
#: decoded, once.
HEAD_BYTES = 65_536
#: Most YAML values (numbers, texts, lists, mappings) in a file, counted as
#: they are parsed and again with aliases expanded: 150 per body of the
#: largest model (1.5 million). The 10,000-body string in closed loops (three
#: joints a body) holds 830,000; the YAML reader takes about 2.5 s a million,
#: and that is how long a file of values past the limit takes to be refused.
#: Aliases (*name) reuse a value without copying it, so a few lines of nested
#: aliases (a "billion laughs" file) can stand for billions of values, which
#: validation would then walk one by one.
MAX_NODES = 150 * LARGEST_MODEL_BODIES
#: Deepest nesting of lists and mappings. A model needs 4 (file, section,
#: entry, vector); the limit stays far below Python's recursion limit.
MAX_DEPTH = 64
#: Most entries in a section (each of SECTIONS, the load cases, the loads of
#: one case): 10 per body of the largest model (100,000; a mechanism of
#: 10,000 bodies in closed loops has 30,000 joints). Checked
#: before validation, which walks each entry: a wrong entry may repeat a
#: hundred thousand times in a generated model before the first one is reported.
MAX_ENTRIES = 10 * LARGEST_MODEL_BODIES

#: The sections that are lists of entries.
SECTIONS = ("bodies", "joints", "loads", "points", "requirements", "deviations")

#: Accepted keys per section, for "did you mean" suggestions.
_SECTION_KEYS = {
    "top": set(Model.model_fields) - {"schema_version"} | {"schema"},
    "bodies": set(Body.model_fields),
    "loads": set(Load.model_fields),
    "points": set(FunctionalPoint.model_fields),
    "requirements": set(Requirement.model_fields),
}

#: libyaml's parser when PyYAML has it (five times faster), else PyYAML's own.
_YamlBase: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class _TooManyNodesError(yaml.YAMLError):
    pass


class _StrictLoader(_YamlBase):  # type: ignore[misc]
    """A YAML loader that refuses duplicate keys instead of keeping the last one,
    and stops after MAX_NODES values."""

    def __init__(self, stream: str):
        super().__init__(stream)
        self.nodes = 0
        #: The tag of each plain text met: a model repeats its keys and numbers,
        #: and PyYAML's resolver tries its patterns on each (a fifth of the parse).
        self.tags: dict[str, str] = {}

    def resolve(self, kind: Any, value: Any, implicit: Any) -> Any:
        # called once per value as the file is parsed, also by libyaml's parser
        self.nodes += 1
        if self.nodes > MAX_NODES:
            raise _TooManyNodesError
        if kind is yaml.ScalarNode and implicit[0]:  # plain: its tag follows from its text
            tag = self.tags.get(value)
            if tag is None:
                tag = self.tags[value] = super().resolve(kind, value, implicit)
            return tag
        return super().resolve(kind, value, implicit)


_MERGE_TAG = "tag:yaml.org,2002:merge"


def _mapping(loader: Any, node: yaml.MappingNode, deep: bool = False) -> dict[Any, Any]:
    return _mapping_of(loader, node, lambda child: loader.construct_object(child, deep=deep))


def _mapping_of(
    loader: Any, node: yaml.MappingNode, construct: Callable[[yaml.Node], Any]
) -> dict[Any, Any]:
    """A mapping's value, its keys names given once; ``construct`` builds a key or a value."""
    # merge keys ('<<: *defaults') give defaults that the mapping's own keys override
    own = sum(1 for key_node, _ in node.value if key_node.tag != _MERGE_TAG)
    loader.flatten_mapping(node)
    merged = len(node.value) - own
    out: dict[Any, Any] = {}
    seen: set[Any] = set()
    for index, (key_node, value_node) in enumerate(node.value):
        key = construct(key_node)
        try:
            hash(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                None,
                None,
                "a list or a mapping cannot be a key; keys are names",
                key_node.start_mark,
            ) from None
        if index >= merged:
            if key in seen:
                mark = key_node.start_mark
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {shown(key)} (line {mark.line + 1})", mark
                )
            seen.add(key)
        out[key] = construct(value_node)
    return out


def _scalar(kind: str) -> Any:
    """PyYAML's constructor for a scalar ``kind``, failing as a YAML error: an
    explicit tag on the wrong text ('!!bool at', '!!float x') raises a bare
    KeyError or ValueError there, and Python refuses to read an integer of
    thousands of digits."""
    construct = getattr(yaml.constructor.SafeConstructor, f"construct_yaml_{kind}")

    def guarded(loader: Any, node: yaml.ScalarNode) -> Any:
        try:
            return construct(loader, node)
        except (ArithmeticError, LookupError, TypeError, ValueError):
            raise _unreadable(node, kind) from None

    return guarded


def _unreadable(node: yaml.ScalarNode, kind: str) -> yaml.YAMLError:
    what = "a number far too long" if len(str(node.value)) > 1000 else f"not a {kind}"
    return yaml.constructor.ConstructorError(
        None, None, f"{shown(node.value)} is {what}", node.start_mark
    )


#: YAML 1.1 reads these as numbers, YAML 1.2 and JSON do not (0x10 is 16, 1_0 is 10,
#: 017 is 15, 1:30 is 90): a model's number is plain decimal.
_PLAIN_INT = re.compile(r"[-+]?(0|[1-9][0-9]*)")
_PLAIN_FLOAT = re.compile(
    r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?|[-+]?\.(inf|Inf|INF)|\.(nan|NaN|NAN)"
)
#: How a plain float that is not decimal ends (.inf, .nan).
_NOT_DECIMAL = frozenset("fFnN")


def _number(kind: str) -> Any:
    """``_scalar(kind)`` for a number, refusing YAML 1.1's other numerals
    and a float that underflows to 0."""
    construct = _scalar(kind)
    plain = _PLAIN_INT if kind == "int" else _PLAIN_FLOAT

    def checked(loader: Any, node: yaml.ScalarNode) -> Any:
        text = str(node.value)
        if node.tag.endswith(f":{kind}") and plain.fullmatch(text) is None:
            raise yaml.constructor.ConstructorError(
                None,
                None,
                f"{shown(text)} is a YAML 1.1 numeral (hexadecimal, octal, sexagesimal or "
                "with '_'), which YAML 1.2 and JSON read otherwise; write the number in "
                "plain decimal",
                node.start_mark,
            )
        if text[-1:] in _NOT_DECIMAL:  # .inf, .nan
            value = construct(loader, node)
        else:  # plain decimal: Python reads it as YAML does, and faster
            try:
                value = int(text) if kind == "int" else float(text)
            except ValueError:  # an integer of thousands of digits
                raise _unreadable(node, kind) from None
        if kind == "float" and value == 0.0:
            try:
                read_number(text)
            except UnderflowError as exc:
                raise yaml.constructor.ConstructorError(
                    None, None, str(exc), node.start_mark
                ) from None
        return value

    return checked


def _text(loader: Any, node: yaml.ScalarNode) -> Any:
    # a date (2001-12-14) stays text: a model has no dates, and an impossible
    # date (2001-13-45) would otherwise stop the reading
    return loader.construct_scalar(node)


_StrictLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _mapping)
_StrictLoader.add_constructor("tag:yaml.org,2002:bool", _scalar("bool"))
for _kind_name in ("int", "float"):
    _StrictLoader.add_constructor(f"tag:yaml.org,2002:{_kind_name}", _number(_kind_name))
_StrictLoader.add_constructor("tag:yaml.org,2002:timestamp", _text)


#: Where the schema says it lives (the YAML language server reads ``$schema``).
SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"


def json_schema() -> dict[str, Any]:
    """The model file's JSON Schema, generated from the validated model: the
    keys, shapes and types a file may hold (``jointplay schema``). Values with
    units are numbers (base unit) or strings that start with a number; what a
    unit means, and the checks across entries (names, topology), are made
    when the file is read."""
    schema = Model.model_json_schema(by_alias=True)
    return {
        "$schema": SCHEMA_DIALECT,
        "title": "jointplay model file",
        "description": (
            "A mechanism with clearances: bodies, joints with their plays, loads, "
            "functional points and requirements (docs/conventions.md)."
        ),
        **{k: v for k, v in schema.items() if k not in ("title", "description")},
    }


def load(path: str | Path) -> Model:
    """Read and validate a model file (``.yaml``/``.yml``, ``.json`` or ``.toml``)."""
    path = Path(path)
    source = str(path)
    text = _read(path, source)
    with _gc_paused():  # the plain data freed before the collector runs again
        model = model_from_dict(parse_text(text, path.suffix.lower(), source), source=source)
    return model


@contextmanager
def _gc_paused() -> Iterator[None]:
    """Python's garbage collector paused, and set going again after. Reading
    makes a few objects per value of the file and frees none of them, yet the
    collector walks them all again and again as they pile up: it took more
    than half the time to read a 10,000-body model."""
    paused = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if paused:
            gc.enable()


def _read(path: Path, source: str) -> str:
    folder = "this is a folder, not a model file; give the model file"
    if "\0" in source:
        raise ModelError("the path holds a NUL character; check the path", source=shown(source))
    raw = b""
    try:
        if path.is_dir():
            raise IsADirectoryError
        with path.open("rb") as stream:
            size = os.fstat(stream.fileno()).st_size
            if size <= MAX_FILE_BYTES:
                head = stream.read(HEAD_BYTES)
                _check_head(head, source)
                # a pipe or a device tells no size: read one byte more than the limit
                raw = head + stream.read(MAX_FILE_BYTES + 1 - len(head))
    except FileNotFoundError:
        raise ModelError("no such file; check the path", source=source) from None
    except IsADirectoryError:
        raise ModelError(folder, source=source) from None
    except OSError as exc:
        raise ModelError(
            f"cannot read the file ({exc.strerror}); check the path and its permissions",
            source=source,
        ) from None
    if max(size, len(raw)) > MAX_FILE_BYTES:
        raise ModelError(
            f"the file is larger than {MAX_FILE_BYTES // 1_000_000} MB, far larger than a "
            f"model file (a model of {LARGEST_MODEL_BODIES:,} bodies is about 5 MB); check "
            "that this is the model",
            source=source,
        )
    return _decode(raw, source)


def _check_head(head: bytes, source: str) -> None:
    """Refuse at once a file whose first bytes are not UTF-8 text."""
    boms = {
        b"\x00\x00\xfe\xff": "UTF-32",
        b"\xff\xfe\x00\x00": "UTF-32",
        b"\xfe\xff": "UTF-16",
        b"\xff\xfe": "UTF-16",
    }
    for bom, name in boms.items():
        if head.startswith(bom):
            raise ModelError(
                f"the file is {name} text; save it as UTF-8 (most editors offer the encoding "
                "in 'Save as')",
                source=source,
            )
    if b"\x00" in head:
        raise ModelError(
            "this is a binary file (it holds NUL bytes), not a model file; give the YAML, "
            "JSON or TOML model",
            source=source,
        )
    try:  # a character cut at the end of the head is checked with the rest
        codecs.getincrementaldecoder("utf-8")().decode(head, final=False)
    except UnicodeDecodeError as exc:
        raise _not_utf8(head, exc, source) from None


def _decode(raw: bytes, source: str) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise _not_utf8(raw, exc, source) from None


def _not_utf8(raw: bytes, exc: UnicodeDecodeError, source: str) -> ModelError:
    line = raw[: exc.start].count(b"\n") + 1
    column = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
    byte = raw[exc.start]
    return ModelError(
        f"not UTF-8 text: byte 0x{byte:02x} at line {line}, column {column} is not "
        "UTF-8; save the file as UTF-8",
        source=source,
    )


def parse_text(text: str, suffix: str, source: str) -> Any:
    """The plain data of a model file's text; ``suffix`` picks the format
    (``.json``, ``.toml``, anything else is YAML)."""
    if len(text.encode("utf-8", "surrogatepass")) > MAX_FILE_BYTES:
        raise ModelError(
            f"the text is larger than {MAX_FILE_BYTES // 1_000_000} MB, too large for a model",
            source=source,
        )
    try:
        if suffix == ".json":
            data = json.loads(text, object_pairs_hook=_json_object, parse_float=read_number)
        elif suffix == ".toml":
            data = tomllib.loads(text, parse_float=read_number)
        else:
            data = _parse_yaml(text, source)
    except json.JSONDecodeError as exc:
        raise ModelError(
            f"not valid JSON: {exc.msg} at line {exc.lineno}, column {exc.colno}"
            + _format_hint(text, ".json"),
            source=source,
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ModelError(
            f"not valid TOML: {exc}" + _format_hint(text, ".toml"), source=source
        ) from None
    except _TooManyNodesError:
        raise ModelError(
            f"the file holds more than {MAX_NODES:,} values, far more than a model (a model "
            f"of {LARGEST_MODEL_BODIES:,} bodies holds under a million); check that this is "
            "the model",
            source=source,
        ) from None
    except yaml.YAMLError as exc:
        raise ModelError(
            _yaml_problem(exc, text) + _format_hint(text, ".yaml"), source=source
        ) from None
    except ModelError:
        raise
    except RecursionError:
        raise ModelError(_too_deep(), source=source) from None
    except _DuplicateKeyError as exc:
        raise ModelError(
            f"not valid JSON: duplicate key {shown(exc.args[0])} in an object; give each key once",
            source=source,
        ) from None
    except UnderflowError as exc:  # JSON or TOML: a number that reads as 0
        raise ModelError(str(exc), source=source) from None
    except ValueError as exc:  # JSON or TOML: an integer of thousands of digits
        problem = (
            "a number in the file has thousands of digits"
            if "digits" in str(exc)
            else f"a value cannot be read ({shown(str(exc))})"
        )
        raise ModelError(f"{problem}; write plain numbers such as 0.2", source=source) from None
    _check_structure(data, source)
    if data is not None and not isinstance(data, dict):
        raise ModelError(_not_a_mapping(data) + _format_hint(text, suffix), source=source)
    return data


def _not_a_mapping(data: Any) -> str:
    kind = "empty" if data is None else _kind(data)
    return (
        f"expected a mapping with 'bodies', 'joints' and 'loads', but the file is {kind}; "
        "see the model file format in the README"
    )


class _DuplicateKeyError(ValueError):
    pass


def _json_object(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKeyError(key)
        out[key] = value
    return out


def _parse_yaml(text: str, source: str) -> Any:
    loader = _StrictLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        return _build(loader, node, source)
    finally:
        loader.dispose()


_TAG = "tag:yaml.org,2002:"
_STR_TAG, _NULL_TAG, _SEQ_TAG, _MAP_TAG = (_TAG + t for t in ("str", "null", "seq", "map"))


def _build(loader: Any, root: yaml.Node, source: str) -> Any:
    """The value of a YAML document's nodes, checked as it is built: no list
    or mapping nested more than MAX_DEPTH deep, none inside its own value
    (an anchor used within it), at most MAX_NODES values with aliases
    expanded. An alias (*name) takes the value built for its anchor, so that
    a "billion laughs" file takes the time of its few lines to be refused.
    Texts, numbers, lists and mappings are built here, about three times faster
    than by PyYAML's constructor; other tags (!!binary, !!set, unknown ones)
    go to it."""
    return _Builder(loader, source).value(root)


class _Builder:
    """``_build``'s state (a class, not a closure: a closure that calls
    itself is a reference cycle, which would keep every value alive until
    the garbage collector's next full pass)."""

    def __init__(self, loader: Any, source: str):
        self.loader = loader
        self.source = source
        self.scalars = {
            tag: loader.yaml_constructors[tag]
            for tag in (_TAG + t for t in ("bool", "int", "float", "timestamp"))
        }
        self.built: dict[yaml.Node, Any] = {}  # the lists and mappings built
        self.size: dict[yaml.Node, int] = {}  # their values, themselves included, aliases expanded
        self.on_path: list[yaml.Node] = []  # the lists and mappings being built, outermost first
        self.total = 0  # the values built, aliases expanded

    def value(self, node: yaml.Node) -> Any:
        if node.__class__ is yaml.ScalarNode:
            self.total += 1  # bounded by the count as parsed (_StrictLoader)
            tag = node.tag
            if tag == _STR_TAG:
                return node.value
            if tag in self.scalars:
                return self.scalars[tag](self.loader, node)
            if tag == _NULL_TAG:
                return None
            return self.loader.construct_object(node, deep=True)
        if node in self.built:
            self._count(self.size[node])
            return self.built[node]
        self._refuse_inside(node)
        if len(self.on_path) >= MAX_DEPTH:
            raise ModelError(_too_deep(), source=self.source)
        self.on_path.append(node)
        before = self.total
        out: Any
        if node.__class__ is yaml.SequenceNode:
            out = [self.value(child) for child in node.value]
        else:
            for key_node, merged in node.value:  # '<<: *name' merged into its own value
                if key_node.tag == _MERGE_TAG:
                    parts = merged.value if merged.__class__ is yaml.SequenceNode else [merged]
                    for part in parts:
                        self._refuse_inside(part)
            out = _mapping_of(self.loader, cast(yaml.MappingNode, node), self.value)
        if node.tag not in (_SEQ_TAG, _MAP_TAG):  # its values are checked: PyYAML builds it
            out = self.loader.construct_object(node, deep=True)
        self._count(1)
        self.on_path.pop()
        self.built[node] = out
        self.size[node] = self.total - before
        return out

    def _count(self, more: int) -> None:
        self.total += more
        if self.total > MAX_NODES:
            raise ModelError(
                f"the YAML aliases (*name) expand to more than {MAX_NODES:,} values, far "
                "more than a model holds (a 'billion laughs' file?); write the values out, "
                "or reuse fewer aliases",
                source=self.source,
            )

    def _refuse_inside(self, node: yaml.Node) -> None:
        if node in self.on_path:
            mark = node.start_mark
            raise ModelError(
                f"the YAML anchor (&name) at line {mark.line + 1}, column {mark.column + 1} "
                "is used (*name) inside its own value, so that value never ends; write the "
                "values out",
                source=self.source,
            )


def _too_deep() -> str:
    return (
        f"the file nests lists or mappings more than {MAX_DEPTH} deep, which no model does; "
        "check the brackets"
    )


def _yaml_problem(exc: yaml.YAMLError, text: str) -> str:
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    problem = getattr(exc, "problem", None)
    if "nesting depth" in str(problem):
        # libyaml (from PyYAML 6.0.4) stops at 1000 levels, before our own check
        # on the nodes can see them: the same problem, in our words.
        return _too_deep()
    if isinstance(exc, yaml.reader.ReaderError):
        position = int(getattr(exc, "position", 0))
        line = text.count("\n", 0, position) + 1
        code = getattr(exc, "character", None)
        char = f"#x{code:04x}" if isinstance(code, int) else shown(code)
        return (
            f"not valid YAML: line {line} holds the control character {char}, which YAML "
            "does not allow; remove it (is this a text model file?)"
        )
    where = ""
    if mark is not None:
        where = f" at line {mark.line + 1}, column {mark.column + 1}"
        lines = text.splitlines()
        if 0 <= mark.line < len(lines) and lines[mark.line].strip():
            where += f" ({shown(lines[mark.line].strip())})"
    if problem is None:
        problem = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    return f"not valid YAML{where}: {problem}"


def _format_hint(text: str, suffix: str) -> str:
    """A hint when the file seems to be in another format than its name says."""
    fmt = suffix if suffix in (".json", ".toml") else ".yaml"
    if fmt != ".yaml" and not text.lstrip().startswith(("{", "[")):
        try:
            if isinstance(yaml.load(text, Loader=_StrictLoader), dict):
                return f"; the file looks like YAML: name it .yaml, or fix the {fmt[1:].upper()}"
        except Exception:  # not YAML either
            pass
    if fmt != ".toml":
        try:
            if tomllib.loads(text):
                return f"; the file looks like TOML: name it .toml, or fix the {fmt[1:].upper()}"
        except Exception:  # not TOML either
            pass
    if fmt == ".yaml" and text.lstrip().startswith("{"):
        return "; if the file is JSON, name it .json to read it as JSON"
    return ""


def _check_structure(data: Any, source: str) -> None:
    """Keys are text and the nesting is not absurd (JSON and TOML have no
    alias check); iteratively, so that nothing recurses."""
    stack: list[tuple[Any, list[Any]]] = [(data, [])]
    while stack:
        value, loc = stack.pop()
        if len(loc) >= MAX_DEPTH:
            raise ModelError(_too_deep(), source=source)
        if isinstance(value, dict):
            for key, item in value.items():
                if not isinstance(key, str):
                    entry, field_path = _entry(loc, data) if loc else ("", "")
                    where = ": ".join(p for p in (entry, field_path) if p)
                    raise ModelError(
                        f"the key {shown(key)} is not a name; keys are names such as 'clearance'"
                        + (f" (write it in quotes: '{key}')" if _quotable(key) else ""),
                        source=source,
                        entry=where or None,
                    )
                if isinstance(item, dict | list):
                    stack.append((item, [*loc, key]))
        elif isinstance(value, list):
            stack.extend(
                (item, [*loc, i]) for i, item in enumerate(value) if isinstance(item, dict | list)
            )


def _quotable(key: Any) -> bool:
    return isinstance(key, bool | int | float) or key is None


def model_from_dict(data: Any, *, source: str = "<model>") -> Model:
    """Validate a plain dict (as read from a model file) into a ``Model``."""
    if not isinstance(data, dict):
        raise ModelError(_not_a_mapping(data), source=source)
    _check_sizes(data, source)
    try:
        with _gc_paused():
            return Model.model_validate(data)
    except ValidationError as exc:
        raise _to_model_error(exc, data, source) from None
    except RecursionError:
        raise ModelError(_too_deep(), source=source) from None


def with_deviations(
    model: Model, measured: Mapping[str, Mapping[str, Any]], *, source: str = "<model>"
) -> Model:
    """``model`` with some deviations known, as measured on a part:
    ``{joint: {"position": [x, y, z], "orientation": [0, wy, wz]}}`` in the
    joint frame (mm and rad, or strings with units), or the same for a shared
    deviation by its name, in its own frame. A given zone becomes that value
    exactly; the other zone stays as the model has it. A value outside the
    zone the model gave is taken still (a rejected part, measured to see what
    it does), with a warning (``Model.warnings``); ``Model.measured`` lists
    what was given."""
    names = [j.name for j in model.joints]
    shared = [d.name for d in model.deviations]
    data = model.model_dump(by_alias=True, exclude_none=True)
    # measured once before: checked against the zones the model gave then
    designed = {m.name: (m.zones, m.ball) for m in model.measured}
    sources = {source.label: source for source in model.deviation_sources()}
    records: list[MeasuredDeviation] = []
    for name, given in measured.items():
        if name not in names and name not in shared:
            known = ", ".join(shown(n) for n in [*names, *shared])
            raise ModelError(
                f"there is no joint or shared deviation {shown(name)}; there are {known}",
                source=source,
                entry="--deviations",
            )
        unknown = sorted(set(given) - {"position", "orientation"})
        if unknown:
            raise ModelError(
                f"{shown(name)}: {shown(unknown[0])} is no deviation; give "
                "'position' ([x, y, z], mm) or 'orientation' ([0, wy, wz], rad)",
                source=source,
                entry="--deviations",
            )
        if name in shared:
            entry = data["deviations"][shared.index(name)]
        else:
            joint = data["joints"][names.index(name)]
            entry = joint.setdefault("deviation", {})
            if entry.get("shared") is not None:
                raise ModelError(
                    f"joint {shown(name)} takes the shared deviation "
                    f"{shown(entry['shared'])}: measure the group, "
                    f"{entry['shared']}.position=[...], in its own frame",
                    source=source,
                    entry="--deviations",
                )
        who = f"shared deviation {shown(name)}" if name in shared else f"joint {shown(name)}"
        own = sources.get(name)  # None: the model gives it no zones
        model_zones = (None, False) if own is None else (own.deviation, own.ball)
        zones, ball = designed.get(name, model_zones)
        for kind, value in _measure(entry, given, name, source).items():
            problem = None if zones is None else outside(zones, kind, value, ball)
            warning = None if problem is None else f"{who}: {problem}"
            records.append(MeasuredDeviation(name, kind, value, zones, ball, warning))
        if not {"position", "orientation"} & set(entry):  # measured at 0: none
            if name in shared:
                entry["position"] = {"diameter": 0}
            else:
                del joint["deviation"]
    try:
        out = model_from_dict(data, source=source)
    except ModelError as exc:
        raise ModelError(
            f"the measured deviations ({', '.join(map(shown, measured))}) do not fit the "
            f"model: {exc.problem} (at {exc.entry})",
            source=source,
            entry="--deviations",
        ) from None
    again = {(m.name, m.kind) for m in records}
    kept = [m for m in model.measured if (m.name, m.kind) not in again]
    out._measured = (*kept, *records)
    return out


def _measure(
    entry: dict[str, Any], given: Mapping[str, Any], name: str, source: str
) -> dict[Kind, tuple[float, float, float]]:
    """A deviation's zones replaced by the measured values: a position as
    limits of no width on the directions where it is not 0 (so that a joint
    that leaves a direction free, a point contact's sideways slip, takes the
    others), an orientation as a tilt of no size around its value. Returns
    the values (mm, rad)."""
    values: dict[Kind, tuple[float, float, float]] = {}
    kinds: tuple[tuple[Kind, str], ...] = (("position", "length"), ("orientation", "angle"))
    for kind, dimension in kinds:
        if kind not in given:
            continue
        try:
            value = _vector(dimension)(given[kind])
        except ValueError as exc:
            raise ModelError(f"{name}.{kind}: {exc}", source=source, entry="--deviations") from None
        values[kind] = value
        if not any(value):
            entry.pop(kind, None)
        elif kind == "position":
            # a component below the value's round-off is 0 (as for a mean)
            kept = mean_components(value)
            entry[kind] = {"xyz"[a]: {"min": value[a], "max": value[a]} for a in kept}
        else:
            entry[kind] = {"angle": 0, "mean": list(value)}
    return values


def _check_sizes(data: dict[str, Any], source: str) -> None:
    """At most MAX_ENTRIES entries per section, before validation walks them."""
    sections = [(name, data.get(name)) for name in SECTIONS]
    cases = data.get("load_cases")
    if isinstance(cases, dict):
        sections.append(("load_cases", cases))
        sections += [(f"load_cases.{_short(name)}", loads) for name, loads in cases.items()]
    for entry, items in sections:
        if isinstance(items, list | dict) and len(items) > MAX_ENTRIES:
            raise ModelError(
                f"{len(items):,} entries, more than the {MAX_ENTRIES:,} a model may have; "
                "check that this is the model, or split it",
                source=source,
                entry=entry,
            )


#: Problems listed in one message at the most; a file with more is far off.
MOST_PROBLEMS = 20


def _to_model_error(exc: ValidationError, data: dict[str, Any], source: str) -> ModelError:
    """Every problem of the file, in file order, the likeliest first
    (``_first``): its entry and fix in the message's first line, then one
    line per other problem. The names that point nowhere are among them
    (``_unknown_names``) even where pydantic stopped at a field, before the
    checks across entries."""
    errors = _consequences_left_out(
        _with_common_joint_problems(exc.errors(include_url=False), data)
    )
    errors.sort(key=lambda err: _position(err["loc"], data))
    first = _first(errors)
    lines = [
        (_position(err["loc"], data), line)
        for err in errors
        if err is not first
        for line in _described(err, data)
    ]
    if all(err["loc"] for err in errors):  # the checks across entries did not run
        lines += _unknown_names(data)
    lines.sort(key=lambda item: item[0])  # a field's problem before its entry's names
    described = [*_described(first, data), *(line for _, line in lines)]
    entry, problem = described[0]
    others = [f"  {where}: {what}" if where else f"  {what}" for where, what in described[1:]]
    if len(others) > MOST_PROBLEMS:
        others = [*others[:MOST_PROBLEMS], f"  ... and {len(others) - MOST_PROBLEMS} more"]
    if others:
        problem += f"\n{len(described) - 1} more problem(s) in this file:\n" + "\n".join(others)
    return ModelError(problem, source=source, entry=entry or None)


#: A name as the model reads it (stripped, one line, at most 100 characters).
_NAME: TypeAdapter[str] = TypeAdapter(Name)
#: The model's keys in file order: problems are listed in it.
_FILE_ORDER = [field.alias or name for name, field in Model.model_fields.items()]


def _position(loc: Any, data: dict[str, Any]) -> tuple[int, ...]:
    """Where a pydantic location is in the file, as a key to sort by: its
    section, then its entry (a load case's by the order of the cases)."""
    if not loc:
        return (-1,)
    section = loc[0]
    out = [_FILE_ORDER.index(section) if section in _FILE_ORDER else len(_FILE_ORDER)]
    rest = list(loc[1:3])
    if section == "load_cases" and rest:
        cases = data.get("load_cases")
        names = list(cases) if isinstance(cases, dict) else []
        out.append(names.index(rest[0]) if rest[0] in names else -1)
        rest = rest[1:]
    if rest and isinstance(rest[0], int):
        out.append(rest[0])
    return tuple(out)


def _unknown_names(data: dict[str, Any]) -> list[tuple[tuple[int, ...], tuple[str, str]]]:
    """The names that point nowhere, read from the file's data as it is, each
    as (position, (entry, problem)), in the words of the checks across
    entries (``Model._check_topology``): a joint's or a load's or a point's
    body, a requirement's point, a joint's shared deviation, a shared
    deviation's body. Names are looked up in a section only when each of its
    entries has a valid name (else a misspelt ``name`` key would make them
    all unknown); a value that is not a valid name, or a ``between`` that is
    not two of them, is a field's problem, said apart."""

    def text(value: Any) -> str | None:
        try:
            return _NAME.validate_python(value)
        except ValidationError:  # not a name: a field's problem
            return None

    def names(section: str, required: bool) -> list[str] | None:
        items = data.get(section, None if required else [])
        if not isinstance(items, list) or (required and not items):
            return None
        out = []
        for item in items:
            name = text(item.get("name") if isinstance(item, dict) else None)
            if name is None:
                return None
            out.append(name)
        return out

    def entries(section: str) -> list[tuple[tuple[Any, ...], dict[str, Any]]]:
        items = data.get(section)
        if section == "load_cases":
            if not isinstance(items, dict):
                return []
            return [
                ((section, case, i), item)
                for case, loads in items.items()
                if isinstance(loads, list)
                for i, item in enumerate(loads)
                if isinstance(item, dict)
            ]
        if not isinstance(items, list):
            return []
        return [((section, i), item) for i, item in enumerate(items) if isinstance(item, dict)]

    bodies = names("bodies", required=True)
    points = names("points", required=False)
    shared = names("deviations", required=False)
    found: list[tuple[tuple[Any, ...], str]] = []
    for loc, joint in entries("joints"):
        between = joint.get("between")
        if bodies is not None and isinstance(between, list) and len(between) == 2:
            for body in between:
                if (name := text(body)) is not None and name not in bodies:
                    found.append((loc, unknown_body("between", name, bodies)))
        deviation = joint.get("deviation")
        group = text(deviation.get("shared") if isinstance(deviation, dict) else deviation)
        if shared is not None and group is not None and group not in shared:
            found.append((loc, unknown_shared_deviation(group, shared)))
    for section in ("loads", "load_cases", "points"):
        for loc, item in entries(section):
            name = text(item.get("body"))
            if bodies is not None and name is not None and name not in bodies:
                found.append((loc, unknown_body("body", name, bodies)))
    for loc, requirement in entries("requirements"):
        name = text(requirement.get("point"))
        if points is not None and name is not None and name not in points:
            found.append((loc, unknown_point(name, points)))
    for loc, deviation in entries("deviations"):
        name = text(deviation.get("body"))
        if bodies is not None and name is not None and name not in bodies:
            found.append((loc, unknown_deviation_body(name, bodies)))
    return [(_position(loc, data), (_entry(list(loc), data)[0], what)) for loc, what in found]


class _AnyJoint(Joint):
    """The fields every joint type has, other keys let through: what can be
    checked of a joint whose type is unknown."""

    model_config = ConfigDict(frozen=True, extra="ignore")


#: Every key some joint type has.
_JOINT_KEYS = {"type"}.union(*(cls.model_fields for cls in JOINT_TYPES.values()))
#: The keys every joint type requires.
_EVERY_JOINT_NEEDS = set.intersection(
    *(
        {name for name, f in cls.model_fields.items() if f.is_required()}
        for cls in JOINT_TYPES.values()
    )
)


def _with_common_joint_problems(errors: list[Any], data: dict[str, Any]) -> list[Any]:
    """The errors, and for a joint of unknown type the problems of the keys
    every type shares (pydantic stops at the type), and of keys no type has."""
    out = list(errors)
    for err in errors:
        loc = tuple(err["loc"])
        tag = err["type"] in ("union_tag_invalid", "union_tag_not_found")
        if not tag or len(loc) != 2 or loc[0] != "joints":
            continue
        joints = data.get("joints")
        item = joints[loc[1]] if isinstance(joints, list) and loc[1] < len(joints) else None
        if not isinstance(item, dict):
            continue
        try:
            _AnyJoint.model_validate({k: v for k, v in item.items() if k != "type"})
        except ValidationError as exc:
            # a key only some types need is theirs to ask for (a prismatic joint has
            # no 'clearance'); one that every type needs is missing whatever the type
            out += [
                {**e, "loc": (*loc, *e["loc"])}
                for e in exc.errors(include_url=False)
                if e["type"] != "missing" or (e["loc"][:1] and e["loc"][0] in _EVERY_JOINT_NEEDS)
            ]
        out += [
            {"type": "extra_forbidden", "loc": (*loc, key), "msg": "", "input": value}
            for key, value in item.items()
            if isinstance(key, str) and key not in _JOINT_KEYS
        ]
    return out


def _described(err: Any, data: dict[str, Any]) -> list[tuple[str, str]]:
    """(where, what) of one validation error: the entry and field, and the
    problem with its fix; a model-level error may hold several."""
    original = (err.get("ctx") or {}).get("error")
    if isinstance(original, EntryProblemsError | EntryError):
        found = original.errors if isinstance(original, EntryProblemsError) else [original]
        return [
            (e.entry, e.problem if e.problem.endswith((".", "?")) else e.problem + ".")
            for e in found
        ]
    loc = list(err["loc"])
    entry, field_path = _entry(loc, data)
    return [(": ".join(p for p in (entry, field_path) if p), _problem(err, loc, data))]


def _consequences_left_out(errors: list[Any]) -> list[Any]:
    """The problems less those that only follow from others: a required key
    missing beside an unknown one (most likely it, misspelt: the unknown key's
    message names it), and a section "too short" because its entries failed."""
    extra = {tuple(e["loc"][:-1]) for e in errors if e["type"] == "extra_forbidden"}
    failed_items = {tuple(e["loc"][:1]) for e in errors if len(e["loc"]) > 1}
    kept = [
        e
        for e in errors
        if not (e["type"] == "missing" and tuple(e["loc"][:-1]) in extra)
        and not (e["type"] == "too_short" and tuple(e["loc"]) in failed_items)
    ]
    return kept or errors


def _first(errors: list[Any]) -> Any:
    """The error to report: the first, except that a key missing next to an
    unknown key is most likely that key misspelt, so the unknown key goes first."""
    err = errors[0]
    if err["type"] == "missing":
        parent = tuple(err["loc"][:-1])
        for other in errors:
            if other["type"] == "extra_forbidden" and tuple(other["loc"][:-1]) == parent:
                return other
    return err


def _entry(loc: list[Any], data: dict[str, Any]) -> tuple[str, str]:
    """Split a pydantic location into ('joints[1] 'l2'', 'clearance')."""
    if len(loc) >= 2 and loc[0] == "load_cases" and loc[-1] == "[key]":
        return "load_cases", ""
    if len(loc) >= 3 and loc[0] == "load_cases" and isinstance(loc[2], int):
        return f"load_cases.{_short(loc[1])}[{loc[2]}]", _join_loc(loc[3:])
    if len(loc) >= 2 and loc[0] in SECTIONS and isinstance(loc[1], int):
        section, index = loc[0], loc[1]
        rest = loc[2:]
        if section == "joints" and rest and isinstance(rest[0], str) and rest[0] in JOINT_TYPES:
            rest = rest[1:]  # the discriminator tag pydantic inserts
        name = ""
        items = data.get(str(section))
        if isinstance(items, list) and index < len(items) and isinstance(items[index], dict):
            item_name = items[index].get("name")
            if isinstance(item_name, str) and item_name.strip():
                name = f" '{_short(item_name.strip())}'"
        return f"{section}[{index}]{name}", _join_loc(rest)
    return "", _join_loc(loc)


def _short(text: Any) -> str:
    """A user's name inside a message: one line, at most 40 characters."""
    out = str(text)[:200]
    if not out.isprintable():
        out = repr(out)[1:-1]
    return out if len(out) <= 40 and len(str(text)) <= 40 else out[:37] + "..."


def _join_loc(parts: list[Any]) -> str:
    """``['a', 0, 'b']`` -> ``a[0].b``."""
    out = ""
    for part in parts:
        out += (
            f"[{part}]" if isinstance(part, int) else (f".{_short(part)}" if out else _short(part))
        )
    return out


def _problem(err: Any, loc: list[Any], data: dict[str, Any]) -> str:
    kind = err["type"]
    ctx = err.get("ctx") or {}
    got = shown(err.get("input"))
    if kind == "extra_forbidden":
        key = str(loc[-1])
        allowed = _allowed_keys(loc, data)
        hint = suggest(key, allowed) if allowed else ""
        listing = f" Allowed keys here: {', '.join(sorted(allowed))}." if allowed else ""
        if not hint:
            listing += " Remove it, or fix its spelling."
        return f"unknown key {shown(key)}.{hint}{listing}"
    if "between" in loc and kind in ("missing", "too_long", "too_short", "tuple_type"):
        value = _lookup(data, loc[: loc.index("between") + 1])
        return f"expected the names of two bodies, [a, b], got {shown(value)}"
    if kind == "missing":
        return f"the key '{loc[-1]}' is required here; add it"
    if kind == "union_tag_invalid":
        tag = str(ctx.get("tag"))
        return (
            f"unknown joint type {shown(tag)}.{suggest(tag, JOINT_TYPES)} "
            f"Known types: {', '.join(sorted(JOINT_TYPES))}"
        )
    if kind == "union_tag_not_found":
        item = _lookup(data, loc)
        typo = ""
        if isinstance(item, dict):
            for key in item:
                if isinstance(key, str) and suggest(key, ["type"]):
                    typo = f" (is {shown(key)} meant to be 'type'?)"
                    break
        return f"the joint needs a 'type'{typo}; one of: {', '.join(sorted(JOINT_TYPES))}"
    if kind == "literal_error" and loc == ["schema"]:
        return f"this is schema version 1; got {got}. Write 'schema: 1' or leave it out"
    if kind in ("too_short",) and loc and loc[0] in ("bodies", "joints"):
        return f"expected at least one entry in '{loc[0]}'"
    if kind in ("tuple_type", "list_type") and len(loc) == 1:
        return f"expected a list of entries, got {_kind(err.get('input'))}"
    if kind in ("tuple_type", "list_type") and loc[0] == "load_cases":
        return f"expected a list of loads (write [] for none), got {_kind(err.get('input'))}"
    if kind == "model_type" or kind == "model_attributes_type":
        return f"expected a mapping of keys (name: ..., ...), got {got}"
    if kind == "dict_type":
        return f"expected a mapping (NAME: [...], ...), got {type(err.get('input')).__name__}"
    if kind == "string_type" and loc[-1] == "[key]":
        return f"the load case name {got} is not text; write it in quotes: '{err.get('input')}'"
    if kind == "string_type":
        quote = " (write it in quotes)" if _quotable(err.get("input")) else ""
        return f"expected a text name, got {got}{quote}"
    if kind == "string_too_short":
        return "expected a name, got an empty text; give it a name"
    if kind == "string_too_long":
        return f"expected a name of at most {ctx.get('max_length')} characters, got {got}"
    if kind == "invalid_key":
        return f"the key {got} is not a name; keys are names such as 'clearance'"
    if kind == "bool_type":
        return f"expected true or false, got {got}"
    message = str(err["msg"])
    return message.removeprefix("Value error, ").removeprefix("Assertion failed, ")


def _kind(value: Any) -> str:
    """What a value is, in words: 'a list ([1, 2])'."""
    if value is None:
        return "nothing (null)"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, bool):
        return f"true or false ({shown(value)})"
    names = {list: "a list", str: "a text", int: "a number", float: "a number"}
    return f"{names.get(type(value), 'a ' + type(value).__name__)} ({shown(value)})"


def _lookup(data: Any, loc: list[Any]) -> Any:
    """The value at a pydantic location, skipping the joint-type tags it inserts."""
    value = data
    for part in loc:
        found = (isinstance(value, dict) and part in value) or (
            isinstance(value, list) and isinstance(part, int) and part < len(value)
        )
        if found:
            value = value[part]
        elif isinstance(part, str) and part in JOINT_TYPES:
            continue
        else:
            return None
    return value


def _nested_keys(model: Any, path: list[Any]) -> set[str]:
    """The keys of the entry at ``path`` (field names) inside ``model``: a
    joint's, or of a mapping nested in it (a deviation's zone)."""
    for name in path:
        field = model.model_fields.get(name)
        if field is None:
            return set()
        nested = [
            t
            for t in (field.annotation, *get_args(field.annotation))
            if isinstance(t, type) and issubclass(t, BaseModel)
        ]
        if not nested:
            return set()
        model = nested[0]
    return set(model.model_fields)


def _allowed_keys(loc: list[Any], data: dict[str, Any]) -> set[str]:
    if len(loc) == 1:
        return _SECTION_KEYS["top"]
    section = loc[0]
    if section == "joints" and len(loc) >= 3:
        tag = loc[2] if isinstance(loc[2], str) and loc[2] in JOINT_TYPES else None
        if tag is not None:
            return _nested_keys(JOINT_TYPES[tag], loc[3:-1])
        if len(loc) == 3:  # a joint of unknown type: the keys of any type
            return _JOINT_KEYS
    if section == "deviations" and len(loc) >= 3:
        return _nested_keys(SharedDeviation, loc[2:-1])
    if section in _SECTION_KEYS and len(loc) == 3:
        return _SECTION_KEYS[section]
    if section == "load_cases" and len(loc) == 4:
        return _SECTION_KEYS["loads"]
    if all(isinstance(part, str) for part in loc):  # a section that is one mapping: motion
        return _nested_keys(Model, loc[:-1])
    return set()
