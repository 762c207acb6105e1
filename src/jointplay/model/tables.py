"""A load's component as a table over the drive's value (``motion``).

``force: [{table: [["0 deg", -1500], ["180 deg", -200], ["360 deg", -1500]]}, 0, 0]``:
the first column is the drive's value (an angle for a spin, a length for a
slide; a plain number is mm, and refused for a spin but 0, as the motion's
range reads), the second
the component in the load's unit; between rows the component is linear in
the drive's value. A ``DriveTable`` is a float equal to the component at the
drive's 0 (the pose written in the file), which a plain solve uses; the
motion reads it at each step (``DriveTable.at``). The model checks the first
column's unit and the rows' reach against its motion (``check_tables``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from jointplay.units import BASE_UNITS, is_plain, shown, to_base

#: The first column's dimension, by how its values are written.
DRIVE_DIMENSIONS = ("angle", "length")
EXAMPLE = "{table: [['0 deg', -1500], ['180 deg', -200], ['360 deg', -1500]]}"


class DriveTable(float):
    """A load's component (N or N*mm) linear in the drive's value between
    rows; as a float, its value at the drive's 0."""

    drive: tuple[float, ...]  # rad or mm, increasing
    value: tuple[float, ...]  # N or N*mm
    dimension: str | None  # "angle" or "length" as written with units; None: plain numbers
    unit: str
    #: the first row whose drive's value (not 0) is written without a unit, as
    #: (row, drive's value, value) as written: mm for a slide, refused for a spin
    plain: tuple[int, Any, Any] | None

    def __new__(
        cls,
        drive: tuple[float, ...],
        value: tuple[float, ...],
        dimension: str | None,
        unit: str,
        plain: tuple[int, Any, Any] | None = None,
    ) -> DriveTable:
        self = super().__new__(cls, float(np.interp(0.0, drive, value)))
        for name, v in (("drive", drive), ("value", value), ("dimension", dimension)):
            object.__setattr__(self, name, v)
        object.__setattr__(self, "unit", unit)
        object.__setattr__(self, "plain", plain)
        return self

    def __reduce__(self) -> tuple[Any, ...]:  # pickled whole (to worker processes)
        return (DriveTable, (self.drive, self.value, self.dimension, self.unit, self.plain))

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("a DriveTable is immutable")

    def __repr__(self) -> str:
        return f"DriveTable({list(zip(self.drive, self.value, strict=True))!r} {self.unit})"

    def at(self, drive: float) -> float:
        """The component at the drive's value ``drive`` (rad or mm)."""
        return float(np.interp(drive, self.drive, self.value))


def is_table(value: Any) -> bool:
    return isinstance(value, Mapping) and "table" in value


def parse_table(value: Mapping[str, Any], dimension: str) -> DriveTable:
    """``{table: [[drive, value], ...]}`` read as a ``DriveTable``;
    ``ValueError`` naming the row and the fix."""
    unknown = sorted(map(str, set(value) - {"table"}))
    if unknown:
        raise ValueError(f"unknown key {shown(unknown[0])} beside 'table'; write {EXAMPLE}")
    rows = value["table"]
    if not isinstance(rows, list | tuple) or len(rows) < 2:
        raise ValueError(
            f"table: expected at least 2 rows [drive, value], got {shown(rows)}; write {EXAMPLE}"
        )
    drive: list[float] = []
    values: list[float] = []
    dimensions: set[str] = set()
    plain: tuple[int, Any, Any] | None = None
    for i, row in enumerate(rows):
        if not isinstance(row, list | tuple) or len(row) != 2:
            raise ValueError(
                f"table row {i}: expected [drive, value], got {shown(row)}; write {EXAMPLE}"
            )
        x, y = row
        if is_plain(x):
            try:
                drive.append(to_base(x, "length"))  # mm, or refused for a spin (check_tables)
            except ValueError as exc:
                raise ValueError(f"table row {i}: the drive's value: {exc}") from None
            if plain is None and drive[-1] != 0.0:
                plain = (i, x, y)
        elif isinstance(x, str):
            for kind in DRIVE_DIMENSIONS:
                try:
                    drive.append(to_base(x, kind))
                except ValueError:
                    continue
                dimensions.add(kind)
                break
            else:
                raise ValueError(
                    f"table row {i}: the drive's value {shown(x)} is neither an angle "
                    "('90 deg') nor a length ('25 mm')"
                )
        else:
            raise ValueError(
                f"table row {i}: the drive's value {shown(x)} is neither an angle "
                "('90 deg') nor a length ('25 mm')"
            )
        try:
            values.append(to_base(y, dimension))
        except ValueError as exc:
            raise ValueError(f"table row {i}: the value: {exc}") from None
    if len(dimensions) > 1:
        raise ValueError(
            "table: the drive's values mix angles and lengths; give them all in the drive's "
            "unit (an angle for a spin, a length for a slide)"
        )
    if plain is not None and "angle" in dimensions:
        # a plain number (mm) beside angles: a unit left out, which the model
        # names against its drive (check_tables); the rows' order means nothing yet
        return DriveTable(tuple(drive), tuple(values), "angle", BASE_UNITS[dimension], plain)
    for i in range(1, len(drive)):
        if not drive[i] > drive[i - 1]:
            raise ValueError(
                f"table row {i}: the drive's value {shown(rows[i][0])} does not follow "
                f"{shown(rows[i - 1][0])}; give the rows in increasing order of the drive's value"
            )
    if not drive[0] <= 0.0 <= drive[-1]:
        raise ValueError(
            f"table: its rows run from {rows[0][0]} to {rows[-1][0]}, but a solve "
            "of the pose written in the file reads it at the drive's 0; extend it to 0"
        )
    return DriveTable(
        tuple(drive),
        tuple(values),
        dimensions.pop() if dimensions else None,
        BASE_UNITS[dimension],
        plain,
    )


def table_schema(dimension: str, quantity: dict[str, Any]) -> dict[str, Any]:
    """The JSON Schema of ``{table: [[drive, value], ...]}``."""
    drive = {
        "anyOf": [{"type": "number"}, {"type": "string"}],
        "description": "the drive's value: an angle ('90 deg') for a spin, a length ('25 mm') "
        "for a slide; a plain number is mm (refused for a spin, but 0)",
    }
    return {
        "type": "object",
        "properties": {
            "table": {
                "type": "array",
                "minItems": 2,
                "items": {
                    "type": "array",
                    "prefixItems": [drive, quantity],
                    "minItems": 2,
                    "maxItems": 2,
                },
            }
        },
        "required": ["table"],
        "additionalProperties": False,
        "description": f"a {dimension} linear in the drive's value between the rows "
        "[drive, value] (a model with a 'motion')",
    }
