"""Free motions of a large mechanism, in time linear in its size.

The free motions are the null space of the stacked constraint rows ``C``
(every contact's rows, the faces' rows, the rigid joints' rows). Each row
touches the six unknowns of one or two bodies, so ``C`` is block-sparse by
bodies. We eliminate the bodies as a multifrontal QR does:
body j's rows (and the rows passed on to it) are rotated so that its own six
columns are split by their singular values. The directions with a singular
value above ``rcond`` times C's largest are pivots: their rows express them
through the bodies not yet eliminated. The other directions are free in the
rows that are left; the rotated rest of the rows, which no longer touch body
j, pass on to its neighbours. A free direction of body j becomes a free
motion of the mechanism by back-substitution through the pivots of the
bodies eliminated before it that it moves.

Singular values are those of C's blocks, not of ``C^T C``, so none is lost
to squaring. A block's singular value below the threshold is a motion that C
moves less than that, so nothing held is called free; but a motion held only
through many bodies together (a chain whose links each halve a motion holds
it 2^-n) may be held far less than any one block shows: the dense SVD may
call it free and this elimination held. Bodies go in rounds of least degree
(bodies of at most two neighbours that share no rows, together, their SVDs
stacked), so a chain or a tree makes no fill and a chain of n bodies takes
about log2(n) rounds; a free motion that one body makes alone (a
shaft's spin) stays a vector on that body. The basis returned is sparse and
orthonormal (or, asked, of unit columns only: ``null_basis``).
"""

from __future__ import annotations

import functools
import heapq
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.linalg import lapack

from jointplay.geometry import FloatArray

IntArray = NDArray[np.intp]

#: Bodies with at most this many neighbours are eliminated in the same round
#: (when they share no rows). Two keeps a chain's and a tree's elimination free
#: of fill, as one at a time in minimum-degree order would.
ELIMINATED_TOGETHER_DEGREE = 2

#: Steps of the power iteration that estimates C's largest singular value:
#: its estimate then is within a few percent, all a relative threshold needs.
POWER_STEPS = 30


@dataclass
class _Pivot:
    """Body j's pivot rows: ``s_r * (V_r^T x_j) + P_other @ x_other = 0``."""

    V_r: FloatArray  # (6, rank)
    s_r: FloatArray  # (rank,)
    others: tuple[int, ...]
    P_other: FloatArray  # (rank, 6 * len(others))


@dataclass
class _Elimination:
    order: list[int] = field(default_factory=list)
    pivots: dict[int, _Pivot] = field(default_factory=dict)
    free: list[tuple[int, FloatArray]] = field(default_factory=list)  # (body, (6, q))
    rounds: int = 0  # rounds of bodies eliminated together


def _row_blocks(C: sp.csr_matrix) -> list[tuple[tuple[int, ...], FloatArray]]:
    """C's rows grouped by the set of bodies they touch, each group a dense
    block over those bodies' columns (vectorized: a large mechanism has
    hundreds of thousands of rows). Groups of one body come first, by body,
    then those of two, by their pair, then the rare rows of more bodies;
    within a group, rows keep their order."""
    C = sp.csr_matrix(C, copy=True)  # the caller's matrix stays as it is
    C.sum_duplicates()  # repeated entries add up, as in any sparse product
    C.eliminate_zeros()
    nb1 = C.shape[1] // 6 + 1
    row_of = np.repeat(np.arange(C.shape[0]), np.diff(C.indptr))
    body_of = C.indices // 6
    # each row's bodies, as (row, body) pairs in order: the entries' codes
    # are sorted (canonical CSR), so each pair is where its code changes
    code_of = row_of.astype(np.int64) * nb1 + body_of
    new_pair = np.ones(len(code_of), dtype=bool)
    new_pair[1:] = code_of[1:] != code_of[:-1]
    pair = code_of[new_pair]
    pair_row, pair_body = np.divmod(pair, nb1)
    count = np.bincount(pair_row, minlength=C.shape[0])
    first = np.concatenate([[0], np.cumsum(count)[:-1]]).astype(np.intp)
    # rows of one or two bodies (a joint between two: the common case), by a
    # code that sorts one-body groups before two-body ones, each by bodies
    simple = np.flatnonzero((count == 1) | (count == 2))
    b0 = pair_body[first[simple]]
    b1 = np.where(count[simple] == 2, pair_body[np.minimum(first[simple] + 1, len(pair) - 1)], -1)
    code = np.where(b1 < 0, b0, nb1 + b0 * nb1 + b1)
    order = np.argsort(code, kind="stable")
    rows_sorted, code_sorted = simple[order], code[order]
    starts = np.flatnonzero(np.r_[len(code_sorted) > 0, code_sorted[1:] != code_sorted[:-1]])
    size = np.diff(np.r_[starts, len(rows_sorted)])
    keys: list[tuple[int, ...]] = [
        (b,) if c < 0 else (b, c)
        for b, c in zip(b0[order][starts].tolist(), b1[order][starts].tolist(), strict=True)
    ]
    group_of = np.zeros(C.shape[0], dtype=np.intp)
    local_row = np.zeros(C.shape[0], dtype=np.intp)
    group_of[rows_sorted] = np.repeat(np.arange(len(starts)), size)
    local_row[rows_sorted] = np.arange(len(rows_sorted)) - np.repeat(starts, size)
    n_rows = size.tolist()
    wide: dict[tuple[int, ...], list[int]] = {}
    for row in np.flatnonzero(count > 2).tolist():  # rows that touch more bodies (rare)
        bodies = tuple(pair_body[first[row] : first[row] + count[row]].tolist())
        wide.setdefault(bodies, []).append(row)
    for key, rows in wide.items():
        group_of[rows] = len(keys)
        local_row[rows] = np.arange(len(rows))
        keys.append(key)
        n_rows.append(len(rows))
    # scatter every entry into one buffer that holds the groups' blocks
    n_rows_a = np.array(n_rows, dtype=np.intp)
    width = 6 * np.array([len(key) for key in keys], dtype=np.intp)
    offset = np.concatenate([[0], np.cumsum(n_rows_a * width)[:-1]]).astype(np.intp)
    rank = np.cumsum(new_pair) - 1 - first[row_of]  # each entry's body among its row's
    group = group_of[row_of]
    flat = offset[group] + local_row[row_of] * width[group] + 6 * rank + C.indices % 6
    buffer = np.zeros(int(np.sum(n_rows_a * width)))
    buffer[flat] = C.data
    return [
        (key, buffer[offset[g] : offset[g] + n_rows[g] * width[g]].reshape(n_rows[g], width[g]))
        for g, key in enumerate(keys)
    ]


def _eliminate(C: sp.csr_matrix, m: int, rcond: float, s_max: float) -> _Elimination:
    """Bodies eliminated in rounds: each round takes bodies of least degree
    (at most two neighbours, or the least there is) that share no rows, so
    that their eliminations are independent, and does their SVDs and products
    as stacks of equal shape (a chain is halved each round, as in cyclic
    reduction: no fill, and a few rounds instead of one Python step per body)."""
    n = m // 6
    store: dict[int, tuple[tuple[int, ...], FloatArray]] = dict(enumerate(_row_blocks(C)))
    on: list[set[int]] = [set() for _ in range(n)]  # body -> ids of its row blocks
    near: list[set[int]] = [set() for _ in range(n)]  # body -> bodies its rows touch
    for b, (bodies, _rows) in store.items():
        for body in bodies:
            on[body].add(b)
            near[body].update(bodies)
    for body in range(n):
        near[body].discard(body)
    next_id = len(store)
    left = set(range(n))
    out = _Elimination()
    tol = rcond * s_max
    while left:
        out.rounds += 1
        least = min(len(near[j]) for j in left)
        bound = max(least, ELIMINATED_TOGETHER_DEGREE)
        taken: list[int] = []
        blocked: set[int] = set()
        for j in sorted(left, key=lambda j: (len(near[j]), j)):
            if len(near[j]) > bound:
                break
            if j in blocked:
                continue
            taken.append(j)
            blocked.add(j)
            blocked.update(near[j])
        # each taken body's rows over (j, its neighbours), stacked by shape;
        # bodies whose row blocks have the same sizes and places are filled
        # together (a Python step per block costs more than the SVDs)
        shapes: dict[tuple[int, int], list[tuple[int, tuple[int, ...]]]] = {}
        slot: dict[int, int] = {}  # body -> its place in its shape's stack
        patterns: dict[tuple[Any, ...], list[tuple[int, list[FloatArray]]]] = {}
        for j in taken:
            others = tuple(sorted(near[j]))
            where = {body: i for i, body in enumerate((j, *others))}
            mine = [store.pop(b) for b in sorted(on[j])]
            places = tuple(
                (rows.shape[0], tuple(where[b] for b in bodies)) for bodies, rows in mine
            )
            shape = (sum(rows.shape[0] for _, rows in mine), 6 * (1 + len(others)))
            members = shapes.setdefault(shape, [])
            slot[j] = len(members)
            members.append((j, others))
            patterns.setdefault((shape, places), []).append((j, [rows for _, rows in mine]))
            left.discard(j)
            out.order.append(j)
        stacks = {shape: np.zeros((len(members), *shape)) for shape, members in shapes.items()}
        for (shape, places), same in patterns.items():
            R = stacks[shape]
            at_slots = np.array([slot[j] for j, _ in same], dtype=np.intp)
            at = 0
            for b, (k, where_b) in enumerate(places):
                block = np.stack([blocks[b] for _, blocks in same])  # (bodies, k, 6 * len(where_b))
                for q, c in enumerate(where_b):
                    R[at_slots, at : at + k, 6 * c : 6 * c + 6] = block[:, :, 6 * q : 6 * q + 6]
                at += k
        for shape, members in shapes.items():
            stack = stacks[shape]
            if stack.shape[1]:
                U, sv, Vt = np.linalg.svd(stack[:, :, :6], full_matrices=True)
                W = U.transpose(0, 2, 1) @ stack  # the rows rotated by each body's U
                ranks = np.count_nonzero(sv > tol, axis=1).tolist()
            else:  # no rows left on these bodies: every direction is free
                Vt = np.broadcast_to(np.eye(6), (len(members), 6, 6))
                W = stack
                ranks = [0] * len(members)
            V = Vt.transpose(0, 2, 1)
            # the rows that still touch the others
            nonzero: list[list[bool]] = np.asarray(W[:, :, 6:].any(axis=2)).tolist()
            for g, (j, others) in enumerate(members):
                rank = ranks[g]
                if rank < 6:
                    out.free.append((j, V[g, :, rank:]))
                if rank:
                    out.pivots[j] = _Pivot(V[g, :, :rank], sv[g, :rank], others, W[g, :rank, 6:])
                if not others:
                    continue
                rest = W[g, rank:, 6:]
                keep = nonzero[g][rank:]
                if rest.shape[0] > rest.shape[1]:  # at most as many rows as columns
                    rest = lapack.dgeqrf(rest)[0][: rest.shape[1]] * _upper(rest.shape[1])
                    keep = rest.any(axis=1).tolist()
                if any(keep):
                    store[next_id] = (others, rest if all(keep) else rest[np.asarray(keep)])
                    for body in others:
                        on[body].add(next_id)
                    next_id += 1
        for j in taken:
            neighbours = near[j]
            for body in neighbours:
                on[body] -= on[j]
                near[body].discard(j)
                near[body].update(neighbours)
                near[body].discard(body)
            on[j].clear()
            near[j] = set()
    return out


@functools.cache
def _upper(n: int) -> FloatArray:
    """(n, n) mask of the upper triangle: R of a QR from LAPACK's packed output."""
    return np.triu(np.ones((n, n)))


def _checked(C: sp.spmatrix, m: int) -> sp.csr_matrix:
    if m % 6 or C.shape[1] != m:
        raise ValueError(f"expected 6 columns per body and {m} in all, got {C.shape[1]}")
    return sp.csr_matrix(C)


def largest_singular_value(C: sp.spmatrix) -> float:
    """C's largest singular value, by power iteration on C^T C (to a few
    percent, which is all a relative threshold needs)."""
    C = sp.csr_matrix(C)
    rng = np.random.default_rng(20140101)
    v = rng.standard_normal(C.shape[1])
    for _ in range(POWER_STEPS):
        w = C.T @ (C @ v)
        norm = float(np.linalg.norm(w))
        if norm == 0.0:
            return 0.0
        v = w / norm
    return float(np.linalg.norm(C @ v))


class Eliminated:
    """The elimination of rows ``C`` by bodies, done once: how many motions
    they leave free (``deficit``) and, when asked, a basis of them
    (``basis``). A face's tests ask both of the same rows (whether it pins
    the position, and which cones hold what it leaves free): a 10,000-segment
    string's elimination costs half a second."""

    def __init__(
        self,
        C: sp.spmatrix,
        m: int,
        rcond: float,
        s_max: float | None = None,
    ):
        C = _checked(C, m)
        self.m = m
        self.elim: _Elimination | None = None  # None: no rows, every motion free
        if C.shape[0] and C.nnz:
            scale = largest_singular_value(C) if s_max is None else s_max
            self.elim = _eliminate(C, m, rcond, scale)

    @property
    def deficit(self) -> int:
        """How many independent motions the rows do not move."""
        if self.elim is None:
            return self.m
        return sum(V.shape[1] for _, V in self.elim.free)

    def basis(self, round_off: float, orthonormal: bool = True) -> sp.csc_matrix:
        """Sparse basis (m, deficit) of the motions the rows leave free:
        orthonormal, or of unit columns only (see ``null_basis``); an entry
        below ``round_off`` of the free direction that starts a vector is 0."""
        elim = self.elim
        if elim is None:
            return sp.identity(self.m, format="csc")
        position = {body: i for i, body in enumerate(elim.order)}
        # bodies eliminated before k whose pivot rows involve k
        dependents: dict[int, list[int]] = {}
        for i, pivot in elim.pivots.items():
            for k in pivot.others:
                dependents.setdefault(k, []).append(i)
        vectors: list[dict[int, FloatArray]] = []
        for j, V in sorted(elim.free, key=lambda free: free[0]):  # in body order
            for q in range(V.shape[1]):
                vectors.append(_back_substitute(j, V[:, q], elim, position, dependents, round_off))
        if orthonormal:
            return _orthonormal(vectors, self.m)
        return _unit_columns(vectors, self.m)


def null_basis(
    C: sp.spmatrix,
    m: int,
    rcond: float,
    round_off: float,
    orthonormal: bool = True,
    s_max: float | None = None,
) -> sp.csc_matrix:
    """Sparse basis (m, p), orthonormal, of the motions ``d`` with ``C d = 0``
    (a singular value of a body's block below ``rcond`` times C's largest
    counts as zero). ``orthonormal=False``: a basis of unit columns, not
    orthogonalized (enough to tell what they move: the QR of vectors that
    run down a long chain is dense, 2 s for 377 of a 10,000-body string).
    ``s_max``: the scale of the threshold, if not C's largest singular value
    (another matrix's: a face's rows counted at the free motions' scale)."""
    return Eliminated(C, m, rcond, s_max).basis(round_off, orthonormal)


def _unit_columns(vectors: list[dict[int, FloatArray]], m: int) -> sp.csc_matrix:
    """The vectors (body -> 6 entries) as sparse columns of unit norm."""
    if not vectors:
        return sp.csc_matrix((m, 0))
    rows = [(6 * np.array(list(v))[:, None] + np.arange(6)).ravel() for v in vectors]
    vals = [np.concatenate(list(v.values())) for v in vectors]
    cols = np.repeat(np.arange(len(vectors)), [len(r) for r in rows])
    out = sp.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), cols)), shape=(m, len(vectors))
    )
    norms = np.sqrt(np.asarray(out.multiply(out).sum(axis=0)).ravel())
    return sp.csc_matrix(out @ sp.diags(1.0 / norms))


def _back_substitute(
    j: int,
    v: FloatArray,
    elim: _Elimination,
    position: dict[int, int],
    dependents: dict[int, list[int]],
    round_off: float,
) -> dict[int, FloatArray]:
    """The free motion that body j's free direction v starts: the bodies
    eliminated before j follow through their pivot rows (latest first: a
    pivot row involves only bodies eliminated after its own)."""
    x = {j: v}
    heap = [-position[i] for i in dependents.get(j, [])]
    heapq.heapify(heap)
    seen = set(heap)
    # an entry below round-off of the free direction that started it does not
    # move that body: dropped, so a local free motion stays local
    floor = round_off * float(np.linalg.norm(v))
    while heap:
        i = elim.order[-heapq.heappop(heap)]
        pivot = elim.pivots[i]
        moved = [k for k in pivot.others if k in x]
        if not moved:
            continue
        x_other = np.zeros(6 * len(pivot.others))
        for k, body in enumerate(pivot.others):
            if body in x:
                x_other[6 * k : 6 * k + 6] = x[body]
        x_i = pivot.V_r @ (-(pivot.P_other @ x_other) / pivot.s_r)
        if float(np.max(np.abs(x_i))) <= floor:
            continue
        x[i] = x_i
        for dep in dependents.get(i, []):
            if -position[dep] not in seen:
                seen.add(-position[dep])
                heapq.heappush(heap, -position[dep])
    return x


def _orthonormal(vectors: list[dict[int, FloatArray]], m: int) -> sp.csc_matrix:
    """The vectors (body -> 6 entries) as orthonormal sparse columns: those
    that share a body are orthonormalized together, the others alone."""
    clusters = _sharing([list(vec) for vec in vectors])
    rows: list[IntArray] = []
    cols: list[IntArray] = []
    vals: list[FloatArray] = []
    p = 0
    for members in clusters:
        bodies = sorted({body for a in members for body in vectors[a]})
        where = {body: i for i, body in enumerate(bodies)}
        X = np.zeros((6 * len(bodies), len(members)))
        for c, a in enumerate(members):
            for body, entries in vectors[a].items():
                X[6 * where[body] : 6 * where[body] + 6, c] = entries
        Q = X / np.linalg.norm(X) if X.shape[1] == 1 else np.linalg.qr(X)[0]
        index = (6 * np.asarray(bodies)[:, None] + np.arange(6)).ravel()
        nz = np.nonzero(Q)
        rows.append(index[nz[0]])
        cols.append(p + nz[1])
        vals.append(Q[nz])
        p += len(members)
    if not p:
        return sp.csc_matrix((m, 0))
    return sp.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(m, p)
    )


def column_groups(basis: sp.spmatrix) -> list[tuple[IntArray, IntArray]]:
    """The columns of a sparse basis in groups that share no body, each with
    its bodies: ``[(columns, bodies), ...]`` (to describe them one group at a
    time, in the few bodies each moves)."""
    N = sp.csc_matrix(basis)
    bodies_of = [
        np.unique(N.indices[N.indptr[c] : N.indptr[c + 1]] // 6) for c in range(N.shape[1])
    ]
    return [
        (np.array(cols, dtype=np.intp), np.unique(np.concatenate([bodies_of[c] for c in cols])))
        for cols in _sharing([b.tolist() for b in bodies_of])
    ]


def _sharing(bodies_of: list[list[int]]) -> list[list[int]]:
    """Items (each with the bodies it moves) in groups: two items that move a
    common body, directly or through others, are in one group (union-find)."""
    parent = list(range(len(bodies_of)))

    def root(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    owner: dict[int, int] = {}
    for a, bodies in enumerate(bodies_of):
        for body in bodies:
            if body in owner:
                parent[root(a)] = root(owner[body])
            else:
                owner[body] = a
    groups: dict[int, list[int]] = {}
    for a in range(len(bodies_of)):
        groups.setdefault(root(a), []).append(a)
    return list(groups.values())
