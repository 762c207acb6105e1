"""Ties: when the optimal positions form a face, the least-norm one.

A load pushing squarely on a flat limit leaves a face of optimal positions.
The documented answer is the point of that face nearest the nominal one in
the least-norm metric: one more cone program on the face, polished by Newton.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from jointplay.assembly import BallStack
from jointplay.errors import SolverError
from jointplay.geometry import FloatArray
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix
from jointplay.settings import TINY
from jointplay.solver import conic, faces, held, newton

if TYPE_CHECKING:
    from jointplay.solver.workspace import Workspace


def face_equalities(
    stack: BallStack, which: faces.FaceKey, x: FloatArray, reach: FloatArray
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
    return linalg.vstack(rows, len(x))[order], np.concatenate(rhs)[order]


def least_norm(
    ws: Workspace, sigma: FloatArray, point: faces.Point, key: faces.FaceKey
) -> faces.Point:
    """Least-norm point of the optimal face (a tie between positions)."""
    face = faces.face_of(ws, key)
    if ws.sparse and face.determined is False:
        x = _least_norm_along(ws, face, _on_face(ws, sigma, point, key))
    else:
        x = _least_norm_on_rows(ws, sigma, point, key)
    # any optimal forces are complementary to every optimal position:
    # those of ``point`` hold at x, which keeps its active cones as they were
    return faces.Point(x, point.lam, point.f, method="least-norm face", iterations=point.iterations)


def _on_face(
    ws: Workspace, sigma: FloatArray, point: faces.Point, key: faces.FaceKey
) -> FloatArray:
    """The point of the face's affine hull nearest ``point.x``: every cone
    of ``key`` at its limit (its reach, with a compliant one's penetration)
    along its direction there, the rigid rows held. An interior point's
    face (when the rounds find no optimum) holds its cones only to its
    tolerance (a 50-shaft chain's: 7.5e-10 mm past), which the face's
    own coordinates would keep. Least squares (LSMR): the face's rows
    repeat each other."""
    surface, linear = key
    both = [*surface, *linear]
    reach = ws.stack.r[both] + sigma[both] * point.lam[both]
    L, l_rhs = face_equalities(ws.stack, key, point.x, reach)
    C = linalg.vstack([ws.E, L], ws.m)
    miss = np.concatenate([-linalg.times(ws.E, point.x), l_rhs - linalg.times(L, point.x)])
    return np.asarray(point.x + linalg.lstsq(C, miss))


def _least_norm_along(ws: Workspace, face: faces.Face, x0: FloatArray) -> FloatArray:
    """A large face that does not tilt: the least-norm program in the face's
    own coordinates, ``x = x0 + F t`` with F the motions it leaves free (its
    elimination's basis, sparse), columns scaled to unit metric. Its rows
    then repeat nothing, and Newton polishes it to round-off. Kept on the
    face's rows instead (repeating each other, 1e10 apart in scale: the
    metric weighs rotations by the mechanism's length), the program stopped
    4e-6 mm from the least-norm point of a 1,000-shaft bearing chain, and
    at 10,000 shafts 1.6e-5 mm past a clearance after 66 steps, and no
    Newton step solved its system. F holds the free motions too: the rows
    ``K`` keep the answer's orthogonal to them, as everywhere."""
    F = face.free_left().basis(orthonormal=False)
    metric = ws.asm.metric_matrix
    weight = np.asarray((F.T @ metric @ F).diagonal())
    F = sp.csc_matrix(F @ sp.diags(1.0 / np.sqrt(np.where(weight > 0, weight, 1.0))))
    P = sp.csr_matrix(F.T @ metric @ F)
    q = np.asarray(F.T @ (metric @ x0))
    Eq = sp.csr_matrix(ws.K @ F)
    e = -linalg.times(ws.K, x0)
    inside = {*face.key[0], *face.key[1]}
    rest = ws.stack.take([i for i in range(len(ws.balls)) if i not in inside]).along(F, x0)
    return np.asarray(x0 + F @ _least_norm(ws, P, q, Eq, e, rest, np.zeros(F.shape[1])))


def _least_norm_on_rows(
    ws: Workspace, sigma: FloatArray, point: faces.Point, key: faces.FaceKey
) -> FloatArray:
    """The least-norm program on the face's rows (independent, by an SVD)
    and the cones outside it: a small face, or one that tilts."""
    surface, linear = key
    both = [*surface, *linear]
    # a compliant contact keeps its penetration; the others stay on its face
    reach = ws.stack.r[both] + sigma[both] * point.lam[both]
    L, L_rhs = face_equalities(ws.stack, key, point.x, reach)
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
    return _least_norm(ws, ws.asm.metric_matrix, np.zeros(ws.m), Eq, e, rest, point.x)


def _least_norm(
    ws: Workspace,
    P: Matrix,
    q: FloatArray,
    Eq: Matrix,
    e: FloatArray,
    rest: BallStack,
    x0: FloatArray,
) -> FloatArray:
    """``min x P x / 2 + q x`` on ``Eq x = e`` inside the cones ``rest``:
    one cone program, polished by Newton (regularized: see
    ``polish_least_norm``); ``x0`` (an optimum, feasible) is where a badly
    scaled program's Newton starts instead."""
    prog = conic.cone_program(ws, P, Eq, e, rest)
    try:
        sol = conic.run(ws, prog, q)
    except SolverError:
        # badly scaled (levers of 100 m on plays of 0.1 mm): the active-set
        # Newton alone, from the optimum, with no other contact active
        lam, f = np.zeros(len(rest.k)), np.zeros(rest.A.shape[0])
        return polish_least_norm(ws, P, q, x0, lam, f, rest, Eq, e, True, strict=True)
    z = np.asarray(sol.z)
    lam, f = z[prog.soc_first], z[prog.f_rows]
    return polish_least_norm(ws, P, q, np.asarray(sol.x), lam, f, rest, Eq, e, True)


def polish_least_norm(
    ws: Workspace,
    P: Matrix,
    q: FloatArray,
    x: FloatArray,
    lam: FloatArray,
    f: FloatArray,
    rest: BallStack,
    Eq: Matrix,
    e: FloatArray,
    regularized: bool = False,
    strict: bool = False,
) -> FloatArray:
    """Newton on the KKT equations of the least-norm program ``min x P x / 2
    + q x`` from its interior point ``x``, with a few active-set rounds
    (cones pushed past their limit join); ``x`` itself if that does not end
    feasible (or, ``strict``, SolverError). ``regularized``: a tie's (large)
    system is singular by construction or nearly (a tilting face's rows
    repeat each other; in a face's coordinates the contacts the program
    presses are often more than the motions they hold), so its steps are
    regularized from the start (``newton``'s); the no-load route's
    equalities (the workspace's own) are independent and keep plain steps."""
    m = len(x)
    surface, linear = faces.active_set(ws, x, lam, f, rest, float(np.max(np.abs(P @ x + q))))
    active = {*surface, *linear}
    apex = set(linear)
    r = np.where(rest.r > 0, rest.r, ws.max_radius)
    st = ws.settings
    for _ in range(st.refine_rounds):
        on_surface = sorted(i for i in active if i not in apex)
        at_apex = sorted(i for i in active if i in apex)
        L2, l2 = face_equalities(rest, ((), tuple(at_apex)), x, rest.r[at_apex])
        polished = newton.newton(
            P,
            q,
            linalg.vstack([Eq, L2], m),
            np.concatenate([e, l2]),
            rest.take(on_surface),
            x,
            np.maximum(lam[on_surface], 0.0),
            settings=st,
            regularized=regularized,
        )
        if polished is None:
            break
        _, _, level = rest.levels(polished[0])
        past = set(np.flatnonzero((level - rest.r) / r > st.feasibility_tolerance).tolist())
        past -= active
        if not past:
            return polished[0]
        active |= past
        apex |= {i for i in past if rest.k[i] == 0}
    if strict:
        raise SolverError(
            "the least-norm point of a tie (an optimum that is not unique) could not "
            "be found accurately on this model. " + held.weak_hint(ws)
        )
    return x


def independent_rows(ws: Workspace, C: Matrix, c: FloatArray) -> tuple[Matrix, FloatArray]:
    """Equalities ``C x = c`` as orthonormal, independent rows (least
    squares): the face's rows often repeat each other (a joint's cones
    share them), and nearly dependent rows make the solvers' multipliers
    huge and their accuracy poor. A large (sparse) system is kept as it is."""
    if linalg.is_sparse(C) or not C.shape[0]:
        return C, c
    U, sv, Vt = np.linalg.svd(np.asarray(C), full_matrices=False)
    keep = sv > ws.settings.free_motion_rcond * sv[0] if sv[0] > 0 else sv > 0
    return Vt[keep], (U[:, keep].T @ c) / sv[keep]
