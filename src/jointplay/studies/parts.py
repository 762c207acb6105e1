"""Sets of parts given by the values of their varying inputs, solved in batches.

A tolerance study's inputs, one row per set of parts, in the Monte Carlo
study's order: the toleranced plays (mm, or rad for a backlash), the varying
load components (N, N*mm), then the deviation zones' components (mm, rad).
An *input* of the contribution studies is one play, one load component, or
one whole zone (a disc or ball of 2 or 3 components, drawn together); a
zone of limits per direction is one input per direction.

A *measure* is what the contribution studies follow of the answer: a
functional point's displacement size, or its component along a
requirement's ``along`` (``Measure``, ``measures_of``, ``measured``).

``solve_sets`` solves such rows the way the Monte Carlo study solves its
samples (``montecarlo._solve_chunk``): the batch solver, started from the
nominal answer, in chunks that may go to worker processes. Every answer is
a certified equilibrium, its displacements to what it proves (``proven``); a
set of parts that cannot be assembled gives NaN.
"""

from __future__ import annotations

import itertools
import uuid
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from jointplay.assembly import Assembly, assemble
from jointplay.errors import StudyError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model
from jointplay.model.tolerance import Toleranced
from jointplay.proven import Resolution, proven
from jointplay.settings import DEFAULT, SolverSettings
from jointplay.solver.solve import Workspace
from jointplay.studies.parallel import run_chunks
from jointplay.studies.variation import (
    DeviationMap,
    LoadMap,
    PlayMap,
    deviation_map,
    load_map,
    play_map,
)

if TYPE_CHECKING:
    from collections.abc import Sequence

#: Sets of parts per batch solve (the Monte Carlo study's chunk).
CHUNK = 10_000


@dataclass(frozen=True)
class Inputs:
    """The varying inputs of a model in one load case, and ``length`` (mm),
    what the positions of its solved sets of parts prove (``proven_length``)."""

    pmap: PlayMap
    lmap: LoadMap
    dmap: DeviationMap
    length: float

    @property
    def columns(self) -> int:
        return len(self.pmap.variables) + len(self.lmap.variables) + len(self.dmap.variables)

    @property
    def nominal(self) -> FloatArray:
        """(columns,) the means, which the model holds."""
        return np.concatenate([self.pmap.nominal, self.lmap.nominal, self.dmap.nominal])

    @property
    def groups(self) -> list[list[int]]:
        """The columns of each input: a play, a load component, a zone."""
        n = len(self.pmap.variables) + len(self.lmap.variables)
        out = [[i] for i in range(n)]
        j = 0
        while j < len(self.dmap.variables):
            width = len(self.dmap.variables[j].zone.axes)
            out.append(list(range(n + j, n + j + width)))
            j += width
        return out

    @property
    def labels(self) -> tuple[str, ...]:
        """Each input's name, as ``ContributionsResult.plays`` has them."""
        out = [*self.pmap.labels, *self.lmap.labels]
        n = len(out)
        for g in self.groups[n:]:
            var = self.dmap.variables[g[0] - n]
            out.append(var.label if len(g) == 1 else var.label.rsplit(".", 1)[0])
        return tuple(out)

    def sample(self, rng: np.random.Generator, n: int) -> FloatArray:
        """(n, columns) ``n`` sets of parts, drawn as the Monte Carlo study draws them."""
        return np.hstack(
            [self.pmap.sample(rng, n), self.lmap.sample(rng, n), self.dmap.sample(rng, n)]
        )

    @property
    def unit_groups(self) -> list[list[int]]:
        """The columns of each input in a design of numbers in [0, 1)
        (``from_unit``): two for a fit's play (the hole, the shaft), one per
        component of a zone, else one."""
        values = self._values()
        widths = [v.draws for v in values] + [len(g) for g in self.groups[len(values) :]]
        starts = [0, *itertools.accumulate(widths)]
        return [list(range(lo, hi)) for lo, hi in itertools.pairwise(starts)]

    def _values(self) -> list[Toleranced]:
        """The laws of the plays and the load components, in column order."""
        return [v.value for v in self.pmap.variables] + [v.value for v in self.lmap.variables]

    def from_unit(self, u: FloatArray) -> FloatArray:
        """(n, columns) the sets of parts of ``u`` (n, unit columns) in [0, 1),
        each input through the inverse of its law (``Toleranced.from_unit``,
        ``Zone.from_unit``): independent uniform ``u`` give the sets of parts
        ``sample`` draws; a quasi-random ``u``, a quasi-random design."""
        values = self._values()
        out = np.tile(self.nominal, (len(u), 1))
        for i, (cols, units) in enumerate(zip(self.groups, self.unit_groups, strict=True)):
            if i < len(values):
                out[:, cols[0]] = values[i].from_unit(u[:, units])
            else:
                var = self.dmap.variables[cols[0] - len(values)]
                out[:, cols] += var.zone.from_unit(u[:, units], var.distribution)
        return out


def inputs_of(model: Model, case: str | None, source: str) -> Inputs:
    asm = assemble(model)
    maps = play_map(asm, source), load_map(asm, case), deviation_map(asm)
    return Inputs(*maps, proven_length(asm))


def proven_length(asm: Assembly, settings: SolverSettings = DEFAULT) -> float:
    """mm: what a study's solved positions prove (``Resolution``); below it a
    position, or a difference of two, is round-off."""
    return Resolution.of(asm.s, asm.ell, settings=settings).length


def solve_sets(
    model: Model, case: str | None, values: FloatArray, *, workers: int | None = 1
) -> FloatArray:
    """(n, points, 3) mm: each functional point's displacement for each row
    of ``values`` (n, columns); NaN for a set of parts that cannot be assembled."""
    run = uuid.uuid4().hex
    tasks = [(case, values[lo : lo + CHUNK], lo, run) for lo in range(0, len(values), CHUNK)]
    parts = run_chunks(_solve_rows, model, tasks, workers, None)
    from jointplay.studies.montecarlo import _PREPARED

    _PREPARED.pop((run, case), None)
    parts.sort(key=lambda p: p[0])
    if not parts:
        return np.zeros((0, len(model.points), 3))
    return np.concatenate([d for _, d in parts])


def _solve_rows(
    model: Model, case: str | None, values: FloatArray, first: int, run: str
) -> tuple[int, FloatArray]:
    from jointplay.studies.montecarlo import _prepared

    prepared = _prepared(model, case, run)
    pmap, lmap, dmap = prepared.pmap, prepared.lmap, prepared.dmap
    n_p, n_l = len(pmap.variables), len(lmap.variables)
    plays, loads, deviations = values[:, :n_p], values[:, n_p : n_p + n_l], values[:, n_p + n_l :]
    work = lmap.work(loads) if n_l else np.tile(lmap.g0, (len(values), 1))
    radii, centres = pmap.radii(plays), None
    if dmap.variables:
        radii = radii + dmap.radii_shift(deviations)
        centres = dmap.centres(deviations)
    ws = Workspace(prepared.asm)
    batch = ws.solve_batch(work, radii, centres, forces=False, starts=prepared.starts)
    d = np.zeros((len(values), len(model.points), 3))
    # below what the positions prove is round-off, 0 as in the Monte Carlo: else a
    # measure that does not vary has a variance, and Sobol' shares, of round-off
    length = proven_length(prepared.asm, ws.settings)
    for p, point in enumerate(model.points):
        motion = batch.body_displacement(point.body)
        d[:, p] = proven(motion[:, :3] + np.cross(motion[:, 3:], np.asarray(point.at)), length)
    d[~batch.assembled] = np.nan
    return first, d


@dataclass(frozen=True)
class Measure:
    """A functional measure: point ``point``'s displacement size, or its
    component along ``along`` (a unit vector)."""

    point: str
    along: tuple[float, float, float] | None = None

    @property
    def label(self) -> str:
        if self.along is None:
            return f"|d {self.point}|"
        return f"d {self.point} along [{', '.join(f'{c:.4g}' for c in self.along)}]"

    def of(self, d: FloatArray) -> FloatArray:
        """(B,) the measure of (B, 3) displacements."""
        if self.along is None:
            return np.asarray(np.linalg.norm(d, axis=1))
        return np.asarray(d @ np.asarray(self.along))


def measures_of(model: Model, source: str) -> list[Measure]:
    if not model.points:
        raise StudyError(
            "contributions are to the deviation of functional points, and the model has "
            "none; add 'points: [{name: tip, body: ..., at: [x, y, z]}]'",
            source=source,
            entry="points",
        )
    out = [Measure(p.name) for p in model.points]
    for req in model.requirements:
        if req.along is not None:
            u = np.asarray(req.along, dtype=float)
            u = u / np.linalg.norm(u)
            m = Measure(req.point, (float(u[0]), float(u[1]), float(u[2])))
            if m not in out:
                out.append(m)
    return out


def measured(model: Model, measures: Sequence[Measure], d: FloatArray) -> FloatArray:
    """(M, n) each measure of (n, points, 3) displacements."""
    names = [p.name for p in model.points]
    return np.array([m.of(d[:, names.index(m.point)]) for m in measures]).reshape(
        len(measures), len(d)
    )
