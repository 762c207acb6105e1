"""The split of the loads between redundant contacts: one rule, one program.

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

The split is one convex program (``_program``: the metric above, the balance
as equalities, each touching contact's cone), solved by Clarabel. A dense
model first takes its least squares on the contacts a nearby split loads
(``_least_squares``, stacked over the rows of a batch), kept only where it
is the program's optimum: inside every cone, and no contact held unloaded
that would take load with profit.
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
from jointplay.settings import TINY
from jointplay.solver import conic

if TYPE_CHECKING:
    from jointplay.settings import SolverSettings


@dataclass(frozen=True)
class Split:
    """Multipliers (scaled) of one answer: per cone ``lam``, force vectors
    ``f`` (stacked like ``BallStack.A``), and the rigid rows' ``nu``.
    ``rule``: shown to be the rule's split (its least squares meets the
    program's optimality conditions, or Clarabel solved the program to its
    tolerance); else the program's best, or (``found`` False: the program
    gave none) the route's own forces."""

    lam: FloatArray
    f: FloatArray
    nu: FloatArray
    rule: bool = True
    found: bool = True


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
    """The split (module docstring) at positions ``x`` under unit loads
    ``g_hat``. ``lam``, ``f``, ``nu``: the solver's own split (a sparse
    model's program starts from it); its compliant contacts keep theirs (a
    face pressed flat, its force but not its force vector: ``_pressing``).
    ``apex_level``: a cone with ``|A_i x|`` at or below it rests at its
    apex, its force vector free inside the cone. None when only one split
    balances the loads (the caller keeps its own, the rule's by itself);
    the route's own (``Split.found`` False) when the program finds none.
    ``unique_on``: a face (surface cones, those
    at their apex) of a hard model whose Newton system was regular: if its
    cones are the touching ones, in the same classes, their forces are the
    only ones (None is returned at once)."""
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
    cones = (int(np.sum(surface)), stack.k[apex & stack.has_offset])
    given = None
    if asm.sparse:  # the route's split, in the unknowns (Z's columns are apart)
        given = Z.T @ np.concatenate([f - keep_f, lam - keep_lam, nu])
        given = given / np.asarray(Z.multiply(Z).sum(axis=0)).ravel()
    y, rule = _rule(_wrenches(asm, Z), G, b, owner, cones, settings, given)
    if y is None:  # no split found: the route's own stands
        return Split(lam, f, nu, rule=False, found=False)
    out = _split_of(stack, Z @ y, keep_lam, keep_f, apex & ~stack.has_offset)
    return Split(out.lam, out.f, out.nu, rule)


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
    ``centres``; dense models). ``near = (lam, f)``: rows of a split close to
    each row's (a neighbouring sample's): its touching contacts with no force
    are held unloaded in one stacked least squares (``_least_squares``);
    the rows where that is not the program's optimum take the rule one by
    one (``_rule``).

    Returns the mask of the rows whose split is the rule's (or the row's
    own, where one split balances the loads), and every row's
    ``(lam, f, nu)`` (the rule's where the mask holds)."""
    stack = asm.stack
    B, n_e = x.shape[0], asm.E.shape[0]
    surface, apex, pressed, u = _classes(stack, x, radii, apex_level, settings, centres, lam)
    keep_lam, keep_f = _compliant(stack, lam, f, pressed)
    b = g_hat - stack.adjoint(keep_f, keep_lam)
    ok = np.zeros(B, dtype=bool)
    lam, f, nu = lam.copy(), f.copy(), np.zeros((B, n_e))
    lam_n = near[0]
    top = np.max(np.abs(lam_n), axis=1, keepdims=True, initial=0.0)
    # only one-sign unknowns are held at 0: a surface force, a one-sided
    # limit's (a ball at its centre has a vector of either sign)
    unloaded = (lam_n <= settings.interior_resolution * top) & (surface | (apex & (stack.k == 0)))
    # rows whose contacts touch alike share the shape of their unknowns
    first_kind, kind = linalg.distinct_rows(np.hstack([surface, apex, pressed, unloaded]))
    for rows in (np.flatnonzero(kind == g) for g in range(len(first_kind))):
        s, a, p = surface[rows[0]], apex[rows[0]], pressed[rows[0]]
        # rows that pose the same problem (a study whose plays vary and whose
        # loads do not, on contacts whose directions do not move) are solved once
        first, same = linalg.distinct_rows(np.hstack([b[rows], u[rows], lam[rows][:, p]]))
        Z, owner = _unknowns(stack, s, a, u[rows[first]], n_e, False)
        if Z.shape[-1] == 0:
            continue
        G, b_rows = _pressing(_work(asm, Z), b[rows[first]], owner, p, lam[rows[first]])
        determinate = _determined_rows(G, settings.free_motion_rcond)
        ok[rows[determinate[same]]] = True
        P = _wrenches(asm, Z)
        cones = (int(np.sum(s)), stack.k[a & stack.has_offset])
        keep = np.flatnonzero((owner < 0) | ~unloaded[rows[0]][np.maximum(owner, 0)])
        y, optimal = _least_squares(P, G, b_rows, keep, cones, settings)
        todo = np.flatnonzero(~optimal & ~determinate)
        rules = _rules(P[todo], G[todo], b_rows[todo], owner, cones, settings)
        for j, (y_j, _) in zip(todo, rules, strict=True):
            if y_j is not None:
                y[j], optimal[j] = y_j, True
        z = (Z @ y[:, :, None])[:, :, 0]
        out = _split_of(stack, z, keep_lam[rows[first]], keep_f[rows[first]], a & ~stack.has_offset)
        split = ~determinate[same]
        at = rows[split]
        lam[at], f[at], nu[at] = (v[same][split] for v in (out.lam, out.f, out.nu))
        ok[at] = optimal[same][split]
    return ok, lam, f, nu


#: The split's cones: the number of surface forces (the first unknowns,
#: each >= 0), then each face's vector size (its ``lam_i``, then ``f_i``).
Cones = tuple[int, IntArray]


def _rule(
    P: Any,
    G: Any,
    b: FloatArray,
    owner: IntArray,
    cones: Cones,
    settings: SolverSettings,
    given: FloatArray | None = None,
) -> tuple[FloatArray | None, bool]:
    """The split's ``y`` of one answer, and whether it is shown to be the
    rule's (``Split.rule``): a dense model's by ``_rules``; a sparse
    model's by the program from ``given``, the route's split."""
    if given is None:
        return _rules(P[None], G[None], b[None], owner, cones, settings)[0]
    parts = _parts(G, P, owner)
    found = _program(P, G, b, given, parts, cones, settings, True)
    return (None, False) if found is None else (found[0], found[2])


def _rules(
    P: FloatArray,
    G: FloatArray,
    b: FloatArray,
    owner: IntArray,
    cones: Cones,
    settings: SolverSettings,
) -> list[tuple[FloatArray | None, bool]]:
    """The split's ``y`` of each row of a dense stack (rows alike in their
    unknowns), and whether it is shown to be the rule's. The least squares
    (``_least_squares``) first: where it lies in every cone it is the
    rule's. The others' programs (``_program``) are then finished by the
    least squares on the forces each leaves pushing, kept where that is the
    program's optimum: the program stops at its tolerance, and a contact
    whose force and multiplier both vanish at the optimum (a lathe slide's
    corner) ends 5e-5 of the largest force off it."""
    n_y = G.shape[2]
    y, optimal = _least_squares(P, G, b, np.arange(n_y), cones, settings)
    out: list[tuple[FloatArray | None, bool]] = [
        (y[j], True) if optimal[j] else (None, False) for j in range(len(y))
    ]
    rest = np.flatnonzero(~optimal)
    if not rest.size:
        return out
    # rows alike: the parts of their program are those of all of them
    parts = _parts(np.any(G[rest] != 0, axis=0), np.any(P[rest] != 0, axis=0), owner)
    for j in rest.tolist():
        found = _program(P[j], G[j], b[j], np.zeros(n_y), parts, cones, settings, False)
        if found is None:
            continue
        y_j, held, solved = found
        keep = np.setdiff1d(np.arange(n_y), held)
        exact, fine = _least_squares(
            P[j : j + 1], G[j : j + 1], b[j : j + 1], keep, cones, settings
        )
        out[j] = (exact[0], True) if fine[0] else (y_j, solved)
    return out


def _least_squares(
    P: FloatArray,
    G: FloatArray,
    b: FloatArray,
    keep: IntArray,
    cones: Cones,
    settings: SolverSettings,
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """For each row of the stacks ``P``, ``G``, ``b``: the ``y`` of least
    ``|P y|`` with ``G y = b`` and the unknowns outside ``keep`` at 0 (held
    unloaded), from the pseudo-inverses of ``G`` (its singular values below
    ``free_motion_rcond`` of the largest are dependent rows') and of ``P``
    on the null space of ``G``. Also the mask of the rows where it is the
    program's optimum (its conditions, to ``equilibrium_tolerance``): it
    balances the loads, lies in every cone, and no held unknown would lower
    ``|P y|`` by taking load (the gradient on each, with the balance's
    multipliers, is >= 0)."""
    B, _, n_y = G.shape
    rcond, tol = settings.free_motion_rcond, settings.equilibrium_tolerance
    Gk, Pk = G[:, :, keep], P[:, :, keep]
    G_pinv = np.linalg.pinv(Gk, rcond=rcond)
    y_k = G_pinv @ b[:, :, None]
    null = np.eye(len(keep)) - G_pinv @ Gk  # the projector on G's null space
    y_k -= null @ (np.linalg.pinv(Pk @ null, rcond=rcond) @ (Pk @ y_k))
    y = np.zeros((B, n_y))
    y[:, keep] = y_k[:, :, 0]
    # each force against those it shares a body's balance with: judged
    # against all, a table's foot pulled 0.75 N beside a block under 1e8 N
    works = G != 0
    near = np.max(works * np.abs(y)[:, None, :], axis=2, initial=0.0)
    top = np.maximum(np.max(works * near[:, :, None], axis=1, initial=0.0), TINY)
    size_b = np.maximum(np.max(np.abs(b), axis=1, initial=0.0), TINY)
    miss = np.max(np.abs((G @ y[:, :, None])[:, :, 0] - b), axis=1, initial=0.0)
    optimal = miss <= tol * size_b
    n_s, k_faces = cones
    optimal &= np.all(y[:, :n_s] >= -tol * top[:, :n_s], axis=1)
    at = n_s
    for k in k_faces.tolist():
        size = np.linalg.norm(y[:, at + 1 : at + 1 + k], axis=1)
        optimal &= size <= y[:, at] + tol * top[:, at]
        at += 1 + k
    held = np.setdiff1d(np.arange(n_y), keep)
    if len(held):
        grad = (P.transpose(0, 2, 1) @ (P @ y[:, :, None]))[:, :, 0]
        mu = -(G_pinv.transpose(0, 2, 1) @ grad[:, keep, None])
        grad += (G.transpose(0, 2, 1) @ mu)[:, :, 0]
        size = tol * np.maximum(np.max(np.abs(grad), axis=1, initial=0.0), TINY)
        optimal &= np.all(grad[:, held] >= -size[:, None], axis=1)
    return y, optimal


def _program(
    P: Any,
    G: Any,
    b: FloatArray,
    given: FloatArray,
    parts: IntArray,
    cones: Cones,
    settings: SolverSettings,
    sparse: bool,
) -> tuple[FloatArray, IntArray, bool] | None:
    """The ``y`` of least ``|P y|`` in its ``cones`` with ``G y = b``: one
    Clarabel call, refined as the model's interior point is
    (``conic.refined``). A sparse model's is written on ``z = y - given``,
    ``given`` a split that balances the loads, with ``G z = 0``: consistent
    even where G's rows depend on each other (a bearing chain's: written
    ``G y = b``, its program ran out of steps). Each of its ``parts``
    (``_parts``: each row's of G, then each unknown's) is posed at its own
    size, so that the tolerance applies to each part's forces. Also the
    one-sign unknowns the program holds at 0 (its dual above its value),
    and whether Clarabel solved it to its tolerance (not "almost")."""
    m, n_y = G.shape
    size = np.zeros(int(parts.max(initial=-1)) + 1)
    np.maximum.at(size, parts[:m], np.abs(b))
    size_row, size = size[parts[:m]], size[parts[m:]]
    miss = np.zeros_like(b) if sparse else b - G @ given
    given_hat = np.divide(given, size, out=np.zeros_like(given), where=size > 0)
    n_s, k_faces = cones
    n_cone = n_s + int(np.sum(k_faces + 1))
    kinds: list[Any] = [clarabel.ZeroConeT(m)] if m else []
    if n_s:
        kinds.append(clarabel.NonnegativeConeT(n_s))
    kinds += [
        clarabel.SecondOrderConeT(int(k) + 1) if k else clarabel.NonnegativeConeT(1)
        for k in k_faces
    ]
    # y = size * y_hat: each part's rows and unknowns divided by its size
    # leave G and the optimum as they are (both separable across parts)
    if sparse:
        Q = sp.csc_matrix(P.T @ P)
        upper, rows = sp.triu(Q, format="csc"), sp.vstack([G, -sp.eye(n_cone, n_y)], format="csc")
    else:  # a small dense program: built dense, then stored once
        Q = P.T @ P
        upper, rows = conic.csc(np.triu(Q)), conic.csc(np.vstack([G, -np.eye(n_cone, n_y)]))
    sol = clarabel.DefaultSolver(
        upper,
        Q @ given_hat,
        rows,
        np.r_[
            np.divide(miss, size_row, out=np.zeros_like(b), where=size_row > 0), given_hat[:n_cone]
        ],
        kinds,
        conic.options(settings, refine=conic.refined(settings, sparse)),
    ).solve()
    if not conic.has_answer(sol):
        return None
    s, z = np.asarray(sol.s)[m:], np.asarray(sol.z)[m:]
    one_sign = np.r_[np.arange(n_s), n_s + (np.cumsum(k_faces + 1) - k_faces - 1)[k_faces == 0]]
    held = one_sign[s[one_sign] <= z[one_sign]].astype(np.intp)
    solved = conic.outcome(sol) == "optimal"  # to its tolerance, not "almost"
    return (given_hat + np.asarray(sol.x)) * size, held, solved


def _parts(G: Any, P: Any, owner: IntArray) -> IntArray:
    """The part of the split's program each row of ``G`` and then each
    unknown is in (a label each): what a row of ``G`` (a body's balance), a
    row of ``P`` (a wrench) or a cone (``owner``) joins, directly or through
    others. ``_program`` poses each part at its size, the largest ``|b|`` on
    its rows: posed at the size of all the loads, a table on four feet
    beside a block welded under a load 1e8 times the table's had its feet's
    split decided to the block's tolerance (8 N off the rule's, of 60); the
    cone joins what the balance may not (a face's force and its force
    vector: two thrust collars). A part with no load has size 0: its split is 0."""
    from scipy.sparse.csgraph import connected_components  # this route only: 0.02 s to import

    coned = np.flatnonzero(owner >= 0)
    cones = sp.csr_matrix(
        (np.ones(len(coned)), (owner[coned], coned)),
        shape=(int(owner.max(initial=-1)) + 1, len(owner)),
    )
    pattern = sp.vstack([sp.csr_matrix(G), sp.csr_matrix(P), cones], format="csr")
    pattern.eliminate_zeros()
    pattern.data[:] = 1.0
    graph = sp.bmat([[None, pattern], [pattern.T, None]], format="csr")
    _, label = connected_components(graph, directed=False)
    m = G.shape[0]
    return np.concatenate([label[:m], label[pattern.shape[0] :]]).astype(np.intp)


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
