"""Studies over the motion: Monte Carlo, worst-case envelope and contributions at every pose.

``MotionMonteCarlo(samples=..., seed=...).run(model)`` draws each set of
parts once (its plays from their limits or ISO fits, its varying load
components, its deviations: as ``MonteCarlo`` draws them, chunk ``i`` from
``numpy.random.default_rng([seed, i])``) and carries the same parts through
the whole cycle: at every pose the posed model (``motion.posed_model``) is
assembled once and all the parts are solved there in one batch
(``Workspace.solve_batch``, every sample certified on its own). Per step it
gives percentile bands of each functional point's displacement, along a
direction or as its size, and the fraction of parts that miss a requirement
anywhere in the cycle.

``MotionEnvelope().run(model)`` takes each point's worst-case envelope
(``Envelope``) on the posed model at every step; ``MotionContributions()``
takes the contributions (``Contributions``, its rule for a measure that is
not linear included) at every step, and names the play that drives each
measure where it varies most.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from jointplay.assembly import assemble
from jointplay.errors import StudyError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model, Requirement, check_case
from jointplay.proven import Resolution, proven
from jointplay.solver.batch import Start, extrapolated, solved_start
from jointplay.solver.solve import Workspace
from jointplay.studies.kinematics import Poses, nominal_poses
from jointplay.studies.montecarlo import PERCENTILES
from jointplay.studies.motion import Motion, MotionResult, posed_model, shown_drive
from jointplay.studies.parallel import run_chunks
from jointplay.studies.parts import inputs_of, measured, measures_of
from jointplay.studies.variation import deviation_map, load_map, nothing_varies, play_map

#: ``progress(done, total)``: called after each pose a study has solved.
Progress = Callable[[int, int], None]

if TYPE_CHECKING:
    import pandas as pd

    from jointplay.studies.contributions import Contributions, ContributionsResult
    from jointplay.studies.envelope import Envelope, EnvelopeResult


@dataclass(frozen=True)
class _Cycle:
    """A model resolved for its motion, with every body's pose per step."""

    model: Model
    drive: str
    coordinate: str
    values: FloatArray
    poses: Poses
    source: str

    @classmethod
    def of(cls, motion: Motion, model: Model, source: str) -> _Cycle:
        model = motion.resolve(model, source)
        assert model.motion is not None  # resolve gives one or raises
        joint, coordinate, start, stop = model.motion_drive()
        values = np.linspace(start, stop, model.motion.steps)
        poses = nominal_poses(model, values, settings=motion.settings, source=source)
        return cls(model, joint.name, coordinate, values, poses, source)

    @property
    def steps(self) -> int:
        return len(self.values)

    def posed(self, step: int) -> Model:
        return posed_model(self.model, self.poses, step, self.source)


def _unit(coordinate: str) -> str:
    return "deg" if coordinate == "spin" else "mm"


# -- Monte Carlo over the motion -------------------------------------------------


@dataclass(frozen=True)
class MotionMonteCarlo:
    """Settings of a Monte Carlo over the motion; ``run`` returns a
    ``MotionMonteCarloResult``. ``samples``: sets of parts; ``seed`` and
    ``chunk`` fix the random streams as in ``MonteCarlo`` (the same seed
    draws the same parts); ``motion``: the drive, range, steps and load case
    (``Motion``; default: the model's ``motion`` section and loads)."""

    samples: int = 1000
    seed: int = 0
    chunk: int = 10_000
    motion: Motion = field(default_factory=Motion)

    def __post_init__(self) -> None:
        if self.samples < 1:
            raise ValueError("samples: at least 1")
        if self.chunk < 1:
            raise ValueError("chunk: at least 1")

    def run(
        self, model: Model, *, workers: int | None = 1, source: str | None = None
    ) -> MotionMonteCarloResult:
        """Draw the parts and solve them at every pose. ``workers``: local
        processes, each solving whole poses (None: one per core; 1: this
        process). ``source``: the model file's name, for messages."""
        cycle = _Cycle.of(self.motion, model, source or model.name or "<model>")
        first = cycle.posed(0)
        _check_inputs(first, self.motion.case, cycle.source)
        asm = assemble(first)
        pmap, lmap, dmap = (
            play_map(asm, cycle.source),
            load_map(asm, self.motion.case),
            deviation_map(asm),
        )
        drawn = []
        left, index = self.samples, 0
        while left > 0:
            n = min(self.chunk, left)
            rng = np.random.default_rng([self.seed, index])
            # plays, then loads, then deviations: as MonteCarlo draws them
            drawn.append((pmap.sample(rng, n), lmap.sample(rng, n), dmap.sample(rng, n)))
            left, index = left - n, index + 1
        plays, loads, deviations = (np.concatenate(part) for part in zip(*drawn, strict=True))
        return self._solved(cycle, plays, loads, deviations, workers)

    def run_parts(
        self,
        model: Model,
        plays: FloatArray,
        loads: FloatArray | None = None,
        deviations: FloatArray | None = None,
        *,
        workers: int | None = 1,
        source: str | None = None,
    ) -> MotionMonteCarloResult:
        """The given sets of parts (rows; columns as ``play_labels``,
        ``load_labels`` and ``deviation_labels`` of a result; default: the
        loads' and deviations' nominal values) through the motion."""
        cycle = _Cycle.of(self.motion, model, source or model.name or "<model>")
        first = cycle.posed(0)
        if not first.points:
            raise _no_points(cycle.source)
        asm = assemble(first)
        lmap, dmap = load_map(asm, self.motion.case), deviation_map(asm)
        plays = np.atleast_2d(np.asarray(plays, dtype=float))
        n = len(plays)
        loads = np.tile(lmap.nominal, (n, 1)) if loads is None else np.atleast_2d(loads)
        if deviations is None:
            deviations = np.zeros((n, len(dmap.labels)))
        return self._solved(cycle, plays, loads, np.atleast_2d(deviations), workers)

    def _solved(
        self,
        cycle: _Cycle,
        plays: FloatArray,
        loads: FloatArray,
        deviations: FloatArray,
        workers: int | None,
    ) -> MotionMonteCarloResult:
        solved = _carried(cycle, (plays, loads, deviations), self.motion.case, workers)
        first = cycle.posed(0)
        asm = assemble(first)
        pmap, lmap, dmap = (
            play_map(asm, cycle.source),
            load_map(asm, self.motion.case),
            deviation_map(asm),
        )
        return MotionMonteCarloResult(
            self,
            cycle.model.name,
            cycle.drive,
            cycle.coordinate,
            cycle.values,
            tuple(p.name for p in first.points),
            tuple(first.requirements),
            pmap.labels,
            plays,
            lmap.labels,
            loads,
            dmap.labels,
            deviations,
            np.array([p.displacement for p in solved]),
            sum(p.batched for p in solved),
            sum(p.full_solves for p in solved),
            max(p.feasibility_mm for p in solved),
            max(p.equilibrium_residual for p in solved),
        )


def _carried(
    cycle: _Cycle,
    parts: tuple[FloatArray, FloatArray, FloatArray],
    case: str | None,
    workers: int | None,
    steps: tuple[int, int] | None = None,
    on_done: Callable[[list[_Pose]], None] | None = None,
) -> list[_Pose]:
    """The sets of parts ``parts`` (plays, loads, deviations) at the poses
    ``steps`` (first, stop; default: all), in contiguous runs of poses, one
    per process: each part starts from its answer at the pose before.
    ``on_done(run)`` after each run."""
    first, stop = (0, cycle.steps) if steps is None else steps
    runs = min(stop - first, workers or os.cpu_count() or 1)
    edges = np.linspace(first, stop, runs + 1).round().astype(int).tolist()
    tasks = list(itertools.pairwise(edges))
    shared = (cycle, *parts, case)
    return sorted(
        (
            pose
            for run in run_chunks(_solve_poses, shared, tasks, workers, None, on_done)
            for pose in run
        ),
        key=lambda p: p.step,
    )


def _no_points(source: str) -> StudyError:
    return StudyError(
        "a Monte Carlo study measures functional points, and the model has none; add "
        "'points: [{name: tip, body: ..., at: [x, y, z]}]'",
        source=source,
        entry="points",
    )


def _check_inputs(model: Model, case: str | None, source: str) -> None:
    check_case(model, case, source, "the study over the motion")
    asm = assemble(model)
    if (
        not play_map(asm, source).variables
        and not load_map(asm, case).variables
        and not deviation_map(asm).variables
    ):
        raise nothing_varies("every set of parts would be the same at every pose", source)
    if not model.points:
        raise _no_points(source)


@dataclass(frozen=True)
class _Pose:
    step: int
    displacement: FloatArray  # (N, P, 3) mm
    batched: int
    full_solves: int
    feasibility_mm: float
    equilibrium_residual: float


def _solve_poses(
    shared: tuple[_Cycle, FloatArray, FloatArray, FloatArray, str | None], first: int, stop: int
) -> list[_Pose]:
    """Poses ``first`` to ``stop - 1`` in turn, each part's Newton starting
    from its own answers at the two poses before, extrapolated (its touching
    contacts seldom change over a step)."""
    poses = []
    before: tuple[Start | None, ...] | None = None
    last: tuple[Start | None, ...] | None = None
    for step in range(first, stop):
        own = last
        if before is not None and last is not None:
            own = tuple(extrapolated(b, a) for b, a in zip(before, last, strict=True))
        pose, after = _solve_pose(shared, step, own)
        before, last = last, after
        poses.append(pose)
    return poses


def _solve_pose(
    shared: tuple[_Cycle, FloatArray, FloatArray, FloatArray, str | None],
    step: int,
    own: tuple[Start | None, ...] | None,
) -> tuple[_Pose, tuple[Start | None, ...] | None]:
    """Every set of parts at pose ``step``: the posed model assembled once,
    the parts' radii, loads and centres from its maps, one batch."""
    cycle, plays, loads, deviations, case = shared
    model = cycle.posed(step)
    asm = assemble(model)
    pmap, lmap, dmap = play_map(asm, cycle.source), load_map(asm, case), deviation_map(asm)
    n = len(plays)
    work = lmap.work(loads) if lmap.variables else np.tile(lmap.g0, (n, 1))
    ws = Workspace(asm)
    radii, centres = pmap.radii(plays), None
    if dmap.variables:
        radii = radii + dmap.radii_shift(deviations)
        centres = dmap.centres(deviations)
    nominal = solved_start(ws, lmap.g0)  # the model's own parts start the batch's Newton
    batch = ws.solve_batch(
        work,
        radii,
        centres,
        forces=False,
        starts=() if nominal is None else (nominal,),
        own_starts=own if own is not None else (None,) * n,
    )
    displacement = np.zeros((n, len(model.points), 3))
    length = Resolution.of(asm.s, asm.ell, settings=ws.settings).length
    for k, point in enumerate(model.points):
        motion = batch.body_displacement(point.body)
        at = np.asarray(point.at)
        displacement[:, k] = proven(motion[:, :3] + np.cross(motion[:, 3:], at), length)
    displacement[~batch.assembled] = np.nan  # parts that cannot be put together at this pose
    pose = _Pose(
        step,
        displacement,
        int(np.sum(batch.batched)),
        batch.full_solves,
        float(np.max(batch.feasibility_mm, initial=0.0)),
        float(np.max(batch.equilibrium_residual, initial=0.0)),
    )
    return pose, batch.own_starts


@dataclass(frozen=True)
class MotionMonteCarloResult:
    """Every set of parts at every step: ``displacement`` (S, N, P, 3) mm,
    global axes (NaN where a set cannot be assembled at that pose), with
    the parts drawn (``plays`` (N, nv) mm, ``loads``, ``deviations``)."""

    settings: MotionMonteCarlo
    model_name: str | None
    drive: str
    coordinate: str  # "spin" or "slide"
    values: FloatArray  # (S,) rad or mm
    point_names: tuple[str, ...]
    requirements: tuple[Requirement, ...]
    play_labels: tuple[str, ...]
    plays: FloatArray
    load_labels: tuple[str, ...]
    loads: FloatArray
    deviation_labels: tuple[str, ...]
    deviations: FloatArray
    displacement: FloatArray
    batched: int  # samples the batched Newton solved, over every pose
    full_solves: int
    feasibility_mm: float  # worst over every sample and pose
    equilibrium_residual: float

    @property
    def steps(self) -> int:
        return len(self.values)

    @property
    def samples(self) -> int:
        return int(self.plays.shape[0])

    @property
    def unit(self) -> str:
        return _unit(self.coordinate)

    def shown_value(self, s: int) -> float:
        return shown_drive(self.coordinate, float(self.values[s]))

    def measure(self, point: str, direction: Any = None) -> FloatArray:
        """(S, N) mm: each part's displacement of ``point`` per step, along
        ``direction`` (global, any length; signed), or its size (None)."""
        d = self.displacement[:, :, self._point(point)]
        if direction is None:
            return np.asarray(np.linalg.norm(d, axis=-1))
        u = np.asarray(direction, dtype=float)
        return np.asarray(d @ (u / np.linalg.norm(u)))

    def band(
        self, point: str, lower_pct: float, upper_pct: float, direction: Any = None
    ) -> tuple[FloatArray, FloatArray]:
        """The ``lower_pct`` and ``upper_pct`` percentiles (in %) per step
        (mm) of ``point``'s displacement along ``direction``, or of its size
        (None), over the parts that can be assembled at that step."""
        if not 0 <= lower_pct <= upper_pct <= 100:
            raise ValueError("percentiles: 0 <= lower <= upper <= 100")
        values = self.measure(point, direction)
        lower, upper = np.full(self.steps, np.nan), np.full(self.steps, np.nan)
        for s in range(self.steps):
            row = values[s][~np.isnan(values[s])]
            if row.size:
                lower[s], upper[s] = np.percentile(row, [lower_pct, upper_pct])
        return lower, upper

    def failing(self, q: int) -> FloatArray:
        """(N,) bool: the parts that miss requirement ``q`` at some step (or
        cannot be assembled at some step)."""
        req = self.requirements[q]
        d = self.displacement[:, :, self._point(req.point)]
        with np.errstate(invalid="ignore"):
            out = (req.measure(d) > req.max_displacement) | np.isnan(d[..., 0])
        return np.asarray(np.any(out, axis=0))

    def fraction_failing(self, q: int) -> float:
        """The fraction of parts that miss requirement ``q`` anywhere in the cycle."""
        return float(np.mean(self.failing(q)))

    def failing_per_step(self, q: int) -> FloatArray:
        """(S,) the fraction of parts that miss requirement ``q`` at each step."""
        req = self.requirements[q]
        d = self.displacement[:, :, self._point(req.point)]
        with np.errstate(invalid="ignore"):
            out = (req.measure(d) > req.max_displacement) | np.isnan(d[..., 0])
        return np.asarray(np.mean(out, axis=1))

    @property
    def unassembled(self) -> int:
        """Sets of parts that cannot be assembled at some step."""
        if not self.point_names:
            return 0
        return int(np.sum(np.any(np.isnan(self.displacement[:, :, 0, 0]), axis=0)))

    def _point(self, name: str) -> int:
        if name not in self.point_names:
            raise ValueError(f"point {name!r}: not one of {', '.join(self.point_names)}")
        return self.point_names.index(name)

    def _directions(self, point: str) -> list[tuple[float, float, float]]:
        """The distinct directions of the requirements on ``point``."""
        out: list[tuple[float, float, float]] = []
        for req in self.requirements:
            if req.point == point and req.along is not None:
                u = np.asarray(req.along, dtype=float)
                t = tuple(float(c) for c in u / np.linalg.norm(u))
                if t not in out:
                    out.append(t)  # type: ignore[arg-type]
        return out

    def _percentiles(self, point: str, direction: Any) -> dict[str, list[float | None]]:
        out = {}
        for lo in (p for p in PERCENTILES if p < 50):
            hi = 100.0 - lo
            a, b = self.band(point, lo, hi, direction)
            out[f"{lo:g}"], out[f"{hi:g}"] = _floats(a), _floats(b)
        median, _ = self.band(point, 50.0, 50.0, direction)
        out["50"] = _floats(median)
        return {k: out[k] for k in sorted(out, key=float)}

    def to_dict(self) -> dict[str, Any]:
        """Per point, per percentile, the value at each step (mm), of the
        size and along each requirement's direction; per requirement the
        parts that miss it anywhere in the cycle."""
        points = {}
        for name in self.point_names:
            points[name] = {
                "size": self._percentiles(name, None),
                "along": [
                    {"direction": list(u), "percentiles": self._percentiles(name, u)}
                    for u in self._directions(name)
                ],
            }
        return {
            "study": "motion_monte_carlo",
            "model": self.model_name,
            "samples": self.samples,
            "seed": self.settings.seed,
            "chunk": self.settings.chunk,
            "drive": {"joint": self.drive, "coordinate": self.coordinate, "unit": self.unit},
            "values": [self.shown_value(s) for s in range(self.steps)],
            "unassembled": self.unassembled,
            "points": points,
            "requirements": [
                {
                    "point": req.point,
                    "max_displacement": req.max_displacement,
                    "along": None if req.along is None else list(req.along),
                    "outside": int(np.sum(self.failing(q))),
                    "fraction_outside": self.fraction_failing(q),
                    "fraction_outside_per_step": _floats(self.failing_per_step(q)),
                }
                for q, req in enumerate(self.requirements)
            ],
            "certificate": {
                "feasibility_mm": self.feasibility_mm,
                "equilibrium_residual": self.equilibrium_residual,
                "batched": self.batched,
                "full_solves": self.full_solves,
            },
        }

    def band_columns(self) -> dict[str, FloatArray]:
        """Per step (mm): each point's size at the 2.5, 50 and 97.5
        percentiles, and its component along each requirement's direction
        at the same, keyed by column name."""
        out: dict[str, FloatArray] = {}
        for name in self.point_names:
            for label, u in (("|d|", None), *((_along(u), u) for u in self._directions(name))):
                lo, hi = self.band(name, 2.5, 97.5, u)
                median, _ = self.band(name, 50.0, 50.0, u)
                out[f"{name} {label} p2.5 (mm)"] = lo
                out[f"{name} {label} p50 (mm)"] = median
                out[f"{name} {label} p97.5 (mm)"] = hi
        return out

    def to_dataframe(self) -> pd.DataFrame:
        """One row per step: the drive's value and the band columns."""
        import pandas as pd

        columns: dict[str, Any] = {
            "step": np.arange(self.steps),
            f"drive ({self.unit})": [self.shown_value(s) for s in range(self.steps)],
        }
        columns.update(self.band_columns())
        for q, req in enumerate(self.requirements):
            columns[f"{req.point} fraction outside (req {q})"] = self.failing_per_step(q)
        return pd.DataFrame(columns)

    to_frame = to_dataframe


def _along(u: Any) -> str:
    return "along [" + ", ".join(f"{c:.4g}" for c in u) + "]"


def _values(v: FloatArray) -> list[float]:
    return [float(c) for c in v]


def _floats(v: FloatArray) -> list[float | None]:
    """JSON numbers; None where there is no value (no part assembled at a
    step, no probe held)."""
    return [float(c) + 0.0 if np.isfinite(c) else None for c in v]


# -- worst-case envelope at every pose -------------------------------------------


@dataclass(frozen=True)
class MotionEnvelope:
    """Settings of the worst-case envelope at every pose (``Envelope`` on
    each posed model, for every functional point); ``run`` returns a
    ``MotionEnvelopeResult``. ``loads``: as ``Envelope``'s, chosen once for
    the whole motion: ``auto`` takes the model's loads where they vary, a
    table over the drive's value included (``envelope.default_loads``)."""

    directions: int = 200
    plays: Literal["max", "mean"] = "max"
    loads: Literal["auto", "model", "probes"] = "auto"
    motion: Motion = field(default_factory=Motion)

    def run(
        self, model: Model, *, source: str | None = None, progress: Progress | None = None
    ) -> MotionEnvelopeResult:
        """Every point's envelope at every pose; ``progress(done, total)`` after each pose."""
        from jointplay.studies.envelope import Envelope, default_loads

        cycle = _Cycle.of(self.motion, model, source or model.name or "<model>")
        # chosen on the model as written: at a pose its tables are read to one value
        loads = (
            default_loads(cycle.model, self.motion.case, tables=True)
            if self.loads == "auto"
            else self.loads
        )
        names = tuple(p.name for p in cycle.model.points)
        if not names:
            raise StudyError(
                "an envelope is a functional point's; the model has none: add "
                "'points: [{name: tip, body: ..., at: [x, y, z]}]'",
                source=cycle.source,
                entry="points",
            )
        found: list[tuple[EnvelopeResult, ...]] = []
        # each point's probes at a pose start from their answers at the pose before
        carried: dict[str, dict[tuple[int, int], Any]] = {name: {} for name in names}
        for s in range(cycle.steps):
            posed = cycle.posed(s)
            found.append(
                tuple(
                    Envelope(name, self.directions, self.plays, loads, case=self.motion.case)._run(
                        posed, source=cycle.source, carry=carried[name]
                    )
                    for name in names
                )
            )
            if progress is not None:
                progress(s + 1, cycle.steps)
        return MotionEnvelopeResult(
            self,
            cycle.model.name,
            cycle.drive,
            cycle.coordinate,
            cycle.values,
            names,
            tuple(cycle.model.requirements),
            tuple(found),
            _under(cycle.model, found[0][0].settings),
        )


def _under(model: Model, envelope: Envelope) -> str:
    """What a motion's envelope is under (``Envelope`` settings), in a few words."""
    if envelope.loads == "model":
        return "the model's loads"
    # the probes push against what ``Envelope`` holds standing
    standing = model.weights() or any(ld.standing for ld in model.loads)
    return f"{envelope.probe:g} N probes" + (" against the standing loads" if standing else "")


@dataclass(frozen=True)
class MotionEnvelopeResult:
    """Per step, per point, its ``EnvelopeResult`` on the posed model."""

    settings: MotionEnvelope
    model_name: str | None
    drive: str
    coordinate: str
    values: FloatArray
    point_names: tuple[str, ...]
    requirements: tuple[Requirement, ...]
    envelopes: tuple[tuple[EnvelopeResult, ...], ...]  # (S, P)
    #: What the envelope is under, in words: "the model's loads", "1 N probes".
    under: str

    @property
    def loads(self) -> str:
        """``"model"`` or ``"probes"``: the loads every step's envelope is over."""
        return self.envelopes[0][0].settings.loads if self.envelopes else self.settings.loads

    @property
    def steps(self) -> int:
        return len(self.values)

    @property
    def unit(self) -> str:
        return _unit(self.coordinate)

    def shown_value(self, s: int) -> float:
        return shown_drive(self.coordinate, float(self.values[s]))

    def at(self, step: int, point: str) -> EnvelopeResult:
        return self.envelopes[step][self.point_names.index(point)]

    def extent(self, point: str, direction: Any = None) -> tuple[FloatArray, FloatArray]:
        """Per step (mm): the least and the greatest component of ``point``'s
        envelope along ``direction`` (over its support points: exact along
        the global axes and over the model's loads), or, with None, 0 and
        its largest displacement."""
        k = self.point_names.index(point)
        if direction is None:
            upper = np.array([row[k].largest for row in self.envelopes], dtype=float)
            return np.zeros(self.steps), upper
        u = np.asarray(direction, dtype=float)
        u = u / np.linalg.norm(u)
        along = [row[k].hull @ u for row in self.envelopes]  # none held: NaN
        return (
            np.array([float(a.min()) if a.size else np.nan for a in along]),
            np.array([float(a.max()) if a.size else np.nan for a in along]),
        )

    def worst_step(self, q: int) -> int:
        """The step where the envelope goes farthest against requirement ``q``."""
        req = self.requirements[q]
        lower, upper = self.extent(req.point, req.along)
        return int(np.argmax(np.maximum(np.abs(lower), np.abs(upper))))

    def to_dict(self) -> dict[str, Any]:
        points = {}
        for name in self.point_names:
            k = self.point_names.index(name)
            _, upper = self.extent(name)
            entry: dict[str, Any] = {
                "largest": _floats(upper),
                "extent": {
                    axis: [
                        [float(row[k].extent[i, 0]), float(row[k].extent[i, 1])]
                        for row in self.envelopes
                    ]
                    for i, axis in enumerate("xyz")
                },
                "along": [],
            }
            for req in self.requirements:
                if req.point == name and req.along is not None:
                    lo, hi = self.extent(name, req.along)
                    entry["along"].append(
                        {"direction": list(req.along), "lower": _floats(lo), "upper": _floats(hi)}
                    )
            points[name] = entry
        return {
            "study": "motion_envelope",
            "model": self.model_name,
            "plays": self.settings.plays,
            "loads": self.envelopes[0][0].over if self.envelopes and self.envelopes[0] else "",
            "values": [self.shown_value(s) for s in range(self.steps)],
            "points": points,
            "requirements": [
                {
                    "point": req.point,
                    "worst_step": self.worst_step(q),
                    "drive": self.shown_value(self.worst_step(q)),
                }
                for q, req in enumerate(self.requirements)
            ],
        }


# -- contributions at every pose -------------------------------------------------


@dataclass(frozen=True)
class MotionContributions:
    """Settings of the contributions at every pose: ``Contributions`` with
    these settings on each posed model, so a pose gets what ``jointplay
    contributions`` gives there (the linear shares where the measure is
    linear over the ranges; where it is not, its reason and, with
    ``variance="auto"``, the shares of the variance); ``run`` returns a
    ``MotionContributionsResult``."""

    step: float = 1e-3
    variance: Literal["auto", "always", "never"] = "auto"
    samples: int = 1024
    seed: int = 0
    motion: Motion = field(default_factory=Motion)

    def study(self) -> Contributions:
        """The plain study taken at every pose."""
        from jointplay.studies.contributions import Contributions

        return Contributions(self.step, self.motion.case, self.variance, self.samples, self.seed)

    def run(
        self,
        model: Model,
        *,
        source: str | None = None,
        progress: Progress | None = None,
        workers: int | None = 1,
    ) -> MotionContributionsResult:
        """The contributions at every pose; ``progress(done, total)`` after
        each pose's linear shares, then after each run of poses of the shares
        of the variance (``total`` grows by them); ``workers``: local processes. Where the
        shares of the variance are taken, the Sobol' design's sets of parts
        are carried through the poses as a Monte Carlo's are (each Newton
        from the same set's answers at the poses before), then analysed
        pose by pose: what ``Contributions`` gives there, at a fraction of
        the time."""
        from jointplay.studies.sobol import Sobol

        cycle = _Cycle.of(self.motion, model, source or model.name or "<model>")
        study = self.study()
        linear = replace(study, variance="never")
        found_at = []
        for s in range(cycle.steps):
            found_at.append(linear.run(cycle.posed(s), source=cycle.source, workers=workers))
            if progress is not None:
                progress(s + 1, cycle.steps)
        wanted = [
            s
            for s, found in enumerate(found_at)
            if self.variance == "always"
            or (self.variance == "auto" and not all(c.linear for c in found.linearity))
        ]
        if wanted:
            sobol = Sobol(self.samples, self.seed, case=self.motion.case)
            designs = [sobol.design(cycle.posed(s), cycle.source) for s in wanted]
            problem, values = designs[0]
            if all(np.array_equal(v, values) for _, v in designs):
                # one design for every pose (its inputs' laws do not move with the bodies)
                inputs = inputs_of(cycle.posed(wanted[0]), self.motion.case, cycle.source)
                n_p, n_l = len(inputs.pmap.variables), len(inputs.lmap.variables)
                parts = (values[:, :n_p], values[:, n_p : n_p + n_l], values[:, n_p + n_l :])
                span = (wanted[0], wanted[-1] + 1)  # the poses from the first to the last
                done = [cycle.steps]

                def advance(run: list[_Pose]) -> None:
                    done[0] += len(run)
                    if progress is not None:
                        progress(done[0], cycle.steps + span[1] - span[0])

                carried = {
                    pose.step: pose.displacement
                    for pose in _carried(cycle, parts, self.motion.case, workers, span, advance)
                }
                for s in wanted:
                    posed = cycle.posed(s)
                    y = measured(posed, measures_of(posed, cycle.source), carried[s])
                    shares = sobol.analysed(posed, problem, y, cycle.source)
                    found_at[s] = replace(found_at[s], settings=study, sobol=shares)
            else:
                for s in wanted:
                    shares = sobol.run(cycle.posed(s), workers=workers, source=cycle.source)
                    found_at[s] = replace(found_at[s], settings=study, sobol=shares)
        found = tuple(found_at)
        return MotionContributionsResult(
            self, cycle.model.name, cycle.drive, cycle.coordinate, cycle.values, found
        )


@dataclass(frozen=True)
class MotionContributionsResult:
    """Per step, the ``ContributionsResult`` of the posed model."""

    settings: MotionContributions
    model_name: str | None
    drive: str
    coordinate: str
    values: FloatArray
    results: tuple[ContributionsResult, ...] = field(default=())

    @property
    def steps(self) -> int:
        return len(self.values)

    @property
    def measures(self) -> tuple[str, ...]:
        return self.results[0].measures if self.results else ()

    @property
    def plays(self) -> tuple[str, ...]:
        return self.results[0].plays if self.results else ()

    def shown_value(self, s: int) -> float:
        return shown_drive(self.coordinate, float(self.values[s]))

    def linear(self, k: int) -> np.ndarray[Any, np.dtype[np.bool_]]:
        """(S,) whether measure ``k`` is linear over the ranges at each step
        (where not, its linear stack, RSS and shares do not hold there)."""
        return np.array([r.linear(k) for r in self.results], dtype=bool)

    def by_variance(self, k: int, step: int) -> bool:
        """Whether measure ``k``'s shares at ``step`` are of its variance:
        not linear there, and the Sobol' study taken."""
        r = self.results[step]
        return not r.linear(k) and r.sobol is not None

    def worst_case(self, k: int) -> FloatArray:
        """(S, nv) % of measure ``k``'s arithmetic stack per step and play
        (the linear shares; they hold only where ``linear``)."""
        return np.array([r.worst_case[k] for r in self.results])

    def shares(self, k: int) -> FloatArray:
        """(S, nv) % per step and play, as ``jointplay contributions`` ranks
        them there: the worst-case share where the shares are linear, the
        total Sobol' index where they are of the variance (``by_variance``)."""
        return np.array(
            [
                100.0 * r.sobol.total[k]  # type: ignore[union-attr]
                if self.by_variance(k, s)
                else r.worst_case[k]
                for s, r in enumerate(self.results)
            ]
        )

    def spread(self, k: int) -> FloatArray:
        """(S,) mm: measure ``k``'s linear worst-case spread ``sum |s| T`` per
        step; NaN where it is not linear over the ranges."""
        return np.array(
            [float(r.worst_case_range[k]) if r.linear(k) else np.nan for r in self.results]
        )

    def sigma(self, k: int) -> FloatArray:
        """(S,) mm: measure ``k``'s standard deviation per step: RSS's where
        linear, the Sobol' study's sample where the shares are of the variance."""
        return np.array(
            [
                float(np.sqrt(r.sobol.variance[k]))  # type: ignore[union-attr]
                if self.by_variance(k, s)
                else float(r.rss_sigma[k])
                for s, r in enumerate(self.results)
            ]
        )

    def worst_step(self, k: int) -> int:
        """The step where measure ``k`` varies most from part to part (its
        ``sigma``: a figure every step has, linear or not)."""
        return int(np.argmax(self.sigma(k)))

    def leading(self, k: int, step: int | None = None) -> str:
        """The play with the largest share (``shares``) of measure ``k`` at
        ``step`` (default: its worst step); the first in the model's order
        where several tie (``leading_plays`` names them all)."""
        s = self.worst_step(k) if step is None else step
        return self.plays[int(np.argmax(self.shares(k)[s]))]

    def leading_plays(self, k: int, step: int | None = None) -> tuple[str, ...]:
        """Every play whose share of measure ``k`` at ``step`` (default: its
        worst step) is the largest as the findings print it (``share_words``):
        two pins of one fit read '50 %' both, and both are named."""
        s = self.worst_step(k) if step is None else step
        return tuple(self.plays[i] for i in tied_largest(self.shares(k)[s]))

    def why(self, k: int, step: int) -> str:
        """Why measure ``k``'s linear figures do not hold at ``step`` ('' where they do)."""
        r = self.results[step]
        return r.linearity[k].why() if r.linearity else ""

    def to_dict(self) -> dict[str, Any]:
        return {
            "study": "motion_contributions",
            "model": self.model_name,
            "values": [self.shown_value(s) for s in range(self.steps)],
            "plays": list(self.plays),
            "measures": [
                {
                    "measure": name,
                    "linear": [bool(v) for v in self.linear(k)],
                    "not_linear_why": [self.why(k, s) for s in range(self.steps)],
                    "shares_of": [
                        "variance" if self.by_variance(k, s) else "worst_case"
                        for s in range(self.steps)
                    ],
                    "spread": _floats(self.spread(k)),
                    "sigma": _floats(self.sigma(k)),
                    "share_percent": {
                        play: _floats(self.shares(k)[:, i]) for i, play in enumerate(self.plays)
                    },
                    "worst_case_percent": {
                        play: _floats(self.worst_case(k)[:, i]) for i, play in enumerate(self.plays)
                    },
                    "worst_step": self.worst_step(k),
                    "leading": self.leading(k),
                    "leading_per_step": [self.leading(k, s) for s in range(self.steps)],
                }
                for k, name in enumerate(self.measures)
            ],
        }


def share_words(percent: float) -> str:
    """A share as the findings print it: '50', '33.3' (3 significant digits)."""
    return f"{percent:.3g}"


def tied_largest(shares: Any) -> list[int]:
    """The indices, in order, of the shares that print (``share_words``) as
    the largest does: the plays that tie for the lead to the resolution
    shown. Only the largest where it is not a positive number (nothing to
    share: all would tie at '0')."""
    values = np.asarray(shares, dtype=float)
    first = int(np.argmax(values))
    top = float(values[first])
    if not (np.isfinite(top) and top > 0):
        return [first]
    shown = share_words(top)
    return [i for i, v in enumerate(values) if share_words(float(v)) == shown]


def _and(names: tuple[str, ...]) -> str:
    """'a', 'a and b', 'a, b and c'."""
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def _contribution_findings(con: MotionContributionsResult, k: int, measure: str) -> list[str]:
    """Measure ``k``'s sentences: where it varies most and which play drives
    it there, by the shares ``jointplay contributions`` gives at that pose;
    the steps where it is not linear over the ranges, and why."""
    s = con.worst_step(k)
    share = share_words(float(np.max(con.shares(k)[s])))
    leading = con.leading_plays(k, s)
    at = f"at step {s} (drive {con.shown_value(s):.6g} {_unit(con.coordinate)})"
    if con.linear(k)[s]:
        spread = f"worst-case spread {con.spread(k)[s]:.6g} mm, RSS sigma {con.sigma(k)[s]:.6g} mm"
        of = "of the worst-case stack"
    else:
        spread = f"sigma {con.sigma(k)[s]:.6g} mm; the linear stack and RSS do not hold there"
        of = "total share of the variance" if con.by_variance(k, s) else "linear share"
    out = [
        f"contributions to {measure}: it varies most {at}: {spread}; driven by "
        f"{_and(leading)} ({'each ' if len(leading) > 1 else ''}{share} % {of})"
    ]
    bent = np.flatnonzero(~con.linear(k))
    if bent.size:
        b = s if s in bent else int(bent[0])
        shares = (
            "the shares there are of the variance (Sobol' indices)"
            if all(con.by_variance(k, int(b)) for b in bent)
            else "the linear shares there do not hold"
        )
        out.append(
            f"  {measure} is not linear over the ranges at {bent.size} of {con.steps} steps "
            f"({_step_runs(bent)}); {shares}; at step {b}: {con.why(k, b)}"
        )
    return out


def _step_runs(steps: Any) -> str:
    """'0-4, 9, 12-20': runs of consecutive steps."""
    runs: list[list[int]] = []
    for step in (int(v) for v in steps):
        if runs and step == runs[-1][-1] + 1:
            runs[-1].append(step)
        else:
            runs.append([step])
    return ", ".join(str(r[0]) if len(r) == 1 else f"{r[0]}-{r[-1]}" for r in runs)


# -- the motion with its studies -------------------------------------------------


@dataclass(frozen=True)
class MotionStudiesResult:
    """The nominal motion (``MotionResult``) with the studies taken over it
    (each None when not asked for): one document, one table."""

    motion: MotionResult
    monte_carlo: MotionMonteCarloResult | None = None
    envelope: MotionEnvelopeResult | None = None
    contributions: MotionContributionsResult | None = None

    def to_dict(self) -> dict[str, Any]:
        doc = self.motion.to_dict()
        for key, study in (
            ("monte_carlo", self.monte_carlo),
            ("envelope", self.envelope),
            ("contributions", self.contributions),
        ):
            if study is not None:
                doc[key] = study.to_dict()
        return doc

    def shown_direction(self, point: str) -> tuple[str, Any]:
        """What the table shows of ``point``: its component along its first
        requirement's direction, or its size."""
        for req in self.motion.results[0].requirements if self.motion.results else ():
            if req.requirement.point == point and req.requirement.along is not None:
                return _along(req.requirement.along), req.requirement.along
        return "|d|", None

    def columns(self) -> dict[str, list[float] | list[str]]:
        """Per step, the studies' columns: each point's 2.5-97.5 % band and
        its envelope's extent (mm, as ``shown_direction``), each measure's
        leading play and its worst-case share."""
        out: dict[str, list[float] | list[str]] = {}
        for name in self.motion.point_names:
            label, u = self.shown_direction(name)
            if self.monte_carlo is not None:
                lo, hi = self.monte_carlo.band(name, 2.5, 97.5, u)
                out[f"{name} {label} p2.5 (mm)"] = _values(lo)
                out[f"{name} {label} p97.5 (mm)"] = _values(hi)
            if self.envelope is not None:
                lo, hi = self.envelope.extent(name, u)
                if u is not None:  # a size's least is no bound worth a column
                    out[f"{name} {label} envelope min (mm)"] = _values(lo)
                out[f"{name} {label} envelope max (mm)"] = _values(hi)
        if self.contributions is not None:
            con = self.contributions
            for k, measure in enumerate(con.measures):
                out[f"{measure} linear"] = ["yes" if v else "no" for v in con.linear(k)]
                out[f"{measure} leading play"] = [con.leading(k, s) for s in range(con.steps)]
                out[f"{measure} leading share (%)"] = [float(row.max()) for row in con.shares(k)]
        return out

    def picture_extras(
        self,
    ) -> tuple[
        dict[str, list[tuple[str, FloatArray, FloatArray]]],
        dict[str, tuple[FloatArray, FloatArray]],
    ]:
        """Per point, the Monte Carlo's bands (0.135-99.865 % and 2.5-97.5 %:
        label, lower, upper per step; a band only where the samples put a
        part beyond each of its ends, on average: 741 and 40 samples) and the
        envelope's extent, as ``shown_direction``: what the motion's figure draws."""
        bands: dict[str, list[tuple[str, FloatArray, FloatArray]]] = {}
        envelopes: dict[str, tuple[FloatArray, FloatArray]] = {}
        for name in self.motion.point_names:
            _, u = self.shown_direction(name)
            if self.monte_carlo is not None:
                bands[name] = [
                    (f"{lo:g}-{100 - lo:g} %", *self.monte_carlo.band(name, lo, 100 - lo, u))
                    for lo in (0.135, 2.5)
                    if self.monte_carlo.samples * lo / 100 >= 1
                ]
            if self.envelope is not None:
                envelopes[name] = self.envelope.extent(name, u)
        return bands, envelopes

    def envelope_label(self) -> str:
        """The envelope's name in the motion's figure: what it is under."""
        under = "" if self.envelope is None else f" under {self.envelope.under}"
        return "worst-case envelope" + under

    def findings(self) -> list[str]:
        """A sentence per requirement and study: how many parts miss it
        anywhere in the cycle, where the envelope goes farthest, which play
        drives each measure where its spread is largest."""
        out = []
        mc, env, con = self.monte_carlo, self.envelope, self.contributions
        for q, req in enumerate(mc.requirements if mc is not None else ()):
            assert mc is not None
            failing = int(np.sum(mc.failing(q)))
            per_step = mc.failing_per_step(q)
            s = int(np.argmax(per_step))
            head = f"Monte Carlo ({mc.samples:,} sets of parts, seed {mc.settings.seed}): "
            if not failing:
                out.append(f"{head}none miss the requirement on {req.point} at any step")
                continue
            out.append(
                f"{head}{failing:,} ({100 * failing / mc.samples:.4g} %) miss the requirement on "
                f"{req.point} somewhere in the cycle; most at step {s} (drive "
                f"{mc.shown_value(s):.6g} {mc.unit}): {100 * per_step[s]:.4g} %"
            )
        for q, req in enumerate(env.requirements if env is not None else ()):
            assert env is not None
            s = env.worst_step(q)
            lo, hi = env.extent(req.point, req.along)
            what = "size" if req.along is None else _along(req.along)
            out.append(
                f"envelope of {req.point} ({what}) under {env.under}: farthest at step {s} "
                f"(drive {env.shown_value(s):.6g} {env.unit}): {lo[s]:.6g} to {hi[s]:.6g} mm"
            )
        if env is not None and not env.requirements:  # the columns alone would not say
            out.append(f"envelopes (their columns above) under {env.under}")
        for k, measure in enumerate(con.measures if con is not None else ()):
            assert con is not None
            out.extend(_contribution_findings(con, k, measure))
        return out

    def to_dataframe(self) -> pd.DataFrame:
        """The motion's table (one row per step) with the studies' columns."""
        frame = self.motion.to_dataframe()
        for key, values in self.columns().items():
            frame[key] = values
        return frame

    to_frame = to_dataframe
