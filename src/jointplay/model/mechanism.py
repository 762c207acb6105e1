"""The mechanism: bodies, joints and loads, frozen and validated.

A ``Model`` is plain data. It never holds solver state or results; the
solver builds its own workspace from it (see ``assembly.py``).
"""

from __future__ import annotations

import difflib
import math
from collections import deque
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Annotated, Any, Literal

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    StrictBool,
    field_serializer,
    model_validator,
)

from jointplay.geometry import FloatArray
from jointplay.model.deviations import (
    MOTION_WORDS,
    MeasuredDeviation,
    SharedDeviation,
    Zones,
    mean_components,
    transport,
)
from jointplay.model.fields import (
    AccelerationVector,
    Direction,
    ForceVector,
    Name,
    NonNegativeMass,
    Point,
    PositiveLength,
    TorqueVector,
)
from jointplay.model.joints import JOINT_TYPES, Joint
from jointplay.model.joints.base import Coordinate
from jointplay.model.motion import DIMENSION, MotionSection, coordinate_of, no_unit, range_of
from jointplay.model.tables import DriveTable
from jointplay.model.tolerance import ANGULAR_PLAYS, Toleranced, play_unit
from jointplay.units import shown

if TYPE_CHECKING:
    AnyJoint = Joint
else:
    from typing import Union

    AnyJoint = Annotated[
        Union[tuple(JOINT_TYPES.values())],  # noqa: UP007 - built from the registry
        Field(discriminator="type"),
    ]


class EntryError(ValueError):
    """A model-level problem that belongs to one entry (``joints[1] 'l2'``)."""

    def __init__(self, entry: str, problem: str):
        self.entry = entry
        self.problem = problem
        super().__init__(f"{entry}: {problem}")


class EntryProblemsError(ValueError):
    """Several model-level problems, each belonging to one entry."""

    def __init__(self, errors: list[EntryError]):
        self.errors = errors
        super().__init__("; ".join(str(e) for e in errors))


def suggest(word: str, candidates: Iterable[str]) -> str:
    """' Did you mean 'x'?' for a likely typo, else ''."""
    if len(word) > 100:  # not a typo, and difflib is slow on long words
        return ""
    close = difflib.get_close_matches(word, list(candidates), n=1, cutoff=0.5)
    return f" Did you mean '{close[0]}'?" if close else ""


def listing(names: Iterable[str], most: int = 10) -> str:
    """'a, b, c' for a message, cut after ``most`` names: 'a, b, ... (and 990 more)'."""
    names = list(names)
    text = ", ".join(names[:most])
    return text + (f", ... (and {len(names) - most} more)" if len(names) > most else "")


def unknown_body(field: str, body: str, bodies: Sequence[str]) -> str:
    """The problem of a ``field`` that names a body the model does not have
    (the same words whether the rest of the file reads or not)."""
    return f"{field}: unknown body '{body}'; bodies are: {listing(bodies)}." + suggest(body, bodies)


def unknown_point(point: str, points: Sequence[str]) -> str:
    """The problem of a requirement on a point the model does not have."""
    known = (
        f"points are: {listing(points)}"
        if points
        else "the model has no 'points' section; add the point there"
    )
    return f"point: unknown point '{point}'; {known}." + suggest(point, points)


def unknown_shared_deviation(shared: str, names: Sequence[str]) -> str:
    """The problem of a joint that takes a shared deviation the model does not have."""
    known = listing(f"'{n}'" for n in names) if names else "none"
    return (
        f"deviation: unknown shared deviation '{shared}'; the 'deviations' section has "
        f"{known}." + suggest(shared, names)
    )


def unknown_deviation_body(body: str, bodies: Sequence[str]) -> str:
    """The problem of a shared deviation made on a body the model does not have."""
    return (
        f"body: there is no body '{body}'; the bodies are "
        + listing(f"'{b}'" for b in bodies)
        + "."
        + suggest(body, bodies)
    )


def _schema_one(value: Any) -> Any:
    if value != 1 or not isinstance(value, int) or isinstance(value, bool):
        raise ValueError(
            f"this is schema version 1; got {shown(value)}. Write 'schema: 1' or leave it out"
        )
    return value


#: A play at least this share of its joint's size is warned about: real plays
#: are below a few percent of it, and "200" meant as 200 um reads as 200 mm.
LARGE_PLAY_SHARE = 0.1
#: A play below this share of the model's size is refused: double precision
#: carries 16 digits and the solver resolves a contact to about 1e-4 of its
#: play, so a smaller play cannot be told from 0 next to the model's lengths
#: (and a subnormal one overflows the scaled program). 0 means no play.
SMALLEST_PLAY_SHARE = 1e-12


class Body(BaseModel):
    """A rigid body. Ground bodies do not move; every other body gets a torsor."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: Name
    ground: StrictBool = False
    mass: NonNegativeMass | None = (
        None  # kg; with the model's gravity, a weight at the centre of mass
    )
    center_of_mass: Point | None = None  # mm, global
    #: Corners drawn for the body in figures (mm, global, at rest), joined in
    #: order and closed; two points draw a bar. Without it the body is drawn
    #: as the shortest tree through its joints and points.
    outline: tuple[Point, ...] | None = None

    @model_validator(mode="after")
    def _check_mass(self) -> Body:
        if self.mass is not None and self.center_of_mass is None:
            raise ValueError("a body with a 'mass' needs its 'center_of_mass: [x, y, z]' (mm)")
        if self.center_of_mass is not None and self.mass is None:
            raise ValueError("'center_of_mass' is given without a 'mass'; add 'mass' (kg)")
        if self.outline is not None:
            if self.ground:
                raise ValueError(
                    "a ground body is not drawn, so its 'outline' would be ignored; remove it"
                )
            if len(self.outline) < 2:
                raise ValueError(
                    "'outline' needs at least two points, [[x, y, z], [x, y, z], ...] (mm)"
                )
        return self


class FunctionalPoint(BaseModel):
    """A point of a body whose displacement the result reports (a tool tip, say)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: Name
    body: Name
    at: Point


class Requirement(BaseModel):
    """A functional requirement: the point's displacement stays within
    ``max_displacement`` (its size, or its component ``along`` a direction)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    point: Name
    max_displacement: PositiveLength
    along: Direction | None = None

    def describe(self) -> str:
        what = "|displacement|" if self.along is None else f"displacement along {list(self.along)}"
        return f"point '{self.point}': {what} <= {self.max_displacement:g} mm"

    def measure(self, displacement: Any) -> Any:
        """What the requirement bounds, in mm: the length of the point's
        displacement, or the size of its component ``along``; on (..., 3)
        arrays of displacements (global, mm), one value per row."""
        d = np.asarray(displacement, dtype=float)
        if self.along is None:
            return np.linalg.norm(d, axis=-1)
        u = np.asarray(self.along, dtype=float)
        return np.abs(d @ (u / np.linalg.norm(u)))


@dataclass(frozen=True)
class LoadRange:
    """A load component given as a range: ``Load.ranges``."""

    key: Literal["force", "torque"]
    index: int
    value: Toleranced
    direction: tuple[float, float, float]


class Load(BaseModel):
    """A force at a point of a body, a torque on a body, or both."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    body: Name
    at: Point | None = None
    force: ForceVector | None = None
    torque: TorqueVector | None = None
    #: A load that always acts, as the weights do (a preload: a spring, a clamp):
    #: an envelope's probes push against it. Every solve takes every load alike.
    standing: bool = False
    #: Through a motion (``motion``), the load's point moves with its body; its
    #: force and torque keep their global directions ("global"), or turn with
    #: the body ("body").
    follows: Literal["global", "body"] = "global"
    #: At a motion's pose, a load that follows its body holds its components
    #: turned to global axes (their means, for a range); its ranges are kept
    #: here, each with the global direction it now acts along (``ranges``).
    _turned_ranges: tuple[LoadRange, ...] | None = PrivateAttr(default=None)

    def ranges(self) -> tuple[LoadRange, ...]:
        """The components given as a range (``{min, max}``): ``(key, index,
        range, direction)``, ``key`` "force" or "torque", ``direction`` the
        global axis the component acts along (the body's axis it was given
        in, at a motion's pose, for a load that follows its body)."""
        if self._turned_ranges is not None:
            return self._turned_ranges
        out = []
        for key in ("force", "torque"):
            for c, value in enumerate(getattr(self, key) or ()):
                if isinstance(value, Toleranced):
                    axis = [0.0, 0.0, 0.0]
                    axis[c] = 1.0
                    out.append(LoadRange(key, c, value, (axis[0], axis[1], axis[2])))
        return tuple(out)

    @model_validator(mode="after")
    def _check(self) -> Load:
        if self.force is None and self.torque is None:
            raise ValueError("a load needs a 'force' (with 'at') or a 'torque', or both")
        if self.force is not None and self.at is None:
            raise ValueError("a force needs its point of application: add 'at: [x, y, z]' (mm)")
        return self


class Model(BaseModel):
    """A mechanism with clearances: schema v1 of the model file."""

    model_config = ConfigDict(frozen=True, extra="forbid", populate_by_name=True)

    schema_version: Annotated[Literal[1], BeforeValidator(_schema_one)] = Field(1, alias="schema")
    name: str | None = None
    description: str | None = None
    bodies: tuple[Body, ...] = Field(min_length=1)
    joints: tuple[AnyJoint, ...] = Field(min_length=1)
    loads: tuple[Load, ...] = ()
    load_cases: dict[Name, tuple[Load, ...]] | None = None
    gravity: AccelerationVector | None = None  # mm/s^2 as plain numbers; "9.81 m/s^2"
    points: tuple[FunctionalPoint, ...] = ()
    requirements: tuple[Requirement, ...] = ()
    #: Deviations shared by several joints' features (``deviations.SharedDeviation``).
    deviations: tuple[SharedDeviation, ...] = ()
    #: The large motion the mechanism is driven through (``jointplay motion``).
    motion: MotionSection | None = None
    #: The deviations measured on the part this model is (``with_deviations``).
    _measured: tuple[MeasuredDeviation, ...] = PrivateAttr(default=())

    @field_serializer("gravity")
    def _gravity_with_its_unit(self, gravity: tuple[float, float, float] | None) -> Any:
        """Written back with its unit, as a file must give it (``fields._with_units``)."""
        if gravity is None:
            return None
        return [c if c == 0 else f"{c!r} mm/s^2" for c in gravity]

    @model_validator(mode="after")
    def _check_topology(self) -> Model:
        """Every problem across entries, listed together (``EntryProblemsError``)."""
        found: list[EntryError] = []
        names = [b.name for b in self.bodies]
        body_set = set(names)  # a list's `in` made a 10,000-body model's check take 3 s
        found += _check_unique(names, "bodies", "body")
        found += _check_unique([j.name for j in self.joints], "joints", "joint")
        unknown_between = False
        grounds = {b.name for b in self.bodies if b.ground}
        if not grounds:
            found.append(
                EntryError(
                    "bodies",
                    "no ground body; mark the fixed body with 'ground: true' "
                    f"(bodies are: {listing(names)})",
                )
            )
        for i, joint in enumerate(self.joints):
            entry = f"joints[{i}] '{joint.name}'"
            a, b = joint.between
            for body in (a, b):
                if body not in body_set:
                    unknown_between = True
                    found.append(EntryError(entry, unknown_body("between", body, names)))
            if a == b:
                found.append(
                    EntryError(
                        entry, f"between: the joint goes from body '{a}' to itself; name two bodies"
                    )
                )
            if a in grounds and b in grounds:
                found.append(
                    EntryError(
                        entry,
                        f"between: both '{a}' and '{b}' are ground bodies, so the joint "
                        "constrains nothing; connect a moving body",
                    )
                )
        sections = [(f"loads[{i}]", load) for i, load in enumerate(self.loads)]
        for case, loads in (self.load_cases or {}).items():
            sections += [(f"load_cases.{case}[{i}]", load) for i, load in enumerate(loads)]
        for entry, load in sections:
            if load.body not in body_set:
                found.append(EntryError(entry, unknown_body("body", load.body, names)))
            if load.body in grounds:
                found.append(
                    EntryError(
                        entry,
                        f"body: '{load.body}' is a ground body, which does not move, so the load "
                        "does nothing; put it on a moving body",
                    )
                )
        if self.load_cases is not None and not self.load_cases:
            found.append(
                EntryError("load_cases", "no cases given; name at least one case, or leave it out")
            )
        found += _check_unique([p.name for p in self.points], "points", "point")
        for i, point in enumerate(self.points):
            if point.body not in body_set:
                found.append(
                    EntryError(
                        f"points[{i}] '{point.name}'", unknown_body("body", point.body, names)
                    )
                )
        point_names = [p.name for p in self.points]
        for i, req in enumerate(self.requirements):
            if req.point not in point_names:
                found.append(
                    EntryError(f"requirements[{i}]", unknown_point(req.point, point_names))
                )
        found += _check_smallest_plays(self)
        found += _check_shared_deviations(self)
        found += _check_motion(self)
        found += _check_load_tables(self, sections)
        # with no ground, or a joint to an unknown body, it would only repeat those
        unreached = (
            _unreached_from_ground(names, grounds, [j.between for j in self.joints])
            if grounds and not unknown_between
            else []
        )
        if unreached:
            found.append(
                EntryError(
                    "bodies",
                    "no chain of joints connects "
                    + listing(f"'{n}'" for n in unreached)
                    + " to a ground body; add a joint, or mark the body 'ground: true'",
                )
            )
        if len(found) == 1:
            raise found[0]
        if found:
            raise EntryProblemsError(found)
        return self

    @cached_property
    def moving_bodies(self) -> tuple[Body, ...]:
        return tuple(b for b in self.bodies if not b.ground)

    @property
    def case_names(self) -> tuple[str, ...]:
        """The load cases, in file order (empty when the model has none)."""
        return tuple(self.load_cases or ())

    def weights(self) -> tuple[Load, ...]:
        """Gravity on each moving body with a mass: m * g at its centre of mass (N)."""
        if self.gravity is None:
            return ()
        out = []
        for b in self.moving_bodies:
            if b.mass and b.center_of_mass is not None:
                # kg * mm/s^2 = 1e-3 N
                gx, gy, gz = self.gravity
                force = (1e-3 * b.mass * gx, 1e-3 * b.mass * gy, 1e-3 * b.mass * gz)
                # built from validated values: no second validation (and its limits)
                out.append(Load.model_construct(body=b.name, at=b.center_of_mass, force=force))
        return tuple(out)

    def loads_of(self, case: str | None = None) -> tuple[Load, ...]:
        """Every load acting in ``case``: the top-level loads (which act in every
        case), the weights, and the case's own loads."""
        own: tuple[Load, ...] = ()
        if case is not None:
            if case not in (self.load_cases or {}):
                cases = self.case_names
                raise KeyError(
                    f"no load case {shown(case)}; cases are: {listing(cases) or '(none)'}."
                    + suggest(case, cases)
                )
            own = (self.load_cases or {})[case]
        return self.loads + self.weights() + own

    @property
    def measured(self) -> tuple[MeasuredDeviation, ...]:
        """The deviations measured on the part (``with_deviations``), as given."""
        return self._measured

    @property
    def warnings(self) -> tuple[str, ...]:
        """What the model says that is legal but likely a slip: no loads at all
        (everything stays at 0), or a play large against its joint (a value
        meant in um, written as mm); and a measured deviation outside its
        zone (a rejected part, measured to see what it does)."""
        out = []
        if not any(self.loads_of(case) for case in (self.case_names or (None,))):
            out.append(
                "the model has no loads (no 'loads', no load cases, no weight): nothing "
                "pushes the parts, so every displacement and force is 0"
            )
        centres = np.array([j.at for j in self.joints], dtype=float)
        extent = float(np.linalg.norm(centres.max(axis=0) - centres.min(axis=0)))
        for joint in self.joints:
            # its own size (a bore's length, a face's width), else the mechanism's extent
            size, what = (
                (joint.size, "its size")
                if joint.size > 0.0
                else (extent, "the diagonal of the box around the joints")
            )
            if size <= 0.0:
                continue
            for field, play in joint.plays().items():
                length = joint.play_length(field, play)
                if length >= LARGE_PLAY_SHARE * size:
                    degrees = f" ({math.degrees(play):.3g} deg)" if field in ANGULAR_PLAYS else ""
                    out.append(
                        f"joint '{joint.name}': {field} {play:g} {play_unit(field)}{degrees} is "
                        f"{length / size:.3g} times {what} ({size:g} mm)"
                        + (
                            f" at its lever ({joint.play_length(field, 1.0):g} mm)"
                            if field in ANGULAR_PLAYS
                            else ""
                        )
                        + f"; a play is usually a small part of it: if {play:g} was meant in "
                        + (
                            f"degrees, write '{play:g} deg'"
                            if field in ANGULAR_PLAYS
                            else f"um, write '{play:g} um'"
                        )
                    )
        out += [m.warning for m in self._measured if m.warning is not None]
        return tuple(out)

    def deviation_sources(self) -> tuple[DeviationSource, ...]:
        """Every deviation, a joint's own or shared, with the joints it moves."""
        out = []
        shared = {d.name: d for d in self.deviations}
        users: dict[str, list[int]] = {name: [] for name in shared}
        for jdx, joint in enumerate(self.joints):
            if joint.deviation is not None and joint.deviation.shared is not None:
                users.setdefault(joint.deviation.shared, []).append(jdx)
            elif joint.deviation is not None:
                ball = joint.type_name == "spherical"
                frame = (joint.frame(), np.asarray(joint.at, dtype=float))
                own = DeviationSource(joint.name, joint.deviation, *frame, (jdx,), (1.0,), ball)
                out.append(own)
        for name, dev in shared.items():
            at = np.asarray(dev.at, dtype=float)
            joints = tuple(users[name])
            # the group's features are on ``body``: a joint's deviation is its a-side's
            # features minus its b-side's, so a joint with the group on its b side
            # takes it with the sign turned
            signs = tuple(-1.0 if self.joints[j].between[1] == dev.body else 1.0 for j in joints)
            out.append(DeviationSource(name, dev, dev.R, at, joints, signs, dev.axis is None))
        return tuple(out)

    def motion_drive(self) -> tuple[Joint, Coordinate, float, float]:
        """The motion's drive: its joint, its coordinate and its range (rad or
        mm); ``KeyError`` if the model has no ``motion`` section."""
        if self.motion is None:
            raise KeyError("motion")
        joint = self.joint(self.motion.drive)
        kind = coordinate_of(joint, *self.motion.range)
        return (joint, kind, *range_of(self.motion, kind, joint_type=joint.type_name))

    def body(self, name: str) -> Body:
        for b in self.bodies:
            if b.name == name:
                return b
        raise KeyError(name)

    def joint(self, name: str) -> Joint:
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(name)

    def replace(self, **changes: Any) -> Model:
        """A new validated model with some top-level fields changed."""
        data = self.model_dump(by_alias=True, exclude_none=True)
        data.update(changes)
        out = Model.model_validate(data)
        if not {"joints", "deviations"} & set(changes):  # still the measured part
            out._measured = self._measured
        return out


@dataclass(frozen=True)
class DeviationSource:
    """One deviation (a joint's own, or shared: ``label`` names it) in its
    frame ``R`` at ``at``, and the joints it moves (model order)."""

    label: str
    deviation: Zones
    R: FloatArray
    at: FloatArray
    joints: tuple[int, ...]
    signs: tuple[float, ...]  # per joint: +1 if the features are on its a side
    ball: bool  # a diameter is a ball (else a disc across the frame's x)

    def torsor_at(self, jdx: int, joint: Joint) -> FloatArray:
        """(6, 6): this deviation's torsor as joint ``jdx`` sees it (at its
        centre, in its frame, a's features minus b's)."""
        T = transport(self.R, self.at, joint.frame(), np.asarray(joint.at, dtype=float))
        return self.signs[self.joints.index(jdx)] * T


def _check_shared_deviations(model: Model) -> list[EntryError]:
    """Shared deviations: named by a joint, their names known, and every
    direction they move taken by some contact of each joint, none rigid."""
    found: list[EntryError] = []
    names = [d.name for d in model.deviations]
    found += _check_unique(names, "deviations", "deviation")
    used = set()
    for i, joint in enumerate(model.joints):
        shared = None if joint.deviation is None else joint.deviation.shared
        if shared is not None:
            used.add(shared)
            if shared not in names:
                found.append(
                    EntryError(
                        f"joints[{i}] '{joint.name}'", unknown_shared_deviation(shared, names)
                    )
                )
    joints = {joint.name for joint in model.joints}
    bodies = [body.name for body in model.bodies]
    for k, dev in enumerate(model.deviations):
        entry = f"deviations[{k}] '{dev.name}'"
        if names.count(dev.name) > 1:
            continue  # its name is taken twice: said above (_check_unique)
        if dev.name in joints:
            found.append(
                EntryError(
                    entry,
                    f"name: '{dev.name}' is also a joint's name; give the shared deviation a "
                    "name of its own (studies and --deviations call each by its name)",
                )
            )
            continue
        if dev.body not in bodies:
            found.append(EntryError(entry, unknown_deviation_body(dev.body, bodies)))
            continue
        if dev.name not in used:
            found.append(
                EntryError(entry, "no joint names it; give joints 'deviation: " + dev.name + "'")
            )
            continue
        source = next(s for s in model.deviation_sources() if s.deviation is dev)
        axes = [a for z in dev.zones(source.ball) for a in z.axes]
        seen = [(model.joints[j], source.torsor_at(j, model.joints[j])) for j in source.joints]
        outside = [model.joints[j] for j in source.joints]
        outside = [joint for joint in outside if dev.body not in joint.between]
        if outside:
            found.append(
                EntryError(
                    entry,
                    f"body: the features are made on '{dev.body}', but joint "
                    f"'{outside[0].name}' is between {list(outside[0].between)}; give the "
                    "body that carries the features, one side of every joint that names it",
                )
            )
            continue
        problems = [
            problem
            for joint, T in seen
            for move in [dev.mean(), *np.eye(6)[axes]]
            if (problem := joint.rigid_problem(T @ move))
        ]
        unseen = [a for a in axes if not any(joint.takes(T[:, a]) for joint, T in seen)]
        if unseen:
            problems.append(
                f"a {MOTION_WORDS[unseen[0]]} of its frame moves none of the contacts of its "
                "joints (they leave that motion free); leave it out"
            )
        idle = [
            a
            for a in mean_components(dev.mean())
            if not any(joint.takes(T[:, a]) for joint, T in seen)
        ]
        if idle:
            problems.append(
                f"its mean is a {MOTION_WORDS[idle[0]]} of its frame, which moves none of the "
                "contacts of its joints (they leave that motion free); leave that component out"
            )
        found += [EntryError(entry, problem) for problem in problems[:1]]
    return found


def _check_motion(model: Model) -> list[EntryError]:
    """The ``motion`` section: its drive is a joint with a spin or a slide,
    its range in that coordinate's unit."""
    motion = model.motion
    if motion is None:
        return []
    names = [j.name for j in model.joints]
    if motion.drive not in names:
        return [
            EntryError(
                "motion",
                f"drive: unknown joint '{motion.drive}'; joints are: {listing(names)}."
                + suggest(motion.drive, names),
            )
        ]
    try:
        model.motion_drive()
    except ValueError as exc:
        return [EntryError("motion", str(exc))]
    return []


def _check_load_tables(model: Model, sections: list[tuple[str, Load]]) -> list[EntryError]:
    """A load's table over the drive's value: the model has a motion, the
    table's first column is in the drive's unit, and its rows reach over the
    motion's range."""
    found = []
    for entry, load in sections:
        for key in ("force", "torque"):
            for i, table in enumerate(getattr(load, key) or ()):
                if not isinstance(table, DriveTable):
                    continue
                where = f"{key}: component {'xyz'[i]}: table"
                if model.motion is None:
                    found.append(
                        EntryError(
                            entry,
                            f"{where}: a table is read against the drive's value, and the model "
                            "has no 'motion' section; add motion: {drive: JOINT, range: "
                            "['0 deg', '360 deg']}, or give the component as a number",
                        )
                    )
                    continue
                try:
                    joint, coordinate, start, stop = model.motion_drive()
                except (KeyError, ValueError):
                    continue  # the motion section's own message says what is wrong
                dimension = DIMENSION[coordinate]
                unit = "deg" if coordinate == "spin" else "mm"
                if coordinate == "spin" and table.plain is not None:
                    row, x, y = table.plain
                    fix = f"[{shown(f'{str(x).strip()} deg')}, {shown(y)}]"
                    found.append(
                        EntryError(
                            entry,
                            f"{where} row {row}: the drive's value {no_unit(x, joint.name, fix)}",
                        )
                    )
                    continue
                if table.dimension not in (None, dimension):
                    found.append(
                        EntryError(
                            entry,
                            f"{where}: its drive's values are {table.dimension}s, but the drive "
                            f"'{joint.name}' is a {coordinate} (its value {_article(dimension)}); "
                            f"give them in {unit}",
                        )
                    )
                    continue
                low, high = min(start, stop), max(start, stop)
                if table.drive[0] > low or table.drive[-1] < high:
                    show = _shown_in(coordinate)
                    found.append(
                        EntryError(
                            entry,
                            f"{where}: its rows run from {show(table.drive[0])} to "
                            f"{show(table.drive[-1])}, but the motion runs from {show(start)} "
                            f"to {show(stop)}; extend the table over the motion's range",
                        )
                    )
    return found


def _shown_in(coordinate: Coordinate) -> Any:
    """A drive's value (rad or mm) as written: '90 deg' or '25 mm'."""
    if coordinate == "spin":
        return lambda v: f"{math.degrees(v):g} deg"
    return lambda v: f"{v:g} mm"


def _article(dimension: str) -> str:
    return f"{'an' if dimension[0] in 'aeiou' else 'a'} {dimension}"


def check_case(model: Model, case: str | None, source: str, study: str | None = None) -> None:
    """An ``OptionError`` naming the cases unless ``case`` is None or one of
    them. ``study`` (a study's name, "the Monte Carlo study"): that study is
    under one load case, so a model with load cases needs ``case`` (the
    top-level loads alone are none of its cases)."""
    if case is None:
        if study is not None and model.case_names:
            from jointplay.errors import OptionError

            raise OptionError(
                f"--case: the model has load cases ({listing(model.case_names)}): give "
                f"--case NAME (case=NAME in Python), the load case {study} is under",
                source=source,
            )
        return
    if not model.case_names:
        from jointplay.errors import OptionError

        raise OptionError(
            f"--case: no load case {shown(case)}; the model has none (no 'load_cases' "
            "section): leave --case out",
            source=source,
        )
    try:
        model.loads_of(case)
    except KeyError as exc:
        from jointplay.errors import OptionError

        raise OptionError(f"--case: {exc.args[0]}", source=source) from None


def _check_smallest_plays(model: Model) -> list[EntryError]:
    """Plays too small to resolve against the model's size (``SMALLEST_PLAY_SHARE``)."""
    spots = [j.at for j in model.joints]
    loads = [*model.loads, *(ld for case in (model.load_cases or {}).values() for ld in case)]
    spots += [ld.at for ld in loads if ld.at is not None]
    spots += [p.at for p in model.points]
    spots += [b.center_of_mass for b in model.bodies if b.center_of_mass is not None]
    P = np.array(spots, dtype=float).reshape(-1, 3)
    extent = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))) if len(P) else 0.0
    size = max([extent, *(j.size for j in model.joints)])
    found = []
    for i, joint in enumerate(model.joints):
        for field, play in joint.plays().items():
            if not play:
                continue
            # a play that varies: its largest value (a part may have any play in its range)
            most, what = (
                (play.high, f"up to {play.high:g} {play_unit(field)}")
                if isinstance(play, Toleranced)
                else (float(play), f"{play:g} {play_unit(field)}")
            )
            if joint.play_length(field, most) < SMALLEST_PLAY_SHARE * size:
                found.append(
                    EntryError(
                        f"joints[{i}] '{joint.name}'",
                        f"{field}: {what} is less than {SMALLEST_PLAY_SHARE:g} of the "
                        f"model's size ({size:g} mm), too small to tell from 0 in double "
                        "precision; write 0 for no play, or the real play "
                        + ("('0.1 deg')" if field in ANGULAR_PLAYS else "('2 um')"),
                    )
                )
    return found


def _check_unique(names: list[str], section: str, what: str) -> list[EntryError]:
    seen: dict[str, int] = {}
    out = []
    for i, n in enumerate(names):
        if n in seen:
            out.append(
                EntryError(
                    f"{section}[{i}]",
                    f"duplicate {what} name '{n}' (also {section}[{seen[n]}]); give each "
                    f"{what} its own name",
                )
            )
        else:
            seen[n] = i
    return out


def _unreached_from_ground(
    names: list[str], grounds: set[str], edges: list[tuple[str, str]]
) -> list[str]:
    neighbours: dict[str, set[str]] = {n: set() for n in names}
    for a, b in edges:
        neighbours[a].add(b)
        neighbours[b].add(a)
    seen = set(grounds)
    queue = deque(grounds)
    while queue:
        for nxt in neighbours[queue.popleft()]:
            if nxt not in seen:
                seen.add(nxt)
                queue.append(nxt)
    return [n for n in names if n not in seen]
