"""What every joint type shares: its frame, and the contract to name its contacts.

A joint between bodies ``a`` and ``b`` limits the small displacement of b
relative to a. That relative torsor is written at the joint centre, in the
joint frame (x = the joint axis), as a 6-vector ``tau = (t, w)``: ``t`` the
relative translation of the centre, ``w`` the relative rotation. The point at
local position ``p`` moves by ``delta(p) = t + w x p``.

Each joint type turns ``tau`` into its *contacts*: named clearance cones
``|| rows @ tau || + offset @ tau <= radius`` (a ball of the play, in 1, 2
or 3 directions, when there is no offset; a one-sided limit ``offset @ tau
<= radius`` when there are no rows; a tilting face in between), or fixed
rows ``rows @ tau = 0``. Nothing else about the joint reaches the solver, so
a new joint type is one new module in this package.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache, cached_property
from typing import Any, ClassVar, Literal, NamedTuple, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, model_validator

from jointplay.geometry import FloatArray, is_parallel, joint_frame, left_jacobian_inverse, skew
from jointplay.model.deviations import MOTION_WORDS, Deviation, mean_components
from jointplay.model.fields import Direction, Name, Play, Point, PositiveStiffness, with_values
from jointplay.model.tolerance import PLAY_FIELDS
from jointplay.settings import DEFAULT

ContactKind = Literal["ball", "fixed"]
#: A cone's vector part (k,) and scalar part.
Parts = tuple[FloatArray, float]

IntArray = NDArray[np.intp]

#: A drive's coordinate (``model.motion``): the spin about the axis, or the slide along it.
Coordinate = Literal["spin", "slide"]


class Holder(NamedTuple):
    """What holds a coordinate a joint type leaves free (where the type takes
    it): its field, what it is, the verb of the coordinate, a phrase for
    messages and an example value."""

    field: str
    role: str
    verb: str
    words: str
    example: str


#: The play that holds each coordinate, for every message that advises it.
HOLDS: dict[Coordinate, Holder] = {
    "spin": Holder(
        "backlash", "a drive", "turn", "the play of a drive that holds its spin",
        'backlash: "0.2 deg"',
    ),
    "slide": Holder(
        "axial_clearance", "", "move", "its play along its axis", 'axial_clearance: "50 um"'
    ),
}  # fmt: skip


@dataclass(frozen=True)
class Ideal:
    """One scalar equation of a joint's ideal (play-free) constraint, exact in
    finite rotations, on the placement of b relative to a in a's joint frame
    (the frame and centre carried by a, ``u_a[k]``; the centre carried by b,
    ``c_b``):

    - ``Ideal("offset", k)``: ``u_a[k] . (c_b - c_a) = 0``, the centre's
      offset along the joint's axis k stays 0;
    - ``Ideal("axes", j, k)``: ``u_a[j] . u_b[k] = 0``, b's axis k keeps no
      component along a's axis j (``R_rel[j, k] = 0``).

    At the pose written in the file every one is 0; ``jointplay.motion``
    closes them through the motion."""

    kind: Literal["offset", "axes"]
    k: int
    j: int = 0


#: The ideal equations of common joints (``Joint.ideal``).
CENTRES_MEET = (Ideal("offset", 0), Ideal("offset", 1), Ideal("offset", 2))
#: b's axis x keeps no component across a's (R_rel[1, 0] = R_rel[2, 0] = 0).
AXES_PARALLEL = (Ideal("axes", k=0, j=1), Ideal("axes", k=0, j=2))
#: With the axes parallel, b's y axis keeps off a's z (R_rel[2, 1] = 0): no spin.
NO_SPIN = (Ideal("axes", k=1, j=2),)

#: Registered joint classes by their ``type`` name, filled by subclassing.
JOINT_TYPES: dict[str, type[Joint]] = {}


@dataclass(frozen=True)
class Contact:
    """One clearance cone of a joint, in the joint frame.

    ``kind == "ball"``: ``|| rows @ tau || + offset @ tau <= radius`` (mm);
    the contact touches when the left side reaches the radius. ``kind ==
    "fixed"``: ``rows @ tau == 0``. ``point`` is where the contact acts, in
    joint-frame coordinates relative to the joint centre (mm).

    The contact's dual is a force ``lam`` (N) with a vector ``f`` in the row
    space, ``|f| <= lam``; it acts on b with the wrench ``-(rows.T @ f + lam
    * offset)`` (force, moment at the centre). For a face that may tilt, the
    centre of pressure moves with the force: it is ``point + lever @ f / lam``.
    """

    name: str
    kind: ContactKind
    rows: FloatArray
    radius: float
    point: FloatArray
    offset: FloatArray | None = None  # (6,): a face's normal row; None for a plain ball
    lever: FloatArray | None = None  # (3, k): where the centre of pressure goes
    #: The contact's own spring (N/mm at its rows' scale); None: the joint's ``stiffness``.
    stiffness: float | None = None
    #: A contact that limits a rotation (a drive): the lever (mm) by which its
    #: rows turn the angle into a length. None: a contact of lengths.
    turn_lever: float | None = None

    @property
    def one_sided(self) -> bool:
        """A limit with no rows: ``offset @ tau <= radius`` (a point on a plane)."""
        return self.offset is not None and self.rows.shape[0] == 0

    def exact_parts(self, R_rel: FloatArray, phi: FloatArray, t_rel: FloatArray) -> Parts:
        """The cone's vector and scalar parts ``(rows @ tau, offset @ tau)``
        for a *finite* relative placement of b in a's joint frame: the point
        at p goes to ``R_rel @ p + t_rel``; ``phi`` is ``R_rel``'s rotation vector.

        Rows are those of the displacement of the contact's point,
        ``rows = [S, -S [point]x]`` (``point_rows``), plus rows of the
        rotation itself (a rigid joint); the exact parts put the exact
        displacement ``d = R_rel @ point + t_rel - point`` in ``S`` and
        ``phi`` in the rotation rows. A contact that is not a point's
        overrides this (the disc face)."""
        p = self.point
        d = t_rel + R_rel @ p - p
        turn = skew(p)

        def part(row: FloatArray) -> FloatArray:
            return np.asarray(row[..., :3] @ d + (row[..., 3:] + row[..., :3] @ turn) @ phi)

        scalar = 0.0 if self.offset is None else float(part(self.offset))
        return part(self.rows), scalar

    def exact_jacobian(self, R_rel: FloatArray, phi: FloatArray, t_rel: FloatArray) -> FloatArray:
        """(k + 1, 6): derivative of ``exact_parts`` (vector rows, then the
        scalar) with respect to a virtual twist of b in a's joint frame,
        ``(dt at the centre, dtheta)``. Its transpose turns the contact's dual
        into the wrench on b (force, moment about the centre)."""
        p = self.point
        q = R_rel @ p + t_rel
        d_point = np.hstack([np.eye(3), -skew(q)])  # the point's displacement
        d_phi = np.hstack([np.zeros((3, 3)), left_jacobian_inverse(phi)])
        turn = skew(p)
        offset = np.zeros(6) if self.offset is None else self.offset
        rows = np.vstack([self.rows, offset])
        return np.asarray(rows[:, :3] @ d_point + (rows[:, 3:] + rows[:, :3] @ turn) @ d_phi)

    def exact_level(self, R_rel: FloatArray, phi: FloatArray, t_rel: FloatArray) -> float:
        """``|a| + b`` of ``exact_parts``: compare with ``radius``."""
        vector, scalar = self.exact_parts(R_rel, phi, t_rel)
        return float(np.linalg.norm(vector)) + scalar

    def acting_point(self, f: FloatArray, lam: float) -> FloatArray:
        """Where the force acts (joint frame, mm), given its dual ``(lam, f)``."""
        if self.lever is None or lam <= 0.0:
            return self.point
        return self.point + self.lever @ (np.asarray(f) / lam)


def _moves(c: Contact, move: FloatArray, scale: float) -> bool:
    """Whether ``move`` changes contact ``c``'s rows or its face's limit."""
    return bool(np.any(np.abs(c.rows @ move) > scale)) or (
        c.offset is not None and abs(float(c.offset @ move)) > scale
    )


def _motion_words(move: FloatArray) -> str:
    """'shift along y and tilt about z': the components of a small torsor."""
    scale = DEFAULT.round_off * float(np.max(np.abs(move), initial=0.0))
    return " and ".join(MOTION_WORDS[int(a)] for a in np.flatnonzero(np.abs(move) > scale))


def point_rows(p: FloatArray, directions: str = "xyz") -> FloatArray:
    """Rows of ``delta(p) = t + w x p = [I, -[p]x] @ tau`` for the chosen joint axes."""
    px, py, pz = (float(c) for c in p)
    rows = {
        "x": (1.0, 0.0, 0.0, 0.0, pz, -py),
        "y": (0.0, 1.0, 0.0, -pz, 0.0, px),
        "z": (0.0, 0.0, 1.0, py, -px, 0.0),
    }
    return np.array([rows[axis] for axis in directions]).reshape(-1, 6)


def point_rows_of(points: FloatArray, directions: str = "xyz") -> FloatArray:
    """``point_rows`` of many points at once, entry for entry: (N, 3) -> (N,
    len(directions), 6)."""
    ones, entries, coordinate, sign = _point_row_entries(directions)
    p = np.asarray(points, dtype=float)
    out = np.zeros((len(p), len(directions) * 6))  # the rows one after another
    out[:, ones] = 1.0
    out[:, entries] = p[:, coordinate] * sign  # times +-1: exactly p or -p
    return out.reshape(len(p), len(directions), 6)


def centred_balls_of(
    name: str, directions: str, clearances: Sequence[float]
) -> list[tuple[Contact, ...]]:
    """One ball at each joint's centre (a spherical joint's, a sphere in a
    cylinder's), radius half its clearance, over ``directions``: the
    contacts of many joints at once."""
    centres = np.zeros((len(clearances), 3))
    rows = point_rows_of(centres, directions)
    radius = (np.array(clearances, dtype=float) / 2).tolist()
    return [
        (Contact(name, "ball", r, play, centre),)
        for r, play, centre in zip(list(rows), radius, list(centres), strict=True)
    ]


@cache
def _point_row_entries(directions: str) -> tuple[IntArray, IntArray, IntArray, FloatArray]:
    """Where ``point_rows``' entries go in its rows laid one after another:
    each row's 1, and its two entries of ``-[p]x`` (place, coordinate of p, sign)."""
    entries = {
        "x": (0, (4, 2, 1.0), (5, 1, -1.0)),  # (1, 0, 0, 0, pz, -py)
        "y": (1, (3, 2, -1.0), (5, 0, 1.0)),  # (0, 1, 0, -pz, 0, px)
        "z": (2, (3, 1, 1.0), (4, 0, -1.0)),  # (0, 0, 1, py, -px, 0)
    }
    if any(axis not in entries for axis in directions):
        raise ValueError(f"point_rows: directions {directions!r} are not all of x, y, z")
    chosen = [entries[axis] for axis in directions]
    pairs = [
        (6 * row + col, c, sign) for row, (_, *two) in enumerate(chosen) for col, c, sign in two
    ]
    return (
        np.array([6 * row + one for row, (one, *_) in enumerate(chosen)], dtype=np.intp),
        np.array([place for place, _, _ in pairs], dtype=np.intp),
        np.array([c for _, c, _ in pairs], dtype=np.intp),
        np.array([sign for _, _, sign in pairs]),
    )


class Joint(BaseModel):
    """Fields common to all joints. Subclasses set ``type`` and ``contacts``."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    type_name: ClassVar[str] = ""
    #: The coordinates a motion may drive (``model.motion``): none by default.
    drivable: ClassVar[tuple[Coordinate, ...]] = ()

    name: Name
    between: tuple[Name, Name]
    at: Point
    axis: Direction = (1.0, 0.0, 0.0)
    up: Direction | None = None
    clearance: Play
    #: Contact stiffness (N/mm), per contact point: a contact may go past its
    #: clearance by p at the cost of an elastic energy k p^2 / 2. None: rigid.
    stiffness: PositiveStiffness | None = None
    #: Where the features really are: a position and an orientation zone
    #: (``deviations.py``). None: on their nominal geometry.
    #: A shared deviation is named (``deviation: setup``, see ``SharedDeviation``).
    deviation: Deviation | None = None

    @classmethod
    def __pydantic_init_subclass__(cls, **kwargs: Any) -> None:
        super().__pydantic_init_subclass__(**kwargs)
        type_field = cls.model_fields.get("type")
        if type_field is not None and isinstance(type_field.default, str):
            cls.type_name = type_field.default
            JOINT_TYPES[cls.type_name] = cls

    @model_validator(mode="after")
    def _check_up(self) -> Joint:
        if self.up is not None and is_parallel(np.array(self.up), np.array(self.axis)):
            raise ValueError(
                f"up {list(self.up)} is parallel to axis {list(self.axis)}; "
                "give an 'up' vector across the axis, or leave it out"
            )
        return self

    @model_validator(mode="before")
    @classmethod
    def _tilt_over_length(cls, data: Any) -> Any:
        """A tilt zone given as a tolerance alone is over the joint's length
        (a parallelism of a bore over the bore)."""
        if not isinstance(data, dict) or "length" not in cls.model_fields:
            return data
        deviation = data.get("deviation")
        if not isinstance(deviation, dict):
            return data
        tilt = deviation.get("orientation")
        if not isinstance(tilt, dict) or "over" in tilt or data.get("length") is None:
            return data
        if "tolerance" in tilt:
            tilt = {**tilt, "over": data["length"]}
            return {**data, "deviation": {**deviation, "orientation": tilt}}
        return data

    @model_validator(mode="after")
    def _check_deviation(self) -> Joint:
        if self.deviation is None or self.deviation.shared is not None:
            return self  # a shared one: the model checks it
        deviation = self.deviation
        axes = [a for z in deviation.zones(self.type_name == "spherical") for a in z.axes]
        for move in [deviation.mean(), *np.eye(6)[axes]]:
            problem = self.rigid_problem(move)
            if problem:
                raise ValueError(f"deviation: {problem}")
        for a in axes:
            if not self.takes(np.eye(6)[a]):
                raise ValueError(
                    f"deviation: a {_motion_words(np.eye(6)[a])} of the features moves none of "
                    "the joint's contacts (the joint leaves that motion free); leave it out"
                )
        for a in mean_components(deviation.mean()):
            if not self.takes(np.eye(6)[a]):
                raise ValueError(
                    f"deviation: its mean is a {_motion_words(np.eye(6)[a])} of the features, "
                    "which moves none of the joint's contacts (the joint leaves that motion "
                    "free); leave that component out"
                )
        return self

    def takes(self, move: FloatArray) -> bool:
        """Whether the deviation ``move`` (a torsor in the joint frame) moves
        some clearance contact of the joint."""
        scale = DEFAULT.round_off * float(np.max(np.abs(move), initial=0.0))  # zero, to round-off
        # contacts(), not the cached cones: a validator must leave no arrays on
        # the model (pydantic's equality compares them)
        return any(_moves(c, move, scale) for c in self.contacts() if c.kind == "ball")

    def rigid_problem(self, move: FloatArray) -> str | None:
        """Why the deviation ``move`` cannot be this joint's: it meets a rigid
        row, which has no play to take it. None if it does not."""
        scale = DEFAULT.round_off * float(np.max(np.abs(move), initial=0.0))
        for c in self.contacts():
            if c.kind == "fixed" and _moves(c, move, scale):
                return (
                    f"a {_motion_words(move)} of the features of joint '{self.name}' meets its "
                    f"rigid contact '{c.name}', which has no play to take it; give the "
                    "deviation to a joint with play in that direction"
                )
        return None

    @cached_property
    def R_world_joint(self) -> FloatArray:
        """Joint axes x, y, z as columns, in global axes (``frame``, kept)."""
        return self.frame()

    def frame(self) -> FloatArray:
        """Joint axes x, y, z as columns, in global axes, computed anew (a
        validator must leave no arrays on the model: see ``takes``). A type
        that overrides it overrides ``frame_inputs`` too."""
        return joint_frame(self.axis, self.up)  # tuples: NumPy's scalars cost more here

    def frame_inputs(self) -> tuple[Any, ...]:
        """What ``frame`` is made of: joints of a type with equal inputs have
        one frame (``frames_of`` works it out once for them)."""
        return (self.axis, self.up)

    @cached_property
    def centre(self) -> FloatArray:
        return np.array(self.at, dtype=float)

    #: The fields that place the joint in the mechanism: its centre and its
    #: axes. Its contacts are in its own frame, and do not depend on them.
    PLACEMENT: ClassVar[tuple[str, ...]] = ("at", "axis", "up", "along")

    def placed(self, **placement: Any) -> Self:
        """This joint moved rigidly with its bodies (a motion's pose): other
        values of its ``PLACEMENT`` fields, validated (tuples of floats). A
        rigid motion keeps what validation checked, so it is not validated
        again (``fields.with_values``); its contacts, which the placement
        does not change, are this joint's own (``cones``), its frame and
        centre made anew from its fields."""
        if not set(placement) <= set(self.PLACEMENT):
            raise ValueError(f"not a placement: {sorted(set(placement) - set(self.PLACEMENT))}")
        moved = with_values(self, **placement)
        moved.__dict__["cones"] = self.cones  # where ``cached_property`` keeps it
        return moved

    def contacts(self) -> tuple[Contact, ...]:
        raise NotImplementedError

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The joint's ideal constraint in exact rotations (``Ideal``), what
        its contacts keep when the play is 0: what a motion closes. A
        coordinate that its contacts hold (a drive's spin, an axial play's
        slide) is held, unless it is the motion's ``driven`` one."""
        raise NotImplementedError

    @classmethod
    def contacts_of(cls, joints: Sequence[Self]) -> list[tuple[Contact, ...]]:
        """``contacts()`` of many joints of this type, one tuple per joint, each
        contact as ``contacts()`` makes it. A type whose contacts are worth
        building together (a large mechanism has thousands of joints of one
        type) overrides this with NumPy over all of them at once."""
        return [joint.contacts() for joint in joints]

    def play_length(self, field: str, play: float) -> float:
        """A play of this joint as a length (mm), to compare with lengths: an
        angular play (``ANGULAR_PLAYS``) at the radius where it acts."""
        return play

    def plays(self) -> dict[str, float]:
        """The joint's plays by field name (mm; a ``Toleranced`` one as
        itself, its mean as a float), those its type has and that are given."""
        fields = type(self).model_fields
        return {
            name: getattr(self, name)
            for name in PLAY_FIELDS
            if name in fields and getattr(self, name) is not None
        }

    @cached_property
    def cones(self) -> tuple[Contact, ...]:
        """``contacts()``, computed once (the joint is immutable)."""
        return self.contacts()

    @property
    def size(self) -> float:
        """A length of the joint itself (mm), used for the model's length scale."""
        return 0.0


def cones_of(joints: Sequence[Joint]) -> list[tuple[Contact, ...]]:
    """``joint.cones`` of every joint: those not made yet are made together,
    a type at a time (``contacts_of``; a type's only joint by ``contacts``,
    which costs it less), and kept on their joints as ``cones`` keeps them."""
    new: dict[type[Joint], list[Joint]] = {}
    for joint in joints:
        if "cones" not in joint.__dict__:
            new.setdefault(type(joint), []).append(joint)
    for kind, group in new.items():
        made = kind.contacts_of(group) if len(group) > 1 else [group[0].contacts()]
        for joint, cones in zip(group, made, strict=True):
            joint.__dict__["cones"] = cones  # where ``cached_property`` keeps it
    return [joint.cones for joint in joints]


def frames_of(joints: Sequence[Joint]) -> FloatArray:
    """(J, 3, 3): every joint's ``R_world_joint``, each distinct frame worked
    out once (the joints of a chain mostly share their axes)."""
    number: dict[tuple[Any, ...], int] = {}
    first: list[Joint] = []  # a joint of each frame
    which = []
    for joint in joints:
        key = (type(joint).frame, *joint.frame_inputs())
        if key not in number:
            number[key] = len(first)
            first.append(joint)
        which.append(number[key])
    frames = np.array([joint.R_world_joint for joint in first]).reshape(-1, 3, 3)
    return frames if len(first) == len(joints) else np.asarray(frames[which])
