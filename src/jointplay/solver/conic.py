"""Clarabel's answers in our words: one explicit map of its statuses.

A status is never read by its suffix: ``AlmostSolved`` is an inaccurate
answer (kept only if our own certificate holds), not an optimum, and a
status that a new Clarabel release adds stops the solve with its name.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any, Literal

import clarabel
import numpy as np
import scipy.sparse as sp

from jointplay.assembly import BallStack, IntArray
from jointplay.errors import SolverError, UnassembledError
from jointplay.geometry import FloatArray
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix
from jointplay.solver import held
from jointplay.solver.records import ConeProgram

if TYPE_CHECKING:
    from jointplay.settings import SolverSettings
    from jointplay.solver.workspace import WorkspaceData

Outcome = Literal["optimal", "inaccurate", "infeasible", "unbounded", "stopped"]

STATUS: dict[str, Outcome] = {
    "Solved": "optimal",
    "AlmostSolved": "inaccurate",
    "PrimalInfeasible": "infeasible",
    "AlmostPrimalInfeasible": "infeasible",
    "DualInfeasible": "unbounded",  # the loads' work grows without end along a ray
    "AlmostDualInfeasible": "unbounded",
    "MaxIterations": "stopped",
    "MaxTime": "stopped",
    "NumericalError": "stopped",
    "InsufficientProgress": "stopped",
    "CallbackTerminated": "stopped",
    "Unsolved": "stopped",
}


def status_name(solution: Any) -> str:
    """The status's name, as Clarabel spells it (``SolverStatus.Solved`` -> ``Solved``)."""
    return str(solution.status).rsplit(".", 1)[-1]


def outcome(solution: Any) -> Outcome:
    """What a Clarabel solution means for us; a status we do not know is ``stopped``."""
    return STATUS.get(status_name(solution), "stopped")


def has_answer(solution: Any) -> bool:
    """Whether the solution holds a point worth certifying."""
    return outcome(solution) in ("optimal", "inaccurate")


# -- the cone program and its solve


def cone_program(
    ws: WorkspaceData,
    P: Matrix | None,
    Eq: Matrix,
    e: FloatArray,
    stack: BallStack,
    *,
    tolerance: float | None = None,
    max_iter: int | None = None,
    refine: bool = True,
    regularization: float | None = None,
) -> ConeProgram:
    """Clarabel's data: the equalities, then one cone ``(r_i - B_i x, c_i - A_i x)``
    per contact (a one-sided limit, with no rows, is a non-negative slack),
    ``c_i`` its centre (``BallStack.centre``). Its dual is ``(lam_i, f_i)``."""
    n_eq, n_cones, n_rows = Eq.shape[0], len(stack.k), stack.A.shape[0]
    n_all = n_eq + n_rows + n_cones
    b = np.zeros(n_all)
    b[:n_eq] = e
    soc_first = n_eq + stack.start + np.arange(n_cones)
    ball_rows = n_eq + np.arange(n_rows) + np.repeat(np.arange(1, n_cones + 1), stack.k)
    b[soc_first] = stack.r
    if stack.centre is not None:
        b[ball_rows] = stack.centre
    order = np.empty(n_all, dtype=np.intp)  # row of the program -> row of (Eq; A; B)
    order[:n_eq] = np.arange(n_eq)
    order[ball_rows] = n_eq + np.arange(n_rows)
    order[soc_first] = n_eq + n_rows + np.arange(n_cones)
    stacked = linalg.vstack([Eq, stack.A, stack.B], ws.m)
    if linalg.is_sparse(stacked):
        A = sp.csc_matrix(sp.csr_matrix(stacked)[order])
    else:
        A = csc(np.asarray(stacked)[order]) if n_all else csc(np.zeros((0, ws.m)))
    cones: list[Any] = [clarabel.ZeroConeT(n_eq)] if n_eq else []
    cones += [
        clarabel.SecondOrderConeT(int(k) + 1) if k else clarabel.NonnegativeConeT(1)
        for k in stack.k
    ]
    settings = options(ws.settings, tolerance, max_iter, refine, regularization)
    return ConeProgram(_upper(P, ws.m), A, b, cones, settings, soc_first, ball_rows)


def interior_program(ws: WorkspaceData) -> ConeProgram:
    """The cone program of the hard problem (its loads are set per solve),
    built on first use and kept on the workspace."""
    if ws.interior_program is None:
        e = np.zeros(ws.Eq.shape[0])
        refine = refined(ws.settings, ws.asm.sparse)
        ws.interior_program = cone_program(ws, None, ws.Eq, e, ws.stack, refine=refine)
    return ws.interior_program


def refined(settings: SolverSettings, sparse: bool) -> bool:
    """Whether a model's cone programs (its interior point, a tie's, the
    split's) get Clarabel's iterative refinement: a small model's do, a
    large (sparse) one's only when ``sparse_interior_refinement`` asks (the
    retry)."""
    return settings.sparse_interior_refinement or not sparse


def options(
    settings: SolverSettings,
    tolerance: float | None = None,
    max_iter: int | None = None,
    refine: bool = True,
    regularization: float | None = None,
) -> Any:
    """Clarabel's settings for every cone program we run: quiet, our
    tolerance (default ``ipm_tolerance``) and iteration limit, ``refine``:
    iterative refinement to ``round_off`` (or none), and the static
    regularization (default ``ipm_regularization``)."""
    out = clarabel.DefaultSettings()
    out.verbose = False
    tol = settings.ipm_tolerance if tolerance is None else tolerance
    out.tol_gap_abs = out.tol_gap_rel = out.tol_feas = tol
    out.max_iter = settings.max_iterations if max_iter is None else max_iter
    # refine each step's linear solve further than the default: with
    # stiff springs pressed far past their play, or a deviation zone's tilt
    # against a long lever, the default leaves some programs "AlmostSolved"
    out.iterative_refinement_enable = refine
    out.iterative_refinement_reltol = settings.round_off
    out.iterative_refinement_abstol = settings.round_off
    out.static_regularization_constant = (
        settings.ipm_regularization if regularization is None else regularization
    )
    # the KKT factorization every answer here was checked with (0.10's
    # default): 0.11's "auto" picks another, whose end points declined 157 of
    # the property tests' 2,338 mechanisms (2 % allowed; pyproject.toml)
    out.direct_solve_method = "qdldl"
    return out


def with_penetrations(prog: ConeProgram, soft: IntArray) -> ConeProgram:
    """The program with a penetration ``p_i >= 0`` per compliant contact
    ``soft``: cone radius ``r_i + p_i``, unknowns ``(x, p)``. Its energy
    ``sum p_i^2 / (2 sigma_i)`` depends on the loads: ``softened`` sets it."""
    n_base, m = prog.A.shape
    nc = len(soft)
    extra = sp.csr_matrix(
        (
            -np.ones(2 * nc),
            (
                np.r_[prog.soc_first[soft], n_base + np.arange(nc)],
                np.r_[np.arange(nc), np.arange(nc)],
            ),
        ),
        shape=(n_base + nc, nc),
    )
    A = sp.hstack([sp.vstack([prog.A, sp.csr_matrix((nc, m))]), extra], format="csc")
    b = np.concatenate([prog.b, np.zeros(nc)])
    cones = [*prog.cones, clarabel.NonnegativeConeT(nc)]
    P = sp.block_diag([prog.P, sp.csc_matrix((nc, nc))], format="csc")
    return ConeProgram(P, A, b, cones, prog.settings, prog.soc_first, prog.f_rows)


def softened(prog: ConeProgram, soft: IntArray, sigma: FloatArray) -> ConeProgram:
    """``with_penetrations``' program with the energy ``p_i^2 / (2 sigma_i)``."""
    m = prog.P.shape[0] - len(soft)
    P = sp.block_diag([prog.P[:m, :m], sp.diags(1.0 / sigma[soft])], format="csc")
    return replace(prog, P=P)


def _upper(P: Matrix | None, m: int) -> sp.csc_matrix:
    """The upper triangle Clarabel reads (``P`` None: no quadratic term)."""
    if P is None:
        return sp.csc_matrix((m, m))
    if linalg.is_sparse(P):
        return sp.csc_matrix(sp.triu(P))
    return csc(np.triu(P))


def run(ws: WorkspaceData, prog: ConeProgram, q: FloatArray) -> Any:
    # a new solver each time: one kept and updated answers as a new one
    # does to the interior-point tolerance only (3.5e-12 apart on the
    # paper's shaft), so a workspace's answers would depend on its history
    sol = clarabel.DefaultSolver(prog.P, q, prog.A, prog.b, prog.cones, prog.settings).solve()
    verdict = outcome(sol) in ("unbounded", "infeasible")
    if verdict and not prog.settings.iterative_refinement_enable:
        # a verdict is read from a refined solve (an unrefined one, a large
        # model's interior point, is Newton's start: ``sparse_interior_refinement``)
        refined = options(ws.settings)
        sol = clarabel.DefaultSolver(prog.P, q, prog.A, prog.b, prog.cones, refined).solve()
    if outcome(sol) == "unbounded":  # a one-sided motion (_check_driven took the rest)
        motion = held.driven_motion(ws, -q[: ws.m], np.asarray(sol.x))
        raise held.unbounded(ws.asm, motion, ws.settings, one_way=True)
    if outcome(sol) == "infeasible":
        ray = infeasibility(ws)
        if ray is not None:
            raise unassembled(ws, ray)
    if not has_answer(sol):
        # Clarabel can stop short of its certificate of unboundedness on a
        # body that lifts off compliant one-sided contacts: look for the ray
        # itself before calling it numerical trouble
        g = -q[: ws.m]
        ray = driven_ray(ws, g)
        if ray is not None:
            raise held.unbounded(ws.asm, held.driven_motion(ws, g, ray), ws.settings, one_way=True)
        raise SolverError(
            f"the cone solver stopped with status {status_name(sol)} on this model. "
            + held.weak_hint(ws)
        )
    return sol


def driven_ray(ws: WorkspaceData, g: FloatArray) -> FloatArray | None:
    """A motion of unit size that the loads' work ``g`` drives and that no
    contact, spring or rigid row stops however far it goes (the recession
    cone of the clearances: ``|A_i d| <= -B_i d``, ``E d = 0``, and ``K d = 0``
    for the free motions, which ``held.check_driven`` took), or None if the
    loads do no work on any: the program ``max g @ d`` over that cone and
    ``|d| <= 1``. A cone with no face row (``B_i = 0``) holds ``A_i d = 0``,
    written as equalities so that the program keeps an interior."""
    if not np.any(g):
        return None
    stack, m = ws.stack, ws.m
    B = sp.csr_matrix(stack.B)
    faced = np.diff(B.indptr) > 0  # cones with a face row
    one_sided, tilted = faced & (stack.k == 0), faced & (stack.k > 0)
    flat = stack.rows_of(np.flatnonzero(~faced))
    zero = linalg.vstack([ws.Eq, stack.A[flat]], m)
    blocks = [sp.csr_matrix(zero), B[np.flatnonzero(one_sided)]]
    cones: list[Any] = [
        clarabel.ZeroConeT(zero.shape[0]),
        clarabel.NonnegativeConeT(int(one_sided.sum())),
    ]
    for i in np.flatnonzero(tilted).tolist():  # (-B_i d, -A_i d) in the cone
        blocks.append(sp.vstack([B[i], sp.csr_matrix(stack.cone_rows(i))]))
        cones.append(clarabel.SecondOrderConeT(int(stack.k[i]) + 1))
    blocks.append(sp.vstack([sp.csr_matrix((1, m)), -sp.identity(m)]))  # (1, d): |d| <= 1
    cones.append(clarabel.SecondOrderConeT(m + 1))
    A = sp.csc_matrix(sp.vstack(blocks))
    b = np.zeros(A.shape[0])
    b[-m - 1] = 1.0
    keep = [c for c in cones if c.dim]
    sol = clarabel.DefaultSolver(
        sp.csc_matrix((m, m)), -g, A, b, keep, options(ws.settings)
    ).solve()
    if not has_answer(sol):
        return None
    d = np.asarray(sol.x)
    size = float(np.linalg.norm(d))
    st = ws.settings
    if float(g @ d) <= st.free_motion_rcond * float(np.linalg.norm(g)) or size == 0.0:
        return None
    d = d / size
    # the interior point's ray to its tolerance: it must hold no contact back
    return d if held.holds_no_more(ws, g, np.zeros(m), d) else None


def infeasibility(ws: WorkspaceData) -> FloatArray | None:
    """Clarabel's certificate that no position lies inside every clearance,
    or None if some does. Without deviations x = 0 does; with them the plain
    cone program with no loads decides (an "infeasible" status of another
    program, a tie's say, is round-off)."""
    if ws.stack.centre is None:
        return None
    prog = interior_program(ws)
    refined = options(ws.settings)  # a verdict's solve (``run``)
    sol = clarabel.DefaultSolver(
        prog.P, np.zeros(prog.A.shape[1]), prog.A, prog.b, prog.cones, refined
    ).solve()
    return np.asarray(sol.z) if outcome(sol) == "infeasible" else None


def unassembled(ws: WorkspaceData, ray: FloatArray) -> UnassembledError:
    """The error for clearances with no position inside them all, naming the
    joints whose cones carry Clarabel's certificate of infeasibility ``ray``
    of the plain program (forces that, pushing together, would have to do
    work from nothing)."""
    lam = np.abs(ray[interior_program(ws).soc_first])
    top = float(np.max(lam, initial=0.0))
    cones = (
        np.flatnonzero(lam > ws.settings.interior_resolution * top) if top > 0 else np.zeros(0, int)
    )
    model = ws.asm.model
    joints = tuple(dict.fromkeys(model.joints[ws.balls[int(i)].joint_index].name for i in cones))
    named = ", ".join(f"'{j}'" for j in joints) or "the joints"
    return UnassembledError(
        f"the parts cannot be assembled: with the joints' deviations, no position of the "
        f"bodies lies inside the clearances of {named} at once. Check the deviations' "
        "sizes and means against the plays (a tilted bore far from the next joint needs "
        "that joint's play times the lever).",
        joints=joints,
    )


class KeptSolver:
    """One cone program's Clarabel solver, kept for a sequence of linear
    costs ``q`` (an envelope's directions): each is given to it with
    ``update(q=...)``, which keeps its KKT matrix's analysis (the paper's
    shaft: 80 us a solve against 125 for a new solver). Its answers are a
    new solver's to the interior-point tolerance, not bit for bit, so it
    serves one run's own sequence, never a workspace's solves (``run``).
    Where the installed Clarabel does not allow the update (its presolve
    removed rows), each solve makes a new solver."""

    def __init__(self, P: Any, A: Any, b: FloatArray, cones: list[Any], settings: Any):
        self.data = (P, A, b, cones, settings)
        self.kept: Any = None

    def solve(self, q: FloatArray) -> Any:
        if self.kept is not None:
            self.kept.update(q=q)
            return self.kept.solve()
        P, A, b, cones, settings = self.data
        solver = clarabel.DefaultSolver(P, q, A, b, cones, settings)
        if solver.is_data_update_allowed():
            self.kept = solver
        return solver.solve()


def csc(a: FloatArray) -> sp.csc_matrix:
    """A dense matrix in compressed-column form, built directly (scipy's
    general constructors cost more than the small solves they feed)."""
    col, row = np.nonzero(a.T)
    indptr = np.zeros(a.shape[1] + 1, dtype=np.int64)
    np.cumsum(np.bincount(col, minlength=a.shape[1]), out=indptr[1:])
    return sp.csc_matrix((a[row, col], row.astype(np.int64), indptr), shape=a.shape)
