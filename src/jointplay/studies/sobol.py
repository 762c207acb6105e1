"""Contributions by variance: Sobol' indices of each input, solved in batches.

Where a measure y is not linear in the tolerances (``linearity.py``), the
shares of the linear stacks say nothing; the share of y's variance does.
For each input i (a play, a load component, a whole deviation zone):

- the first-order index ``S_i = Var(E[y | x_i]) / Var(y)``: the share of
  the variance that x_i explains alone;
- the total index ``S_Ti = E[Var(y | x_~i)] / Var(y)``: its share with every
  interaction it takes part in. ``S_Ti - S_i`` is its interactions' share
  (contacts that change with several inputs together).

SALib computes them. Its design (``SALib.sample.sobol``, Saltelli's scheme
on a scrambled Sobol' sequence) gives two matrices A and B of N base rows
and, for each input, A with that input's columns from B: N (D + 2) rows for
D inputs. Its rows are numbers in [0, 1), one column per independent draw
of an input (``Inputs.unit_groups``: a fit's hole and shaft, a zone's
components, taken together as one input); ``Inputs.from_unit`` turns them
into sets of parts of the Monte Carlo study's laws, and the batch solver
solves them as a Monte Carlo of as many samples (``parts.solve_sets``).
``SALib.analyze.sobol`` then gives the indices (Saltelli et al. 2010 for
the first order, Jansen 1999 for the total) and their confidence intervals
(the normal interval of ``RESAMPLES`` bootstrap resamples of the base rows).
For a linear y, S_i = S_Ti = the RSS share (s_i sigma_i)^2 / sum (s sigma)^2.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model, check_case
from jointplay.studies.parts import inputs_of, measured, measures_of, solve_sets
from jointplay.studies.variation import nothing_varies

if TYPE_CHECKING:
    import pandas as pd

#: Bootstrap resamples of the base rows for the indices' intervals (SALib's
#: ``num_resamples``): the interval's half-width is z times their standard
#: deviation, known to about 1 / sqrt(2 RESAMPLES) = 5 % of itself.
RESAMPLES = 200


@dataclass(frozen=True)
class Sobol:
    """Settings of a Sobol' study; ``run`` returns a ``SobolResult``.

    ``samples``: N, the base sets of parts, a power of 2 (the Sobol'
    sequence's points are balanced only then); the study solves N (D + 2).
    ``confidence``: of the intervals. ``case``: the load case."""

    samples: int = 1024
    seed: int = 0
    confidence: float = 0.95
    case: str | None = None

    def __post_init__(self) -> None:
        check_samples(self.samples)
        if not 0 < self.confidence < 1:
            raise ValueError("confidence: between 0 and 1 (0.95 is 95 %)")

    def run(
        self, model: Model, *, workers: int | None = 1, source: str | None = None
    ) -> SobolResult:
        source = source or model.name or "<model>"
        problem, values = self.design(model, source)
        measures = measures_of(model, source)
        y = measured(model, measures, solve_sets(model, self.case, values, workers=workers))
        return self.analysed(model, problem, y, source)

    def design(self, model: Model, source: str) -> tuple[dict[str, Any], FloatArray]:
        """SALib's problem and its design's sets of parts (rows; columns as
        ``parts.Inputs``: plays, loads, deviations)."""
        from SALib.sample import sobol as design

        check_case(model, self.case, source, "the Sobol' study")
        inputs = inputs_of(model, self.case, source)
        if not inputs.groups:
            raise nothing_varies("nothing has a share of the variance", source)
        units = inputs.unit_groups
        width = units[-1][-1] + 1
        problem = {
            "num_vars": width,
            "names": [f"u{j}" for j in range(width)],
            "bounds": [[0.0, 1.0]] * width,
            "groups": [f"x{i}" for i, cols in enumerate(units) for _ in cols],
        }
        u = design.sample(
            problem, self.samples, calc_second_order=False,
            seed=np.random.default_rng([self.seed, 0]),
        )  # fmt: skip
        return problem, inputs.from_unit(u)

    def analysed(
        self, model: Model, problem: dict[str, Any], y: FloatArray, source: str
    ) -> SobolResult:
        """The indices of the measures ``y`` (M, rows of the design) of ``model``."""
        from SALib.analyze import sobol as analysis

        inputs = inputs_of(model, self.case, source)
        measures = measures_of(model, source)
        n, d = self.samples, len(inputs.groups)
        # SALib's order: each base row's A, its D rows A_B^i, then B
        f = y.reshape(len(measures), n, d + 2)
        keep = ~np.any(np.isnan(f), axis=(0, 2))  # a set of parts not assembled: row left out
        f = f[:, keep]
        both = np.concatenate([f[:, :, 0], f[:, :, -1]], axis=1)  # A and B
        variance = np.var(both, axis=1) if np.any(keep) else np.full(len(measures), np.nan)
        # a measure whose spread the positions do not prove does not vary: its
        # variance is the solver's round-off, and so would its shares be
        if np.any(keep):
            variance[np.ptp(both, axis=1) <= inputs.length] = 0.0
        first = np.full((len(measures), d), np.nan)
        first_ci = np.full((len(measures), d, 2), np.nan)
        total, total_ci = first.copy(), first_ci.copy()
        # SALib draws its resamples from default_rng(seed) only for a seed that is not 0
        resample_seed = 1 + int(np.random.SeedSequence([self.seed, 2]).generate_state(1)[0])
        for k in range(len(measures)):
            if not variance[k] > 0:
                continue  # a measure that does not vary has no shares
            with warnings.catch_warnings():
                # SALib 1.5.1 (the last for numpy 1) hands pandas.unique a list
                warnings.filterwarnings("ignore", category=FutureWarning, module="SALib")
                s = analysis.analyze(
                    problem,
                    f[k].ravel(),
                    calc_second_order=False,
                    num_resamples=RESAMPLES,
                    conf_level=self.confidence,
                    seed=resample_seed,
                )
            first[k], total[k] = s["S1"], s["ST"]
            first_ci[k] = np.column_stack([s["S1"] - s["S1_conf"], s["S1"] + s["S1_conf"]])
            total_ci[k] = np.column_stack([s["ST"] - s["ST_conf"], s["ST"] + s["ST_conf"]])
        return SobolResult(
            self,
            model.name,
            tuple(m.label for m in measures),
            inputs.labels,
            first,
            first_ci,
            total,
            total_ci,
            variance,
            y.shape[1],
        )


def check_samples(samples: int) -> None:
    """A Sobol' study's base sets of parts: a power of 2, at least 8."""
    if samples < 8 or samples & (samples - 1):
        raise ValueError(
            f"samples: a power of 2, at least 8 (the Sobol' sequence's points are balanced "
            f"only then), got {samples}; for instance 256, 1024 or 4096"
        )


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
