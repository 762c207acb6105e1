"""The ``motion`` section of a model file: which joint drives the mechanism
through its large motion, over which range, in how many steps.

``motion: {drive: motor, range: ["0 deg", "360 deg"], steps: 73}``

The drive is a coordinate of one joint: the spin of a revolute or
cylindrical joint (an angle), or the slide of a prismatic or cylindrical
joint (a length). A cylindrical joint's coordinate is told by the range's
unit ("deg" or "mm"). The drive's value is measured from the pose written in
the file: 0 is that pose. The range's values are read here as written; the
model checks them against the drive's joint (``check_motion``): a plain
number is mm for a slide, as every length, but is refused for a spin (save
0): a user who writes 90 there means degrees, and it would be read as rad.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    StrictFloat,
    StrictInt,
    StrictStr,
    field_validator,
)

from jointplay.settings import MOST_MOTION_STEPS
from jointplay.units import is_plain, shown, to_base, without_plain_hint

if TYPE_CHECKING:
    from jointplay.model.joints.base import Joint

#: A drive's coordinate: the spin about the joint's axis, or the slide along it.
Coordinate = Literal["spin", "slide"]
#: What each coordinate is measured in, as the model reads units.
DIMENSION: dict[str, str] = {"spin": "angle", "slide": "length"}
#: The most steps a motion may have (each is a solve).
MOST_STEPS = MOST_MOTION_STEPS
#: The fewest: the range's two ends.
FEWEST_STEPS = 2
#: A range as the file writes it.
RANGE_EXAMPLE = "['0 deg', '360 deg']"


def steps_problem(steps: int) -> str | None:
    """What is wrong with ``steps`` steps (None: nothing), with the fix."""
    if steps < FEWEST_STEPS:
        return f"give at least {FEWEST_STEPS} steps: the range's start and stop are both steps"
    if steps > MOST_STEPS:
        return f"give at most {MOST_STEPS:,} steps (each step is a solve)"
    return None


def no_unit(value: Any, joint: str, fix: str) -> str:
    """A spin's value written without a unit (the range's or a load table's):
    what is wrong and ``fix``, the value as the user wrote it with a unit."""
    return (
        f"{shown(value)} has no unit; the spin of joint '{joint}' is an angle, and a plain "
        f"number would be read as radians: give a unit, {fix} (or 'rad' if radians are meant)"
    )


class MotionSection(BaseModel):
    """``motion``: the drive, its range (start, stop) and the number of steps
    (both ends included)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    drive: StrictStr = Field(min_length=1)
    range: tuple[StrictFloat | StrictInt | StrictStr, StrictFloat | StrictInt | StrictStr]
    steps: StrictInt = Field(73, ge=FEWEST_STEPS, le=MOST_STEPS)

    @field_validator("range", mode="before")
    @classmethod
    def _two_ends(cls, value: Any) -> Any:
        if isinstance(value, str):
            raise ValueError(
                f"expected a list [START, STOP], got the text {shown(value)}; give the range "
                f"as [START, STOP], e.g. {RANGE_EXAMPLE}"
            )
        if isinstance(value, list | tuple) and len(value) != 2:
            raise ValueError(
                f"a range needs START and STOP, got {shown(list(value))}; e.g. {RANGE_EXAMPLE}"
            )
        return value

    @field_validator("steps", mode="before")
    @classmethod
    def _step_count(cls, value: Any) -> Any:
        if isinstance(value, int) and not isinstance(value, bool):
            problem = steps_problem(value)
            if problem is not None:
                raise ValueError(f"got {value}; {problem}")
        return value


def plain_angle(value: Any) -> bool:
    """A spin's value written without a unit, and not 0 (0 is 0 in any unit)."""
    if not is_plain(value):
        return False
    try:
        return float(value) != 0.0
    except (ValueError, OverflowError):
        return True


#: How errors name the range's ends, the range and the drive: the file's
#: motion section's entries, or the command line's options.
FILE_NAMES = ("range[0]", "range[1]", "range", "drive")
OPTION_NAMES = ("--range START", "--range STOP", "--range", "--drive")


def suggested_range(start: Any, stop: Any, unit: str, option: bool) -> str:
    """The range as the user gave it, its plain numbers with ``unit``."""
    ends = [
        f"{str(value).strip()} {unit}" if is_plain(value) else str(value) for value in (start, stop)
    ]
    if option:
        return f"--range '{ends[0]}:{ends[1]}'"
    return f"range: ['{ends[0]}', '{ends[1]}']"


def coordinate_of(
    joint: Joint, start: Any, stop: Any, names: tuple[str, str, str, str] = FILE_NAMES
) -> Coordinate:
    """Which coordinate of ``joint`` a range of ``start``, ``stop`` drives;
    ``ValueError`` with the fix where the joint cannot be driven so."""
    kinds: tuple[Coordinate, ...] = type(joint).drivable
    if not kinds:
        raise ValueError(
            f"{names[3]}: joint '{joint.name}' is a {joint.type_name} joint, which has no spin or "
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
        f"{names[2]}: joint '{joint.name}' is cylindrical, so its spin or its slide may be "
        "driven; give the range with its unit, "
        + (
            "--range '0 deg:360 deg' for the spin or --range '0 mm:50 mm' for the slide"
            if names is OPTION_NAMES
            else "['0 deg', '360 deg'] for the spin or ['0 mm', '50 mm'] for the slide"
        )
        + f" (got {shown([start, stop])})"
    )


def range_of(
    section: MotionSection,
    coordinate: Coordinate,
    names: tuple[str, str, str, str] = FILE_NAMES,
    joint_type: str = "",
) -> tuple[float, float]:
    """The range in the coordinate's base unit (rad or mm); ``ValueError``
    naming the end that does not read (as ``names`` call the ends) and what
    the drive of the joint (of type ``joint_type``) takes."""
    out = []
    for i, value in enumerate(section.range):
        if coordinate == "spin" and plain_angle(value):
            fix = suggested_range(*section.range, "deg", names is OPTION_NAMES)
            raise ValueError(f"{names[i]}: {no_unit(value, section.drive, fix)}")
        try:
            out.append(to_base(value, DIMENSION[coordinate]))
        except ValueError as exc:
            told = without_plain_hint(str(exc), "angle") if coordinate == "spin" else exc
            kind, example = (
                ("an angle", "'90 deg'") if coordinate == "spin" else ("a length (mm)", "'25 mm'")
            )
            joint = f"{joint_type} joint" if joint_type else "joint"
            raise ValueError(
                f"{names[i]}: {told}; the drive of {joint} '{section.drive}' is its "
                f"{coordinate}, which takes {kind}, such as {example}"
            ) from None
    if out[0] == out[1]:
        raise ValueError(
            f"{names[2]}: starts and stops at {shown(section.range[0])}; give two different values"
        )
    return out[0], out[1]
