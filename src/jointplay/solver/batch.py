"""Many equilibria of one mechanism at once: the same joints, other loads.

Most samples of a study share their active contact set. For one set, the
optimality (KKT) equations of all samples are solved together by Newton's
method with batched linear algebra, on an independent part of the set's
rows where its contacts are redundant. Forces that are one of many (a
redundant set, or contacts touching outside it) take the documented split.
A sample is kept only if its own certificate holds and its optimum is the
answer: the only one where its loaded contacts pin the position, or, on a
tie, the least-norm point of a face that every contact of the set loads.
The first sample left over goes through the full solver; its active set is
then tried on the others, until none is left.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from jointplay.assembly import Assembly, IntArray
from jointplay.errors import SolverError, UnassembledError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Load
from jointplay.numerics import linalg
from jointplay.numerics.linalg import Matrix
from jointplay.result import Result
from jointplay.settings import DEFAULT, TINY, SolverSettings
from jointplay.solver import certificate, faces, forces, held, newton, pipeline
from jointplay.solver.records import Face, FaceKey, Point

BoolArray = NDArray[np.bool_]

if TYPE_CHECKING:
    from jointplay.settings import SolverSettings
    from jointplay.solver.workspace import WorkspaceData

#: Entries of the (rows, n, n) stack of one batched Newton (8 MB): fewer
#: rows cost Python overhead per call, more leave the cache.
CHUNK_ENTRIES = 1 << 20


@dataclass(frozen=True)
class BatchSolution:
    """Equilibria of B samples; every row passed its certificate.

    ``x``: scaled unknowns (B, m). ``forces``: ball-contact forces (B, n) in N,
    in the order of ``Assembly.balls`` (None when asked for positions
    only). ``batched[i]`` says whether sample i
    was solved by the batched Newton path (else by the full solver).
    ``assembled[i]`` is False for a sample whose own deviations leave no
    position inside every clearance (its parts cannot be put together): its
    rows are NaN.
    """

    asm: Assembly
    x: FloatArray
    forces: FloatArray | None
    potential_energy: FloatArray  # (B,) N*mm
    feasibility_mm: FloatArray  # (B,) largest overshoot of a clearance (0: feasible)
    equilibrium_residual: FloatArray  # (B,) relative
    batched: BoolArray  # (B,)
    full_solves: int
    assembled: BoolArray  # (B,)
    #: each row's answer as a ``Start`` for the same sample in a nearby batch
    #: (None where it has no active set), when asked (``own_starts``)
    own_starts: tuple[Start | None, ...] | None = None

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

    def gap_used(self, settings: SolverSettings = DEFAULT) -> FloatArray:
        """(B, n): fraction of each ball contact's play used."""
        stack = self.asm.stack
        reach = settings.feasibility_tolerance * stack.largest_play()
        return stack.gap_used(stack.levels(self.x)[2], reach)


@dataclass(frozen=True)
class Start:
    """A sample solved before a batch, to start its Newton like a sample the
    batch solved itself: unit loads, scaled radii and centres, the answer's
    scaled unknowns and multipliers, and its active set (or a tie's)."""

    g_hat: FloatArray
    r: FloatArray
    c: FloatArray
    x: FloatArray
    lam: FloatArray
    f: FloatArray
    key: FaceKey


def extrapolated(before: Start | None, last: Start | None) -> Start | None:
    """The start for the next of evenly spaced nearby models (a motion's
    poses): ``last`` moved on by its change since ``before`` when both hold
    one active set, its loads, plays and centres with its answer (Newton's
    start, not an answer: it takes the pose's curvature in fewer steps, and
    the batch predicts from it only what the extrapolation misses), else
    ``last``."""
    if before is None or last is None or before.key != last.key:
        return last

    def on(a: FloatArray, b: FloatArray) -> FloatArray:
        return b + (b - a)

    return replace(
        last,
        g_hat=on(before.g_hat, last.g_hat),
        r=on(before.r, last.r),
        c=on(before.c, last.c),
        x=on(before.x, last.x),
        lam=np.maximum(on(before.lam, last.lam), 0.0),
        f=on(before.f, last.f),
    )


def solved_start(
    ws: WorkspaceData,
    work: FloatArray,
    radii: FloatArray | None = None,
    centres: FloatArray | None = None,
) -> Start | None:
    """The full solve of one sample (loads' work ``work``, and the model's
    plays and centres unless given) as a ``Start``; None for a large (sparse)
    mechanism, whose rows are solved one by one, for no load, for a sample
    the full solver declines, and for an answer with no active set to start
    from."""
    norm = float(np.linalg.norm(work))
    if ws.asm.sparse or norm == 0.0:
        return None
    r = ws.stack.r if radii is None else np.asarray(radii, dtype=float)
    c = ws.stack.centres() if centres is None else np.asarray(centres, dtype=float)
    solver = ws if radii is None and centres is None else ws.with_radii(r, centres)
    try:
        with linalg.one_blas_thread():
            scale = pipeline.load_scale(solver, norm)
            g_hat = np.asarray(work, dtype=float) / scale
            point = pipeline.optimum(solver, g_hat, ws.softness(scale))
    except (UnassembledError, SolverError):
        return None  # no start: the batch meets this sample's trouble itself, if at all
    return _start_of(point, g_hat, r, c)


def _start_of(point: Point, g_hat: FloatArray, r: FloatArray, c: FloatArray) -> Start | None:
    """A full solve's answer as a ``Start``; None where it has no active set
    (nor a tie's) to start from."""
    key = point.active if point.active is not None else point.tie
    return None if key is None else Start(g_hat, r, c, point.x, point.lam, point.f, key)


def _check_starts(ws: WorkspaceData, starts: Sequence[Start]) -> None:
    shapes = (ws.m, len(ws.balls), ws.stack.A.shape[0])
    for known in starts:
        parts = (known.g_hat, known.r, known.c, known.x, known.lam, known.f)
        sizes = (shapes[0], shapes[1], shapes[2], shapes[0], shapes[1], shapes[2])
        if any(np.shape(p) != (n,) for p, n in zip(parts, sizes, strict=True)):
            raise ValueError("starts must come from this workspace's model (batch.solved_start)")
        if not all(np.all(np.isfinite(p)) for p in parts):
            raise ValueError("starts must be finite")


def solve_batch(
    ws: WorkspaceData,
    work: FloatArray,
    radii: FloatArray | None = None,
    centres: FloatArray | None = None,
    *,
    forces: bool = True,
    starts: Sequence[Start] = (),
    own_starts: Sequence[Start | None] | None = None,
) -> BatchSolution:
    """See ``Workspace.solve_batch``. ``radii`` (B, n): each sample's scaled
    cone radii (``Assembly.balls`` order; default: the model's); ``centres``
    (B, rows): each sample's cone centres, stacked like ``stack.A``'s rows
    (a deviation of the joints' features; default: the model's). In one
    BLAS thread: the work is many small matrices, which more threads only
    slow down, and a study's processes would compete for the cores."""
    with linalg.one_blas_thread():
        return _solve_batch(ws, work, radii, centres, forces, starts, own_starts)


def follow(
    ws: WorkspaceData, start: Start | None, loads: Sequence[Load] | None = None
) -> tuple[Result, Start | None]:
    """The certified equilibrium of ``ws``'s model under its loads (or
    ``loads``) as a batch of one whose Newton starts from ``start`` (the
    same sample's answer on a nearby model: the pose before, in a motion),
    with its answer as the start of the next; the full solve where there is
    no start or Newton's answer from it is not the optimum. Either way its
    forces are the single solve's: the split, rigid joints' included
    (``pipeline.split``), then the certificate."""
    began = time.perf_counter()
    with linalg.one_blas_thread():
        loads, g = pipeline.loads_and_work(ws, loads)
        held.check_driven(ws, g, loads)
        scale = pipeline.load_scale(ws, float(np.linalg.norm(g)))
        g_hat = g / scale if scale else g
        sigma = ws.softness(scale)
        dense = not ws.asm.sparse and scale > 0
        point: Point | None = None
        if start is not None and dense:
            followed = _solve_batch(ws, g[None], None, None, True, (), (start,)).own_starts
            after = None if followed is None else followed[0]
            if after is not None:
                found = Point(after.x, after.lam, after.f, method="Newton from a nearby answer")
                found = pipeline.certified(
                    ws, g_hat, sigma, pipeline.split(ws, g_hat, sigma, found)
                )
                if found.certificate is not None and found.certificate.certified:
                    point = found
        if point is None:
            point = pipeline.optimum(ws, g_hat, sigma)
            after = _start_of(point, g_hat, ws.stack.r, ws.stack.centres()) if dense else None
        return pipeline.result_of(ws, point, scale, loads, g, began), after


def _solve_batch(
    ws: WorkspaceData,
    work: FloatArray,
    radii: FloatArray | None,
    centres: FloatArray | None,
    split_forces: bool,
    starts: Sequence[Start] = (),
    own_starts: Sequence[Start | None] | None = None,
) -> BatchSolution:
    from scipy.spatial import cKDTree  # here: a single solve need not import it

    work = np.atleast_2d(np.asarray(work, dtype=float))
    if work.ndim != 2 or work.shape[1] != ws.m:
        raise ValueError(f"work must have shape (B, {ws.m}), not {work.shape}")
    B = work.shape[0]
    norms = np.linalg.norm(work, axis=1)
    if not np.all(np.isfinite(work)):
        raise ValueError("work has non-finite entries")
    _check_driven(ws, work, norms)
    n_balls = len(ws.balls)
    r = _per_row("radii", radii, ws.stack.r, B)  # < 0: a limit a deviation moved in past its play
    c = _per_row("centres", centres, ws.stack.centres(), B)
    varied = radii is not None or centres is not None
    # each row's loads divided by their size, or by the preload of springs
    # its deviations press, if larger (pipeline.load_scale): one preload for
    # the model's own plays; with varied ones, an unloaded row's own now and
    # a faintly loaded row's own if it goes to a full solve
    if varied:
        scales = _preloads(ws, norms, r, c)
    else:
        scales = np.maximum(norms, pipeline.load_scale(ws, 0.0))
    g_hat = np.divide(work, scales[:, None], out=np.zeros_like(work), where=scales[:, None] > 0)
    sigma = ws.softness(scales)  # (B, n): compliance makes the answer depend on the scale
    # the starts follow the samples as rows solved already (dense mechanisms:
    # a large one's rows are solved one by one)
    _check_starts(ws, starts)
    starts = starts if not ws.asm.sparse else ()
    # each row's own start (the same sample in a nearby batch), tried first
    if own_starts is not None and len(own_starts) != B:
        raise ValueError(f"own_starts must have one entry per row ({B}), not {len(own_starts)}")
    own = [
        (row, known)
        for row, known in enumerate(own_starts or ())
        if known is not None and not ws.asm.sparse and scales[row] > 0
    ]
    _check_starts(ws, [known for _, known in own])
    before = [*starts, *(known for _, known in own)]
    if before:
        g_hat = np.vstack([g_hat, *(s.g_hat for s in before)])
        r = np.vstack([r, *(s.r for s in before)])
        c = np.vstack([c, *(s.c for s in before)])
        sigma = np.vstack([sigma, np.zeros((len(before), n_balls))])  # read for samples only
    rows_all = B + len(before)
    # the nearest solved sample (loads, and plays when they vary) starts Newton
    scale = max(ws.max_radius, TINY)
    features = np.hstack([g_hat, r / scale, c / scale]) if varied else g_hat

    x = np.zeros((rows_all, ws.m))
    lam = np.zeros((rows_all, n_balls))
    f = np.zeros((rows_all, ws.stack.A.shape[0]))
    batched = np.zeros(rows_all, dtype=bool)
    assembled = np.ones(rows_all, dtype=bool)
    feas = np.zeros(rows_all)  # each row's certificate, where it was certified
    residual = np.zeros(rows_all)
    pending = np.flatnonzero(scales > 0)
    solved_by_set: dict[FaceKey, list[IntArray]] = {}  # active set -> solved rows
    keys: list[FaceKey | None] = [None] * B  # each row's active set (or tie's), once solved
    for j, known in enumerate(before):
        x[B + j], lam[B + j], f[B + j] = known.x, known.lam, known.f
        if j < len(starts):
            solved_by_set.setdefault(known.key, []).append(np.array([B + j]))
    # active set -> how often each row failed from it: a row is not tried
    # again after ``batch_give_up`` failures (else every full solve would
    # re-run Newton on every pending row: time quadratic in the samples)
    failures: dict[FaceKey, IntArray] = {}
    # active set -> each row's distance to the start it was last tried from
    start_distance: dict[FaceKey, FloatArray] = {}
    queried: dict[FaceKey, int] = {}  # active set -> its solved rows already queried
    give_up = ws.settings.batch_give_up
    guess_rows = ws.settings.batch_guess_rows
    full = 0
    # the batched Newton works on dense stacks; a large (sparse) mechanism's
    # rows are solved one by one
    dense = not ws.asm.sparse
    # rows per Newton batch (n at most the unknowns and all multipliers)
    n_most = ws.m + n_balls + ws.stack.A.shape[0] + ws.Eq.shape[0]
    chunk = max(1, CHUNK_ENTRIES // n_most**2)

    def take(now: IntArray, ok: BoolArray, solved: tuple[Any, ...], active: FaceKey) -> IntArray:
        """Keep the rows ``now[ok]`` Newton solved on ``active``."""
        xs, lams, fs, checks = solved
        won = now[ok]
        x[won], lam[won], f[won], batched[won] = xs[ok], lams[ok], fs[ok], True
        assert checks is not None  # rows were accepted: they were checked
        feas[won], residual[won] = checks.feasibility[ok], checks.balance[ok]
        for row in won.tolist():
            keys[row] = active
        return won

    own_sets: dict[FaceKey, list[tuple[int, int]]] = {}
    for j, (sample, known) in enumerate(own):
        own_sets.setdefault(known.key, []).append((sample, B + len(starts) + j))
    for active, pairs in own_sets.items():
        for part in range(0, len(pairs), chunk):
            now, near = np.array(pairs[part : part + chunk]).T
            ok, xs, lams, fs, checks, _ = _newton_batch(
                ws, active, g_hat[now], sigma[now], x[near], lam[near], f[near],
                r[now], c[now], (r[near], c[near]), g_hat[near],
            )  # fmt: skip
            if np.any(ok):
                won = take(now, ok, (xs, lams, fs, checks), active)
                solved_by_set.setdefault(active, []).append(won)
                pending = np.setdiff1d(pending, won, assume_unique=True)
    while pending.size:
        # Newton from the nearest solved sample of each known active set, while it helps.
        progress = True
        while progress and pending.size:
            progress = False
            for active, rows in solved_by_set.items():
                failed = failures.setdefault(active, np.zeros(B, dtype=np.intp))
                start_distance.setdefault(active, np.full(B, np.inf))
                ref = np.concatenate(rows)
                # a row that failed on this set is tried again only from a nearer
                # start: one among the rows solved on it since it was last tried
                new = ref[queried.get(active, 0) :]
                queried[active] = len(ref)
                tried = pending[failed[pending] < give_up]
                if not tried.size or not new.size:
                    continue
                dist, at = cKDTree(features[new]).query(features[tried])
                closer = dist < start_distance[active][tried]
                tried, dist, nearest = tried[closer], dist[closer], new[at[closer]]
                start_distance[active][tried] = dist
                for part in range(0, len(tried), chunk):
                    now, near = tried[part : part + chunk], nearest[part : part + chunk]
                    ok, xs, lams, fs, checks, wrong_set = _newton_batch(
                        ws,
                        active,
                        g_hat[now],
                        sigma[now],
                        x[near],
                        lam[near],
                        f[near],
                        r[now],
                        c[now],
                        (r[near], c[near]),
                        g_hat[near],
                    )
                    failed[now[~ok]] += 1
                    failed[now[wrong_set]] = give_up
                    guess = part == 0 and np.all(near >= B) and len(now) >= guess_rows
                    if guess and not np.any(ok):
                        # a start from before the batch (a study's nominal
                        # answer) is a guess: a set that fails on every row of
                        # its first part is not tried on the rest from it (a
                        # tilted guide's samples all lie on another set); a
                        # row solved on the set later may start them
                        start_distance[active][tried[chunk:]] = np.inf
                        break
                    if np.any(ok):
                        won = take(now, ok, (xs, lams, fs, checks), active)
                        rows.append(won)
                        pending = np.setdiff1d(pending, won, assume_unique=True)
                        progress = True
        if not pending.size:
            break
        first, pending = int(pending[0]), pending[1:]
        solver = ws.with_radii(r[first], c[first]) if varied else ws
        full += 1
        try:
            if varied and scales[first] == norms[first]:  # a faint load beside a preload?
                scales[first] = pipeline.load_scale(solver, norms[first])
                g_hat[first] = work[first] / scales[first]
                sigma[first] = ws.softness(scales[first])
            point = pipeline.optimum(solver, g_hat[first], sigma[first])
        except UnassembledError:
            if not varied:
                raise  # the model's own parts
            assembled[first] = False
            continue
        x[first], lam[first], f[first] = point.x, point.lam, point.f
        assert point.certificate is not None  # optimum certifies or raises
        feas[first] = point.certificate.feasibility_mm / ws.asm.s
        residual[first] = point.certificate.equilibrium_residual
        found = point.active if point.active is not None else point.tie
        keys[first] = found
        if found is not None and dense:
            solved_by_set.setdefault(found, []).append(np.array([first]))

    if centres is not None or ws.stack.centre is not None:
        # with no load and no preload, the rest position: where the centres put it
        for row in np.flatnonzero(scales == 0):
            try:
                rest = pipeline.rest_position(ws.with_radii(r[row], c[row]))
            except UnassembledError:
                assembled[row] = False
            else:
                x[row] = rest.x
            full += 1
    x, lam, f, batched, assembled = x[:B], lam[:B], f[:B], batched[:B], assembled[:B]
    feas, residual = feas[:B], residual[:B]
    followed = None
    if own_starts is not None:
        followed = tuple(
            Start(g_hat[i], r[i], c[i], x[i].copy(), lam[i].copy(), f[i].copy(), key)
            if key is not None and assembled[i]
            else None
            for i, key in enumerate(keys)
        )
    x[~assembled] = np.nan
    lam[~assembled] = np.nan
    return BatchSolution(
        asm=ws.asm,
        x=x,
        forces=lam * scales[:, None] / ws.asm.s if split_forces else None,
        potential_energy=-np.einsum("bm,bm->b", work, x),
        feasibility_mm=np.maximum(feas, 0.0) * ws.asm.s,
        equilibrium_residual=residual,
        batched=batched,
        full_solves=full,
        assembled=assembled,
        own_starts=followed,
    )


def _per_row(name: str, given: FloatArray | None, default: FloatArray, B: int) -> FloatArray:
    """Each row's radii or centres: ``given`` (B, n), checked, or the model's."""
    if given is None:
        return np.broadcast_to(default, (B, len(default)))
    out = np.asarray(given, dtype=float)
    if out.shape != (B, len(default)):
        raise ValueError(f"{name} must have shape ({B}, {len(default)}), not {out.shape}")
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{name} must be finite")
    return out


def _preloads(ws: WorkspaceData, norms: FloatArray, r: FloatArray, c: FloatArray) -> FloatArray:
    """``norms``, and each unloaded row's ``pipeline.load_scale`` (the
    preload of springs its plays and centres press, a program each)."""
    scales = norms.copy()
    if not np.any(ws.stack.spring > 0):
        return scales
    for row in np.flatnonzero(norms == 0):
        with contextlib.suppress(UnassembledError):  # the rest position says so
            scales[row] = pipeline.load_scale(ws.with_radii(r[row], c[row]), 0.0)
    return scales


def _check_driven(ws: WorkspaceData, work: FloatArray, norms: FloatArray) -> None:
    if ws.N.shape[1] == 0:
        return
    drive = linalg.times(ws.N.T, work)  # work @ N
    bad = np.linalg.norm(drive, axis=1) > ws.settings.free_motion_rcond * norms
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        held.check_driven(ws, work[i])  # raises, naming the body and the motion


def _newton_batch(
    ws: WorkspaceData,
    key: FaceKey,
    g_hat: FloatArray,
    sigma: FloatArray,
    x0: FloatArray,
    lam0: FloatArray,
    f0: FloatArray,
    r: FloatArray,
    c: FloatArray,
    near: tuple[FloatArray, FloatArray] | None = None,
    g_near: FloatArray | None = None,
) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray, certificate.Checks | None, BoolArray]:
    """KKT equations of the active set ``key`` for every row of ``g_hat``,
    each from its own start (rows of ``x0``, ``lam0``, ``f0``: the nearest
    solved sample's answer and split) and with its own cone radii (rows of
    ``r``) and centres (rows of ``c``); ``near``: the start's own radii and
    centres (default: the same as the rows').

    Returns (accepted mask, x, full multipliers, force vectors, their
    certificate, wrong-set mask); a row is accepted as the module says. The
    wrong-set rows
    converged, Newton's forces all strictly positive, to a point that
    crosses a contact outside the set: their optimum lies on another set.
    """
    B = g_hat.shape[0]
    stack = ws.stack
    x = x0.copy()
    lam = np.zeros((B, len(ws.balls)))
    f = np.zeros((B, stack.A.shape[0]))
    face = faces.face_of(ws, key)
    Eq, e = face.Eq, face.e
    tie = face.tie_rows  # a tie: its rows pick the least-norm point of the face
    if tie is not None:
        Eq, e = np.vstack([linalg.dense(Eq), tie]), np.concatenate([e, np.zeros(len(tie))])
    elif face.determined is False:  # a large tie (sparse: no tie rows)
        return np.zeros(B, dtype=bool), x, lam, f, None, np.zeros(B, dtype=bool)
    surface, linear = key
    ne0 = ws.Eq.shape[0]
    eq_soft = np.zeros((B, len(Eq)))
    eq_soft[:, ne0 + face.lam_rows] = sigma[:, list(linear)]
    e_rows = np.repeat(e[None, :], B, axis=0)
    e_rows[:, ne0 + face.lam_rows] = r[:, list(linear)]
    e_rows[:, ne0 + face.f_rows] = c[:, face.linear_rows]
    r_surface = r[:, list(surface)]
    c_surface = c[:, face.surface_rows]
    if near is not None and tie is None:
        # only where the centres moved: rows whose plays alone differ keep the
        # neighbour's position, so that rows posing one problem stay equal to
        # the last digit (the force split solves each distinct problem once)
        shifted = np.any(c != near[1], axis=1)
        if np.any(shifted):
            x[shifted] = _predicted(
                face,
                Eq,
                x0[shifted],
                e_rows[shifted],
                r_surface[shifted],
                c_surface[shifted],
                (near[0][shifted], near[1][shifted]),
                ne0,
                ws.settings.free_motion_rcond,
            )
    lam_first = lam0.copy()  # Newton's start (the split starts from the neighbour's)
    if g_near is not None and tie is None and len(surface) and not np.any(sigma):
        # rows whose loads differ from their start's: forces, directions of
        # contact and positions predicted for their own loads (a compliant
        # contact's force follows its penetration: those rows start as they are)
        turned = np.flatnonzero(np.any(g_hat != g_near, axis=1))
        if turned.size:
            on = np.ix_(turned, np.array(surface, dtype=np.intp))
            x[turned], lam_first[on] = _load_predicted(
                face,
                Eq,
                x[turned],
                lam0[on],
                f0[np.ix_(turned, face.surface_rows)],
                g_hat[turned] - g_near[turned],
                r_surface[turned],
                c_surface[turned],
                e_rows[turned],
                ws.settings.free_motion_rcond,
            )
    na, ne = len(surface), Eq.shape[0]
    # redundant contacts: Newton on an independent part of the active rows
    # (the same positions), the others masked out; the forces are split after
    kept = _independent_rows(ws, face, x0[0], c_surface[0])
    redundant = kept is not None
    s_keep, e_keep = kept if kept is not None else (np.arange(na), np.arange(ne))
    mask = np.zeros((B, na + ne), dtype=bool)
    mask[:, s_keep], mask[:, na + e_keep] = True, True
    mask[:, na + face.Eq.shape[0] :] = True  # a tie's rows
    lam_s = lam_first[:, list(surface)].copy()
    nu = np.zeros((B, ne))
    conv = newton.newton(
        None,
        -g_hat,
        Eq,
        e_rows,
        face.stack,
        x,
        lam_s,
        nu,
        ws.settings,
        r=r_surface,
        c=c_surface,
        soft=sigma[:, list(surface)],
        eq_soft=eq_soft,
        active=mask,
        accept=ws.settings.newton_accept,
    ).converged
    # a row that did not converge is no answer (``ok`` below needs ``conv``):
    # its start stands in for it, so that a diverged row reaches no check
    lost = ~conv
    x[lost], lam_s[lost], nu[lost] = x0[lost], lam0[:, list(surface)][lost], 0.0
    lam_s[:, ~mask[0, :na]] = 0.0

    lam, f = newton.face_forces(ws, face, x, lam_s, nu[:, ne0:], c_surface)
    st = ws.settings
    strict = ~np.any(newton.weak_rows(ws, lam, f, key), axis=1)  # Newton's own forces
    # contacts that touch outside the set may share the load (unloaded in the
    # neighbour's split): the split rule decides, as when the set is redundant
    in_set = np.zeros(len(ws.balls), dtype=bool)
    in_set[[*surface, *linear]] = True
    used = stack.gap_used(stack.levels(x, c)[2], st.feasibility_tolerance * ws.max_radius, r)
    outside = np.any((stack.spring == 0) & (used >= st.touching) & ~in_set, axis=1)
    if tie is not None:
        # the least-norm point of the face's affine hull is the tie's answer only
        # where it stays inside every other cone, off their limits (else the
        # optimal face is smaller: the full solver's least-norm program)
        conv = conv & ~outside
        outside[:] = False
    # forces that are one of many: the documented split (``forces``), from the
    # neighbour's split
    shared = conv & (redundant | outside)
    ok = conv.copy()
    if np.any(shared):
        rows = np.flatnonzero(shared)
        apex = st.feasibility_tolerance * ws.max_radius
        split, lam[rows], f[rows], _ = forces.least_squares_rows(
            ws.asm,
            x[rows],
            lam[rows],
            f[rows],
            g_hat[rows],
            r[rows],
            (lam0[rows], f0[rows]),
            apex,
            st,
            c[rows],
        )
        ok[rows] &= split
    checks = certificate.check(ws, g_hat, x, lam, f, sigma, r, c=c)
    ok &= checks.passed(st, ws.max_radius)
    # converged with Newton's forces strictly positive: the optimum of the
    # (convex) program on the set's contacts alone, unique where the face pins
    # it; where it crosses another contact, no other start on this set does better
    wrong_set = conv & strict & (checks.feasibility > st.feasibility_tolerance * ws.max_radius)
    if tie is not None:
        wrong_set[:] = False
    wrong = np.flatnonzero(wrong_set)
    wrong_set[wrong] = faces.determined_rows(ws, face, x[wrong], c_surface[wrong])
    rows = np.flatnonzero(ok)
    if tie is None:
        # a certified optimum, the only one where its loaded contacts pin x
        ok[rows] = _pinned(ws, key, x[rows], lam[rows], f[rows], c[rows])
    else:
        # the tie's rows pick the least-norm point of the face, which holds
        # every optimum where each contact of the set is loaded
        ok[rows] = ~np.any(newton.weak_rows(ws, lam[rows], f[rows], key), axis=1)
    return ok, x, lam, f, checks, wrong_set


def _load_predicted(
    face: Face,
    Eq: Matrix,
    x0: FloatArray,
    lam0: FloatArray,
    f0: FloatArray,
    dg: FloatArray,
    r_surface: FloatArray,
    c_surface: FloatArray,
    e_rows: FloatArray,
    rcond: float,
) -> tuple[FloatArray, FloatArray]:
    """Newton's start for rows whose loads differ by ``dg`` from their
    neighbour's (position ``x0``, surface cones' forces ``lam0`` and force
    vectors ``f0``): returns positions and the surface cones' forces.

    The balance is linear in the multipliers taken as free vectors (each
    surface cone's force vector, an offset cone's push, the equalities'
    multipliers): the change of least size that balances ``dg`` gives each
    cone a force, and its direction of contact is along it. Each cone
    without an offset then touches its play along that direction (an offset
    cone keeps its place), and the position moves least to get there (least
    squares over the cones' and the equalities' rows). Where the set's
    balance fixes its forces, the start is the answer (6.1.6.1's force
    turned about the shaft: no Newton step)."""
    sub = face.stack
    A, E = linalg.dense(sub.A), linalg.dense(Eq)
    n_rows = A.shape[0]
    offset = np.flatnonzero(sub.has_offset)
    balance = np.hstack([A.T, linalg.dense(sub.B)[offset].T, E.T])
    change = dg @ np.linalg.pinv(balance, rcond=rcond).T
    f = f0 + change[:, :n_rows]
    size = np.sqrt(sub.segment_sum(f * f))
    lam = size.copy()
    lam[:, offset] = lam0[:, offset] + change[:, n_rows : n_rows + len(offset)]
    reach = x0 @ A.T
    v = reach - c_surface
    rho = np.sqrt(sub.segment_sum(v * v))
    # a cone whose force the change cancels keeps its neighbour's direction
    pushed = np.repeat(size > 0, sub.k, axis=1)
    u = np.where(
        pushed,
        f / np.repeat(np.where(size > 0, size, 1.0), sub.k, axis=1),
        v / np.repeat(np.where(rho > 0, rho, 1.0), sub.k, axis=1),
    )
    target = np.where(
        np.repeat(sub.has_offset, sub.k), reach, c_surface + np.repeat(r_surface, sub.k, axis=1) * u
    )
    rows = np.vstack([A, E])
    step = np.hstack([target - reach, e_rows - x0 @ E.T]) @ np.linalg.pinv(rows, rcond=rcond).T
    return x0 + step, lam


def _predicted(
    face: Face,
    Eq: Matrix,
    x0: FloatArray,
    e_rows: FloatArray,
    r_surface: FloatArray,
    c_surface: FloatArray,
    near: tuple[FloatArray, FloatArray],
    ne0: int,
    rcond: float,
) -> FloatArray:
    """Newton's start for each row: its neighbour's position ``x0`` moved so
    that each active cone keeps the neighbour's direction of contact while
    its centre and radius become the row's (least squares over the face's
    rows). Where the samples move the clearances' centres (deviations), the
    contacts' directions follow the loads rather than the positions: Newton
    from there takes one or two steps. A tilting face (on the rim of its
    offset) is left out where the other contacts span its rows: where on its
    rim it touches then follows the parts' relative tilt, which they set (a
    nut's face under a carriage whose guide's tilt is drawn)."""
    r0, c0 = near
    sub = face.stack
    surface, linear = face.key
    v, rho = sub.norms(x0, c0[:, face.surface_rows])
    u = v / np.repeat(np.where(rho > 0, rho, 1.0), sub.k, axis=1)
    moved = c_surface - c0[:, face.surface_rows]
    moved += np.repeat(r_surface - r0[:, list(surface)], sub.k, axis=1) * u
    e_near = e_rows.copy()
    e_near[:, ne0 + face.lam_rows] = r0[:, list(linear)]
    e_near[:, ne0 + face.f_rows] = c0[:, face.linear_rows]
    M = np.vstack([linalg.dense(sub.A), linalg.dense(Eq)])
    plain = np.repeat(~sub.has_offset, sub.k)
    rest = np.vstack([linalg.dense(sub.A)[plain], linalg.dense(Eq)])
    if not np.all(plain) and linalg.rank(rest, rcond) == linalg.rank(M, rcond):
        # the other contacts span the tilting faces' rows: where each face
        # touches its rim follows the relative tilt they set
        M, moved = rest, moved[:, plain]
    step = np.hstack([moved, e_rows - e_near]) @ np.linalg.pinv(M).T
    return np.asarray(x0 + step)


def _pinned(
    ws: WorkspaceData, key: FaceKey, x: FloatArray, lam: FloatArray, f: FloatArray, c: FloatArray
) -> BoolArray:
    """Whether the forces ``lam``, ``f`` (rows) pin each row's position
    down: any other optimum keeps every loaded contact where it is, so the
    position is unique if their rows (and the equalities) have full rank.
    A surface cone with an offset, or a face whose force reaches its rim,
    keeps only the rows across its tilt (see ``faces.is_determined``); an
    unloaded contact keeps none. Rows (B, m)."""
    stack, st = ws.stack, ws.settings
    B = x.shape[0]
    loaded = lam > st.positive_force * np.max(lam, axis=1, keepdims=True)
    v, rho = stack.norms(x, c)
    f_norm = np.sqrt(stack.segment_sum(f * f))
    parts = [np.broadcast_to(linalg.dense(ws.Eq), (B, *ws.Eq.shape))]
    surface, linear = key
    for i in (*surface, *linear):
        k, rows = int(stack.k[i]), stack.rows_of([i])
        M = np.broadcast_to(linalg.dense(stack.face_rows(i)), (B, k + 1, ws.m))
        if i in surface:  # tilts along its direction of contact, if it has an offset
            u = v[:, rows] / np.maximum(rho[:, i : i + 1], TINY)
            tilt = np.full(B, bool(stack.has_offset[i]))
            if not stack.has_offset[i]:
                M = M[:, :k]
        else:  # a face flat at its apex may tilt about the rim its force reaches
            u = f[:, rows] / np.maximum(f_norm[:, i : i + 1], TINY)
            tilt = stack.has_rim[i] & (f_norm[:, i] >= (1.0 - st.interior_resolution) * lam[:, i])
        if np.any(tilt):
            w = np.concatenate([u, -np.ones((B, 1))], axis=1)
            w /= np.linalg.norm(w, axis=1, keepdims=True)
            across = M - w[:, :, None] * np.einsum("bk,bkm->bm", w, M)[:, None, :]
            M = np.where(tilt[:, None, None], across, M)
        parts.append(np.where(loaded[:, i, None, None], M, 0.0))
    J = np.concatenate(parts, axis=1)
    if J.shape[1] < ws.m or B == 0:
        return np.zeros(B, dtype=bool)
    if np.all(J[0] == J):  # one system (a study whose contacts do not turn)
        return np.repeat(linalg.full_column_rank_rows(J[:1], st.free_motion_rcond), B)
    return linalg.full_column_rank_rows(J, st.free_motion_rcond)


def _independent_rows(
    ws: WorkspaceData, face: Face, x: FloatArray, centre: FloatArray
) -> tuple[IntArray, IntArray] | None:
    """None if the active rows of ``face`` at ``x`` (each surface cone's
    gradient and the equalities) are independent. Else they are redundant
    (contacts on the four corners of a guide: the forces are not unique,
    the positions are) and this returns the surface cones and equality rows
    of an independent part that spans them all (a pivoted QR): Newton on
    those finds the same positions. Compliant contacts always stay: their
    force follows their penetration."""
    sub, (surface, linear) = face.stack, face.key
    Eq = linalg.dense(face.Eq)
    rows = [Eq]
    if len(sub.k):
        v, rho = sub.norms(x, centre)
        u = v / np.repeat(np.where(rho > 0, rho, 1.0), sub.k)
        rows.insert(0, np.add.reduceat(linalg.dense(sub.A) * u[:, None], sub.start, axis=0) + sub.B)
    J = np.vstack(rows)
    spring = ws.stack.spring
    soft = np.zeros(len(J), dtype=bool)
    soft[: len(surface)] = spring[list(surface)] > 0
    ne0 = Eq.shape[0] - face.L.shape[0]
    soft[len(surface) + ne0 + face.lam_rows] = spring[list(linear)] > 0
    hard = np.flatnonzero(~soft)
    if not len(hard):
        return None
    _, R, piv = scipy.linalg.qr(J[hard].T, mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    rank = int(np.sum(d > ws.settings.free_motion_rcond * d[0])) if d.size and d[0] > 0 else 0
    if rank == len(hard):
        return None
    keep = np.sort(np.r_[np.flatnonzero(soft), hard[piv[:rank]]])
    na = len(surface)
    return keep[keep < na], keep[keep >= na] - na
