"""Newton's method on the KKT equations of an active set.

``newton`` is the one algorithm: stationarity, the active cones on their
surface and the equalities, solved to round-off from a nearby point (an
interior-point answer or a batch neighbour). ``kkt_point`` puts it on a face.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from jointplay.assembly import BallStack, IntArray
from jointplay.geometry import FloatArray
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix
from jointplay.settings import DEFAULT, SolverSettings
from jointplay.solver import faces

if TYPE_CHECKING:
    from jointplay.solver.workspace import Workspace


def weak_forces(ws: Workspace, point: faces.Point, key: faces.FaceKey) -> IntArray:
    """The cones of ``key`` whose force is not strictly positive (or, at
    the apex of a face, not strictly inside its cone)."""
    surface, linear = key
    both = np.array([*surface, *linear], dtype=np.intp)
    lam_a = point.lam[both]
    if not len(lam_a):
        return both
    strict = ws.settings.positive_force
    weak = lam_a <= strict * float(np.max(lam_a))
    if linear:
        lin = ws.stack.take(linear)
        f_norm = np.sqrt(lin.segment_sum(point.f[ws.stack.rows_of(linear)] ** 2))
        at_apex = lin.has_rim
        weak[len(surface) :] |= at_apex & (f_norm >= (1.0 - strict) * point.lam[list(linear)])
    return both[weak]


def kkt_point(
    ws: Workspace,
    g_hat: FloatArray,
    sigma: FloatArray,
    key: faces.FaceKey,
    x0: FloatArray,
    lam0: FloatArray,
    iterations: int,
    method: str,
    max_iter: int,
    pinned: bool = True,
) -> faces.Point | None:
    """The solution of the KKT equations of the active set ``key``, if
    Newton converges and (``pinned``) the face pins the position down
    (forces unchecked). Unpinned, Newton's least-squares steps stop at an
    optimum near ``x0`` on the tied face."""
    face = faces.face_of(ws, key)
    if pinned and not faces.is_determined(ws, face, x0):
        return None
    surface, linear = key
    ne = ws.Eq.shape[0]
    eq_soft = None
    if linear and np.any(sigma[list(linear)]):
        eq_soft = np.zeros(face.Eq.shape[0])
        eq_soft[ne + face.lam_rows] = sigma[list(linear)]
    out = newton(
        None,
        -g_hat,
        face.Eq,
        face.e,
        face.stack,
        x0,
        lam0[list(surface)],
        max_iter,
        sigma[list(surface)],
        eq_soft,
        settings=ws.settings,
        prox=0.0 if pinned else ws.settings.tie_prox,
        accept=ws.settings.newton_accept if pinned else ws.settings.equilibrium_tolerance,
    )
    if out is None:
        return None
    x, lam_s, nu, its, factors = out
    if pinned and not faces.is_determined(ws, face, x):
        return None
    point = assemble_point(ws, x, face, lam_s, nu[ne:], method, iterations + its)
    # a tilting face's free motion depends on x, and the factors may be a
    # few steps old (kept while they solve): they speak for flat faces only
    if factors is not None and not face.tilting and factors.regular(ws.settings.free_motion_rcond):
        point.regular_on = face.key
    return point


def assemble_point(
    ws: Workspace,
    x: FloatArray,
    face: faces.Face,
    lam_surface: FloatArray,
    nu_linear: FloatArray,
    method: str,
    iterations: int,
) -> faces.Point:
    """The full multipliers from a face's: ``lam`` and ``f`` of every cone."""
    surface, linear = face.key
    lam = np.zeros(len(ws.balls))
    f = np.zeros(ws.stack.A.shape[0])
    lam[list(surface)] = lam_surface
    v, rho = face.stack.norms(x)
    f[face.surface_rows] = face.stack.surface_forces(v, rho, lam_surface)
    lam[list(linear)] = nu_linear[face.lam_rows]
    f[face.linear_rows] = nu_linear[face.f_rows]
    faces.rimless_forces(ws.stack, list(linear), lam, f)
    return faces.Point(x, lam, f, method, iterations, active=face.key)


def newton(
    P: Matrix | None,
    q: FloatArray,
    Eq: Matrix,
    e: FloatArray,
    stack: BallStack,
    x0: FloatArray,
    lam0: FloatArray,
    max_iter: int = 30,
    soft: FloatArray | None = None,
    eq_soft: FloatArray | None = None,
    settings: SolverSettings = DEFAULT,
    prox: float = 0.0,
    accept: float = DEFAULT.newton_accept,
    repeated_rows: bool = False,
) -> tuple[FloatArray, FloatArray, FloatArray, int, linalg.Factors | None] | None:
    """Newton's method on the KKT equations of an active set.

    Stationarity ``P x + q + sum lam_i (A_i^T u_i + B_i) + Eq^T nu = 0``,
    active contacts on their surface ``|A_i x - c_i| + B_i x = r_i + soft_i lam_i``
    (``soft``: compliance, default 0), equalities ``Eq x = e + eq_soft nu``.
    A singular system (statically indeterminate contact forces) takes
    least-squares steps. ``prox`` > 0: the steps are proximal ones
    (``linalg.solve_kkt``): on a tied face, whose directions make the system
    singular only up to round-off, they stay short and end at the optimum
    nearest ``x0``, with the forces nearest ``lam0``. Returns None when its
    equations do not hold to ``accept`` (relative: stationarity to the size
    of the forces that balance, the other rows to the size of x).
    ``repeated_rows``: a sparse ``Eq`` may hold rows that repeat each other
    (a tied face's, ``ties.polish_least_norm``): the system is then
    singular by construction, and its steps are regularized from the start
    (``linalg.solve_kkt``'s ``plain``). Returned with the answer: the
    plain factors that solved its last step (made at that step or, kept
    while they solve, a few steps before; a dense run's proximal steps,
    the last system's own; None if it ended on a regularized or failed
    step), whose pivots tell whether the system is regular.
    """
    m, na, ne = len(x0), len(stack.k), Eq.shape[0]
    A, start, k, r, Bo = stack.A, stack.start, stack.k, stack.r, stack.B
    centre = stack.centres()
    sparse = linalg.is_sparse(A) or linalg.is_sparse(Eq)
    x, lam = x0.copy(), lam0.astype(float).copy()
    soft_na = np.zeros(na) if soft is None else soft
    soft_eq = np.zeros(ne) if eq_soft is None else eq_soft
    nu = np.zeros(ne)
    n = m + na + ne
    if not sparse:
        K = np.zeros((n, n))
        K[m + np.arange(na), m + np.arange(na)] = -soft_na
        K[m + na + np.arange(ne), m + na + np.arange(ne)] = -soft_eq
        K[:m, m + na :] = Eq.T
        K[m + na :, :m] = Eq
    S = stack.segment_matrix if sparse else None
    load_size = max(1.0, float(np.linalg.norm(q)))  # the loads' share of the terms' size
    best: tuple[float, FloatArray, FloatArray, FloatArray, int] | None = None
    history: list[float] = []
    factors = None  # the last step's plain factors (``linalg.solve_kkt``)
    failed = False  # a step's system could not be solved
    for it in range(max_iter + 1):
        grad = q + linalg.adjoint(Eq, nu)
        if P is not None:
            grad = grad + P @ x
        if na:
            v = linalg.times(A, x) - centre
            rho = np.sqrt(np.add.reduceat(v * v, start))
            if rho.min() == 0.0:
                return None
            u = v / rho.repeat(k)
            # sparse: A may be dense beside a sparse Eq, and J is kept sparse
            J = stack.surface_work(u) if S is None else sp.csr_matrix(S.T @ sp.diags(u) @ A + Bo)
            grad = grad + linalg.adjoint(J, lam)
            F = np.concatenate(
                [grad, rho + linalg.times(Bo, x) - r - soft_na * lam, Eq @ x - e - soft_eq * nu]
            )
        else:
            F = np.concatenate([grad, Eq @ x - e - soft_eq * nu])
        # relative errors: stationarity to the forces that balance (round-off
        # grows with them: long chains carry large ones), the contact and
        # equality rows to the size of the position
        force_scale = max(load_size, linalg.largest(lam), linalg.largest(nu))
        if P is not None:
            force_scale = max(force_scale, linalg.largest(P @ x))
        length_scale = max(1.0, linalg.largest(x))
        err = max(linalg.largest(F[:m]) / force_scale, linalg.largest(F[m:]) / length_scale)
        if best is None or err < best[0]:
            best = (err, x, lam, nu, it)
        history.append(err)
        stalled = it >= 3 and err > settings.newton_stall * min(history[-4:-1])
        if err <= settings.round_off or it == max_iter or stalled:
            break
        if na:
            c = lam / rho
            Ju = J - Bo
        if not sparse:
            H = np.zeros((m, m)) if P is None else np.array(P, dtype=float)
            if na:
                H += (A.T * c.repeat(k)) @ A - (Ju.T * c) @ Ju
                K[:m, m : m + na] = J.T
                K[m : m + na, :m] = J
            K[:m, :m] = H
            Kmat: Matrix = K
        else:
            H = sp.csr_matrix((m, m)) if P is None else sp.csr_matrix(P)
            if na:
                H = H + A.T @ sp.diags(np.repeat(c, k)) @ A - Ju.T @ sp.diags(c) @ Ju
                Jm = J
            else:
                Jm = sp.csr_matrix((0, m))
            Kmat = sp.bmat(
                [
                    [H, Jm.T, sp.csr_matrix(Eq).T],
                    [Jm, sp.diags(-soft_na) if na else None, None],
                    [sp.csr_matrix(Eq), None, sp.diags(-soft_eq) if ne else None],
                ],
                format="csc",
            )
        try:
            # proximal steps where a tie may be (dense: small systems, whose
            # refinement is cheap); a large system's only when its plain step
            # is absurd (they converge slowly on a long chain's weak modes)
            # a step solves its system once its residual is below where Newton stops
            # a tie's sparse system in Newton's own terms (``err``): a long
            # chain's tie parts forces and lengths by eight orders
            # (``linalg.solve_kkt``). Every other system keeps one floor:
            # weighted too, a 10,000-segment chain's first try failed (its
            # rounds' Newton runs) and it took the retry (5.3 s to 21 s),
            # and a dense random mechanism of the rigid-motion property test
            # answered 3e-7 of its energy apart in two placements (causes
            # not found)
            if sparse and repeated_rows:
                weights = np.r_[np.full(m, 1.0 / force_scale), np.full(n - m, 1.0 / length_scale)]
                floor = settings.round_off
            else:
                weights, floor = None, settings.round_off * min(force_scale, length_scale)
            plain = not (sparse and repeated_rows)
            step, factors = linalg.solve_kkt(
                Kmat, -F, m, 0.0 if sparse else prox, floor, plain, factors, weights
            )
            if (
                prox
                and sparse
                and (
                    linalg.largest(step[:m]) > settings.far * length_scale
                    or linalg.largest(step[m:]) > settings.far * force_scale
                )
            ):  # round-off's step along a tie or an indeterminate force
                step, factors = linalg.solve_kkt(Kmat, -F, m, prox, floor, weights=weights)
        except linalg.SingularSystemError:
            factors, failed = None, True  # an earlier system's say nothing of this one
            break
        x = x + step[:m]
        lam = lam + step[m : m + na]
        nu = nu + step[m + na :]
    assert best is not None
    err, x, lam, nu, its = best
    if err > accept:  # the certificate has the last word
        return None
    if factors is None and not failed and not sparse and len(history) > 1:
        # proximal steps (a tie may be): the last system's own LU, a few
        # microseconds, tells whether it is regular
        factors = linalg._factored(K)
    return x, lam, nu, its, factors
