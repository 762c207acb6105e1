"""From the plays of real parts to the cone program: which radii each play moves.

A toleranced play (``tolerance.Toleranced``) of a joint enters the cone
program only through the radii of that joint's contacts, linearly (half the
diametral clearance of a bore's end, say). ``play_map`` finds that map for
every toleranced play of a model by asking the joint itself for its contacts
at the play's two limits, so a new joint type needs nothing here; it checks
that the play changes no contact's rows (only its radius), and that the
joint is valid at both limits (a bore engaged over less than its play, say).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from jointplay.assembly import Assembly
from jointplay.errors import ModelError, StudyError
from jointplay.geometry import FloatArray
from jointplay.model.deviations import Zone
from jointplay.model.joints import Joint
from jointplay.model.mechanism import Load, Model
from jointplay.model.tolerance import Distribution, Toleranced


@dataclass(frozen=True)
class PlayVariable:
    """One toleranced play: ``joint``'s field ``field`` (``l2.clearance``)."""

    joint: str
    field: str
    value: Toleranced

    @property
    def label(self) -> str:
        return f"{self.joint}.{self.field}"


@dataclass(frozen=True)
class PlayMap:
    """Scaled cone radii as an affine function of the plays (mm):
    ``radii = r0 + (plays - nominal) @ D``, in the order of ``Assembly.balls``."""

    variables: tuple[PlayVariable, ...]
    nominal: FloatArray  # (nv,) mm: the mean plays, which the model holds
    r0: FloatArray  # (n,) scaled radii of the model
    D: FloatArray  # (nv, n) scaled radius per mm of each play

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(v.label for v in self.variables)

    def radii(self, plays: FloatArray) -> FloatArray:
        """(B, n) scaled radii for (B, nv) plays (mm)."""
        plays = np.atleast_2d(np.asarray(plays, dtype=float))
        return np.asarray(self.r0 + (plays - self.nominal) @ self.D)

    def sample(self, rng: np.random.Generator, n: int) -> FloatArray:
        """(n, nv) plays (mm) of ``n`` sets of real parts."""
        out = np.empty((n, len(self.variables)))
        for j, var in enumerate(self.variables):
            out[:, j] = var.value.sample(rng, n)
        return out


@dataclass(frozen=True)
class LoadVariable:
    """One load component that varies: ``loads[0].force[1]`` (N or N*mm)."""

    entry: str
    value: Toleranced

    @property
    def label(self) -> str:
        return self.entry


@dataclass(frozen=True)
class LoadMap:
    """The loads' work as an affine function of their varying components:
    ``work = g0 + (values - nominal) @ W`` (the work is linear in each force
    and torque component)."""

    variables: tuple[LoadVariable, ...]
    nominal: FloatArray  # (nl,) the means, which the model holds
    g0: FloatArray  # (m,) the work of the loads at their means
    W: FloatArray  # (nl, m) work per unit of each component

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(v.label for v in self.variables)

    def work(self, values: FloatArray) -> FloatArray:
        """(B, m) work rows for (B, nl) component values."""
        values = np.atleast_2d(np.asarray(values, dtype=float))
        return np.asarray(self.g0 + (values - self.nominal) @ self.W)

    def sample(self, rng: np.random.Generator, n: int) -> FloatArray:
        """(n, nl) component values of ``n`` samples."""
        out = np.empty((n, len(self.variables)))
        for j, var in enumerate(self.variables):
            out[:, j] = var.value.sample(rng, n)
        return out


def load_map(asm: Assembly, case: str | None = None) -> LoadMap:
    """The ``LoadMap`` of the loads acting in ``case`` (``Model.loads_of``)."""
    model: Model = asm.model
    entries = [(f"loads[{i}]", load) for i, load in enumerate(model.loads)]
    if case is not None:
        own = (model.load_cases or {})[case]
        entries += [(f"load_cases.{case}[{i}]", load) for i, load in enumerate(own)]
    variables, rows = [], []
    for entry, load in entries:
        for part in load.ranges():  # each along its axis (a turned one, at a motion's pose)
            unit = part.direction
            one = (
                Load.model_construct(body=load.body, at=load.at, force=unit)
                if part.key == "force"
                else Load.model_construct(body=load.body, torque=unit)
            )
            variables.append(LoadVariable(f"{entry}.{part.key}[{part.index}]", part.value))
            rows.append(asm.work_of([one]))
    W = np.array(rows) if rows else np.zeros((0, asm.m))
    nominal = np.array([float(v.value) for v in variables])
    return LoadMap(tuple(variables), nominal, asm.work_of(model.loads_of(case)), W)


def toleranced_plays(asm: Assembly) -> tuple[PlayVariable, ...]:
    """Every play of the model given by limits or a fit, in joint order."""
    out = []
    for joint in asm.model.joints:
        for name, value in joint.plays().items():
            if isinstance(value, Toleranced):
                out.append(PlayVariable(joint.name, name, value))
    return tuple(out)


def play_map(asm: Assembly, source: str = "<model>") -> PlayMap:
    """The ``PlayMap`` of ``asm``'s toleranced plays (``ModelError`` if the
    joint is not valid at a play's limit, or the play moves more than radii)."""
    variables = toleranced_plays(asm)
    balls = asm.balls
    where = {(c.joint_index, c.contact_index): i for i, c in enumerate(balls)}
    index = {j.name: jdx for jdx, j in enumerate(asm.model.joints)}
    D = np.zeros((len(variables), len(balls)))
    for v, var in enumerate(variables):
        jdx = index[var.joint]
        joint = asm.model.joints[jdx]
        entry = f"joints[{jdx}] '{joint.name}'"
        low, high = var.value.low, var.value.high
        at_low = _cones_with(joint, var.field, low, source, entry)
        at_high = _cones_with(joint, var.field, high, source, entry)
        nominal = joint.cones
        for cdx, (a, b, c) in enumerate(zip(at_low, at_high, nominal, strict=True)):
            same = (
                a.kind == b.kind == c.kind
                and np.array_equal(a.rows, c.rows)
                and np.array_equal(b.rows, c.rows)
                and _same_offset(a.offset, c.offset)
                and _same_offset(b.offset, c.offset)
            )
            if not same:
                raise ModelError(
                    f"{var.field}: its play changes the geometry of contact '{c.name}', "
                    "not only its size, so it cannot be varied part to part; give it as "
                    "one length",
                    source=source,
                    entry=entry,
                )
            if c.kind != "ball" or (jdx, cdx) not in where:
                continue
            slope = 0.0 if high == low else (b.radius - a.radius) / (high - low)
            mean = a.radius + slope * (float(var.value) - low)
            if not np.isclose(mean, c.radius, rtol=1e-12, atol=1e-15 * max(1.0, high)):
                raise ModelError(  # pragma: no cover - every joint type's radius is linear
                    f"{var.field}: contact '{c.name}''s size is not linear in the play",
                    source=source,
                    entry=entry,
                )
            D[v, where[(jdx, cdx)]] = slope / asm.s
    nominal_plays = np.array([float(v.value) for v in variables])
    return PlayMap(variables, nominal_plays, asm.stack.r.copy(), D)


def _same_offset(a: NDArray[Any] | None, b: NDArray[Any] | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return bool(np.array_equal(a, b))


def _cones_with(joint: Joint, field: str, value: float, source: str, entry: str) -> Any:
    data = joint.model_dump()
    data[field] = value
    try:
        other = type(joint).model_validate(data)
    except ValueError as exc:
        problem = str(exc).splitlines()[-1].split(", [type=")[0].strip()
        problem = problem.removeprefix("Value error, ")
        raise ModelError(
            f"{field}: at its limit of {value:g} mm the joint is not valid: {problem}",
            source=source,
            entry=entry,
        ) from None
    return other.cones


@dataclass(frozen=True)
class DeviationVariable:
    """One component of a deviation that varies: joint ``l2``'s (or shared
    deviation ``setup``'s) position along y (mm) or tilt about z (rad), in
    its frame, drawn with the others of its zone."""

    owner: str  # the joint, or the shared deviation
    zone: Zone
    axis: int  # 0-5: the torsor component (t x, y, z mm; w x, y, z rad)
    mean: float
    distribution: Distribution

    @property
    def label(self) -> str:
        kind = "position" if self.axis < 3 else "orientation"
        return f"{self.owner}.deviation.{kind}.{'xyz'[self.axis % 3]}"

    @property
    def unit(self) -> str:
        return self.zone.unit

    def describe(self) -> str:
        shape = {1: "within", 2: "in a disc of radius", 3: "in a ball of radius"}
        return (
            f"{self.distribution} {shape[len(self.zone.axes)]} {self.zone.radius:.6g} "
            f"{self.unit} around {self.mean:.6g} ({self.zone.name} zone)"
        )


@dataclass(frozen=True)
class DeviationMap:
    """Cone centres and radii as affine functions of the joints' deviations:
    ``centres = c0 + (values - nominal) @ C`` (stacked like the rows of
    ``stack.A``) and ``radii += (values - nominal) @ D`` (``Assembly.balls``
    order; a face's limit along its normal), all scaled."""

    variables: tuple[DeviationVariable, ...]
    nominal: FloatArray  # (nd,) the means (mm or rad), which the model holds
    c0: FloatArray  # (rows,)
    C: FloatArray  # (nd, rows)
    D: FloatArray  # (nd, n)

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(v.label for v in self.variables)

    def centres(self, values: FloatArray) -> FloatArray:
        """(B, rows) scaled centres for (B, nd) deviations."""
        values = np.atleast_2d(np.asarray(values, dtype=float))
        return np.asarray(self.c0 + (values - self.nominal) @ self.C)

    def radii_shift(self, values: FloatArray) -> FloatArray:
        """(B, n) what the deviations add to the scaled radii."""
        values = np.atleast_2d(np.asarray(values, dtype=float))
        return np.asarray((values - self.nominal) @ self.D)

    def sample(self, rng: np.random.Generator, n: int) -> FloatArray:
        """(n, nd) deviations of ``n`` sets of real parts: each zone drawn
        whole (a disc by area), in joint order."""
        out = np.tile(self.nominal, (n, 1))
        j = 0
        while j < len(self.variables):
            var = self.variables[j]
            width = len(var.zone.axes)
            out[:, j : j + width] += var.zone.sample(rng, n, var.distribution)
            j += width
        return out


def deviation_map(asm: Assembly) -> DeviationMap:
    """The ``DeviationMap`` of every zone with a size, of the joints' own
    deviations and the shared ones (``Model.deviation_sources``)."""
    model: Model = asm.model
    stack = asm.stack
    where = {(c.joint_index, c.contact_index): i for i, c in enumerate(asm.balls)}
    variables: list[DeviationVariable] = []
    C_rows, D_rows = [], []
    for source in model.deviation_sources():
        dev = source.deviation
        mean = dev.mean()
        seen = [(jdx, source.torsor_at(jdx, model.joints[jdx])) for jdx in source.joints]
        for zone in dev.zones(source.ball):
            if zone.radius == 0.0:
                continue
            for axis in zone.axes:
                variables.append(
                    DeviationVariable(source.label, zone, axis, float(mean[axis]), dev.distribution)
                )
                c_row, d_row = np.zeros(stack.A.shape[0]), np.zeros(len(asm.balls))
                for jdx, T in seen:
                    move = T[:, axis]  # the unit component, as this joint sees it
                    for cdx, contact in enumerate(model.joints[jdx].cones):
                        i = where.get((jdx, cdx))
                        if i is None:
                            continue
                        rows = slice(stack.start[i], stack.start[i] + stack.k[i])
                        c_row[rows] += (contact.rows @ move) / asm.s
                        if contact.offset is not None:
                            d_row[i] += float(contact.offset @ move) / asm.s
                C_rows.append(c_row)
                D_rows.append(d_row)
    nd = len(variables)
    return DeviationMap(
        tuple(variables),
        np.array([v.mean for v in variables]),
        stack.centres().copy(),
        np.array(C_rows).reshape(nd, stack.A.shape[0]),
        np.array(D_rows).reshape(nd, len(asm.balls)),
    )


def nothing_varies(what: str, source: str) -> StudyError:
    """The error of a study (``what`` it would do) on a model in which
    nothing varies from part to part."""
    return StudyError(
        "nothing in this model varies from part to part (every play is one length, every "
        f"load fixed, no deviation zone), so {what}; to study it, give a joint's clearance "
        "as limits, {min: 0.02, max: 0.06}, or as an ISO fit, {fit: 'H7/g6', diameter: 20}, "
        "a load's component as {min: 8, max: 12}, or a joint a deviation zone, "
        "deviation: {position: '0.02 mm'}",
        source=source,
    )
