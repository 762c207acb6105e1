"""The ``motion`` section of a model file: which joint drives the mechanism
through its large motion, over which range, in how many steps.

``motion: {drive: motor, range: ["0 deg", "360 deg"], steps: 73}``

The drive is a coordinate of one joint: the spin of a revolute or
cylindrical joint (an angle), or the slide of a prismatic or cylindrical
joint (a length). A cylindrical joint's coordinate is told by the range's
unit ("deg" or "mm"). The drive's value is measured from the pose written in
the file: 0 is that pose. The range's values are read here as written; the
model checks them against the drive's joint (``check_motion``), since a plain
number means rad for a spin and mm for a slide.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictFloat, StrictInt, StrictStr

from jointplay.units import shown, to_base

if TYPE_CHECKING:
    from jointplay.model.joints.base import Joint

#: A drive's coordinate: the spin about the joint's axis, or the slide along it.
Coordinate = Literal["spin", "slide"]
#: What each coordinate is measured in, as the model reads units.
DIMENSION: dict[str, str] = {"spin": "angle", "slide": "length"}
#: The most steps a motion may have (each is a solve).
MOST_STEPS = 100_000


class MotionSection(BaseModel):
    """``motion``: the drive, its range (start, stop) and the number of steps
    (both ends included)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    drive: StrictStr = Field(min_length=1)
    range: tuple[StrictFloat | StrictInt | StrictStr, StrictFloat | StrictInt | StrictStr]
    steps: StrictInt = Field(73, ge=2, le=MOST_STEPS)


def coordinate_of(joint: Joint, start: Any, stop: Any) -> Coordinate:
    """Which coordinate of ``joint`` a range of ``start``, ``stop`` drives;
    ``ValueError`` with the fix where the joint cannot be driven so."""
    kinds: tuple[Coordinate, ...] = type(joint).drivable
    if not kinds:
        raise ValueError(
            f"drive: joint '{joint.name}' is a {joint.type_name} joint, which has no spin or "
            "slide to drive; name a revolute or cylindrical joint (its spin) or a prismatic "
            "or cylindrical joint (its slide)"
        )
    if len(kinds) == 1:
        return kinds[0]
    for kind in kinds:  # a cylindrical joint: told by the range's unit
        try:
            for value in (start, stop):
                if not isinstance(value, str):
                    raise ValueError("a plain number")
                to_base(value, DIMENSION[kind])
        except ValueError:
            continue
        return kind
    raise ValueError(
        f"range: joint '{joint.name}' is cylindrical, so its spin or its slide may be driven; "
        f"give the range with its unit, ['0 deg', '360 deg'] for the spin or ['0 mm', "
        f"'50 mm'] for the slide (got {shown([start, stop])})"
    )


def range_of(section: MotionSection, coordinate: Coordinate) -> tuple[float, float]:
    """The range in the coordinate's base unit (rad or mm); ``ValueError``
    naming the end that does not read."""
    out = []
    for i, value in enumerate(section.range):
        try:
            out.append(to_base(value, DIMENSION[coordinate]))
        except ValueError as exc:
            kind, example = (
                ("an angle", "'90 deg'") if coordinate == "spin" else ("a length", "'25 mm'")
            )
            raise ValueError(
                f"range[{i}]: {exc}; the {coordinate} of joint '{section.drive}' is {kind}, "
                f"such as {example}"
            ) from None
    if out[0] == out[1]:
        raise ValueError(
            f"range: starts and stops at {shown(section.range[0])}; give two different values"
        )
    return out[0], out[1]
