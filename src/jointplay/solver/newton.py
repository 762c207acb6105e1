"""Newton's method on the KKT equations of an active set.

``newton`` is the one algorithm, batched: stationarity, the active cones on
their surface and the equalities, solved to round-off for many rows
(problems) at once, each from a nearby point (an interior-point answer or a
batch neighbour) and with its own mask over the contacts; a single solve is
a batch of one. ``kkt_point`` puts it on a face.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from jointplay.assembly import BallStack, IntArray
from jointplay.geometry import FloatArray
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix, solve_rows
from jointplay.settings import SolverSettings
from jointplay.solver import faces, records

BoolArray = NDArray[np.bool_]

if TYPE_CHECKING:
    from jointplay.solver.workspace import WorkspaceData


def weak_forces(ws: WorkspaceData, point: records.Point, key: records.FaceKey) -> IntArray:
    """The cones of ``key`` whose force is not strictly positive (or, at
    the apex of a face, not strictly inside its cone)."""
    both = np.array([*key[0], *key[1]], dtype=np.intp)
    return np.asarray(both[weak_rows(ws, point.lam[None], point.f[None], key)[0]])


def weak_rows(ws: WorkspaceData, lam: FloatArray, f: FloatArray, key: records.FaceKey) -> BoolArray:
    """(B, cones of ``key``): ``weak_forces`` of each row's forces."""
    surface, linear = key
    lam_a = lam[:, [*surface, *linear]]
    strict = ws.settings.positive_force
    weak: BoolArray = lam_a <= strict * np.max(lam_a, axis=1, keepdims=True, initial=0.0)
    if linear:
        lin = ws.stack.take(linear)
        f_norm = np.sqrt(lin.segment_sum(f[:, ws.stack.rows_of(linear)] ** 2))
        weak[:, len(surface) :] |= lin.has_rim & (f_norm >= (1.0 - strict) * lam[:, list(linear)])
    return weak


def kkt_point(
    ws: WorkspaceData,
    g_hat: FloatArray,
    sigma: FloatArray,
    key: records.FaceKey,
    x0: FloatArray,
    lam0: FloatArray,
    iterations: int,
    method: str,
    pinned: bool = True,
) -> records.Point | None:
    """The solution of the KKT equations of the active set ``key``, if
    Newton converges and (``pinned``) the face pins the position down
    (forces unchecked). Unpinned, Newton's least-squares steps stop at an
    optimum near ``x0`` on the tied face."""
    face = faces.face_of(ws, key)
    if pinned and not faces.is_determined(ws, face, x0):
        return None
    surface, linear = key
    ne = ws.Eq.shape[0]
    eq_soft = np.zeros((1, face.Eq.shape[0]))
    eq_soft[0, ne + face.lam_rows] = sigma[list(linear)]
    x, lam_s = x0[None].copy(), lam0[None, list(surface)].astype(float)
    nu = np.zeros((1, face.Eq.shape[0]))
    st = ws.settings
    run = newton(
        None,
        -g_hat[None],
        face.Eq,
        face.e[None],
        face.stack,
        x,
        lam_s,
        nu,
        st,
        soft=sigma[None, list(surface)],
        eq_soft=eq_soft,
        accept=st.newton_accept if pinned else st.equilibrium_tolerance,
        least_squares=True,
        prox=0.0 if pinned else st.tie_prox,
    )
    if not run.converged[0] or (pinned and not faces.is_determined(ws, face, x[0])):
        return None
    point = assemble_point(ws, x[0], face, lam_s[0], nu[0, ne:], method, iterations + run.steps)
    # a tilting face's free motion depends on x, and the factors may be a
    # few steps old (kept while they solve): they speak for flat faces only
    factors = run.factors
    if factors is not None and not face.tilting and factors.regular(st.free_motion_rcond):
        point.regular_on = face.key
    return point


def assemble_point(
    ws: WorkspaceData,
    x: FloatArray,
    face: records.Face,
    lam_surface: FloatArray,
    nu_linear: FloatArray,
    method: str,
    iterations: int,
) -> records.Point:
    """The point of a face's multipliers: ``lam`` and ``f`` of every cone."""
    lam, f = face_forces(ws, face, x[None], lam_surface[None], nu_linear[None])
    return records.Point(x, lam[0], f[0], method, iterations, active=face.key)


def face_forces(
    ws: WorkspaceData,
    face: records.Face,
    x: FloatArray,
    lam_surface: FloatArray,
    nu_linear: FloatArray,
    c_surface: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Rows' full multipliers from a face's (its surface cones' forces, its
    equalities' multipliers past the workspace's own): ``lam`` and ``f`` of
    every cone; ``c_surface``: each row's centres of the surface cones."""
    surface, linear = face.key
    lam = np.zeros((len(x), len(ws.balls)))
    f = np.zeros((len(x), ws.stack.A.shape[0]))
    lam[:, list(surface)] = lam_surface
    v, rho = face.stack.norms(x, c_surface)
    f[:, face.surface_rows] = face.stack.surface_forces(v, rho, lam_surface)
    lam[:, list(linear)] = nu_linear[:, face.lam_rows]
    f[:, face.linear_rows] = nu_linear[:, face.f_rows]
    faces.rimless_forces(ws.stack, list(linear), lam, f)
    return lam, f


def _kkt_step(
    K: Matrix,
    rhs: FloatArray,
    m: int,
    size: float,
    floor: float,
    weights: FloatArray,
    settings: SolverSettings,
    shift: float,
) -> tuple[FloatArray, linalg.Factors | None]:
    """One Newton step's solve: residual at ``kkt_plain`` of the right side
    plain, ``kkt_refined`` regularized, and never below ``floor``."""
    bar = settings.kkt_refined if shift else settings.kkt_plain
    tol = max(bar * size, floor) / weights
    return linalg.solve_kkt(K, rhs, m, tol=tol, refinements=settings.kkt_refinements, shift=shift)


class Run(NamedTuple):
    """What a Newton run did: each row's verdict (its equations hold to
    ``accept``), the most steps a row took, and, for a batch of one, the
    plain factors that solved its last step (None if it ended on a
    regularized or failed one), whose pivots tell whether it is regular."""

    converged: BoolArray
    steps: int
    factors: linalg.Factors | None


def newton(
    P: Matrix | None,
    q: FloatArray,
    Eq: Matrix,
    e: FloatArray,
    stack: BallStack,
    x: FloatArray,
    lam: FloatArray,
    nu: FloatArray,
    settings: SolverSettings,
    *,
    r: FloatArray | None = None,
    c: FloatArray | None = None,
    soft: FloatArray | None = None,
    eq_soft: FloatArray | None = None,
    active: BoolArray | None = None,
    accept: float,
    least_squares: bool = False,
    prox: float = 0.0,
    repeated_rows: bool = False,
) -> Run:
    """Newton's method on the KKT equations of an active set, for B rows
    (problems) at once; ``x`` (B, m), ``lam`` (B, na), ``nu`` (B, ne) are
    each row's start and become its best iterate.

    Stationarity ``P x + q + sum lam_i (A_i^T u_i + B_i) + Eq^T nu = 0``,
    active cones on their surface ``|A_i x - c_i| + B_i x = r_i + soft_i lam_i``,
    equalities ``Eq x = e + eq_soft nu``; ``q``, ``e``, ``r``, ``c``, ``soft``,
    ``eq_soft`` are per row (``r``, ``c`` default to the stack's own).
    ``active`` (B, na + ne): a row's multipliers outside its mask are held at
    0 and their equations dropped (the independent part of a redundant set).
    A row stops at round-off, when it stalls (a step gains less than
    ``newton_stall`` on the best of the three before it) or diverges, or
    after ``newton_steps``; errors are relative (stationarity to the forces
    that balance, the other rows to the size of x), and a row has converged
    when its best is below ``accept``.

    Rows whose system is singular fail alone, unless ``least_squares`` (a
    batch of one, whose set may be redundant or tied): then its steps are
    ``linalg.solve_kkt``'s least-squares ones, proximal (``prox`` > 0) on a
    face that may be tied, so that they end at the optimum nearest the
    start. A sparse system (a large model) is a batch of one.
    ``repeated_rows``: a sparse ``Eq`` holds rows that repeat each other (a
    tied face's, ``ties.polish_least_norm``), and its steps are regularized
    from the start.
    """
    B, m = x.shape
    na, ne = len(stack.k), Eq.shape[0]
    if active is not None and not np.all(np.any(active, axis=0)):
        # multipliers no row uses: a smaller system, the same steps
        used = np.any(active, axis=0)
        cones, eqs = np.flatnonzero(used[:na]), np.flatnonzero(used[na:])
        rows = stack.rows_of(cones)
        lam_u, nu_u = lam[:, cones], nu[:, eqs]
        run = newton(
            P, q, Eq[eqs], e[:, eqs], stack.take(cones), x, lam_u, nu_u, settings,
            r=None if r is None else r[:, cones],
            c=None if c is None else c[:, rows],
            soft=None if soft is None else soft[:, cones],
            eq_soft=None if eq_soft is None else eq_soft[:, eqs],
            active=active[:, used], accept=accept, least_squares=least_squares,
            prox=prox, repeated_rows=repeated_rows,
        )  # fmt: skip
        lam[:], nu[:] = 0.0, 0.0
        lam[:, cones], nu[:, eqs] = lam_u, nu_u
        return run
    n = m + na + ne
    sparse = linalg.is_sparse(stack.A) or linalg.is_sparse(Eq) or linalg.is_sparse(P)
    assert B == 1 or not (sparse or least_squares), "a sparse or least-squares batch is of one"
    k, start = stack.k, stack.start
    r = np.broadcast_to(stack.r, (B, na)) if r is None else r
    c = np.broadcast_to(stack.centres(), (B, stack.A.shape[0])) if c is None else c
    # the multipliers as one (B, na + ne), with their rows' right sides and softness
    y = np.hstack([lam, nu])
    target = np.hstack([r, e])
    softness = np.hstack([np.zeros((B, na)) if soft is None else soft, np.zeros((B, ne))])
    if eq_soft is not None:
        softness[:, na:] = eq_soft
    off = None if active is None or np.all(active) else ~active
    if off is not None:
        y[off] = 0.0
    if sparse:
        A, Bo, E, Pm = stack.A, stack.B, Eq, P
    else:
        A, Bo, E = linalg.dense(stack.A), linalg.dense(stack.B), linalg.dense(Eq)
        Pm = None if P is None else linalg.dense(P)
        K0 = np.zeros((n, n))
        K0[:m, m + na :], K0[m + na :, :m] = E.T, E
        # many rows: each cone's rows as one matrix, so that ``u @ T`` is every
        # cone's ``u_i^T A_i`` (B, na * m) and ``w @ AA`` every
        # ``sum_i w_i A_i^T A_i`` (B, m * m), one product each for all rows
        stacked = B > 1 and na > 0
        if stacked:
            T3 = np.zeros((A.shape[0], na, m))
            T3[np.arange(A.shape[0]), np.repeat(np.arange(na), k)] = A
            T = T3.reshape(A.shape[0], na * m)
            AA = (A[:, :, None] * A[:, None, :]).reshape(A.shape[0], m * m)
        BE_T = np.vstack([Bo, E]).T  # each multiplier's row's gradient
    load = np.maximum(1.0, np.linalg.norm(q, axis=1))  # the loads' share of the terms' size
    best = np.full(B, np.inf)
    best_x, best_y = x.copy(), y.copy()
    history = np.full((B, settings.newton_steps + 1), np.inf)
    todo = np.arange(B)
    factors: linalg.Factors | None = None  # a batch of one's last plain factors
    Kmat: Matrix | None = None
    last: FloatArray | None = None  # a dense batch of one's last system
    failed = False  # its step could not be solved
    steps = 0
    diag = np.arange(m, n)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for it in range(settings.newton_steps + 1):
            xs, ys = x[todo], y[todo]
            ls, ns = ys[:, :na], ys[:, na:]
            v = (linalg.times(A, xs[0])[None] if sparse else xs @ A.T) - c[todo]
            rho = np.sqrt(np.add.reduceat(v * v, start, axis=1)) if na else np.zeros((len(todo), 0))
            u = v / np.repeat(np.where(rho > 0, rho, 1.0), k, axis=1)
            if sparse:
                S, Ju = stack.segment_matrix, None
                J: Any = sp.csr_matrix(S.T @ sp.diags(u[0]) @ A + Bo)
                grad = q[todo] + (linalg.adjoint(J, ls[0]) + linalg.adjoint(E, ns[0]))[None]
                if Pm is not None:
                    grad = grad + linalg.times(Pm, xs[0])[None]
                reach = np.concatenate([linalg.times(Bo, xs[0]), linalg.times(E, xs[0])])[None]
            else:
                if stacked:
                    Ju = (u @ T).reshape(-1, na, m)
                else:
                    Ju = np.add.reduceat(u[:, :, None] * A[None], start, axis=1) if na else None
                J = (Ju if Ju is not None else np.zeros((len(todo), 0, m))) + Bo
                grad = q[todo] + ns @ E + (ls[:, None, :] @ J)[:, 0]
                if Pm is not None:
                    grad = grad + xs @ Pm.T
                reach = xs @ BE_T
            reach[:, :na] += rho
            F = np.concatenate([grad, reach - target[todo] - softness[todo] * ys], axis=1)
            lost = (rho == 0).any(axis=1)  # an active contact at its centre has no direction
            if off is not None:
                F[:, m:][off[todo]] = 0.0
                lost = ((rho == 0) & ~off[todo, :na]).any(axis=1)
            force = np.maximum(load[todo], np.abs(ys).max(axis=1, initial=0.0))
            if Pm is not None:
                px = linalg.times(Pm, xs[0])[None] if sparse else xs @ Pm.T
                force = np.maximum(force, np.abs(px).max(axis=1))
            length = np.maximum(1.0, np.abs(xs).max(axis=1))
            err = np.maximum(
                np.abs(F[:, :m]).max(axis=1) / force,
                np.abs(F[:, m:]).max(axis=1, initial=0.0) / length,
            )
            err[lost | ~np.isfinite(err)] = np.inf
            better = err < best[todo]
            if better.any():
                won = todo[better]
                best[won], best_x[won], best_y[won] = err[better], xs[better], ys[better]
            history[todo, it] = err
            before = history[todo, max(it - 3, 0) : it].min(axis=1, initial=np.inf)
            stalled = err > settings.newton_stall * before if it >= 3 else np.zeros_like(err, bool)
            keep = ~((err <= settings.round_off) | stalled | ~np.isfinite(err))
            if it == settings.newton_steps or not keep.any():
                break
            steps = it + 1
            if not keep.all():
                todo, xs, ls, F, rho = todo[keep], xs[keep], ls[keep], F[keep], rho[keep]
                force, length = force[keep], length[keep]
                J, Ju = J[keep], (Ju[keep] if Ju is not None else None)  # dense: sparse is of one
            w = ls / np.where(rho > 0, rho, 1.0)  # each cone's curvature weight
            if sparse:
                Ju_s = J - Bo
                H = A.T @ sp.diags(np.repeat(w[0], k)) @ A - Ju_s.T @ sp.diags(w[0]) @ Ju_s
                if Pm is not None:
                    H = H + sp.csr_matrix(Pm)
                Kmat = sp.bmat(
                    [
                        [H, J.T, sp.csr_matrix(E).T],
                        [J, sp.diags(-softness[todo[0], :na]) if na else None, None],
                        [sp.csr_matrix(E), None, sp.diags(-softness[todo[0], na:]) if ne else None],
                    ],
                    format="csc",
                )
            else:
                Kb = np.repeat(K0[None], len(todo), axis=0)
                if Ju is not None:
                    if stacked:
                        Kb[:, :m, :m] = (np.repeat(w, k, axis=1) @ AA).reshape(-1, m, m)
                    else:
                        Kb[:, :m, :m] = (A.T[None] * np.repeat(w, k, axis=1)[:, None, :]) @ A
                    Kb[:, :m, :m] -= (Ju * w[:, :, None]).transpose(0, 2, 1) @ Ju
                if Pm is not None:
                    Kb[:, :m, :m] += Pm
                Kb[:, :m, m : m + na] = J.transpose(0, 2, 1)
                Kb[:, m : m + na, :m] = J
                Kb[:, diag, diag] = -softness[todo]
                if off is not None:  # a multiplier held at 0: its own row and column
                    held_at_0 = off[todo]
                    Kb[:, m:, :] *= ~held_at_0[:, :, None]
                    Kb[:, :, m:] *= ~held_at_0[:, None, :]
                    Kb[:, diag, diag] += held_at_0
            if sparse or least_squares:
                Kone = Kmat if sparse else Kb[0]
                last = None if sparse else Kb[0]
                assert Kone is not None
                weighted = sparse and repeated_rows
                # a tie's sparse system in Newton's own terms (its forces and
                # lengths part by eight orders on a long chain); every other
                # system stops its step at Newton's own floor
                weights = (
                    np.r_[np.full(m, 1.0 / force[0]), np.full(n - m, 1.0 / length[0])]
                    if weighted
                    else None
                )
                floor = settings.round_off * (1.0 if weighted else min(force[0], length[0]))
                w_rows = np.ones(n) if weights is None else weights
                size = linalg.largest(w_rows * F[0])
                solve = functools.partial(_kkt_step, Kone, -F[0], m, size, floor, w_rows, settings)
                try:
                    shift = settings.kkt_round_off if weighted else (0.0 if sparse else prox)
                    try:
                        step, factors = solve(shift)
                    except linalg.SingularSystemError:
                        try:
                            if shift:
                                raise
                            step, factors = solve(settings.kkt_round_off)  # singular: regularized
                        except linalg.SingularSystemError:
                            if sparse:
                                raise
                            # no step solves it (a degenerate set): its least squares
                            step = linalg.lstsq(Kone, -F[0], settings.lstsq_rcond, 0)
                            factors = None
                    if (
                        prox
                        and sparse
                        and (
                            linalg.largest(step[:m]) > settings.far * length[0]
                            or linalg.largest(step[m:]) > settings.far * force[0]
                        )
                    ):  # round-off's step along a tie or an indeterminate force
                        step, factors = solve(prox)
                except linalg.SingularSystemError:
                    factors, failed = None, True  # an earlier system's say nothing of this one
                    break
                steps_rows = step[None]
            else:
                steps_rows, regular = solve_rows(Kb, -F)
                todo, steps_rows = todo[regular], steps_rows[regular]  # a singular row fails alone
            x[todo] += steps_rows[:, :m]
            y[todo] += steps_rows[:, m:]
    x[:], lam[:], nu[:] = best_x, best_y[:, :na], best_y[:, na:]
    if factors is None and not failed and last is not None:
        # proximal steps (a tie may be): the last system's own LU, a few
        # microseconds, tells whether it is regular
        factors = linalg._factored(last)
    return Run(best <= accept, steps, factors)
