"""Validated field types for the model: quantities with units, vectors, names.

Each type accepts a plain number (in the base unit of its dimension) or a
string with units, and fails with an "expected ..., got ..." message.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Annotated, Any

from pydantic import AfterValidator, BeforeValidator, StringConstraints

from .units import to_base

Vec3 = tuple[float, float, float]


def _scalar(dimension: str) -> Callable[[Any], float]:
    def parse(value: Any) -> float:
        return to_base(value, dimension)

    return parse


def _vector(dimension: str) -> Callable[[Any], Vec3]:
    def parse(value: Any) -> Vec3:
        if isinstance(value, str | bytes) or not hasattr(value, "__len__") or len(value) != 3:
            raise ValueError(
                f"expected a list of 3 components [x, y, z] ({dimension}), got {value!r}"
            )
        out = []
        for i, component in enumerate(value):
            try:
                out.append(to_base(component, dimension))
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


def _nonzero_vector(value: Vec3) -> Vec3:
    if math.hypot(*value) == 0.0:
        raise ValueError("expected a nonzero direction, got [0, 0, 0]")
    return value


Name = Annotated[str, StringConstraints(strict=True, min_length=1, strip_whitespace=True)]
Length = Annotated[float, BeforeValidator(_scalar("length"))]
NonNegativeLength = Annotated[
    float, BeforeValidator(_scalar("length")), AfterValidator(_non_negative)
]
PositiveLength = Annotated[float, BeforeValidator(_scalar("length")), AfterValidator(_positive)]
Point = Annotated[Vec3, BeforeValidator(_vector("length"))]
Direction = Annotated[Vec3, BeforeValidator(_vector("length")), AfterValidator(_nonzero_vector)]
ForceVector = Annotated[Vec3, BeforeValidator(_vector("force"))]
TorqueVector = Annotated[Vec3, BeforeValidator(_vector("torque"))]
NonNegativeMass = Annotated[float, BeforeValidator(_scalar("mass")), AfterValidator(_non_negative)]
AccelerationVector = Annotated[Vec3, BeforeValidator(_vector("acceleration"))]
PositiveStiffness = Annotated[
    float, BeforeValidator(_scalar("stiffness")), AfterValidator(_positive)
]
