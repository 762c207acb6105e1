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
from dataclasses import dataclass
from typing import Any

import clarabel
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .assembly import Assembly, ContactRows, assemble
from .errors import SolverError, UnboundedMechanismError
from .geometry import FloatArray, describe_motion
from .model import Model
from .result import Certificate, Result, build_result


@dataclass(frozen=True)
class SolverSettings:
    """Knobs of the solve; the defaults are what the tests and the CLI use."""

    #: Clarabel's gap and feasibility tolerances (relative, scaled problem).
    ipm_tolerance: float = 1e-10
    max_iterations: int = 200
    #: Refine the interior-point answer on its active set (Newton on the KKT system).
    polish: bool = True
    #: Singular values below this (relative) span the free motions.
    free_motion_rcond: float = 1e-9
    #: A load component on a free motion below this fraction of the load is taken as 0.
    drive_tolerance: float = 1e-9
    #: Certificate thresholds: feasibility as a fraction of the largest play,
    #: equilibrium residual as a fraction of the load.
    feasibility_tolerance: float = 1e-9
    equilibrium_tolerance: float = 1e-8


@dataclass
class _Point:
    """A candidate optimum in scaled unknowns, with its multipliers."""

    x: FloatArray
    lam: FloatArray  # per ball contact (scaled)
    method: str = "interior-point"
    iterations: int = 0
    certificate: Certificate | None = None


def solve(model: Model, settings: SolverSettings | None = None) -> Result:
    """Find the equilibrium of ``model``: positions, contacts and certificate."""
    return Workspace(assemble(model), settings).solve()


class Workspace:
    """The solver's side: assembled matrices, free motions and scratch data.

    Built once from an ``Assembly``; the model is never modified.
    """

    def __init__(self, assembly: Assembly, settings: SolverSettings | None = None):
        self.asm = assembly
        self.settings = settings or SolverSettings()
        self.m = assembly.m
        self.E = assembly.E
        self.balls = assembly.balls
        self.N = self._free_motions()
        self.M = assembly.metric
        self.K = sp.csr_matrix(np.asarray(self.M @ self.N).T)
        self._E_dense = self.E.toarray()
        self._eq = sp.vstack([self.E, self.K], format="csr")
        self._eq_dense = self._eq.toarray()
        self._phase1_data: tuple[Any, ...] | None = None

    # -- free motions -------------------------------------------------------
    def _free_motions(self) -> FloatArray:
        rows = [c.dense() for c in self.asm.contacts]
        C = np.vstack(rows) if rows else np.zeros((0, self.m))
        if C.shape[0] == 0:
            return np.eye(self.m)
        return np.asarray(sla.null_space(C, rcond=self.settings.free_motion_rcond))

    def _check_driven(self, g: FloatArray) -> None:
        if self.N.shape[1] == 0:
            return
        drive = self.N.T @ g
        if np.linalg.norm(drive) <= self.settings.drive_tolerance * np.linalg.norm(g):
            return
        raise _unbounded(self.asm, self.N @ drive)

    # -- the solve ----------------------------------------------------------
    def solve(self) -> Result:
        start = time.perf_counter()
        g = self.asm.g
        self._check_driven(g)
        g_norm = float(np.linalg.norm(g))
        if g_norm == 0.0:
            point = _Point(np.zeros(self.m), np.zeros(len(self.balls)), method="no load")
            g_hat = g
        else:
            g_hat = g / g_norm
            point = self._phase1(g_hat)
            if self.settings.polish:
                point = self._polish(g_hat, point)
        cert = point.certificate or self._certify(g_hat, point)
        if not cert.certified:
            raise SolverError(
                "the solver's answer could not be certified: "
                f"feasibility {cert.feasibility_mm:.3g} mm, equilibrium residual "
                f"{cert.equilibrium_residual:.3g} (relative), smallest contact force "
                f"{cert.min_force:.3g} N; please report this model"
            )
        elapsed = time.perf_counter() - start
        return build_result(
            self.asm, point.x, point.lam * g_norm / self.asm.s, cert, elapsed, self.N
        )

    # -- phase 1: the cone program -----------------------------------------
    def _equalities(self) -> sp.csr_matrix:
        return self._eq

    def _phase1(self, g_hat: FloatArray) -> _Point:
        eq = self._equalities()
        sol = self._clarabel(None, -g_hat, eq, np.zeros(eq.shape[0]), self.balls, cache=True)
        lam = np.array([sol.z[j] for j in self._soc_starts(eq.shape[0], self.balls)])
        x = np.asarray(sol.x)
        return _Point(x, lam, iterations=sol.iterations)

    def _soc_starts(self, n_eq: int, balls: tuple[ContactRows, ...]) -> list[int]:
        starts, row = [], n_eq
        for c in balls:
            starts.append(row)
            row += 1 + c.k
        return starts

    def _clarabel(
        self,
        P: sp.csc_matrix | None,
        q: FloatArray,
        eq: sp.csr_matrix,
        eq_rhs: FloatArray,
        balls: tuple[ContactRows, ...],
        cache: bool = False,
    ) -> clarabel.DefaultSolution:
        data = self._phase1_data if cache else None
        if data is None:
            data = self._cone_data(P, eq, eq_rhs, balls)
            if cache:
                self._phase1_data = data
        P_upper, A, b, cones, settings = data
        sol = clarabel.DefaultSolver(P_upper, q, A, b, cones, settings).solve()
        status = str(sol.status)
        if status.endswith("DualInfeasible"):  # should have been caught by _check_driven
            raise _unbounded(self.asm, np.asarray(sol.x))
        if not (status.endswith("Solved")):
            raise SolverError(f"the cone solver stopped with status {status}")
        return sol

    # -- phase 2 and polishing ---------------------------------------------
    def _cone_data(
        self,
        P: sp.csc_matrix | None,
        eq: sp.csr_matrix,
        eq_rhs: FloatArray,
        balls: tuple[ContactRows, ...],
    ) -> tuple[Any, ...]:
        """Clarabel's (P, A, b, cones, settings): equalities, then one cone per contact."""
        rows, cols, vals = [], [], []
        eq_coo = eq.tocoo()
        rows.append(eq_coo.row)
        cols.append(eq_coo.col)
        vals.append(eq_coo.data)
        rhs = [eq_rhs]
        cones = []
        if eq.shape[0]:
            cones.append(clarabel.ZeroConeT(eq.shape[0]))
        row = eq.shape[0]
        for c in balls:
            k, n = c.k, len(c.cols)
            rows.append(row + 1 + np.repeat(np.arange(k), n))
            cols.append(np.tile(c.cols, k))
            vals.append(c.block.ravel())
            rhs.append(np.r_[c.radius, np.zeros(k)])
            cones.append(clarabel.SecondOrderConeT(k + 1))
            row += k + 1
        A = sp.csc_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(row, self.m),
        )
        b = np.concatenate(rhs)
        P_upper = sp.csc_matrix((self.m, self.m)) if P is None else sp.triu(P, format="csc")
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        tol = self.settings.ipm_tolerance
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = tol
        settings.max_iter = self.settings.max_iterations
        return P_upper, A, b, cones, settings

    def _active(
        self, point: _Point, balls: tuple[ContactRows, ...], lam_scale: float = 0.0
    ) -> list[int]:
        """Contacts whose multiplier outweighs their slack (both relative)."""
        if len(point.lam) == 0:
            return []
        lam_max = max(float(np.max(point.lam)), lam_scale, 1e-300)
        active = []
        for i, c in enumerate(balls):
            slack = c.radius - float(np.linalg.norm(c.apply(point.x)))
            if point.lam[i] / lam_max > max(slack / c.radius, 1e-9):
                active.append(i)
        return active

    def _polish(self, g_hat: FloatArray, point: _Point) -> _Point:
        active = self._active(point, self.balls)
        eq = self._equalities()
        eq_dense = self._eq_dense
        face = np.vstack([eq_dense, *[self.balls[i].dense() for i in active]])
        if face.shape[0] and _rank(face) == self.m:
            polished = _newton(
                None,
                -g_hat,
                eq_dense,
                np.zeros(eq.shape[0]),
                [self.balls[i] for i in active],
                point.x,
                point.lam[active],
            )
            if polished is not None:
                x, lam_active, _nu, its = polished
                lam = np.zeros(len(self.balls))
                lam[active] = lam_active
                candidate = _Point(x, lam, method="polished", iterations=point.iterations + its)
                candidate.certificate = self._certify(g_hat, candidate)
                if candidate.certificate.certified:
                    return candidate
            return point
        return self._phase2(g_hat, point, active)

    def _phase2(self, g_hat: FloatArray, point: _Point, active: list[int]) -> _Point:
        """Least-norm point of the optimal face (a tie between positions)."""
        eq = self._equalities()
        directions = []
        for i in active:
            v = self.balls[i].apply(point.x)
            directions.append(self.balls[i].radius * v / np.linalg.norm(v))
        face = sp.vstack([eq, *[self.balls[i].A for i in active]], format="csr")
        face_rhs = (
            np.concatenate([np.zeros(eq.shape[0]), *directions])
            if active
            else np.zeros(eq.shape[0])
        )
        rest = tuple(c for i, c in enumerate(self.balls) if i not in active)
        rest_index = [i for i in range(len(self.balls)) if i not in active]
        sol = self._clarabel(self.M, np.zeros(self.m), face, face_rhs, rest)
        x = np.asarray(sol.x)
        lam_rest = np.array([sol.z[j] for j in self._soc_starts(face.shape[0], rest)])
        p2 = _Point(x, lam_rest)
        active2 = self._active(p2, rest, float(np.max(np.abs(self.M @ x))))
        polished = _newton(
            self.M.toarray(),
            np.zeros(self.m),
            face.toarray(),
            face_rhs,
            [rest[i] for i in active2],
            x,
            lam_rest[active2],
        )
        if polished is not None:
            x = polished[0]
        lam = self._forces_at(g_hat, x, sorted(set(active) | {rest_index[i] for i in active2}))
        return _Point(x, lam, method="least-norm face", iterations=point.iterations)

    def _forces_at(self, g_hat: FloatArray, x: FloatArray, active: list[int]) -> FloatArray:
        """Contact multipliers that best balance the loads at ``x`` (least squares)."""
        cols = [self.balls[i].adjoint(_unit(self.balls[i].apply(x))) for i in active]
        E = self._E_dense
        Amat = np.column_stack([*cols, E.T]) if (cols or E.shape[0]) else np.zeros((self.m, 0))
        coef = np.linalg.lstsq(Amat, g_hat, rcond=None)[0] if Amat.shape[1] else np.zeros(0)
        lam = np.zeros(len(self.balls))
        lam[active] = coef[: len(active)]
        return lam

    # -- certificate --------------------------------------------------------
    def _certify(self, g_hat: FloatArray, point: _Point) -> Certificate:
        x, lam = point.x, point.lam
        s = self.asm.s
        feas = 0.0
        max_ball_radius = max([c.radius for c in self.balls], default=1.0)
        residual_vec = g_hat.copy()
        comp = 0.0
        for i, c in enumerate(self.balls):
            v = c.apply(x)
            rho = float(np.linalg.norm(v))
            feas = max(feas, rho - c.radius)
            if lam[i] != 0.0 and rho > 0.0:
                residual_vec -= lam[i] * c.adjoint(v / rho)
                comp = max(comp, abs(lam[i]) * max(c.radius - rho, 0.0) / max_ball_radius)
        if self.E.shape[0]:
            E = self._E_dense
            feas = max(feas, float(np.max(np.abs(E @ x))))
            nu = np.linalg.lstsq(E.T, residual_vec, rcond=None)[0]
            residual_vec -= E.T @ nu
        loaded = bool(np.linalg.norm(g_hat) > 0)
        residual = float(np.linalg.norm(residual_vec)) if loaded else 0.0
        min_force = float(np.min(lam)) if len(lam) else 0.0
        lam_scale = max([1.0, *np.abs(lam)])
        st = self.settings
        certified = (
            feas <= st.feasibility_tolerance * max_ball_radius
            and residual <= st.equilibrium_tolerance
            and min_force >= -st.equilibrium_tolerance * lam_scale
            and comp <= st.equilibrium_tolerance * lam_scale
        )
        return Certificate(
            certified=bool(certified),
            method=point.method,
            feasibility_mm=max(feas, 0.0) * s,
            equilibrium_residual=residual,
            complementarity=comp,
            min_force=min_force,
            iterations=point.iterations,
        )


def _unit(v: FloatArray) -> FloatArray:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


def _rank(a: FloatArray, rcond: float = 1e-9) -> int:
    sv = np.linalg.svd(a, compute_uv=False)
    return int(np.sum(sv > rcond * sv[0])) if sv.size and sv[0] > 0 else 0


def _newton(
    P: FloatArray | None,
    q: FloatArray,
    Eq: FloatArray,
    e: FloatArray,
    balls: list[ContactRows],
    x0: FloatArray,
    lam0: FloatArray,
    max_iter: int = 30,
) -> tuple[FloatArray, FloatArray, FloatArray, int] | None:
    """Newton's method on the KKT equations of an active set.

    Stationarity ``P x + q + sum lam_i A_i^T u_i + Eq^T nu = 0``, active
    contacts ``|A_i x| = r_i``, equalities ``Eq x = e``. Steps are least-squares
    solutions, so statically indeterminate contact forces do not stop it.
    Returns None when it does not converge to machine precision.
    """
    m, na, ne = len(x0), len(balls), Eq.shape[0]
    A = [c.dense() for c in balls]
    r = np.array([c.radius for c in balls])
    x, lam = x0.copy(), lam0.astype(float).copy()
    nu = np.zeros(ne)
    scale = max(1.0, float(np.linalg.norm(q)))
    best = None
    for it in range(max_iter + 1):
        grad = q.copy() if P is None else P @ x + q
        H = np.zeros((m, m)) if P is None else P.copy()
        Jc = np.zeros((na, m))
        cres = np.zeros(na)
        for i in range(na):
            v = A[i] @ x
            rho = float(np.linalg.norm(v))
            if rho == 0.0:
                return None
            u = v / rho
            a = A[i].T @ u
            grad += lam[i] * a
            H += (lam[i] / rho) * (A[i].T @ (A[i] - np.outer(u, u) @ A[i]))
            Jc[i] = a
            cres[i] = rho - r[i]
        if ne:
            grad += Eq.T @ nu
        eres = Eq @ x - e if ne else np.zeros(0)
        F = np.concatenate([grad, cres, eres])
        err = float(np.max(np.abs(F))) if F.size else 0.0
        if best is None or err < best[0]:
            best = (err, x.copy(), lam.copy(), nu.copy(), it)
        if err <= 1e-14 * scale:
            break
        K = np.zeros((m + na + ne, m + na + ne))
        K[:m, :m] = H
        K[:m, m : m + na] = Jc.T
        K[m : m + na, :m] = Jc
        if ne:
            K[:m, m + na :] = Eq.T
            K[m + na :, :m] = Eq
        step = np.linalg.lstsq(K, -F, rcond=1e-13)[0]
        x = x + step[:m]
        lam = lam + step[m : m + na]
        nu = nu + step[m + na :]
    assert best is not None
    err, x, lam, nu, its = best
    if err > 1e-11 * scale:
        return None
    return x, lam, nu, its


def _unbounded(asm: Assembly, direction: FloatArray) -> UnboundedMechanismError:
    """Describe a driven free motion (scaled unknowns) in words."""
    moves = []
    for i, name in enumerate(asm.body_names):
        omega, v_origin = asm.body_motion(direction, i)
        size = float(np.linalg.norm(asm.s * direction[6 * i : 6 * i + 3])) + asm.ell * float(
            np.linalg.norm(omega)
        )
        moves.append((size, name, omega, v_origin))
    moves.sort(key=lambda t: -t[0])
    biggest = moves[0][0]
    moving = [mv for mv in moves if mv[0] > 1e-6 * biggest]
    _, body, omega, v_origin = moving[0]
    motion = describe_motion(omega, v_origin, asm.ell)
    others = [mv[1] for mv in moving[1:]]
    with_others = f" (together with {', '.join(repr(o) for o in others)})" if others else ""
    message = (
        f"body '{body}': {motion} is not held by any joint, and the loads drive it{with_others}. "
        "There is no equilibrium: add a joint or a clearance limit that holds this motion, "
        "or balance the loads on it."
    )
    scale = 1.0 / max(biggest, 1e-300)
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
