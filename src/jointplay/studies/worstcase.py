"""The worst case of a requirement's measure over the tolerances' limits.

The size a requirement bounds (a point's |d|, or |d . u| along the
requirement's direction), taken as tolerance analysts take a worst case,
at the limits, but on the mechanism's own equilibria:

- without deviation zones: every combination of the toleranced plays at
  their lower and upper limits with the varying load components at their
  limits and mean (their limits only where three values each would be more
  than ``MOST_LOAD_SETS``), each solved as the model's own equilibrium,
  springs and all (one batch, certified answers). The worst case is the
  largest of those answers, at the combination it names: exact there. A
  smaller play can push a point further (a gear between two bearings tilts
  more about a tighter one), so the lower limits count as much as the upper
  ones; between the limits a part may still go further, and the Monte Carlo
  beside it says so when one of its samples does (``Tolerances``);
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

    def at(j: int) -> str:
        names = [v.label for v in plays] + [v.label for v in lmap.variables]
        words = ", ".join(
            f"{name} = {value:g} {unit_of(name)}"
            for name, value in zip(names, rows[j], strict=True)
        )
        return words or "the plays as given"

    out = []
    for k, m in enumerate(measures):
        top = int(np.nanargmax(np.abs(y[k])))
        signed = None if m.along is None else float(y[k, top])
        out.append(Reach(m.label, float(abs(y[k, top])), at(top), over, signed))
    return tuple(out)


def _over_zones(model: Model, inputs: Inputs, m: Measure, case: str | None, source: str) -> Reach:
    from jointplay.solver import held
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
    held.check_loads(ws, case)  # the support is over positions: the loads' verdict first
    if point.body not in asm.body_index:  # the ground does not move
        return Reach(m.label, 0.0, words, over, 0.0)
    if inputs.pmap.variables:
        highs = np.array([v.value.high for v in inputs.pmap.variables])
        ws = ws.with_radii(inputs.pmap.radii(highs)[0])
    program = _ZoneProgram(ws, inputs.dmap, _point_map(asm, point.body, np.asarray(point.at)))
    u = np.asarray(m.along)
    # the greatest and the least d . u: a component unbounded either way has no worst case
    ends: list[FloatArray | None] = [program.support(u), program.support(-u)]
    if ends[0] is None or ends[1] is None:
        return Reach(m.label, math.inf, words, over, math.inf if ends[0] is None else -math.inf)
    high, low = float(u @ ends[0]), float(u @ ends[1])
    signed = high if abs(high) >= abs(low) else low
    return Reach(m.label, abs(signed), words, over, signed)
