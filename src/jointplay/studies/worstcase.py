"""The worst case of a requirement's measure over the tolerances' limits.

The size a requirement bounds (a point's |d|, or |d . u| along the
requirement's direction), taken as tolerance analysts take a worst case,
at the limits, but on the mechanism's own equilibria:

- without deviation zones: every combination of the toleranced plays at
  their lower and upper limits with the varying load components at their
  limits and mean (their limits only where three values each would be more
  than ``MOST_LOAD_SETS``), each solved as the model's own equilibrium,
  springs and all (one batch, certified answers). The worst case is the
  largest of those answers, at the combination it names (only the inputs
  that decide it: those left out reach it at each of their limits, and a
  load's mean): exact there. A smaller play can push a point further (a gear
  between two bearings tilts more about a tighter one), so the lower limits
  count as much as the upper ones; between the limits a part may still go
  further, and the Monte Carlo beside it says so when one of its samples
  does (``Tolerances``);
- with deviation zones: the support of every position the plays and the
  zones allow (the envelope's program over the positions and the
  deviations together), whatever the loads: along u, the larger of
  ``max u . d`` and ``-min u . d``; for |d|, the envelope's largest
  displacement (its climb from the farthest supports).

The linear stack (``tolerances.py``) extrapolates slopes at the nominal;
where the touching contacts change over the ranges (a load that changes
side), it can be far off, and these equilibria are what holds.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from jointplay.assembly import assemble
from jointplay.errors import OptionError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model
from jointplay.proven import proven
from jointplay.studies.contributions import unit_of
from jointplay.studies.envelope import MOST_LOAD_SETS
from jointplay.studies.parts import Inputs, Measure, inputs_of, measured, solve_sets


@dataclass(frozen=True)
class Reach:
    """One requirement measure's worst case: the greatest value ``worst`` (mm)
    of |d|, or of |d . u| along a direction (the size a requirement bounds),
    with the configuration that reaches it and, along a direction, the
    signed component there."""

    measure: str
    worst: float
    at: str  # the configuration, in words
    over: str  # over which load sets (or positions), in words
    signed: float | None = None  # d . u at the worst case (along a direction)
    #: Along a direction: the least and the greatest d . u over the same sets
    #: (mm), which may both have one sign.
    low: float | None = None
    high: float | None = None


def worst_cases(
    model: Model, measures: list[Measure], case: str | None, *, source: str
) -> tuple[Reach, ...]:
    """Each measure's worst case over the tolerances (module docstring)."""
    inputs = inputs_of(model, case, source)
    if inputs.dmap.variables:
        return tuple(_over_zones(model, inputs, m, case, source) for m in measures)
    return _over_load_sets(model, inputs, measures, case, source)


def _plays_words(inputs: Inputs) -> str:
    return "the plays at their upper limits" if inputs.pmap.variables else "the plays as given"


def _over_load_sets(
    model: Model, inputs: Inputs, measures: list[Measure], case: str | None, source: str
) -> tuple[Reach, ...]:
    lmap, plays = inputs.lmap, inputs.pmap.variables
    nl, corners = len(lmap.variables), 2 ** len(plays)
    levels = 3 if corners * 3**nl <= MOST_LOAD_SETS else 2
    if corners * levels**nl > MOST_LOAD_SETS:
        raise OptionError(
            f"{len(plays)} plays and {nl} load components vary: {corners * levels**nl:,} "
            f"combinations of their limits are more than the worst case's "
            f"{MOST_LOAD_SETS:,}; fix some of them, or run montecarlo",
            source=source,
        )
    grids: list[Any] = [(v.value.low, v.value.high) for v in plays]
    grids += [np.linspace(v.value.low, v.value.high, levels) for v in lmap.variables]
    rows = np.array(list(itertools.product(*grids)), dtype=float).reshape(-1, len(grids))
    y = measured(model, measures, solve_sets(model, case, rows))
    each = "both limits" if levels == 2 else "the limits and the mean"
    over = (
        " and ".join(
            ([f"both limits of each play ({corners:,} sets)"] if plays else [])
            + ([f"{each} of each varying load component"] if nl else [])
        )
        or "the model's loads"
    )

    names = [v.label for v in plays] + [v.label for v in lmap.variables]
    shape = [len(g) for g in grids]

    def at(size: FloatArray, j: int) -> str:
        if not names:
            return "the plays as given"
        deciding = _deciding(size.reshape(shape), np.unravel_index(j, shape), inputs.length)
        if not deciding:
            return "every combination alike (no input changes it)"
        words = ", ".join(f"{names[i]} = {rows[j, i]:g} {unit_of(names[i])}" for i in deciding)
        return words + ("" if len(deciding) == len(names) else "; the others do not change it")

    out = []
    for k, m in enumerate(measures):
        size = np.abs(y[k])
        top = int(np.nanargmax(size))
        if m.along is None:
            out.append(Reach(m.label, float(size[top]), at(size, top), over))
            continue
        low, high = float(np.nanmin(y[k])), float(np.nanmax(y[k]))
        out.append(
            Reach(m.label, float(size[top]), at(size, top), over, float(y[k, top]), low, high)
        )
    return tuple(out)


def _deciding(size: FloatArray, top: tuple[Any, ...], length: float) -> list[int]:
    """The inputs (axes of the grid ``size``) that decide its greatest value at
    ``top``: the others, left to any of their values in the grid together,
    keep it to ``length`` (what the positions prove). Each input is let go in
    turn while that holds, so the named ones with the others free reach it."""
    worst = size[top]
    free: list[int] = []
    for i in range(size.ndim):
        trial = [*free, i]
        index = tuple(slice(None) if a in trial else top[a] for a in range(size.ndim))
        shortfall = worst - size[index]
        if not np.isnan(shortfall).any() and not np.any(proven(shortfall, length)):
            free = trial
    return [i for i in range(size.ndim) if i not in free]


def _over_zones(model: Model, inputs: Inputs, m: Measure, case: str | None, source: str) -> Reach:
    from jointplay.solver.solve import Workspace
    from jointplay.studies.envelope import Envelope, _point_map, _ZoneProgram

    over = (
        "every position the plays and the deviation zones allow (the envelope's support, "
        "whatever the loads)"
    )
    words = _plays_words(inputs) + ", the deviations and the position that reach it"
    if m.along is None:
        env = Envelope(m.point, plays="max", loads="probes").run(model, source=source)
        return Reach(m.label, env.largest, words, over)
    point = next(p for p in model.points if p.name == m.point)
    asm = assemble(model)
    ws = Workspace(asm)
    ws.check_held(case)  # the support is over positions: the loads' verdict first
    if point.body not in asm.body_index:  # the ground does not move
        return Reach(m.label, 0.0, words, over, 0.0, 0.0, 0.0)
    if inputs.pmap.variables:
        highs = np.array([v.value.high for v in inputs.pmap.variables])
        ws = ws.with_radii(inputs.pmap.radii(highs)[0])
    program = _ZoneProgram(ws, inputs.dmap, _point_map(asm, point.body, np.asarray(point.at)))
    u = np.asarray(m.along)
    # the greatest and the least d . u: a component unbounded either way has no worst case
    ends = [program.support(u), program.support(-u)]
    high = math.inf if ends[0] is None else float(u @ ends[0])
    low = -math.inf if ends[1] is None else float(u @ ends[1])
    signed = high if abs(high) >= abs(low) else low
    return Reach(m.label, abs(signed), words, over, signed, low, high)
