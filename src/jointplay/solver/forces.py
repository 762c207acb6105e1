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
penetration and stays as it is. A compliant face pressed flat (at its cone's
apex) keeps that force, but where it acts on the face (its force vector, the
centre of pressure) is not fixed by the positions: it is split by the same
rule, inside the face's cone.

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

from jointplay.assembly import Assembly, BallStack, IntArray
from jointplay.geometry import FloatArray
from jointplay.numerics import linalg
from jointplay.settings import GRAM_CERTAIN, GRAM_MARGIN, TINY
from jointplay.solver import conic

if TYPE_CHECKING:
    from jointplay.settings import SolverSettings


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
    unique_on: tuple[tuple[int, ...], tuple[int, ...]] | None = None,
) -> Split | None:
    """The least-squares split (module docstring) at positions ``x`` under
    unit loads ``g_hat``. ``lam``, ``f``, ``nu``: the solver's own split;
    its compliant contacts keep theirs (a face pressed flat, its force but
    not its force vector: ``_pressing``). ``apex_level``: a cone with
    ``|A_i x|`` at or below it rests at its apex, its force vector free
    inside the cone (the position's round-off). None when no split with
    these contacts is found, or when only one balances the loads (the
    caller keeps its own). ``settings``: the
    equilibrium tolerance (how far a force may fall below 0 or outside its
    cone by round-off), the rank cutoff, the KKT regularization and the
    interior-point tolerance. ``unique_on``: a face (surface cones, those
    at their apex) of a hard model whose Newton system was regular, so its
    rows are independent: if its cones are the touching ones, in the same
    classes, their forces are the only ones (None is returned at once)."""
    stack = asm.stack
    surface, apex, pressed, u = _classes(stack, x, stack.r, apex_level, settings, lam=lam)
    if unique_on is not None and (
        np.flatnonzero(surface).tolist() == sorted(unique_on[0])
        and np.flatnonzero(apex).tolist() == sorted(unique_on[1])
    ):
        return None
    keep_lam, keep_f = _compliant(stack, lam, f, pressed)
    b = g_hat - stack.adjoint(keep_f, keep_lam)
    Z, owner = _unknowns(stack, surface, apex, u, asm.E.shape[0], asm.sparse)
    if Z.shape[1] == 0:
        return None
    G, b = _pressing(_work(asm, Z), b, owner, pressed, lam)
    if not asm.sparse and _determined_rows(G[None], settings.free_motion_rcond)[0]:
        return None  # one split balances the loads: the solver's own
    P = _wrenches(asm, Z)
    centred = apex & ~stack.has_offset

    def split_of(y: FloatArray, cols: IntArray | slice = slice(None)) -> Split:
        return _split_of(stack, Z[:, cols] @ y, keep_lam, keep_f, centred)

    given = Z.T @ np.concatenate([f - keep_f, lam - keep_lam, nu])
    given = given / np.asarray((Z.multiply(Z) if asm.sparse else Z * Z).sum(axis=0)).ravel()
    y = _least_squares(P, G, b, given, asm.m, settings)
    if y is not None:
        split = split_of(y)
        if _inside(split.lam, split.f, stack, settings.equilibrium_tolerance):
            return split
    faces = apex & stack.has_offset
    refine = conic.refined(settings, asm.sparse)
    d = _part_scales(G, P, owner, given)
    given_hat = np.divide(given, d, out=np.zeros_like(given), where=d > 0)
    y = _cone_program(P, G, given_hat, int(np.sum(surface)), stack.k[faces], settings, refine)
    if y is None:
        return None
    y = y * d
    split = split_of(y)
    # the cone program's answer is good to its tolerance; the limits that
    # bind it held as equalities, the split is exact
    if not asm.sparse:
        rows = least_squares_rows(
            asm,
            x[None],
            lam[None],
            f[None],
            g_hat[None],
            stack.r[None],
            (split.lam[None], split.f[None]),
            apex_level,
            settings,
        )
        if rows[0][0]:
            return Split(rows[1][0], rows[2][0], rows[3][0])
        return split
    pushing = split.lam > settings.positive_force * float(np.max(np.abs(split.lam)))
    cols = np.flatnonzero((owner < 0) | pushing[np.maximum(owner, 0)])
    y = _least_squares(P[:, cols], G[:, cols], b, y[cols], asm.m, settings)
    if y is not None:
        exact = split_of(y, cols)
        if _inside(exact.lam, exact.f, stack, settings.equilibrium_tolerance):
            return exact
    return split


def least_squares_rows(
    asm: Assembly,
    x: FloatArray,
    lam: FloatArray,
    f: FloatArray,
    g_hat: FloatArray,
    radii: FloatArray,
    near: tuple[FloatArray, FloatArray],
    apex_level: float,
    settings: SolverSettings,
    centres: FloatArray | None = None,
) -> tuple[NDArray[np.bool_], FloatArray, FloatArray, FloatArray]:
    """``least_squares_split`` of B answers at once (rows of ``x``, ``lam``,
    ``f``, ``g_hat``, each with its own cone ``radii`` and, if given,
    ``centres``; dense models), on the cone limits that bind a split ``near`` it.

    ``near = (lam, f)``: rows of a split close to each row's, such as the
    cone program's answer or a neighbouring sample's split. Its touching
    contacts with no force are left unloaded (the least-squares split of all
    would pull on them), and its faces whose force reaches their rim
    (``|f_i| = lam_i``: the centre of pressure on the rim) keep it there.
    The split is the least-squares one with those limits held as
    equalities, by Newton from ``near`` (``_split_newton``). It is the
    rule's only if no other limit is broken and none of these could be let
    go with profit (their multipliers are >= 0).

    Returns the mask of the rows whose split is the rule's, and every row's
    ``(lam, f, nu)`` (the rule's where the mask holds)."""
    stack = asm.stack
    B, n_e = x.shape[0], asm.E.shape[0]
    surface, apex, pressed, u = _classes(stack, x, radii, apex_level, settings, centres, lam)
    keep_lam, keep_f = _compliant(stack, lam, f, pressed)
    b = g_hat - stack.adjoint(keep_f, keep_lam)
    ok = np.zeros(B, dtype=bool)
    lam, f, nu = lam.copy(), f.copy(), np.zeros((B, n_e))
    faces = apex & stack.has_offset & (stack.k > 0)
    lam_n, f_n = near
    top = np.max(np.abs(lam_n), axis=1, keepdims=True, initial=0.0)
    pushing = lam_n > settings.noise_force * top  # below: the cone program's round-off
    on_rim = np.sqrt(stack.segment_sum(f_n * f_n)) >= (1.0 - settings.apex) * lam_n
    # only one-sign unknowns are held at 0: a surface force, a one-sided
    # limit's (a ball at its centre has a vector of either sign)
    unloaded = ~pushing & (surface | (apex & (stack.k == 0)))
    rim = pushing & on_rim & faces
    start = np.concatenate([f_n - keep_f, lam_n - keep_lam, np.zeros((B, n_e))], axis=1)
    # rows whose contacts touch alike share the shape of their unknowns
    first_kind, kind = linalg.distinct_rows(np.hstack([surface, apex, pressed, unloaded, rim]))
    for rows in (np.flatnonzero(kind == g) for g in range(len(first_kind))):
        s, a, d, e = surface[rows[0]], apex[rows[0]], unloaded[rows[0]], rim[rows[0]]
        # rows that pose the same problem (a study whose plays vary and whose
        # loads do not, on contacts whose directions do not move) are solved once
        first, same = linalg.distinct_rows(
            np.hstack([b[rows], u[rows], start[rows], lam[rows][:, pressed[rows[0]]]])
        )
        Z, owner = _unknowns(stack, s, a, u[rows[first]], n_e, False)
        if Z.shape[-1] == 0:
            continue
        G, b_rows = _pressing(
            _work(asm, Z), b[rows[first]], owner, pressed[rows[0]], lam[rows[first]]
        )
        # a split that one balance determines is the row's own (as in
        # ``least_squares_split``): its touching contacts are not redundant
        determinate = _determined_rows(G, settings.free_motion_rcond)[same]
        ok[rows[determinate]] = True
        if np.all(determinate):
            continue
        P = _wrenches(asm, Z)
        cone = np.maximum(owner, 0)
        keep = np.flatnonzero((owner < 0) | ~d[cone])
        # a face's columns: its lam first, then its force vector
        rims = [np.flatnonzero(owner == i) for i in np.flatnonzero(e)]
        y0 = np.einsum("brj,br->bj", Z, start[rows[first]]) / np.sum(Z * Z, axis=1)
        y, optimal = _split_newton(P, G, b_rows, keep, rims, settings, y0)
        z = (Z @ y[:, :, None])[same, :, 0]
        out = _split_of(stack, z, keep_lam[rows], keep_f[rows], a & ~stack.has_offset)
        split = rows[~determinate]
        lam[split], f[split], nu[split] = (v[~determinate] for v in (out.lam, out.f, out.nu))
        inside = _inside(out.lam, out.f, stack, settings.equilibrium_tolerance)
        ok[split] = (optimal[same] & inside)[~determinate]
    return ok, lam, f, nu


def _split_newton(
    P: FloatArray,
    G: FloatArray,
    b: FloatArray,
    keep: IntArray,
    rims: list[IntArray],
    settings: SolverSettings,
    y0: FloatArray | None = None,
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The ``y`` (rows) of least ``|P y|^2 / 2`` with ``G y = b``, the
    unknowns outside ``keep`` at 0 and each face of ``rims`` (its columns:
    ``lam_i``, then ``f_i``) with ``|f_i| = lam_i``: Newton on the KKT
    equations from ``y0`` (needed with rims: their force's direction; else
    the first step is the least-squares split, the problem being linear).
    Also the mask of the rows where that is the optimum of the cone
    program: the equations hold (``newton_accept``), each rim's multiplier
    is >= 0 and so is the gradient on each unknown held at 0 (to
    ``equilibrium_tolerance``)."""
    B, m, n_y = G.shape
    Pk, Gk = P[:, :, keep], G[:, :, keep]
    Q = Pk.transpose(0, 2, 1) @ Pk
    where = {int(c): j for j, c in enumerate(keep)}
    rims = [np.array([where[int(c)] for c in cols]) for cols in rims]
    nk, nr = len(keep), len(rims)
    n = nk + m + nr
    z = np.zeros((B, n))  # y on keep, mu, eta
    if y0 is not None:
        z[:, :nk] = y0[:, keep]
    ok = np.zeros(B, dtype=bool)
    scale = np.maximum(np.max(np.abs(b), axis=1, initial=0.0), TINY)
    # G's rows depend on each other where no contact works (a free spin):
    # a regularization of mu that small leaves every step exact to round-off
    # on a consistent system (the steps refine it), and LU never meets a
    # singular matrix
    K0 = np.zeros((B, n, n))
    K0[:, :nk, :nk] = Q
    K0[:, :nk, nk : nk + m] = Gk.transpose(0, 2, 1)
    K0[:, nk : nk + m, :nk] = Gk
    size = np.max(np.abs(K0), axis=(1, 2), initial=1.0)
    K0[:, nk + np.arange(m), nk + np.arange(m)] = -settings.kkt_round_off * size[:, None]
    polished = False
    for step in range(settings.newton_steps + 1):
        yk, mu, eta = z[:, :nk], z[:, nk : nk + m], z[:, nk + m :]
        K = K0.copy()
        grad = (Q @ yk[:, :, None])[:, :, 0] + np.einsum("bmy,bm->by", Gk, mu)
        c = np.zeros((B, nr))
        for j, cols in enumerate(rims):
            at, fc = cols[0], cols[1:]
            size = np.maximum(np.linalg.norm(yk[:, fc], axis=1), TINY)
            w = yk[:, fc] / size[:, None]
            c[:, j] = size - yk[:, at]
            row = np.zeros((B, nk))
            row[:, fc], row[:, at] = w, -1.0
            grad += eta[:, j : j + 1] * row
            curve = (np.eye(len(fc))[None] - w[:, :, None] * w[:, None, :]) / size[:, None, None]
            K[:, fc[:, None], fc[None, :]] += eta[:, j, None, None] * curve
            K[:, nk + m + j, :nk] = row
            K[:, :nk, nk + m + j] = row
        F = np.concatenate([grad, (Gk @ yk[:, :, None])[:, :, 0] - b, c], axis=1)
        ok = np.max(np.abs(F), axis=1) <= settings.newton_accept * scale
        if np.all(ok):
            if polished:
                break
            polished = True  # one more step: from there quadratic to round-off
        if step == settings.newton_steps:
            break  # ``ok`` is that of the last step's answer
        z += linalg.solve_stack(K, -F, settings.kkt_plain, settings.lstsq_rcond)
    yk, mu, eta = z[:, :nk], z[:, nk : nk + m], z[:, nk + m :]
    y = np.zeros((B, n_y))
    y[:, keep] = yk
    # multipliers of the limits: each rim's, and the gradient on each unknown at 0
    size = settings.equilibrium_tolerance * np.maximum(
        np.max(np.abs(Q @ yk[:, :, None]), axis=(1, 2), initial=0.0), TINY
    )
    held = np.setdiff1d(np.arange(n_y), keep)
    if len(held):
        grad = (P.transpose(0, 2, 1) @ (P @ y[:, :, None]))[:, :, 0]
        grad += np.einsum("bmy,bm->by", G, mu)
        ok &= np.all(grad[:, held] >= -size[:, None], axis=1)
    ok &= np.all(eta >= -size[:, None], axis=1)
    return y, ok


def _classes(
    stack: BallStack,
    x: FloatArray,
    radii: FloatArray,
    apex_level: float,
    settings: SolverSettings,
    centres: FloatArray | None = None,
    lam: FloatArray | None = None,
) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_], FloatArray]:
    """Which hard contacts touch on their cone's surface, and which rest at
    its apex (a one-sided limit, a face flat, a ball centred: ``|A_i x|`` at
    or below ``apex_level``); which compliant faces are pressed flat (with
    force ``lam``: counted with the apex ones, see ``_pressing``); and each
    cone's direction of contact ``u``. One answer (m,) or rows (B, m) with
    their ``radii`` (and ``centres``)."""
    v, rho, level = stack.levels(x, centres)
    flat = (stack.k == 0) | (rho <= apex_level)
    reach = settings.feasibility_tolerance * stack.largest_play()
    touching = (stack.spring == 0) & (stack.gap_used(level, reach, radii) >= settings.touching)
    apex = touching & flat
    pressed = np.zeros_like(apex)
    if lam is not None:
        pressed = (stack.spring > 0) & stack.has_offset & (stack.k > 0) & flat & (lam > 0)
    safe = np.where(rho > 0, rho, 1.0)
    return touching & ~apex, apex | pressed, pressed, v / np.repeat(safe, stack.k, axis=-1)


def _compliant(
    stack: BallStack, lam: FloatArray, f: FloatArray, pressed: NDArray[np.bool_]
) -> tuple[FloatArray, FloatArray]:
    """The forces the split keeps: the compliant contacts' (0 on the
    others), but for a face ``pressed`` flat, whose force vector is split."""
    hard = (stack.spring == 0) | pressed
    return np.where(hard, 0.0, lam), np.where(np.repeat(hard, stack.k, axis=-1), 0.0, f)


def _pressing(
    G: Any, b: FloatArray, owner: IntArray, pressed: NDArray[np.bool_], lam: FloatArray
) -> tuple[Any, FloatArray]:
    """The balance ``G y = b`` with a row per compliant face pressed flat
    (``pressed``, one mask for all rows): its force is ``lam_i``, the one its
    penetration makes; its force vector (its columns after ``lam_i``) is an
    unknown of the split. ``G``, ``b`` and ``lam``: one answer or rows."""
    cones = np.flatnonzero(pressed)
    if not len(cones):
        return G, b
    first = np.array([np.flatnonzero(owner == i)[0] for i in cones.tolist()], dtype=np.intp)
    rows = np.zeros((len(cones), G.shape[-1]))
    rows[np.arange(len(cones)), first] = 1.0
    fixed = lam[..., cones]
    if linalg.is_sparse(G):
        return sp.vstack([G, sp.csr_matrix(rows)], format="csr"), np.concatenate([b, fixed])
    if G.ndim == 3:
        rows_b = np.broadcast_to(rows, (G.shape[0], *rows.shape))
        return np.concatenate([G, rows_b], axis=1), np.concatenate([b, fixed], axis=1)
    return np.vstack([G, rows]), np.concatenate([b, fixed])


def _split_of(
    stack: BallStack,
    z: FloatArray,
    keep_lam: FloatArray,
    keep_f: FloatArray,
    centred: NDArray[np.bool_],
) -> Split:
    """The multipliers ``z`` of the unknowns (``Z @ y``, one row or rows)
    added to the kept ones, as ``(lam, f, nu)``."""
    n, n_rows = len(stack.k), stack.A.shape[0]
    out = Split(
        keep_lam + z[..., n_rows : n_rows + n], keep_f + z[..., :n_rows], z[..., n_rows + n :]
    )
    # a ball at its centre (no play): its force is its vector's size
    size = np.sqrt(stack.segment_sum(out.f * out.f))
    out.lam[..., centred] = size[..., centred]
    return out


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
    n_rows, n = int(k.sum()), len(k)
    s_idx = np.flatnonzero(surface)
    a_idx = np.flatnonzero(apex & stack.has_offset)
    c_idx = np.flatnonzero(apex & ~stack.has_offset)
    ns, ka, kc = len(s_idx), k[a_idx], k[c_idx]
    # surface cones: one column, f_i = u_i lam_i
    s_rows = stack.rows_of(s_idx)
    rows = [s_rows, n_rows + s_idx]
    cols = [np.repeat(np.arange(ns), k[s_idx]), np.arange(ns)]
    lead = u.shape[:-1]  # rows of a batch, if any (dense only)
    vals = [u[..., s_rows], np.ones((*lead, ns))]
    # faces at their apex: lam_i, then f_i
    first = (ns + np.cumsum(1 + ka) - (1 + ka)).astype(np.intp)
    within = np.arange(int(ka.sum())) - np.repeat(np.cumsum(ka) - ka, ka)
    rows += [n_rows + a_idx, stack.rows_of(a_idx)]
    cols += [first, np.repeat(first + 1, ka) + within]
    vals += [np.ones((*lead, len(a_idx))), np.ones((*lead, int(ka.sum())))]
    # balls at their centre: f_i
    col = ns + int((1 + ka).sum())
    rows.append(stack.rows_of(c_idx))
    cols.append(col + np.arange(int(kc.sum())))
    vals.append(np.ones((*lead, int(kc.sum()))))
    col += int(kc.sum())
    # rigid rows
    rows.append(n_rows + n + np.arange(n_e))
    cols.append(col + np.arange(n_e))
    vals.append(np.ones((*lead, n_e)))
    col += n_e
    owner = np.concatenate(
        [s_idx, np.repeat(a_idx, 1 + ka), np.repeat(c_idx, kc), np.full(n_e, -1)]
    ).astype(np.intp)
    shape = (n_rows + n + n_e, col)
    i_all = np.concatenate(rows).astype(np.intp)
    j_all = np.concatenate(cols).astype(np.intp)
    v_all = np.concatenate(vals, axis=-1)
    if sparse:
        Z: Any = sp.csc_matrix((v_all, (i_all, j_all)), shape=shape)
    else:
        Z = np.zeros((*lead, *shape))
        Z[..., i_all, j_all] = v_all
    return Z, owner


def _work(asm: Assembly, Z: Any) -> Any:
    """``G = [A^T B^T E^T] Z``: the unknowns' work."""
    stack = asm.stack
    if asm.sparse:
        G_full = sp.hstack([stack.A.T, stack.B.T, sp.csr_matrix(asm.E).T], format="csr")
        return sp.csr_matrix(G_full @ Z)
    G_full = np.hstack([np.asarray(stack.A).T, np.asarray(stack.B).T, np.asarray(asm.E).T])
    return G_full @ Z


def _determined_rows(G: FloatArray, rcond: float) -> NDArray[np.bool_]:
    """For each row of a stack (B, m, n_y): whether G's columns are
    independent, so that a single split balances the loads."""
    if not G.shape[2]:
        return np.zeros(len(G), dtype=bool)
    return linalg.full_column_rank_rows(G, rcond)


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
    P: Any, G: Any, b: FloatArray, given: FloatArray, m: int, settings: SolverSettings
) -> FloatArray | None:
    """The ``y`` of least ``|P y|`` with ``G y = b``. Dense: from an SVD of
    G (rows below ``rcond`` of the largest are dependent ones), to machine
    precision. Sparse: ``given + z``, a split near the answer (``G given = b``
    to round-off) corrected by the ``z`` of least ``|P (given + z)|`` with
    ``G z = b - G given``, each body's six balance rows (the first ``m``)
    taken by their span (``_spanned_balance``): one KKT solve, refined until
    (``linalg.solve_kkt``). None when K cannot be factored, or ``G y = b`` holds neither to
    ``kkt_refined`` of ``b`` nor as well as for ``given``: a subset of the
    contacts (those the cone program loads) may not balance the loads
    exactly, and its least-squares answer then misses by more than the split
    it would refine (a 100-shaft bearing chain: 5.9e-9 of 0.08, against
    1.1e-11 for the cone program's split, to which it fell back)."""
    n_y = G.shape[1]
    kkt_round_off = settings.kkt_round_off
    if not linalg.is_sparse(G):
        y, ok = _split_newton(P[None], G[None], b[None], np.arange(n_y), [], settings)
        return y[0] if ok[0] else None
    size_b = float(np.max(np.abs(b), initial=0.0))
    PtP = sp.csr_matrix(P.T @ P)
    T = _spanned_balance(G, m, settings.free_motion_rcond)
    G_t = sp.vstack([T @ G[:m], G[m:]], format="csr")
    miss_given = b - G @ given
    K = sp.bmat([[PtP, G_t.T], [G_t, None]], format="csc")
    rhs = np.r_[-(PtP @ given), T @ miss_given[:m], miss_given[m:]]
    try:  # no residual bar: the balance is checked below (the system may be inconsistent)
        step, _ = linalg.solve_kkt(
            K, rhs, n_y, tol=np.inf, refinements=settings.kkt_refinements, shift=kkt_round_off
        )
    except linalg.SingularSystemError:
        return None
    y = np.asarray(given + step[:n_y])
    miss = float(np.max(np.abs(G @ y - b), initial=0.0))
    bar = max(settings.kkt_refined * size_b, float(np.max(np.abs(miss_given), initial=0.0)))
    return y if miss <= bar else None


def _spanned_balance(G: Any, m: int, rcond: float) -> sp.csr_matrix:
    """``T`` (r, m): each body's six balance rows (the first ``m`` rows of
    the sparse ``G``) replaced by an orthonormal basis of their span: the
    left singular vectors of the body's block whose singular values are
    above ``rcond`` of the largest of all, or the rows themselves where
    their Gram matrix shows them clearly independent (``GRAM_CERTAIN``:
    most bodies of a closed loop; an SVD each cost 0.2 s on 10,000). A
    body's rows often depend on each other (a free spin's row is empty; a
    tube's three contacts span four of its six), which leaves the
    least-squares KKT system singular: regularized, its refinement crawled
    where the balance is ill-conditioned (a 1,000-segment tube string: 115
    rounds; taken by their span, the system is regular and 4 rounds of its
    plain factors settle it)."""
    rows_m = sp.csr_matrix(G[:m], copy=True)
    rows_m.sum_duplicates()  # a repeated entry adds up, as in any product
    top = rows_m.tocoo()
    n_y = G.shape[1]
    code = (top.row // 6).astype(np.int64) * n_y + top.col
    pairs, entry_pair = np.unique(code, return_inverse=True)
    pair_body = pairs // n_y
    count = np.bincount(pair_body, minlength=m // 6)
    column = np.arange(len(pairs)) - (np.cumsum(count) - count)[pair_body]
    body = pair_body[entry_pair]
    blocks = []
    for c in np.unique(count[count > 0]).tolist():  # bodies with as many unknowns, together
        same = np.flatnonzero(count == c)
        slot = np.full(m // 6, -1)
        slot[same] = np.arange(len(same))
        block = np.zeros((len(same), 6, c))
        mine = slot[body] >= 0
        block[slot[body[mine]], top.row[mine] % 6, column[entry_pair[mine]]] = top.data[mine]
        blocks.append((same, block, np.linalg.eigvalsh(block @ block.transpose(0, 2, 1))))
    if not blocks:
        return sp.csr_matrix((0, m))
    top_square = max(float(w[:, -1].max()) for _, _, w in blocks)  # largest singular value, squared
    certain = max(GRAM_CERTAIN, GRAM_MARGIN * rcond**2) * top_square
    cutoff = rcond * np.sqrt(top_square)
    bodies: list[IntArray] = []
    vectors: list[FloatArray] = []
    for same, block, w in blocks:
        clear = w[:, 0] > certain
        bodies.append(np.repeat(same[clear], 6))
        vectors.append(np.tile(np.eye(6), (int(np.sum(clear)), 1)))
        U, sv, _ = np.linalg.svd(block[~clear], full_matrices=False)
        b_idx, e_idx = np.nonzero(sv > cutoff)
        bodies.append(same[~clear][b_idx])
        vectors.append(U[b_idx, :, e_idx])
    owner = np.concatenate(bodies)
    order = np.argsort(owner, kind="stable")  # by body; a body's as found
    n_t = len(order)
    return sp.csr_matrix(
        (
            np.concatenate(vectors)[order].ravel(),
            (np.repeat(np.arange(n_t), 6), (6 * owner[order][:, None] + np.arange(6)).ravel()),
        ),
        shape=(n_t, m),
    )


def _inside(lam: FloatArray, f: FloatArray, stack: BallStack, tol: float) -> Any:
    """Whether every contact pushes (``lam >= 0``) with its force vector
    inside its cone (``|f_i| <= lam_i``), to ``tol`` of the largest force:
    one bool, or a mask over rows."""
    if not lam.shape[-1]:
        return np.ones(lam.shape[:-1], dtype=bool) if lam.ndim > 1 else True
    size = tol * np.maximum(np.max(np.abs(lam), axis=-1, keepdims=True), TINY)
    f_norm = np.sqrt(stack.segment_sum(f * f))
    inside = np.all(lam >= -size, axis=-1) & np.all(f_norm <= lam + size, axis=-1)
    return inside if lam.ndim > 1 else bool(inside)


def _part_scales(G: Any, P: Any, owner: IntArray, given: FloatArray) -> FloatArray:
    """Per unknown, the size of the forces of its part of the mechanism,
    relative to the largest part's: the largest ``|given|`` among the
    unknowns joined to it, directly or through others, by a row of ``G``
    (a body's balance), a row of ``P`` (a wrench) or their cone
    (``owner``). The split's program is separable across parts, so each
    part's unknowns divided by their own size leave its answer the same,
    while its tolerance applies to each part's forces alike: a table on
    four feet beside a block welded under a load 1e6 times the table's had
    its feet's split decided to the block's tolerance (8 N off the rule's,
    of 60). The cone joins what the balance may not: a face's force and
    its force vector, scaled apart, moved two thrust collars' split by
    5.7 N of 50. A part whose ``given`` is 0 carries no load and its split
    is 0: its size 0 keeps it there."""
    from scipy.sparse.csgraph import connected_components  # this route only: 0.02 s to import

    coned = np.flatnonzero(owner >= 0)
    cones = sp.csr_matrix(
        (np.ones(len(coned)), (owner[coned], coned)),
        shape=(int(owner.max(initial=-1)) + 1, len(owner)),
    )
    pattern = sp.vstack([sp.csr_matrix(G), sp.csr_matrix(P), cones], format="csr")
    pattern.eliminate_zeros()
    rows = pattern.shape[0]
    pattern.data[:] = 1.0
    graph = sp.bmat([[None, pattern], [pattern.T, None]], format="csr")
    _, label = connected_components(graph, directed=False)
    part = label[rows:]
    size = np.zeros(int(label.max()) + 1)
    np.maximum.at(size, part, np.abs(given))
    # relative to the largest part's, which keeps its scale: a mechanism of
    # one part poses the program as before (a uniform rescale moved the
    # program's path, and file-order scans by 1e2 either way)
    return np.asarray(size[part] / max(float(size.max()), TINY))


def _cone_program(
    P: Any,
    G: Any,
    given: FloatArray,
    n_s: int,
    k_faces: IntArray,
    settings: SolverSettings,
    refine: bool,
) -> FloatArray | None:
    """The ``y`` of least ``|P y|`` among ``y = given + z`` with ``G z = 0``
    (the same work as the solver's own split ``given``), surface forces
    non-negative and each face's ``(lam_i, f_i)`` in its cone: one Clarabel
    call, ``refine``d or not (``sparse_interior_refinement``). Written on
    ``z``, the equalities are consistent even where G's rows depend on each
    other."""
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
    Q = sp.csc_matrix(P.T @ P)
    sol = clarabel.DefaultSolver(
        sp.triu(Q, format="csc"),
        Q @ given,
        A,
        np.r_[np.zeros(m), given[:n_cone]],
        cones,
        conic.options(settings, refine=refine),
    ).solve()
    if not conic.has_answer(sol):
        return None
    return np.asarray(given + np.asarray(sol.x))
