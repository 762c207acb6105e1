"""Many equilibria of one mechanism at once: the same joints, other loads.

Most samples of a study share their active contact set. For one set, the
optimality (KKT) equations of all samples are solved together by Newton's
method with batched linear algebra. A sample is kept only if its own
certificate holds: feasible, every active force strictly positive, forces
balancing its loads, on a face that pins the position down (so the optimum
is unique). The first sample left over goes through the full solver; its
active set is then tried on the others, until none is left.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from . import certificate, linalg
from .assembly import Assembly, BallStack, IntArray
from .geometry import FloatArray
from .settings import TINY

BoolArray = NDArray[np.bool_]

if TYPE_CHECKING:
    from .settings import SolverSettings
    from .solver import Workspace, _FaceKey

#: Samples per batched linear solve (bounds the memory of the (B, n, n) stack).
CHUNK_ENTRIES = 1 << 22


@dataclass(frozen=True)
class BatchSolution:
    """Equilibria of B samples; every row passed its certificate.

    ``x``: scaled unknowns (B, m). ``forces``: ball-contact forces (B, n) in N,
    in the order of ``Assembly.balls``. ``batched[i]`` says whether sample i
    was solved by the batched Newton path (else by the full solver).
    """

    asm: Assembly
    x: FloatArray
    forces: FloatArray
    potential_energy: FloatArray  # (B,) N*mm
    feasibility_mm: FloatArray  # (B,) largest overshoot of a clearance (0: feasible)
    equilibrium_residual: FloatArray  # (B,) relative
    batched: BoolArray  # (B,)
    full_solves: int

    def __len__(self) -> int:
        return int(self.x.shape[0])

    def joint_torsor(self, name: str) -> FloatArray:
        """(B, 6): joint ``name``'s relative torsor (t mm, w rad), joint frame."""
        jdx = [j.name for j in self.asm.model.joints].index(name)
        G = self.asm.G[jdx]
        return self.x[:, G.cols] @ G.block.T

    def body_displacement(self, name: str) -> FloatArray:
        """(B, 6): body ``name``'s translation at the global origin (mm) and rotation (rad)."""
        out = np.zeros((len(self), 6))
        if name not in self.asm.body_index:
            return out  # a ground body
        i = self.asm.body_index[name]
        omega, v_origin = self.asm.body_motion(self.x, i)
        out[:, 3:] = omega
        out[:, :3] = v_origin
        return out

    def gap_used(self) -> FloatArray:
        """(B, n): fraction of each ball contact's play used."""
        stack = self.asm.stack
        return stack.gap_used(stack.levels(self.x)[2])


def solve_batch(ws: Workspace, work: FloatArray, radii: FloatArray | None = None) -> BatchSolution:
    """See ``Workspace.solve_batch``. ``radii`` (B, n): each sample's scaled
    cone radii (``Assembly.balls`` order; default: the model's)."""
    work = np.atleast_2d(np.asarray(work, dtype=float))
    if work.ndim != 2 or work.shape[1] != ws.m:
        raise ValueError(f"work must have shape (B, {ws.m}), not {work.shape}")
    B = work.shape[0]
    norms = np.linalg.norm(work, axis=1)
    if not np.all(np.isfinite(work)):
        raise ValueError("work has non-finite entries")
    _check_driven(ws, work, norms)
    g_hat = np.divide(work, norms[:, None], out=np.zeros_like(work), where=norms[:, None] > 0)
    sigma = ws.softness(norms)  # (B, n): compliance makes the answer depend on |g|
    n_balls = len(ws.balls)
    if radii is None:
        r = np.broadcast_to(ws.stack.r, (B, n_balls))
        varied = False
    else:
        r = np.asarray(radii, dtype=float)
        if r.shape != (B, n_balls):
            raise ValueError(f"radii must have shape ({B}, {n_balls}), not {r.shape}")
        if not np.all(np.isfinite(r)) or np.any(r < 0):
            raise ValueError("radii must be finite and >= 0")
        varied = True
    # the nearest solved sample (loads, and plays when they vary) starts Newton
    features = np.hstack([g_hat, r / max(ws._max_radius, TINY)]) if varied else g_hat

    x = np.zeros((B, ws.m))
    lam = np.zeros((B, n_balls))
    f = np.zeros((B, ws.stack.A.shape[0]))
    batched = np.zeros(B, dtype=bool)
    feas = np.zeros(B)  # each row's certificate, where it was certified
    residual = np.zeros(B)
    pending = np.flatnonzero(norms > 0)
    solved_by_set: dict[_FaceKey, list[IntArray]] = {}  # active set -> solved rows
    # active set -> how often each row failed from it: a row is not tried
    # again after ``batch_give_up`` failures (else every full solve would
    # re-run Newton on every pending row: time quadratic in the samples)
    failures: dict[_FaceKey, IntArray] = {}
    give_up = ws.settings.batch_give_up
    full = 0
    while pending.size:
        # Newton from the nearest solved sample of each known active set, while it helps.
        progress = True
        while progress and pending.size:
            progress = False
            for active, rows in solved_by_set.items():
                failed = failures.setdefault(active, np.zeros(B, dtype=np.intp))
                tried = pending[failed[pending] < give_up]
                if not tried.size:
                    continue
                ref = np.concatenate(rows)
                nearest = ref[cKDTree(features[ref]).query(features[tried])[1]]
                ok, xs, lams, fs, checks = _newton_batch(
                    ws,
                    active,
                    g_hat[tried],
                    sigma[tried],
                    x[nearest],
                    lam[nearest],
                    r[tried],
                )
                failed[tried[~ok]] += 1
                if np.any(ok):
                    won = tried[ok]
                    x[won], lam[won], f[won], batched[won] = xs[ok], lams[ok], fs[ok], True
                    assert checks is not None  # rows were accepted: they were checked
                    feas[won], residual[won] = checks.feasibility[ok], checks.balance[ok]
                    rows.append(won)
                    pending = np.setdiff1d(pending, won, assume_unique=True)
                    progress = True
        if not pending.size:
            break
        first, pending = int(pending[0]), pending[1:]
        solver = ws.with_radii(r[first]) if varied else ws
        solver._last = None
        point = solver._optimum(g_hat[first], sigma[first])
        full += 1
        x[first], lam[first], f[first] = point.x, point.lam, point.f
        assert point.certificate is not None  # _optimum certifies or raises
        feas[first] = point.certificate.feasibility_mm / ws.asm.s
        residual[first] = point.certificate.equilibrium_residual
        if point.active is not None:
            solved_by_set.setdefault(point.active, []).append(np.array([first]))

    return BatchSolution(
        asm=ws.asm,
        x=x,
        forces=lam * norms[:, None] / ws.asm.s,
        potential_energy=-np.einsum("bm,bm->b", work, x),
        feasibility_mm=np.maximum(feas, 0.0) * ws.asm.s,
        equilibrium_residual=residual,
        batched=batched,
        full_solves=full,
    )


def _check_driven(ws: Workspace, work: FloatArray, norms: FloatArray) -> None:
    if ws.N.shape[1] == 0:
        return
    drive = linalg.times(ws.N.T, work)  # work @ N
    bad = np.linalg.norm(drive, axis=1) > ws.settings.drive_tolerance * norms
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        ws._check_driven(work[i])  # raises, naming the body and the motion


def _newton_batch(
    ws: Workspace,
    key: _FaceKey,
    g_hat: FloatArray,
    sigma: FloatArray,
    x0: FloatArray,
    lam0: FloatArray,
    r: FloatArray,
) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray, certificate.Checks | None]:
    """KKT equations of the active set ``key`` for every row of ``g_hat``,
    each from its own start (rows of ``x0``, ``lam0``) and with its own
    cone radii (rows of ``r``).

    Returns (accepted mask, x, full multipliers, force vectors, their
    certificate); a row is accepted only if it converged and passes the
    certificate of a unique optimum.
    """
    B, m = g_hat.shape
    stack = ws.stack
    x = x0.copy()
    lam = np.zeros((B, len(ws.balls)))
    f = np.zeros((B, stack.A.shape[0]))
    face = ws._face(key)
    if not face.determined:  # a tie, or a tilting face (uniqueness depends on x)
        return np.zeros(B, dtype=bool), x, lam, f, None
    surface, linear = key
    ne0 = ws.Eq.shape[0]
    Eq, e = face.Eq, face.e
    eq_soft = np.zeros((B, len(Eq)))
    eq_soft[:, ne0 + face.lam_rows] = sigma[:, list(linear)]
    e_rows = np.repeat(e[None, :], B, axis=0)
    e_rows[:, ne0 + face.lam_rows] = r[:, list(linear)]
    r_surface = r[:, list(surface)]
    na, ne = len(surface), Eq.shape[0]
    n = m + na + ne
    lam_s = lam0[:, list(surface)].copy()
    nu = np.zeros((B, ne))
    conv = np.zeros(B, dtype=bool)
    chunk = max(1, CHUNK_ENTRIES // (n * n))
    for lo in range(0, B, chunk):
        sl = slice(lo, min(B, lo + chunk))
        conv[sl] = _newton_rows(
            face.stack,
            r_surface[sl],
            Eq,
            e_rows[sl],
            eq_soft[sl],
            -g_hat[sl],
            sigma[sl][:, list(surface)],
            x[sl],
            lam_s[sl],
            nu[sl],
            ws.settings,
        )

    lam[:, list(surface)] = lam_s
    v, rho = face.stack.norms(x)
    f[:, face.surface_rows] = face.stack.surface_forces(v, rho, lam_s)
    lam[:, list(linear)] = nu[:, ne0 + face.lam_rows]
    f[:, face.linear_rows] = nu[:, ne0 + face.f_rows]
    lam_a = lam[:, list(surface) + list(linear)]
    positive = ws.settings.positive_force
    strict = np.min(lam_a, axis=1) > positive * np.max(lam_a, axis=1) if lam_a.shape[1] else conv
    if linear:
        lin = stack.take(linear)
        f_norm = np.sqrt(lin.segment_sum(f[:, face.linear_rows] ** 2))
        inside = (f_norm < (1.0 - positive) * lam[:, list(linear)]) | (lin.k == 0)
        strict &= np.all(inside, axis=1)
    checks = certificate.check(ws, g_hat, x, lam, f, sigma, r)
    return conv & strict & checks.passed(ws.settings, ws._max_radius), x, lam, f, checks


def _newton_rows(
    sub: BallStack,
    r: FloatArray,
    Eq: FloatArray,
    e: FloatArray,
    eq_soft: FloatArray,
    q: FloatArray,
    soft: FloatArray,
    x: FloatArray,
    lam: FloatArray,
    nu: FloatArray,
    settings: SolverSettings,
) -> BoolArray:
    """Newton on the KKT equations (see ``solver._newton``), rows in place,
    each row with its own radii ``r`` (B, na) and right sides ``e`` (B, ne);
    returns the converged mask."""
    B, m = q.shape
    A, start, k, Bo = sub.A, sub.start, sub.k, sub.B
    na, ne = len(k), Eq.shape[0]
    n = m + na + ne
    K0 = np.zeros((n, n))
    K0[:m, m + na :] = Eq.T
    K0[m + na :, :m] = Eq
    todo = np.arange(B)
    conv = np.zeros(B, dtype=bool)
    for it in range(settings.batch_newton_steps + 1):
        xs = x[todo]
        v = xs @ A.T
        rho = np.sqrt(np.add.reduceat(v * v, start, axis=1)) if na else np.zeros((len(todo), 0))
        directed = np.all(rho > 0, axis=1)
        if not np.all(directed):  # a contact at its centre has no direction: full solver
            todo, xs, v, rho = todo[directed], xs[directed], v[directed], rho[directed]
        ls = lam[todo]
        u = v / np.repeat(rho, k, axis=1) if na else v
        Ju = np.add.reduceat(A[None, :, :] * u[:, :, None], start, axis=1) if na else None
        grad = q[todo] + nu[todo] @ Eq
        if Ju is not None:
            grad += np.einsum("bi,bim->bm", ls, Ju) + ls @ Bo
        F = np.concatenate(
            [
                grad,
                rho + xs @ Bo.T - r[todo] - soft[todo] * ls,
                xs @ Eq.T - e[todo] - eq_soft[todo] * nu[todo],
            ],
            axis=1,
        )
        err = np.max(np.abs(F), axis=1) if n else np.zeros(len(todo))
        done = err <= settings.round_off
        conv[todo[done]] = True
        keep = ~done
        if it >= settings.batch_give_up:  # far from quadratic convergence: a wrong start or set
            keep &= err <= settings.batch_continue
        if not np.any(keep):
            break
        todo, xs, ls, F, rho = todo[keep], xs[keep], ls[keep], F[keep], rho[keep]
        Kb = np.broadcast_to(K0, (len(todo), n, n)).copy()
        Kb[:, m + np.arange(na), m + np.arange(na)] = -soft[todo]
        Kb[:, m + na + np.arange(ne), m + na + np.arange(ne)] = -eq_soft[todo]
        if Ju is not None:
            Ju = Ju[keep]
            c = ls / rho
            AtCA = (A.T[None, :, :] * np.repeat(c, k, axis=1)[:, None, :]) @ A
            Kb[:, :m, :m] = AtCA - np.einsum("bim,bi,bin->bmn", Ju, c, Ju)
            J = Ju + Bo
            Kb[:, :m, m : m + na] = J.transpose(0, 2, 1)
            Kb[:, m : m + na, :m] = J
        step, regular = solve_rows(Kb, -F)
        todo, step = todo[regular], step[regular]  # a singular row is left to the full solver
        x[todo] += step[:, :m]
        lam[todo] += step[:, m : m + na]
        nu[todo] += step[:, m + na :]
    # rows still in ``todo`` did not converge
    return conv


def solve_rows(K: FloatArray, rhs: FloatArray) -> tuple[FloatArray, BoolArray]:
    """``K[b] step[b] = rhs[b]`` for every row b of a stack of square systems,
    and the mask of the rows that have a solution: an exactly singular row
    gets a zero step and ``False``, the others are solved together."""
    try:
        step = np.asarray(np.linalg.solve(K, rhs[:, :, None])[:, :, 0], dtype=np.float64)
        return step, np.ones(len(K), dtype=bool)
    except np.linalg.LinAlgError:  # some row is singular: find which (one LU each)
        regular: BoolArray = np.linalg.slogdet(K)[0] != 0
    step = np.zeros_like(rhs)
    if np.any(regular):
        step[regular] = np.linalg.solve(K[regular], rhs[regular][:, :, None])[:, :, 0]
    return step, regular
