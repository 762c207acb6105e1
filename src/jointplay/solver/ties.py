"""Ties: when the optimal positions form a face, the least-norm one.

A load pushing squarely on a flat limit leaves a face of optimal positions.
The documented answer is the point of that face nearest the nominal one in
the least-norm metric: one more cone program on the face, polished by Newton.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from jointplay.assembly import BallStack
from jointplay.errors import SolverError
from jointplay.geometry import FloatArray
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix
from jointplay.settings import TINY
from jointplay.solver import conic, faces, held, newton, records

if TYPE_CHECKING:
    from jointplay.solver.workspace import WorkspaceData


def face_equalities(
    ws: WorkspaceData, stack: BallStack, which: records.FaceKey, x: FloatArray, reach: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Linear rows that keep the cones ``which`` where they are at ``x``:
    a surface cone keeps its direction ``u`` (``A_i x - c_i`` along ``u`` and
    ``u . (A_i x - c_i) + B_i x = reach_i``); a linear cone ``A_i x = c_i``,
    ``B_i x = reach_i``. ``reach`` is per cone of ``which`` (surface first)."""
    surface, linear = which
    v, rho = stack.norms(x)
    centres = stack.centres()
    cones = np.array([*surface, *linear], dtype=np.intp)
    on_surface = np.arange(len(cones)) < len(surface)
    plain = on_surface & (stack.k[cones] > 0) & ~stack.has_offset[cones]
    # the surface cones with no offset, all at once (a large tie has thousands)
    idx = cones[plain]
    at = stack.rows_of(idx)
    u = v[at] / np.repeat(np.maximum(rho[idx], TINY), stack.k[idx])
    rows: list[Matrix] = [stack.A[at]]
    rhs: list[FloatArray] = [centres[at] + np.repeat(reach[plain], stack.k[idx]) * u]
    size = np.where(plain, stack.k[cones], 0)  # each cone's rows, in ``which`` order
    for j in np.flatnonzero(~plain):
        i = int(cones[j])
        c = centres[stack.start[i] : stack.start[i] + stack.k[i]]
        if on_surface[j] and stack.k[i]:  # tilting on its offset
            u = v[stack.start[i] : stack.start[i] + stack.k[i]] / max(rho[i], TINY)
            across = np.linalg.svd(u[None, :])[2][1:]  # directions across u
            M = linalg.dense(stack.face_rows(i))
            rows.append(np.vstack([across @ M[:-1], u @ M[:-1] + M[-1]]))
            rhs.append(np.append(across @ c, reach[j] + u @ c))
        else:
            rows.append(stack.face_rows(i))
            rhs.append(np.append(c, reach[j]))
        size[j] = rows[-1].shape[0]
    # back in ``which`` order, cone by cone: the least-norm program's round-off
    # then does not depend on how the cones were grouped here
    grouped = np.concatenate([np.flatnonzero(plain), np.flatnonzero(~plain)])
    first = np.empty(len(cones), dtype=np.intp)
    first[grouped] = np.cumsum(size[grouped]) - size[grouped]
    at_end = np.cumsum(size) - size  # each cone's first row in ``which`` order
    order = np.repeat(first - at_end, size) + np.arange(int(np.sum(size)))
    return linalg.vstack(rows, ws.m)[order], np.concatenate(rhs)[order]


def least_norm(
    ws: WorkspaceData, sigma: FloatArray, point: records.Point, key: records.FaceKey
) -> records.Point:
    """Least-norm point of the optimal face (a tie between positions)."""
    surface, linear = key
    both = [*surface, *linear]
    # a compliant contact keeps its penetration; the others stay on its face
    reach = ws.stack.r[both] + sigma[both] * point.lam[both]
    L, L_rhs = face_equalities(ws, ws.stack, key, point.x, reach)
    Eq, e = independent_rows(
        ws, linalg.vstack([ws.Eq, L], ws.m), np.concatenate([np.zeros(ws.Eq.shape[0]), L_rhs])
    )
    in_face = set(both)
    rest_index = [i for i in range(len(ws.balls)) if i not in in_face]
    rest = ws.stack.take(rest_index)
    # a tilting face stays on the side it leans to: u . (A_i x - c_i) >= 0
    stack = ws.stack
    v, rho = stack.norms(point.x)
    leaning = [i for i in surface if stack.k[i] and stack.has_offset[i] and rho[i] > 0]
    rows = [slice(stack.start[i], stack.start[i] + stack.k[i]) for i in leaning]
    lean = [-(v[k] / rho[i]) @ linalg.dense(stack.A[k]) for i, k in zip(leaning, rows, strict=True)]
    if lean:
        centres = stack.centres()
        bound = [-(v[k] / rho[i]) @ centres[k] for i, k in zip(leaning, rows, strict=True)]
        rest = rest.with_limits(np.array(lean), np.array(bound))
    metric = ws.asm.metric_matrix
    # its answer is printed as it is where the polish fails (a 135-shaft
    # bearing chain's), and at the first try's regularization it takes more
    # steps (``fine_ipm_regularization``); a large model's goes unrefined,
    # as its interior point does (``sparse_interior_refinement``)
    fine = ws.settings.fine_ipm_regularization
    refine = conic.refined(ws.settings, ws.asm.sparse)
    prog = conic.cone_program(ws, metric, Eq, e, rest, refine=refine, regularization=fine)
    try:
        sol = conic.run(ws, prog, np.zeros(ws.m))
    except SolverError:
        # badly scaled (levers of 100 m on plays of 0.1 mm): the active-set
        # Newton alone, from the optimum, with no other contact active
        x = polish_least_norm(
            ws,
            point.x,
            np.zeros(len(rest.k)),
            np.zeros(rest.A.shape[0]),
            rest,
            Eq,
            e,
            strict=True,
            face=True,
        )
    else:
        z = np.asarray(sol.z)
        lam_rest, f_rest = z[prog.soc_first], z[prog.f_rows]
        x = polish_least_norm(ws, np.asarray(sol.x), lam_rest, f_rest, rest, Eq, e, face=True)
    # any optimal forces are complementary to every optimal position:
    # those of ``point`` hold at x, which keeps its active cones as they were
    return records.Point(
        x, point.lam, point.f, method="least-norm face", iterations=point.iterations
    )


def polish_least_norm(
    ws: WorkspaceData,
    x: FloatArray,
    lam: FloatArray,
    f: FloatArray,
    rest: BallStack,
    Eq: Matrix,
    e: FloatArray,
    strict: bool = False,
    face: bool = False,
) -> FloatArray:
    """One Newton run on the KKT equations of the least-norm program from
    its interior point ``x`` (a QP's positions are accurate only to about
    the square root of its gap: 1.3e-6 mm on a faint push under a large
    turn); ``x`` itself if that does not end feasible (or, ``strict``,
    SolverError). ``face``: ``Eq`` holds a tied face's rows,
    which repeat each other (kept as they are in a sparse system), so its
    steps are regularized from the start (``newton``'s ``repeated_rows``);
    the workspace's own equalities alone (no load) are independent."""
    metric = ws.asm.metric_matrix
    surface, linear = faces.active_set(ws, x, lam, f, rest, float(np.max(np.abs(metric @ x))))
    r = np.where(rest.r > 0, rest.r, ws.max_radius)
    st = ws.settings
    L2, l2 = face_equalities(ws, rest, ((), tuple(linear)), x, rest.r[list(linear)])
    Eq2 = linalg.vstack([Eq, L2], ws.m)
    x1, nu = x[None].copy(), np.zeros((1, Eq2.shape[0]))
    run = newton.newton(
        metric,
        np.zeros((1, ws.m)),
        Eq2,
        np.concatenate([e, l2])[None],
        rest.take(list(surface)),
        x1,
        np.maximum(lam[None, list(surface)], 0.0),
        nu,
        st,
        accept=st.newton_accept,
        least_squares=True,
        repeated_rows=face,
    )
    if run.converged[0]:
        _, _, level = rest.levels(x1[0])
        if not np.any((level - rest.r) / r > st.feasibility_tolerance):
            return np.asarray(x1[0])
    if strict:
        raise SolverError(
            "the least-norm point of a tie (an optimum that is not unique) could not "
            "be found accurately on this model. " + held.weak_hint(ws)
        )
    return x


def independent_rows(ws: WorkspaceData, C: Matrix, c: FloatArray) -> tuple[Matrix, FloatArray]:
    """Equalities ``C x = c`` as orthonormal, independent rows (least
    squares): the face's rows often repeat each other (a joint's cones
    share them), and nearly dependent rows make the solvers' multipliers
    huge and their accuracy poor. A large (sparse) system is kept as it is."""
    if linalg.is_sparse(C) or not C.shape[0]:
        return C, c
    U, sv, Vt = np.linalg.svd(np.asarray(C), full_matrices=False)
    keep = sv > ws.settings.free_motion_rcond * sv[0] if sv[0] > 0 else sv > 0
    return Vt[keep], (U[:, keep].T @ c) / sv[keep]
