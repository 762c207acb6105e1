"""Validated field types for the model: quantities with units, vectors, names.

Each type accepts a plain number (in the base unit of its dimension) or a
string with units, and fails with an "expected ..., got ..." message.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any

from pydantic import AfterValidator, BeforeValidator, PlainValidator, StringConstraints

from jointplay.model.tolerance import parse_play, parse_scattered
from jointplay.units import shown, to_base

Vec3 = tuple[float, float, float]


def _scalar(dimension: str) -> Callable[[Any], float]:
    def parse(value: Any) -> float:
        return to_base(value, dimension)

    return parse


def _vector(dimension: str, scatter: bool = False) -> Callable[[Any], Vec3]:
    """``scatter``: a component may be ``{min, max, distribution}`` (a load
    that varies in a Monte Carlo study; see ``tolerance.parse_scattered``)."""

    def read(component: Any) -> float:
        return parse_scattered(component, dimension) if scatter else to_base(component, dimension)

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


#: Names appear in every message and report: one printable line, at most 100 characters.
Name = Annotated[
    str,
    StringConstraints(strict=True, min_length=1, max_length=100, strip_whitespace=True),
    AfterValidator(_plain_name),
]
Length = Annotated[float, BeforeValidator(_scalar("length"))]
NonNegativeLength = Annotated[
    float, BeforeValidator(_scalar("length")), AfterValidator(_non_negative)
]
#: A joint's play: a length, or limits / an ISO fit (``tolerance.Toleranced``,
#: a float equal to the mean play that also knows its spread).
Play = Annotated[float, PlainValidator(parse_play), AfterValidator(_non_negative)]
PositiveLength = Annotated[float, BeforeValidator(_scalar("length")), AfterValidator(_positive)]
Point = Annotated[Vec3, BeforeValidator(_vector("length"))]
Direction = Annotated[Vec3, BeforeValidator(_vector("length")), AfterValidator(_nonzero_vector)]
#: A load's vectors: a component may vary in Monte Carlo studies (kept as a
#: ``Toleranced``, hence a plain validator: a before-validator's float
#: subclass would be turned into a float).
ForceVector = Annotated[Vec3, PlainValidator(_vector("force", scatter=True))]
TorqueVector = Annotated[Vec3, PlainValidator(_vector("torque", scatter=True))]
NonNegativeMass = Annotated[float, BeforeValidator(_scalar("mass")), AfterValidator(_non_negative)]
AccelerationVector = Annotated[Vec3, BeforeValidator(_vector("acceleration"))]
PositiveStiffness = Annotated[
    float, BeforeValidator(_scalar("stiffness")), AfterValidator(_stiff_enough)
]
