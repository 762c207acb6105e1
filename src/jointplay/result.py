"""Results that carry their own proof.

A ``Result`` holds, per body, its small displacement (global axes, at the
global origin); per joint, the relative torsor of b with respect to a at the
joint centre in the joint frame, and the state of each contact; and the
``Certificate`` that the solver checked before handing the result out.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from jointplay.errors import SolverError
from jointplay.finite import IDENTITY, Linearization, Placement, linearization
from jointplay.geometry import FloatArray, cross, describe_motion
from jointplay.indeterminacy import DETERMINATE, Indeterminacy, indeterminacy_of
from jointplay.numerics.free_motions import IntArray, column_groups
from jointplay.proven import EXACT, Resolution, proven
from jointplay.settings import DEFAULT, SolverSettings

if TYPE_CHECKING:
    from jointplay.assembly import Assembly
    from jointplay.model.mechanism import Load, Model, Requirement


@dataclass(frozen=True)
class Certificate:
    """Independent checks of an optimum, computed from the final numbers.

    ``feasibility_mm``: the largest amount by which a contact goes past its
    clearance (0 when feasible). ``equilibrium_residual``: the imbalance of
    loads and contact forces in generalized coordinates, relative to the
    largest of them. ``min_force``: the smallest contact multiplier (must not be
    negative). ``method``: ``polished`` (KKT equations solved to machine
    precision), ``least-norm face`` (a tie resolved by a second program),
    ``interior-point`` (the cone solver's own answer), ``no load``, or
    ``no contact load`` (rigid joints hold the loads alone).
    """

    certified: bool
    method: str
    feasibility_mm: float
    equilibrium_residual: float
    complementarity: float
    min_force: float
    iterations: int


@dataclass(frozen=True)
class ContactResult:
    """One contact of a joint: how much play it uses and how hard it pushes.

    ``force`` is the force that body a exerts on body b at this contact (N,
    joint frame), acting at ``point`` (mm, global; on the joint axis for
    cylindrical ends, as in the paper's modelling). ``torque`` is the moment
    it adds about that point (N*mm, joint frame): a drive's reaction torque,
    0 for a contact that pushes at a point. A contact that does not touch
    carries no force.
    """

    name: str
    gap_used: float  # fraction of the play used, 0..1
    in_contact: bool
    force: FloatArray  # N, joint frame, a on b
    point: FloatArray  # mm, global
    penetration: float = 0.0  # past the clearance, in ``unit`` (compliant contacts only)
    torque: FloatArray = field(default_factory=lambda: np.zeros(3))  # N*mm, joint frame
    unit: str = "mm"  # of the play: "rad" for a drive's backlash

    @property
    def force_magnitude(self) -> float:
        return float(np.linalg.norm(self.force))

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "gap_used": self.gap_used,
            "in_contact": self.in_contact,
            "force": _list(self.force),
            "point": _list(self.point),
            "penetration": self.penetration,
            "torque": _list(self.torque),
            "unit": self.unit,
        }


@dataclass(frozen=True)
class JointResult:
    name: str
    type: str
    between: tuple[str, str]
    centre: FloatArray  # mm, global
    R_world_joint: FloatArray  # joint axes as columns
    translation: FloatArray  # mm, b relative to a, at the centre, joint frame
    rotation: FloatArray  # rad, joint frame
    contacts: tuple[ContactResult, ...]
    reaction_force: FloatArray  # N, a on b, joint frame
    reaction_moment: FloatArray  # N*mm, a on b, about the centre, joint frame

    def to_dict(self) -> dict[str, Any]:
        R = self.R_world_joint
        return {
            "axes": {k: _list(R[:, i]) for i, k in enumerate("xyz")},
            "translation": _list(self.translation),
            "rotation": _list(self.rotation),
            "contacts": [c.to_dict() for c in self.contacts],
            "reaction": {
                "force": _list(self.reaction_force),
                "moment": _list(self.reaction_moment),
            },
        }


@dataclass(frozen=True)
class PointResult:
    name: str
    body: str
    at: FloatArray  # mm, global, before displacement
    displacement: FloatArray  # mm, global

    def to_dict(self) -> dict[str, Any]:
        return {"body": self.body, "displacement": _list(self.displacement)}


@dataclass(frozen=True)
class BodyResult:
    name: str
    translation: FloatArray  # mm, of the body point at the global origin, global axes
    rotation: FloatArray  # rad, global axes (a rotation vector)
    #: The exact rotation matrix, for an answer with exact rotations (``--exact``);
    #: None: small displacements (a point P moves by translation + rotation x P).
    R: FloatArray | None = None

    def displacement_of(self, point: FloatArray) -> FloatArray:
        """Displacement (mm) of the body point at ``point`` (mm, global)."""
        P = np.asarray(point, dtype=float)
        if self.R is not None:
            return np.asarray(self.translation + self.R @ P - P)
        return self.translation + cross(self.rotation, P)

    def to_dict(self) -> dict[str, Any]:
        return {"translation": _list(self.translation), "rotation": _list(self.rotation)}


RowT = TypeVar("RowT")


class Rows(Mapping[str, RowT]):
    """``{name: row}``, read-only, whose rows are made from an answer's
    stacked arrays when first read: a large mechanism's answer has tens of
    thousands of joints and contacts, and most readers look at a few.
    ``make(i)`` makes the row of the ``i``-th name (a table's method, so
    that the mapping pickles as plain data)."""

    def __init__(self, names: tuple[str, ...], make: Callable[[int], RowT]):
        self._names = names
        self._make = make
        self._made: dict[int, RowT] = {}

    @cached_property
    def _index(self) -> dict[str, int]:
        return {n: i for i, n in enumerate(self._names)}

    def __getitem__(self, name: str) -> RowT:
        i = self._index[name]
        row = self._made.get(i)
        if row is None:
            row = self._made[i] = self._make(i)
        return row

    def __contains__(self, name: object) -> bool:
        return name in self._index

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __getstate__(self) -> dict[str, Any]:
        """Pickled without the rows made so far: the tables hold their numbers."""
        return {"_names": self._names, "_make": self._make, "_made": {}}

    def __len__(self) -> int:
        return len(self._names)

    def __repr__(self) -> str:
        return f"Rows({list(self._names)!r})"


@dataclass(frozen=True)
class BodyTable:
    """Every body's displacement, stacked (``Model.bodies`` order)."""

    name: tuple[str, ...]
    translation: FloatArray  # (n, 3) mm
    rotation: FloatArray  # (n, 3) rad

    def row(self, i: int) -> BodyResult:
        return BodyResult(self.name[i], self.translation[i], self.rotation[i])


@dataclass(frozen=True)
class ContactTable:
    """Every contact's state, stacked (``Assembly.contacts`` order): the
    fields of ``ContactResult``."""

    name: tuple[str, ...]
    gap_used: FloatArray
    in_contact: NDArray[np.bool_]
    force: FloatArray  # (nc, 3)
    point: FloatArray  # (nc, 3)
    penetration: FloatArray
    torque: FloatArray  # (nc, 3)
    is_turn: NDArray[np.bool_]  # a drive's backlash: penetration in rad

    def row(self, c: int) -> ContactResult:
        return ContactResult(
            self.name[c],
            float(self.gap_used[c]),
            bool(self.in_contact[c]),
            self.force[c],
            self.point[c],
            float(self.penetration[c]),
            self.torque[c],
            "rad" if self.is_turn[c] else "mm",
        )


@dataclass(frozen=True)
class JointTable:
    """Every joint's torsor and reaction, stacked (``Model.joints`` order):
    the fields of ``JointResult``; its contacts ``by_joint[first[j] : first[j + 1]]``."""

    name: tuple[str, ...]
    type: tuple[str, ...]
    between: tuple[tuple[str, str], ...]
    centre: FloatArray  # (J, 3)
    R_world_joint: FloatArray  # (J, 3, 3)
    translation: FloatArray  # (J, 3)
    rotation: FloatArray  # (J, 3)
    reaction: FloatArray  # (J, 6): force, moment
    contacts: ContactTable
    by_joint: IntArray
    first: IntArray

    def row(self, j: int) -> JointResult:
        own = self.by_joint[self.first[j] : self.first[j + 1]].tolist()
        return JointResult(
            self.name[j],
            self.type[j],
            self.between[j],
            self.centre[j],
            self.R_world_joint[j],
            self.translation[j],
            self.rotation[j],
            tuple(self.contacts.row(c) for c in own),
            self.reaction[j, :3],
            self.reaction[j, 3:],
        )


@dataclass(frozen=True)
class _Known:
    """A lazy value already known (what a pickled ``Result`` keeps)."""

    value: tuple[str, ...]

    def __call__(self) -> tuple[str, ...]:
        return self.value


@dataclass(frozen=True)
class Result:
    status: str
    potential_energy: float  # N*mm
    bodies: Mapping[str, BodyResult]
    joints: Mapping[str, JointResult]
    points: Mapping[str, PointResult]
    certificate: Certificate
    #: Worst imbalance of loads and contact forces over the moving bodies,
    #: computed in global axes from the reported forces (relative to the
    #: largest force in the balance: a load, or a joint's reaction).
    equilibrium_residual: float
    solve_time: float  # s
    #: Describes the free motions that no load drives (reported as 0); called lazily.
    describe_free: Callable[[], tuple[str, ...]] = field(repr=False, compare=False)
    #: The exact-rotation check of this answer (see ``jointplay.finite``); called lazily.
    linearize: Callable[[], Linearization] | None = field(default=None, repr=False, compare=False)
    #: The model's requirements checked on this answer's functional points.
    requirements: tuple[RequirementResult, ...] = ()
    #: What the model says that is legal but likely a slip (``Model.warnings``).
    model_warnings: tuple[str, ...] = ()
    #: The smallest length, angle, force and moment this answer proves: every
    #: number of it below them is 0.
    resolution: Resolution = EXACT
    #: The largest relative imbalance ``check`` accepts: the solve's settings'.
    equilibrium_tolerance: float = DEFAULT.equilibrium_tolerance
    #: Counts the static indeterminacy of the touching contacts (see
    #: ``indeterminate``); called lazily. None: not counted (``--exact``).
    find_indeterminate: Callable[[], Indeterminacy] | None = field(
        default=None, repr=False, compare=False
    )
    _indeterminate: Indeterminacy | None = field(default=None, repr=False, compare=False)

    @property
    def indeterminate(self) -> Indeterminacy:
        """The static indeterminacy of the touching contacts
        (``jointplay.indeterminacy``): its degree, and the joints and contacts
        whose forces are split by the least-squares rule, not by the balance
        (degree 0 and none when the balance decides every force)."""
        if self._indeterminate is None:
            found = self.find_indeterminate() if self.find_indeterminate else DETERMINATE
            object.__setattr__(self, "_indeterminate", found)
        assert self._indeterminate is not None
        return self._indeterminate

    @property
    def linearization(self) -> Linearization:
        """How far the contacts, placed with exact rotations, go past their play."""
        if self._linearization is None:
            value = self.linearize() if self.linearize else Linearization(0.0, None, ())
            object.__setattr__(self, "_linearization", value)
        assert self._linearization is not None
        return self._linearization

    _linearization: Linearization | None = field(default=None, repr=False, compare=False)

    @property
    def linearization_error(self) -> float:
        """mm: the largest overshoot of a clearance under exact rotations."""
        return float(proven(self.linearization.error_mm, self.resolution.length))

    @property
    def warnings(self) -> tuple[str, ...]:
        return self.model_warnings + self.linearization.warnings

    @property
    def free_motions(self) -> tuple[str, ...]:
        return self.describe_free()

    def __getstate__(self) -> dict[str, Any]:
        """Pickled as plain data: the lazy parts (closures over the solver's
        workspace) are evaluated and travel as values."""
        state = dict(self.__dict__)
        state["describe_free"] = _Known(self.free_motions)
        state["_linearization"] = self.linearization
        state["linearize"] = None
        state["_indeterminate"] = self.indeterminate
        state["find_indeterminate"] = None
        return state

    def to_dict(self) -> dict[str, Any]:
        """The JSON document of ``jointplay solve --json``."""
        return {
            "status": self.status,
            "potential_energy": float(self.potential_energy),
            "bodies": {n: b.to_dict() for n, b in self.bodies.items()},
            "joints": {n: j.to_dict() for n, j in self.joints.items()},
            "points": {n: p.to_dict() for n, p in self.points.items()},
            "equilibrium_residual": self.equilibrium_residual,
            "linearization_error": self.linearization_error,
            "warnings": list(self.warnings),
            "accuracy": self.accuracy(),
            "requirements": [r.to_dict() for r in self.requirements],
            "indeterminate": self.indeterminate.to_dict(),
            # the motions no joint holds and no load drives, reported as 0 (as the text says)
            "free_motions": list(self.free_motions),
        }

    def accuracy(self) -> dict[str, Any]:
        """What the certificate proved, in numbers (JSON ``accuracy``): how far
        any contact goes past its play (mm), the relative imbalance of the
        forces, the complementarity of forces and gaps, the path taken."""
        c = self.certificate
        return {
            "method": c.method,
            "feasibility_mm": float(c.feasibility_mm),
            "equilibrium_residual": float(c.equilibrium_residual),
            "complementarity": float(c.complementarity),
            "certified": bool(c.certified),
        }

    def check(self) -> None:
        """Raise ``SolverError`` unless the certificate holds (a plain check,
        not an ``assert``: ``python -O`` does not skip it)."""
        c = self.certificate
        if not c.certified:
            raise SolverError(f"uncertified result: {c}")
        if not self.equilibrium_residual <= self.equilibrium_tolerance:
            raise SolverError(
                f"forces do not balance the loads: residual {self.equilibrium_residual:.3g} "
                f"of the largest force ({self.equilibrium_tolerance:g} is required)"
            )


def _list(v: FloatArray) -> list[float]:
    return [float(c) + 0.0 for c in v]  # + 0.0 turns -0.0 into 0.0


def build_result(
    asm: Assembly,
    x: FloatArray,
    ball_forces: FloatArray,
    ball_vectors: FloatArray,
    rigid_forces: FloatArray,
    certificate: Certificate,
    solve_time: float,
    describe_free: Callable[[], tuple[str, ...]],
    loads: tuple[Load, ...],
    g: FloatArray,
    settings: SolverSettings = DEFAULT,
    by_rule: bool = True,
) -> Result:
    """Turn the solver's numbers into a ``Result``, each to what the
    certificate proves (``proven``). ``by_rule``: the forces are shown to
    be the split rule's, where the touching contacts are redundant
    (``Indeterminacy.by_rule``).

    ``ball_forces``: the force (N) of each clearance contact (``asm.balls``
    order), ``ball_vectors`` their force vectors (N, stacked like the rows
    of ``asm.stack.A``; see ``Contact``); ``rigid_forces``: the multipliers
    (N, N*mm) of the fixed rows (``asm.fixed`` order, rows stacked); ``loads`` and ``g``: the loads
    solved for and their work. Every number is computed here, for every
    body, joint and contact at once (``Assembly.tables``); the per-joint
    objects are made when read (``Rows``).
    """
    model = asm.model
    n = len(asm.body_names)
    X = x.reshape(n, 6)
    omega = asm.turn[:, None] * X[:, 3:]
    v_origin = asm.s * X[:, :3] - cross(omega, asm.body_ref)

    T = asm.tables
    stack = asm.stack
    _, _, level = stack.levels(x)
    used = stack.gap_used(level, settings.feasibility_tolerance * stack.largest_play())
    # past the clearance: only compliant contacts may be (hard ones by round-off)
    penetration = np.where(stack.spring > 0, np.maximum(level - stack.r, 0.0) * asm.s, 0.0)
    nc = len(asm.contacts)
    wrench = np.zeros((nc, 6))
    wrench[T.is_ball] = (T.wrench_ball @ ball_vectors).reshape(-1, 6) - (
        ball_forces[:, None] * T.offset_ball
    )
    wrench[~T.is_ball] = (T.wrench_fixed @ rigid_forces).reshape(-1, 6)
    gap = np.ones(nc)
    gap[T.is_ball] = proven(used, settings.feasibility_tolerance)
    past = np.zeros(nc)
    past[T.is_ball] = penetration
    is_turn = ~np.isnan(T.turn_lever)
    past[is_turn] /= T.turn_lever[is_turn]
    local = T.local_point.copy()
    ball_of = np.cumsum(T.is_ball) - 1
    for c in T.leaning:  # the centre of pressure of a tilting face moves
        i = int(ball_of[c])
        f = ball_vectors[stack.start[i] : stack.start[i] + stack.k[i]]
        local[c] = asm.contacts[c].contact.acting_point(f, float(ball_forces[i]))
    point = T.centre[T.joint_of] + np.einsum("cab,cb->ca", T.R_world_joint[T.joint_of], local)
    reaction = np.zeros((len(model.joints), 6))
    np.add.at(reaction, T.joint_of, wrench)
    residual = equilibrium_residual(asm, reaction, loads)
    res = Resolution.of(asm.s, asm.ell, largest_force(asm, reaction, loads), settings)

    names = tuple(b.name for b in model.bodies)
    translation, rotation = np.zeros((len(names), 3)), np.zeros((len(names), 3))
    moving = np.array([asm.body_index.get(name, -1) for name in names], dtype=np.intp)
    has = moving >= 0
    translation[has] = proven(v_origin[moving[has]], res.length)
    rotation[has] = proven(omega[moving[has]], res.angle)
    bodies = Rows(names, BodyTable(names, translation, rotation).row)
    # what the contact adds besides its force at its point: a drive's torque
    torque = wrench[:, 3:] - cross(local, wrench[:, :3])
    contacts = ContactTable(
        T.contact_name,
        gap,
        gap >= settings.touching,
        proven(wrench[:, :3], res.force),
        point,
        past,
        proven(torque, res.moment),
        is_turn,
    )
    # the sum of the contacts as printed, so that they add up to it
    reaction = np.zeros((len(model.joints), 6))
    np.add.at(
        reaction,
        T.joint_of,
        np.c_[contacts.force, cross(local, contacts.force) + contacts.torque],
    )
    reaction[:, 3:] = proven(reaction[:, 3:], res.moment)

    taus = (T.tau_map @ x).reshape(-1, 6)
    t_rel, w_rel = proven(taus[:, :3], res.length), proven(taus[:, 3:], res.angle)
    table = JointTable(
        T.joint_name,
        T.joint_type,
        T.between,
        T.centre,
        T.R_world_joint,
        t_rel,
        w_rel,
        reaction,
        contacts,
        T.by_joint,
        T.first_contact,
    )
    joints = Rows(T.joint_name, table.row)

    points = points_of(model, bodies, res)
    energy = float(proven(-float(g @ x), res.energy))  # no load: 0, not -0
    reach_mm = stack.r * asm.s + penetration
    return Result(
        "optimal",
        energy,
        bodies,
        joints,
        points,
        certificate,
        residual,
        solve_time,
        describe_free,
        lambda: linearization(asm, x, reach_mm),
        requirements_of(model, points),
        asm.model_warnings,
        res,
        settings.equilibrium_tolerance,
        functools.partial(indeterminacy_of, asm, x.copy(), settings, by_rule),
    )


def equilibrium_residual(
    asm: Assembly,
    reaction: FloatArray,
    loads: tuple[Load, ...],
    place: dict[str, Placement] | None = None,
) -> float:
    """The worst imbalance of each moving body, in global axes: the applied
    loads plus the reactions of its joints, forces relative to the largest
    force in the balance (a load or a joint's reaction) and moments relative
    to it times the length scale. ``reaction`` (J, 6): each joint's force
    and moment on b, in its joint frame, about its centre.

    ``place``: the bodies' exact placements (an answer with exact rotations);
    the loads then act at their displaced points, and each joint's reaction
    (a's joint frame, about its centre) at a's displaced joint centre.
    Without it, everything stays where the model puts it (small displacements)."""
    place = place or {}
    index = asm.body_index
    n = len(index)
    F = np.zeros((n, 3))
    M = np.zeros((n, 3))  # about each body's (displaced) reference point
    ref = asm.body_ref
    if place:
        ref = np.array([place.get(name, IDENTITY)(asm.body_ref[i]) for name, i in index.items()])
    if loads:
        on = np.array([index[load.body] for load in loads], dtype=np.intp)
        force = np.array([(0.0, 0.0, 0.0) if ld.force is None else ld.force for ld in loads], float)
        moment = np.array(
            [(0.0, 0.0, 0.0) if ld.torque is None else ld.torque for ld in loads], float
        )
        at_rows = [q for q, ld in enumerate(loads) if ld.at is not None]
        if at_rows:
            at = np.array([loads[q].at for q in at_rows], dtype=float)
            if place:
                at = np.array(
                    [
                        place.get(loads[q].body, IDENTITY)(p)
                        for q, p in zip(at_rows, at, strict=True)
                    ]
                )
            moment[at_rows] += cross(at - ref[on[at_rows]], force[at_rows])
        np.add.at(F, on, force)
        np.add.at(M, on, moment)
    T = asm.tables
    if len(reaction):  # every joint at once: large mechanisms have thousands
        rf, rm = reaction[:, :3], reaction[:, 3:]
        centre = T.centre
        if place:
            a_places = [place.get(a, IDENTITY) for a, _ in T.between]
            R = np.stack([pl.R for pl in a_places]) @ T.R_world_joint
            centre = np.stack([pl(c) for pl, c in zip(a_places, centre, strict=True)])
        else:
            R = T.R_world_joint
        force = np.einsum("jab,jb->ja", R, rf)
        moment = np.einsum("jab,jb->ja", R, rm)
        # on b as given, on a against it (a moving body on either side)
        body = T.between_index.T.ravel()
        moving = body >= 0
        body, sign = body[moving], np.repeat([-1.0, 1.0], len(reaction))[moving, None]
        force, moment, centre = (np.concatenate([v, v])[moving] for v in (force, moment, centre))
        np.add.at(F, body, sign * force)
        np.add.at(M, body, sign * (moment + cross(centre - ref[body], force)))
    scale = largest_force(asm, reaction, loads)
    if scale == 0.0:
        return 0.0
    worst = max(_largest_norm(F), _largest_norm(M) / asm.ell)
    return worst / scale


def largest_force(asm: Assembly, reaction: FloatArray, loads: tuple[Load, ...]) -> float:
    """N: the largest force in the balance, a load's or a joint's reaction
    (a moment counting as moment / ``ell``); 0 with neither. ``reaction``
    as in ``equilibrium_residual``."""
    # each load's own norm, as one vector
    forces = [0.0, *(float(np.linalg.norm(ld.force)) for ld in loads if ld.force is not None)]
    torques = [0.0, *(float(np.linalg.norm(ld.torque)) for ld in loads if ld.torque is not None)]
    scale = max(max(forces), max(torques) / asm.ell)
    if len(reaction):
        scale = max(scale, _largest_norm(reaction[:, :3]), _largest_norm(reaction[:, 3:]) / asm.ell)
    return scale


def _largest_norm(rows: FloatArray) -> float:
    """The largest Euclidean norm of the rows of ``rows`` (n, 3); 0 for none."""
    # the root of the largest square: sqrt is monotone and correctly rounded
    return math.sqrt(float((rows * rows).sum(axis=1).max(initial=0.0)))


def points_of(
    model: Model, bodies: Mapping[str, BodyResult], res: Resolution
) -> dict[str, PointResult]:
    """The functional points' displacements, from the bodies' results."""
    return {
        p.name: PointResult(
            p.name,
            p.body,
            np.array(p.at),
            proven(bodies[p.body].displacement_of(np.array(p.at)), res.length),
        )
        for p in model.points
    }


@dataclass(frozen=True)
class RequirementResult:
    """One requirement checked on one answer: what it bounds, measured (mm),
    against its limit. Passed when the measure is at most the limit."""

    requirement: Requirement
    measured: float  # mm

    @property
    def passed(self) -> bool:
        return self.measured <= self.requirement.max_displacement

    @property
    def margin(self) -> float:
        """mm left before the limit (negative: by how much it is missed)."""
        return self.requirement.max_displacement - self.measured

    def to_dict(self) -> dict[str, Any]:
        req = self.requirement
        return {
            "point": req.point,
            "max_displacement": req.max_displacement,
            "along": None if req.along is None else list(req.along),
            "measured": self.measured,
            "margin": self.margin,
            "passed": self.passed,
        }


def requirements_of(
    model: Model, points: Mapping[str, PointResult]
) -> tuple[RequirementResult, ...]:
    """Each of the model's requirements on these functional points."""
    return tuple(
        RequirementResult(req, float(req.measure(points[req.point].displacement)))
        for req in model.requirements
    )


def describe_free_motions(asm: Assembly, free_basis: Any) -> tuple[str, ...]:
    """The free motions (columns of ``free_basis``, dense or sparse), one phrase each."""
    if not sp.issparse(free_basis):
        bodies = np.arange(len(asm.body_names))
        return tuple(_describe_free(asm, d, bodies) for d in _echelon(free_basis.T))
    out = []
    for cols, bodies in column_groups(free_basis):  # a large mechanism: group by group
        rows = (6 * bodies[:, None] + np.arange(6)).ravel()
        block = free_basis[rows][:, cols].toarray()
        for local in _echelon(block.T):
            d = np.zeros(asm.m)
            d[rows] = local
            out.append(_describe_free(asm, d, bodies))
    return tuple(out)


def _echelon(basis_rows: FloatArray, tol: float = DEFAULT.free_motion_rcond) -> list[FloatArray]:
    """Reduced row-echelon form of a basis, so that each free motion involves as
    few bodies and components as possible (one spin per shaft, say)."""
    a = np.array(basis_rows, dtype=float)
    rows, cols = a.shape
    r = 0
    for c in range(cols):
        if r == rows:
            break
        p = r + int(np.argmax(np.abs(a[r:, c])))
        if abs(a[p, c]) <= tol:
            continue
        a[[r, p]] = a[[p, r]]
        a[r] /= a[r, c]
        for k in range(rows):
            if k != r:
                a[k] -= a[k, c] * a[r]
        r += 1
    return [row for row in a[:r]]


def _describe_free(asm: Assembly, d: FloatArray, bodies: IntArray) -> str:
    """One free motion ``d`` in words (``bodies``: those it may move)."""
    parts = []
    sizes = []
    for i in bodies.tolist():
        name = asm.body_names[i]
        omega, v_origin = asm.body_motion(d, i)
        size = float(np.linalg.norm(d[6 * i : 6 * i + 6]))
        if size > 0:
            sizes.append(size)
            parts.append((size, f"body '{name}': {describe_motion(omega, v_origin, asm.ell)}"))
    biggest = max(sizes, default=0.0)
    shown = DEFAULT.free_motion_rcond * biggest  # a unit null vector's round-off
    return ", with ".join(text for size, text in parts if size > shown)
