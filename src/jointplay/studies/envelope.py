"""The worst-case envelope of a functional point: where the plays let it go.

Under loads that push a functional point P in a direction u, P goes as far
as the clearances let it: the support function ``h(u) = max u . d_P(x)``
over the positions x that every clearance allows is one cone program, the
equilibrium under a unit force along u at P (with rigid contacts only the
load's direction matters). The envelope takes it in many directions spread
evenly over the sphere, all in one batch, then climbs from the farthest
support points to the largest displacement (each step ``u <- d / |d|`` can
only increase |d|).

Over which loads (``Envelope.loads``):

* ``probes``: such unit probes at P, added to the *standing* loads: the
  weights, and the loads marked ``standing`` (a preload: a spring, a clamp).
  They hold the parts against some limits; the probe shows where a push
  sends the point across the plays they leave free. A probe direction is kept
  only if the mechanism holds it: a force at P that would drive a free
  motion (a door about its hinges) or lift a part off its one-sided supports
  (a plate off its buttons) has no equilibrium, and is listed instead.
* ``model``: the loads the model itself says it takes: every load case, and
  for each, every combination of its varying load components (``{min,
  max}``) at ``levels`` evenly spaced values (3: their limits and mean,
  or 2 where three would make too many; 2: their limits). The
  envelope is then the convex hull of P's displacements under those loads.
  It is exact for those loads; a load between them (a force turning between
  two limits, on a round bore) may push P a little further: raise
  ``levels`` to see.
* ``auto`` (the default): ``model`` if the model has load cases or varying
  load components, else ``probes`` (``default_loads``). Over a motion
  (``MotionEnvelope``) a component given as a table over the drive's value
  varies too: the model says which load acts at each pose, and probes would
  push the point where that load never sends it.

With deviation zones (``deviations.py``) the envelope is the support of
every position the plays and the zones allow (``_ZoneProgram``: one cone
program per direction, over the positions and the deviations together):
exact under probes without standing loads, an upper bound under the model's
loads or against standing loads (said in ``over``).

The envelope is that of the plays alone: a contact's stiffness, and a
drive's, are left out (they would let the point go further the harder it is
pushed). With toleranced plays it is taken at their upper limits
(``plays="max"``) or at their means (``plays="mean"``). Without standing
loads, a probe envelope at the upper limits holds every part of the batch:
each clearance domain holds the smaller ones. Against standing loads, or
under the model's load sets, it need not: a larger play moves the equilibrium elsewhere,
not always further along every axis (the Monte Carlo study takes each
part's own plays).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from jointplay.assembly import assemble
from jointplay.errors import (
    OptionError,
    SolverError,
    UnassembledError,
    UnboundedMechanismError,
)
from jointplay.geometry import FloatArray, skew
from jointplay.model.mechanism import Model, check_case
from jointplay.model.tables import DriveTable
from jointplay.proven import Resolution, direction, proven
from jointplay.settings import SMALLEST_PROBE
from jointplay.solver import held
from jointplay.solver.solve import Workspace
from jointplay.studies.variation import deviation_map, load_map, play_map
from jointplay.units import LIMITS

if TYPE_CHECKING:
    import pandas as pd

#: The directions always taken first: +-X, +-Y, +-Z (the exact extents).
AXES = np.vstack([np.eye(3), -np.eye(3)]) + 0.0  # + 0.0: no -0 in the output
#: Steps of the climb from a support point to the largest displacement.
CLIMB_STEPS = 30
#: Most load combinations an envelope over the model's loads solves (levels ** components
#: per case): beyond it the grid is a slip, and Monte Carlo is the study to run.
MOST_LOAD_SETS = 100_000


def sphere_directions(n: int) -> FloatArray:
    """``n`` unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5.0**0.5) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


@dataclass(frozen=True)
class Envelope:
    """Settings of a worst-case envelope; ``run`` returns an ``EnvelopeResult``.

    ``loads``: ``"probes"``, ``"model"`` or ``"auto"`` (module docstring).
    ``levels``: values per varying load component (``model``). ``probe``: the
    probe force (N) against the standing loads (``probes``; without weights
    only its direction matters). ``case``: only this load case of the model
    (None: every case)."""

    point: str
    directions: int = 200
    plays: Literal["max", "mean"] = "max"
    loads: Literal["auto", "model", "probes"] = "auto"
    levels: int | None = None
    probe: float = 1.0
    case: str | None = None

    def __post_init__(self) -> None:
        if self.directions < 6:
            raise ValueError("directions: at least 6")
        if self.levels is not None and self.levels < 2:
            raise ValueError("levels: at least 2 (the limits of each varying load)")
        if not SMALLEST_PROBE <= self.probe <= LIMITS["force"]:
            raise ValueError(
                f"probe: a force of {SMALLEST_PROBE:g} to {LIMITS['force']:g} N, "
                f"not {self.probe:.10g}"
            )

    def run(self, model: Model, *, source: str | None = None) -> EnvelopeResult:
        """``source``: the model file's name, for messages."""
        return self._run(model, source=source or model.name or "<model>")

    def _cases(self, model: Model) -> tuple[str | None, ...]:
        """The load cases the envelope takes (None: the model's loads)."""
        if self.case is not None:
            return (self.case,)
        return tuple(model.case_names) or (None,)

    def _run(
        self, model: Model, *, source: str, carry: dict[tuple[int, int], Any] | None = None
    ) -> EnvelopeResult:
        """``carry``: the answers of a nearby model's envelope (the pose
        before, in a motion), read and replaced here: each batch's rows start
        Newton from the same rows' answers there (``own_starts``)."""
        names = [p.name for p in model.points]
        if self.point not in names:
            known = ", ".join(names) if names else "none; add a 'points' section"
            raise OptionError(
                f"--point: unknown point '{self.point}'; the points are: {known}", source=source
            )
        point = model.points[names.index(self.point)]
        check_case(model, self.case, source)
        rigid = model.model_copy(
            update={
                "joints": tuple(
                    j.model_copy(update=_without_springs(type(j).model_fields))
                    for j in model.joints
                )
            }
        )
        asm = assemble(rigid)
        ws = Workspace(asm)
        pmap = play_map(asm, source)
        if self.plays == "max" and pmap.variables:
            highs = np.array([v.value.high for v in pmap.variables])
            ws = ws.with_radii(pmap.radii(highs)[0])
        for each in self._cases(model):  # probes stand in for the loads: check them first
            ws.check_held(each)
        mode = self.loads if self.loads != "auto" else default_loads(model, self.case)
        directions = np.vstack([AXES, sphere_directions(self.directions)])
        if point.body not in asm.body_index:  # a point of the ground does not move
            zero = np.zeros_like(directions)
            return EnvelopeResult(
                self,
                point.body,
                directions,
                np.zeros(len(directions)),
                zero,
                zero[0],
                0.0,
                "a point of the ground: it does not move",
                (),
            )
        at = np.asarray(point.at)
        dmap = deviation_map(asm)
        if dmap.variables:
            return self._over_zones(rigid, ws, dmap, point.body, at, directions, mode)

        resolution = Resolution.of(asm.s, asm.ell, settings=ws.settings)

        batches = [0]  # this run's batches so far: the k-th meets the k-th before

        def motion_of(work: FloatArray) -> FloatArray:
            # a batch's rows (not a climb's single steps) start from the same
            # rows' answers on the model before: its batch of the same place
            # in the run (a load case's, the probes') and size
            kept = carry is not None and len(work) > 1
            key = (batches[0], len(work))
            batches[0] += kept
            before = carry.get(key, (None,) * len(work)) if kept and carry is not None else None
            batch = ws.solve_batch(work, forces=False, own_starts=before)
            if kept and carry is not None and batch.own_starts is not None:
                carry[key] = batch.own_starts
            motion = batch.body_displacement(point.body)
            return proven(motion[:, :3] + np.cross(motion[:, 3:], at), resolution.length)

        if mode == "model":
            d, over, not_held = self._over_model(rigid, asm, motion_of, source)
            h = directions @ d.T  # (n, samples)
            best = np.argmax(h, axis=1)
            size = np.linalg.norm(d, axis=1)
            top = int(np.argmax(size))
            return EnvelopeResult(
                self,
                point.body,
                directions,
                h[np.arange(len(directions)), best],
                d[best],
                d[top],
                float(size[top]),
                over,
                not_held,
            )
        return self._probed(rigid, ws, point.body, at, directions, motion_of)

    def _over_model(
        self, model: Model, asm: Any, motion_of: Any, source: str
    ) -> tuple[FloatArray, str, tuple[str, ...]]:
        """P's displacement under every load set the model takes that the
        mechanism holds, those words, and the load sets it does not hold."""
        parts, counts, not_held = [], [], []
        why: UnboundedMechanismError | None = None
        varied = False
        used: set[int] = set()
        for case in self._cases(model):
            lmap = load_map(asm, case)
            nl = len(lmap.variables)
            varied = varied or nl > 0
            # by default the limits and the mean, or the limits only where that is too many
            levels = self.levels or (3 if 3**nl <= MOST_LOAD_SETS else 2)
            used.add(levels)
            if levels**nl > MOST_LOAD_SETS:
                raise OptionError(
                    f"{nl} load components vary{'' if case is None else f' in case {case!r}'}: "
                    f"{levels}^{nl} load combinations are more than the envelope's "
                    f"{MOST_LOAD_SETS:,}; fix some of them, lower --levels, or run a Monte "
                    "Carlo study",
                    source=source,
                )
            grids = [np.linspace(v.value.low, v.value.high, levels) for v in lmap.variables]
            combos = list(itertools.product(*grids))
            values = np.array(combos, dtype=float).reshape(len(combos), nl)
            work = lmap.work(values)
            d, ok, why = _solved_rows(work, motion_of, why)
            name = "the loads" if case is None else f"case {case!r}"
            if not np.all(ok):
                lost = ", ".join(
                    f"{v.label} = {value:g}"
                    for v, value in zip(lmap.variables, values[~ok][0], strict=True)
                )
                not_held.append(
                    f"{int(np.sum(~ok))} of {len(values)} load sets of {name} "
                    + (f"(e.g. {lost}) " if lost else "")
                    + f"have no equilibrium: {why}"
                )
            parts.append(d[ok])
            counts.append(int(np.sum(ok)))
        if not any(model.loads_of(case) for case in self._cases(model)):
            raise OptionError(
                "--loads model: the model has no loads (no 'loads', no weight, no case with "
                "loads): nothing pushes the point; use --loads probes",
                source=source,
            )
        if not sum(counts):
            assert why is not None
            raise UnboundedMechanismError(
                f"no load set of the model is held: {'; '.join(not_held)}",
                body=why.body,
                motion=why.motion,
                direction=why.direction,
            )
        cases = model.case_names if self.case is None else ()
        each = (
            "both limits of each varying load component"
            if used == {2}
            else f"{'/'.join(map(str, sorted(used)))} evenly spaced values of each varying "
            "load component"
        )
        total = sum(counts)
        over = (
            f"the model's loads: {total:,} load set{'s' if total > 1 else ''}"
            + (f" over {len(cases)} load cases" if cases else "")
            + (f" of load case '{self.case}'" if self.case is not None else "")
            + (f", {each}" if varied else "")
        )
        return np.vstack(parts), over, tuple(not_held)

    def _over_zones(
        self,
        model: Model,
        ws: Workspace,
        dmap: Any,
        body: str,
        at: FloatArray,
        directions: FloatArray,
        mode: str,
    ) -> EnvelopeResult:
        """With deviation zones: the support of every position the plays and
        the zones allow (``_ZoneProgram``), in the held directions. Exact for
        probes without standing loads; under loads that hold parts against
        some limits, an upper bound."""
        asm = ws.asm
        program = _ZoneProgram(ws, dmap, _point_map(asm, body, at))
        standing = model.weights() + tuple(ld for ld in model.loads if ld.standing)
        g0 = asm.work_of(standing)
        W = asm.wrench_work(body, tuple(at))[:, :3]
        held_dirs, not_held, why = _held_directions(ws, g0, W, directions, self.directions)
        if not len(held_dirs):
            raise _none_held(self.point, not_held, why)
        found = [(u, program.support(u)) for u in held_dirs]
        lost = [u for u, d in found if d is None]
        if lost:
            not_held.append(
                f"{len(lost)} of {len(held_dirs)} directions lead the point on for ever (a "
                f"part lifting off its supports), e.g. along {_words(lost[0])}"
            )
        kept = [(u, d) for u, d in found if d is not None]
        if not kept:
            raise OptionError(
                "no direction of the point is bounded by the clearances and the deviation "
                "zones; give the mechanism supports that hold it",
            )
        held_dirs = np.array([u for u, _ in kept])
        d = np.array([dd for _, dd in kept])
        size = np.linalg.norm(d, axis=1)
        far_d = d[int(np.argmax(size))]
        for start in np.argsort(size)[-4:]:  # climb to the largest displacement
            cur = d[start]
            for _ in range(CLIMB_STEPS):
                n = float(np.linalg.norm(cur))
                nxt = program.support(cur / n) if n > 0 else None
                if nxt is None or float(np.linalg.norm(nxt)) <= n * (1 + 1e-13):
                    break
                cur = nxt
            if np.linalg.norm(cur) > np.linalg.norm(far_d):
                far_d = cur
        h = np.einsum("ij,ij->i", held_dirs, d)
        exact = mode == "probes" and not np.any(g0)
        over = (
            f"a push at the point in {len(held_dirs)} directions and every deviation within "
            "its zone (one cone program per direction, over the positions and the deviations "
            "together): "
            + (
                "exact"
                if exact
                else "an upper bound for the "
                + ("model's loads" if mode == "model" else "standing loads")
                + ", which may keep the point from part of it"
            )
        )
        largest = float(np.linalg.norm(far_d))
        return EnvelopeResult(self, body, held_dirs, h, d, far_d, largest, over, tuple(not_held))

    def _probed(
        self,
        model: Model,
        ws: Workspace,
        body: str,
        at: FloatArray,
        directions: FloatArray,
        motion_of: Any,
    ) -> EnvelopeResult:
        """Unit probes at the point against the standing loads (the weights and
        the loads marked ``standing``), in the directions held."""
        asm = ws.asm
        g0 = asm.work_of(model.weights() + tuple(ld for ld in model.loads if ld.standing))
        W = asm.wrench_work(body, tuple(at))[:, :3] * self.probe
        held_dirs, not_held, why = _held_directions(ws, g0, W, directions, self.directions)
        if not len(held_dirs):
            raise _none_held(self.point, not_held, why)
        work = g0 + held_dirs @ W.T
        d, ok, why = _solved_rows(work, motion_of, why)
        if not np.all(ok):
            lost = held_dirs[~ok]
            not_held = [
                *not_held,
                f"{len(lost)} of {len(held_dirs)} probe directions lift a part off its "
                f"supports, e.g. a force at the point along {_words(lost[0])}",
            ]
            held_dirs, d = held_dirs[ok], d[ok]
        if not len(held_dirs):
            raise _none_held(self.point, not_held, why)
        # climb from the farthest few to the largest displacement, in held directions
        size = np.linalg.norm(d, axis=1)
        top = int(np.argmax(size))
        far, far_d = float(size[top]), d[top]
        for start in np.argsort(size)[-4:]:
            cur = d[start]
            for _ in range(CLIMB_STEPS):
                n = float(np.linalg.norm(cur))
                if n == 0.0:
                    break
                u = cur / n
                if not _is_held(ws, g0, W, u):
                    break
                nxt, fine, _ = _solved_rows((g0 + W @ u)[None, :], motion_of, why)
                if not fine[0] or float(np.linalg.norm(nxt[0])) <= n * (1 + 1e-13):
                    break
                cur = nxt[0]
            if float(np.linalg.norm(cur)) > far:
                far, far_d = float(np.linalg.norm(cur)), cur
        h = np.einsum("ij,ij->i", held_dirs, d)
        standing = "the standing loads" if np.any(g0) else "no standing load"
        over = (
            f"probe forces of {self.probe:g} N at the point in {len(held_dirs)} directions "
            f"the mechanism holds, against {standing}"
        )
        return EnvelopeResult(self, body, held_dirs, h, d, far_d, far, over, tuple(not_held))


def default_loads(
    model: Model, case: str | None = None, *, tables: bool = False
) -> Literal["model", "probes"]:
    """What ``loads="auto"`` takes: the model's loads where they vary (load
    cases, or a component given as a range; with ``tables``, over a motion,
    also a component given as a table over the drive's value), else probes,
    as it does where the model has no loads. ``case``: the load case taken
    (None: every case)."""
    cases = (case,) if case is not None else tuple(model.case_names) or (None,)
    loads = [load for each in cases for load in model.loads_of(each)]
    if not loads:
        return "probes"
    varying = bool(model.case_names) or any(load.ranges() for load in loads)
    if tables:
        varying = varying or any(
            isinstance(c, DriveTable)
            for load in loads
            for c in (*(load.force or ()), *(load.torque or ()))
        )
    return "model" if varying else "probes"


def _without_springs(fields: Any) -> dict[str, None]:
    return {name: None for name in ("stiffness", "torsional_stiffness") if name in fields}


def _words(u: FloatArray) -> str:
    return "[" + ", ".join(f"{c + 0.0:.3g}" for c in u) + "]"


def _none_held(
    point: str, not_held: list[str], why: UnboundedMechanismError | None
) -> UnboundedMechanismError:
    assert why is not None  # no direction is held only after one was found not held
    return UnboundedMechanismError(
        f"no force at point '{point}' is held: {'; '.join(not_held)}",
        body=why.body,
        motion=why.motion,
        direction=why.direction,
    )


def _held_directions(
    ws: Workspace, g0: FloatArray, W: FloatArray, directions: FloatArray, n: int
) -> tuple[FloatArray, list[str], UnboundedMechanismError | None]:
    """The probe directions that drive no free motion (a subspace of the
    sphere's), the words for those that do, and the free motion they drive."""
    held.check_driven(ws, g0)  # the weights alone drive a free motion: exit 3, as a solve
    if ws.N.shape[1] == 0:
        return directions, [], None
    C = np.asarray(ws.N.T @ W)  # (free motions, 3): what a unit probe drives
    _, sv, Vt = np.linalg.svd(C)
    # as a solve judges a load: its part on the free motions against the load itself
    probe_size = float(np.linalg.norm(W, 2))
    rank = int(np.sum(sv > ws.settings.free_motion_rcond * probe_size))
    if rank == 0:
        return directions, [], None
    basis = Vt[rank:].T  # (3, k): the probe directions that drive nothing
    driven = _near_the_axes(Vt[:rank], ws.settings.free_motion_rcond)
    # each driven direction drives its own motion: a force along Y at an arm's
    # end on a ball turns it about Z, one along Z about Y
    whys = [held.unbounded(ws.asm, np.asarray(ws.N @ (C @ u)), ws.settings) for u in driven]
    why = whys[0]
    clauses = [
        f"{'a force at the point' if i == 0 else 'one'} with a part along {_words(u)} drives "
        + str(w).split(" is not held by any joint")[0]  # "body 'door': rotation about ..."
        for i, (u, w) in enumerate(zip(driven, whys, strict=True))
    ]
    listed = clauses[0] if rank == 1 else ", ".join(clauses[:-1]) + ", and " + clauses[-1]
    not_held = [f"{listed}, which no joint holds"]
    k = basis.shape[1]
    if k == 0:
        return np.zeros((0, 3)), not_held, why
    if k == 1:
        out = np.vstack([basis[:, 0], -basis[:, 0]])
    else:  # a great circle, evenly
        theta = 2 * np.pi * np.arange(max(n, 4)) / max(n, 4)
        out = np.outer(np.cos(theta), basis[:, 0]) + np.outer(np.sin(theta), basis[:, 1])
    return out, not_held, why


def _near_the_axes(rows: FloatArray, step: float) -> FloatArray:
    """An orthonormal basis of the span of ``rows`` (orthonormal), as near
    the global axes as it goes, each with its largest component positive:
    the axes' parts in the span in turn, the longest first, each less its
    parts along those taken (an SVD's basis of a span that holds the Y and
    Z axes may be any pair of its directions). Components below ``step``,
    the rank cut's round-off, are 0."""
    left = rows.T @ rows  # the projection on the span: the axes' parts are its columns
    out: list[FloatArray] = []
    for _ in range(len(rows)):
        j = int(np.argmax(np.linalg.norm(left, axis=0)))
        u = left[:, j] / np.linalg.norm(left[:, j])
        u = direction(u if u[np.argmax(np.abs(u))] > 0 else -u, step)
        out.append(u)
        left = left - np.outer(u, u @ left)
    return np.array(out)


def _is_held(ws: Workspace, g0: FloatArray, W: FloatArray, u: FloatArray) -> bool:
    if ws.N.shape[1] == 0:
        return True
    g = g0 + W @ u
    drive = np.asarray(ws.N.T @ g)
    return bool(np.linalg.norm(drive) <= ws.settings.free_motion_rcond * np.linalg.norm(g))


def _solved_rows(
    work: FloatArray, motion_of: Any, why: UnboundedMechanismError | None
) -> tuple[FloatArray, Any, UnboundedMechanismError | None]:
    """P's displacement per row, which rows are held (a row that lifts a part
    off its one-sided supports has no equilibrium), and why one was not."""
    try:
        return motion_of(work), np.ones(len(work), dtype=bool), why
    except UnboundedMechanismError:
        pass
    d = np.zeros((len(work), 3))
    ok = np.zeros(len(work), dtype=bool)
    for i, row in enumerate(work):
        try:
            d[i] = motion_of(row[None, :])[0]
            ok[i] = True
        except UnboundedMechanismError as exc:
            why = exc
    return d, ok, why


@dataclass(frozen=True)
class EnvelopeResult:
    """Support values ``h`` in ``directions`` (mm), the support points
    ``hull`` (mm, global: on the envelope's boundary) and the largest
    displacement ``largest`` (mm) with its vector ``largest_vector``."""

    settings: Envelope
    body: str
    directions: FloatArray  # (n, 3) unit
    h: FloatArray  # (n,) mm
    hull: FloatArray  # (n, 3) mm
    largest_vector: FloatArray  # (3,) mm
    largest: float  # mm
    #: Over which loads, in words (``Envelope.loads``).
    over: str = ""
    #: The directions of a probe force that the mechanism does not hold, in words.
    not_held: tuple[str, ...] = ()

    @property
    def extent(self) -> FloatArray:
        """(3, 2): per global axis, the least and the greatest displacement (mm)
        among the support points: exact when the directions include +-X, +-Y,
        +-Z (every probe held), or over the model's loads."""
        if not len(self.hull):
            return np.zeros((3, 2))
        return np.column_stack([self.hull.min(axis=0), self.hull.max(axis=0)])

    @property
    def largest_direction(self) -> FloatArray:
        """(3,) the unit vector of the largest displacement (0 where there is none)."""
        return direction(self.largest_vector, 0.0)

    def contains(self, displacement: FloatArray, tol: float = 1e-9) -> FloatArray:
        """(N,) bool: each displacement (N, 3) is inside every supporting plane."""
        d = np.atleast_2d(displacement)
        return np.asarray(np.all(d @ self.directions.T <= self.h + tol, axis=1))

    def to_dict(self) -> dict[str, Any]:
        ext = self.extent
        direction = self.largest_direction.tolist()
        return {
            "study": "envelope",
            "point": self.settings.point,
            "body": self.body,
            "plays": self.settings.plays,
            "loads": self.over,
            "not_held": list(self.not_held),
            "largest_displacement": self.largest,
            "largest_direction": direction,
            "largest_vector": self.largest_vector.tolist(),
            "extent": {axis: ext[i].tolist() for i, axis in enumerate("xyz")},
            "directions": self.directions.tolist(),
            "support": self.h.tolist(),
            "hull": self.hull.tolist(),
        }

    def to_dataframe(self) -> pd.DataFrame:
        """One row per direction: u, the support value and the support point."""
        import pandas as pd

        return pd.DataFrame(
            {
                "ux": self.directions[:, 0],
                "uy": self.directions[:, 1],
                "uz": self.directions[:, 2],
                "support": self.h,
                "dx": self.hull[:, 0],
                "dy": self.hull[:, 1],
                "dz": self.hull[:, 2],
            }
        )


def point_envelopes(
    model: Model,
    plays: Literal["max", "mean"] = "max",
    *,
    source: str | None = None,
    case: str | None = None,
) -> tuple[dict[str, EnvelopeResult], dict[str, str]]:
    """Every functional point's envelope (over load case ``case``, or every
    case), and why a point has none: its joints leave it free along some
    direction (the message names the motion)."""
    found: dict[str, EnvelopeResult] = {}
    missing: dict[str, str] = {}
    for point in model.points:
        try:
            found[point.name] = Envelope(point.name, plays=plays, case=case).run(
                model, source=source
            )
        except UnboundedMechanismError as exc:
            missing[point.name] = str(exc)
    return found, missing


class _ZoneProgram:
    """The cone program of every position the plays and the deviation zones
    allow, over positions x and deviations e (from their means) together:
    each contact ``|A_i x - c0_i - C_i e| + B_i x <= r_i + D_i e``, each zone
    ``|e_z| <= R_z``, and the equalities (rigid rows, free motions at 0).
    Its support ``max u . P x`` is, for a unit push along u at the point,
    the farthest equilibrium over every deviation (with rigid contacts a push
    goes to the edge of the clearances; section 3a of docs/formulation.md)."""

    def __init__(self, ws: Workspace, dmap: Any, P: FloatArray):
        import clarabel
        import scipy.sparse as sp

        from jointplay.numerics import linalg
        from jointplay.solver import conic

        stack, m = ws.stack, ws.m
        nd = len(dmap.variables)
        self.m, self.P = m, P
        self.zero = Resolution.of(ws.asm.s, ws.asm.ell, settings=ws.settings).length
        A, B = linalg.dense(stack.A), linalg.dense(stack.B)
        Eq = linalg.dense(ws.Eq)
        blocks: list[FloatArray] = [np.hstack([Eq, np.zeros((len(Eq), nd))])]
        b: list[FloatArray] = [np.zeros(len(Eq))]
        cones: list[Any] = [clarabel.ZeroConeT(len(Eq))] if len(Eq) else []
        self.n_zero = len(Eq)  # the equalities' rows, then each cone's ``sizes``
        self.sizes: list[int] = []
        # each zone's components over its radius: |e_z| <= 1 (a tilt's
        # radians next to scaled lengths left Clarabel "AlmostSolved")
        size = np.ones(nd)
        j = 0
        while j < nd:
            zone = dmap.variables[j].zone
            size[j : j + len(zone.axes)] = zone.radius if zone.radius > 0 else 1.0
            j += len(zone.axes)
        c0, C, D = stack.centres(), dmap.C * size[:, None], dmap.D * size[:, None]
        for i, k in enumerate(stack.k):
            rows = slice(stack.start[i], stack.start[i] + k)
            blocks.append(np.hstack([B[i : i + 1], -D[:, i][None, :]]))
            b.append(np.array([stack.r[i]]))
            blocks.append(np.hstack([A[rows], -C[:, rows].T]))
            b.append(c0[rows])
            cones.append(
                clarabel.SecondOrderConeT(int(k) + 1) if k else clarabel.NonnegativeConeT(1)
            )
            self.sizes.append(int(k) + 1)
        j = 0
        while j < nd:  # each zone: |e_z| <= R_z
            zone = dmap.variables[j].zone
            w = len(zone.axes)
            pick = np.zeros((w + 1, m + nd))
            pick[1:, m + j : m + j + w] = -np.eye(w)
            blocks.append(pick)
            b.append(np.r_[1.0 if zone.radius > 0 else 0.0, np.zeros(w)])
            cones.append(clarabel.SecondOrderConeT(w + 1))
            self.sizes.append(w + 1)
            j += w
        self.A = conic.csc(np.vstack(blocks))
        self.b = np.concatenate(b)
        self.cones = cones
        self.Pq = sp.csc_matrix((m + nd, m + nd))
        self.settings = conic.options(ws.settings)
        # one solver for every direction: each support only changes the cost
        self.solver = conic.KeptSolver(self.Pq, self.A, self.b, self.cones, self.settings)
        # an inaccurate support is kept inside every clearance to the
        # certificate's tolerance, its value to ``support_gap``
        self.tol = ws.settings.feasibility_tolerance * ws.max_radius
        self.gap_mm = ws.settings.support_gap

    def support(self, u: FloatArray) -> FloatArray | None:
        """The support point d (mm) in direction u, or None if the point goes
        on for ever along u (a part lifting off its one-sided supports)."""
        from jointplay.solver import conic

        q = np.zeros(self.A.shape[1])
        q[: self.m] = -(u @ self.P)
        sol = self.solver.solve(q)
        if conic.outcome(sol) == "unbounded":
            return None
        if conic.outcome(sol) == "infeasible":
            raise UnassembledError(
                "no set of parts within the deviation zones can be assembled: the zones "
                "leave no position inside every clearance; check them against the plays",
                joints=(),
            )
        if conic.outcome(sol) != "optimal" and not (
            conic.outcome(sol) == "inaccurate" and self._holds(sol)
        ):
            raise SolverError(
                f"the envelope over the deviation zones: the cone solver stopped with status "
                f"{conic.status_name(sol)}"
            )
        d = np.asarray(self.P @ np.asarray(sol.x)[: self.m])
        return proven(d, self.zero)

    def _holds(self, sol: Any) -> bool:
        """Whether an inaccurate answer (Clarabel's "AlmostSolved", its gap
        stalled just above the tolerance) is as good as a certified one:
        inside every cone to ``tol``, its value within ``gap_mm`` of the
        dual bound."""
        slack = self.b - self.A @ np.asarray(sol.x)
        worst = float(np.max(np.abs(slack[: self.n_zero]), initial=0.0))
        at = self.n_zero
        for n in self.sizes:  # second-order cones, and one-row ones (n = 1: >= 0)
            part, at = slack[at : at + n], at + n
            worst = max(worst, float(np.linalg.norm(part[1:]) - part[0]))
        gap = abs(float(sol.obj_val) - float(sol.obj_val_dual))
        return worst <= self.tol and gap <= self.gap_mm


def _point_map(asm: Any, body: str, at: FloatArray) -> FloatArray:
    """(3, m): the point's displacement (mm) per scaled unknown."""
    i = asm.body_index[body]
    P = np.zeros((3, asm.m))
    P[:, 6 * i : 6 * i + 3] = asm.s * np.eye(3)
    lever = np.asarray(at, dtype=float) - asm.body_ref[i]
    P[:, 6 * i + 3 : 6 * i + 6] = -asm.turn[i] * skew(lever)
    return P
