"""Motions the joints do not hold, in the user's words.

A load that works on a free motion has no equilibrium (exit 3): these name
the body and the motion. ``weak_hint`` words the motion held most weakly,
for a solve that fails on a nearly free mechanism.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from jointplay.assembly import Assembly, IntArray
from jointplay.errors import UnboundedMechanismError
from jointplay.geometry import FloatArray, describe_motion
from jointplay.model.joints.base import HOLDS, Coordinate
from jointplay.model.mechanism import Load
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix
from jointplay.settings import TINY, SolverSettings
from jointplay.solver.workspace import limit_rows

if TYPE_CHECKING:
    from jointplay.solver.workspace import WorkspaceData


def check_driven(ws: WorkspaceData, g: FloatArray, loads: Sequence[Load] = ()) -> None:
    """``UnboundedMechanismError`` if the loads' work ``g`` drives a free
    motion; ``loads``: theirs, to name the one that drives it most."""
    if ws.N.shape[1] == 0:
        return
    drive = ws.N.T @ g
    if np.linalg.norm(drive) <= ws.settings.free_motion_rcond * np.linalg.norm(g):
        return
    raise unbounded(ws.asm, ws.N @ drive, ws.settings, loads=loads)


def driven_motion(ws: WorkspaceData, g: FloatArray, fallback: FloatArray) -> FloatArray:
    """A motion that the joints let go on for ever and the loads ``g``
    drive (a body lifting off its point contacts, say), in the simplest
    words found: a translation or a rotation of one body, or of all the
    moving bodies together, along a global axis; else the solver's own
    certificate of unboundedness (``fallback``), without the bodies it
    moves needlessly (``needed_only``)."""
    m, n = ws.m, len(ws.asm.body_names)
    stack = ws.stack
    # each body alone (a translation, or a turn about its reference): unit
    # vectors, whose levels are the columns' norms per cone plus B
    S = stack.segment_matrix  # (rows, cones)
    if ws.sparse:
        rho = sp.csr_matrix(S.T @ stack.A.multiply(stack.A)).sqrt()  # (cones, m)
    else:
        rho = np.sqrt(S.T @ stack.A**2)
    e_cols = column_max(abs(ws.E), m)
    tol = ws.settings.feasibility_tolerance  # a unit motion that moves nothing
    best, best_work = fallback[:m], 0.0
    for sign in (1.0, -1.0):
        held = column_max(rho + sign * stack.B, m) > tol
        works = sign * g
        free = ~held & (e_cols <= tol) & (works > best_work)
        if np.any(free):
            j = int(np.flatnonzero(free)[np.argmax(works[free])])
            best, best_work = sign * np.eye(1, m, j)[0], float(works[j])
    if n > 1:  # all together: a translation (a common turn has no obvious centre)
        for d in [*(np.tile(np.eye(6)[a], n) / np.sqrt(n) for a in range(3))]:
            for sd in (d, -d):
                work = float(g @ sd)
                if work > best_work and holds_no_more(ws, g, np.zeros(m), sd):
                    best, best_work = sd, work
    return best if best_work > 0.0 else needed_only(ws, g, best)


def needed_only(ws: WorkspaceData, g: FloatArray, ray: FloatArray) -> FloatArray:
    """The interior point's ray of unboundedness ``ray`` without the bodies
    it moves needlessly: its round-off can carry a held body along a little
    (a property test's case: a share of 3e-6, pressing on a point contact,
    and the error named that body with the free one). The most moved body
    alone is tried first, then the ray without every body moved too little
    to be named; then bodies one at a time, from the least moved: one is
    left out when, without it, the contacts and rigid rows it shares still
    hold no more than before or than ``feasibility_tolerance`` (the ray at
    unit size), and the loads still drive the motion."""
    size = float(np.linalg.norm(ray))
    if size == 0.0:
        return ray
    d = ray / size
    stack = ws.stack.homogeneous
    share = np.linalg.norm(d.reshape(-1, 6), axis=1)
    moving = np.flatnonzero(share > 0)
    by_share = moving[np.argsort(share[moving], kind="stable")]

    alone = np.zeros_like(d)  # the most moved body alone: the usual case, checked at once
    top = slice(6 * by_share[-1], 6 * by_share[-1] + 6)
    alone[top] = d[top]
    if holds_no_more(ws, g, d, alone):
        return alone * size
    # then every body too little moved to be named (``interior_resolution``) at once:
    # round-off moves them all, and one at a time costs a check each
    faint = by_share[share[by_share] <= ws.settings.interior_resolution * share[by_share[-1]]]
    trial = d.copy()
    trial[(6 * faint[:, None] + np.arange(6)).ravel()] = 0.0
    if len(faint) and holds_no_more(ws, g, d, trial):
        d, by_share = trial, by_share[len(faint) :]
    cone_of_row = np.repeat(np.arange(len(stack.k)), stack.k)
    rows_A, rows_B, rows_E = (_rows_by_body(M, ws.m) for M in (stack.A, stack.B, ws.E))
    for body in by_share[:-1].tolist():
        trial = d.copy()
        trial[6 * body : 6 * body + 6] = 0.0
        cones = np.union1d(cone_of_row[rows_A(body)], rows_B(body))
        if holds_no_more(ws, g, d, trial, cones, rows_E(body)):
            d = trial
    return d * size


def holds_no_more(
    ws: WorkspaceData,
    g: FloatArray,
    d: FloatArray,
    trial: FloatArray,
    cones: IntArray | None = None,
    rows: IntArray | None = None,
) -> bool:
    """Whether the loads ``g`` drive the motion ``trial`` and it moves the
    contacts ``cones`` and rigid rows ``rows`` (all, if None) no further
    toward their limits (centres at 0: for ever) than the motion ``d`` does,
    or than ``feasibility_tolerance`` (motions of unit size)."""
    if float(g @ trial) <= 0.0:
        return False
    tol = ws.settings.feasibility_tolerance
    stack = ws.stack.homogeneous
    sub = stack if cones is None else stack.take(cones)
    if len(sub.k):
        before, after = sub.levels(d)[2], sub.levels(trial)[2]
        if np.any(after > np.maximum(before, tol)):
            return False
    E = ws.E if rows is None else ws.E[rows]
    return not E.shape[0] or bool(np.all(np.abs(E @ trial) <= np.maximum(np.abs(E @ d), tol)))


def _rows_by_body(M: Matrix, m: int) -> Callable[[int], IntArray]:
    """For a body, the rows of ``M`` with an entry in its six columns."""
    C = sp.csc_matrix(M) if M.shape[0] else sp.csc_matrix((0, m))
    C.eliminate_zeros()

    def rows(body: int) -> IntArray:
        return np.unique(C.indices[C.indptr[6 * body] : C.indptr[6 * body + 6]])

    return rows


def check_turns(ws: WorkspaceData, x: FloatArray) -> None:
    """A body that the loads turn by more than ``free_turn_rad`` is not
    held in any sense a small-displacement answer can describe."""
    asm = ws.asm
    if not ws.m:
        return
    turns = np.linalg.norm(x.reshape(-1, 6)[:, 3:], axis=1) * asm.turn
    worst = int(np.argmax(turns))
    if turns[worst] > ws.settings.free_turn_rad:
        raise unbounded(asm, x, ws.settings, one_way=True, turn=float(turns[worst]))


def weak_hint(ws: WorkspaceData) -> str:
    """Words on the motion the joints hold most weakly, for a solve that
    fails: a nearly free mechanism is the usual cause."""
    C = limit_rows(ws)
    if ws.sparse or not C.shape[0]:
        return "Check for nearly coincident joints or a contact almost on an axis."
    C = C - (C @ ws.N) @ ws.N.T  # leave out the free motions
    _, sv, Vt = np.linalg.svd(C)
    keep = sv > ws.settings.free_motion_rcond * sv[0]
    weakest = int(np.flatnonzero(keep)[-1])
    ratio = sv[0] / sv[weakest]
    d = Vt[weakest]
    body = int(np.argmax([np.linalg.norm(d[6 * i : 6 * i + 6]) for i in range(ws.m // 6)]))
    omega, v_origin = ws.asm.body_motion(d, body)
    motion = describe_motion(omega, v_origin, ws.asm.ell)
    return (
        f"The motion the joints hold most weakly is body '{ws.asm.body_names[body]}': "
        f"{motion}, held {ratio:.1e} times less firmly than the best-held one. Nearly "
        "coincident joints or a contact almost on an axis make a mechanism nearly "
        "free: move them apart, or make that motion free (remove the joint) and "
        "balance the loads on it."
    )


def column_max(a: Matrix, m: int) -> FloatArray:
    """Each column's largest entry (0 for no rows)."""
    if not a.shape[0]:
        return np.zeros(m)
    if linalg.is_sparse(a):
        return np.asarray(a.max(axis=0).toarray()).ravel()
    return np.asarray(np.max(a, axis=0))


def unbounded(
    asm: Assembly,
    direction: FloatArray,
    settings: SolverSettings,
    one_way: bool = False,
    turn: float | None = None,
    loads: Sequence[Load] = (),
) -> UnboundedMechanismError:
    """Describe a driven free motion (scaled unknowns) in words (``one_way``:
    a motion the joints stop in one sense only, such as lifting off; ``turn``:
    the motion is held, but only after this many radians; ``loads``: the
    loads, the one that works most on it named)."""
    moves = []
    for i, name in enumerate(asm.body_names):
        omega, v_origin = asm.body_motion(direction, i)
        size = float(np.linalg.norm(asm.s * direction[6 * i : 6 * i + 3])) + asm.ell * float(
            np.linalg.norm(omega)
        )
        moves.append((size, name, omega, v_origin))
    moves.sort(key=lambda t: -t[0])
    biggest = moves[0][0]
    moving = [mv for mv in moves if mv[0] > settings.interior_resolution * biggest]
    _, body, omega, v_origin = moving[0]
    motion = describe_motion(omega, v_origin, asm.ell, signed=one_way)
    others = [mv[1] for mv in moving[1:]]
    with_others = f" (together with {', '.join(repr(o) for o in others)})" if others else ""
    fix = _held_by(asm, direction, settings) or (
        "add a joint or a clearance limit that holds this motion"
    )
    message = (
        f"body '{body}': {motion} is not held by any joint, and the loads drive it{with_others}"
        f"{_driven_most_by(asm, direction, loads)}. There is no equilibrium: {fix}, "
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


def _driven_most_by(asm: Assembly, direction: FloatArray, loads: Sequence[Load]) -> str:
    """', most by loads[0] on 'shaft'': the load that works most on the
    free motion ``direction`` (none named where no load works on it)."""
    work = []
    for load in loads:
        try:
            work.append(float(asm.work_of([load]) @ direction))
        except ValueError:  # on a ground body: no work on any motion
            work.append(0.0)
    if not work or max(work) <= 0.0:
        return ""
    load = loads[int(np.argmax(work))]
    model = asm.model
    if load in model.loads:
        return f", most by loads[{model.loads.index(load)}] on '{load.body}'"
    for case, own in (model.load_cases or {}).items():
        if load in own:
            return f", most by load {own.index(load)} of load case '{case}' on '{load.body}'"
    if load in model.weights():
        return f", most by the weight of '{load.body}'"
    return f", most by a load on '{load.body}'"  # given to the solve, none of the model's


def _held_by(asm: Assembly, direction: FloatArray, settings: SolverSettings) -> str | None:
    """The fix where the free motion turns (or slides) some joints about
    (along) their own axes alone, and their type can hold that with a play
    they are not given: a shaft in bearings without a drive, a linkage whose
    pins all turn. Holding that one coordinate of any of them holds the
    motion. None where no joint is such."""
    moving = []
    for joint, G in zip(asm.model.joints, asm.G, strict=True):
        tw = G.block @ direction[G.cols]  # relative torsor at the joint centre, joint frame
        t, w = tw[:3], tw[3:]
        moving.append((float(np.linalg.norm(t)) + asm.ell * float(np.linalg.norm(w)), joint, t, w))
    top = max((size for size, *_ in moving), default=0.0)
    found: dict[Coordinate, list[str]] = {}
    for size, joint, t, w in moving:
        if size <= settings.interior_resolution * top:
            continue  # still
        own: dict[Coordinate, float] = {"spin": asm.ell * abs(w[0]), "slide": abs(t[0])}
        kind = max(own, key=lambda k: own[k])
        field = HOLDS[kind].field
        # its own coordinate alone moves (to the resolution of a ray's motion)
        alone = size - own[kind] <= settings.interior_resolution * size
        if alone and field in type(joint).model_fields and getattr(joint, field) is None:
            found.setdefault(kind, []).append(repr(joint.name))
    if len(found) != 1:
        return None
    kind, names = found.popitem()
    field, _, _, words, example = HOLDS[kind]
    a = "an" if field[0] in "aeiou" else "a"
    if len(names) == 1:
        return f"give joint {names[0]} {a} {field} ({words}, e.g. {example})"
    verb = "turn about" if kind == "spin" else "slide along"
    return (
        f"joints {', '.join(names)} each {verb} their axes in it: give one of them {a} "
        f"{field} ({words}, e.g. {example})"
    )
