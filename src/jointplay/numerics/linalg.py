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
from jointplay.settings import GRAM_CERTAIN, GRAM_MARGIN, TINY

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


def null_space(C: Matrix, m: int, rcond: float, round_off: float) -> Matrix:
    """Orthonormal basis (m, p) of the motions ``d`` with ``C d = 0``: singular
    values below ``rcond`` times the largest count as zero.

    Dense: one SVD. Sparse: a sparse basis from an elimination by bodies
    (``free_motions.null_basis``), in time linear in the mechanism's size.
    """
    if C.shape[0] == 0:
        return sp.identity(m, format="csc") if sp.issparse(C) else np.eye(m)
    if sp.issparse(C):
        return free_motions.null_basis(C, m, rcond, round_off)
    _, sv, Vt = np.linalg.svd(C, full_matrices=True)
    tol = rcond * (sv[0] if sv.size else 0.0)
    rank = int(np.sum(sv > tol)) if sv.size and sv[0] > 0 else 0
    return np.ascontiguousarray(Vt[rank:].T)


def rank(M: FloatArray, rcond: float) -> int:
    """A dense matrix's rank: its singular values above ``rcond`` of the largest."""
    sv = np.linalg.svd(M, compute_uv=False)
    return int(np.sum(sv > rcond * sv[0])) if sv.size and sv[0] > 0 else 0


def full_column_rank(rows: Matrix, m: int, rcond: float) -> bool:
    """Whether only ``d = 0`` has ``rows @ d = 0`` (the rows pin every unknown)."""
    if rows.shape[0] < m:
        return False
    if not sp.issparse(rows):
        sv = np.linalg.svd(rows, compute_uv=False)
        return bool(sv.size and sv[0] > 0 and np.sum(sv > rcond * sv[0]) == m)
    return free_motions.Eliminated(rows, m, rcond).deficit == 0


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
    *,
    tol: float | FloatArray,
    refinements: int,
    shift: float = 0.0,
) -> tuple[FloatArray, Factors | None]:
    """A solution of the square system ``K step = rhs`` (a Newton step on KKT
    equations) from one LU factorization, refined against K ``refinements``
    times (each a solve with the factors: cheap beside the factorization).
    Raises ``SingularSystemError`` when K cannot be factored or a residual
    ``|rhs - K step|`` is then above ``tol`` (a number or one per row;
    ``inf``: the caller checks what it needs).

    ``shift`` > 0: the factors are those of the quasi-definite ``K + D``,
    ``D`` ``+shift`` on the first ``n_primal`` unknowns and ``-shift`` on the
    others. Refined against K, a
    consistent singular system (a tied face, indeterminate forces) then
    converges to its solution nearest 0 in the norm ``D``. Returned with the
    step: K's own factors (their pivots tell whether K is regular), None
    when regularized."""
    factors = _factored(K if not shift else K + _diag(_quasi_definite(K, n_primal, shift), K))
    if factors is None:
        raise SingularSystemError
    step = np.asarray(factors(rhs), dtype=float)
    for _ in range(refinements):
        step = step + np.asarray(factors(rhs - K @ step), dtype=float)
    if np.all(np.abs(rhs - K @ step) <= tol):  # NaN: not solved
        return np.asarray(step, dtype=np.float64), None if shift else factors
    raise SingularSystemError


def _quasi_definite(K: Matrix, n_primal: int, shift: float) -> FloatArray:
    """``+shift`` on the primal unknowns, ``-shift`` on the multipliers (the
    problem is scaled to loads of unit norm: an absolute shift)."""
    return np.asarray(np.r_[np.full(n_primal, shift), np.full(K.shape[0] - n_primal, -shift)])


def _diag(d: FloatArray, like: Matrix) -> Matrix:
    return sp.diags(d) if sp.issparse(like) else np.diag(d)


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
    descriptors 1 and 2, where C libraries write): SuperLU fails on a
    singular K, as it should, but OpenBLAS prints its complaint first; we
    catch the failure, and nothing but our own words may reach the user.
    Only around a factorization, which prints nothing else."""
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


def lstsq(A: Matrix, b: FloatArray, rcond: float, refinements: int) -> FloatArray:
    """The least-norm least-squares solution of ``A y = b``. Dense: by an
    SVD, singular values below ``rcond`` of the largest dropped. Sparse: the
    normal equations, regularized by ``sqrt(rcond)`` of their largest entry
    (they square A's singular values; a smaller shift leaves the solve's
    round-off along A's null space at eps over it), one LU, refined
    ``refinements`` times against A itself: a proximal-point iteration,
    which converges to the least-norm solution. Raises
    ``SingularSystemError`` where it cannot be done."""
    if A.shape[1] == 0:
        return np.zeros(0)
    if not sp.issparse(A):
        try:
            return np.asarray(np.linalg.lstsq(A, b, rcond=rcond)[0])
        except np.linalg.LinAlgError as exc:  # its SVD did not converge (an entry not finite)
            raise SingularSystemError from exc
    AtA = sp.csc_matrix(A.T @ A)
    shift = np.sqrt(rcond) * max(float(abs(AtA).max()), TINY)
    factors = _factored(AtA + shift * sp.identity(AtA.shape[0], format="csc"))
    if factors is None:
        raise SingularSystemError
    y = np.zeros(A.shape[1])
    for _ in range(refinements + 1):
        y = y + np.asarray(factors(A.T @ (b - A @ y)), dtype=float)
    return np.asarray(y)


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
