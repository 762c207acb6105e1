"""One path from a model to a cone program, with a map back to joints and contacts.

Unknowns. Each moving body b gets a 6-vector of *scaled* unknowns
``x_b = (V_b / s, Omega_b * ell_b / s)``: ``V_b`` the translation of the body
point at its reference point ``c_b`` (the centroid of its joint centres),
``Omega_b`` its rotation vector. ``s`` is a displacement scale (the largest
play), ``ell_b`` the body's own length (how far its joints are from ``c_b``).
Working at ``c_b``, with each body's own lever, keeps far-away and small
parts of a large mechanism well conditioned; results are reported at the
global origin. ``ell``, a length of the whole mechanism, weighs rotations
against translations in the least-norm metric.

Everything the solver needs is linear in ``x``:

* ``G_joint @ x`` is a joint's relative torsor ``(t [mm], w [rad])`` of b with
  respect to a, at the joint centre, in the joint frame;
* each contact is ``|| A @ x - c || + B @ x <= radius`` (scaled by ``s``;
  ``B`` is zero for a plain ball of play; ``c``, the centre of its play, is
  zero unless the joint's features deviate, see ``deviations.py``), or
  ``A @ x = 0``;
* the loads' work is ``g @ x`` (N*mm), so the potential energy is ``-g @ x``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from jointplay.geometry import FloatArray, cross, skew
from jointplay.model.joints import Contact, Joint
from jointplay.model.mechanism import Load, Model
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix
from jointplay.settings import DEFAULT

IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class JointMap:
    """A joint's (6, m) map from scaled unknowns to its relative torsor
    ``(t mm, w rad)``, stored compactly: only the columns of its two bodies."""

    cols: IntArray
    block: FloatArray  # (6, len(cols))
    m: int

    def apply(self, x: FloatArray) -> FloatArray:
        return self.block @ x[self.cols]

    def __matmul__(self, x: FloatArray) -> FloatArray:
        return self.apply(x)


@dataclass(frozen=True)
class ContactRows:
    """Where one contact of one joint sits in the cone program: its rows
    ``A = rows @ G_joint / s`` (scaled), kept on the joint's columns only."""

    joint_index: int
    contact_index: int
    contact: Contact
    cols: IntArray
    block: FloatArray  # (k, len(cols))
    radius: float  # scaled: contact.radius / s
    m: int
    stiffness: float = 0.0  # N/mm; 0: rigid (the clearance is a hard limit)
    offset_block: FloatArray | None = None  # (len(cols),): the row B of a face, scaled
    #: A ball with no play is fixed rows, unless its play was set by a study
    #: (``Assembly.with_radii``): the contacts then keep the model's layout.
    zero_play_is_fixed: bool = True
    #: (k,) scaled: where the play's centre sits, ``rows @ delta / s`` for the
    #: joint's deviation ``delta``; None: at 0 (no deviation).
    centre: FloatArray | None = None

    @property
    def is_fixed(self) -> bool:
        if self.contact.kind == "fixed":
            return True
        return (
            self.zero_play_is_fixed
            and self.radius == 0.0
            and self.stiffness == 0.0
            and self.offset_block is None
            and self.centre is None
        )

    @property
    def k(self) -> int:
        return int(self.block.shape[0])

    def apply(self, x: FloatArray) -> FloatArray:
        """``A @ x``."""
        return self.block @ x[self.cols]

    def adjoint(self, u: FloatArray) -> FloatArray:
        """``A.T @ u`` as a full m-vector."""
        out = np.zeros(self.m)
        np.add.at(out, self.cols, self.block.T @ u)
        return out

    def dense(self) -> FloatArray:
        out = np.zeros((self.k, self.m))
        np.add.at(out.T, self.cols, self.block.T)
        return out

    def exact_parts(
        self, s: float, R_rel: FloatArray, phi: FloatArray, t_rel: FloatArray
    ) -> tuple[FloatArray, float]:
        """``Contact.exact_parts`` (mm) measured from the play's centre."""
        vector, scalar = self.contact.exact_parts(R_rel, phi, t_rel)
        vector = np.asarray(vector, dtype=float)
        if self.centre is not None:
            vector = vector - self.centre * s
        return vector, scalar

    def exact_level(self, s: float, R_rel: FloatArray, phi: FloatArray, t_rel: FloatArray) -> float:
        """``|a| + b`` of ``exact_parts``: compare with ``radius * s``."""
        vector, scalar = self.exact_parts(s, R_rel, phi, t_rel)
        return float(np.linalg.norm(vector)) + scalar

    def dense_offset(self) -> FloatArray:
        """``B`` as a full m-vector (zero for a plain ball)."""
        out = np.zeros(self.m)
        if self.offset_block is not None:
            np.add.at(out, self.cols, self.offset_block)
        return out


def _rows_matrix(blocks: Sequence[tuple[IntArray, FloatArray]], m: int, sparse: bool) -> Matrix:
    """Rows given as (columns, block) pairs, stacked: dense or sparse (CSR)."""
    n_rows = sum(block.shape[0] for _, block in blocks)
    if not sparse:
        out = np.zeros((n_rows, m))
        at = 0
        for cols, block in blocks:
            np.add.at(out[at : at + block.shape[0]].T, cols, block.T)
            at += block.shape[0]
        return out
    if not blocks:
        return sp.csr_matrix((0, m))
    # each block's entries go to their place in one buffer, a shape at a time
    # (thousands of blocks share a few shapes: a Python step per block costs more)
    ks = np.array([block.shape[0] for _, block in blocks], dtype=np.intp)
    cs = np.array([len(cols) for cols, _ in blocks], dtype=np.intp)
    nnz = ks * cs
    first = np.cumsum(nnz) - nnz
    rows = np.repeat(np.arange(n_rows), np.repeat(cs, ks))
    cols_all = np.empty(int(nnz.sum()), dtype=np.intp)
    vals = np.empty(int(nnz.sum()))
    shape_code = ks * (m + 1) + cs
    for code in np.unique(shape_code).tolist():
        which = np.flatnonzero(shape_code == code)
        k, c = divmod(code, m + 1)
        if not k or not c:
            continue
        at = first[which][:, None, None] + np.arange(k * c).reshape(k, c)
        cols_all[at] = np.stack([blocks[i][0] for i in which.tolist()])[:, None, :]
        vals[at] = np.stack([blocks[i][1] for i in which.tolist()])
    return sp.csr_matrix((vals, (rows, cols_all)), shape=(n_rows, m))


@dataclass(frozen=True)
class BallStack:
    """The clearance cones ``|A_i x - c_i| + B_i x <= r_i`` stacked for vectorized work.

    ``A`` holds the rows of every cone one after the other (cone ``i`` is rows
    ``start[i] : start[i] + k[i]``; ``k[i]`` is 0 for a one-sided limit),
    ``B`` one row per cone (zero for a plain ball), ``r`` the radii (scaled),
    ``centre`` the cones' centres stacked like the rows of A (None: all 0).
    The dual of cone i is a force ``lam_i >= |f_i|`` with a vector ``f_i``
    (``f`` stacks them like the rows of ``A``); it does the work
    ``A_i^T f_i + lam_i B_i`` (see ``adjoint``).
    """

    A: Matrix  # (sum k, m), dense or sparse (see ``linalg``)
    start: IntArray  # (n,) first row of each cone
    k: IntArray  # (n,) rows per cone
    r: FloatArray  # (n,)
    spring: FloatArray  # (n,) contact stiffness N/mm, 0 for a hard limit
    B: Matrix  # (n, m)
    centre: FloatArray | None = None  # (sum k,) scaled; None: every centre at 0

    @staticmethod
    def of(balls: Sequence[ContactRows], m: int, sparse: bool = False) -> BallStack:
        k = np.array([c.k for c in balls], dtype=np.intp)
        start = np.concatenate([[0], np.cumsum(k)[:-1]]).astype(np.intp) if len(k) else k
        A = _rows_matrix([(c.cols, c.block) for c in balls], m, sparse)
        r = np.array([c.radius for c in balls], dtype=float)
        spring = np.array([c.stiffness for c in balls], dtype=float)
        zero = np.zeros((1, 0))
        B = _rows_matrix(
            [
                (c.cols, c.offset_block[None, :])
                if c.offset_block is not None
                else (c.cols[:0], zero)
                for c in balls
            ],
            m,
            sparse,
        )
        centre = None
        if any(c.centre is not None for c in balls):
            centre = np.concatenate(
                [np.zeros(c.k) if c.centre is None else c.centre for c in balls]
            )
        return BallStack(A, start, k, r, spring, B, centre)

    @property
    def m(self) -> int:
        return int(self.A.shape[1])

    def cone_rows(self, i: int) -> Matrix:
        """The rows ``A_i`` of cone i."""
        return self.A[self.start[i] : self.start[i] + self.k[i]]

    def face_rows(self, i: int) -> Matrix:
        """``(A_i; B_i)``: the rows that hold when cone i rests flat at its apex."""
        return linalg.vstack([self.cone_rows(i), self.B[i : i + 1]], self.m)

    def rows_of(self, which: Sequence[int] | IntArray) -> IntArray:
        """Rows of ``A`` (and entries of ``f``) of the cones ``which``."""
        idx = np.asarray(which, dtype=np.intp)
        if not len(idx):
            return np.zeros(0, dtype=np.intp)
        k = self.k[idx]
        before = np.cumsum(k) - k  # rows of the earlier cones in ``which``
        return np.asarray(np.repeat(self.start[idx] - before, k) + np.arange(int(k.sum())))

    def take(self, which: Sequence[int] | IntArray) -> BallStack:
        """The sub-stack of cones ``which`` (in that order)."""
        idx = np.asarray(which, dtype=np.intp)
        k = self.k[idx]
        start = np.concatenate([[0], np.cumsum(k)[:-1]]).astype(np.intp) if len(k) else k
        rows = self.rows_of(idx)
        return BallStack(
            self.A[rows],
            start,
            k,
            self.r[idx],
            self.spring[idx],
            self.B[idx],
            None if self.centre is None else self.centre[rows],
        )

    def with_limits(self, rows: Matrix, bounds: FloatArray | None = None) -> BallStack:
        """This stack and the one-sided limits ``rows @ x <= bounds`` (one
        per row; 0 by default)."""
        n = rows.shape[0]
        total = np.full(n, int(np.sum(self.k)), dtype=np.intp)
        return BallStack(
            self.A,
            np.concatenate([self.start, total]),
            np.concatenate([self.k, np.zeros(n, dtype=np.intp)]),
            np.concatenate([self.r, np.zeros(n) if bounds is None else bounds]),
            np.concatenate([self.spring, np.zeros(n)]),
            linalg.vstack([self.B, rows], self.m),
            self.centre,
        )

    @cached_property
    def has_offset(self) -> NDArray[np.bool_]:
        """(n,): the cone has a face row ``B_i`` (a one-sided limit or a tilting face)."""
        return np.asarray(linalg.nonzero_rows(self.B), dtype=bool)

    @cached_property
    def has_rim(self) -> NDArray[np.bool_]:
        """(n,): a face that may rest flat at its apex (``A_i x = c_i``) and
        tilt onto its rim. A cone with no offset reaches its apex only with
        no play (a ball with a position zone and no clearance): it has no
        rim, its force vector is free and its force is ``|f_i|``."""
        return np.asarray(self.has_offset & (self.k > 0))

    @cached_property
    def segment_matrix(self) -> sp.csr_matrix:
        """(sum k, n) sparse indicator of each row's cone."""
        n_rows = int(np.sum(self.k))
        rows = np.arange(n_rows)
        return sp.csr_matrix(
            (np.ones(n_rows), (rows, np.repeat(np.arange(len(self.k)), self.k))),
            shape=(n_rows, len(self.k)),
        )

    @cached_property
    def _with_rows(self) -> NDArray[np.bool_] | None:
        """The cones that have rows, when some have none (``reduceat`` cannot
        sum an empty segment: those are summed apart, as 0)."""
        return None if np.all(self.k > 0) else np.asarray(self.k > 0)

    @cached_property
    def cone_size(self) -> FloatArray:
        """(n,): ``|A_i|_F + |B_i|``, which bounds the generalized force of cone
        i per unit of its multiplier (to weigh a balance of forces)."""
        a2 = linalg.row_norms(self.A) ** 2
        return np.asarray(np.sqrt(self.segment_sum(a2)) + linalg.row_norms(self.B))

    def segment_sum(self, w: FloatArray) -> FloatArray:
        """Per cone, the sum of ``w`` over its rows (last axis)."""
        if not len(self.k):
            return np.zeros((*w.shape[:-1], 0))
        has = self._with_rows
        if has is None:
            return np.add.reduceat(w, self.start, axis=-1)
        # not a (rows, cones) indicator matrix: that grows with the square
        # of the size (a 2,000-body model with point contacts: 0.5 GB)
        out = np.zeros((*w.shape[:-1], len(self.k)))
        if np.any(has):
            out[..., has] = np.add.reduceat(w, self.start[has], axis=-1)
        return out

    def centres(self, centre: FloatArray | None = None) -> FloatArray:
        """The centres stacked like the rows of A: ``centre`` if given (a
        study's, a row per sample), else the stack's own (0 without)."""
        if centre is not None:
            return centre
        return np.zeros(self.A.shape[0]) if self.centre is None else self.centre

    def norms(
        self, x: FloatArray, centre: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray]:
        """``(A @ x - c, |A_i x - c_i|)`` for one x (m,) or a batch of rows
        (B, m); ``centre``: other centres than the stack's (like ``v``)."""
        v = linalg.times(self.A, x)
        c = self.centre if centre is None else centre
        if c is not None:
            v = v - c
        return v, np.sqrt(self.segment_sum(v * v))

    def levels(
        self, x: FloatArray, centre: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(A @ x - c, |A_i x - c_i|, |A_i x - c_i| + B_i x)``: each cone's
        level, to compare with r."""
        v, rho = self.norms(x, centre)
        return v, rho, rho + linalg.times(self.B, x)

    @property
    def homogeneous(self) -> BallStack:
        """The same cones centred at 0: the directions they let go on for ever."""
        return self if self.centre is None else replace(self, centre=None)

    def adjoint(self, f: FloatArray, lam: FloatArray) -> FloatArray:
        """``sum_i A_i^T f_i + lam_i B_i``: the work of the contact forces (rows batched)."""
        return linalg.adjoint(self.A, f) + linalg.adjoint(self.B, lam)

    def surface_forces(self, v: FloatArray, rho: FloatArray, lam: FloatArray) -> FloatArray:
        """``f_i = lam_i A_i x / |A_i x|`` (0 where ``A_i x = 0``): the force vectors
        of contacts on their cone's surface."""
        safe = np.where(rho > 0.0, rho, 1.0)
        return v * np.repeat(lam / safe, self.k, axis=-1)

    def gap_used(self, level: FloatArray, radii: FloatArray | None = None) -> FloatArray:
        """Fraction of each cone's play used at ``level = |A_i x| + B_i x``, in
        [0, 1] (a limit with no play, or one a deviation moved in past its
        play, counts as used as soon as it is reached); ``radii``: other
        radii than the stack's (a row each, like ``level``)."""
        radii = self.r if radii is None else radii
        r = np.where(radii > 0, radii, 1.0)
        reached = level >= np.minimum(radii, 0.0) - DEFAULT.zero_play_reach
        return np.clip(np.where(radii > 0, level / r, reached), 0.0, 1.0)


@dataclass(frozen=True)
class ContactTables:
    """Every joint and contact at once, to turn an answer into per-joint
    results without a Python step per contact (``Assembly.contacts`` order)."""

    # dense for a small mechanism (scipy's constructors cost more than its
    # whole solve), sparse for a large one (``Assembly.sparse``)
    tau_map: Matrix  # (6 J, m): x -> each joint's torsor (t mm, w rad)
    wrench_ball: Matrix  # (6 nb, sum k): stacked f -> -(rows.T f) per ball
    offset_ball: FloatArray  # (nb, 6): each ball's face row (0 for a plain ball)
    wrench_fixed: Matrix  # (6 nf, sum k): stacked multipliers -> -(rows.T nu)
    is_ball: NDArray[np.bool_]  # (nc,)
    joint_of: IntArray  # (nc,)
    local_point: FloatArray  # (nc, 3) joint frame, mm: where each contact acts
    leaning: IntArray  # contacts whose centre of pressure moves with the force
    centre: FloatArray  # (J, 3) joint centres, mm
    R_world_joint: FloatArray  # (J, 3, 3)
    contact_name: tuple[str, ...]  # (nc,)
    turn_lever: FloatArray  # (nc,) mm per rad of a drive's backlash, nan for a play in mm
    joint_name: tuple[str, ...]  # (J,)
    joint_type: tuple[str, ...]  # (J,)
    between: tuple[tuple[str, str], ...]  # (J,) bodies a, b
    between_index: IntArray  # (J, 2) moving-body index of a and b, -1 for the ground
    by_joint: IntArray  # (nc,) the contacts by joint, each joint's in its ``cones`` order
    first_contact: IntArray  # (J + 1,) joint j's contacts: by_joint[first[j] : first[j + 1]]


def _wrench_map(contacts: Sequence[ContactRows], sparse: bool) -> Matrix:
    """Block-diagonal ``-rows.T`` of the contacts (their duals stacked)."""
    k = np.array([c.k for c in contacts], dtype=np.intp)
    rows = np.concatenate([c.contact.rows for c in contacts]) if contacts else np.zeros((0, 6))
    owner = np.repeat(np.arange(len(contacts)), k)
    i = (6 * owner[:, None] + np.arange(6)).ravel()
    j = np.repeat(np.arange(rows.shape[0]), 6)
    return _matrix(-rows.ravel(), i, j, (6 * len(contacts), rows.shape[0]), sparse)


def _matrix(
    v: FloatArray, i: IntArray, j: IntArray, shape: tuple[int, int], sparse: bool
) -> Matrix:
    """The matrix with entries ``v`` at ``(i, j)`` (repeats add up)."""
    if sparse:
        return sp.csr_matrix((v, (i, j)), shape=shape)
    out = np.zeros(shape)
    np.add.at(out, (i, j), v)
    return out


@dataclass(frozen=True)
class Assembly:
    """The model turned into matrices, once; the solver reads only this."""

    model: Model
    body_names: tuple[str, ...]  # moving bodies, in unknown-block order
    body_ref: FloatArray  # (n, 3) reference point c_b of each moving body (mm)
    s: float  # mm per unit of scaled translation
    ell: float  # mm: rotation lever of the least-norm metric (the whole mechanism)
    G: tuple[JointMap, ...]  # per joint: scaled x -> (t mm, w rad) in joint frame
    contacts: tuple[ContactRows, ...]
    g: FloatArray  # (m,) work of the loads per unit scaled x (N*mm)
    turn: FloatArray  # (n,) rad per unit of each body's scaled rotation: s / ell_b

    @property
    def m(self) -> int:
        return 6 * len(self.body_names)

    @property
    def sparse(self) -> bool:
        """Whether the matrices are sparse (a large mechanism; see ``linalg``)."""
        return self.m > linalg.SPARSE_FROM

    @cached_property
    def is_ball(self) -> NDArray[np.bool_]:
        """(contacts,) whether each contact is a clearance cone (else fixed rows)."""
        return np.array([not c.is_fixed for c in self.contacts], dtype=bool)

    @cached_property
    def balls(self) -> tuple[ContactRows, ...]:
        pairs = zip(self.contacts, self.is_ball.tolist(), strict=True)
        return tuple(c for c, ball in pairs if ball)

    @cached_property
    def fixed(self) -> tuple[ContactRows, ...]:
        pairs = zip(self.contacts, self.is_ball.tolist(), strict=True)
        return tuple(c for c, ball in pairs if not ball)

    @cached_property
    def metric(self) -> FloatArray:
        """Least-norm metric (dense m x m): sum over joints of |t/s|^2 + |w * ell / s|^2.

        It measures the relative motion in the joints, so it does not change
        under a rigid motion of the whole model or a change of units, and a
        rigid joint (no relative motion) adds nothing to it.
        """
        w = self._metric_weights
        M = np.zeros((self.m, self.m))
        for G in self.G:
            wb = w[:, None] * G.block
            M[np.ix_(G.cols, G.cols)] += wb.T @ wb
        return M

    @cached_property
    def metric_matrix(self) -> Matrix:
        """The least-norm metric, sparse for a large mechanism (else ``metric``)."""
        if not self.sparse:
            return self.metric
        w2 = self._metric_weights**2
        parts = []
        for width in sorted({len(G.cols) for G in self.G}):  # joints to ground, between bodies
            same = [G for G in self.G if len(G.cols) == width]
            blocks = np.stack([G.block for G in same])  # (J, 6, width)
            cols = np.stack([G.cols for G in same])  # (J, width)
            products = blocks.transpose(0, 2, 1) @ (w2[:, None] * blocks)  # (J, width, width)
            parts.append(
                (
                    np.repeat(cols, width, axis=1).ravel(),
                    np.tile(cols, (1, width)).ravel(),
                    products.ravel(),
                )
            )
        if not parts:
            return sp.csr_matrix((self.m, self.m))
        rows, cols, vals = (np.concatenate(p) for p in zip(*parts, strict=True))
        return sp.csr_matrix((vals, (rows, cols)), shape=(self.m, self.m))

    @property
    def _metric_weights(self) -> FloatArray:
        """Weights of (t, w) in the metric: |t/s|^2 + |w * ell / s|^2."""
        return np.concatenate([np.full(3, 1.0 / self.s), np.full(3, self.ell / self.s)])

    def metric_times(self, X: FloatArray) -> FloatArray:
        """``metric @ X`` without forming the metric."""
        w2 = self._metric_weights**2
        out = np.zeros((self.m, X.shape[1]))
        for G in self.G:
            out[G.cols] += G.block.T @ (w2[:, None] * (G.block @ X[G.cols]))
        return out

    def with_radii(self, radii: FloatArray, centre: FloatArray | None = None) -> Assembly:
        """This assembly with other scaled radii for its clearance cones
        (``balls`` order) and, if given, other centres (stacked like the rows
        of ``stack.A``); everything else, the scales included, is kept."""
        radii = np.asarray(radii, dtype=float)
        if radii.shape != (len(self.balls),):
            raise ValueError(f"radii must have shape ({len(self.balls)},), not {radii.shape}")
        k = [c.k for c in self.balls]
        if centre is not None:
            centre = np.asarray(centre, dtype=float)
            if centre.shape != (sum(k),):
                raise ValueError(f"centre must have shape ({sum(k)},), not {centre.shape}")
            ends = np.cumsum(k)
            centres = [centre[e - n : e] for e, n in zip(ends, k, strict=True)]
        new = {
            id(c): (float(r), c.centre if centre is None else centres[i])
            for i, (c, r) in enumerate(zip(self.balls, radii, strict=True))
        }
        contacts = tuple(
            replace(c, radius=new[id(c)][0], centre=new[id(c)][1], zero_play_is_fixed=False)
            if id(c) in new
            else c
            for c in self.contacts
        )
        return replace(self, contacts=contacts)

    @cached_property
    def model_warnings(self) -> tuple[str, ...]:
        """``Model.warnings``, worked out once for all of this assembly's
        answers (a 10,000-joint model takes 0.2 s; the model, which a copy
        may change, does not keep them)."""
        return self.model.warnings

    @cached_property
    def body_index(self) -> dict[str, int]:
        return {name: i for i, name in enumerate(self.body_names)}

    def work_of(self, loads: Sequence[Load]) -> FloatArray:
        """``g`` for another set of loads on the same mechanism."""
        for load in loads:
            if load.body not in self.body_index:
                raise ValueError(f"load on body {load.body!r}, which is not a moving body")
        return load_work(loads, self.body_index, self.body_ref, self.s, self.turn)

    def wrench_work(self, body: str, at: Sequence[float] | None = None) -> FloatArray:
        """The (m, 6) map from a wrench ``(force N, torque N*mm)`` acting on
        ``body`` at point ``at`` (mm, global) to its work ``g``: loads add up
        linearly, so a study builds many load cases as ``W @ wrench``."""
        i = self.body_index[body]
        W = np.zeros((self.m, 6))
        W[6 * i : 6 * i + 3, :3] = self.s * np.eye(3)
        W[6 * i + 3 : 6 * i + 6, 3:] = self.turn[i] * np.eye(3)
        if at is not None:
            lever = np.asarray(at, dtype=float) - self.body_ref[i]
            W[6 * i + 3 : 6 * i + 6, :3] = self.turn[i] * skew(lever)
        return W

    @cached_property
    def tables(self) -> ContactTables:
        """Joints and contacts stacked for vectorized results (``ContactTables``)."""
        joints = self.model.joints
        nj = len(self.G)
        widths = np.array([len(G.cols) for G in self.G], dtype=np.intp)
        parts: list[tuple[IntArray, IntArray, FloatArray]] = []
        for w in np.unique(widths):  # joints to ground (6 columns), between bodies (12)
            which = np.flatnonzero(widths == w)
            cols = np.array([self.G[q].cols for q in which]).reshape(-1, 1, w)
            blocks = np.array([self.G[q].block for q in which]).reshape(-1, 6, w)
            rows = 6 * which[:, None, None] + np.arange(6)[None, :, None]
            shape = blocks.shape
            parts.append(
                (
                    np.broadcast_to(rows, shape).ravel(),
                    np.broadcast_to(cols, shape).ravel(),
                    blocks.ravel(),
                )
            )
        i = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, dtype=np.intp)
        j = np.concatenate([p[1] for p in parts]) if parts else np.zeros(0, dtype=np.intp)
        v = np.concatenate([p[2] for p in parts]) if parts else np.zeros(0)
        tau_map = _matrix(v, i, j, (6 * nj, self.m), self.sparse)
        offsets = [
            np.zeros(6) if c.contact.offset is None else c.contact.offset for c in self.balls
        ]
        contacts = self.contacts
        joint_of = np.array([c.joint_index for c in contacts], dtype=np.intp)
        by_joint = np.argsort(joint_of, kind="stable").astype(np.intp)
        return ContactTables(
            tau_map,
            _wrench_map(self.balls, self.sparse),
            np.array(offsets).reshape(-1, 6),
            _wrench_map(self.fixed, self.sparse),
            self.is_ball,
            joint_of,
            np.array([c.contact.point for c in contacts], dtype=float).reshape(-1, 3),
            np.array(
                [n for n, c in enumerate(contacts) if c.contact.lever is not None], dtype=np.intp
            ),
            np.array([jt.centre for jt in joints], dtype=float).reshape(-1, 3),
            np.array([jt.R_world_joint for jt in joints], dtype=float).reshape(-1, 3, 3),
            tuple(c.contact.name for c in contacts),
            np.array([c.contact.turn_lever for c in contacts], dtype=float),  # None: nan
            tuple(jt.name for jt in joints),
            tuple(jt.type_name for jt in joints),
            tuple(jt.between for jt in joints),
            np.array(
                [[self.body_index.get(name, -1) for name in jt.between] for jt in joints],
                dtype=np.intp,
            ).reshape(-1, 2),
            by_joint,
            np.searchsorted(joint_of[by_joint], np.arange(len(joints) + 1)).astype(np.intp),
        )

    @cached_property
    def stack(self) -> BallStack:
        """All clearance cones stacked into dense arrays (see ``BallStack``)."""
        return BallStack.of(self.balls, self.m, self.sparse)

    @cached_property
    def E_length(self) -> FloatArray:
        """(rows of E,) the factor that turns each rigid row's residual into
        mm across the mechanism: 1 for a point's displacement (mm); for a
        row of a turn alone, ``ell`` over the row's own lever (a weld's turn
        row is the angle: ``ell``; a tight drive's is the angle times its
        lever rho: ``ell / rho``). A turn w opens a weld by about w * ell."""
        if not self.fixed:
            return np.zeros(0)
        rows = np.vstack([c.contact.rows for c in self.fixed])
        lever = np.linalg.norm(rows[:, 3:], axis=1)
        turn = ~np.any(rows[:, :3] != 0.0, axis=1) & (lever > 0.0)
        return np.where(turn, self.ell / np.where(turn, lever, 1.0), 1.0)

    @cached_property
    def E(self) -> Matrix:
        """Equality rows (rigid joints and zero-clearance contacts)."""
        return _rows_matrix([(c.cols, c.block) for c in self.fixed], self.m, self.sparse)

    def scale_matrix(self) -> FloatArray:
        """Physical (V_c mm, Omega rad) per body from scaled x: ``x_phys = D * x``."""
        n = len(self.body_names)
        return np.column_stack(
            [np.full((n, 3), self.s), np.repeat(self.turn[:, None], 3, 1)]
        ).ravel()

    def unknowns_of(self, bodies: Mapping[str, Any]) -> FloatArray:
        """The scaled unknowns x of an answer's bodies (``Result.bodies``:
        each with ``displacement_of(point)`` and ``rotation``)."""
        x = np.zeros(self.m)
        for i, name in enumerate(self.body_names):
            body = bodies[name]
            x[6 * i : 6 * i + 3] = body.displacement_of(self.body_ref[i]) / self.s
            x[6 * i + 3 : 6 * i + 6] = body.rotation / self.turn[i]
        return x

    def body_motion(self, x: FloatArray, i: int) -> tuple[FloatArray, FloatArray]:
        """(rotation rad, translation at global origin mm) of moving body ``i``
        (for one x, or for each row of a batch)."""
        v_ref = self.s * x[..., 6 * i : 6 * i + 3]
        omega = self.turn[i] * x[..., 6 * i + 3 : 6 * i + 6]
        if x.ndim == 1:
            return omega, v_ref - cross(omega, self.body_ref[i])
        return omega, v_ref - cross(omega, self.body_ref[i])


def assemble(model: Model) -> Assembly:
    body_names = tuple(b.name for b in model.moving_bodies)
    index = {name: i for i, name in enumerate(body_names)}
    n = len(body_names)
    m = 6 * n
    joints = model.joints
    # every joint at once: large mechanisms have thousands
    centre = np.array([j.centre for j in joints], dtype=float).reshape(-1, 3)
    side_a = np.array([index.get(j.between[0], -1) for j in joints], dtype=np.intp)
    side_b = np.array([index.get(j.between[1], -1) for j in joints], dtype=np.intp)

    count = np.zeros(n)
    body_ref = np.zeros((n, 3))
    for side in (side_a, side_b):
        on = side >= 0
        np.add.at(count, side[on], 1.0)
        np.add.at(body_ref, side[on], centre[on])
    body_ref /= np.maximum(count, 1.0)[:, None]

    # Rigid joints add nothing to the metric, so they do not set its length scale:
    # splitting a body with a weld anywhere leaves every answer unchanged.
    has_play = np.array([any(c.kind == "ball" for c in j.cones) for j in joints], dtype=bool)
    spread_from = centre[has_play] if np.any(has_play) else centre
    spread = float(np.max(np.linalg.norm(spread_from - spread_from.mean(axis=0), axis=1)))
    radii = [c.radius for j in joints for c in j.cones if c.kind == "ball"]
    s = max(radii, default=0.0)
    size = np.array([j.size if play else 0.0 for j, play in zip(joints, has_play, strict=True)])
    sizes = size[has_play].tolist()
    if s == 0.0:  # every joint is tight: any length of the model will do
        s = max([spread, *sizes, 1.0])
    ell = max([spread, *sizes, s])
    # each body's own lever: its farthest joint centre, or its largest joint
    lever = np.full(n, s)
    for side in (side_a, side_b):
        on = side >= 0
        far = np.linalg.norm(centre[on] - body_ref[side[on]], axis=1)
        np.maximum.at(lever, side[on], np.maximum(far, size[on]))
    turn = s / lever

    G_list = _joint_maps(joints, side_a, side_b, centre, body_ref, s, turn, m)
    # each deviated joint's torsor at its mean (its own deviation, or its share of a group's)
    deviated: dict[int, FloatArray] = {}
    for source in model.deviation_sources():
        for jdx in source.joints:
            mean = source.torsor_at(jdx, joints[jdx]) @ source.deviation.mean()
            deviated[jdx] = deviated.get(jdx, np.zeros(6)) + mean
    blocks_of = _contact_blocks(joints, G_list, s)
    contacts: list[ContactRows] = []
    for jdx, (joint, G) in enumerate(zip(joints, G_list, strict=True)):
        cones = joint.cones
        if not cones:
            continue
        blocks = blocks_of[jdx]
        spring = joint.stiffness or 0.0
        # a deviation moves each play's centre, and a face's limit along its normal
        delta = deviated.get(jdx, np.zeros(6))
        at = 0
        for cdx, contact in enumerate(cones):
            k = contact.rows.shape[0]
            offset = None if contact.offset is None else (contact.offset / s) @ G.block
            moved = jdx in deviated and contact.kind == "ball"
            radius = contact.radius
            if moved and contact.offset is not None:
                radius += float(contact.offset @ delta)
            contacts.append(
                ContactRows(
                    jdx,
                    cdx,
                    contact,
                    G.cols,
                    blocks[at : at + k],
                    radius / s,
                    m,
                    0.0
                    if contact.kind == "fixed"
                    else spring
                    if contact.stiffness is None
                    else contact.stiffness,
                    offset,
                    centre=(contact.rows @ delta) / s if moved else None,
                )
            )
            at += k

    g = load_work(model.loads_of(None), index, body_ref, s, turn)
    return Assembly(model, body_names, body_ref, s, ell, tuple(G_list), tuple(contacts), g, turn)


def load_work(
    loads: Sequence[Load],
    index: dict[str, int],
    body_ref: FloatArray,
    s: float,
    turn: FloatArray,
) -> FloatArray:
    """The loads' work per unit of scaled unknowns (N*mm): ``g`` with V = -g @ x."""
    g = np.zeros(6 * len(body_ref))
    for load in loads:
        i = index[load.body]
        force = np.zeros(3) if load.force is None else np.array(load.force)
        moment = np.zeros(3) if load.torque is None else np.array(load.torque)
        if load.at is not None:
            moment += cross(np.array(load.at) - body_ref[i], force)
        g[6 * i : 6 * i + 3] += s * force
        g[6 * i + 3 : 6 * i + 6] += turn[i] * moment
    return g


def _contact_blocks(
    joints: Sequence[Joint], G_list: Sequence[JointMap], s: float
) -> dict[int, FloatArray]:
    """Each joint's contact rows on its bodies' columns, ``(rows / s) @ G.block``
    (joint index -> (its cones' rows, columns)), for joints of the same shape
    at once: a large mechanism has thousands (a stack of equal shapes gives
    each product exactly as one at a time does)."""
    with_cones = [jdx for jdx, joint in enumerate(joints) if joint.cones]
    if not with_cones:
        return {}
    cones = [c.rows for jdx in with_cones for c in joints[jdx].cones]
    rows = np.concatenate(cones) / s
    per_joint = np.array([len(joints[jdx].cones) for jdx in with_cones], dtype=np.intp)
    k_cone = np.array([r.shape[0] for r in cones], dtype=np.intp)
    k = np.add.reduceat(k_cone, np.cumsum(per_joint) - per_joint)
    first = np.cumsum(k) - k
    same_shape: dict[tuple[int, int], list[int]] = {}  # (rows, columns) -> places in with_cones
    for i, (jdx, k_j) in enumerate(zip(with_cones, k.tolist(), strict=True)):
        same_shape.setdefault((k_j, len(G_list[jdx].cols)), []).append(i)
    out: dict[int, FloatArray] = {}
    for (k_j, _), which in same_shape.items():
        taken = [with_cones[i] for i in which]
        products = rows[first[which][:, None] + np.arange(k_j)] @ np.stack(
            [G_list[jdx].block for jdx in taken]
        )
        out.update(zip(taken, products, strict=True))
    return out


def _joint_maps(
    joints: Sequence[Joint],
    side_a: IntArray,
    side_b: IntArray,
    centre: FloatArray,
    body_ref: FloatArray,
    s: float,
    turn: FloatArray,
    m: int,
) -> list[JointMap]:
    """Each joint's map from scaled unknowns to the relative torsor of b
    w.r.t. a at the joint (``side_a``/``side_b``: body indices, -1 ground)."""
    if not joints:
        return []
    R_joint_world = np.array([j.R_world_joint.T for j in joints])  # (J, 3, 3)
    part: list[FloatArray] = []
    for sign, side in ((-1.0, side_a), (1.0, side_b)):
        on = side >= 0
        i = np.where(on, side, 0)
        lever = centre - body_ref[i]
        lever_cross = np.zeros((len(joints), 3, 3))
        lever_cross[:, 0, 1], lever_cross[:, 0, 2] = -lever[:, 2], lever[:, 1]
        lever_cross[:, 1, 0], lever_cross[:, 1, 2] = lever[:, 2], -lever[:, 0]
        lever_cross[:, 2, 0], lever_cross[:, 2, 1] = -lever[:, 1], lever[:, 0]
        t = turn[i][:, None, None]
        block = np.zeros((len(joints), 6, 6))
        block[:, :3, :3] = s * R_joint_world
        block[:, :3, 3:] = -t * (R_joint_world @ lever_cross)
        block[:, 3:, 3:] = t * R_joint_world
        part.append(sign * block)
    both = np.concatenate(part, axis=2)  # (J, 6, 12): a's columns, then b's
    cols_a = 6 * side_a[:, None] + np.arange(6)
    cols_b = 6 * side_b[:, None] + np.arange(6)
    cols = np.concatenate([cols_a, cols_b], axis=1)
    out: list[JointMap] = []
    for jdx in range(len(joints)):
        if side_a[jdx] < 0:  # ground side: b's columns only
            out.append(JointMap(cols_b[jdx], both[jdx, :, 6:], m))
        elif side_b[jdx] < 0:
            out.append(JointMap(cols_a[jdx], both[jdx, :, :6], m))
        else:
            out.append(JointMap(cols[jdx], both[jdx], m))
    return out
