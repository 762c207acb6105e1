"""Monte Carlo over real parts: plays drawn from their limits or ISO fits.

Each sample is one set of parts: every toleranced play of the model
(``tolerance.Toleranced``) is drawn, and the equilibrium under the model's
loads is solved exactly (``Workspace.solve_batch``: Newton on the active set
that most samples share, each answer certified on its own, the full solver
for the rest). The functional points' displacements are then summarized:
mean, standard deviation, percentiles (0.135 % and 99.865 % are the +-3 sigma
points of a normal law) and the fraction of parts that miss each requirement.

Reproducible anywhere. Samples come in chunks of a fixed size; chunk ``i``
draws from its own random stream, ``numpy.random.default_rng([seed, i])``, so
the numbers do not depend on how many processes, machines or Dask workers
solve the chunks, nor in which order: a local run and a cluster run with the
same seed give the same samples and the same answers.
"""

from __future__ import annotations

import math
import os
import uuid
from collections import OrderedDict
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from jointplay.assembly import Assembly, assemble
from jointplay.errors import StudyError, UnassembledError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model, Requirement, check_case
from jointplay.proven import Resolution, proven
from jointplay.solver.batch import Start, solved_start
from jointplay.solver.solve import Workspace
from jointplay.studies.parallel import run_chunks
from jointplay.studies.variation import (
    DeviationMap,
    LoadMap,
    PlayMap,
    deviation_map,
    load_map,
    nothing_varies,
    play_map,
)

if TYPE_CHECKING:
    import pandas as pd

#: Percentiles reported (in %): the +-3 sigma points, 2.5/97.5 and the median.
PERCENTILES = (0.135, 2.5, 50.0, 97.5, 99.865)


@dataclass(frozen=True)
class MonteCarlo:
    """Settings of a Monte Carlo study; ``run`` returns a ``MonteCarloResult``.

    ``samples``: how many sets of parts (with ``target_rel_error``: the most
    to draw). ``target_rel_error``: stop as soon as every estimate's relative
    error at ``confidence`` is below it: the fraction of parts missing each
    requirement, or, without requirements, each point's mean displacement.
    ``chunk``: samples per chunk (fixes the random streams; keep it to get the
    same numbers). ``case``: the load case to solve (needed when the model has load cases).
    """

    samples: int = 10_000
    seed: int = 0
    target_rel_error: float | None = None
    confidence: float = 0.95
    chunk: int = 10_000
    case: str | None = None

    def __post_init__(self) -> None:
        if self.samples < 1:
            raise ValueError("samples: at least 1")
        if self.chunk < 1:
            raise ValueError("chunk: at least 1")
        if self.target_rel_error is not None and not 0 < self.target_rel_error < 1:
            raise ValueError("target relative error: between 0 and 1 (0.01 is 1 %)")
        if not 0 < self.confidence < 1:
            raise ValueError("confidence: between 0 and 1 (0.95 is 95 %)")

    def run(
        self,
        model: Model,
        *,
        workers: int | None = 1,
        scheduler: str | None = None,
        progress: Callable[[int, int], None] | None = None,
        source: str | None = None,
    ) -> MonteCarloResult:
        """Draw and solve the samples. ``workers``: local processes (None: one
        per core; 1: this process). ``scheduler``: a Dask scheduler address
        (``tcp://host:8786``) to solve the chunks on a cluster instead.
        ``progress(done, total)`` is called after each chunk. ``source``: the
        model file's name, for messages."""
        source = source or model.name or "<model>"
        _study_inputs(model, self.case, source)
        sizes = _chunk_sizes(self.samples, self.chunk)
        parts: list[_Chunk] = []
        done = 0
        run = uuid.uuid4().hex  # this run's chunks share what ``_prepared`` makes
        for batch in _waves(sizes, self, workers, scheduler):
            done += sum(n for _, n in batch)
            results = _solve_chunks(model, self, batch, workers, scheduler, run)
            parts.extend(results)
            if progress is not None:
                progress(done, self.samples)
            if self.target_rel_error is not None and _converged(model, self, parts):
                break
        _PREPARED.pop((run, self.case), None)  # this process's; a worker's ages out
        return _result(model, self, parts)


@dataclass(frozen=True)
class _Chunk:
    index: int
    plays: FloatArray  # (n, nv) mm
    loads: FloatArray  # (n, nl) N or N*mm: the load components that vary
    deviations: FloatArray  # (n, nd) mm or rad: the deviations' components
    displacement: FloatArray  # (n, points, 3) mm
    batched: int
    full_solves: int
    feasibility_mm: float
    equilibrium_residual: float


def _chunk_sizes(samples: int, chunk: int) -> list[tuple[int, int]]:
    out, index, left = [], 0, samples
    while left > 0:
        out.append((index, min(chunk, left)))
        left -= chunk
        index += 1
    return out


def _waves(
    sizes: list[tuple[int, int]], mc: MonteCarlo, workers: int | None, scheduler: str | None
) -> Iterator[list[tuple[int, int]]]:
    """All chunks at once, or (converging) a few at a time, to stop early."""
    if mc.target_rel_error is None:
        yield sizes
        return
    width = 8 if scheduler else max(1, workers or (os.cpu_count() or 1))
    for lo in range(0, len(sizes), width):
        yield sizes[lo : lo + width]


def _study_inputs(model: Model, case: str | None, source: str) -> None:
    check_case(model, case, source, "the Monte Carlo study")
    asm = assemble(model)
    if (
        not play_map(asm, source).variables
        and not load_map(asm, case).variables
        and not deviation_map(asm).variables
    ):
        raise nothing_varies("every sample of a Monte Carlo would be the same", source)
    if not model.points:
        raise StudyError(
            "a Monte Carlo study measures functional points, and the model has none; add "
            "'points: [{name: tip, body: ..., at: [x, y, z]}]'",
            source=source,
            entry="points",
        )


@dataclass(frozen=True)
class _Prepared:
    """What every chunk of a study shares (``_prepared``)."""

    asm: Assembly
    pmap: PlayMap
    lmap: LoadMap
    dmap: DeviationMap
    starts: tuple[Start, ...]


#: ``_prepared``'s answers in this process, by study run (the newest few).
_PREPARED: OrderedDict[tuple[str, str | None], _Prepared] = OrderedDict()
_PREPARED_KEPT = 4  # runs: a process may serve a few studies at once (Dask)


def _prepare(model: Model, case: str | None) -> _Prepared:
    asm = assemble(model)
    lmap = load_map(asm, case)
    ws = Workspace(asm)
    ws.check_held(case)  # a model its joints do not hold has no samples to draw
    nominal = solved_start(ws, lmap.g0)
    return _Prepared(
        asm,
        play_map(asm, model.name or "<model>"),
        lmap,
        deviation_map(asm),
        () if nominal is None else (nominal,),
    )


def _prepared(model: Model, case: str | None, run: str | None) -> _Prepared:
    """The assembly, the maps from samples to radii, loads and centres, and
    the nominal sample's answer (the model as it is), made once per process
    for all the chunks of study run ``run`` (None: made for this chunk). The
    nominal answer starts every chunk's Newton: a chunk no longer pays a
    full solve of its own first sample (chunks of 10,000 ran 9 to 13 %
    slower than chunks of 50,000), and it is the same in every process, so
    a chunk's answers do not depend on where or after which other chunk it
    was solved. Runs are told apart by a token, not by the model: a model
    that has been solved carries cached arrays, which do not compare."""
    if run is None:
        return _prepare(model, case)
    key = (run, case)
    hit = _PREPARED.get(key)
    if hit is None:
        hit = _PREPARED[key] = _prepare(model, case)
        while len(_PREPARED) > _PREPARED_KEPT:
            _PREPARED.popitem(last=False)
    else:
        _PREPARED.move_to_end(key)
    return hit


def solve_chunk(model: Model, mc: MonteCarlo, index: int, size: int) -> _Chunk:
    """Chunk ``index`` of the study: its ``size`` samples, drawn and solved."""
    return _solve_chunk(model, mc, index, size, None)


def _solve_chunk(model: Model, mc: MonteCarlo, index: int, size: int, run: str | None) -> _Chunk:
    """``solve_chunk`` within study run ``run`` (a token that ``MonteCarlo.run``
    makes): what ``_prepared`` makes for the run serves its other chunks."""
    prepared = _prepared(model, mc.case, run)
    asm, pmap, lmap, dmap = prepared.asm, prepared.pmap, prepared.lmap, prepared.dmap
    rng = np.random.default_rng([mc.seed, index])
    plays = pmap.sample(rng, size)
    # after the plays, loads, then deviations: each draws nothing when none
    # varies, so a study without them keeps its random stream
    loads = lmap.sample(rng, size)
    deviations = dmap.sample(rng, size)
    work = lmap.work(loads) if lmap.variables else np.tile(lmap.g0, (size, 1))
    ws = Workspace(asm)
    radii, centres = pmap.radii(plays), None
    if dmap.variables:
        radii = radii + dmap.radii_shift(deviations)
        centres = dmap.centres(deviations)
    batch = ws.solve_batch(work, radii, centres, forces=False, starts=prepared.starts)
    displacement = np.zeros((size, len(model.points), 3))
    step = Resolution.of(asm.s, asm.ell, settings=ws.settings).length  # at the nominal plays
    for p, point in enumerate(model.points):
        motion = batch.body_displacement(point.body)
        at = np.asarray(point.at)
        displacement[:, p] = proven(motion[:, :3] + np.cross(motion[:, 3:], at), step)
    displacement[~batch.assembled] = np.nan  # every point, those on the ground too
    return _Chunk(
        index,
        plays,
        loads,
        deviations,
        displacement,
        int(np.sum(batch.batched)),
        batch.full_solves,
        float(np.max(batch.feasibility_mm, initial=0.0)),
        float(np.max(batch.equilibrium_residual, initial=0.0)),
    )


def _solve_chunks(
    model: Model,
    mc: MonteCarlo,
    chunks: Sequence[tuple[int, int]],
    workers: int | None,
    scheduler: str | None,
    run: str,
) -> list[_Chunk]:
    return run_chunks(_solve_chunk, model, [(mc, i, n, run) for i, n in chunks], workers, scheduler)


def _z(confidence: float) -> float:
    from scipy import stats  # on first use: it takes half a second to import

    return float(stats.norm.ppf(0.5 + confidence / 2))


def _outside(req: Requirement, model: Model, displacement: FloatArray) -> FloatArray:
    """(n,) bool: the samples whose point misses the requirement; a set of
    parts that cannot be assembled (NaN) misses every requirement."""
    p = [pt.name for pt in model.points].index(req.point)
    d = displacement[:, p]
    with np.errstate(invalid="ignore"):
        return np.asarray((req.measure(d) > req.max_displacement) | np.isnan(d[:, 0]))


def _converged(model: Model, mc: MonteCarlo, parts: list[_Chunk]) -> bool:
    assert mc.target_rel_error is not None
    d = np.concatenate([c.displacement for c in parts])
    return bool(np.all(_rel_errors(model, d, mc.confidence) <= mc.target_rel_error))


def _rel_errors(model: Model, displacement: FloatArray, confidence: float) -> FloatArray:
    """Relative error (half-width of the confidence interval over the estimate)
    of the study's estimates: each requirement's miss fraction, or each
    point's mean displacement size. inf while an estimate is 0."""
    n, z = displacement.shape[0], _z(confidence)
    out = []
    if model.requirements:
        for req in model.requirements:
            p = float(np.mean(_outside(req, model, displacement)))
            out.append(z * math.sqrt(p * (1 - p) / n) / p if p > 0 else math.inf)
    else:
        size = np.linalg.norm(displacement, axis=2)
        size = size[~np.isnan(size[:, 0])] if size.shape[1] else size  # assembled parts
        n = len(size)
        mean, std = np.mean(size, axis=0), np.std(size, axis=0, ddof=1) if n > 1 else 0.0
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.where(mean > 0, z * std / np.sqrt(n) / mean, math.inf)
        out.extend(np.atleast_1d(rel).tolist())
    return np.array(out)


@dataclass(frozen=True)
class PointStats:
    """One functional point over the samples (mm, global axes)."""

    name: str
    mean: FloatArray  # (3,)
    std: FloatArray  # (3,)
    percentiles: dict[float, FloatArray]  # % -> (3,) per component
    size_mean: float  # |d|
    size_std: float
    size_percentiles: dict[float, float]
    size_max: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "mean": self.mean.tolist(),
            "std": self.std.tolist(),
            "percentiles": {f"{k:g}": v.tolist() for k, v in self.percentiles.items()},
            "size": {
                "mean": self.size_mean,
                "std": self.size_std,
                "max": self.size_max,
                "percentiles": {f"{k:g}": v for k, v in self.size_percentiles.items()},
            },
        }


@dataclass(frozen=True)
class RequirementStats:
    """How many parts miss one requirement, with a confidence interval (Wilson)."""

    requirement: Requirement
    outside: int
    fraction: float
    interval: tuple[float, float]

    def to_dict(self) -> dict[str, Any]:
        return {
            "point": self.requirement.point,
            "max_displacement": self.requirement.max_displacement,
            "along": None if self.requirement.along is None else list(self.requirement.along),
            "outside": self.outside,
            "fraction_outside": self.fraction,
            "interval": list(self.interval),
            "ppm": self.fraction * 1e6,
        }


@dataclass(frozen=True)
class MonteCarloResult:
    """The samples (plays and point displacements) and their summary."""

    settings: MonteCarlo
    model_name: str | None
    play_labels: tuple[str, ...]
    point_names: tuple[str, ...]
    plays: FloatArray  # (N, nv) mm
    displacement: FloatArray  # (N, points, 3) mm
    points: dict[str, PointStats]
    requirements: tuple[RequirementStats, ...]
    relative_error: FloatArray  # the estimates' relative errors at the confidence
    batched: int  # samples solved by the batched Newton path
    full_solves: int
    feasibility_mm: float  # worst over the samples
    equilibrium_residual: float  # worst over the samples
    plays_described: dict[str, str] = field(default_factory=dict)
    load_labels: tuple[str, ...] = ()
    loads: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))  # (N, nl)
    loads_described: dict[str, str] = field(default_factory=dict)
    deviation_labels: tuple[str, ...] = ()
    deviations: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))  # (N, nd)
    deviations_described: dict[str, str] = field(default_factory=dict)
    #: Sets of parts whose deviations leave no position inside every
    #: clearance: they cannot be assembled. Their displacements are NaN, the
    #: points' statistics leave them out, and they miss every requirement.
    unassembled: int = 0

    @property
    def samples(self) -> int:
        return int(self.plays.shape[0])

    def to_dict(self) -> dict[str, Any]:
        return {
            "study": "montecarlo",
            "model": self.model_name,
            "samples": self.samples,
            "unassembled": self.unassembled,
            "seed": self.settings.seed,
            "chunk": self.settings.chunk,
            "case": self.settings.case,
            "plays": self.plays_described,
            "loads": self.loads_described,
            "deviations": self.deviations_described,
            "points": {n: p.to_dict() for n, p in self.points.items()},
            "requirements": [r.to_dict() for r in self.requirements],
            "confidence": self.settings.confidence,
            "relative_error": [float(e) for e in self.relative_error],
            "certificate": {
                "feasibility_mm": self.feasibility_mm,
                "equilibrium_residual": self.equilibrium_residual,
                "batched": self.batched,
                "full_solves": self.full_solves,
            },
        }

    def to_dataframe(self) -> pd.DataFrame:
        """One row per sample: the plays (mm), the varying load components (N,
        N*mm), the deviations' components (mm, rad) and each point's
        displacement (mm)."""
        import pandas as pd

        columns: dict[str, FloatArray] = {}
        for j, label in enumerate(self.play_labels):
            columns[label] = self.plays[:, j]
        for j, label in enumerate(self.load_labels):
            columns[label] = self.loads[:, j]
        for j, label in enumerate(self.deviation_labels):
            columns[label] = self.deviations[:, j]
        for p, name in enumerate(self.point_names):
            for c, axis in enumerate("xyz"):
                columns[f"{name}.d{axis}"] = self.displacement[:, p, c]
            columns[f"{name}.size"] = np.linalg.norm(self.displacement[:, p], axis=1)
        return pd.DataFrame(columns)

    def summary(self) -> pd.DataFrame:
        """One row per point: mean, std and percentiles of its displacement size."""
        import pandas as pd

        rows = []
        for name, ps in self.points.items():
            row: dict[str, Any] = {"point": name, "mean": ps.size_mean, "std": ps.size_std}
            row.update({f"p{k:g}": v for k, v in ps.size_percentiles.items()})
            row["max"] = ps.size_max
            rows.append(row)
        return pd.DataFrame(rows).set_index("point")


def _result(model: Model, mc: MonteCarlo, parts: list[_Chunk]) -> MonteCarloResult:
    parts = sorted(parts, key=lambda c: c.index)
    asm = assemble(model)
    pmap = play_map(asm, model.name or "<model>")
    lmap = load_map(asm, mc.case)
    dmap = deviation_map(asm)
    plays = np.concatenate([c.plays for c in parts])
    d = np.concatenate([c.displacement for c in parts])
    assembled = ~np.isnan(d[:, 0, 0]) if model.points else np.ones(len(d), dtype=bool)
    if not np.any(assembled):
        raise UnassembledError(
            f"none of the {len(d):,} sets of parts can be assembled: their deviations leave "
            "no position inside every clearance. Check the deviation zones against the plays",
            joints=(),
            source=model.name,
        )
    points = {}
    for p, point in enumerate(model.points):
        dp = d[assembled, p]  # the statistics of the parts that can be put together
        size = np.linalg.norm(dp, axis=1)
        pct = np.percentile(dp, PERCENTILES, axis=0)
        spct = np.percentile(size, PERCENTILES)
        points[point.name] = PointStats(
            point.name,
            dp.mean(axis=0),
            dp.std(axis=0, ddof=1) if len(dp) > 1 else np.zeros(3),
            {k: pct[i] for i, k in enumerate(PERCENTILES)},
            float(size.mean()),
            float(size.std(ddof=1)) if len(size) > 1 else 0.0,
            {k: float(spct[i]) for i, k in enumerate(PERCENTILES)},
            float(size.max()),
        )
    reqs = []
    z = _z(mc.confidence)
    for req in model.requirements:
        out = int(np.sum(_outside(req, model, d)))
        reqs.append(RequirementStats(req, out, out / len(d), _wilson(out, len(d), z)))
    return MonteCarloResult(
        mc,
        model.name,
        pmap.labels,
        tuple(p.name for p in model.points),
        plays,
        d,
        points,
        tuple(reqs),
        _rel_errors(model, d, mc.confidence),
        sum(c.batched for c in parts),
        sum(c.full_solves for c in parts),
        max(c.feasibility_mm for c in parts),
        max(c.equilibrium_residual for c in parts),
        {v.label: v.value.describe() for v in pmap.variables},
        lmap.labels,
        np.concatenate([c.loads for c in parts]),
        {v.label: v.value.describe() for v in lmap.variables},
        dmap.labels,
        np.concatenate([c.deviations for c in parts]),
        {v.label: v.describe() for v in dmap.variables},
        int(np.sum(~assembled)),
    )


def _wilson(k: int, n: int, z: float) -> tuple[float, float]:
    """Wilson score interval of a binomial fraction k / n; its bound at a
    count of 0 (or n) is exactly 0 (or 1), not the formula's round-off."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (0.0 if k == 0 else centre - half, 1.0 if k == n else centre + half)
