"""Quantities with units.

Plain numbers are millimetres, newtons, newton-millimetres and radians. Any
number may instead be a string with units (``"400 um"``, ``"4 cm"``,
``"1 N*m"``), converted with pint. The registry is built on first use only,
because building it takes a noticeable fraction of a second.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

#: The unit that a plain number means, per physical dimension.
BASE_UNITS: dict[str, str] = {
    "length": "mm",
    "force": "N",
    "torque": "N*mm",
    "angle": "rad",
    "stiffness": "N/mm",
    "mass": "kg",
    "acceleration": "mm/s^2",
}

#: Examples shown in error messages.
UNIT_EXAMPLES: dict[str, str] = {
    "length": "'0.2 mm', '400 um' or '4 cm'",
    "force": "'10 N' or '2 kN'",
    "torque": "'1 N*m' or '500 N*mm'",
    "angle": "'0.5 deg' or '1 mrad'",
    "stiffness": "'2e5 N/mm' or '200 N/um'",
    "mass": "'2 kg' or '300 g'",
    "acceleration": "'9.81 m/s^2'",
}


@cache
def _registry() -> Any:
    import pint

    return pint.UnitRegistry()


def to_base(value: Any, dimension: str) -> float:
    """Return ``value`` as a float in the base unit of ``dimension``.

    Raises ``ValueError`` with an "expected ..., got ..." message, which the
    model validation turns into a message that names the file and entry.
    """
    unit = BASE_UNITS[dimension]
    if isinstance(value, bool) or value is None:
        raise ValueError(_expected(dimension, value))
    if isinstance(value, int | float):
        number = float(value)
    elif isinstance(value, str):
        number = _parse(value, dimension, unit)
    else:
        raise ValueError(_expected(dimension, value))
    if not math.isfinite(number):
        raise ValueError(f"expected a finite {dimension}, got {value!r}")
    return number


def _parse(text: str, dimension: str, unit: str) -> float:
    import pint

    registry = _registry()
    stripped = text.strip()
    try:
        quantity = registry.Quantity(stripped)
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError) as exc:
        raise ValueError(f"unknown unit in {text!r} ({exc}); {_hint(dimension)}") from exc
    except Exception as exc:  # pint's parser raises assorted errors on garbage
        raise ValueError(f"cannot read {text!r} as a {dimension}; {_hint(dimension)}") from exc
    if not isinstance(quantity, registry.Quantity):  # a bare number in a string
        return float(quantity)
    if quantity.unitless:  # "5": a plain number in the base unit
        return float(quantity.magnitude)
    try:
        return float(quantity.to(unit).magnitude)
    except pint.errors.DimensionalityError as exc:
        raise ValueError(
            f"expected a {dimension}, got {text!r}, which is a {quantity.dimensionality}; "
            f"{_hint(dimension)}"
        ) from exc


def _hint(dimension: str) -> str:
    return (
        f"write a plain number in {BASE_UNITS[dimension]} or a string with units "
        f"such as {UNIT_EXAMPLES[dimension]}"
    )


def _expected(dimension: str, value: Any) -> str:
    return f"expected a {dimension}, got {value!r}; {_hint(dimension)}"
