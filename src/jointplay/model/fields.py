"""Validated field types for the model: quantities with units, vectors, names.

Each type accepts a plain number (in the base unit of its dimension) or a
string with units, and fails with an "expected ..., got ..." message.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Annotated, Any, TypeVar

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    PlainValidator,
    StringConstraints,
    WithJsonSchema,
)

from jointplay.model.tables import DriveTable, is_table, parse_table, table_schema
from jointplay.model.tolerance import parse_angular_play, parse_play, parse_scattered
from jointplay.units import BASE_UNITS, NUMBER_FIRST, UNIT_EXAMPLES, shown, to_base

Vec3 = tuple[float, float, float]

EntryT = TypeVar("EntryT", bound=BaseModel)


def with_values(entry: EntryT, **values: Any) -> EntryT:
    """``entry`` with some fields given other values, already validated (as
    validation makes them: a point a tuple of 3 floats), without validating
    it again: a motion's posed model, whose entries the rigid motion of their
    bodies keeps valid. A new object: nothing that ``entry`` worked out from
    its fields (a ``cached_property``) comes with it."""
    fields = {name: getattr(entry, name) for name in type(entry).model_fields}
    unknown = set(values) - set(fields)
    if unknown:
        raise ValueError(f"{type(entry).__name__} has no field {sorted(unknown)[0]!r}")
    fields.update(values)
    return type(entry).model_construct(entry.model_fields_set | set(values), **fields)


def _scalar(dimension: str) -> Callable[[Any], float]:
    def parse(value: Any) -> float:
        return to_base(value, dimension)

    return parse


def _vector(dimension: str, scatter: bool = False) -> Callable[[Any], Vec3]:
    """``scatter``: a component may be ``{min, max, distribution}`` (a load
    that varies in a Monte Carlo study; see ``tolerance.parse_scattered``),
    or ``{table: ...}`` (a load that varies over the motion; see
    ``tables.parse_table``)."""

    def read(component: Any) -> float:
        if not scatter:
            return to_base(component, dimension)
        if isinstance(component, DriveTable):
            return component
        if is_table(component):
            return parse_table(component, dimension)
        return parse_scattered(component, dimension)

    def parse(value: Any) -> Vec3:
        if not isinstance(value, list | tuple) or len(value) != 3:
            raise ValueError(
                f"expected a list of 3 components [x, y, z] ({dimension}), got {shown(value)}"
            )
        out = []
        for i, component in enumerate(value):
            try:
                out.append(read(component))
            except ValueError as exc:
                raise ValueError(f"component {'xyz'[i]}: {exc}") from exc
        return (out[0], out[1], out[2])

    return parse


def _non_negative(value: float) -> float:
    if value < 0:
        raise ValueError(f"expected a value >= 0, got {value:g}")
    return value


def _positive(value: float) -> float:
    if not value > 0:
        raise ValueError(f"expected a value > 0, got {value:g}")
    return value


#: Softest contact spring (N/mm, 1 N per km): a softer one holds nothing, and
#: the solver's scaling divides by it.
SOFTEST_STIFFNESS = 1e-6


def _stiff_enough(value: float) -> float:
    if not value >= SOFTEST_STIFFNESS:
        raise ValueError(
            f"expected a stiffness of at least {SOFTEST_STIFFNESS:g} N/mm, got {value:g}; "
            "give the contact's stiffness in N/mm, or remove 'stiffness' for a rigid contact"
        )
    return value


#: A direction's largest component must reach this (in any unit): below it the
#: squares of the components underflow and the direction cannot be normalized.
_SHORTEST_DIRECTION = 1e-100


def _nonzero_vector(value: Vec3) -> Vec3:
    if max(abs(c) for c in value) < _SHORTEST_DIRECTION:
        got = "[0, 0, 0]" if not any(value) else f"[{', '.join(f'{c:g}' for c in value)}]"
        raise ValueError(
            f"expected a nonzero direction, got {got}; write plain numbers such as [1, 0, 0]"
        )
    return value


def _plain_name(value: str) -> str:
    if not value.isprintable():
        raise ValueError(
            f"a name is one line of text, without tabs, line breaks or control characters; "
            f"got {shown(value)}"
        )
    return value


# -- JSON Schema of the model file (``jointplay schema``): what a file may
# hold, as the validators above read it. The schema checks shapes and keys; a
# unit's meaning is checked when the file is read.


def _article(dimension: str) -> str:
    """'a length', 'an angle', 'a torsional stiffness'."""
    words = dimension.replace("_", " ")
    return f"{'an' if words[0] in 'aeiou' else 'a'} {words}"


def _quantity_schema(dimension: str) -> dict[str, Any]:
    unit = BASE_UNITS[dimension]
    return {
        "anyOf": [{"type": "number"}, {"type": "string", "pattern": NUMBER_FIRST}],
        "description": f"{_article(dimension)}: a number in {unit}, or with its unit: "
        f"{UNIT_EXAMPLES[dimension]}",
    }


def _range_schema(dimension: str) -> dict[str, Any]:
    return {
        "type": "object",
        "properties": {
            "min": _quantity_schema(dimension),
            "max": _quantity_schema(dimension),
            "distribution": {"enum": ["uniform", "normal"]},
        },
        "required": ["min", "max"],
        "additionalProperties": False,
        "description": f"{_article(dimension)} that varies from part to part: its limits",
    }


def _vector_schema(item: dict[str, Any]) -> dict[str, Any]:
    return {"type": "array", "items": item, "minItems": 3, "maxItems": 3}


def _quantity(dimension: str) -> WithJsonSchema:
    return WithJsonSchema(_quantity_schema(dimension))


def _vector_of(dimension: str, scatter: bool = False) -> WithJsonSchema:
    item = _quantity_schema(dimension)
    if scatter:
        item = {"anyOf": [item, _range_schema(dimension), table_schema(dimension, item)]}
    return WithJsonSchema(_vector_schema(item))


_FIT_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "fit": {"type": "string", "description": "an ISO 286 fit, e.g. 'H7/g6'"},
        "diameter": _quantity_schema("length"),
        "distribution": {"enum": ["uniform", "normal"]},
    },
    "required": ["fit", "diameter"],
    "additionalProperties": False,
}
_PLAY_SCHEMA = WithJsonSchema(
    {"anyOf": [_quantity_schema("length"), _range_schema("length"), _FIT_SCHEMA]}
)
_AT_RADIUS_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {"length": _quantity_schema("length"), "radius": _quantity_schema("length")},
    "required": ["length", "radius"],
    "additionalProperties": False,
    "description": "a play along an arc at a radius: the angle length / radius",
}
_ANGLE_OR_ARC: dict[str, Any] = {"anyOf": [_quantity_schema("angle"), _AT_RADIUS_SCHEMA]}
_ANGULAR_RANGE: dict[str, Any] = {
    **_range_schema("angle"),
    "properties": {
        "min": _ANGLE_OR_ARC,
        "max": _ANGLE_OR_ARC,
        "distribution": {"enum": ["uniform", "normal"]},
    },
}
_ANGULAR_PLAY_SCHEMA = WithJsonSchema({"anyOf": [*_ANGLE_OR_ARC["anyOf"], _ANGULAR_RANGE]})


#: Names appear in every message and report: one printable line, at most 100 characters.
Name = Annotated[
    str,
    StringConstraints(strict=True, min_length=1, max_length=100, strip_whitespace=True),
    AfterValidator(_plain_name),
]
Length = Annotated[float, BeforeValidator(_scalar("length")), _quantity("length")]
NonNegativeLength = Annotated[
    float, BeforeValidator(_scalar("length")), AfterValidator(_non_negative), _quantity("length")
]
#: A joint's play: a length, or limits / an ISO fit (``tolerance.Toleranced``,
#: a float equal to the mean play that also knows its spread).
Play = Annotated[float, PlainValidator(parse_play), AfterValidator(_non_negative), _PLAY_SCHEMA]
#: A drive's angular play (rad): an angle, a length at a radius, or limits.
AngularPlay = Annotated[
    float, PlainValidator(parse_angular_play), AfterValidator(_non_negative), _ANGULAR_PLAY_SCHEMA
]
PositiveLength = Annotated[
    float, BeforeValidator(_scalar("length")), AfterValidator(_positive), _quantity("length")
]
Point = Annotated[Vec3, BeforeValidator(_vector("length")), _vector_of("length")]
Direction = Annotated[
    Vec3,
    BeforeValidator(_vector("length")),
    AfterValidator(_nonzero_vector),
    _vector_of("length"),
]
#: A load's vectors: a component may vary in Monte Carlo studies (kept as a
#: ``Toleranced``) or over the motion (a ``DriveTable``), hence a plain
#: validator: a before-validator's float subclass would be turned into a float.
ForceVector = Annotated[
    Vec3, PlainValidator(_vector("force", scatter=True)), _vector_of("force", scatter=True)
]
TorqueVector = Annotated[
    Vec3, PlainValidator(_vector("torque", scatter=True)), _vector_of("torque", scatter=True)
]
NonNegativeMass = Annotated[
    float, BeforeValidator(_scalar("mass")), AfterValidator(_non_negative), _quantity("mass")
]


_NUMBER_ONLY = re.compile(NUMBER_FIRST.removeprefix(r"^\s*"))


def _with_units(value: Any) -> Any:
    """Gravity's components carry their unit: a plain number would be mm/s^2,
    so the -9.81 everyone writes would be a thousandth of the weight."""
    if isinstance(value, list | tuple):
        for i, component in enumerate(value):
            nonzero_number = (
                isinstance(component, int | float)
                and not isinstance(component, bool)
                and component != 0  # an int of any size: no conversion to float
            )
            if isinstance(component, str) and _NUMBER_ONLY.fullmatch(component.strip()):
                nonzero_number = float(component) != 0.0  # a number written as text
            if nonzero_number:
                raise ValueError(
                    f"component {'xyz'[i] if i < 3 else i}: a plain number ({shown(component)}) "
                    'would be mm/s^2; write the unit, e.g. [0, 0, "-9.81 m/s^2"] '
                    "(0 may stay a plain number)"
                )
    return value


#: Gravity: each nonzero component with its unit (see ``_with_units``).
_GRAVITY_COMPONENT: dict[str, Any] = {
    "anyOf": [{"const": 0}, {"type": "string", "pattern": NUMBER_FIRST}],
    "description": "an acceleration with its unit, e.g. '-9.81 m/s^2' (0 may be a plain number)",
}
AccelerationVector = Annotated[
    Vec3,
    BeforeValidator(_vector("acceleration")),
    BeforeValidator(_with_units),
    WithJsonSchema(_vector_schema(_GRAVITY_COMPONENT)),
]
PositiveTorsionalStiffness = Annotated[
    float,
    BeforeValidator(_scalar("torsional_stiffness")),
    AfterValidator(_positive),
    _quantity("torsional_stiffness"),
]
PositiveStiffness = Annotated[
    float,
    BeforeValidator(_scalar("stiffness")),
    AfterValidator(_stiff_enough),
    _quantity("stiffness"),
]
