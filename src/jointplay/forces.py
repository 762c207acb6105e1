"""The split of the loads between redundant contacts: one rule, whatever the route.

When touching contacts are redundant (a carriage on four corners of its
guide, a weld in a closed loop), the optimal positions fix only some sums of
their forces. Any split that balances the loads is an optimum, and the one a
solver stops at depends on its path and on the order of the file's entries.
We report one split, the same whatever the order: among the contact forces
that balance the loads at the answer's positions (only touching contacts
push, each along its contact's direction, inside its cone), the one of least

    sum over contacts of |F_c|^2 + |M_c / ell|^2

where ``(F_c, M_c)`` is the contact's wrench at its joint centre (N, N*mm)
and ``ell`` the mechanism's length (``Assembly.ell``, which weighs rotations
in the least-norm metric of positions too). Rigid joints take part with the
wrench of their multipliers; a compliant contact's force is fixed by its
penetration and stays as it is.

The least-squares split comes from one linear (KKT) solve. Only when it
would make a contact pull, or push outside its cone, the same objective is
minimized as a small cone program with those limits.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import clarabel
import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from . import conic, linalg
from .assembly import Assembly, BallStack, IntArray
from .geometry import FloatArray
from .settings import TINY

if TYPE_CHECKING:
    from .settings import SolverSettings


@dataclass(frozen=True)
class Split:
    """Multipliers (scaled) of one answer: per cone ``lam``, force vectors
    ``f`` (stacked like ``BallStack.A``), and the rigid rows' ``nu``."""

    lam: FloatArray
    f: FloatArray
    nu: FloatArray


def least_squares_split(
    asm: Assembly,
    x: FloatArray,
    lam: FloatArray,
    f: FloatArray,
    nu: FloatArray,
    g_hat: FloatArray,
    apex_level: float,
    settings: SolverSettings,
) -> Split | None:
    """The least-squares split (module docstring) at positions ``x`` under
    unit loads ``g_hat``. ``lam``, ``f``, ``nu``: the solver's own split;
    its compliant contacts keep theirs. ``apex_level``: a cone with
    ``|A_i x|`` at or below it rests at its apex, its force vector free
    inside the cone (the position's round-off). None when no split with
    these contacts is found, or when only one balances the loads (the
    caller keeps its own). ``settings``: the
    equilibrium tolerance (how far a force may fall below 0 or outside its
    cone by round-off), the rank cutoff, the KKT regularization and the
    interior-point tolerance."""
    stack = asm.stack
    v, rho, level = stack.levels(x)
    hard = stack.spring == 0
    touching = hard & (stack.gap_used(level) >= settings.touching)
    apex = touching & ((stack.k == 0) | (rho <= apex_level))
    surface = touching & ~apex
    keep_lam = np.where(hard, 0.0, lam)
    keep_f = np.where(np.repeat(hard, stack.k), 0.0, f)
    b = g_hat - stack.adjoint(keep_f, keep_lam)
    safe = np.where(rho > 0, rho, 1.0)
    u = v / np.repeat(safe, stack.k)  # each cone's direction of contact
    Z, owner = _unknowns(stack, surface, apex, u, asm.E.shape[0], asm.sparse)
    if Z.shape[1] == 0:
        return None
    G = _work(asm, Z)
    if not asm.sparse and _determined(G, settings.free_motion_rcond):
        return None  # one split balances the loads: the solver's own
    P = _wrenches(asm, Z)
    n, n_rows = len(stack.k), stack.A.shape[0]
    centred = apex & ~stack.has_offset

    def split_of(y: FloatArray, cols: IntArray | slice = slice(None)) -> Split:
        z = Z[:, cols] @ y
        out = Split(keep_lam + z[n_rows : n_rows + n], keep_f + z[:n_rows], z[n_rows + n :])
        # a ball at its centre (no play): its force is its vector's size
        out.lam[centred] = np.sqrt(stack.segment_sum(out.f * out.f))[centred]
        return out

    given = Z.T @ np.concatenate([f - keep_f, lam - keep_lam, nu])
    given = given / np.asarray((Z.multiply(Z) if asm.sparse else Z * Z).sum(axis=0)).ravel()
    y = _least_squares(P, G, b, given, settings)
    if y is not None:
        split = split_of(y)
        if _inside(split, stack, settings.equilibrium_tolerance):
            return split
    faces = apex & stack.has_offset
    y = _cone_program(P, G, given, int(np.sum(surface)), stack.k[faces], settings)
    if y is None:
        return None
    split = split_of(y)
    # the cone program's answer is good to its tolerance; the contacts it
    # leaves unloaded out, the least-squares split of the others is exact
    pushing = split.lam > settings.positive_force * float(np.max(np.abs(split.lam)))
    cols = np.flatnonzero((owner < 0) | pushing[np.maximum(owner, 0)])
    y = _least_squares(P[:, cols], G[:, cols], b, y[cols], settings)
    if y is not None:
        exact = split_of(y, cols)
        if _inside(exact, stack, settings.equilibrium_tolerance):
            return exact
    return split


def _unknowns(
    stack: BallStack,
    surface: NDArray[np.bool_],
    apex: NDArray[np.bool_],
    u: FloatArray,
    n_e: int,
    sparse: bool,
) -> tuple[Any, IntArray]:
    """The map Z from the split's unknowns ``y`` to all multipliers
    ``(f, lam, nu)``, and each unknown's cone (-1 for a rigid row). In this
    order: a surface cone's force along ``u``; a face at its apex, its force
    and vector (``lam_i >= |f_i|``); a ball at its centre (no face row, no
    play), its vector (its force is ``|f_i|``, see ``_split``); a rigid row."""
    k = stack.k
    n_rows, n = int(np.sum(k)), len(k)
    s_idx = np.flatnonzero(surface)
    a_idx = np.flatnonzero(apex & stack.has_offset)
    c_idx = np.flatnonzero(apex & ~stack.has_offset)
    ns, ka, kc = len(s_idx), k[a_idx], k[c_idx]
    # surface cones: one column, f_i = u_i lam_i
    s_rows = stack.rows_of(s_idx)
    rows = [s_rows, n_rows + s_idx]
    cols = [np.repeat(np.arange(ns), k[s_idx]), np.arange(ns)]
    vals = [u[s_rows], np.ones(ns)]
    # faces at their apex: lam_i, then f_i
    first = (ns + np.cumsum(1 + ka) - (1 + ka)).astype(np.intp)
    within = np.arange(int(np.sum(ka))) - np.repeat(np.cumsum(ka) - ka, ka)
    rows += [n_rows + a_idx, stack.rows_of(a_idx)]
    cols += [first, np.repeat(first + 1, ka) + within]
    vals += [np.ones(len(a_idx)), np.ones(int(np.sum(ka)))]
    # balls at their centre: f_i
    col = ns + int(np.sum(1 + ka))
    rows.append(stack.rows_of(c_idx))
    cols.append(col + np.arange(int(np.sum(kc))))
    vals.append(np.ones(int(np.sum(kc))))
    col += int(np.sum(kc))
    # rigid rows
    rows.append(n_rows + n + np.arange(n_e))
    cols.append(col + np.arange(n_e))
    vals.append(np.ones(n_e))
    col += n_e
    owner = np.concatenate(
        [s_idx, np.repeat(a_idx, 1 + ka), np.repeat(c_idx, kc), np.full(n_e, -1)]
    ).astype(np.intp)
    shape = (n_rows + n + n_e, col)
    i_all = np.concatenate(rows).astype(np.intp)
    j_all = np.concatenate(cols).astype(np.intp)
    v_all = np.concatenate(vals)
    if sparse:
        Z: Any = sp.csc_matrix((v_all, (i_all, j_all)), shape=shape)
    else:
        Z = np.zeros(shape)
        Z[i_all, j_all] = v_all
    return Z, owner


def _work(asm: Assembly, Z: Any) -> Any:
    """``G = [A^T B^T E^T] Z``: the unknowns' work."""
    stack = asm.stack
    if asm.sparse:
        G_full = sp.hstack([stack.A.T, stack.B.T, sp.csr_matrix(asm.E).T], format="csr")
        return sp.csr_matrix(G_full @ Z)
    G_full = np.hstack([np.asarray(stack.A).T, np.asarray(stack.B).T, np.asarray(asm.E).T])
    return G_full @ Z


def _determined(G: FloatArray, rcond: float) -> bool:
    """Whether G's columns are independent: a single split balances the loads."""
    if G.shape[1] > G.shape[0]:
        return False
    sv = np.linalg.svd(G, compute_uv=False)
    return bool(sv.size and sv[-1] > rcond * sv[0])


def _wrenches(asm: Assembly, Z: Any) -> Any:
    """``P``: the unknowns' wrenches at the joint centres (6 per contact,
    moments over ``ell``)."""
    stack, T = asm.stack, asm.tables
    n_rows, n = stack.A.shape[0], len(stack.k)
    per = np.r_[np.ones(3), np.full(3, 1.0 / asm.ell)]
    n_ball, n_fixed = T.wrench_ball.shape[0], T.wrench_fixed.shape[0]
    w_ball, w_fixed = np.tile(per, n_ball // 6), np.tile(per, n_fixed // 6)
    offset = -(T.offset_ball * per).ravel()  # lam_i's wrench: its face row, against it
    o_rows = np.arange(6 * n)
    o_cols = np.repeat(np.arange(n), 6)
    if asm.sparse:
        ball = sp.hstack(
            [
                sp.diags(w_ball) @ T.wrench_ball,
                sp.csr_matrix((offset, (o_rows, o_cols)), shape=(6 * n, n)),
            ]
        )
        P_full = sp.block_diag([ball, sp.diags(w_fixed) @ T.wrench_fixed], format="csr")
        return sp.csr_matrix(P_full @ Z)
    n_e = asm.E.shape[0]
    P_full = np.zeros((n_ball + n_fixed, n_rows + n + n_e))
    P_full[:n_ball, :n_rows] = w_ball[:, None] * T.wrench_ball
    P_full[o_rows, n_rows + o_cols] = offset
    P_full[n_ball:, n_rows + n :] = w_fixed[:, None] * T.wrench_fixed
    return P_full @ Z


def _least_squares(
    P: Any, G: Any, b: FloatArray, given: FloatArray, settings: SolverSettings
) -> FloatArray | None:
    """The ``y`` of least ``|P y|`` with ``G y = b``. Dense: from an SVD of
    G (rows below ``rcond`` of the largest are dependent ones), to machine
    precision. Sparse: ``given + z``, a split near the answer (``G given = b``
    to round-off) corrected by the ``z`` of least ``|P (given + z)|`` with
    ``G z = b - G given``: one KKT solve, singular where G's rows depend on
    each other, regularized (``kkt_round_off``) and refined to round-off
    (``linalg.proximal_solve``); the certificate judges the answer."""
    n_y = G.shape[1]
    rcond, round_off, kkt_round_off = (
        settings.free_motion_rcond,
        settings.round_off,
        settings.kkt_round_off,
    )
    if not linalg.is_sparse(G):
        U, sv, Vt = np.linalg.svd(G, full_matrices=True)
        rank = int(np.sum(sv > rcond * sv[0])) if sv.size and sv[0] > 0 else 0
        y0 = Vt[:rank].T @ ((U[:, :rank].T @ b) / sv[:rank])
        free = Vt[rank:].T  # splits that do no work
        if not free.shape[1]:
            return np.asarray(y0)
        w = np.linalg.lstsq(P @ free, -(P @ y0), rcond=None)[0]
        return np.asarray(y0 + free @ w)
    PtP = sp.csr_matrix(P.T @ P)
    K = sp.bmat([[PtP, G.T], [G, None]], format="csc")
    rhs = np.r_[-(PtP @ given), b - G @ given]
    size = float(np.max(np.abs(rhs), initial=0.0))
    eps = kkt_round_off * float(abs(K).max())
    step = linalg.proximal_solve(K, rhs, n_y, eps, round_off * size, settings.newton_stall)
    return None if step is None else np.asarray(given + step[:n_y])


def _inside(split: Split, stack: BallStack, tol: float) -> bool:
    """Whether every contact pushes (``lam >= 0``) with its force vector
    inside its cone (``|f_i| <= lam_i``), to ``tol`` of the largest force."""
    if not len(split.lam):
        return True
    size = tol * max(float(np.max(np.abs(split.lam))), TINY)
    f_norm = np.sqrt(stack.segment_sum(split.f * split.f))
    return bool(np.all(split.lam >= -size) and np.all(f_norm <= split.lam + size))


def _cone_program(
    P: Any, G: Any, given: FloatArray, n_s: int, k_faces: IntArray, settings: SolverSettings
) -> FloatArray | None:
    """The ``y`` of least ``|P y|`` among ``y = given + z`` with ``G z = 0``
    (the same work as the solver's own split ``given``), surface forces
    non-negative and each face's ``(lam_i, f_i)`` in its cone: one Clarabel
    call. Written on ``z``, the equalities are consistent even where G's
    rows depend on each other."""
    m, n_y = G.shape
    n_cone = n_s + int(np.sum(k_faces + 1))
    cone_part = sp.eye(n_cone, n_y, format="csr")
    A = sp.vstack([sp.csr_matrix(G), -cone_part], format="csc")
    cones: list[Any] = [clarabel.ZeroConeT(m)] if m else []
    if n_s:
        cones.append(clarabel.NonnegativeConeT(n_s))
    cones += [
        clarabel.SecondOrderConeT(int(k) + 1) if k else clarabel.NonnegativeConeT(1)
        for k in k_faces
    ]
    options = clarabel.DefaultSettings()
    options.verbose = False
    options.tol_gap_abs = options.tol_gap_rel = options.tol_feas = settings.ipm_tolerance
    options.max_iter = settings.max_iterations
    refine = settings.ipm_refinement
    options.iterative_refinement_reltol = options.iterative_refinement_abstol = refine
    Q = sp.csc_matrix(P.T @ P)
    sol = clarabel.DefaultSolver(
        sp.triu(Q, format="csc"),
        Q @ given,
        A,
        np.r_[np.zeros(m), given[:n_cone]],
        cones,
        options,
    ).solve()
    if not conic.has_answer(sol):
        return None
    return np.asarray(given + np.asarray(sol.x))
