"""Static indeterminacy: which touching contacts share a load the balance does not decide.

At an answer's positions each hard touching contact has force unknowns: a
contact on its cone's surface one (its force along its direction of
contact), a face resting flat at its cone's apex its force and its force
vector (where on the face it pushes), a ball held at its centre (no play)
its force vector, a rigid joint's rows one each. Their work on the moving
bodies is the balance map ``G`` (one column per unknown, one row per body
unknown), the one the split rule of ``solver/forces.py`` solves. The degree
of static indeterminacy is

    degree = (number of unknowns) - rank(G),

the dimension of the self-balanced force systems ``G y = 0``: loads the
touching contacts can pass between themselves without any body noticing.
With degree > 0 the positions and the balance fix only some sums of these
forces, and the split printed is a convention (the least
``sum |F|^2 + |M/ell|^2``, the split of equal springs). The contacts that
share the redundant load are those whose unknowns take part in that null
space: a nonzero row of a null-space basis of ``G``.

The rank is counted at ``SolverSettings.free_motion_rcond`` (singular
values below it of the largest count as zero: the threshold of free
motions and dependent rows), and an unknown takes part where its row of an
orthonormal null-space basis is above it. Dense models take one SVD of
``G`` (the split's own test of a determinate balance). Large (sparse) ones
go in time linear in the size: first the joints between each pair of
bodies together (side by side, the ground one body), a small SVD each
(a door's two hinges, a carriage's corners: most redundancy is there);
then what the pairs pass on, the range of each pair's work, through loops
of bodies: the null space of those ranges side by side (six columns a
pair, padded with zero columns, whose own null directions are counted
off), by the elimination that finds free motions
(``free_motions.null_basis``): a row, one body's balance, touches the few
pairs at that body. That elimination measures blocks, not the whole: a
redundancy that the positions' round-off blurs (singular values between
1e-12 and 1e-9 of the largest) may be counted by the SVD and not by it.

Compliant contacts (with ``stiffness``) are left out: their force is fixed by
their penetration (the springs decide the split, the rule does not), so they
act here as known loads, not as rigid redundancy. That includes a compliant
face pressed flat, whose force the spring gives; only where on the face it
acts is split by the rule.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from jointplay.numerics import free_motions, linalg

if TYPE_CHECKING:
    from jointplay.assembly import Assembly, IntArray
    from jointplay.geometry import FloatArray
    from jointplay.settings import SolverSettings


@dataclass(frozen=True)
class Indeterminacy:
    """The static indeterminacy of an answer's touching contacts.

    ``degree``: independent self-balanced force systems of the hard touching
    contacts (0: their forces are decided by the balance). ``joints``: the
    joints whose contacts share the redundant load (model order);
    ``contacts``: those contacts, as ``joint.contact`` (model order). Both
    empty when the degree is 0. ``by_rule``: the printed split is shown to
    be the split rule's (``solver/forces.py``); False where its program gave
    no split that certifies (Clarabel stopped short of its tolerance or found
    none: long degenerate bearing chains, where a change of the loads below
    the certificate's tolerance moves the rule's split by per cents): the
    printed forces are the route's, which balance the loads as others would."""

    degree: int = 0
    joints: tuple[str, ...] = ()
    contacts: tuple[str, ...] = ()
    by_rule: bool = True

    def to_dict(self) -> dict[str, Any]:
        """JSON ``indeterminate``."""
        return {
            "degree": self.degree,
            "joints": list(self.joints),
            "contacts": list(self.contacts),
            "by_rule": self.by_rule,
        }


#: The answer of a determinate mechanism (and of a route that does not count).
DETERMINATE = Indeterminacy()


def over_steps(found: Sequence[Indeterminacy], joints: Sequence[str]) -> Indeterminacy:
    """What a study's answers (a sweep's or a motion's steps) say together:
    the largest degree, every joint and contact that shares a redundant load
    at some step (in the order of ``joints``, the model's), and ``by_rule``
    where every step's split is the rule's."""
    order = {name: k for k, name in enumerate(joints)}
    shared = {name for f in found for name in f.joints}
    contacts = list(dict.fromkeys(name for f in found for name in f.contacts))

    def joint_of(contact: str) -> int:  # "joint.contact": the longest joint name that fits
        fits = [j for j in shared if contact.startswith(j + ".")]
        return order.get(max(fits, key=len), len(order)) if fits else len(order)

    return Indeterminacy(
        max((f.degree for f in found), default=0),
        tuple(sorted(shared, key=lambda j: order.get(j, len(order)))),
        tuple(sorted(contacts, key=joint_of)),  # stable: each joint's contacts as found
        all(f.by_rule for f in found),
    )


def steps_dict(found: Sequence[Indeterminacy], joints: Sequence[str]) -> dict[str, Any]:
    """JSON ``indeterminate`` of a study's steps: ``over_steps``, and the
    steps (from 0) whose forces are a convention."""
    return {
        **over_steps(found, joints).to_dict(),
        "steps": [s for s, f in enumerate(found) if f.degree > 0],
    }


def indeterminacy_of(
    asm: Assembly, x: FloatArray, settings: SolverSettings, by_rule: bool = True
) -> Indeterminacy:
    """The indeterminacy (module docstring) of the answer ``x`` (scaled
    unknowns of ``asm``): its hard touching contacts as ``solver/forces.py``
    classes them (touching at ``settings.touching`` of their play; flat at
    their apex within the positions' round-off, ``feasibility_tolerance`` of
    the largest play), rank at ``settings.free_motion_rcond``; ``by_rule``:
    whether its forces are shown to be the split rule's."""
    work, owner = _unknowns(asm, x, settings)
    if not len(owner):
        return DETERMINATE
    T = asm.tables
    # joints between the same two bodies act side by side: their unknowns
    # are taken together (the fixed bodies are one, the ground)
    lo, hi = np.min(T.between_index, axis=1), np.max(T.between_index, axis=1)
    pairs, pair_of_joint = np.unique(np.c_[lo, hi], axis=0, return_inverse=True)
    pair = np.asarray(pair_of_joint).ravel()[T.joint_of[owner]]
    keep = pairs[pair, 1] >= 0  # between two fixed bodies: no work on any
    work, owner, pair = work[np.flatnonzero(keep)], owner[keep], pair[keep]
    if not len(owner):
        return DETERMINATE
    rcond = settings.free_motion_rcond
    if linalg.is_sparse(work):
        degree, part = _by_elimination(asm.m, work, pair, pairs, rcond, settings.round_off)
    else:
        degree, part = _by_svd(work, rcond)
    if degree <= 0:
        return DETERMINATE
    contacts = np.unique(owner[part])  # asm.contacts order
    joints = np.unique(T.joint_of[contacts])
    return Indeterminacy(
        degree,
        tuple(T.joint_name[j] for j in joints.tolist()),
        tuple(f"{T.joint_name[T.joint_of[c]]}.{T.contact_name[c]}" for c in contacts.tolist()),
        by_rule,
    )


def _by_svd(work: FloatArray, rcond: float) -> tuple[int, NDArray[np.bool_]]:
    """A dense model's degree and the unknowns that take part, from one SVD
    of ``G`` (the split's own test of a determinate balance,
    ``forces._determined_rows``): singular values above ``rcond`` of the
    largest count; an unknown takes part where its row of the orthonormal
    null-space basis is above ``rcond``."""
    G = np.asarray(work).T
    _, sv, Vt = np.linalg.svd(G, full_matrices=True)
    rank = int(np.sum(sv > rcond * sv[0])) if sv.size and sv[0] > 0 else 0
    null = Vt[rank:]
    return G.shape[1] - rank, np.linalg.norm(null, axis=0) > rcond


def _by_elimination(
    m: int, work: Any, pair: IntArray, pairs: IntArray, rcond: float, round_off: float
) -> tuple[int, NDArray[np.bool_]]:
    """A large model's degree and the unknowns that take part, in time
    linear in its size: first within each pair of bodies (the joints between
    them side by side: a door's hinges, a carriage's corners), from a small
    SVD of their work, at ``rcond`` of the largest singular value of all
    pairs; then through loops of bodies (``_loops``)."""
    blocks = _pair_blocks(work, pair, pairs)
    top = max(float(b.s[:, 0].max(initial=0.0)) for b in blocks)
    part = np.zeros(len(pair), dtype=bool)
    if top == 0.0:
        return 0, part
    degree = 0
    for b in blocks:  # within a pair of bodies: its unknowns' null space
        rank = np.count_nonzero(b.s > rcond * top, axis=1)
        b.rank = rank
        degree += int(np.sum(b.n - rank))
        null = np.arange(b.n)[None, None, :] >= rank[:, None, None]
        size = np.sqrt(np.sum(np.where(null, b.V, 0.0) ** 2, axis=2))  # (pairs, n)
        part[b.unknowns[size > rcond]] = True
    loop_degree, in_loops = _loops(m, blocks, len(pair), pair, rcond, round_off)
    return degree + loop_degree, part | in_loops


@dataclass
class _Blocks:
    """Pairs of bodies with ``n`` unknowns between them on ``w`` body
    unknowns (6: one moving body and the ground, 12: two moving), stacked:
    their unknowns (``unknowns[j, p]``: the p-th of the j-th pair), the body
    unknowns of the rows (``rows[j, l]``) and the SVD ``U diag(s) V^T`` of
    each pair's work (w, n)."""

    n: int
    unknowns: IntArray  # (P, n)
    rows: IntArray  # (P, w)
    U: FloatArray  # (P, w, w)
    s: FloatArray  # (P, min(w, n))
    V: FloatArray  # (P, n, n)
    rank: IntArray | None = None


def _pair_blocks(work: Any, pair: IntArray, pairs: IntArray) -> list[_Blocks]:
    """Each pair's work (its unknowns' rows on its bodies' columns: the
    first body's six, if it moves, then the second's), SVD'd in stacks of
    one shape. ``pairs`` (P, 2): the moving-body indices of each pair, in
    ascending order (-1: the ground)."""
    n_y = len(pair)
    count = np.bincount(pair, minlength=len(pairs))
    first = np.cumsum(count) - count
    order = np.argsort(pair, kind="stable")
    pos = np.empty(n_y, dtype=np.intp)
    pos[order] = np.arange(n_y) - first[pair[order]]
    coo = sp.coo_matrix(work)
    q, col, val = coo.row, coo.col, coo.data
    ends = pairs[pair[q]]
    local = np.where((ends[:, 0] >= 0) & (col // 6 == ends[:, 1]), 6, 0) + col % 6
    width = 6 + 6 * (pairs[:, 0] >= 0)
    used = np.flatnonzero(count)
    shape_of = count[used] * 13 + width[used]  # (n, w) as one code (w is 6 or 12)
    out = []
    for code in np.unique(shape_of).tolist():
        n, w = divmod(code, 13)
        same = used[shape_of == code]
        slot = np.full(len(pairs), -1, dtype=np.intp)
        slot[same] = np.arange(len(same))
        mine = slot[pair[q]] >= 0
        A = np.zeros((len(same), w, n))  # each pair's work, transposed: (body rows, unknowns)
        np.add.at(A, (slot[pair[q[mine]]], local[mine], pos[q[mine]]), val[mine])
        U, s, Vt = np.linalg.svd(A, full_matrices=True)
        body = pairs[same]
        lead = np.where(body[:, 0] >= 0, body[:, 0], body[:, 1])
        rows = 6 * lead[:, None] + np.arange(6)
        if w == 12:
            rows = np.hstack([rows, 6 * body[:, 1][:, None] + np.arange(6)])
        unknowns = order[first[same][:, None] + np.arange(n)]
        out.append(_Blocks(n, unknowns, rows, U, s, Vt.transpose(0, 2, 1)))
    return out


def _loops(
    m: int, blocks: list[_Blocks], n_y: int, pair: IntArray, rcond: float, round_off: float
) -> tuple[int, NDArray[np.bool_]]:
    """The self-balanced force systems that run through several pairs of
    bodies (a closed loop of bodies): each pair passes on its range, its
    work's ``U_r diag(s_r) = G_p V_r`` (so that the singular values are
    ``G``'s), and those that balance on every body are the null space of
    ``C = [U_r diag(s_r) of each pair]`` (body unknowns x six columns per
    pair, padded with zero columns). Returns their number and the unknowns
    that take part: ``y = V_r z`` of a null vector's part ``z`` on the pair
    (its entries above ``rcond`` of the largest of the pair, on a ``z``
    above ``rcond`` of the vector's size)."""
    c_rows, c_cols, c_vals = [], [], []
    y_rows, y_cols, y_vals = [], [], []
    real = []
    at = 0
    for b in blocks:
        assert b.rank is not None
        loop = np.flatnonzero(b.rank > 0)
        if not len(loop):
            continue
        slot = at + np.arange(len(loop))
        at += len(loop)
        r_max = int(b.rank[loop].max())
        i = np.arange(r_max)
        on = i[None, :] < b.rank[loop][:, None]  # (L, r_max): columns in the range
        # C: U[:, l, i] at (rows[l], 6 slot + i)
        jj, ii = np.nonzero(on)
        w = b.rows.shape[1]
        c_rows.append(b.rows[loop][jj].ravel())
        c_cols.append(np.repeat(6 * slot[jj] + ii, w))
        c_vals.append((b.U[loop][jj, :, ii] * b.s[loop][jj, ii][:, None]).ravel())
        # Y: V[p, i] at (unknowns[p], 6 slot + i)
        y_rows.append(b.unknowns[loop][jj].ravel())
        y_cols.append(np.repeat(6 * slot[jj] + ii, b.n))
        y_vals.append(b.V[loop][jj, :, ii].ravel())
        real.append(6 * slot[jj] + ii)
    part = np.zeros(n_y, dtype=bool)
    if not at:
        return 0, part
    n_c = 6 * at
    C = sp.csr_matrix(
        (np.concatenate(c_vals), (np.concatenate(c_rows), np.concatenate(c_cols))), shape=(m, n_c)
    )
    Z = sp.csc_matrix(free_motions.null_basis(C, n_c, rcond, round_off, orthonormal=False))
    n_real = sum(len(r) for r in real)
    degree = Z.shape[1] - (n_c - n_real)  # less the padding's own directions
    if degree <= 0:
        return 0, part
    is_real = np.zeros(n_c, dtype=bool)
    is_real[np.concatenate(real)] = True
    # a vector's entries on the joints' range, above rcond of its size
    Zc = Z.tocoo()
    size = np.zeros(Z.shape[1])
    np.maximum.at(size, Zc.col, np.abs(Zc.data))
    big = is_real[Zc.row] & (np.abs(Zc.data) > rcond * size[Zc.col])
    Zr = sp.csc_matrix((Zc.data[big], (Zc.row[big], Zc.col[big])), shape=Z.shape)
    M = sp.csr_matrix(
        (np.concatenate(y_vals), (np.concatenate(y_rows), np.concatenate(y_cols))),
        shape=(n_y, n_c),
    )
    Y = sp.coo_matrix(M @ Zr)
    # per pair and vector: its unknowns above rcond of the largest of them
    key = pair[Y.row].astype(np.int64) * Z.shape[1] + Y.col
    keys, inverse = np.unique(key, return_inverse=True)
    top = np.zeros(len(keys))
    np.maximum.at(top, inverse, np.abs(Y.data))
    part[Y.row[np.abs(Y.data) > rcond * top[inverse]]] = True
    return degree, part


def _unknowns(asm: Assembly, x: FloatArray, settings: SolverSettings) -> tuple[Any, Any]:
    """The hard touching contacts' force unknowns at ``x``: their work, one
    row each (``G`` transposed; dense or sparse like the assembly), and the
    contact (``asm.contacts`` index) each belongs to. In this order: a
    surface cone's force along its direction ``u_i`` (``A_i^T u_i + B_i``);
    a face at its apex, its force (``B_i``); a cone at its apex, its force
    vector (``A_i``); a rigid row (``E``)."""
    stack = asm.stack
    v, rho, level = stack.levels(x)
    largest = float(np.max(stack.r)) if len(stack.r) else 0.0
    apex_level = settings.feasibility_tolerance * (largest if largest > 0 else 1.0)
    touching = (stack.spring == 0) & (
        stack.gap_used(level, settings.feasibility_tolerance * stack.largest_play())
        >= settings.touching
    )
    flat = (stack.k == 0) | (rho <= apex_level)
    surface, apex = np.flatnonzero(touching & ~flat), np.flatnonzero(touching & flat)
    face = apex[stack.has_offset[apex]]
    ball_contact = np.flatnonzero(asm.is_ball)
    fixed_contact = np.flatnonzero(~asm.is_ball)
    u = v / np.repeat(np.where(rho > 0, rho, 1.0), stack.k)
    on_surface = (
        stack.take(surface).surface_work(u[stack.rows_of(surface)])
        if len(surface)
        else np.zeros((0, asm.m))
    )
    parts = [
        on_surface,
        stack.B[face],
        stack.A[stack.rows_of(apex)],
        asm.E,
    ]
    owner = np.concatenate(
        [
            ball_contact[surface],
            ball_contact[face],
            np.repeat(ball_contact[apex], stack.k[apex]),
            np.repeat(fixed_contact, [c.k for c in asm.fixed]),
        ]
    ).astype(np.intp)
    return linalg.vstack(parts, asm.m), owner
