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
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from jointplay.geometry import FloatArray, cross, skew
from jointplay.model.joints import Contact
from jointplay.model.joints.base import cones_of, frames_of
from jointplay.model.mechanism import Load, Model
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix

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


#: Columns of a joint's map: the 6 unknowns of each of its two bodies (6 for
#: a joint to the ground). ``JointRows`` pads every joint's to this many.
JOINT_COLUMNS = 12
_EACH_COLUMN = np.arange(JOINT_COLUMNS)


@dataclass(frozen=True)
class JointRows:
    """``Assembly.G`` and ``Assembly.contacts`` as arrays, which ``assemble``
    makes with them: the matrices are built from these with no Python step
    per joint or contact (a large mechanism has tens of thousands).

    Joint j's columns are ``cols[j, :width[j]]`` (``G.cols``); its map's
    rows, and its contacts' rows, have their entries on those columns in
    that order, padded with 0 to ``JOINT_COLUMNS``. A contact's columns are
    its joint's.
    """

    width: IntArray  # (J,) columns of each joint's map: 6 to the ground, else 12
    cols: IntArray  # (J, 12) ``G.cols``
    maps: FloatArray  # (J, 6, 12) ``G.block``
    frames: FloatArray  # (J, 3, 3) each joint's ``R_world_joint``
    between: IntArray  # (J, 2) moving-body index of a and b, -1 for the ground
    joint_of: IntArray  # (nc,) each contact's joint
    k: IntArray  # (nc,) each contact's rows
    rows: FloatArray  # (sum k, 6) the contacts' ``Contact.rows``, stacked
    blocks: FloatArray  # (sum k, 12) their ``ContactRows.block``, stacked
    faces: FloatArray  # (nc, 12) each contact's ``offset_block`` (0 without)
    has_face: NDArray[np.bool_]  # (nc,) the contact has an ``offset_block``
    #: (nc,) not ``ContactRows.is_fixed`` (a study's radii leave it: ``with_radii``)
    is_ball: NDArray[np.bool_]

    @staticmethod
    def of(asm: Assembly) -> JointRows:
        """The arrays of an assembly made without them, from its objects."""
        n_joints = len(asm.G)
        width = np.array([len(G.cols) for G in asm.G], dtype=np.intp).reshape(n_joints)
        cols = np.zeros((n_joints, JOINT_COLUMNS), dtype=np.intp)
        maps = np.zeros((n_joints, 6, JOINT_COLUMNS))
        for j, G in enumerate(asm.G):
            cols[j, : len(G.cols)] = G.cols
            maps[j, :, : len(G.cols)] = G.block
        contacts = asm.contacts
        k = np.array([c.k for c in contacts], dtype=np.intp).reshape(len(contacts))
        blocks = np.zeros((int(k.sum()), JOINT_COLUMNS))
        faces = np.zeros((len(contacts), JOINT_COLUMNS))
        at = 0
        for i, c in enumerate(contacts):
            blocks[at : at + c.k, : len(c.cols)] = c.block
            if c.offset_block is not None:
                faces[i, : len(c.cols)] = c.offset_block
            at += c.k
        joints = asm.model.joints
        return JointRows(
            width,
            cols,
            maps,
            frames_of(joints),
            np.array(
                [[asm.body_index.get(name, -1) for name in j.between] for j in joints],
                dtype=np.intp,
            ).reshape(-1, 2),
            np.array([c.joint_index for c in contacts], dtype=np.intp).reshape(len(contacts)),
            k,
            np.concatenate([np.zeros((0, 6)), *(c.contact.rows for c in contacts)]),
            blocks,
            faces,
            np.array([c.offset_block is not None for c in contacts], dtype=bool),
            np.array([not c.is_fixed for c in contacts], dtype=bool),
        )

    @cached_property
    def _ascending(self) -> tuple[IntArray, IntArray, NDArray[np.bool_]]:
        """Each joint's columns from the smallest, as a sparse matrix keeps its
        entries: (J, 12) their order and (J, 12) the columns so (padding last),
        and (J,) where that order is not the joint's own (a joint whose b
        comes before its a among the unknowns)."""
        padding = self.width[:, None] <= _EACH_COLUMN
        key = np.where(padding, np.iinfo(np.intp).max, self.cols)
        order = np.argsort(key, axis=1, kind="stable").astype(np.intp)
        reordered = np.any(order != _EACH_COLUMN, axis=1)
        return order, np.take_along_axis(self.cols, order, axis=1), reordered

    def matrix(
        self,
        vals: FloatArray,
        joint: IntArray,
        m: int,
        sparse: bool,
        has: NDArray[np.bool_] | None = None,
    ) -> Matrix:
        """Rows on their joints' columns as one matrix: row i holds ``vals[i]``
        (padded like ``maps``) on the columns of joint ``joint[i]``, or
        nothing where ``has`` is False. Dense, or CSR with each row's columns
        ascending, as SciPy keeps entries given one by one (none repeats)."""
        if not len(joint) or (has is not None and not has.any()):  # no entries
            return sp.csr_matrix((len(joint), m)) if sparse else np.zeros((len(joint), m))
        width = self.width[joint] if has is None else self.width[joint] * has
        keep = width[:, None] > _EACH_COLUMN
        if not sparse:
            out = np.zeros((len(joint), m))
            out[keep.nonzero()[0], self.cols[joint][keep]] += vals[keep]  # to 0, as entries add
            return out
        order, ascending, reordered = self._ascending
        turned = reordered[joint].nonzero()[0]
        if len(turned):
            vals = vals.copy()
            vals[turned] = np.take_along_axis(vals[turned], order[joint[turned]], axis=1)
        indptr = np.zeros(len(joint) + 1, dtype=np.intp)
        width.cumsum(out=indptr[1:])
        return sp.csr_matrix((vals[keep], ascending[joint][keep], indptr), shape=(len(joint), m))

    @cached_property
    def row_joint(self) -> IntArray:
        """(sum k,) the joint of each of the contacts' rows."""
        return self.joint_of.repeat(self.k)


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
        A = _rows_matrix([(c.cols, c.block) for c in balls], m, sparse)
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
        return BallStack.around(balls, k, A, B)

    @staticmethod
    def around(balls: Sequence[ContactRows], k: IntArray, A: Matrix, B: Matrix) -> BallStack:
        """The stack of ``balls`` (``k`` rows each) whose rows ``A`` and face
        rows ``B`` are made: their radii, springs and centres."""
        start = np.concatenate([[0], np.cumsum(k)[:-1]]).astype(np.intp) if len(k) else k
        r = np.array([c.radius for c in balls], dtype=float)
        spring = np.array([c.stiffness for c in balls], dtype=float)
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

    def surface_work(self, u: FloatArray) -> Matrix:
        """(n, m): ``A_i^T u_i + B_i``, the work of a unit force of each cone
        on its surface along ``u_i`` (stacked like the rows of A; every cone
        has rows): the rows of its contact law's Jacobian."""
        if linalg.is_sparse(self.A):
            return sp.csr_matrix(self.segment_matrix.T @ sp.diags(u) @ self.A + self.B)
        return np.add.reduceat(self.A * u[:, None], self.start, axis=0) + self.B

    def surface_forces(self, v: FloatArray, rho: FloatArray, lam: FloatArray) -> FloatArray:
        """``f_i = lam_i A_i x / |A_i x|`` (0 where ``A_i x = 0``): the force vectors
        of contacts on their cone's surface."""
        safe = np.where(rho > 0.0, rho, 1.0)
        return v * np.repeat(lam / safe, self.k, axis=-1)

    def largest_play(self) -> float:
        """The largest radius (scaled; 1 where every play is 0, springs at no
        play): the length the certificate's feasibility is relative to."""
        largest = float(np.max(self.r)) if len(self.r) else 0.0
        return largest if largest > 0 else 1.0

    def gap_used(
        self, level: FloatArray, reach: float, radii: FloatArray | None = None
    ) -> FloatArray:
        """Fraction of each cone's play used at ``level = |A_i x| + B_i x``, in
        [0, 1] (a limit with no play, or one a deviation moved in past its
        play, counts as used once it is reached to ``reach``, the
        certificate's feasibility as a length); ``radii``: other radii than
        the stack's (a row each, like ``level``)."""
        radii = self.r if radii is None else radii
        r = np.where(radii > 0, radii, 1.0)
        reached = level >= np.minimum(radii, 0.0) - reach
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


def _wrench_map(rows: FloatArray, k: IntArray, sparse: bool) -> Matrix:
    """Block-diagonal ``-rows.T`` of contacts of ``k`` rows each (their rows
    stacked): their duals stacked -> their wrenches."""
    n_rows = rows.shape[0]
    owner = np.repeat(np.arange(len(k)), k)
    i = (6 * owner[:, None] + np.arange(6)).ravel()
    shape = (6 * len(k), n_rows)
    if sparse:  # column by column (a row's 6 entries each), then turned: nothing to sort
        by_column = sp.csc_matrix((-rows.ravel(), i, np.arange(0, 6 * n_rows + 1, 6)), shape)
        return by_column.tocsr()
    return _matrix(-rows.ravel(), i, np.repeat(np.arange(n_rows), 6), shape, sparse)


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
    #: ``G`` and ``contacts`` as arrays, made with them (``with_radii`` keeps
    #: them: they hold no radius); None: worked out from them when first needed.
    joint_rows: JointRows | None = field(default=None, repr=False, compare=False)

    @property
    def m(self) -> int:
        return 6 * len(self.body_names)

    @property
    def sparse(self) -> bool:
        """Whether the matrices are sparse (a large mechanism; see ``linalg``)."""
        return self.m > linalg.SPARSE_FROM

    @cached_property
    def _joint_rows(self) -> JointRows:
        """``joint_rows``, or for an assembly made without them, their like."""
        return self.joint_rows if self.joint_rows is not None else JointRows.of(self)

    @cached_property
    def is_ball(self) -> NDArray[np.bool_]:
        """(contacts,) whether each contact is a clearance cone (else fixed rows)."""
        return self._joint_rows.is_ball

    @cached_property
    def balls(self) -> tuple[ContactRows, ...]:
        contacts = self.contacts
        return tuple([contacts[i] for i in self.is_ball.nonzero()[0].tolist()])

    @cached_property
    def fixed(self) -> tuple[ContactRows, ...]:
        contacts = self.contacts
        return tuple([contacts[i] for i in (~self.is_ball).nonzero()[0].tolist()])

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
        maps = self._joint_rows
        widths = np.unique(maps.width).tolist()  # joints to ground, between bodies
        groups = [np.flatnonzero(maps.width == width) for width in widths]
        total = sum(len(same) * width**2 for width, same in zip(widths, groups, strict=True))
        if not total:
            return sp.csr_matrix((self.m, self.m))
        # each joint's entries, (width, width) of them, in place at once; SciPy's own
        # index type, so that it takes them as they are
        small = max(total, self.m) <= np.iinfo(np.int32).max
        rows = np.empty(total, dtype=np.int32 if small else np.intp)
        cols = np.empty(total, dtype=rows.dtype)
        vals = np.empty(total)
        at = 0
        for width, same in zip(widths, groups, strict=True):
            blocks = np.ascontiguousarray(maps.maps[same][:, :, :width])  # (J, 6, width)
            joint_cols = maps.cols[same][:, :width]  # (J, width)
            products = blocks.transpose(0, 2, 1) @ (w2[:, None] * blocks)  # (J, width, width)
            end = at + products.size
            rows[at:end].reshape(products.shape)[...] = joint_cols[:, :, None]
            cols[at:end].reshape(products.shape)[...] = joint_cols[:, None, :]
            vals[at:end] = products.ravel()
            at = end
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
        rows = self._joint_rows
        joints = self.model.joints
        nj = len(self.G)
        each_row = np.arange(nj).repeat(6)
        tau_map = rows.matrix(rows.maps.reshape(-1, JOINT_COLUMNS), each_row, self.m, self.sparse)
        is_ball = self.is_ball
        on_ball = is_ball.repeat(rows.k)
        cones = [c.contact for c in self.contacts]
        normals = [cones[i].offset for i in is_ball.nonzero()[0].tolist()]
        offsets = np.zeros((len(normals), 6))  # 0 for a plain ball
        faced = [i for i, normal in enumerate(normals) if normal is not None]
        if faced:
            offsets[faced] = np.array([normals[i] for i in faced])
        joint_of = rows.joint_of
        by_joint = np.argsort(joint_of, kind="stable").astype(np.intp)
        return ContactTables(
            tau_map,
            _wrench_map(rows.rows[on_ball], rows.k[is_ball], self.sparse),
            offsets,
            _wrench_map(rows.rows[~on_ball], rows.k[~is_ball], self.sparse),
            is_ball,
            joint_of,
            np.concatenate([np.zeros(0), *(c.point for c in cones)]).reshape(-1, 3),
            np.array([n for n, c in enumerate(cones) if c.lever is not None], dtype=np.intp),
            np.array([jt.at for jt in joints], dtype=float).reshape(-1, 3),
            rows.frames,
            tuple([c.name for c in cones]),
            np.array([c.turn_lever for c in cones], dtype=float),  # None: nan
            tuple([jt.name for jt in joints]),
            tuple([jt.type_name for jt in joints]),
            tuple([jt.between for jt in joints]),
            rows.between,
            by_joint,
            np.searchsorted(joint_of[by_joint], np.arange(len(joints) + 1)).astype(np.intp),
        )

    @cached_property
    def stack(self) -> BallStack:
        """All clearance cones stacked into dense arrays (see ``BallStack``)."""
        rows = self._joint_rows
        is_ball = self.is_ball
        on_ball = is_ball.repeat(rows.k)
        A = rows.matrix(rows.blocks[on_ball], rows.row_joint[on_ball], self.m, self.sparse)
        faces = rows.faces[is_ball]
        B = rows.matrix(faces, rows.joint_of[is_ball], self.m, self.sparse, rows.has_face[is_ball])
        return BallStack.around(self.balls, rows.k[is_ball], A, B)

    @cached_property
    def E_length(self) -> FloatArray:
        """(rows of E,) the factor that turns each rigid row's residual into
        mm across the mechanism: 1 for a point's displacement (mm); for a
        row of a turn alone, ``ell`` over the row's own lever (a weld's turn
        row is the angle: ``ell``; a tight drive's is the angle times its
        lever rho: ``ell / rho``). A turn w opens a weld by about w * ell."""
        if self.is_ball.all():  # no fixed rows
            return np.zeros(0)
        rows = self._joint_rows.rows[(~self.is_ball).repeat(self._joint_rows.k)]
        lever = np.linalg.norm(rows[:, 3:], axis=1)
        turn = ~np.any(rows[:, :3] != 0.0, axis=1) & (lever > 0.0)
        return np.where(turn, self.ell / np.where(turn, lever, 1.0), 1.0)

    @cached_property
    def E(self) -> Matrix:
        """Equality rows (rigid joints and zero-clearance contacts)."""
        rows = self._joint_rows
        if self.is_ball.all():  # no fixed rows
            return rows.matrix(rows.blocks[:0], rows.joint_of[:0], self.m, self.sparse)
        on_fixed = (~self.is_ball).repeat(rows.k)
        return rows.matrix(rows.blocks[on_fixed], rows.row_joint[on_fixed], self.m, self.sparse)

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
    centre = np.array([j.at for j in joints], dtype=float).reshape(-1, 3)
    between = np.array(
        [[index.get(a, -1), index.get(b, -1)] for a, b in (j.between for j in joints)],
        dtype=np.intp,
    ).reshape(-1, 2)
    cones = cones_of(joints)  # a joint type's together
    every = [c for joint_cones in cones for c in joint_cones]
    joint_of = np.arange(len(joints)).repeat([len(c) for c in cones])

    # both sides of every joint: a's, then b's
    sides, at_sides = between.T.ravel(), np.concatenate([centre, centre])
    on = sides >= 0
    count = np.zeros(n)
    body_ref = np.zeros((n, 3))
    np.add.at(count, sides[on], 1.0)
    np.add.at(body_ref, sides[on], at_sides[on])
    body_ref /= np.maximum(count, 1.0)[:, None]

    # Rigid joints add nothing to the metric, so they do not set its length scale:
    # splitting a body with a weld anywhere leaves every answer unchanged.
    is_play = np.array([c.kind == "ball" for c in every], dtype=bool)
    has_play = np.zeros(len(joints), dtype=bool)
    has_play[joint_of[is_play]] = True
    spread_from = centre[has_play] if has_play.any() else centre
    # the norms as np.linalg.norm and the mean as .mean() make them, without their calls' cost
    off = spread_from - spread_from.sum(axis=0) / len(spread_from)
    spread = float(np.sqrt((off * off).sum(axis=1)).max())
    radius = np.array([c.radius for c in every], dtype=float)
    s = max(radius[is_play].tolist(), default=0.0)
    size = np.array([j.size if p else 0.0 for j, p in zip(joints, has_play.tolist(), strict=True)])
    sizes = size[has_play].tolist()
    if s == 0.0:  # every joint is tight: any length of the model will do
        s = max([spread, *sizes, 1.0])
    ell = max([spread, *sizes, s])
    # each body's own lever: its farthest joint centre, or its largest joint
    lever = np.full(n, s)
    off = at_sides[on] - body_ref[sides[on]]
    far = np.sqrt((off * off).sum(axis=1))
    np.maximum.at(lever, sides[on], np.maximum(far, np.concatenate([size, size])[on]))
    turn = s / lever

    frames = frames_of(joints)
    width, cols, maps = _joint_maps(frames, between, centre, body_ref, s, turn)
    G_list = tuple(
        [  # list(): NumPy makes the views at once
            JointMap(c, b, m) if w == JOINT_COLUMNS else JointMap(c[:w], b[:, :w], m)
            for c, b, w in zip(list(cols), list(maps), width.tolist(), strict=True)
        ]
    )
    # each deviated joint's torsor at its mean (its own deviation, or its share of a group's)
    deviated: dict[int, FloatArray] = {}
    for source in model.deviation_sources():
        for jdx in source.joints:
            mean = source.torsor_at(jdx, joints[jdx]) @ source.deviation.mean()
            deviated[jdx] = deviated.get(jdx, np.zeros(6)) + mean
    k = np.array([c.rows.shape[0] for c in every], dtype=np.intp).reshape(len(every))
    rows = np.concatenate([np.zeros((0, 6)), *(c.rows for c in every)])
    blocks_of, blocks = _contact_blocks(rows / s, k, joint_of, width, maps)
    faces = np.zeros((len(every), JOINT_COLUMNS))
    has_face = np.zeros(len(every), dtype=bool)
    scaled, k_list = (radius / s).tolist(), k.tolist()
    contacts: list[ContactRows] = []
    for jdx, joint_cones in enumerate(cones):
        if not joint_cones:
            continue
        G, joint_blocks = G_list[jdx], blocks_of[jdx]
        spring = joints[jdx].stiffness or 0.0
        # a deviation moves each play's centre, and a face's limit along its normal
        delta = deviated.get(jdx)
        at = 0
        for cdx, contact in enumerate(joint_cones):
            i = len(contacts)
            offset = None
            if contact.offset is not None:
                offset = (contact.offset / s) @ G.block
                faces[i, : len(G.cols)], has_face[i] = offset, True
            r, moved = scaled[i], None
            if delta is not None and contact.kind == "ball":
                play = contact.radius
                if contact.offset is not None:
                    play += float(contact.offset @ delta)
                r, moved = play / s, (contact.rows @ delta) / s
            contacts.append(
                ContactRows(
                    jdx,
                    cdx,
                    contact,
                    G.cols,
                    joint_blocks[at : at + k_list[i]],
                    r,
                    m,
                    0.0
                    if contact.kind == "fixed"
                    else spring
                    if contact.stiffness is None
                    else contact.stiffness,
                    offset,
                    True,
                    moved,
                )
            )
            at += k_list[i]

    g = load_work(model.loads_of(None), index, body_ref, s, turn)
    is_ball = np.array([not c.is_fixed for c in contacts], dtype=bool)
    arrays = JointRows(
        width,
        cols,
        maps,
        frames,
        between,
        joint_of,
        k,
        rows,
        blocks,
        faces,
        has_face,
        is_ball,
    )
    return Assembly(model, body_names, body_ref, s, ell, G_list, tuple(contacts), g, turn, arrays)


def load_work(
    loads: Sequence[Load],
    index: dict[str, int],
    body_ref: FloatArray,
    s: float,
    turn: FloatArray,
) -> FloatArray:
    """The loads' work per unit of scaled unknowns (N*mm): ``g`` with V = -g @ x."""
    g = np.zeros(6 * len(body_ref))
    if not loads:
        return g
    # every load at once (a large mechanism has one on each of thousands of bodies)
    on = np.array([index[load.body] for load in loads], dtype=np.intp)
    none = (0.0, 0.0, 0.0)
    wrench = np.array(
        [(*(ld.force or none), *(ld.torque or none), *(ld.at or none)) for ld in loads],
        dtype=float,
    )
    # a force's moment about its body's reference point (0 for a load with no
    # point: adding it leaves every entry of g as it was)
    lever = wrench[:, 6:] - body_ref[on]
    lever[[ld.at is None for ld in loads]] = 0.0
    wrench[:, 3:6] += cross(lever, wrench[:, :3])
    wrench[:, :3] *= s
    wrench[:, 3:6] *= turn[on, None]
    np.add.at(g.reshape(-1, 6), on, wrench[:, :6])  # in the loads' order, as one after another
    return g


def _contact_blocks(
    rows: FloatArray, k: IntArray, joint_of: IntArray, width: IntArray, maps: FloatArray
) -> tuple[list[FloatArray], FloatArray]:
    """Each joint's contact rows on its bodies' columns, ``(rows / s) @ G.block``
    for all its cones (``rows`` scaled, ``k`` each, their joints ``joint_of``;
    ``width`` and ``maps`` as in ``JointRows``), made for joints of the same
    shape at once (a stack of equal shapes gives each product exactly as one
    at a time does): a list by joint (empty for a joint with no cones), and
    all of them stacked like ``JointRows.blocks``."""
    n_joints = len(width)
    per_joint = np.bincount(joint_of, weights=k, minlength=n_joints).astype(np.intp)
    first = per_joint.cumsum() - per_joint
    with_cones = np.bincount(joint_of, minlength=n_joints) > 0
    by_joint: list[FloatArray] = [np.zeros((0, 0))] * n_joints
    stacked = np.zeros((len(rows), JOINT_COLUMNS))
    shape = per_joint * (JOINT_COLUMNS + 1) + width  # a joint's rows and columns
    for code in sorted(set(shape[with_cones].tolist())):
        which = ((shape == code) & with_cones).nonzero()[0]
        k_j, w = divmod(code, JOINT_COLUMNS + 1)
        at = first[which][:, None] + np.arange(k_j)
        products = rows[at] @ np.ascontiguousarray(maps[which][:, :, :w])
        stacked[at, :w] = products
        for jdx, product in zip(which.tolist(), list(products), strict=True):
            by_joint[jdx] = product
    return by_joint, stacked


#: [l]x = ((0, -l_z, l_y), (l_z, 0, -l_x), (-l_y, l_x, 0)): where its entries
#: go, row after row, which coordinate of l, and its sign
_CROSS_PLACE = np.array([1, 2, 3, 5, 6, 7])
_CROSS_COORDINATE = np.array([2, 1, 2, 0, 1, 0])
_CROSS_SIGN = np.array([-1.0, 1.0, 1.0, -1.0, -1.0, 1.0])


def _joint_maps(
    R_world_joint: FloatArray,
    between: IntArray,
    centre: FloatArray,
    body_ref: FloatArray,
    s: float,
    turn: FloatArray,
) -> tuple[IntArray, IntArray, FloatArray]:
    """Each joint's map from scaled unknowns to the relative torsor of b
    w.r.t. a at the joint (``between``: (J, 2) body indices of a and b, -1
    the ground), as ``JointRows`` keeps them: ``(width, cols, maps)``, b's
    columns only for a joint whose a side is the ground, a's only for one
    whose b is."""
    n_joints = len(between)
    R_joint_world = np.ascontiguousarray(R_world_joint.transpose(0, 2, 1))  # (J, 3, 3)
    sides = between.T  # (2, J): a's side, then b's
    i = np.where(sides >= 0, sides, 0)
    lever = (centre - body_ref[i]).reshape(-1, 3)
    lever_cross = np.zeros((2 * n_joints, 9))  # [lever]x, row after row
    lever_cross[:, _CROSS_PLACE] = lever[:, _CROSS_COORDINATE] * _CROSS_SIGN  # exactly +-l
    t = turn[i][..., None, None]
    block = np.zeros((2, n_joints, 6, 6))
    block[..., :3, :3] = s * R_joint_world
    block[..., :3, 3:] = -t * (R_joint_world @ lever_cross.reshape(2, n_joints, 3, 3))
    block[..., 3:, 3:] = t * R_joint_world
    block *= np.array([-1.0, 1.0])[:, None, None, None]  # a's side moves b back
    cols = 6 * sides[..., None] + np.arange(6)  # (2, J, 6)
    # a's columns, then b's; b's alone (first) for a joint whose a is the ground, a's alone
    # for one whose b is
    a_ground, ground = sides[0] < 0, np.any(sides < 0, axis=0)
    first = np.where(a_ground[:, None, None], block[1], block[0])
    then = np.where(ground[:, None, None], 0.0, block[1])
    maps = np.concatenate([first, then], axis=2)  # (J, 6, 12)
    first_cols = np.where(a_ground[:, None], cols[1], cols[0])
    cols = np.concatenate([first_cols, np.where(ground[:, None], 0, cols[1])], axis=1)
    width = np.where(ground, 6, JOINT_COLUMNS).astype(np.intp)
    return width, cols, maps
