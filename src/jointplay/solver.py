"""Solve the clearance equilibrium: a second-order cone program, exactly.

Minimizing the loads' potential energy ``-g @ x`` under the clearance cones is
convex, so Clarabel's interior-point answer is the global optimum. Then:

1. *Free motions* that no joint limits form the lineality space ``N`` of the
   cones. If the loads work on any of them there is no equilibrium: we raise
   ``UnboundedMechanismError`` naming the body and the motion. Otherwise the
   answer is pinned to be orthogonal to ``N`` in the least-norm metric, so free
   unloaded motions come out as exactly 0.
2. *Polishing.* The interior-point answer is accurate to its tolerance only.
   From it we read the active contacts and solve the optimality (KKT)
   equations of that active set with Newton's method, to machine precision.
3. *Ties.* When the optimal positions form a face (a load that pushes
   squarely on a flat limit, for example), a second cone program picks the
   least-norm point of that face.
4. *Certificate.* Whatever the path, the answer is accepted only if it is
   feasible, its contact forces are non-negative, and they balance the loads.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import TYPE_CHECKING, Any

import clarabel
import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from . import certificate, conic, forces, linalg
from .assembly import Assembly, BallStack, IntArray, assemble
from .errors import SolverError, UnboundedMechanismError
from .geometry import FloatArray, describe_motion
from .linalg import Matrix
from .model import Load, Model
from .result import (
    EQUILIBRIUM_TOLERANCE,
    Certificate,
    Result,
    build_result,
    describe_free_motions,
)
from .settings import DEFAULT, TINY, SolverSettings

if TYPE_CHECKING:
    from .batch import BatchSolution


@dataclass
class _Point:
    """A candidate optimum in scaled unknowns, with its multipliers."""

    x: FloatArray
    lam: FloatArray  # per ball contact (scaled)
    f: FloatArray  # force vectors, stacked like the rows of BallStack.A (scaled)
    method: str = "interior-point"
    iterations: int = 0
    certificate: Certificate | None = None
    active: _FaceKey | None = None  # the active set that determines x, if any
    nu: FloatArray | None = None  # the rigid rows' multipliers (None: least squares)


#: An active set: (cones on their surface, cones whose rows all hold as equalities).
_FaceKey = tuple[tuple[int, ...], tuple[int, ...]]


@dataclass(frozen=True)
class _Face:
    """An active set, split by how its cones are held.

    ``surface``: cones on their curved surface, ``|A_i x| + B_i x = r_i``
    with ``A_i x != 0`` (their force is along ``A_i x``). ``linear``: cones
    whose rows all hold as equalities: one-sided limits (no rows) and faces
    resting flat at their apex (``A_i x = 0``, ``B_i x = r_i``; their force
    vector is free inside ``|f_i| <= lam_i``). The linear cones' rows ``L x = l``
    join the equalities; ``lam_rows`` are the rows of L that carry a cone's
    ``lam`` (and its compliance), ``f_rows`` the rows that carry its ``f``.
    """

    key: _FaceKey
    stack: BallStack  # the surface cones
    L: Matrix
    rhs: FloatArray
    lam_rows: IntArray
    f_rows: IntArray
    Eq: Matrix  # the workspace's equalities, then L
    e: FloatArray
    surface_rows: IntArray  # rows of the full stack's A (and f) of the surface cones
    linear_rows: IntArray  # ... and of the linear cones
    #: Whether the active cones and equalities determine x uniquely; None when
    #: that depends on x (a tilting face: see ``Workspace._determined``).
    #: Computed when first asked (a null space): most trial faces never are.
    _determine: Callable[[], bool | None] = field(repr=False, compare=False)

    @cached_property
    def determined(self) -> bool | None:
        return self._determine()


def solve(
    model: Model,
    settings: SolverSettings | None = None,
    *,
    case: str | None = None,
    exact: bool = False,
) -> Result:
    """Find the equilibrium of ``model`` (under load case ``case``, if given):
    positions, contacts, forces and certificate. ``exact``: with exact
    rotations, refined from the small-displacement answer (``jointplay.exact``)."""
    ws = Workspace(assemble(model), settings)
    return ws.solve(loads=None if case is None else model.loads_of(case), exact=exact)


def solve_cases(
    model: Model, settings: SolverSettings | None = None, *, exact: bool = False
) -> dict[str, Result]:
    """Every load case of ``model`` on one assembly: ``{case: Result}``."""
    ws = Workspace(assemble(model), settings)
    return {case: ws.solve(loads=model.loads_of(case), exact=exact) for case in model.case_names}


class Workspace:
    """The solver's side: assembled matrices, free motions and scratch data.

    Built once from an ``Assembly``; the model is never modified. ``solve``
    may be called again with other loads (``loads=``): each call after the
    first starts from the previous active set (see ``SolverSettings.warm_start``).
    """

    def __init__(self, assembly: Assembly, settings: SolverSettings | None = None):
        self.asm = assembly
        self.settings = settings or SolverSettings()
        self.m = assembly.m
        self.balls = assembly.balls
        self.stack = assembly.stack
        self.E = assembly.E
        self.sparse = assembly.sparse
        self.N = self._free_motions()  # dense, or sparse for a large mechanism
        self.K = (
            sp.csr_matrix((assembly.metric_matrix @ self.N).T)
            if self.sparse
            else assembly.metric_times(self.N).T
        )
        self.Eq = linalg.vstack([self.E, self.K], self.m)
        largest = float(np.max(self.stack.r)) if len(self.stack.r) else 0.0
        self._max_radius = largest if largest > 0 else 1.0  # all zero: springs at 0 play
        self.balance = certificate.Balance(self)
        self._phase1_data: _ConeProgram | None = None
        self._faces: dict[_FaceKey, _Face] = {}
        self._last: _Point | None = None
        self._free_words: tuple[str, ...] | None = None
        #: Per solve: softness of each contact (scaled penetration per unit of
        #: scaled force), 0 for a hard limit; see ``softness``.
        self.sigma = np.zeros(len(self.balls))
        self._compliant_data: _ConeProgram | None = None

    @classmethod
    def of(cls, model: Model, settings: SolverSettings | None = None) -> Workspace:
        return cls(assemble(model), settings)

    # -- free motions -------------------------------------------------------
    def _free_motions(self) -> Matrix:
        stack = self.stack
        C = linalg.vstack([stack.A, stack.B[np.flatnonzero(stack.has_offset)], self.E], self.m)
        return linalg.null_space(C, self.m, self.settings.free_motion_rcond)

    def _check_driven(self, g: FloatArray) -> None:
        if self.N.shape[1] == 0:
            return
        drive = self.N.T @ g
        if np.linalg.norm(drive) <= self.settings.drive_tolerance * np.linalg.norm(g):
            return
        raise _unbounded(self.asm, self.N @ drive)

    def _driven_motion(self, g: FloatArray, fallback: FloatArray) -> FloatArray:
        """A motion that the joints let go on for ever and the loads ``g``
        drive (a body lifting off its point contacts, say), in the simplest
        words found: a translation or a rotation of one body, or of all the
        moving bodies together, along a global axis; else the solver's own
        certificate of unboundedness (``fallback``)."""
        m, n = self.m, len(self.asm.body_names)
        stack = self.stack
        # each body alone (a translation, or a turn about its reference): unit
        # vectors, whose levels are the columns' norms per cone plus B
        S = stack.segment_matrix  # (rows, cones)
        if self.sparse:
            rho = sp.csr_matrix(S.T @ stack.A.multiply(stack.A)).sqrt()  # (cones, m)
        else:
            rho = np.sqrt(S.T @ stack.A**2)
        e_cols = _column_max(abs(self.E), m)
        tol = self.settings.feasibility_tolerance  # a unit motion that moves nothing
        best, best_work = fallback[:m], 0.0
        for sign in (1.0, -1.0):
            held = _column_max(rho + sign * stack.B, m) > tol
            works = sign * g
            free = ~held & (e_cols <= tol) & (works > best_work)
            if np.any(free):
                j = int(np.flatnonzero(free)[np.argmax(works[free])])
                best, best_work = sign * np.eye(1, m, j)[0], float(works[j])
        if n > 1:  # all together: a translation (a common turn has no obvious centre)
            for d in [*(np.tile(np.eye(6)[a], n) / np.sqrt(n) for a in range(3))]:
                for sd in (d, -d):
                    work = float(g @ sd)
                    if work <= best_work:
                        continue
                    _, _, level = stack.levels(sd)
                    if len(level) and float(np.max(level)) > tol:
                        continue
                    if self.E.shape[0] and float(np.max(np.abs(self.E @ sd))) > tol:
                        continue
                    best, best_work = sd, work
        return best

    def free_motions(self) -> tuple[str, ...]:
        """The free motions in words (computed once)."""
        if self._free_words is None:
            self._free_words = describe_free_motions(self.asm, self.N)
        return self._free_words

    # -- the solve ----------------------------------------------------------
    def solve(self, loads: Sequence[Load] | None = None, *, exact: bool = False) -> Result:
        """The equilibrium under the model's loads, or under ``loads`` instead
        (``exact``: with exact rotations, see ``jointplay.exact``)."""
        if exact:
            from .exact import solve_exact

            return solve_exact(self, loads)
        start = time.perf_counter()
        if loads is None:
            loads = self.asm.model.loads_of(None)
            g = self.asm.g
        else:
            loads = tuple(loads)
            g = self.asm.work_of(loads)
        self._check_driven(g)
        g_norm = float(np.linalg.norm(g))
        g_hat = g / g_norm if g_norm else g
        point = self._optimum(g_hat, self.softness(g_norm))
        assert point.certificate is not None
        to_newton = g_norm / self.asm.s  # scaled multipliers -> N
        nu = point.nu if point.nu is not None else self._rigid_multipliers(g_hat, point)
        rigid = nu * to_newton
        elapsed = time.perf_counter() - start
        result = build_result(
            self.asm,
            point.x,
            point.lam * to_newton,
            point.f * to_newton,
            rigid,
            point.certificate,
            elapsed,
            self.free_motions,
            loads,
            g,
        )
        # The certificate balances the forces in the solver's scaled unknowns;
        # per body and in newtons (Result.check) a badly scaled mechanism can
        # fall short. A number that fails its own check is not printed.
        if result.equilibrium_residual > EQUILIBRIUM_TOLERANCE:
            raise SolverError(
                "the solver's answer could not be certified: its contact forces balance the "
                f"loads on each body only to {result.equilibrium_residual:.3g} of the largest "
                f"force ({EQUILIBRIUM_TOLERANCE:g} is required). "
                + self._weak_hint()
                + " If not, please report this model."
            )
        return result

    def _split(self, g_hat: FloatArray, point: _Point) -> _Point:
        """The optimum with the least-squares split of its forces
        (``forces.least_squares_split``: forces from the positions, by the
        documented rule) and its rigid multipliers, if that split certifies;
        else the route's own forces."""
        st = self.settings
        apex = st.feasibility_tolerance * self._max_radius  # positions' round-off
        nu = self._rigid_multipliers(g_hat, point)
        split = forces.least_squares_split(
            self.asm, point.x, point.lam, point.f, nu, g_hat, apex, st
        )
        if split is not None:
            trial = replace(point, lam=split.lam, f=split.f, nu=split.nu, certificate=None)
            cert = self._certify(g_hat, trial, split.nu)
            if cert.certified:
                trial.certificate = cert
                return trial
        return replace(point, nu=nu)

    def _rigid_multipliers(self, g_hat: FloatArray, point: _Point) -> FloatArray:
        """Forces in the rigid rows (scaled): what the contacts leave of the loads.

        Statically indeterminate rigid joints share the load in the least-squares way.
        """
        rest = g_hat - self.stack.adjoint(point.f, point.lam)
        return np.asarray(self.balance.rigid_multipliers(rest[None])[0])

    def solve_batch(self, work: FloatArray, radii: FloatArray | None = None) -> BatchSolution:
        """Equilibria under many loads at once: ``work`` is (B, m), one row of
        the loads' work per sample (build rows with ``Assembly.wrench_work``).
        ``radii`` (B, n): each sample's own plays, as scaled cone radii in the
        order of ``Assembly.balls`` (``variation.PlayMap.radii`` builds them)."""
        from .batch import solve_batch

        return solve_batch(self, work, radii)

    def with_radii(self, radii: FloatArray) -> Workspace:
        """A workspace of the same mechanism with other plays: ``radii`` are
        the scaled cone radii (``Assembly.balls`` order); scales, free motions
        and unknowns stay those of this one, so answers compare row by row."""
        return Workspace(self.asm.with_radii(radii), self.settings)

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

    def _optimum(self, g_hat: FloatArray, sigma: FloatArray | None = None) -> _Point:
        """The certified optimum for unit loads ``g_hat`` (or 0 for no load),
        with contact softness ``sigma`` (default: every contact hard)."""
        self.sigma = np.zeros(len(self.balls)) if sigma is None else sigma
        if not np.any(g_hat):
            point = _Point(
                np.zeros(self.m), np.zeros(len(self.balls)), self._no_f(), method="no load"
            )
        else:
            warm = self._warm(g_hat) if self.settings.warm_start else None
            point = warm if warm is not None else self._phase1(g_hat)
            self._check_turns(point.x)  # before polishing, which a nearly free body defeats
            if warm is None and self.settings.polish:
                point = self._polish(g_hat, point)
            self._last = point if point.active is not None else None
            point = self._split(g_hat, point)
        cert = point.certificate or self._certify(g_hat, point, point.nu)
        fine_ipm = self.settings.fine_ipm_tolerance
        if not cert.certified and np.any(g_hat) and self.settings.ipm_tolerance > fine_ipm:
            # a nearly degenerate mechanism can leave the interior-point answer
            # (and its polish) 1e-7 mm off at the usual tolerance: once more, finer
            fine = Workspace(
                self.asm, replace(self.settings, ipm_tolerance=fine_ipm, warm_start=False)
            )
            try:
                point = fine._optimum(g_hat, sigma)
            except SolverError:
                pass
            else:
                assert point.certificate is not None
                cert = point.certificate
        if not cert.certified:
            raise SolverError(
                "the solver's answer could not be certified: "
                f"feasibility {cert.feasibility_mm:.3g} mm, equilibrium residual "
                f"{cert.equilibrium_residual:.3g} (relative), smallest contact force "
                f"{cert.min_force:.3g} N. " + self._weak_hint() + " If not, please report "
                "this model."
            )
        point.certificate = cert
        return point

    def _check_turns(self, x: FloatArray) -> None:
        """A body that the loads turn by more than ``free_turn_rad`` is not
        held in any sense a small-displacement answer can describe."""
        asm = self.asm
        if not self.m:
            return
        turns = np.linalg.norm(x.reshape(-1, 6)[:, 3:], axis=1) * asm.turn
        worst = int(np.argmax(turns))
        if turns[worst] > self.settings.free_turn_rad:
            raise _unbounded(asm, x, one_way=True, turn=float(turns[worst]))

    # -- phase 1: the cone program -----------------------------------------
    def _phase1(self, g_hat: FloatArray) -> _Point:
        if np.any(self.sigma > 0):
            return self._phase1_compliant(g_hat)
        if self._phase1_data is None:
            self._phase1_data = self._cone_program(
                None, self.Eq, np.zeros(self.Eq.shape[0]), self.stack
            )
        prog = self._phase1_data
        sol = self._clarabel(prog, -g_hat)
        z = np.asarray(sol.z)
        return _Point(
            np.asarray(sol.x), z[prog.soc_first], z[prog.f_rows], iterations=sol.iterations
        )

    def _phase1_compliant(self, g_hat: FloatArray) -> _Point:
        """The cone program with a penetration ``p_i >= 0`` per compliant contact:
        ``|A_i x| <= r_i + p_i`` and energy ``-g_hat x + sum p_i^2 / (2 sigma_i)``."""
        soft = np.flatnonzero(self.stack.spring > 0)
        m, nc = self.m, len(soft)
        if self._compliant_data is None:
            base = self._cone_program(None, self.Eq, np.zeros(self.Eq.shape[0]), self.stack)
            n_base = base.A.shape[0]
            extra = sp.csr_matrix(
                (
                    -np.ones(2 * nc),
                    (
                        np.r_[base.soc_first[soft], n_base + np.arange(nc)],
                        np.r_[np.arange(nc), np.arange(nc)],
                    ),
                ),
                shape=(n_base + nc, nc),
            )  # cone radius r_i + p_i, and p_i >= 0
            A = sp.hstack([sp.vstack([base.A, sp.csr_matrix((nc, m))]), extra], format="csc")
            b = np.concatenate([base.b, np.zeros(nc)])
            cones = [*base.cones, clarabel.NonnegativeConeT(nc)]
            self._compliant_data = _ConeProgram(
                base.P, A, b, cones, base.settings, base.soc_first, base.f_rows
            )
        prog = self._compliant_data
        P = sp.csc_matrix(
            (1.0 / self.sigma[soft], (m + np.arange(nc), m + np.arange(nc))), shape=(m + nc, m + nc)
        )
        prog = _ConeProgram(
            P, prog.A, prog.b, prog.cones, prog.settings, prog.soc_first, prog.f_rows
        )
        sol = self._clarabel(prog, np.concatenate([-g_hat, np.zeros(nc)]))
        z = np.asarray(sol.z)
        x = np.asarray(sol.x)[:m]
        return _Point(x, z[prog.soc_first], z[prog.f_rows], iterations=sol.iterations)

    def _cone_program(
        self, P: Matrix | None, Eq: Matrix, e: FloatArray, stack: BallStack
    ) -> _ConeProgram:
        """Clarabel's data: the equalities, then one cone ``(r_i - B_i x, -A_i x)``
        per contact (a one-sided limit, with no rows, is a non-negative slack).
        Its dual is ``(lam_i, f_i)``."""
        n_eq, n_cones, n_rows = Eq.shape[0], len(stack.k), stack.A.shape[0]
        n_all = n_eq + n_rows + n_cones
        b = np.zeros(n_all)
        b[:n_eq] = e
        soc_first = n_eq + stack.start + np.arange(n_cones)
        ball_rows = n_eq + np.arange(n_rows) + np.repeat(np.arange(1, n_cones + 1), stack.k)
        b[soc_first] = stack.r
        order = np.empty(n_all, dtype=np.intp)  # row of the program -> row of (Eq; A; B)
        order[:n_eq] = np.arange(n_eq)
        order[ball_rows] = n_eq + np.arange(n_rows)
        order[soc_first] = n_eq + n_rows + np.arange(n_cones)
        stacked = linalg.vstack([Eq, stack.A, stack.B], self.m)
        if linalg.is_sparse(stacked):
            A = sp.csc_matrix(sp.csr_matrix(stacked)[order])
        else:
            A = _csc(np.asarray(stacked)[order]) if n_all else _csc(np.zeros((0, self.m)))
        cones: list[Any] = [clarabel.ZeroConeT(n_eq)] if n_eq else []
        cones += [
            clarabel.SecondOrderConeT(int(k) + 1) if k else clarabel.NonnegativeConeT(1)
            for k in stack.k
        ]
        if P is None:
            P_upper = sp.csc_matrix((self.m, self.m))
        elif linalg.is_sparse(P):
            P_upper = sp.csc_matrix(sp.triu(P))
        else:
            P_upper = _csc(np.triu(P))
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        tol = self.settings.ipm_tolerance
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = tol
        settings.max_iter = self.settings.max_iterations
        # refine each step's linear solve further than the default: with
        # stiff springs pressed far past their play, the default leaves some
        # programs "AlmostSolved" at a 1e-7 gap
        refine = self.settings.ipm_refinement
        settings.iterative_refinement_reltol = settings.iterative_refinement_abstol = refine
        return _ConeProgram(P_upper, A, b, cones, settings, soc_first, ball_rows)

    def _clarabel(self, prog: _ConeProgram, q: FloatArray) -> Any:
        sol = clarabel.DefaultSolver(prog.P, q, prog.A, prog.b, prog.cones, prog.settings).solve()
        if conic.outcome(sol) == "unbounded":  # a one-sided motion (_check_driven took the rest)
            motion = self._driven_motion(-q[: self.m], np.asarray(sol.x))
            raise _unbounded(self.asm, motion, one_way=True)
        if not conic.has_answer(sol):  # our programs are feasible (x = 0): numerical trouble
            raise SolverError(
                f"the cone solver stopped with status {conic.status_name(sol)} on this model. "
                + self._weak_hint()
            )
        return sol

    def _weak_hint(self) -> str:
        """Words on the motion the joints hold most weakly, for a solve that
        fails: a nearly free mechanism is the usual cause."""
        stack = self.stack
        C = linalg.vstack([stack.A, stack.B[np.flatnonzero(stack.has_offset)], self.E], self.m)
        if self.sparse or not C.shape[0]:
            return "Check for nearly coincident joints or a contact almost on an axis."
        C = C - (C @ self.N) @ self.N.T  # leave out the free motions
        _, sv, Vt = np.linalg.svd(C)
        keep = sv > self.settings.free_motion_rcond * sv[0]
        weakest = int(np.flatnonzero(keep)[-1])
        ratio = sv[0] / sv[weakest]
        d = Vt[weakest]
        body = int(np.argmax([np.linalg.norm(d[6 * i : 6 * i + 6]) for i in range(self.m // 6)]))
        omega, v_origin = self.asm.body_motion(d, body)
        motion = describe_motion(omega, v_origin, self.asm.ell)
        return (
            f"The motion the joints hold most weakly is body '{self.asm.body_names[body]}': "
            f"{motion}, held {ratio:.1e} times less firmly than the best-held one. Nearly "
            "coincident joints or a contact almost on an axis make a mechanism nearly "
            "free: move them apart, or make that motion free (remove the joint) and "
            "balance the loads on it."
        )

    # -- warm start, polishing and phase 2 ----------------------------------
    def _no_f(self) -> FloatArray:
        return np.zeros(self.stack.A.shape[0])

    def _face(self, key: _FaceKey) -> _Face:
        face = self._faces.get(key)
        if face is None:
            surface, linear = key
            stack = self.stack
            sub = stack.take(surface)
            lin = stack.take(linear)
            k = lin.k
            n_l, n_f = int(np.sum(k)) + len(k), int(np.sum(k))
            rhs = np.zeros(n_l)
            first = (lin.start + np.arange(len(k))).astype(np.intp)  # each cone's A rows, then B
            lam_rows = first + k
            f_rows = lin.rows_of(np.arange(len(k))) + np.repeat(np.arange(len(k)), k)
            order = np.empty(n_l, dtype=np.intp)  # row of L -> row of (A; B)
            order[f_rows] = np.arange(n_f)
            order[lam_rows] = n_f + np.arange(len(k))
            L = linalg.vstack([lin.A, lin.B], self.m)[order]
            rhs[lam_rows] = lin.r
            tilting = bool(np.any(sub.has_offset & (sub.k > 0)))

            def determined(L: Matrix = L, sub: BallStack = sub) -> bool | None:
                if tilting:
                    return None
                return self._determined_rows(linalg.vstack([L, sub.A], self.m))

            face = _Face(
                key,
                sub,
                L,
                rhs,
                lam_rows,
                f_rows,
                linalg.vstack([self.Eq, L], self.m),
                np.concatenate([np.zeros(self.Eq.shape[0]), rhs]),
                stack.rows_of(surface),
                stack.rows_of(linear),
                determined,
            )
            self._faces[key] = face
        return face

    def _determined_rows(self, rows: Matrix) -> bool:
        all_rows = linalg.vstack([self.Eq, rows], self.m)
        return linalg.full_column_rank(all_rows, self.m)

    def _determined(self, face: _Face, x: FloatArray) -> bool:
        """Whether the optimum on ``face`` is unique. On a tilting face
        (``|A_i x| + B_i x = r_i`` with ``B_i != 0``) two optima may trade
        tilt for shift along ``(A_i d, B_i d) ~ (u_i, -1)``, so only the rows
        of ``(A_i; B_i)`` across that direction count; they depend on x."""
        if face.determined is not None:
            return face.determined
        sub = face.stack
        v, rho = sub.norms(x)
        rows = [face.L]
        for i in range(len(sub.k)):
            if not sub.has_offset[i]:
                rows.append(sub.cone_rows(i))
                continue
            if rho[i] == 0.0:
                return False
            w = np.append(v[sub.start[i] : sub.start[i] + sub.k[i]] / rho[i], -1.0) / np.sqrt(2)
            M = linalg.dense(sub.face_rows(i))
            rows.append(M - np.outer(w, w @ M))
        return self._determined_rows(linalg.vstack(rows, self.m))

    def _newton_on(
        self,
        g_hat: FloatArray,
        key: _FaceKey,
        x0: FloatArray,
        lam0: FloatArray,
        iterations: int,
        method: str,
        max_iter: int,
    ) -> _Point | None:
        """Solve the KKT equations of the active set ``key`` and accept only a
        certified, unique optimum: feasible, forces balancing the loads, every
        active force strictly positive (strictly inside its cone for a face at
        its apex), on a face that pins the position down."""
        point = self._kkt_point(g_hat, key, x0, lam0, iterations, method, max_iter)
        if point is None or self._weak_forces(point, key).size:
            return None
        point.certificate = self._certify(g_hat, point)
        return point if point.certificate.certified else None

    def _weak_forces(self, point: _Point, key: _FaceKey) -> IntArray:
        """The cones of ``key`` whose force is not strictly positive (or, at
        the apex of a face, not strictly inside its cone)."""
        surface, linear = key
        both = np.array([*surface, *linear], dtype=np.intp)
        lam_a = point.lam[both]
        if not len(lam_a):
            return both
        strict = self.settings.positive_force
        weak = lam_a <= strict * float(np.max(lam_a))
        if linear:
            lin = self.stack.take(linear)
            f_norm = np.sqrt(lin.segment_sum(point.f[self.stack.rows_of(linear)] ** 2))
            at_apex = lin.k > 0
            weak[len(surface) :] |= at_apex & (f_norm >= (1.0 - strict) * point.lam[list(linear)])
        return both[weak]

    def _kkt_point(
        self,
        g_hat: FloatArray,
        key: _FaceKey,
        x0: FloatArray,
        lam0: FloatArray,
        iterations: int,
        method: str,
        max_iter: int,
        pinned: bool = True,
    ) -> _Point | None:
        """The solution of the KKT equations of the active set ``key``, if
        Newton converges and (``pinned``) the face pins the position down
        (forces unchecked). Unpinned, Newton's least-squares steps stop at an
        optimum near ``x0`` on the tied face."""
        face = self._face(key)
        if pinned and not self._determined(face, x0):
            return None
        surface, linear = key
        ne = self.Eq.shape[0]
        eq_soft = None
        if linear and np.any(self.sigma[list(linear)]):
            eq_soft = np.zeros(face.Eq.shape[0])
            eq_soft[ne + face.lam_rows] = self.sigma[list(linear)]
        out = _newton(
            None,
            -g_hat,
            face.Eq,
            face.e,
            face.stack,
            x0,
            lam0[list(surface)],
            max_iter,
            self.sigma[list(surface)],
            eq_soft,
            settings=self.settings,
            prox=0.0 if pinned else self.settings.tie_prox,
            accept=self.settings.newton_accept if pinned else self.settings.equilibrium_tolerance,
        )
        if out is None:
            return None
        x, lam_s, nu, its = out
        if pinned and not self._determined(face, x):
            return None
        return self._assemble_point(x, face, lam_s, nu[ne:], method, iterations + its)

    def _assemble_point(
        self,
        x: FloatArray,
        face: _Face,
        lam_surface: FloatArray,
        nu_linear: FloatArray,
        method: str,
        iterations: int,
    ) -> _Point:
        """The full multipliers from a face's: ``lam`` and ``f`` of every cone."""
        surface, linear = face.key
        lam = np.zeros(len(self.balls))
        f = self._no_f()
        lam[list(surface)] = lam_surface
        v, rho = face.stack.norms(x)
        f[face.surface_rows] = face.stack.surface_forces(v, rho, lam_surface)
        lam[list(linear)] = nu_linear[face.lam_rows]
        f[face.linear_rows] = nu_linear[face.f_rows]
        return _Point(x, lam, f, method, iterations, active=face.key)

    def _warm(self, g_hat: FloatArray) -> _Point | None:
        last = self._last
        if last is None or last.active is None:
            return None
        return self._newton_on(g_hat, last.active, last.x, last.lam, 0, "warm-started Newton", 12)

    def _active(
        self,
        x: FloatArray,
        lam: FloatArray,
        f: FloatArray,
        stack: BallStack,
        lam_scale: float | None = None,
    ) -> _FaceKey:
        """Contacts whose multiplier outweighs their slack (both relative),
        split into those on their cone's surface and those at its apex (or
        with no rows): see ``_Face``. Multipliers are relative to the largest,
        or to ``lam_scale`` if that is larger (when rigid joints carry the
        loads, the contacts' multipliers are round-off)."""
        if len(lam) == 0:
            return (), ()
        st = self.settings
        floor = st.noise_force if lam_scale is None else lam_scale
        lam_max = max(float(np.max(lam)), floor, TINY)
        _, rho, level = stack.levels(x)
        r = np.where(stack.r > 0, stack.r, self._max_radius)
        slack = (stack.r - level) / r
        active = np.flatnonzero(lam / lam_max > np.maximum(slack, st.feasibility_tolerance))
        f_norm = np.sqrt(stack.segment_sum(f * f))
        apex = (stack.k == 0) | (
            (rho <= st.apex * r) & (f_norm < (1.0 - st.apex) * np.maximum(lam, 0.0))
        )
        surface = tuple(int(i) for i in active if not apex[i])
        linear = tuple(int(i) for i in active if apex[i])
        return surface, linear

    def _polish(self, g_hat: FloatArray, point: _Point) -> _Point:
        key = self._active(point.x, point.lam, point.f, self.stack)
        optimum = self._refine_active(g_hat, point, key)
        if optimum is None:  # the interior point as it is, if it certifies
            optimum = point
        elif optimum.active is not None:
            key = optimum.active
        if self._determined(self._face(key), optimum.x):
            return optimum
        optimum.active = None  # the face is not a warm start: x is not unique
        return self._phase2(g_hat, optimum, key)

    def _refine_active(self, g_hat: FloatArray, point: _Point, key: _FaceKey) -> _Point | None:
        """A certified optimum, from the KKT equations of the active set
        ``key`` read from the interior-point answer or, failing that, of every
        cone near its limit; if some force comes out negative or a cone is
        pushed past its limit, take a few steps of an active-set method: drop
        those cones, add these. A large mechanism needs them: there an
        interior-point answer to 1e-10 cannot tell a slightly loaded contact
        from a nearly touching one. The optimum need not be unique (a tie)."""
        stack = self.stack
        if not len(stack.k):
            return None
        _, rho, level = stack.levels(point.x)
        r = np.where(stack.r > 0, stack.r, self._max_radius)
        f_norm = np.sqrt(stack.segment_sum(point.f * point.f))
        st = self.settings
        at_apex = (stack.k == 0) | ((rho <= st.apex * r) & (f_norm < (1.0 - st.apex) * point.lam))
        near = set(np.flatnonzero((stack.r - level) / r <= st.near_limit).tolist())
        # a contact the interior point loads faintly may be one that nearly
        # touches (its equations then contradict the others')
        both = np.array([*key[0], *key[1]], dtype=np.intp)
        top = float(np.max(point.lam, initial=0.0))
        faint = set(both[point.lam[both] < st.faint * top].tolist())
        seen: set[frozenset[int]] = set()
        for start in ({*key[0], *key[1]}, near, {*key[0], *key[1]} - faint):
            found = self._active_set_steps(g_hat, point, start, at_apex, seen)
            if found is not None:
                return found
        return None

    def _active_set_steps(
        self,
        g_hat: FloatArray,
        point: _Point,
        active: set[int],
        at_apex: NDArray[np.bool_],
        seen: set[frozenset[int]],
    ) -> _Point | None:
        """The active-set rounds of ``_refine_active`` from ``active``."""
        stack = self.stack
        r = np.where(stack.r > 0, stack.r, self._max_radius)
        lam_scale = float(np.max(np.abs(point.lam)))
        x, lam = point.x, point.lam
        st = self.settings
        for _ in range(st.refine_rounds):
            if frozenset(active) in seen:
                return None
            seen.add(frozenset(active))
            trial_key: _FaceKey = (
                tuple(sorted(i for i in active if not at_apex[i])),
                tuple(sorted(i for i in active if at_apex[i])),
            )
            trial = self._kkt_point(
                g_hat, trial_key, x, lam, point.iterations, "polished", 30, pinned=False
            )
            if trial is None:
                return None
            weak = self._weak_forces(trial, trial_key)
            _, _, level = stack.levels(trial.x)
            past = np.flatnonzero((level - stack.r) / r > st.feasibility_tolerance)
            past = past[[i not in active for i in past]]
            if not past.size:
                trial.certificate = self._certify(g_hat, trial)
                if trial.certificate.certified:
                    # a cone with no force (to round-off) does not bound the tie
                    trial.active = (
                        tuple(i for i in trial_key[0] if i not in weak),
                        tuple(i for i in trial_key[1] if i not in weak),
                    )
                    return trial
                if not weak.size:
                    return None
            # a face at its apex whose force reaches its cone's edge tilts
            # onto its surface; the other weak cones leave the set
            lam_top = float(np.max(trial.lam, initial=0.0))
            tilts = {
                int(i)
                for i in weak
                if at_apex[i] and self.stack.k[i] and trial.lam[i] > st.positive_force * lam_top
            }
            at_apex = at_apex.copy()
            at_apex[list(tilts)] = False
            active = (active - (set(weak.tolist()) - tilts)) | set(past.tolist())
            x, lam = trial.x, np.maximum(trial.lam, st.positive_force * lam_scale)
        return None

    def _face_equalities(
        self, stack: BallStack, which: _FaceKey, x: FloatArray, reach: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Linear rows that keep the cones ``which`` where they are at ``x``:
        a surface cone keeps its direction ``u`` (``A_i x`` along ``u`` and
        ``u . A_i x + B_i x = reach_i``); a linear cone ``A_i x = 0``,
        ``B_i x = reach_i``. ``reach`` is per cone of ``which`` (surface first)."""
        surface, linear = which
        rows: list[Matrix] = []
        rhs: list[FloatArray] = []
        v, rho = stack.norms(x)
        for j, i in enumerate((*surface, *linear)):
            Ai = stack.cone_rows(i)
            if j < len(surface) and stack.k[i]:
                u = v[stack.start[i] : stack.start[i] + stack.k[i]] / max(rho[i], TINY)
                if not stack.has_offset[i]:
                    rows.append(Ai)
                    rhs.append(reach[j] * u)
                    continue
                across = np.linalg.svd(u[None, :])[2][1:]  # directions across u
                M = linalg.dense(stack.face_rows(i))
                rows.append(np.vstack([across @ M[:-1], u @ M[:-1] + M[-1]]))
            else:
                rows.append(stack.face_rows(i))
            rhs.append(np.append(np.zeros(rows[-1].shape[0] - 1), reach[j]))
        if not rows:
            return np.zeros((0, self.m)), np.zeros(0)
        return linalg.vstack(rows, self.m), np.concatenate(rhs)

    def _phase2(self, g_hat: FloatArray, point: _Point, key: _FaceKey) -> _Point:
        """Least-norm point of the optimal face (a tie between positions)."""
        surface, linear = key
        both = [*surface, *linear]
        # a compliant contact keeps its penetration; the others stay on its face
        reach = self.stack.r[both] + self.sigma[both] * point.lam[both]
        L, L_rhs = self._face_equalities(self.stack, key, point.x, reach)
        Eq, e = self._independent_rows(
            linalg.vstack([self.Eq, L], self.m), np.concatenate([np.zeros(self.Eq.shape[0]), L_rhs])
        )
        rest_index = [i for i in range(len(self.balls)) if i not in set(both)]
        rest = self.stack.take(rest_index)
        # a tilting face stays on the side it leans to: u . A_i x >= 0
        v, rho = self.stack.norms(point.x)
        lean = [
            -(v[self.stack.start[i] : self.stack.start[i] + self.stack.k[i]] / rho[i])
            @ linalg.dense(self.stack.cone_rows(i))
            for i in surface
            if self.stack.k[i] and self.stack.has_offset[i] and rho[i] > 0
        ]
        if lean:
            rest = rest.with_limits(np.array(lean))
        metric = self.asm.metric_matrix
        prog = self._cone_program(metric, Eq, e, rest)
        try:
            sol = self._clarabel(prog, np.zeros(self.m))
        except SolverError:
            # badly scaled (levers of 100 m on plays of 0.1 mm): the active-set
            # Newton alone, from the optimum, with no other contact active
            x = self._phase2_polish(
                point.x, np.zeros(len(rest.k)), np.zeros(rest.A.shape[0]), rest, Eq, e, strict=True
            )
        else:
            z = np.asarray(sol.z)
            lam_rest, f_rest = z[prog.soc_first], z[prog.f_rows]
            x = self._phase2_polish(np.asarray(sol.x), lam_rest, f_rest, rest, Eq, e)
        # any optimal forces are complementary to every optimal position:
        # those of ``point`` hold at x, which keeps its active cones as they were
        return _Point(x, point.lam, point.f, method="least-norm face", iterations=point.iterations)

    def _phase2_polish(
        self,
        x: FloatArray,
        lam: FloatArray,
        f: FloatArray,
        rest: BallStack,
        Eq: Matrix,
        e: FloatArray,
        strict: bool = False,
    ) -> FloatArray:
        """Newton on the KKT equations of the least-norm program from its
        interior point ``x``, with a few active-set rounds (cones pushed past
        their limit join); ``x`` itself if that does not end feasible (or,
        ``strict``, SolverError)."""
        metric = self.asm.metric_matrix
        surface, linear = self._active(x, lam, f, rest, float(np.max(np.abs(metric @ x))))
        active = {*surface, *linear}
        apex = set(linear)
        r = np.where(rest.r > 0, rest.r, self._max_radius)
        st = self.settings
        for _ in range(st.refine_rounds):
            on_surface = sorted(i for i in active if i not in apex)
            at_apex = sorted(i for i in active if i in apex)
            L2, l2 = self._face_equalities(rest, ((), tuple(at_apex)), x, rest.r[at_apex])
            polished = _newton(
                metric,
                np.zeros(self.m),
                linalg.vstack([Eq, L2], self.m),
                np.concatenate([e, l2]),
                rest.take(on_surface),
                x,
                np.maximum(lam[on_surface], 0.0),
                settings=st,
            )
            if polished is None:
                break
            _, _, level = rest.levels(polished[0])
            past = set(np.flatnonzero((level - rest.r) / r > st.feasibility_tolerance).tolist())
            past -= active
            if not past:
                return polished[0]
            active |= past
            apex |= {i for i in past if rest.k[i] == 0}
        if strict:
            raise SolverError(
                "the least-norm point of a tie (an optimum that is not unique) could not "
                "be found accurately on this model. " + self._weak_hint()
            )
        return x

    def _independent_rows(self, C: Matrix, c: FloatArray) -> tuple[Matrix, FloatArray]:
        """Equalities ``C x = c`` as orthonormal, independent rows (least
        squares): the face's rows often repeat each other (a joint's cones
        share them), and nearly dependent rows make the solvers' multipliers
        huge and their accuracy poor. A large (sparse) system is kept as it is."""
        if linalg.is_sparse(C) or not C.shape[0]:
            return C, c
        U, sv, Vt = np.linalg.svd(np.asarray(C), full_matrices=False)
        keep = sv > self.settings.free_motion_rcond * sv[0] if sv[0] > 0 else sv > 0
        return Vt[keep], (U[:, keep].T @ c) / sv[keep]

    # -- certificate --------------------------------------------------------
    def _certify(
        self, g_hat: FloatArray, point: _Point, nu: FloatArray | None = None
    ) -> Certificate:
        """The certificate (``certificate.check``) of one answer."""
        c = certificate.check(
            self,
            g_hat[None],
            point.x[None],
            point.lam[None],
            point.f[None],
            self.sigma[None],
            nu=None if nu is None else nu[None],
        )
        return Certificate(
            certified=bool(c.passed(self.settings, self._max_radius)[0]),
            method=point.method,
            feasibility_mm=max(float(c.feasibility[0]), 0.0) * self.asm.s,
            equilibrium_residual=float(c.balance[0]),
            complementarity=float(c.complementarity[0]),
            min_force=float(c.min_force[0]),
            iterations=point.iterations,
        )


@dataclass(frozen=True)
class _ConeProgram:
    P: sp.csc_matrix
    A: sp.csc_matrix
    b: FloatArray
    cones: list[Any]
    settings: Any
    soc_first: IntArray  # row of each cone's first entry (its multiplier lam)
    f_rows: IntArray  # rows of the cones' other entries (their force vectors f)


def _csc(a: FloatArray) -> sp.csc_matrix:
    """A dense matrix in compressed-column form, built directly (scipy's
    general constructors cost more than the small solves they feed)."""
    col, row = np.nonzero(a.T)
    indptr = np.zeros(a.shape[1] + 1, dtype=np.int64)
    np.cumsum(np.bincount(col, minlength=a.shape[1]), out=indptr[1:])
    return sp.csc_matrix((a[row, col], row.astype(np.int64), indptr), shape=a.shape)


def _column_max(a: Matrix, m: int) -> FloatArray:
    """Each column's largest entry (0 for no rows)."""
    if not a.shape[0]:
        return np.zeros(m)
    if linalg.is_sparse(a):
        return np.asarray(a.max(axis=0).toarray()).ravel()
    return np.asarray(np.max(a, axis=0))


def _rank(a: FloatArray, rcond: float = DEFAULT.free_motion_rcond) -> int:
    sv = np.linalg.svd(a, compute_uv=False)
    return int(np.sum(sv > rcond * sv[0])) if sv.size and sv[0] > 0 else 0


def _newton(
    P: Matrix | None,
    q: FloatArray,
    Eq: Matrix,
    e: FloatArray,
    stack: BallStack,
    x0: FloatArray,
    lam0: FloatArray,
    max_iter: int = 30,
    soft: FloatArray | None = None,
    eq_soft: FloatArray | None = None,
    settings: SolverSettings = DEFAULT,
    prox: float = 0.0,
    accept: float = DEFAULT.newton_accept,
) -> tuple[FloatArray, FloatArray, FloatArray, int] | None:
    """Newton's method on the KKT equations of an active set.

    Stationarity ``P x + q + sum lam_i (A_i^T u_i + B_i) + Eq^T nu = 0``,
    active contacts on their surface ``|A_i x| + B_i x = r_i + soft_i lam_i``
    (``soft``: compliance, default 0), equalities ``Eq x = e + eq_soft nu``.
    A singular system (statically indeterminate contact forces) takes
    least-squares steps. ``prox`` > 0: the steps are proximal ones
    (``linalg.solve_kkt``): on a tied face, whose directions make the system
    singular only up to round-off, they stay short and end at the optimum
    nearest ``x0``, with the forces nearest ``lam0``. Returns None when its
    equations do not hold to ``accept`` (relative: stationarity to the size
    of the forces that balance, the other rows to the size of x).
    """
    m, na, ne = len(x0), len(stack.k), Eq.shape[0]
    A, start, k, r, Bo = stack.A, stack.start, stack.k, stack.r, stack.B
    sparse = linalg.is_sparse(A) or linalg.is_sparse(Eq)
    x, lam = x0.copy(), lam0.astype(float).copy()
    soft_na = np.zeros(na) if soft is None else soft
    soft_eq = np.zeros(ne) if eq_soft is None else eq_soft
    nu = np.zeros(ne)
    n = m + na + ne
    if not sparse:
        K = np.zeros((n, n))
        K[m + np.arange(na), m + np.arange(na)] = -soft_na
        K[m + na + np.arange(ne), m + na + np.arange(ne)] = -soft_eq
        K[:m, m + na :] = Eq.T
        K[m + na :, :m] = Eq
    S = stack.segment_matrix if sparse else None
    best: tuple[float, FloatArray, FloatArray, FloatArray, int] | None = None
    history: list[float] = []
    for it in range(max_iter + 1):
        grad = q + linalg.adjoint(Eq, nu)
        if P is not None:
            grad = grad + P @ x
        if na:
            v = linalg.times(A, x)
            rho = np.sqrt(np.add.reduceat(v * v, start))
            if float(np.min(rho)) == 0.0:
                return None
            u = v / np.repeat(rho, k)
            if S is None:
                J = np.add.reduceat(A * u[:, None], start, axis=0) + Bo
            else:
                J = sp.csr_matrix(S.T @ sp.diags(u) @ A + Bo)
            grad = grad + linalg.adjoint(J, lam)
            F = np.concatenate(
                [grad, rho + linalg.times(Bo, x) - r - soft_na * lam, Eq @ x - e - soft_eq * nu]
            )
        else:
            F = np.concatenate([grad, Eq @ x - e - soft_eq * nu])
        # relative errors: stationarity to the forces that balance (round-off
        # grows with them: long chains carry large ones), the contact and
        # equality rows to the size of the position
        force_scale = _term_scale(q, lam, nu)
        if P is not None:
            force_scale = max(force_scale, float(np.max(np.abs(P @ x), initial=0.0)))
        length_scale = max(1.0, float(np.max(np.abs(x), initial=0.0)))
        err = max(
            float(np.max(np.abs(F[:m]), initial=0.0)) / force_scale,
            float(np.max(np.abs(F[m:]), initial=0.0)) / length_scale,
        )
        if best is None or err < best[0]:
            best = (err, x, lam, nu, it)
        history.append(err)
        stalled = it >= 3 and err > settings.newton_stall * min(history[-4:-1])
        if err <= settings.round_off or it == max_iter or stalled:
            break
        if na:
            c = lam / rho
            Ju = J - Bo
        if not sparse:
            H = np.zeros((m, m)) if P is None else np.array(P, dtype=float)
            if na:
                H += (A.T * np.repeat(c, k)) @ A - (Ju.T * c) @ Ju
                K[:m, m : m + na] = J.T
                K[m : m + na, :m] = J
            K[:m, :m] = H
            Kmat: Matrix = K
        else:
            H = sp.csr_matrix((m, m)) if P is None else sp.csr_matrix(P)
            if na:
                H = H + A.T @ sp.diags(np.repeat(c, k)) @ A - Ju.T @ sp.diags(c) @ Ju
                Jm = J
            else:
                Jm = sp.csr_matrix((0, m))
            Kmat = sp.bmat(
                [
                    [H, Jm.T, sp.csr_matrix(Eq).T],
                    [Jm, sp.diags(-soft_na) if na else None, None],
                    [sp.csr_matrix(Eq), None, sp.diags(-soft_eq) if ne else None],
                ],
                format="csc",
            )
        try:
            # proximal steps where a tie may be (dense: small systems, whose
            # refinement is cheap); a large system's only when its plain step
            # is absurd (they converge slowly on a long chain's weak modes)
            step = linalg.solve_kkt(Kmat, -F, m, 0.0 if sparse else prox)
            if (
                prox
                and sparse
                and (
                    float(np.max(np.abs(step[:m]))) > settings.far * length_scale
                    or float(np.max(np.abs(step[m:]), initial=0.0)) > settings.far * force_scale
                )
            ):  # round-off's step along a tie or an indeterminate force
                step = linalg.solve_kkt(Kmat, -F, m, prox)
        except linalg.SingularSystemError:
            break
        x = x + step[:m]
        lam = lam + step[m : m + na]
        nu = nu + step[m + na :]
    assert best is not None
    err, x, lam, nu, its = best
    if err > accept:  # the certificate has the last word
        return None
    return x, lam, nu, its


def _term_scale(q: FloatArray, lam: FloatArray, nu: FloatArray) -> float:
    """The size of the terms that balance in the KKT equations."""
    return max(
        1.0,
        float(np.linalg.norm(q)),
        float(np.max(np.abs(lam), initial=0.0)),
        float(np.max(np.abs(nu), initial=0.0)),
    )


def _unbounded(
    asm: Assembly, direction: FloatArray, one_way: bool = False, turn: float | None = None
) -> UnboundedMechanismError:
    """Describe a driven free motion (scaled unknowns) in words (``one_way``:
    a motion the joints stop in one sense only, such as lifting off; ``turn``:
    the motion is held, but only after this many radians)."""
    moves = []
    for i, name in enumerate(asm.body_names):
        omega, v_origin = asm.body_motion(direction, i)
        size = float(np.linalg.norm(asm.s * direction[6 * i : 6 * i + 3])) + asm.ell * float(
            np.linalg.norm(omega)
        )
        moves.append((size, name, omega, v_origin))
    moves.sort(key=lambda t: -t[0])
    biggest = moves[0][0]
    moving = [mv for mv in moves if mv[0] > DEFAULT.mover_share * biggest]
    _, body, omega, v_origin = moving[0]
    motion = describe_motion(omega, v_origin, asm.ell, signed=one_way)
    others = [mv[1] for mv in moving[1:]]
    with_others = f" (together with {', '.join(repr(o) for o in others)})" if others else ""
    message = (
        f"body '{body}': {motion} is not held by any joint, and the loads drive it{with_others}. "
        "There is no equilibrium: add a joint or a clearance limit that holds this motion, "
        "or balance the loads on it."
    )
    if turn is not None:
        message = (
            f"body '{body}': {motion} is held only weakly{with_others}: the loads drive it "
            f"until the body has turned by {turn:.3g} rad, far beyond the small "
            "displacements that this model describes. Nearly coincident joints, or a "
            "contact or an axis almost along this motion, leave it practically free: "
            "move them apart, add a joint that holds it, or balance the loads on it."
        )
    scale = 1.0 / max(biggest, TINY)
    direction_map = {
        mv[1]: (
            tuple(float(c) for c in mv[2] * scale),
            tuple(float(c) for c in mv[3] * scale),
        )
        for mv in moving
    }
    return UnboundedMechanismError(
        message,
        body=body,
        motion=motion,
        direction=direction_map,  # type: ignore[arg-type]
    )
