"""Whether a measure is linear in the tolerances over their ranges.

The linear stack and RSS extrapolate the slopes s at the nominal,
``y = y0 + s . (x - x0)``. That holds while the touching contacts stay the
same over the ranges; where they change (a load that changes side, a pin
that can touch either side of its bore) the slopes at the nominal say
nothing about the rest. The check solves, all in one batch:

- each play and load component at its two limits and half-way to each
  (4 solves per tolerance);
- each deviation zone's components at the zone's edge, +-R along each of
  its axes;
- ``DESIGN`` sets of parts drawn at random as the Monte Carlo study draws
  them (seeded),

and compares each answer with the slopes' prediction. A measure is linear
when every error is within ``LINEAR_ERROR_SHARE`` of its linear stack's
half-width ``sum |s| T / 2`` (and round-off). Else the input whose limits
err most beyond it is named: over its range the touching contacts change
(or turn); if only the random design errs, the inputs do so together.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model
from jointplay.settings import LINEAR_ERROR_SHARE, ROUND_OFF_MM
from jointplay.studies.parts import Inputs, Measure, measured, solve_sets

#: Random sets of parts in the check: a few beyond the limits' one-at-a-time
#: solves, to catch inputs that bend the measure only together.
DESIGN = 16


@dataclass(frozen=True)
class Linearity:
    """One measure's check: its largest error against the slopes' prediction
    (mm), what it may be, and where it is largest."""

    measure: str
    linear: bool
    error: float  # mm
    allowed: float  # mm
    culprit: str | None  # the input at whose limit the error is largest; None: the design
    value: float  # mm: the measure there
    predicted: float  # mm: what the slopes at the nominal say there
    solves: int

    def why(self) -> str:
        """Why the linear figures do not apply ('' where they do)."""
        if self.linear:
            return ""
        where = (
            f"{self.culprit} changes the touching contacts over its range: at one of its limits"
            if self.culprit is not None
            else "the tolerances together change the touching contacts: in a random set of parts"
        )
        return (
            f"{where} {self.measure} is {self.value:.4g} mm where the slopes at the nominal "
            f"say {self.predicted:.4g} mm (an error of {self.error:.3g} mm; a linear "
            f"response stays within {self.allowed:.3g} mm)"
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "linear": self.linear,
            "error": self.error,
            "allowed": self.allowed,
            "culprit": self.culprit,
            "value": self.value,
            "predicted": self.predicted,
            "solves": self.solves,
            "why": self.why(),
        }


def check_linearity(
    model: Model,
    case: str | None,
    inputs: Inputs,
    measures: list[Measure],
    y0: FloatArray,
    slopes: FloatArray,
    half_width: FloatArray,
    *,
    seed: int = 0,
) -> tuple[Linearity, ...]:
    """Each measure's check. ``y0`` (M,): the measures at the nominal;
    ``slopes`` (M, columns): their slopes per column of the inputs;
    ``half_width`` (M,): the linear stacks' half-widths (mm)."""
    x0 = inputs.nominal
    rows, owner = [], []
    n_single = len(inputs.pmap.variables) + len(inputs.lmap.variables)
    limits = [(v.value.low, v.value.high) for v in inputs.pmap.variables]
    limits += [(v.value.low, v.value.high) for v in inputs.lmap.variables]
    for g, columns in enumerate(inputs.groups):
        for c in columns:
            if c < n_single:
                low, high = limits[c]
                mean = x0[c]
                values: tuple[float, ...] = (low, (low + mean) / 2, (mean + high) / 2, high)
            else:
                radius = inputs.dmap.variables[c - n_single].zone.radius
                values = (x0[c] - radius, x0[c] + radius)
            for value in values:
                row = x0.copy()
                row[c] = value
                rows.append(row)
                owner.append(g)
    design = inputs.sample(np.random.default_rng([seed, 1_000_003]), DESIGN)
    rows.extend(design)
    owner.extend([-1] * DESIGN)
    x = np.array(rows)
    y = measured(model, measures, solve_sets(model, case, x))
    predicted = y0[:, None] + slopes @ (x - x0).T
    error = np.abs(y - predicted)
    error[np.isnan(error)] = np.inf  # a set of parts that cannot be assembled is no line
    labels = inputs.labels
    out = []
    at_limits = np.array(owner) >= 0
    for k, m in enumerate(measures):
        allowed = LINEAR_ERROR_SHARE * float(half_width[k]) + ROUND_OFF_MM
        j = int(np.argmax(error[k]))
        worst_limit = int(np.argmax(np.where(at_limits, error[k], -1.0)))
        if error[k, worst_limit] > allowed:  # name the input, where one errs alone
            j = worst_limit
        out.append(
            Linearity(
                m.label,
                bool(error[k, j] <= allowed),
                float(error[k, j]),
                allowed,
                labels[owner[j]] if owner[j] >= 0 else None,
                float(y[k, j]),
                float(predicted[k, j]),
                len(x),
            )
        )
    return tuple(out)
