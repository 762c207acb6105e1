"""Nominal kinematics: every body's large displacement through a motion.

A body's pose ``(R, p)`` places the point written at ``X`` at ``R X + p``
(the pose written in the file is ``(I, 0)``; ground bodies keep it). Each
joint's ideal constraint (``Joint.ideal``) is a list of scalar equations on
the frame carried by its first body and the centre carried by its second,
exact in finite rotations; the drive adds one equation, its coordinate at
the step's value. Each step is solved by SciPy's ``leastsq`` (MINPACK's
Levenberg-Marquardt, analytic Jacobian; ``least_squares`` where there are
fewer equations than unknowns) from the previous step's pose, so open chains
and any number of loops are solved alike. Before the first step, the rank
rule of the mobility check says whether the drive can move at all: a
drive's equation that depends on the other joints' rows (another joint's
held spin locks the loop) moves nothing, whatever the range.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares, leastsq

from jointplay.errors import MotionError, UnboundedMechanismError
from jointplay.geometry import FloatArray, describe_motion
from jointplay.model.joints.base import HOLDS, Coordinate, Ideal
from jointplay.model.mechanism import Model
from jointplay.settings import MOTION, MotionSettings

IntArray = NDArray[np.intp]


class ReachError(MotionError):
    """A ``MotionError`` of kind "unreachable" where the drive's reach ends
    at a toggle (a dead point) between two steps: ``end`` is the drive's
    value there (rad or mm), ``joints`` those at the toggle."""

    def __init__(self, message: str, *, end: float, **fields: Any):
        self.end = end
        super().__init__(message, **fields)


@dataclass(frozen=True)
class Poses:
    """Per step, every moving body's pose: ``R`` (S, B, 3, 3), ``p`` (S, B, 3)."""

    bodies: tuple[str, ...]
    values: FloatArray  # (S,) the drive's value, rad or mm
    R: FloatArray
    p: FloatArray

    def place(self, step: int, body: str, X: FloatArray) -> FloatArray:
        """Where the point written at ``X`` of ``body`` is at ``step`` (mm)."""
        if body not in self.bodies:
            return np.asarray(X, dtype=float)
        i = self.bodies.index(body)
        return np.asarray(self.R[step, i] @ np.asarray(X, dtype=float) + self.p[step, i])

    def turn(self, step: int, body: str) -> FloatArray:
        if body not in self.bodies:
            return np.eye(3)
        return np.asarray(self.R[step, self.bodies.index(body)])


def _rotations(w: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(B, 3, 3) ``exp([w]x)`` of each row of ``w`` (Rodrigues) and the left
    Jacobians ``J_l`` (``geometry.rotation_matrix``, ``left_jacobian``),
    all at once; below 1e-4 rad by their series, exact there to round-off."""
    theta = np.linalg.norm(w, axis=1)
    K = np.zeros((len(w), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -w[:, 2], w[:, 1], -w[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = w[:, 2], -w[:, 1], w[:, 0]
    K2 = K @ K
    small = theta < 1e-4
    t = np.where(small, 1.0, theta)
    t2 = theta * theta
    sin_t = np.where(small, 1.0 - t2 / 6.0, np.sin(t) / t)
    one_cos = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(t)) / t**2)
    t_sin = np.where(small, 1.0 / 6.0 - t2 / 120.0, (t - np.sin(t)) / t**3)
    eye = np.eye(3)[None]
    R = eye + sin_t[:, None, None] * K + one_cos[:, None, None] * K2
    J = eye + one_cos[:, None, None] * K + t_sin[:, None, None] * K2
    return R, J


def _cross(u: FloatArray, v: FloatArray) -> FloatArray:
    """Row-wise cross products of (r, 3) arrays (``np.cross`` costs ten
    times more on small arrays)."""
    return np.stack(
        [
            u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1],
            u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
            u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0],
        ],
        axis=1,
    )


@dataclass(frozen=True)
class _Rows:
    """The equations of one kind as arrays: their rows, bodies (a ground body
    is ``B``, the last of the stacked poses) and the written vectors they
    turn: a's axis, and b's axis (``axes``) or the joint's centre (``offset``)."""

    rows: IntArray
    a: IntArray
    b: IntArray
    axis_a: FloatArray
    axis_b: FloatArray
    centre: FloatArray

    @classmethod
    def of(cls, eqs: _Equations, kind: str) -> _Rows:
        B = len(eqs.bodies)
        picked = [(r, row) for r, row in enumerate(eqs.rows) if row[3].kind == kind]
        F = [eqs.frames[jdx][0] for _, (jdx, _, _, _) in picked]
        return cls(
            np.array([r for r, _ in picked], dtype=np.intp),
            np.array([a if a >= 0 else B for _, (_, a, _, _) in picked], dtype=np.intp),
            np.array([b if b >= 0 else B for _, (_, _, b, _) in picked], dtype=np.intp),
            np.array(
                [
                    f[:, eq.j if kind == "axes" else eq.k]
                    for f, (_, (_, _, _, eq)) in zip(F, picked, strict=True)
                ]
            ).reshape(-1, 3),
            np.array([f[:, eq.k] for f, (_, (_, _, _, eq)) in zip(F, picked, strict=True)]).reshape(
                -1, 3
            ),
            np.array([eqs.frames[jdx][1] for _, (jdx, _, _, _) in picked]).reshape(-1, 3),
        )


class _Equations:
    """The ideal equations of a model with its drive, on the bodies' poses."""

    def __init__(self, model: Model, settings: MotionSettings):
        joint, coordinate, _, _ = model.motion_drive()
        self.drive: Coordinate = coordinate
        self.drive_joint = joint.name
        self.bodies = tuple(b.name for b in model.moving_bodies)
        index = {name: i for i, name in enumerate(self.bodies)}
        centres = np.array([j.at for j in model.joints], dtype=float)
        self.ell = max(float(np.linalg.norm(centres.max(axis=0) - centres.min(axis=0))), 1.0)
        self.settings = settings
        # one row per equation: (joint index, body a, body b, Ideal)
        self.rows: list[tuple[int, int, int, Ideal]] = []
        #: per row, the coordinate it holds that the joint's type frees when
        #: driven (a drive's spin, an axial play's slide), or None
        self.holds: list[Coordinate | None] = []
        self.frames = []
        for jdx, j in enumerate(model.joints):
            a, b = (index.get(name, -1) for name in j.between)
            self.frames.append((j.R_world_joint, np.array(j.at, dtype=float)))
            driven = coordinate if j.name == joint.name else None
            equations = j.ideal(driven)
            self.rows += [(jdx, a, b, eq) for eq in equations]
            kinds: tuple[Coordinate, ...] = ("spin", "slide")
            freed = {c: set(j.ideal(c)) for c in kinds if c != driven}
            self.holds += [
                next((c for c, kept in freed.items() if eq not in kept), None) for eq in equations
            ]
        self.drive_index = [j.name for j in model.joints].index(joint.name)
        self.joint_names = tuple(j.name for j in model.joints)
        self.n = 6 * len(self.bodies)
        self._drive_bodies: tuple[int, int] = (
            index.get(joint.between[0], -1),
            index.get(joint.between[1], -1),
        )
        self.offset_rows = _Rows.of(self, "offset")
        self.axes_rows = _Rows.of(self, "axes")
        o, x = self.offset_rows, self.axes_rows
        B = len(self.bodies)
        a, b = (i if i >= 0 else B for i in self._drive_bodies)
        F, c = self.frames[self.drive_index]
        # the drive's vectors: its axis x and centre (a slide), or a's axes z
        # and y and b's axis y (a spin)
        self._drive_ab = (a, b)
        drive_bodies, drive_vectors = ([a, b, a], [F[:, 0], c, c])
        if self.drive == "spin":
            drive_bodies, drive_vectors = [a, a, b], [F[:, 2], F[:, 1], F[:, 1]]
        #: the written vectors ``evaluate`` turns with their bodies, all at
        #: once: the offset rows' u_a, c carried by b and by a, the axes
        #: rows' u_a and v_b, then the drive's (a ground body is ``B``)
        self._turned_body = np.concatenate(
            [o.a, o.b, o.a, x.a, x.b, np.array(drive_bodies, dtype=np.intp)]
        ).astype(np.intp)
        self._turned_vector = np.vstack(
            [o.axis_a, o.centre, o.centre, x.axis_a, x.axis_b, np.array(drive_vectors)]
        )
        #: the row and body of each gradient block ``evaluate`` stacks, in its
        #: order; a row's blocks are on distinct bodies (a joint's two), so
        #: each entry of the Jacobian is set once
        rows = np.concatenate([o.rows, o.rows, x.rows, x.rows, [len(self.rows)] * 2])
        rows = rows.astype(np.intp)
        bodies = np.concatenate([o.a, o.b, x.a, x.b, [a], [b]]).astype(np.intp)
        #: a ground body's blocks are left out: it has no unknowns
        self._moving_block = bodies < B
        self._block_body = bodies[self._moving_block]
        self._block_entry = (
            rows[self._moving_block, None] * self.n + 6 * self._block_body[:, None] + np.arange(6)
        ).ravel()

    def _pose(
        self, R0: FloatArray, p0: FloatArray, z: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        w = z.reshape(-1, 6)
        turn, Jl = _rotations(w[:, :3])
        return turn @ R0, p0 + w[:, 3:], Jl

    def evaluate(
        self, R: FloatArray, p: FloatArray, Jl: FloatArray, value: float
    ) -> tuple[FloatArray, FloatArray]:
        """Residuals (mm) and their Jacobian w.r.t. ``z`` (per body: the
        rotation vector's increment, then the shift), all rows at once: a
        ground body is the last of the stacked poses, with no unknowns."""
        ell = self.ell
        Rx = np.concatenate([R, np.eye(3)[None]])
        px = np.concatenate([p, np.zeros((1, 3))])
        o, x = self.offset_rows, self.axes_rows
        no, nx = len(o.rows), len(x.rows)
        turned = np.einsum("rij,rj->ri", Rx[self._turned_body], self._turned_vector)
        # offset rows: u_a . (c_b - c_a); axes rows: ell u_a . v_b
        u, rb, ca = turned[:no], turned[no : 2 * no], turned[2 * no : 3 * no]
        ua, vb = turned[3 * no : 3 * no + nx], turned[3 * no + nx : 3 * no + 2 * nx]
        d1, d2, d3 = turned[3 * no + 2 * nx :]
        arm = rb + px[o.b] - px[o.a]  # c_b - p_a
        if self.drive == "slide":  # the drive's offset along its axis x, less the value
            a, b = self._drive_ab
            darm = d2 + px[b] - px[a]
            d_res = float(d1 @ (darm - d3)) - value
            left = np.vstack([u, rb, ua, d1, d2])
            right = np.vstack([arm, u, vb, darm, d1])
        else:  # ell sin(phi - value), R_rel[2, 1] = sin(phi), R_rel[1, 1] = cos(phi)
            cos, sin = np.cos(value), np.sin(value)
            weights = ell * np.array([cos, -sin])
            d_res = float(weights[0] * (d1 @ d3) + weights[1] * (d2 @ d3))
            left, right = np.vstack([u, rb, ua, d1, d2]), np.vstack([arm, u, vb, d3, d3])
        crossed = _cross(left, right)
        g_axes = ell * crossed[2 * no : 2 * no + nx]
        zero = np.zeros((nx, 3))
        if self.drive == "slide":
            g_da, g_db = crossed[2 * no + nx][None], crossed[2 * no + nx + 1][None]
            s_da, s_db = -d1[None], d1[None]
        else:
            g_da = (weights @ crossed[2 * no + nx :])[None]
            g_db, s_da, s_db = -g_da, np.zeros((1, 3)), np.zeros((1, 3))
        g_rot = np.vstack([crossed[: 2 * no], g_axes, -g_axes, g_da, g_db])
        g_shift = np.vstack([-u, u, zero, zero, s_da, s_db])
        m = len(self.rows) + 1
        res = np.empty(m)
        res[o.rows] = np.einsum("ri,ri->r", u, arm - ca)
        res[x.rows] = ell * np.einsum("ri,ri->r", ua, vb)
        res[m - 1] = d_res
        moving = self._moving_block
        blocks = np.hstack(
            [np.einsum("ri,rij->rj", g_rot[moving], Jl[self._block_body]), g_shift[moving]]
        )
        jac = np.zeros(m * self.n)
        jac[self._block_entry] = blocks.ravel()
        return res, jac.reshape(m, self.n)

    def joints_of(self, weights: FloatArray) -> tuple[str, ...]:
        """The joints whose equations carry ``weights`` (per row) most."""
        size = np.abs(weights)
        top = float(size.max(initial=0.0))
        names: list[str] = []
        for row, w in enumerate(size):
            if w > 0.1 * top:
                jdx = self.rows[row][0] if row < len(self.rows) else self.drive_index
                if self.joint_names[jdx] not in names:
                    names.append(self.joint_names[jdx])
        return tuple(names)


def moves_only_the_drive(
    model: Model,
    poses: Poses,
    step: int,
    direction: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]],
    settings: MotionSettings = MOTION,
) -> bool:
    """Whether the small motion ``direction`` at ``step``'s pose (per moving
    body its rotation and the translation at the global origin, as
    ``UnboundedMechanismError.direction``) is the drive's own coordinate: by
    the mobility's rank rule (``mobility_rcond`` of the equations' largest
    singular value) it moves no ideal joint's equation, and the drive's."""
    eqs = _Equations(model, settings)
    R, p = poses.R[step], poses.p[step]
    none = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    d = np.zeros(eqs.n)
    for i, name in enumerate(eqs.bodies):
        omega, v_origin = (np.asarray(v, dtype=float) for v in direction.get(name, none))
        # the unknowns shift the point at the body's p, not the global origin
        d[6 * i : 6 * i + 6] = np.concatenate([omega, v_origin + np.cross(omega, p[i])])
    _, J = eqs.evaluate(R, p, np.repeat(np.eye(3)[None], len(R), axis=0), poses.values[step])
    scale = _column_scale(eqs)
    moved = (J * scale) @ (d / scale)
    top = float(np.linalg.norm(J * scale, 2) * np.linalg.norm(d / scale))
    rcond = settings.mobility_rcond * top
    return bool(top > 0.0 and abs(moved[-1]) > rcond and np.all(np.abs(moved[:-1]) <= rcond))


def _shown(coordinate: Coordinate, value: float) -> str:
    return f"{np.degrees(value):.6g} deg" if coordinate == "spin" else f"{value:.6g} mm"


def nominal_poses(
    model: Model,
    values: FloatArray,
    *,
    settings: MotionSettings = MOTION,
    source: str | None = None,
) -> Poses:
    """Every moving body's pose at each drive value of ``values`` (rad or
    mm, from the pose written in the file), reached step by step from it.
    Raises ``UnboundedMechanismError`` when the drive leaves a motion free,
    ``MotionError`` at a dead point or a value out of reach (a ``ReachError``,
    with the value where the reach ends, when it ends at a toggle)."""
    eqs = _Equations(model, settings)
    B = len(eqs.bodies)
    R = np.repeat(np.eye(3)[None], B, axis=0)
    p = np.zeros((B, 3))
    _check_movable(eqs, R, p, source)
    _check_driven(eqs, R, p, model)
    values = np.asarray(values, dtype=float)
    limit = settings.largest_step * (1.0 if eqs.drive == "spin" else eqs.ell)
    out_R, out_p = [], []
    current = 0.0  # the pose written in the file
    # the last two steps' changes of pose per unit of the drive: each step's
    # least squares start from their extrapolation
    rates: list[FloatArray] = []
    for s, value in enumerate(values):
        parts = max(1, int(np.ceil(abs(float(value) - current) / limit)))
        last = current
        for part in np.linspace(current, float(value), parts + 1)[1:]:
            guess = np.zeros(eqs.n) if not rates else 2 * rates[-1] - rates[0]
            step = _Step(s, current, float(value), float(part))
            try:
                R, p, z = _solve_step(eqs, R, p, step, source, guess * (part - last))
            except MotionError as exc:
                if exc.kind != "unreachable":
                    raise
                raise _reach_end(eqs, R, p, step, last, exc, source) from None
            if part != last:
                rates = [*rates[-1:], z / (part - last)]
            last = float(part)
        current = float(value)
        out_R.append(R)
        out_p.append(p)
    return Poses(eqs.bodies, values, np.array(out_R), np.array(out_p))


@dataclass(frozen=True)
class _Step:
    """Where a part of a step is: the user's step ``index`` runs from the
    drive's value ``previous`` (the step before's, or the written pose's 0)
    to ``value``; ``part`` is the value solved now, between them. Messages
    name the user's values only."""

    index: int
    previous: float
    value: float
    part: float

    def at(self, eqs: _Equations) -> str:
        return f"step {self.index} (drive '{eqs.drive_joint}' at {_shown(eqs.drive, self.value)})"

    def between(self, eqs: _Equations) -> str:
        before = (
            f"step {self.index - 1} ({_shown(eqs.drive, self.previous)})"
            if self.index > 0
            else f"the pose written in the file ({_shown(eqs.drive, self.previous)})"
        )
        return f"between {before} and step {self.index} ({_shown(eqs.drive, self.value)})"


def _solve_step(
    eqs: _Equations,
    R0: FloatArray,
    p0: FloatArray,
    step: _Step,
    source: str | None,
    z0: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The pose at drive ``step.part`` from the pose ``(R0, p0)`` before it,
    least squares starting at the change ``z0`` (the last step's, in
    proportion: the same closure from fewer evaluations); with the change found."""
    R, p, z, res, J = _closed(eqs, R0, p0, step.part, z0)
    settings = eqs.settings
    worst = float(np.max(np.abs(res)))
    if worst > settings.closure * eqs.ell:
        joints = eqs.joints_of(res)
        raise MotionError(
            f"unreachable: at {step.at(eqs)} the ideal joints "
            f"{', '.join(repr(j) for j in joints)} cannot close (off by {worst:.3g} mm): the "
            f"linkage does not reach that drive value, and turns back {step.between(eqs)}; "
            "give a range the linkage reaches",
            kind="unreachable",
            step=step.index,
            value=step.value,
            joints=joints,
            source=source,
        )
    scaled = J * _column_scale(eqs)
    sigma = np.linalg.svd(scaled, compute_uv=False)  # the vectors only at a dead point
    if sigma.size and sigma[-1] < settings.dead_point * sigma[0]:
        U = np.linalg.svd(scaled, full_matrices=False)[0]
        joints = eqs.joints_of(U[:, -1])
        # on the user's step, or on the way to it
        where = f"at {step.at(eqs)}" if step.part == step.value else step.between(eqs)
        raise MotionError(
            f"dead point: {where} the drive no longer decides the pose: joints "
            f"{', '.join(repr(j) for j in joints)} are at a toggle, which the drive cannot "
            "pass; stop the range short of it, or drive another joint",
            kind="dead point",
            step=step.index,
            value=step.value,
            joints=joints,
            source=source,
        )
    return R, p, z


def _reach_end(
    eqs: _Equations,
    R: FloatArray,
    p: FloatArray,
    step: _Step,
    last: float,
    failed: MotionError,
    source: str | None,
) -> MotionError:
    """Where the drive's reach ends, between ``last`` (closed, the pose
    ``(R, p)``) and ``step.part`` (not closed): bisection on the drive's
    value, each half closed from the last pose that closed, down to
    ``MotionSettings.reach_resolution``. A toggle there (the equations'
    smallest singular value near 0, as at a dead point) is named with its
    joints and the value; without one, ``failed`` as it was."""
    settings = eqs.settings
    lo, hi = last, step.part
    width = settings.reach_resolution * (1.0 if eqs.drive == "spin" else eqs.ell)
    while abs(hi - lo) > width:  # from 0.1 rad (largest_step) to 1e-10: 30 closes
        mid = 0.5 * (lo + hi)
        Rm, pm, _, res, _ = _closed(eqs, R, p, mid, np.zeros(eqs.n))
        if float(np.max(np.abs(res))) <= settings.closure * eqs.ell:
            lo, R, p = mid, Rm, pm
        else:
            hi = mid
    Jl = np.repeat(np.eye(3)[None], len(R), axis=0)
    _, J = eqs.evaluate(R, p, Jl, lo)
    U, sigma, _ = np.linalg.svd(J * _column_scale(eqs), full_matrices=False)
    if not sigma.size or sigma[-1] >= settings.toggle * sigma[0]:
        return failed
    joints = eqs.joints_of(U[:, -1])
    end = _short_of(eqs.drive, lo, hi - lo)
    return ReachError(
        f"unreachable: at {step.at(eqs)} the linkage is out of reach: the drive's reach ends "
        f"at {end}, {step.between(eqs)}, at a toggle (a dead point) of joints "
        f"{', '.join(repr(j) for j in joints)}, which the drive cannot pass; the range asks "
        "for values past it, which no pose of the linkage reaches from there; stop the range "
        f"short of {end}, or drive another joint",
        kind="unreachable",
        step=step.index,
        value=step.value,
        joints=joints,
        source=source,
        end=lo,
    )


def _short_of(coordinate: Coordinate, value: float, onward: float) -> str:
    """``value`` (rad or mm) as ``_shown`` gives it, 6 significant digits
    cut towards the range's start (against ``onward``): a value still within
    the reach that ends at ``value``."""
    x = float(np.degrees(value)) if coordinate == "spin" else value
    if x != 0.0:
        q = 10.0 ** (np.floor(np.log10(abs(x))) - 5)
        x = float(np.floor(x / q) if onward > 0 else np.ceil(x / q)) * q
    return f"{x:.6g} deg" if coordinate == "spin" else f"{x:.6g} mm"


def _closed(
    eqs: _Equations, R0: FloatArray, p0: FloatArray, value: float, z0: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """The least squares pose at drive ``value`` from ``(R0, p0)``, starting
    at the change ``z0``: the pose, the change, and its residuals and Jacobian."""
    settings = eqs.settings
    tol = max(settings.solve_tolerance, float(np.finfo(float).eps))
    # the last point evaluated: least squares ask for the residuals and the
    # Jacobian at each point, and mostly end on the last one they evaluated
    seen: dict[bytes, tuple[FloatArray, FloatArray, FloatArray, FloatArray]] = {}

    def evaluated(z: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        key = z.tobytes()
        if key not in seen:
            seen.clear()
            R, p, Jl = eqs._pose(R0, p0, z)
            seen[key] = (R, p, *eqs.evaluate(R, p, Jl, value))
        return seen[key]

    def fun(z: FloatArray) -> FloatArray:
        return evaluated(z)[2]

    def jac(z: FloatArray) -> FloatArray:
        return evaluated(z)[3]

    m = len(eqs.rows) + 1
    if m >= eqs.n:  # MINPACK's Levenberg-Marquardt, called with little overhead
        z = leastsq(fun, z0, Dfun=jac, xtol=tol, ftol=tol, gtol=tol, maxfev=settings.evaluations)[0]
    else:
        z = least_squares(fun, z0, jac=jac, method="trf", xtol=tol, ftol=tol, gtol=tol,
                          max_nfev=settings.evaluations).x  # fmt: skip
    R, p, res, J = evaluated(z)
    return R, p, z, res, J


def _column_scale(eqs: _Equations) -> FloatArray:
    """Rotations' columns times ``ell``: every unknown a length."""
    scale = np.ones(eqs.n)
    for i in range(eqs.n // 6):
        scale[6 * i : 6 * i + 3] = 1.0 / eqs.ell
    return scale


def _moves(J: FloatArray, others: IntArray, rcond: float) -> bool:
    """Whether the last row of ``J`` (the drive's) is independent of the rows
    ``others``: the mobility's rank rule, both ranks against J's largest
    singular value."""
    full = np.linalg.svd(J, compute_uv=False)
    if not full.size or full[0] == 0.0:
        return False
    kept = np.linalg.svd(J[others], compute_uv=False) if others.size else np.zeros(0)
    return int(np.sum(full > rcond * full[0])) > int(np.sum(kept > rcond * full[0]))


def _mobility(J: FloatArray, rows: IntArray, rcond: float) -> int:
    """How many motions of the bodies the rows ``rows`` of ``J`` leave free
    (its rank against J's largest singular value, as ``_moves``)."""
    full = np.linalg.svd(J, compute_uv=False)
    kept = np.linalg.svd(J[rows], compute_uv=False) if rows.size else np.zeros(0)
    top = full[0] if full.size else 0.0
    return int(J.shape[1]) - int(np.sum(kept > rcond * top)) if top > 0 else int(J.shape[1])


def _check_movable(eqs: _Equations, R: FloatArray, p: FloatArray, source: str | None) -> None:
    """``MotionError`` (exit 2) if, at the written pose, the other joints'
    ideal constraints leave the driven coordinate no motion at all (the
    drive's equation depends on their rows), naming the joints whose held
    coordinate (a drive's spin, an axial play's slide) locks it."""
    Jl = np.repeat(np.eye(3)[None], len(R), axis=0)
    _, J = eqs.evaluate(R, p, Jl, 0.0)
    J = J * _column_scale(eqs)
    rcond = eqs.settings.mobility_rcond
    rows = np.arange(len(eqs.rows), dtype=np.intp)
    if _moves(J, rows, rcond):
        return
    # per joint, the rows holding a coordinate that driving it would free
    held: dict[str, tuple[IntArray, Coordinate]] = {}
    for jdx, name in enumerate(eqs.joint_names):
        own = np.array([r for r in rows if eqs.rows[r][0] == jdx and eqs.holds[r] is not None])
        if own.size:
            coordinate = eqs.holds[int(own[0])]
            assert coordinate is not None
            held[name] = (own.astype(np.intp), coordinate)
    alone = [n for n, (own, _) in held.items() if _moves(J, np.setdiff1d(rows, own), rcond)]
    together = not alone and bool(held)
    if together:
        every = np.concatenate([own for own, _ in held.values()])
        together = _moves(J, np.setdiff1d(rows, every), rcond)
    holding = alone or (list(held) if together else [])
    drive = f"the drive '{eqs.drive_joint}' cannot move at the pose written in the file"
    if holding:

        def what(name: str) -> tuple[str, str]:
            field, role, verb, _, _ = HOLDS[held[name][1]]
            return (
                f"joint '{name}' holds the {held[name][1]} it would {verb} "
                f"(its {field}{': ' + role if role else ''})",
                f"the {field} of '{name}'",
            )

        joints = tuple(holding)
        if len(holding) == 1:
            [name] = holding
            fix = f"drive '{name}' instead, or remove its {HOLDS[held[name][1]].field}"
        else:
            each = ", ".join(what(n)[1] for n in holding)
            # held together, every one must go: driving one leaves the others'
            fix = (
                f"drive one of them instead, or remove one of: {each}"
                if alone
                else (f"remove all of: {each}")
            )
        message = f"{drive}: {'; '.join(what(n)[0] for n in holding)}; {fix}"
    else:
        # the other rows' combination that makes the drive's: the joints it weighs most
        weights = np.linalg.lstsq(J[rows].T, J[-1], rcond=None)[0]
        joints = tuple(j for j in eqs.joints_of(weights) if j != eqs.drive_joint)
        named = ", ".join(repr(j) for j in joints)
        if _mobility(J, rows, rcond) == 0:  # no joint could drive it: the linkage is locked
            fix = (
                "no joint can drive it: the linkage cannot move at all as written; check "
                "those joints' types, axes and centres (a rigid joint in the loop, or a "
                "pin whose axis is not parallel to the others', locks it)"
            )
        else:
            fix = "drive another joint"
        message = (
            f"{drive}: the ideal joints {named} leave its "
            f"{eqs.drive} no motion (they fix the linkage without it); {fix}"
        )
    raise MotionError(message, kind="locked", step=0, value=0.0, joints=joints, source=source)


def _check_driven(eqs: _Equations, R: FloatArray, p: FloatArray, model: Model) -> None:
    """``UnboundedMechanismError`` (exit 3) if the ideal joints and the drive
    leave a motion of some body free at the written pose."""
    Jl = np.repeat(np.eye(3)[None], len(R), axis=0)
    _, J = eqs.evaluate(R, p, Jl, 0.0)
    scale = _column_scale(eqs)
    _, sigma, Vt = np.linalg.svd(J * scale)
    rank = int(np.sum(sigma > eqs.settings.mobility_rcond * sigma[0])) if sigma.size else 0
    if rank == eqs.n:
        return
    d = Vt[-1] * scale
    sizes = [
        float(np.linalg.norm(d[6 * i : 6 * i + 6] / scale[6 * i : 6 * i + 6]))
        for i in range(eqs.n // 6)
    ]
    i = int(np.argmax(sizes))
    omega, shift = d[6 * i : 6 * i + 3], d[6 * i + 3 : 6 * i + 6]
    motion = describe_motion(omega, shift, eqs.ell)  # about the origin at the written pose
    body = eqs.bodies[i]
    raise UnboundedMechanismError(
        f"the drive '{eqs.drive_joint}' does not decide the motion: with its "
        f"{eqs.drive} fixed, the ideal joints leave body '{body}' free ({motion}); "
        "hold that motion with a joint, or drive it",
        body=body,
        motion=motion,
        direction={
            eqs.bodies[k]: (
                tuple(float(c) for c in d[6 * k : 6 * k + 3]),  # type: ignore[misc]
                tuple(float(c) for c in d[6 * k + 3 : 6 * k + 6]),
            )
            for k in range(eqs.n // 6)
        },
    )
