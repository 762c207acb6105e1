"""``--exact``: the equilibrium with exact rotations, by re-linearization.

Start from the small-displacement answer. At the current placement of every
body (``finite.placements``: P -> c_b + V + R(Omega)(P - c_b)), linearize
each contact's exact cone (``Contact.exact_parts``) and the loads' virtual
work, and solve that cone program for a step; repeat until the step is
below ``exact_settle_mm``. A small proximal term (the joint metric) makes
each step unique; it vanishes at the fixed point, where the step is 0, so
the answer is an exact-geometry equilibrium. It is accepted only if the one
certificate (``certificate.check``: feasibility, per-body balance, forces in
their cones, complementarity) holds for the exact cones linearized at the
final placement with the last program's duals, and its forces balance the
loads at the displaced points in global axes (``Result.equilibrium_residual``).

Free motions of the current placement keep the value of the small-displacement
answer (0). Derivatives are analytic: each contact's parts with respect to a
virtual twist of b in a's joint frame (``Contact.exact_jacobian``), each
body's twist with respect to its unknowns through the rotation's left
Jacobian, and the loads' virtual work likewise.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from jointplay.assembly import Assembly, BallStack
from jointplay.errors import SolverError
from jointplay.finite import IDENTITY, Linearization, Placement, placements, relative_in_joint
from jointplay.geometry import (
    FloatArray,
    cross,
    left_jacobian,
    rotation_matrix,
    rotation_vector,
    skew,
)
from jointplay.model.mechanism import Load
from jointplay.proven import Resolution, proven
from jointplay.result import (
    BodyResult,
    Certificate,
    ContactResult,
    JointResult,
    Result,
    equilibrium_residual,
    largest_force,
    points_of,
    requirements_of,
)
from jointplay.solver import certificate, conic, pipeline, records
from jointplay.solver.workspace import Balance

if TYPE_CHECKING:
    from jointplay.solver.workspace import WorkspaceData


def solve_exact(ws: WorkspaceData, loads: Sequence[Load] | None = None) -> Result:
    """The equilibrium of ``ws``'s model with exact rotations (see module doc)."""
    start = time.perf_counter()
    asm = ws.asm
    loads = tuple(asm.model.loads_of(None) if loads is None else loads)
    linear = pipeline.solve_loads(ws, loads)
    x = asm.unknowns_of(linear.bodies)
    iterations = 0
    st = ws.settings
    preload = pipeline.load_scale(ws, 0.0)  # of springs deviations press (pipeline.load_scale)
    for iterations in range(1, st.exact_max_steps + 1):  # noqa: B007 - reported below
        parts = _contact_parts(asm, x)
        g = _virtual_work(asm, x, loads)
        scale = max(float(np.linalg.norm(g)), preload)
        step, *_ = _step(ws, x, parts, g, scale)
        x = x + step
        moved = float(np.max(np.abs(step))) * asm.s  # mm (a turn: mm at the length scale)
        if moved <= st.exact_settle_mm:
            break
    else:
        raise SolverError(
            f"--exact: the re-linearization did not settle in {st.exact_max_steps} steps "
            f"(last step {moved:.3g} mm); the small-displacement answer is the one printed "
            "without --exact"
        )
    parts = _contact_parts(asm, x)
    g = _virtual_work(asm, x, loads)
    scale = max(float(np.linalg.norm(g)), preload)
    _, lam, f, nu, here = _step(ws, x, parts, g, scale)
    # the one certificate (``certificate.check``) at the final placement, in
    # its own terms: the exact cones linearized there, where the step is 0
    g_hat = g / scale if scale else g
    sigma = ws.softness(scale)
    method = f"exact rotations ({iterations} re-linearizations)"
    point = records.Point(np.zeros(asm.m), lam, f, method, iterations, nu=nu)
    cert = certificate.certify(here, g_hat, sigma, point, nu)
    if not cert.certified:
        raise SolverError(
            "--exact: the exact-geometry answer could not be certified: "
            + certificate.refusal(here, g_hat, sigma, point)
            + "; the small-displacement answer is the one printed without --exact. "
            "Please report this model."
        )
    to_newton = scale / asm.s
    result = _build(ws, x, lam * to_newton, f * to_newton, nu * to_newton, loads, cert)
    # as the small-displacement route (``pipeline``): per body and in newtons
    if result.equilibrium_residual > st.equilibrium_tolerance:
        raise SolverError(
            "--exact: the exact-geometry answer could not be certified: its contact forces "
            f"balance the loads on each body only to {result.equilibrium_residual:.3g} of the "
            f"largest force ({st.equilibrium_tolerance:g} is required); please report this model"
        )
    object.__setattr__(result, "solve_time", time.perf_counter() - start)
    # its forces are its last program's, not the split rule's: where the
    # small-displacement answer's touching contacts are redundant, so are these
    found = linear.indeterminate
    object.__setattr__(result, "_indeterminate", replace(found, by_rule=found.degree == 0))
    object.__setattr__(result, "_linearization", Linearization(cert.feasibility_mm, None, ()))
    return result


def _at_placement(ws: WorkspaceData, stack: BallStack, fixed: FloatArray) -> WorkspaceData:
    """``ws`` with the cones ``stack`` and rigid rows ``fixed`` of the exact
    geometry linearized at a placement (unknowns: the step from it), for the
    certificate."""
    out = copy.copy(ws)
    out.stack, out.E = stack, fixed
    out.balance = Balance(out)
    return out


class _Parts:
    """Every contact's exact cone parts at one placement, in mm (balls, fixed)."""

    def __init__(
        self, balls: list[tuple[FloatArray, float]], fixed: list[tuple[FloatArray, float]]
    ):
        self.balls = balls
        self.fixed = fixed

    def flat(self) -> FloatArray:
        out: list[float] = []
        for a, b in (*self.balls, *self.fixed):
            out.extend(a)
            out.append(b)
        return np.array(out)


def _contact_parts(asm: Assembly, x: FloatArray) -> _Parts:
    place = placements(asm, x)
    relative: dict[int, tuple[FloatArray, FloatArray, FloatArray]] = {}
    balls: list[tuple[FloatArray, float]] = []
    fixed: list[tuple[FloatArray, float]] = []
    for c in (*asm.balls, *asm.fixed):
        if c.joint_index not in relative:
            relative[c.joint_index] = relative_in_joint(asm, place, c.joint_index)
        a, b = c.exact_parts(asm.s, *relative[c.joint_index])
        (fixed if c.is_fixed else balls).append((a, b))
    return _Parts(balls, fixed)


def _virtual_work(asm: Assembly, x: FloatArray, loads: Sequence[Load]) -> FloatArray:
    """The loads' generalized forces at the placement ``x``: forces follow their
    points, torques do work on the spatial rotation increment ``J_l dOmega``."""
    g = np.zeros(asm.m)
    for load in loads:
        i = asm.body_index[load.body]
        omega = asm.turn[i] * x[6 * i + 3 : 6 * i + 6]
        R = rotation_matrix(omega)
        moment = np.zeros(3) if load.torque is None else np.array(load.torque, dtype=float)
        if load.force is not None:
            force = np.array(load.force, dtype=float)
            at = np.array(load.at) if load.at is not None else asm.body_ref[i]
            g[6 * i : 6 * i + 3] += asm.s * force
            moment = moment + cross(R @ (at - asm.body_ref[i]), force)
        g[6 * i + 3 : 6 * i + 6] += asm.turn[i] * left_jacobian(omega).T @ moment
    return g


def _twist_map(asm: Assembly, x: FloatArray, place: dict[str, Placement], jdx: int) -> FloatArray:
    """(6, m): scaled unknowns' variation -> virtual twist of b relative to a,
    in a's joint frame, about a's displaced joint centre."""
    joint = asm.model.joints[jdx]
    a_place = place.get(joint.between[0], IDENTITY)
    R_ga = a_place.R @ joint.R_world_joint
    O_a = a_place(joint.centre)
    T = np.zeros((6, asm.m))
    for sign, name in ((-1.0, joint.between[0]), (1.0, joint.between[1])):
        if name not in asm.body_index:
            continue
        i = asm.body_index[name]
        omega = asm.turn[i] * x[6 * i + 3 : 6 * i + 6]
        turn = asm.turn[i] * left_jacobian(omega)  # dtheta per unit scaled x
        lever = O_a - place[name](asm.body_ref[i])
        T[:3, 6 * i : 6 * i + 3] = sign * R_ga.T * asm.s
        T[:3, 6 * i + 3 : 6 * i + 6] = sign * R_ga.T @ (-skew(lever) @ turn)
        T[3:, 6 * i + 3 : 6 * i + 6] = sign * R_ga.T @ turn
    return T


def _parts_jacobian(asm: Assembly, x: FloatArray) -> FloatArray:
    """d(exact parts)/dx, stacked like ``_Parts.flat`` (mm per scaled unit)."""
    place = placements(asm, x)
    rows = []
    maps: dict[int, FloatArray] = {}
    for c in (*asm.balls, *asm.fixed):
        jdx = c.joint_index
        if jdx not in maps:
            maps[jdx] = _twist_map(asm, x, place, jdx)
        G = c.contact.exact_jacobian(*relative_in_joint(asm, place, jdx))
        rows.append(G @ maps[jdx])
    return np.vstack(rows) if rows else np.zeros((0, asm.m))


def _step(
    ws: WorkspaceData, x: FloatArray, parts: _Parts, g: FloatArray, scale: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, WorkspaceData]:
    """One linearized cone program: (step, lam, f, fixed multipliers), scaled:
    the loads' work divided by ``scale`` (``pipeline.load_scale``), and the
    workspace of that linearization (``_at_placement``).

    The same program as a small-displacement solve (``conic.cone_program``),
    with each contact's exact parts linearized at ``x``: cone i is
    ``|a_i + J_a d| + b_i + J_b d <= r_i``, a fixed contact ``a_i + J_a d = 0``,
    plus the proximal term that makes the step unique."""
    asm, m, st = ws.asm, ws.m, ws.settings
    J = _parts_jacobian(asm, x) / asm.s
    now = parts.flat() / asm.s
    # where each contact's parts sit in ``flat``: balls (vector rows, scalar), then fixed
    k = np.array([len(a) for a, _ in parts.balls], dtype=np.intp)
    scalar = np.cumsum(k + 1) - 1
    vector = np.flatnonzero(~np.isin(np.arange(int(np.sum(k + 1))), scalar))
    cursor = int(np.sum(k + 1))
    fixed_rows: list[int] = []
    for a, _ in parts.fixed:
        fixed_rows.extend(range(cursor, cursor + len(a)))
        cursor += len(a) + 1
    stack = ws.stack
    assert np.array_equal(k, stack.k), "the exact parts follow the assembly's cones"
    linear = BallStack(
        J[vector], stack.start, k, stack.r - now[scalar], stack.spring, J[scalar], -now[vector]
    )
    # free motions of the current placement (no cone or fixed row moves them):
    # the step leaves them alone, as the small-displacement answer did
    _, sv, Vt = np.linalg.svd(J, full_matrices=True)
    rank = int(np.sum(sv > st.free_motion_rcond * sv[0])) if sv.size and sv[0] > 0 else 0
    K = (asm.metric @ Vt[rank:].T).T
    Eq = np.vstack([J[fixed_rows], K])
    e = np.concatenate([-now[fixed_rows], np.zeros(len(K))])
    prog = conic.cone_program(
        ws,
        st.exact_proximal * asm.metric,
        Eq,
        e,
        linear,
        tolerance=st.fine_ipm_tolerance,
        max_iter=st.exact_ipm_iterations,
    )
    soft = np.flatnonzero(stack.spring > 0)
    if len(soft):
        prog = conic.softened(conic.with_penetrations(prog, soft), soft, ws.softness(scale))
    q = np.zeros(prog.A.shape[1])
    q[:m] = -g / scale if scale else 0.0
    sol = conic.run(ws, prog, q)
    z = np.asarray(sol.z)
    here = _at_placement(ws, linear, J[fixed_rows])
    return np.asarray(sol.x)[:m], z[prog.soc_first], z[prog.f_rows], z[: len(fixed_rows)], here


def _build(
    ws: WorkspaceData,
    x: FloatArray,
    lam: FloatArray,
    f: FloatArray,
    nu: FloatArray,
    loads: tuple[Load, ...],
    cert: Certificate,
) -> Result:
    """The exact answer as a ``Result``: bodies with their exact rotations,
    joint torsors of the exact relative placement, forces at the displaced points."""
    asm = ws.asm
    st = ws.settings
    model = asm.model
    place = placements(asm, x)
    bodies = {}
    for b in model.bodies:
        pl = place.get(b.name, IDENTITY)
        bodies[b.name] = BodyResult(b.name, pl.shift, rotation_vector(pl.R), pl.R)
    ball_index = {id(c): i for i, c in enumerate(asm.balls)}
    fixed_index: dict[int, int] = {}
    row = 0
    for c in asm.fixed:
        fixed_index[id(c)] = row
        row += c.k
    f_start = np.concatenate([[0], np.cumsum([c.k for c in asm.balls])]).astype(int)
    joints = {}
    for jdx, joint in enumerate(model.joints):
        R_rel, phi, t_rel = relative_in_joint(asm, place, jdx)
        a_place = place.get(joint.between[0], IDENTITY)
        Rw = joint.R_world_joint
        contacts = []
        total = np.zeros(6)
        for c in asm.contacts:
            if c.joint_index != jdx:
                continue
            G = c.contact.exact_jacobian(R_rel, phi, t_rel)
            i = ball_index.get(id(c))
            if i is None:
                k0 = fixed_index[id(c)]
                wrench = -G[: c.k].T @ nu[k0 : k0 + c.k]
                local_point = c.contact.point
                gap, touching, past = 1.0, True, 0.0
            else:
                fi = f[f_start[i] : f_start[i + 1]]
                wrench = -(G[: c.k].T @ fi + lam[i] * G[c.k])
                local_point = c.contact.acting_point(fi, float(lam[i]))
                level = c.exact_level(asm.s, R_rel, phi, t_rel)
                r = c.radius * asm.s
                reached = level >= -st.feasibility_tolerance * ws.max_radius * asm.s
                gap = float(np.clip(level / r, 0.0, 1.0)) if r > 0 else float(reached)
                touching = gap >= st.touching
                past = max(level - r, 0.0) if c.stiffness > 0 else 0.0
            total += wrench
            q = t_rel + R_rel @ local_point  # where b's contact point is, in a's joint frame
            contacts.append(
                ContactResult(
                    c.contact.name,
                    gap,
                    touching,
                    wrench[:3] + 0.0,
                    a_place(joint.centre + Rw @ q),
                    past if c.contact.turn_lever is None else past / c.contact.turn_lever,
                    wrench[3:] - np.cross(q, wrench[:3]),
                    "mm" if c.contact.turn_lever is None else "rad",
                )
            )
        joints[joint.name] = JointResult(
            joint.name,
            joint.type_name,
            joint.between,
            joint.centre,
            Rw,
            t_rel,
            phi,
            tuple(contacts),
            total[:3],
            total[3:],
        )
    reactions = np.array(
        [np.r_[jr.reaction_force, jr.reaction_moment] for jr in joints.values()]
    ).reshape(-1, 6)
    residual = equilibrium_residual(asm, reactions, loads, place)
    # positions to what this route certifies them (exact_tolerance_mm)
    res = Resolution.of(
        asm.s, asm.ell, largest_force(asm, reactions, loads), st, at_least=st.exact_tolerance_mm
    )
    bodies = {
        n: replace(
            b, translation=proven(b.translation, res.length), rotation=proven(b.rotation, res.angle)
        )
        for n, b in bodies.items()
    }
    joints = {n: _proven_joint(jr, res) for n, jr in joints.items()}
    points = points_of(model, bodies, res)
    energy = 0.0
    for ld in loads:
        if ld.force is not None:
            i = asm.body_index[ld.body]
            at = np.array(ld.at) if ld.at is not None else asm.body_ref[i]
            energy -= float(np.array(ld.force) @ (place[ld.body](at) - at))
    return Result(
        "optimal",
        energy,
        bodies,
        joints,
        points,
        cert,
        residual,
        0.0,
        ws.free_motions,
        requirements=requirements_of(model, points),
        model_warnings=asm.model_warnings,
        resolution=res,
        equilibrium_tolerance=st.equilibrium_tolerance,
    )


def _proven_joint(jr: JointResult, res: Resolution) -> JointResult:
    """``jr`` to what the answer proves (``proven``)."""
    contacts = tuple(
        replace(
            c,
            force=proven(c.force, res.force),
            torque=proven(c.torque, res.moment),
            point=proven(c.point, res.length),
        )
        for c in jr.contacts
    )
    # the sum of the contacts as printed (a weld has none: its own reaction)
    force = (
        sum((c.force for c in contacts), np.zeros(3))
        if contacts
        else proven(jr.reaction_force, res.force)
    )
    return replace(
        jr,
        translation=proven(jr.translation, res.length),
        rotation=proven(jr.rotation, res.angle),
        contacts=contacts,
        reaction_force=force,
        reaction_moment=proven(jr.reaction_moment, res.moment),
    )
