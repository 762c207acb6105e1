"""Contributions by variance: Sobol' indices of each input, solved in batches.

Where a measure y is not linear in the tolerances (``linearity.py``), the
shares of the linear stacks say nothing; the share of y's variance does.
For each input i (a play, a load component, a whole deviation zone):

- the first-order index ``S_i = Var(E[y | x_i]) / Var(y)``: the share of
  the variance that x_i explains alone;
- the total index ``S_Ti = E[Var(y | x_~i)] / Var(y)``: its share with every
  interaction it takes part in. ``S_Ti - S_i`` is its interactions' share
  (contacts that change with several inputs together).

Saltelli's design: two independent matrices A and B of N sets of parts
(drawn as the Monte Carlo study draws them), and for each input the
matrices A_B^i (A with input i from B) and B_A^i: N (2 D + 2) sets of parts
for D inputs, solved as a Monte Carlo of as many samples
(``parts.solve_sets``). Estimators (Saltelli et al. 2010, Jansen 1999),
each taken both ways (A with A_B^i, and B with B_A^i) and averaged:

    S_i  = mean(f(B) (f(A_B^i) - f(A))) / V
    S_Ti = mean((f(A) - f(A_B^i))^2) / (2 V)

with V the variance of f over A and B together. Their confidence intervals
come from the bootstrap over the N base rows (``RESAMPLES``). For a linear
y, S_i = S_Ti = the RSS share (s_i sigma_i)^2 / sum (s sigma)^2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from jointplay.errors import ModelError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model, check_case
from jointplay.studies.contributions import _measures
from jointplay.studies.parts import inputs_of, measured, solve_sets

if TYPE_CHECKING:
    import pandas as pd

#: Bootstrap resamples of the base rows for the indices' intervals: the
#: interval's ends move by about 1 % of its width from one seed to another.
RESAMPLES = 1000
BLOCK = 50  # resamples at a time


@dataclass(frozen=True)
class Sobol:
    """Settings of a Sobol' study; ``run`` returns a ``SobolResult``.

    ``samples``: N, the base sets of parts (the study solves N (2 D + 2)).
    ``confidence``: of the bootstrap intervals. ``case``: the load case."""

    samples: int = 1024
    seed: int = 0
    confidence: float = 0.95
    case: str | None = None

    def __post_init__(self) -> None:
        if self.samples < 8:
            raise ValueError("samples: at least 8 base sets of parts")
        if not 0 < self.confidence < 1:
            raise ValueError("confidence: between 0 and 1 (0.95 is 95 %)")

    def run(
        self, model: Model, *, workers: int | None = 1, source: str | None = None
    ) -> SobolResult:
        source = source or model.name or "<model>"
        check_case(model, self.case, source)
        inputs = inputs_of(model, self.case, source)
        groups = inputs.groups
        if not groups:
            raise ModelError(
                "no play, load or deviation varies, so nothing has a share of the variance",
                source=source,
                entry="joints",
            )
        measures = _measures(model, source)
        n, d = self.samples, len(groups)
        a = inputs.sample(np.random.default_rng([self.seed, 0]), n)
        b = inputs.sample(np.random.default_rng([self.seed, 1]), n)
        blocks = [a, b]
        for cols in groups:  # A_B^i, then B_A^i
            ab = a.copy()
            ab[:, cols] = b[:, cols]
            blocks.append(ab)
        for cols in groups:
            ba = b.copy()
            ba[:, cols] = a[:, cols]
            blocks.append(ba)
        values = np.vstack(blocks)
        y = measured(model, measures, solve_sets(model, self.case, values, workers=workers))
        f = y.reshape(len(measures), 2 * d + 2, n)
        rng = np.random.default_rng([self.seed, 2])
        first, total, variance = _indices(f, None)
        resampled = [  # in blocks, to keep the arrays small
            _indices(f, rng.integers(0, n, size=(min(BLOCK, RESAMPLES - lo), n)))
            for lo in range(0, RESAMPLES, BLOCK)
        ]
        first_b = np.concatenate([r[0] for r in resampled], axis=1)
        total_b = np.concatenate([r[1] for r in resampled], axis=1)
        tail = (1 - self.confidence) / 2
        with np.errstate(invalid="ignore"):
            first_ci = np.nanquantile(first_b, [tail, 1 - tail], axis=1)  # (2, M, d)
            total_ci = np.nanquantile(total_b, [tail, 1 - tail], axis=1)
        return SobolResult(
            self,
            model.name,
            tuple(m.label for m in measures),
            inputs.labels,
            first,
            np.moveaxis(first_ci, 0, -1),
            total,
            np.moveaxis(total_ci, 0, -1),
            variance,
            len(values),
        )


def _indices(f: FloatArray, pick: Any) -> tuple[FloatArray, FloatArray, FloatArray]:
    """First-order and total indices (M, D), and the variance (M,), from the
    answers f (M, 2 D + 2, N); ``pick`` (R, N): bootstrap rows, giving
    (M, R, D) indices instead. A base row with any set of parts that cannot
    be assembled (NaN) is left out."""
    d = (f.shape[1] - 2) // 2
    keep = ~np.any(np.isnan(f), axis=(0, 1))
    # centred: the first-order estimator's spread grows with the mean of f
    f = np.where(keep, f, 0.0)
    f = f - np.sum(f[:, :2] * keep, axis=(1, 2), keepdims=True) / max(2 * int(np.sum(keep)), 1)
    f = np.where(keep, f, 0.0)
    if pick is not None:
        f = f[:, :, pick]  # (M, 2D+2, R, N)
        keep = keep[pick]
    fa, fb = f[:, 0], f[:, 1]
    fab, fba = f[:, 2 : 2 + d], f[:, 2 + d :]
    count = np.sum(keep, axis=-1)

    def mean(x: FloatArray) -> FloatArray:
        return np.asarray(np.sum(np.where(keep, x, 0.0), axis=-1) / np.maximum(count, 1))

    both_mean = (mean(fa) + mean(fb)) / 2
    variance = (mean(fa**2) + mean(fb**2)) / 2 - both_mean**2
    v = np.where(variance > 0, variance, np.nan)
    # input axis next to the measure's: (M, D, ...) -> indices per input
    fa_, fb_ = fa[:, None], fb[:, None]
    first = (mean(fb_ * (fab - fa_)) + mean(fa_ * (fba - fb_))) / 2
    total = (mean((fa_ - fab) ** 2) + mean((fb_ - fba) ** 2)) / 4
    with np.errstate(invalid="ignore"):
        first = first / v[:, None]
        total = total / v[:, None]
    if pick is not None:
        first, total = np.moveaxis(first, 1, 2), np.moveaxis(total, 1, 2)  # (M, R, D)
    return first, total, variance


@dataclass(frozen=True)
class SobolResult:
    """Per measure and input: the first-order and total Sobol' indices
    (fractions of the measure's variance) with their intervals."""

    settings: Sobol
    model_name: str | None
    measures: tuple[str, ...]
    inputs: tuple[str, ...]
    first: FloatArray  # (M, D)
    first_interval: FloatArray  # (M, D, 2)
    total: FloatArray  # (M, D)
    total_interval: FloatArray  # (M, D, 2)
    variance: FloatArray  # (M,) mm^2
    solves: int

    @property
    def interactions(self) -> FloatArray:
        """(M, D) each input's share in interactions, ``S_T - S`` (at least 0)."""
        return np.asarray(np.maximum(self.total - self.first, 0.0))

    def to_dict(self) -> dict[str, Any]:
        def num(v: float) -> float | None:
            return float(v) if np.isfinite(v) else None

        return {
            "study": "sobol",
            "model": self.model_name,
            "samples": self.settings.samples,
            "solves": self.solves,
            "seed": self.settings.seed,
            "confidence": self.settings.confidence,
            "measures": {
                measure: {
                    "variance": num(self.variance[k]),
                    "inputs": {
                        name: {
                            "first": num(self.first[k, i]),
                            "first_interval": [num(v) for v in self.first_interval[k, i]],
                            "total": num(self.total[k, i]),
                            "total_interval": [num(v) for v in self.total_interval[k, i]],
                            "interactions": num(self.interactions[k, i]),
                        }
                        for i, name in enumerate(self.inputs)
                    },
                }
                for k, measure in enumerate(self.measures)
            },
        }

    def to_dataframe(self) -> pd.DataFrame:
        """One row per measure and input."""
        import pandas as pd

        return pd.DataFrame(
            [
                {
                    "measure": measure,
                    "input": name,
                    "first": self.first[k, i],
                    "first_low": self.first_interval[k, i, 0],
                    "first_high": self.first_interval[k, i, 1],
                    "total": self.total[k, i],
                    "total_low": self.total_interval[k, i, 0],
                    "total_high": self.total_interval[k, i, 1],
                    "interactions": self.interactions[k, i],
                }
                for k, measure in enumerate(self.measures)
                for i, name in enumerate(self.inputs)
            ]
        )
