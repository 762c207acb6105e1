"""The single solve: from a workspace and loads to a certified equilibrium.

Minimizing the loads' potential energy ``-g @ x`` under the clearance cones is
convex, so Clarabel's interior-point answer is the global optimum. Then:

1. *Free motions* that no joint limits form the lineality space ``N`` of the
   cones. If the loads work on any of them there is no equilibrium: we raise
   ``UnboundedMechanismError`` naming the body and the motion (``held.py``).
   Otherwise the answer is pinned orthogonal to ``N`` in the least-norm
   metric, so free unloaded motions come out as exactly 0.
2. *Polish.* The interior-point answer is accurate to its tolerance only.
   From it we read the active contacts and solve the optimality (KKT)
   equations of that active set with Newton's method (``newton.py``), with
   at most ``newton_runs`` corrections of the set where the interior point
   cannot tell a faintly loaded contact from a nearly touching one.
3. *Ties.* When the optimal positions form a face, one more cone program
   picks its least-norm point (``ties.py``).
4. *Forces* by the documented least-squares split (``forces.py``).
5. *Certificate.* Whatever the route, the answer is accepted only if the one
   certificate (``certificate.py``) holds; else once more at a finer
   interior-point tolerance, then declined.

The route: interior point, then Newton on its active set (bounded
corrections); the least-norm face program when the face does not pin the
position; the split; the certificate; once, the finer retry.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from jointplay.errors import SolverError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Load
from jointplay.result import Result, build_result
from jointplay.solver import certificate, conic, faces, forces, held, newton, records, ties
from jointplay.solver.workspace import WorkspaceData


def solve_loads(ws: WorkspaceData, loads: Sequence[Load] | None = None) -> Result:
    """The certified small-displacement equilibrium of ``ws``'s model under
    its loads, or under ``loads`` instead."""
    start = time.perf_counter()
    loads, g = loads_and_work(ws, loads)
    held.check_driven(ws, g, loads)
    scale = load_scale(ws, float(np.linalg.norm(g)))
    g_hat = g / scale if scale else g
    point = optimum(ws, g_hat, ws.softness(scale))
    return result_of(ws, point, scale, loads, g, start)


def loads_and_work(
    ws: WorkspaceData, loads: Sequence[Load] | None
) -> tuple[tuple[Load, ...], FloatArray]:
    """The loads (the model's own if None) and their work on the unknowns."""
    if loads is None:
        return tuple(ws.asm.model.loads_of(None)), ws.asm.g
    loads = tuple(loads)
    return loads, ws.asm.work_of(loads)


def result_of(
    ws: WorkspaceData,
    point: records.Point,
    scale: float,
    loads: Sequence[Load],
    g: FloatArray,
    start: float,
) -> Result:
    """The ``Result`` of a certified ``point`` (scaled by ``scale``, the
    loads' ``load_scale``), timed from ``start``."""
    assert point.certificate is not None
    to_newton = scale / ws.asm.s  # scaled multipliers -> N
    g_hat = g / scale if scale else g
    nu = point.nu if point.nu is not None else rigid_multipliers(ws, g_hat, point)
    rigid = nu * to_newton
    elapsed = time.perf_counter() - start
    result = build_result(
        ws.asm,
        point.x,
        point.lam * to_newton,
        point.f * to_newton,
        rigid,
        point.certificate,
        elapsed,
        ws.free_motions,
        tuple(loads),
        g,
        ws.settings,
        point.by_rule,
    )
    # The certificate balances the forces in the solver's scaled unknowns;
    # per body and in newtons (Result.check) a badly scaled mechanism can
    # fall short. A number that fails its own check is not printed.
    tolerance = ws.settings.equilibrium_tolerance
    if result.equilibrium_residual > tolerance:
        raise SolverError(
            "the solver's answer could not be certified: its contact forces balance the "
            f"loads on each body only to {result.equilibrium_residual:.3g} of the largest "
            f"force ({tolerance:g} is required). "
            + held.weak_hint(ws)
            + " If not, please report this model."
        )
    return result


#: Why a tie's answer may fail its certificate (``optimum``'s decline).
TIE_HINT = (
    "The optimal positions are not unique here (a play that no load takes), and the "
    "least-norm one was not found to these limits: degenerate mechanisms, where contacts "
    "touch with no force (shafts each in a bearing and coupled to the next), can do this. "
)


def load_scale(ws: WorkspaceData, g_norm: float) -> float:
    """What the scaled problem divides the loads' work by: its size ``|g|``,
    or the preload of compliant contacts that deviations press past their
    play, if larger. Such a spring pushes at no load at all; scaled by ``|g|``
    alone, a faint load made it 1e7 times too stiff and the parts were "not
    assembled". The preload is the largest force of the no-load compliant
    program (penetrations within the positions' round-off count as none)."""
    if ws.preload is None:  # found once per workspace: it depends on the plays alone
        ws.preload = _preload(ws)
    return max(g_norm, ws.preload)


def _preload(ws: WorkspaceData) -> float:
    soft = ws.stack.spring > 0
    zero = np.zeros(ws.m)
    if not np.any(soft) or np.all(ws.stack.levels(zero)[2] <= ws.stack.r):
        return 0.0  # no spring, or 0 fits every play: nothing is pressed at no load
    try:
        rest = interior_point_compliant(ws, zero, ws.softness(1.0))
    except SolverError:  # as an answer's route: the one retry (``optimum``)
        fine = retry_of(ws)
        if fine is None:
            raise
        rest = interior_point_compliant(fine, zero, ws.softness(1.0))
    penetration = ws.softness(1.0)[soft] * rest.lam[soft]
    if np.max(penetration) <= ws.settings.feasibility_tolerance * ws.max_radius:
        return 0.0
    return float(np.max(rest.lam))


def split(
    ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray, point: records.Point
) -> records.Point:
    """The optimum with the least-squares split of its forces
    (``forces.least_squares_split``: forces from the positions, by the
    documented rule) and its rigid multipliers, if that split certifies;
    else the route's own forces."""
    st = ws.settings
    apex = st.feasibility_tolerance * ws.max_radius  # positions' round-off
    nu = rigid_multipliers(ws, g_hat, point)
    unique_on = point.active if faces.pins_by_newton(point) and not np.any(sigma) else None
    shared = forces.least_squares_split(
        ws.asm, point.x, point.lam, point.f, nu, g_hat, apex, st, unique_on
    )
    if shared is None:  # the only split that balances the loads
        return replace(point, nu=nu)
    if shared.found:
        trial = replace(point, lam=shared.lam, f=shared.f, nu=shared.nu, certificate=None)
        cert = certificate.certify(ws, g_hat, sigma, trial, shared.nu)
        if cert.certified:
            trial.certificate, trial.by_rule = cert, shared.rule
            return trial
    return replace(point, nu=nu, by_rule=False)


def rigid_multipliers(ws: WorkspaceData, g_hat: FloatArray, point: records.Point) -> FloatArray:
    """Forces in the rigid rows (scaled): what the contacts leave of the loads.

    Statically indeterminate rigid joints share the load in the least-squares way.
    """
    rest = g_hat - ws.stack.adjoint(point.f, point.lam)
    return np.asarray(ws.balance.rigid_multipliers(rest[None])[0])


def optimum(ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray | None = None) -> records.Point:
    """The certified optimum for loads ``g_hat`` (unit, smaller beside a
    preload, or 0 for no load: ``load_scale``), with contact softness
    ``sigma`` (default: every contact hard)."""
    sigma = np.zeros(len(ws.balls)) if sigma is None else sigma
    loaded = bool(np.any(g_hat) or np.any(sigma))
    failed: SolverError | None = None
    try:
        point = answer(ws, g_hat, sigma, loaded)
        certified = point.certificate is not None and point.certificate.certified
    except SolverError as exc:  # a step of the route could not be done
        failed, certified = exc, False
    fine = retry_of(ws) if not certified and loaded else None
    if fine is not None:
        # a nearly degenerate mechanism can leave the interior-point answer
        # (and its polish) 1e-7 mm off at the usual tolerance, or a step of
        # its route undone: once more, finer and on another path
        try:
            return optimum(fine, g_hat, sigma)
        except SolverError:
            pass
    if failed is not None:
        raise failed
    if not certified:
        raise SolverError(
            "the solver's answer could not be certified: "
            + certificate.refusal(ws, g_hat, sigma, point)
            + ". "
            + (TIE_HINT if point.tie is not None else "")
            + held.weak_hint(ws)
            + " If not, please report this model."
        )
    return point


def retry_of(ws: WorkspaceData) -> WorkspaceData | None:
    """The one retry's workspace (``SolverSettings.retry``), or None if
    ``ws`` is the retry's."""
    if ws.settings.ipm_tolerance <= ws.settings.fine_ipm_tolerance:
        return None
    return ws.with_settings(ws.settings.retry())


def answer(ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray, loaded: bool) -> records.Point:
    """The route's answer, with its certificate (which may refuse it)."""
    if not loaded:
        return certified(ws, g_hat, sigma, rest_position(ws))
    return certified(ws, g_hat, sigma, split(ws, g_hat, sigma, contacts_optimum(ws, g_hat, sigma)))


def certified(
    ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray, point: records.Point
) -> records.Point:
    """``point`` with its certificate (which may refuse it). A cone with no
    play and no offset holds only at its apex: whatever the route, its force
    is |f| (the interior point's lam may be any above it)."""
    tight = np.flatnonzero(ws.stack.r == 0).tolist()
    if tight:
        before = point.lam[tight].copy()
        faces.rimless_forces(ws.stack, tight, point.lam, point.f)
        if not np.array_equal(before, point.lam[tight]):
            point.certificate = None
    if point.certificate is None:
        point.certificate = certificate.certify(ws, g_hat, sigma, point, point.nu)
    return point


def contacts_optimum(ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray) -> records.Point:
    """The optimal positions, with the route's forces (relative to ``g_hat``,
    uncertified), found under the contacts' share of the loads
    (``WorkspaceData.contacts_share``): the same program, since the rigid rows
    hold every position at ``E x = 0``, but its forces are the contacts' own,
    not round-off against what a rigid joint carries. With no share the
    contacts carry nothing, and the rest position is the answer. Not with
    compliant contacts: a deviation may press one past its play, and then it
    pushes whatever the loads (its force does not scale with the share: a
    weld-held load left it 1e10 times the share, or no program at all)."""
    g_c, share = ws.contacts_share(g_hat) if not np.any(sigma) else (g_hat, 1.0)
    if share <= ws.settings.round_off:
        return rest_position(ws, "no contact load")
    sigma_c = sigma * share  # the compliance of loads of the share's size
    point = interior_point(ws, g_c, sigma_c)
    held.check_turns(ws, point.x)  # before polishing, which a nearly free body defeats
    point = polish(ws, g_c, sigma_c, point)
    if g_c is g_hat:  # the whole load: the route's certificate is the answer's
        return replace(point, lam=point.lam.copy(), f=point.f.copy(), nu=None)
    return replace(point, lam=point.lam * share, f=point.f * share, nu=None, certificate=None)


def rest_position(ws: WorkspaceData, method: str = "no load") -> records.Point:
    """The answer with no load (or none the contacts carry, ``method``):
    every feasible position is optimal, so the least-norm one (the tie
    rule): 0, unless deviations move the clearances off it; then one cone
    program on the whole feasible set, polished."""
    lam, f = np.zeros(len(ws.balls)), np.zeros(ws.stack.A.shape[0])
    zero = np.zeros(ws.m)
    if np.all(ws.stack.levels(zero)[2] <= ws.stack.r):  # 0 fits: no deviation, or small ones
        return records.Point(zero, lam, f, method=method)
    e = np.zeros(ws.Eq.shape[0])
    prog = conic.cone_program(ws, ws.asm.metric_matrix, ws.Eq, e, ws.stack)
    sol = conic.run(ws, prog, np.zeros(ws.m))  # no position at all: UnassembledError
    z = np.asarray(sol.z)
    x = ties.polish_least_norm(
        ws, np.asarray(sol.x), z[prog.soc_first], z[prog.f_rows], ws.stack, ws.Eq, e
    )
    return records.Point(x, lam, f, method=f"{method}: the least-norm position")


def interior_point(ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray) -> records.Point:
    if np.any(sigma > 0):
        return interior_point_compliant(ws, g_hat, sigma)
    prog = conic.interior_program(ws)
    sol = conic.run(ws, prog, -g_hat)
    z = np.asarray(sol.z)
    return records.Point(
        np.asarray(sol.x), z[prog.soc_first], z[prog.f_rows], iterations=sol.iterations
    )


def interior_point_compliant(
    ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray
) -> records.Point:
    """The cone program with a penetration ``p_i >= 0`` per compliant contact:
    ``|A_i x| <= r_i + p_i`` and energy ``-g_hat x + sum p_i^2 / (2 sigma_i)``."""
    soft = np.flatnonzero(ws.stack.spring > 0)
    if ws.compliant_program is None:  # built on first use, then kept
        ws.compliant_program = conic.with_penetrations(conic.interior_program(ws), soft)
    prog = conic.softened(ws.compliant_program, soft, sigma)
    sol = conic.run(ws, prog, np.concatenate([-g_hat, np.zeros(len(soft))]))
    z = np.asarray(sol.z)
    x = np.asarray(sol.x)[: ws.m]
    return records.Point(x, z[prog.soc_first], z[prog.f_rows], iterations=sol.iterations)


def polish(
    ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray, point: records.Point
) -> records.Point:
    key = faces.active_set(ws, point.x, point.lam, point.f, ws.stack)
    optimum = refine_active(ws, g_hat, sigma, point, key)
    if optimum is None:  # the interior point as it is, if it certifies
        optimum = point
    elif optimum.active is not None:
        key = optimum.active
    if faces.pins_by_newton(optimum) or faces.is_determined(ws, faces.face_of(ws, key), optimum.x):
        return optimum
    optimum.active = None  # the face does not pin x: it is not unique
    tied = ties.least_norm(ws, sigma, optimum, key)
    tied.tie = key  # but the batch solves other loads on it (``Face.tie_rows``)
    return tied


def refine_active(
    ws: WorkspaceData,
    g_hat: FloatArray,
    sigma: FloatArray,
    point: records.Point,
    key: records.FaceKey,
) -> records.Point | None:
    """A certified optimum from the KKT equations of the active set ``key``
    the interior point shows, with at most ``newton_runs`` corrections of
    that set (``active_set_steps``): an interior-point answer to 1e-10
    cannot always tell a faintly loaded contact from a nearly touching one.
    The retry's set (``retry_of``) adds every contact whose force the
    balance cannot drop: a faint push under a large turn is one that the
    interior point leaves short of its limit. The optimum need not be
    unique (a tie)."""
    stack = ws.stack
    if not len(stack.k):
        return None
    _, rho, _ = stack.levels(point.x)
    r = np.where(stack.r > 0, stack.r, ws.max_radius)
    f_norm = np.sqrt(stack.segment_sum(point.f * point.f))
    st = ws.settings
    at_apex = (stack.k == 0) | (
        (rho <= st.interior_resolution * r) & (f_norm < (1.0 - st.interior_resolution) * point.lam)
    )
    active = {*key[0], *key[1]}
    if retry_of(ws) is None:
        top = float(np.max(point.lam, initial=0.0))
        active |= set(np.flatnonzero(point.lam > st.equilibrium_tolerance * top).tolist())
    return active_set_steps(ws, g_hat, sigma, point, active, at_apex)


def active_set_steps(
    ws: WorkspaceData,
    g_hat: FloatArray,
    sigma: FloatArray,
    point: records.Point,
    active: set[int],
    at_apex: NDArray[np.bool_],
) -> records.Point | None:
    """The active-set corrections of ``refine_active`` from ``active``, each
    a Newton run, at most ``newton_runs`` (a set met before ends them)."""
    stack = ws.stack
    r = np.where(stack.r > 0, stack.r, ws.max_radius)
    lam_scale = float(np.max(np.abs(point.lam)))
    x, lam = point.x, point.lam
    st = ws.settings
    seen: set[frozenset[int]] = set()
    for _ in range(st.newton_runs):
        if frozenset(active) in seen:
            return None
        seen.add(frozenset(active))
        trial_key: records.FaceKey = (
            tuple(sorted(i for i in active if not at_apex[i])),
            tuple(sorted(i for i in active if at_apex[i])),
        )
        trial = newton.kkt_point(
            ws, g_hat, sigma, trial_key, x, lam, point.iterations, "polished", pinned=False
        )
        if trial is None:
            return None
        weak = newton.weak_forces(ws, trial, trial_key)
        _, _, level = stack.levels(trial.x)
        past = np.flatnonzero((level - stack.r) / r > st.feasibility_tolerance)
        past = past[[i not in active for i in past]]
        if not past.size:
            trial.certificate = certificate.certify(ws, g_hat, sigma, trial)
            if trial.certificate.certified:
                # a cone with no force (to round-off) does not bound the tie
                # (and Newton's system then says nothing of the face left)
                unloaded = set(weak.tolist())
                trial.active = (
                    tuple(i for i in trial_key[0] if i not in unloaded),
                    tuple(i for i in trial_key[1] if i not in unloaded),
                )
                return trial
            if not weak.size:
                return None
            # Newton's forces on a degenerate set (more contacts touch than
            # the positions need) are one split of many: one may pull where
            # another pushes only, and then these positions are optimal
            shared = split_optimum(ws, g_hat, sigma, trial, trial_key)
            if shared is not None:
                return shared
        # a face at its apex whose force reaches its cone's edge tilts
        # onto its surface; the other weak cones leave the set
        lam_top = float(np.max(trial.lam, initial=0.0))
        tilts = {
            int(i)
            for i in weak
            if at_apex[i] and ws.stack.has_rim[i] and trial.lam[i] > st.positive_force * lam_top
        }
        at_apex = at_apex.copy()
        at_apex[list(tilts)] = False
        # one at a time, the most negative: dropped all at once, the contacts
        # of a degenerate bearing chain that touch with no force left and
        # rejoined round after round, and chains of 19, 20 and 22 shafts were
        # declined (the textbook rule, as in a primal active-set method)
        leaving = set(weak.tolist()) - tilts
        if leaving and not past.size and not tilts:
            leaving = {min(leaving, key=lambda i: (trial.lam[i], i))}
        active = (active - leaving) | set(past.tolist())
        x, lam = trial.x, np.maximum(trial.lam, st.positive_force * lam_scale)
    return None


def split_optimum(
    ws: WorkspaceData,
    g_hat: FloatArray,
    sigma: FloatArray,
    trial: records.Point,
    key: records.FaceKey,
) -> records.Point | None:
    """``trial`` (a round's positions, every contact of ``key`` touching,
    none past) with the split's forces on its touching contacts
    (``forces.least_squares_split``), if they certify: then its positions
    are optimal whatever Newton's forces on a degenerate set. Hard models."""
    if np.any(sigma):
        return None
    apex = ws.settings.feasibility_tolerance * ws.max_radius
    nu = rigid_multipliers(ws, g_hat, trial)
    shared = forces.least_squares_split(
        ws.asm, trial.x, trial.lam, trial.f, nu, g_hat, apex, ws.settings, None
    )
    if shared is None or not shared.found:
        return None
    point = replace(trial, lam=shared.lam, f=shared.f, nu=shared.nu, certificate=None)
    point.certificate = certificate.certify(ws, g_hat, sigma, point, shared.nu)
    if not point.certificate.certified:
        return None
    # a contact with no force (to round-off) does not bound the tie
    loaded = shared.lam > ws.settings.positive_force * float(np.max(shared.lam))
    point.active = (
        tuple(i for i in key[0] if loaded[i]),
        tuple(i for i in key[1] if loaded[i]),
    )
    return point
