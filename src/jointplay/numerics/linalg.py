"""Linear algebra that works on dense arrays (small mechanisms, fastest) and on
sparse matrices (large ones, where a dense m x m matrix would not fit).

Every function takes either kind; ``Assembly.sparse`` decides which kind the
assembly builds (see ``SPARSE_FROM``).
"""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import AbstractContextManager, contextmanager
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.linalg import lapack

from jointplay.geometry import FloatArray
from jointplay.numerics import free_motions
from jointplay.settings import DEFAULT, GRAM_CERTAIN, GRAM_MARGIN, TINY

#: Mechanisms with more unknowns than this (6 per moving body) are assembled
#: into sparse matrices. Below it, dense LAPACK calls are faster.
SPARSE_FROM = 240

Matrix = Any  # a dense 2-D FloatArray or a scipy sparse matrix


def one_blas_thread() -> AbstractContextManager[Any]:
    """BLAS (numpy's and scipy's) in one thread for the duration: a solve is
    many small matrices, which more threads only slow down, and on a busy
    2-core machine a thread that waits for the other core is far worse (a
    30-shaft bearing chain: 0.53 s in one thread, 2.7 s in two while another
    process ran; a study's processes compete for the cores as well)."""
    return _blas().limit(limits=1, user_api="blas")  # type: ignore[no-any-return]


@functools.cache
def _blas() -> Any:
    """The BLAS libraries loaded, found once (0.6 ms; each limit then 14 us)."""
    from threadpoolctl import ThreadpoolController  # here: the CLI starts without it

    return ThreadpoolController()


def is_sparse(a: Matrix) -> bool:
    return bool(sp.issparse(a))


def largest(a: FloatArray) -> float:
    """The largest ``|a_i|`` (0 for none): the size a stop or a tolerance
    is relative to. Small arrays, often: ndarray.max costs half of np.max."""
    return float(np.abs(a).max(initial=0.0))


def times(A: Matrix, x: FloatArray) -> FloatArray:
    """``x @ A.T`` for one x (m,) or a batch of rows (B, m)."""
    if sp.issparse(A):
        return np.asarray((A @ x.T).T)
    return np.asarray(x @ A.T)


def adjoint(A: Matrix, y: FloatArray) -> FloatArray:
    """``y @ A`` (that is ``A.T @ y``) for one y or a batch of rows."""
    if sp.issparse(A):
        return np.asarray((A.T @ y.T).T)
    return np.asarray(y @ A)


def vstack(mats: Sequence[Matrix], m: int) -> Matrix:
    """Rows on rows; sparse if any part is sparse."""
    parts = [a for a in mats if a.shape[0]]
    if not parts:
        return np.zeros((0, m))
    if any(sp.issparse(a) for a in parts):
        return sp.vstack([sp.csr_matrix(a) for a in parts], format="csr")
    return np.vstack(parts)


def hstack(mats: Sequence[Matrix], rows: int) -> Matrix:
    parts = [a for a in mats if a.shape[1]]
    if not parts:
        return np.zeros((rows, 0))
    if any(sp.issparse(a) for a in parts):
        return sp.hstack([sp.csr_matrix(a) for a in parts], format="csr")
    return np.hstack(parts)


def dense(a: Matrix) -> FloatArray:
    return np.asarray(a.toarray()) if sp.issparse(a) else np.asarray(a)


def row_norms(A: Matrix) -> FloatArray:
    if sp.issparse(A):
        return np.asarray(np.sqrt(np.asarray(A.multiply(A).sum(axis=1)).ravel()), dtype=float)
    return np.asarray(np.linalg.norm(A, axis=1), dtype=float)


def nonzero_rows(A: Matrix) -> FloatArray:
    """(rows,) bool: the rows that have a non-zero entry."""
    if sp.issparse(A):
        A = sp.csr_matrix(A)
        A.eliminate_zeros()
        return np.asarray(np.diff(A.indptr) > 0)
    return np.asarray(np.any(A != 0.0, axis=1))


def null_space(C: Matrix, m: int, rcond: float = DEFAULT.free_motion_rcond) -> Matrix:
    """Orthonormal basis (m, p) of the motions ``d`` with ``C d = 0``: singular
    values below ``rcond`` times the largest count as zero.

    Dense: one SVD. Sparse: a sparse basis from an elimination by bodies
    (``free_motions.null_basis``), in time linear in the mechanism's size.
    """
    if C.shape[0] == 0:
        return sp.identity(m, format="csc") if sp.issparse(C) else np.eye(m)
    if sp.issparse(C):
        return free_motions.null_basis(C, m, rcond)
    _, sv, Vt = np.linalg.svd(C, full_matrices=True)
    tol = rcond * (sv[0] if sv.size else 0.0)
    rank = int(np.sum(sv > tol)) if sv.size and sv[0] > 0 else 0
    return np.ascontiguousarray(Vt[rank:].T)


def rank(M: FloatArray, rcond: float = DEFAULT.free_motion_rcond) -> int:
    """A dense matrix's rank: its singular values above ``rcond`` of the largest."""
    sv = np.linalg.svd(M, compute_uv=False)
    return int(np.sum(sv > rcond * sv[0])) if sv.size and sv[0] > 0 else 0


def full_column_rank(rows: Matrix, m: int, rcond: float = DEFAULT.free_motion_rcond) -> bool:
    """Whether only ``d = 0`` has ``rows @ d = 0`` (the rows pin every unknown)."""
    if rows.shape[0] < m:
        return False
    if not sp.issparse(rows):
        sv = np.linalg.svd(rows, compute_uv=False)
        return bool(sv.size and sv[0] > 0 and np.sum(sv > rcond * sv[0]) == m)
    return free_motions.column_rank_deficit(rows, m, rcond) == 0


def full_column_rank_rows(J: FloatArray, rcond: float) -> NDArray[np.bool_]:
    """For a stack of small matrices (B, r, m): whether each has ``m``
    singular values above ``rcond`` of its largest.

    Each matrix is scaled to entries of at most 1 and its Gram matrix
    ``G = J^T J`` formed. If every ``G - c tr(G) I`` has a Cholesky
    factor (``c``: ``GRAM_CERTAIN``, or ``GRAM_MARGIN`` rcond^2 if larger),
    every ``G``'s smallest eigenvalue is above ``c`` of its largest, less Cholesky's
    backward error (a few ``m * eps`` of the trace): the SVD's verdict is
    "full rank" for all, at a fifth of the eigenvalues' cost. Else the
    eigenvalues decide the rows that are clearly of full rank, and the SVD
    the others. A row with a non-finite entry pins nothing."""
    B, r, m = J.shape
    if not m:
        return np.ones(B, dtype=bool)
    if r < m or not B:
        return np.zeros(B, dtype=bool)
    finite = np.all(np.isfinite(J), axis=(1, 2))
    size = np.max(np.abs(np.where(finite[:, None, None], J, 0.0)), axis=(1, 2))
    scaled = J / np.where(finite & (size > 0), size, 1.0)[:, None, None]
    scaled[~finite] = 0.0
    G = scaled.transpose(0, 2, 1) @ scaled
    # certain: above round-off, and above rcond squared with room to spare
    certain = max(GRAM_CERTAIN, GRAM_MARGIN * rcond**2)
    if np.all(finite):
        shift = certain * np.trace(G, axis1=1, axis2=2)
        try:
            np.linalg.cholesky(G - shift[:, None, None] * np.eye(m))
        except np.linalg.LinAlgError:
            pass  # some row is not clearly of full rank: find which
        else:
            return np.ones(B, dtype=bool)
    ev = np.linalg.eigvalsh(G)
    full = ev[:, 0] > certain * ev[:, -1]
    unsure = np.flatnonzero(~full & finite)
    if unsure.size:
        sv = np.linalg.svd(scaled[unsure], compute_uv=False)
        full[unsure] = (sv[:, 0] > 0) & (sv[:, m - 1] > rcond * sv[:, 0])
    return np.asarray(full & finite)


class SingularSystemError(Exception):
    """A linear system had no accurate solution."""


def solve_kkt(
    K: Matrix,
    rhs: FloatArray,
    n_primal: int,
    prox: float = 0.0,
    floor: float = 0.0,
    plain: bool = True,
    factors: Any = None,
    weights: FloatArray | None = None,
) -> tuple[FloatArray, Any]:
    """A solution of the square system ``K step = rhs`` (a Newton step on KKT
    equations). A singular but consistent system (statically indeterminate
    forces) gets a solution: the plain factors' if round-off lets them solve
    it (its split of the indeterminate multipliers is then any; the position
    step is the one there is), else a regularized-and-refined one (dense:
    least squares if that fails too). Raises ``SingularSystemError`` when no
    step solves it accurately.

    ``prox`` > 0: the system is expected to be singular up to round-off (a
    tied face); the step is the regularized-and-refined one, which stays
    nearest the current point in every unknown (a plain solve would take the
    round-off's huge step along the singular directions).

    ``floor``: a residual that small is solved whatever the right side's
    size (Newton's own stopping point: near it, its right side is so small
    that a tolerance relative to it falls below round-off; a 100-shaft
    bearing chain's step stopped at 2.9e-16 against 7.5e-17 asked, and every
    polish of it failed).

    ``plain=False``: K is singular by construction (equality rows that
    repeat each other, kept as they are in a sparse system): no plain
    factorization, the regularized one at once. SuperLU fills a large
    singular K in before it meets the zero pivot: on a 4,000-shaft bearing
    chain's tie, 3.8 s and 1.2 GB to fail, against 0.08 s regularized
    (and equilibrated: ``proximal_solve``).

    ``factors``: the plain factors of the previous Newton step's K, tried
    first (refined against this K); returned with the step are the plain
    factors that solved it (None if none did). Newton's K moves with its
    steps only, and near the optimum hardly at all: its last steps need no
    factorization of their own. A sparse K's only: a small dense LU costs
    less than one round of refinement (6.1.6.1's warm re-solve: half its
    reuses failed after five rounds).

    ``weights``: per row, what a residual is measured in (default 1): the
    residual is ``largest(weights * (rhs - K step))``, and ``floor`` is in
    those terms. Newton's rows differ in kind (forces, lengths), and on a
    long chain's tie their sizes part by eight orders: one absolute floor
    either asks the forces' rows for digits below their round-off or lets
    the lengths' rows stop short (``newton``)."""
    w = np.ones(len(rhs)) if weights is None else weights
    size = largest(w * rhs)
    scale = max(1.0, float(abs(K).max()))
    if plain and not prox:
        # plain factors, with a few steps of iterative refinement (long chains need them)
        tol = max(DEFAULT.kkt_plain * size, floor)
        if factors is not None and sp.issparse(K):
            step = _refined(K, factors, rhs, tol, 4, w)
            if step is not None:
                return step, factors
        factors = _factored(K)
        step = _refined(K, factors, rhs, tol, 4, w)
        if step is not None:
            return step, factors
    # Quasi-definite regularization, refined against K: on a consistent
    # system, the solution nearest the current point (in the scaled norm,
    # where equilibrated: ``proximal_solve``)
    tol = max(DEFAULT.kkt_refined * size, floor)
    eps = max(prox, DEFAULT.kkt_round_off * scale)
    step = proximal_solve(K, rhs, n_primal, eps, tol, equilibrated=not plain, weights=w)
    if step is not None and largest(w * (rhs - K @ step)) <= tol:
        return step, None
    if not sp.issparse(K):
        try:
            return np.asarray(np.linalg.lstsq(K, rhs, rcond=DEFAULT.lstsq_rcond)[0]), None
        except np.linalg.LinAlgError:  # its SVD did not converge (an entry not finite)
            pass
    raise SingularSystemError


def proximal_solve(
    K: Matrix,
    rhs: FloatArray,
    n_primal: int,
    eps: float,
    tol: float = 0.0,
    equilibrated: bool = False,
    weights: FloatArray | None = None,
) -> FloatArray | None:
    """Quasi-definite regularization (``+eps`` on the first ``n_primal``
    unknowns, ``-eps`` on the others), then refinement against K itself: a
    proximal-point iteration that converges on a consistent system to the
    solution nearest 0, as a least-squares step does. Stops when
    ``|K step - rhs| <= tol`` (each row times its ``weights``, default 1),
    else returns the best of 40 rounds (None if the regularized matrix
    cannot be factored): on a system consistent only up to round-off, the
    caller checks what it needs.

    ``equilibrated`` (sparse, symmetric K): regularize and factor ``D K D``
    instead, with D the symmetric scaling that brings each row's largest
    entry to about 1 (``eps`` kept relative to the largest entry). A tied
    face's system holds a metric of lever squared (1e8 on a 10,000-shaft
    chain) beside rows of size 1: a regularization relative to the largest
    entry then swamps the small rows' pivots and the refinement crawls
    (0.975 a round on 1,000 shafts; 3 rounds equilibrated). The solution is
    the same; where K is singular, the one it converges to is nearest 0 in
    the norm ``|D^-1 step|`` (on a tie: the split of the repeated rows'
    multipliers, which Newton does not read)."""
    signs = np.r_[np.ones(n_primal), -np.ones(K.shape[0] - n_primal)]
    if sp.issparse(K) and equilibrated:
        d = _equilibration(K)
        scaled = sp.diags(d) @ K @ sp.diags(d)
        top = float(abs(K).max())  # 0: nothing to scale (SuperLU then says singular)
        eps_d = eps * float(abs(scaled).max()) / top if top > 0 else eps
        factors = _factored(scaled + sp.diags(eps_d * signs))
        solve = None if factors is None else (lambda b: d * factors(d * b))
    else:
        solve = _factored(K + (sp.diags(eps * signs) if sp.issparse(K) else np.diag(eps * signs)))
    if solve is None:
        return None
    w = np.ones(len(rhs)) if weights is None else weights
    step = np.zeros(K.shape[0])
    best, best_miss = step, float("inf")
    sizes: list[float] = []
    for _ in range(41):
        miss = rhs - K @ step
        size = largest(w * miss)
        if size <= tol:
            if size < best_miss:
                best = step
            break
        if size < best_miss:
            best, best_miss = step, size
        sizes.append(size)
        if _stalled(sizes):
            break  # the system is not consistent (to round-off)
        step = step + np.asarray(solve(miss), dtype=float)
        if not np.all(np.isfinite(step)):
            break
    return np.asarray(best, dtype=np.float64)


def settled_solve(
    K: sp.spmatrix, rhs: FloatArray, n_primal: int, settle: float, eps: float
) -> FloatArray | None:
    """A solution of the sparse ``K step = rhs`` whose first ``n_primal``
    unknowns are refined until what is left to move them is below
    ``settle``: from K's plain factors where its pattern lets it be regular,
    else (or where they do not settle) from the quasi-definite
    regularization ``eps`` (``proximal_solve``). What is left is read from
    the last two moves, ``d_k (d_k / d_k-1) / (1 - d_k / d_k-1)``: a slow
    contraction leaves more than its last move. None if neither settles in
    41 rounds, or if its moves stall as a regularized refinement's residual
    does (``kkt_refine_window``: a 2,000-shaft bearing chain's split on the
    cone program's support moved 4.7e-6 a round, 40 rounds of a large
    factorization for nothing). For a caller that reads those unknowns
    only, beside multipliers so large that their rows' residual sits at
    round-off and cannot show the others' progress (a 300-segment tube
    string's force split: multipliers of 1,800 against forces of 1;
    stopped by its residual, it was 2e-8 of its forces off, two rounds in)."""
    from scipy.sparse.csgraph import structural_rank  # large models only: 0.02 s to import

    pattern = sp.csr_matrix(K, copy=True)
    pattern.eliminate_zeros()
    # plain factors only where the pattern lets K be regular: SuperLU
    # crashed on a singular pattern (a compliant model's split, clarabel 0.11)
    shifts = [0.0, eps] if structural_rank(pattern) == K.shape[0] else [eps]
    signs = np.r_[np.ones(n_primal), -np.ones(K.shape[0] - n_primal)]
    for shift in shifts:
        solve = _factored(K + sp.diags(shift * signs) if shift else K)
        if solve is None:
            continue
        step = np.zeros(K.shape[0])
        sizes: list[float] = []
        for _ in range(41):
            moved = np.asarray(solve(rhs - K @ step), dtype=float)
            step = step + moved
            if not np.isfinite(step).all():
                break
            sizes.append(largest(moved[:n_primal]))
            before = sizes[-2] if len(sizes) > 1 else float("inf")
            left = sizes[-1] ** 2 / max(before - sizes[-1], TINY)
            if sizes[-1] <= settle and left <= settle:
                return np.asarray(step, dtype=np.float64)
            if _stalled(sizes):
                break
    return None


def _stalled(sizes: list[float]) -> bool:
    """Whether a refinement's last ``kkt_refine_window`` rounds gained less
    than ``kkt_refine_stall`` on the best before them (``sizes``: its
    residuals, or its moves)."""
    window, gain = DEFAULT.kkt_refine_window, 1.0 - DEFAULT.kkt_refine_stall
    return len(sizes) > window and min(sizes[-window:]) > gain * min(sizes[:-window])


def _equilibration(K: Any) -> FloatArray:
    """The symmetric (Ruiz) scaling d of a sparse, symmetric K (a KKT
    system; its rows are its columns): each row of ``diag(d) K diag(d)``
    has its largest entry near 1 (``equilibration_sweeps``)."""
    K = sp.csr_matrix(K)
    d = np.ones(K.shape[0])
    filled = np.flatnonzero(np.diff(K.indptr))  # rows with an entry
    rows = np.repeat(np.arange(K.shape[0]), np.diff(K.indptr))
    size = np.abs(K.data)
    for _ in range(DEFAULT.equilibration_sweeps):
        top = np.ones(K.shape[0])
        top[filled] = np.maximum.reduceat(size * d[rows] * d[K.indices], K.indptr[filled])
        d /= np.sqrt(np.where(top > 0, top, 1.0))
    return d


class Factors:
    """One LU factorization of K: called, ``b -> K^-1 b``; ``regular`` reads
    its pivots (a sparse one's only when asked: 0.01 s on 10,000 bodies)."""

    def __init__(self, solve: Callable[[FloatArray], Any], pivots: Callable[[], Any]):
        self.solve = solve
        self.pivots = pivots

    def __call__(self, b: FloatArray) -> Any:
        return self.solve(b)

    def regular(self, cutoff: float) -> bool:
        """Whether every pivot is above ``cutoff`` of the largest: K is
        regular (an LU is not rank revealing: a pivot may sit well above the
        smallest singular value, so near the cutoff this and a rank test by
        singular values may disagree)."""
        d = np.abs(np.asarray(self.pivots()))
        return bool(d.size) and float(d.min()) >= cutoff * float(d.max())


def _factored(K: Matrix) -> Factors | None:
    """A solver ``b -> K^-1 b`` from one LU factorization, or None when K is
    exactly singular. A sparse K with an empty row or column (a bearing
    chain's polish: one per free spin) never reaches SuperLU: it would fail
    anyway, and on systems singular by their pattern it has corrupted
    memory (a segmentation fault, scipy 1.11 and 1.17; SuperLU's own issue
    33 names empty rows and columns)."""
    try:
        if sp.issparse(K):
            import scipy.sparse.linalg as spla  # large mechanisms only: 0.05 s to import

            K = sp.csc_matrix(K)
            if _has_empty_line(K):
                return None
            with _silenced():  # SuperLU on an exactly singular K fails inside BLAS, which prints
                lu_s = spla.splu(K)
            return Factors(lu_s.solve, lambda: lu_s.U.diagonal())
        # LAPACK directly: scipy's wrappers cost more than a small system's solve
        lu, piv, info = lapack.dgetrf(K)
    except (RuntimeError, ValueError, np.linalg.LinAlgError):
        return None
    if info != 0 or not lu.diagonal().all():  # a zero pivot
        return None

    def solve(b: FloatArray) -> FloatArray:
        return np.asarray(lapack.dgetrs(lu, piv, b)[0])

    return Factors(solve, lu.diagonal)


def _has_empty_line(K: sp.csc_matrix) -> bool:
    """Whether the square sparse K has a row or a column with no non-zero
    entry (a stored 0 is none)."""
    n = K.shape[0]
    held = K.data != 0
    columns = np.repeat(np.arange(n), np.diff(K.indptr))[held]
    return bool(np.any(np.bincount(columns, minlength=n) == 0)) or bool(
        np.any(np.bincount(K.indices[held], minlength=n) == 0)
    )


@contextmanager
def _silenced() -> Iterator[None]:
    """Standard output and error of the process routed to /dev/null (file
    descriptors 1 and 2, where C libraries write): a KKT system of a tied
    face or of indeterminate forces is singular by construction, SuperLU then
    fails, as it should, but OpenBLAS prints its complaint first; we catch
    the failure and take the regularized step, and nothing but our own words
    may reach the user. Only around a factorization, which prints nothing else."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


def _refined(
    K: Matrix, solve: Any, rhs: FloatArray, tol: float, rounds: int, weights: FloatArray
) -> FloatArray | None:
    """``solve(rhs)`` refined against K until ``|K step - rhs| <= tol``,
    each row times its ``weights`` (None if it does not get there in
    ``rounds`` corrections)."""
    if solve is None:
        return None
    step = np.zeros(K.shape[0])
    miss = rhs  # the miss of step 0
    for _ in range(rounds + 1):
        if largest(weights * miss) <= tol:
            return np.asarray(step, dtype=np.float64)
        step = step + np.asarray(solve(miss), dtype=float)
        if not np.isfinite(step).all():
            return None
        miss = rhs - K @ step
    return None


def lstsq(A: Matrix, b: FloatArray) -> FloatArray:
    """Least-squares (least-norm for a dense A) solution of ``A y = b``."""
    if A.shape[1] == 0:
        return np.zeros(0)
    if not sp.issparse(A):
        return np.asarray(np.linalg.lstsq(A, b, rcond=None)[0])
    tol = DEFAULT.lsmr_tolerance
    import scipy.sparse.linalg as spla  # large mechanisms only

    out = spla.lsmr(A, b, atol=tol, btol=tol, maxiter=20 * max(A.shape))
    return np.asarray(out[0])


def solve_rows(K: FloatArray, rhs: FloatArray) -> tuple[FloatArray, NDArray[np.bool_]]:
    """``K[b] z[b] = rhs[b]`` for every row b of a stack of square systems,
    and the mask of the rows that have a solution: an exactly singular row
    gets a zero step and ``False``, the others are solved together by LU."""
    try:
        z = np.asarray(np.linalg.solve(K, rhs[:, :, None])[:, :, 0], dtype=np.float64)
        return z, np.ones(len(K), dtype=bool)
    except np.linalg.LinAlgError:  # some row is singular: find which
        regular: NDArray[np.bool_] = np.linalg.slogdet(K)[0] != 0
    z = np.zeros_like(rhs)
    try:
        if np.any(regular):
            z[regular] = np.linalg.solve(K[regular], rhs[regular][:, :, None])[:, :, 0]
        return z, regular
    except np.linalg.LinAlgError:
        # LU and the determinant disagree on a row at the edge of singular
        # (numpy 1.26's LAPACK does, on a split's KKT system): one at a time
        pass
    for b in np.flatnonzero(regular):
        try:
            z[b] = np.linalg.solve(K[b], rhs[b])
        except np.linalg.LinAlgError:
            regular[b] = False
    return z, regular


def solve_stack(K: FloatArray, rhs: FloatArray, plain: float, rcond: float) -> FloatArray:
    """``K[b] z[b] = rhs[b]`` for a stack of small square systems: one LU
    each, together; a row that is singular, or whose residual is above
    ``plain`` of its right side, gets its least-norm least-squares solution
    instead (an SVD, singular values below ``rcond`` of the largest dropped)."""
    z, regular = solve_rows(K, rhs)
    z[~regular] = np.nan
    miss = np.max(np.abs(np.einsum("bij,bj->bi", K, z) - rhs), axis=1, initial=0.0)
    bad = ~(miss <= plain * np.max(np.abs(rhs), axis=1, initial=0.0))  # NaN too
    if np.any(bad):
        z[bad] = (np.linalg.pinv(K[bad], rcond=rcond) @ rhs[bad][:, :, None])[:, :, 0]
    return np.asarray(z)


def distinct_rows(a: NDArray[Any]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """The first of each distinct row of ``a`` (B, k), and for every row the
    index of its distinct one: ``a[first][same] == a``."""
    if not len(a) or np.all(a == a[0]):
        return np.zeros(min(len(a), 1), dtype=np.intp), np.zeros(len(a), dtype=np.intp)
    # each row's bytes as one item (np.unique with axis=0 costs a millisecond
    # of Python per call); equal bytes are equal rows (-0.0 and 0.0 differ)
    rows = np.ascontiguousarray(a).reshape(len(a), -1)
    items = rows.view(np.dtype((np.void, rows.dtype.itemsize * rows.shape[1]))).ravel()
    _, first, same = np.unique(items, return_index=True, return_inverse=True)
    return first.astype(np.intp), same.ravel().astype(np.intp)
