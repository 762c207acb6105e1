"""The workspace: one model's cone program as plain data, made once.

It holds what every solve of the model shares: the assembled matrices, the
free motions ``N`` and the rows that pin them (``K``), the equalities, and
data derived from them on first use (the interior-point program, each active
set's face), the rows that limit motion (``limit_rows``) and what the
balance check needs (``Balance``). A solve reads it and changes nothing but
those caches. The algorithms are functions in the layers above, which take
it and import this module, never the reverse; the public ``Workspace``, with
``solve`` and ``solve_batch``, is this data with the top layer's entry
points on it (``solve.py``).
"""

from __future__ import annotations

import copy
from functools import cached_property
from typing import Self

import numpy as np
import scipy.sparse as sp

from jointplay.assembly import Assembly, IntArray, assemble
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model
from jointplay.numerics import free_motions, linalg
from jointplay.numerics.linalg import Matrix
from jointplay.result import describe_free_motions
from jointplay.settings import SolverSettings
from jointplay.solver.records import ConeProgram, Face, FaceKey


class WorkspaceData:
    """The solver's side of one model: assembled matrices and free motions.

    Built once from an ``Assembly``; the model is never modified. Every
    algorithm of the solver takes it; the public ``Workspace`` (``solve.py``)
    adds the solves.
    """

    def __init__(self, assembly: Assembly, settings: SolverSettings | None = None):
        self.asm = assembly
        self.settings = settings or SolverSettings()
        self.m = assembly.m
        self.balls = assembly.balls
        self.stack = stack = assembly.stack
        #: each contact's own play, what the certificate weighs its slack
        #: against (``exact`` linearizes the cones, their offsets in the radii)
        self.plays = stack.r
        self.E = assembly.E
        self.sparse = assembly.sparse
        #: the free motions (dense, or sparse for a large mechanism)
        with linalg.one_blas_thread():
            rcond = self.settings.free_motion_rcond
            self.N = linalg.null_space(limit_rows(self), self.m, rcond, self.settings.round_off)
        #: rows that hold the answer orthogonal to N in the least-norm metric
        if not self.sparse:
            self.K = assembly.metric_times(self.N).T
        elif self.N.shape[1]:
            self.K = sp.csr_matrix((assembly.metric_matrix @ self.N).T)
        else:  # none: the metric (0.2 s at 10,000 joints) waits for a tie, if any
            self.K = sp.csr_matrix((0, self.m))
        self.Eq = linalg.vstack([self.E, self.K], self.m)
        self.max_radius = stack.largest_play()
        self.balance = Balance(self)
        #: each active set's face, built when first met (``faces.face_of``)
        self.faces: dict[FaceKey, Face] = {}
        #: the cone program of the hard problem, built when first needed
        #: (``conic.interior_program``)
        self.interior_program: ConeProgram | None = None
        #: the cone program with penetrations, built when first needed
        self.compliant_program: ConeProgram | None = None
        #: the largest force of springs that deviations press at no load
        #: (``pipeline.load_scale``), found when first needed
        self.preload: float | None = None

    @classmethod
    def of(cls, model: Model, settings: SolverSettings | None = None) -> Self:
        return cls(assemble(model), settings)

    def with_settings(self, settings: SolverSettings) -> Self:
        """The same mechanism under other solver settings (the finer retry):
        what depends on the assembly and the free motions' threshold alone
        is shared: the free motions (a 10,000-shaft chain's cost 2 s), the
        balance's maps and the faces (their rows and whether they pin the
        position); the cone programs are made anew."""
        if settings.free_motion_rcond != self.settings.free_motion_rcond:
            return type(self)(self.asm, settings)
        other = copy.copy(self)
        other.settings = settings
        other.interior_program = None  # its Clarabel settings are the old ones
        other.compliant_program = None
        return other

    @cached_property
    def limit_scale(self) -> float:
        """The largest singular value of the rows that limit motion: the
        scale of the free motions' rank threshold (a large mechanism's face
        tests count against it, ``faces.pins_position``)."""
        return free_motions.largest_singular_value(limit_rows(self))

    def contacts_share(self, g_hat: FloatArray) -> tuple[FloatArray, float]:
        """The unit loads' work ``g_hat`` less what the rigid rows hold alone
        (least squares): an equal load on every position the rigid joints
        allow (``E x = 0``), carried by the contacts. Returned at unit size,
        with its size (``g_hat`` itself and 1 with no rigid rows: a
        degenerate optimum's route can turn on the last bit of the loads)."""
        if not self.E.shape[0]:
            return g_hat, 1.0
        nu = self.balance.rigid_multipliers(g_hat[None])[0]
        share = np.asarray(g_hat - linalg.adjoint(self.E, nu))
        size = float(np.linalg.norm(share))
        return (share / size if size > 0 else share), size

    @cached_property
    def _free_motion_words(self) -> tuple[str, ...]:
        return describe_free_motions(self.asm, self.N)

    def free_motions(self) -> tuple[str, ...]:
        """The free motions in words (computed once)."""
        return self._free_motion_words

    def with_radii(self, radii: FloatArray, centre: FloatArray | None = None) -> Self:
        """A workspace of the same mechanism with other plays: ``radii`` are
        the scaled cone radii (``Assembly.balls`` order) and ``centre`` the
        cones' centres (stacked like the rows of ``stack.A``); scales, free
        motions and unknowns stay those of this one, so answers compare row by row."""
        return type(self)(self.asm.with_radii(radii, centre), self.settings)

    def softness(self, g_norm: float | FloatArray) -> FloatArray:
        """Compliant contacts: the elastic energy k p^2 / 2 (p in mm) becomes
        ``p~^2 / (2 sigma)`` in the scaled problem whose loads have unit norm,
        with ``sigma = |g| / (k s^2)``: the answer depends on the load's size."""
        spring = self.stack.spring
        g_arr = np.asarray(g_norm, dtype=float)
        out = np.zeros((*g_arr.shape, len(spring)))
        mask = spring > 0
        out[..., mask] = g_arr[..., None] / (spring[mask] * self.asm.s**2)
        return out


def limit_rows(ws: WorkspaceData) -> Matrix:
    """Every row that limits a motion: the contacts' rows, the offsets of the
    faces that tilt, the rigid rows. What they leave free is ``ws.N``."""
    stack = ws.stack
    return linalg.vstack([stack.A, stack.B[np.flatnonzero(stack.has_offset)], ws.E], ws.m)


class Balance:
    """What the balance check needs of a mechanism, built once per workspace."""

    def __init__(self, ws: WorkspaceData):
        asm = ws.asm
        self.asm = asm
        self.stack = ws.stack  # the workspace's cones: exact rotations' are linearized
        self.E = ws.E
        self.settings = ws.settings
        n = len(asm.body_names)
        # per body: force rows as they are, moment rows to N*mm over ell (units of |g|/s)
        self.weight = np.column_stack(
            [np.ones((n, 3)), np.repeat((asm.s / (asm.turn * asm.ell))[:, None], 3, 1)]
        ).ravel()
        self.per_contact = np.r_[np.ones(3), np.full(3, 1.0 / asm.ell)]

    @cached_property
    def reaction_maps(self) -> tuple[linalg.Matrix, linalg.Matrix, linalg.Matrix]:
        """Each joint's reaction (6 per joint: force, moment over ell) from
        the force vectors ``f``, the forces ``lam`` and the rigid rows' ``nu``:
        the sum of its contacts' wrenches, one map each, built once."""
        T = self.asm.tables
        n_joints = int(T.centre.shape[0])
        ball_joint = T.joint_of[T.is_ball]
        fixed_joint = T.joint_of[~T.is_ball]
        w = np.tile(self.per_contact, n_joints)

        def gather(joint_of: IntArray) -> linalg.Matrix:  # contacts' 6-rows -> joints' 6-rows
            rows = (6 * joint_of[:, None] + np.arange(6)).ravel()
            cols = np.arange(6 * len(joint_of))
            if self.asm.sparse:
                return sp.csr_matrix(
                    (w[rows], (rows, cols)), shape=(6 * n_joints, 6 * len(joint_of))
                )
            out = np.zeros((6 * n_joints, 6 * len(joint_of)))
            out[rows, cols] = w[rows]
            return out

        n = len(ball_joint)
        offsets = T.offset_ball.ravel()
        rows, cols = np.arange(6 * n), np.repeat(np.arange(n), 6)
        if self.asm.sparse:
            offset_map: linalg.Matrix = sp.csr_matrix((-offsets, (rows, cols)), shape=(6 * n, n))
        else:
            offset_map = np.zeros((6 * n, n))
            offset_map[rows, cols] = -offsets
        to_ball, to_fixed = gather(ball_joint), gather(fixed_joint)
        return to_ball @ T.wrench_ball, to_ball @ offset_map, to_fixed @ T.wrench_fixed

    def rigid_multipliers(self, rest: FloatArray) -> FloatArray:
        """(B, rigid rows): what the rigid rows carry of the generalized
        forces ``rest``, by least squares (redundant rigid joints share)."""
        E = self.E
        if not E.shape[0]:
            return np.zeros((rest.shape[0], 0))
        if not linalg.is_sparse(E):
            return np.asarray(np.linalg.lstsq(np.asarray(E).T, rest.T, rcond=None)[0].T)
        st = self.settings
        return np.array(
            [linalg.lstsq(E.T, row, st.lstsq_rcond, st.kkt_refinements) for row in rest]
        )

    def largest_reaction(self, lam: FloatArray, f: FloatArray, nu: FloatArray) -> FloatArray:
        """(B,): the largest joint reaction, force or moment over ell."""
        B = lam.shape[0]
        if not self.asm.tables.centre.shape[0]:
            return np.zeros(B)
        of_f, of_lam, of_nu = self.reaction_maps
        joints = linalg.times(of_f, f) + linalg.times(of_lam, lam)
        if nu.shape[1]:
            joints = joints + linalg.times(of_nu, nu)
        joints = joints.reshape(B, -1, 3)
        return np.asarray(np.sqrt((joints * joints).sum(axis=-1).max(axis=1, initial=0.0)))

    def residual(
        self, g_hat: FloatArray, lam: FloatArray, f: FloatArray, nu: FloatArray | None
    ) -> tuple[FloatArray, FloatArray]:
        """(B,) worst per-body imbalance relative to the largest force in the
        balance, and the rigid multipliers used."""
        stack = self.stack
        rest = g_hat - stack.adjoint(f, lam) if len(stack.k) else g_hat.copy()
        if nu is None:
            nu = self.rigid_multipliers(rest)
        if nu.shape[1]:
            rest = rest - linalg.adjoint(self.E, nu)
        B = g_hat.shape[0]
        # the largest norms as roots of the largest squares (sqrt is monotone
        # and correctly rounded: the same numbers, fewer roots)
        body = (rest * self.weight).reshape(B, -1, 2, 3)
        applied = (g_hat * self.weight).reshape(B, -1, 2, 3)
        scale = np.maximum(
            np.sqrt((applied * applied).sum(axis=-1).max(axis=(1, 2), initial=0.0)),
            self.largest_reaction(lam, f, nu),
        )
        worst = np.sqrt((body * body).sum(axis=-1).max(axis=(1, 2), initial=0.0))
        # no load and no force: nothing to balance (a preload is balanced too)
        out = np.where(scale > 0, worst / np.where(scale > 0, scale, 1.0), 0.0)
        return np.asarray(out), np.asarray(nu)
