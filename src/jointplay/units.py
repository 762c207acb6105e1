"""Quantities with units.

Plain numbers are millimetres, newtons, newton-millimetres and radians. Any
number may instead be a string with units (``"400 um"``, ``"4 cm"``,
``"1 N*m"``), converted with pint. The registry is built on first use only,
because building it takes a noticeable fraction of a second.

A string is read as a number followed by a unit expression (names, ``*``,
``/``, ``^`` or ``**`` with a small exponent, parentheses). It is checked
before pint sees it: pint evaluates what it parses as arithmetic, so a
string such as ``"10**10**10 mm"`` would otherwise compute a number with ten
billion digits and never return.
"""

from __future__ import annotations

import math
import re
import reprlib
import sys
from functools import cache, lru_cache
from typing import Any

#: The unit that a plain number means, per physical dimension.
BASE_UNITS: dict[str, str] = {
    "length": "mm",
    "force": "N",
    "torque": "N*mm",
    "angle": "rad",
    "stiffness": "N/mm",
    "torsional_stiffness": "N*mm/rad",
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
    "torsional_stiffness": "'50 N*m/deg' or '3e6 N*mm/rad'",
    "mass": "'2 kg' or '300 g'",
    "acceleration": "'9.81 m/s^2'",
}

#: The largest magnitude accepted, per dimension, in the base unit: far beyond
#: any mechanism (1 km, 1 GN, a thousand tonnes, 1000 g), so that a value above
#: it is a slip (a unit, an exponent) or hostile. It keeps products and squares
#: of the inputs finite, and the ratio of a model's size to its plays within
#: what double precision resolves (a joint 1e9 mm away from one 200 mm away
#: leaves the cone solver unable to certify).
LIMITS: dict[str, float] = {
    "length": 1e6,
    "force": 1e9,
    "torque": 1e12,
    "angle": 1e3,
    "stiffness": 1e12,
    "torsional_stiffness": 1e15,
    "mass": 1e6,
    "acceleration": 1e7,
}

#: Short reprs of user values in messages: a message stays one short paragraph
#: even for a huge list or a long string.
_SHORT = reprlib.Repr()
_SHORT.maxstring = 60
_SHORT.maxother = 60
_SHORT.maxlong = 30
_SHORT.maxlist = _SHORT.maxtuple = _SHORT.maxdict = _SHORT.maxset = 4
_SHORT.maxlevel = 3


def shown(value: Any) -> str:
    """``repr(value)``, shortened for an error message."""
    try:
        return _SHORT.repr(value)
    except Exception:  # a repr that fails (an int too long to print, say)
        return f"a {type(value).__name__}"


@cache
def _pint() -> Any:
    """pint, imported on first use. At import it looks for Dask (to handle
    Dask arrays, which we never give it), and importing Dask takes 0.2 s: it
    is hidden from pint for that moment, unless something imported it already."""
    hide = "dask" not in sys.modules
    if hide:
        sys.modules["dask"] = None  # type: ignore[assignment]  # import dask -> ImportError
    try:
        import pint
    finally:
        if hide:
            del sys.modules["dask"]
    return pint


@cache
def _registry() -> Any:
    """pint's registry, its definitions parsed once and kept in the user's
    cache folder (pint's own cache: 0.05 s to load instead of 0.4 s to build);
    built afresh where no cache folder can be written."""
    pint = _pint()
    try:
        return pint.UnitRegistry(cache_folder=":auto:")
    except Exception:  # no writable cache folder, or a cache pint cannot read
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
        try:
            number = float(value)
        except OverflowError:  # an int beyond the float range
            number = math.inf
    elif isinstance(value, str):
        number = _parse(value, dimension)
    else:
        raise ValueError(_expected(dimension, value))
    if not math.isfinite(number):
        raise ValueError(
            f"expected a finite {dimension.replace('_', ' ')}, got {shown(value)}; write a "
            f"number of at most {LIMITS[dimension]:g} {unit}"
        )
    if abs(number) > LIMITS[dimension]:
        raise ValueError(
            f"expected {_a(dimension)} of at most {LIMITS[dimension]:g} {unit} in size, got "
            f"{shown(value)} ({number:g} {unit}); check the value and its unit"
        )
    return number + 0.0  # -0.0 -> 0.0


_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


class UnderflowError(ValueError):
    """A number's text that double precision reads as 0 though it is not."""


def read_number(text: str) -> float:
    """The float of a number's text, refusing one that underflows to 0 (a
    zero play would silently make its joint ideal)."""
    value = float(text)
    if value == 0.0 and any(c in "123456789" for c in text.lower().split("e")[0]):
        raise UnderflowError(
            f"{shown(text)} is too small for double precision and would read as 0; write 0 "
            "if you mean none, or a value of at least 1e-300"
        )
    return value


def is_plain(value: Any) -> bool:
    """A number written without a unit (``90``, ``"90"``)."""
    if isinstance(value, str):
        try:
            read_number(value.strip())
        except ValueError:
            return False
        return True
    return isinstance(value, int | float) and not isinstance(value, bool)


#: What a quantity written as text looks like (the model file's JSON Schema):
#: a number first, then its unit (or nothing: the base unit).
NUMBER_FIRST = r"^\s*" + _NUMBER.pattern
#: 0x10, 0o17, 0b11: numerals with a base prefix, not a number and a unit.
_PREFIXED = re.compile(r"[+-]?0[xXoObB][0-9a-fA-F_]+(?=\s|$)")
_NOT_FINITE = re.compile(r"[+-]?\.?(?:inf|infinity|nan)\b", re.IGNORECASE)
_TOKEN = re.compile(r"\s*(\*\*|[*/^()·]|[^\W\d]\w*|\d+(?:\.\d+)?|-|\S)")
#: Longest unit expression read; longer is not a unit.
_MAX_UNIT = 60


def _parse(text: str, dimension: str) -> float:
    stripped = text.strip()
    number = _NUMBER.match(stripped)
    if number is not None and number.end() == len(stripped):
        return read_number(stripped)  # "0.2": a plain number in the base unit
    if _NOT_FINITE.match(stripped):
        return math.inf
    if number is None:
        raise ValueError(
            f"expected {_a(dimension)}, got {shown(text)}, which does not start with a number; "
            f"{_hint(dimension)}"
        )
    if _PREFIXED.match(stripped):
        raise ValueError(
            f"{shown(text)} is a hexadecimal, octal or binary numeral, which YAML 1.1, YAML "
            "1.2 and JSON read differently; write the number in plain decimal"
        )
    expression = stripped[number.end() :].strip()
    factor = _factor(expression, dimension)
    if isinstance(factor, tuple):
        before, after = factor
        raise ValueError(f"{before}{shown(text)}{after}")
    value = read_number(number.group()) * factor
    if value == 0.0 and float(number.group()) != 0.0:
        raise ValueError(
            f"{shown(text)} is too small for double precision in "
            f"{BASE_UNITS[dimension]} and would read as 0; write 0 if you mean none"
        )
    return value


@lru_cache(maxsize=1024)
def _factor(expression: str, dimension: str) -> float | tuple[str, str]:
    """How many base units one ``expression`` is; or, when it is not a unit of
    ``dimension``, the message as the parts before and after the value.
    Cached: a file repeats its few units thousands of times, and pint takes
    a tenth of a millisecond for each."""
    cannot = ("cannot read ", f" as {_a(dimension)}; {_hint(dimension)}")
    if not _is_unit_expression(expression):
        return cannot
    pint = _pint()
    registry = _registry()
    try:
        parsed = registry.parse_units(expression)
    except pint.errors.UndefinedUnitError as exc:
        names = ", ".join(f"'{n}'" for n in getattr(exc, "unit_names", ()) or ())
        what = f" ({names} is not a unit)" if names else ""
        return ("unknown unit in ", f"{what}; {_hint(dimension)}")
    except Exception:  # pint's parser raises assorted errors on garbage
        return cannot
    quantity = registry.Quantity(1.0, parsed)
    base = BASE_UNITS[dimension]
    reference = registry.Quantity(1.0, base)
    # pint counts angles as dimensionless: compare the powers of the radian as well,
    # so that "2 percent" is no angle and "0.5 deg" no length
    turns = (_radians(quantity), _radians(reference))
    if quantity.dimensionality != reference.dimensionality or turns[0] != turns[1]:
        if quantity.dimensionality == reference.dimensionality and not quantity.dimensionless:
            kind = f"a unit whose angle differs from {base}'s"
        elif quantity.dimensionless and not turns[0]:  # pint's "dimensionless" angles are angles
            kind = (
                f"dimensionless (a bare number means the base unit; a unit must be {_a(dimension)})"
            )
        else:
            # the name of a dimension the model takes elsewhere (a force where a
            # length is due), else pint's own words
            named = [
                name.replace("_", " ")
                for name, unit in BASE_UNITS.items()
                if registry.Quantity(1.0, unit).dimensionality == quantity.dimensionality
                and _radians(registry.Quantity(1.0, unit)) == turns[0]
            ]
            kind = _a(named[0]) if named else f"a {quantity.dimensionality}"
        return (f"expected {_a(dimension)}, got ", f", which is {kind}; {_hint(dimension)}")
    try:
        return float(quantity.to(base).magnitude)
    except Exception:  # an offset unit (degC)
        return cannot


def _radians(quantity: Any) -> float:
    """The power of the radian in ``quantity``'s unit (deg, arcmin: 1; percent: 0)."""
    return float(dict(quantity.to_base_units().units._units).get("radian", 0))


def _is_unit_expression(expression: str) -> bool:
    """Whether ``expression`` is unit names joined by ``*``, ``/``, ``·`` or spaces,
    with small exponents (``^2``, ``**-1``, ``^0.5``) and balanced parentheses."""
    if not expression or len(expression) > _MAX_UNIT:
        return False
    tokens = _TOKEN.findall(expression)
    if "".join(tokens) != "".join(expression.split()):
        return False
    depth = 0
    previous = ""  # "name" (a unit or ")"), "op", "power", "exp" or "" at the start
    i = 0
    while i < len(tokens):
        token = tokens[i]
        if token in ("**", "^"):
            if previous != "name":
                return False
            i += 1
            if i < len(tokens) and tokens[i] == "-":
                i += 1
            if i >= len(tokens) or not re.fullmatch(r"\d{1,2}(?:\.\d{1,3})?", tokens[i]):
                return False
            previous = "exp"
        elif token in ("*", "/", "·"):
            if previous not in ("name", "exp"):
                return False
            previous = "op"
        elif token == "(":
            depth += 1
            if depth > 4 or previous in ("name", "exp"):
                return False
            previous = "op"
        elif token == ")":
            depth -= 1
            if depth < 0 or previous not in ("name", "exp"):
                return False
            previous = "name"
        elif re.fullmatch(r"[^\W\d]\w*", token):
            previous = "name"  # side by side, names multiply ("N mm")
        else:
            return False
        i += 1
    return depth == 0 and previous in ("name", "exp")


def _hint(dimension: str) -> str:
    return (
        f"write a plain number in {BASE_UNITS[dimension]} or a string with units "
        f"such as {UNIT_EXAMPLES[dimension]}"
    )


def without_plain_hint(message: str, dimension: str) -> str:
    """``message`` with its hint asking for units only: where a plain number is
    refused (a spin's range), the hint must not offer one."""
    return message.replace(
        _hint(dimension), f"write it with its unit, such as {UNIT_EXAMPLES[dimension]}"
    )


def _expected(dimension: str, value: Any) -> str:
    return f"expected {_a(dimension)}, got {shown(value)}; {_hint(dimension)}"


def _a(dimension: str) -> str:
    """'a length', 'an acceleration', 'a torsional stiffness'."""
    return f"{'an' if dimension[0] in 'aeiou' else 'a'} {dimension.replace('_', ' ')}"
