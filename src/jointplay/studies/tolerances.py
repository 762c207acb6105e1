"""Each requirement three ways, side by side: worst case, RSS and Monte Carlo.

The figures a tolerance analyst reports (docs/conventions.md, "Tolerance
results side by side"), for each requirement's measure y: |d| of its point
(one-sided: y <= L), or the component d . u along its direction (two-sided:
-L <= y <= L).

- *Worst case* (arithmetic stack): y0 -/+ sum_i |s_i| T_i / 2, from the
  contributions' sensitivities s_i at the nominal plays and the tolerance
  widths T_i (each play from its mean to either limit). Linear at the
  nominal: exact while the contacts stay the same; where they change at the
  nominal (a kink), each side's own slope.
- *RSS*: sigma = sqrt(sum_i (s_i sigma_i)^2); Cp = (USL - LSL) / (6 sigma)
  (two-sided only), Cpk = min(USL - y0, y0 - LSL) / (3 sigma) (one-sided:
  (USL - y0) / (3 sigma)); ppm from the normal law of that mean and sigma.
- *Monte Carlo*: the samples' mean m and standard deviation s; Pp and Ppk as
  Cp and Cpk with m and s; ppm the fraction of samples outside, with its
  Wilson interval; the samples' range, and how many of them lie beyond the
  worst case. The linear stack is no bound: where the response bends over the
  tolerances (a position zone read as a distance, contacts that change) a
  sample can pass it, and the report says so. ``jointplay envelope`` gives a
  proven bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from jointplay.errors import StudyError
from jointplay.model.mechanism import Model, Requirement
from jointplay.studies.contributions import Contributions, ContributionsResult, Measure
from jointplay.studies.montecarlo import MonteCarlo, MonteCarloResult

if TYPE_CHECKING:
    import pandas as pd


def _normal_tail(z: float) -> float:
    """P(Z > z) for a standard normal Z."""
    return 0.5 * math.erfc(z / math.sqrt(2.0))


#: A spread below this share of the measure's scale (its mean or its limit) is
#: round-off of a measure that does not vary: it counts as 0.
ROUND_OFF_SPREAD = 1e-12


def _spread(sigma: float, mean: float, limit: float) -> float:
    return 0.0 if sigma <= ROUND_OFF_SPREAD * max(abs(mean), limit) else sigma


def _capability(low: float | None, high: float, mean: float, sigma: float) -> tuple[float, float]:
    """(Cp, Cpk) of a normal law: Cp is NaN for a one-sided limit; a sigma of
    0 gives infinite capability inside the limits (and -inf outside)."""
    spread = 6.0 * sigma
    margin = high - mean if low is None else min(high - mean, mean - low)
    if sigma == 0.0:
        inside = math.inf if margin >= 0 else -math.inf
        return (math.nan if low is None else math.inf), inside
    return (math.nan if low is None else (high - low) / spread), margin / (3.0 * sigma)


def _normal_ppm(low: float | None, high: float, mean: float, sigma: float) -> float:
    if sigma == 0.0:
        inside = mean <= high and (low is None or mean >= low)
        return 0.0 if inside else 1e6
    out = _normal_tail((high - mean) / sigma)
    if low is not None:
        out += _normal_tail((mean - low) / sigma)
    return 1e6 * out


@dataclass(frozen=True)
class RequirementTolerances:
    """One requirement's figures, worst case / RSS / Monte Carlo (mm, ppm)."""

    requirement: Requirement
    two_sided: bool  # along a direction: -L <= d . u <= L; else |d| <= L
    nominal: float  # the measure at the nominal (mean) plays
    kink: bool  # the contacts change at the nominal: the linear figures are one-sided slopes
    worst_low: float
    worst_high: float
    rss_sigma: float
    cp: float  # NaN for a one-sided requirement
    cpk: float
    rss_ppm: float
    mc_mean: float
    mc_sigma: float
    pp: float
    ppk: float
    mc_ppm: float
    mc_interval_ppm: tuple[float, float]
    mc_low: float  # the assembled samples' range
    mc_high: float
    beyond_stack: int  # samples outside the worst case's [worst_low, worst_high]

    @property
    def limits(self) -> tuple[float | None, float]:
        high = self.requirement.max_displacement
        return (-high if self.two_sided else None), high

    def beyond_words(self, samples: int) -> str:
        """Why the worst case is no bound, when samples pass it ('' if none do)."""
        if not self.beyond_stack:
            return ""
        return (
            f"{self.beyond_stack:,} of the {samples:,} samples lie beyond the worst case: "
            "the response is not linear over these tolerances, so the linear stack is no "
            "bound here; the command 'jointplay envelope' gives a proven one"
        )

    @property
    def worst_case_passes(self) -> bool:
        low, high = self.limits
        return self.worst_high <= high and (low is None or self.worst_low >= low)

    def to_dict(self) -> dict[str, Any]:
        def num(v: float) -> float | None:
            return v if math.isfinite(v) else None  # JSON has no NaN nor infinity

        req = self.requirement
        return {
            "point": req.point,
            "along": None if req.along is None else list(req.along),
            "max_displacement": req.max_displacement,
            "two_sided": self.two_sided,
            "nominal": self.nominal,
            "kink": self.kink,
            "worst_case": {
                "low": self.worst_low,
                "high": self.worst_high,
                "passes": self.worst_case_passes,
            },
            "rss": {
                "sigma": self.rss_sigma,
                "cp": num(self.cp),
                "cpk": num(self.cpk),
                "ppm": self.rss_ppm,
            },
            "monte_carlo": {
                "mean": num(self.mc_mean),
                "sigma": self.mc_sigma,
                "pp": num(self.pp),
                "ppk": num(self.ppk),
                "ppm": self.mc_ppm,
                "interval_ppm": list(self.mc_interval_ppm),
                "low": num(self.mc_low),
                "high": num(self.mc_high),
                "beyond_worst_case": self.beyond_stack,
            },
        }


@dataclass(frozen=True)
class Tolerances:
    """Settings of the side-by-side study; ``run`` returns a ``TolerancesResult``.

    ``samples``, ``seed``, ``confidence``, ``case``: those of the Monte Carlo
    study (``MonteCarlo``); the worst case and RSS come from ``Contributions``."""

    samples: int = 100_000
    seed: int = 0
    confidence: float = 0.95
    case: str | None = None

    def run(
        self, model: Model, *, workers: int | None = 1, source: str | None = None
    ) -> TolerancesResult:
        source = source or model.name or "<model>"
        if not model.requirements:
            raise StudyError(
                "the side-by-side tolerance figures are per requirement, and the model has "
                "none; add 'requirements: [{point: tip, max_displacement: \"40 um\"}]'",
                source=source,
                entry="requirements",
            )
        linear = Contributions(case=self.case).run(model, source=source)
        mc = MonteCarlo(
            samples=self.samples, seed=self.seed, confidence=self.confidence, case=self.case
        ).run(model, workers=workers, source=source)
        return TolerancesResult(self, model.name, side_by_side(linear, mc), linear, mc)


def side_by_side(
    linear: ContributionsResult, mc: MonteCarloResult
) -> tuple[RequirementTolerances, ...]:
    """Each requirement's figures from a contribution study and a Monte Carlo
    study of the same model and load case (the HTML report has both)."""
    return tuple(_one(stats.requirement, stats.interval, linear, mc) for stats in mc.requirements)


def _one(
    req: Requirement,
    interval: tuple[float, float],
    linear: ContributionsResult,
    mc: MonteCarloResult,
) -> RequirementTolerances:
    two_sided = req.along is not None
    if two_sided:
        u = np.asarray(req.along, dtype=float)
        u = u / np.linalg.norm(u)
        measure = Measure(req.point, (float(u[0]), float(u[1]), float(u[2])))
    else:
        measure = Measure(req.point)
    k = linear.measures.index(measure.label)
    y0 = float(linear.nominal[k])
    # each play to either limit: the slope's change there, one-sided where the
    # contacts change at the nominal (a kink: the two sides differ)
    half_t = linear.width / 2.0
    kink = linear.kink[k]
    up = np.where(kink, linear.slope_up[k], linear.sensitivity[k]) * half_t
    down = -np.where(kink, linear.slope_down[k], linear.sensitivity[k]) * half_t
    rise = float(np.sum(np.maximum(np.maximum(up, down), 0.0)))
    fall = float(np.sum(np.minimum(np.minimum(up, down), 0.0)))
    high = req.max_displacement
    low = -high if two_sided else None
    sigma = _spread(float(linear.rss_sigma[k]), y0, high)
    cp, cpk = _capability(low, high, y0, sigma)
    y = measure.of(mc.displacement[:, mc.point_names.index(req.point)])
    assembled = ~np.isnan(y)  # parts that cannot be assembled miss the requirement
    mean = float(np.mean(y[assembled]))
    n = int(np.sum(assembled))
    spread = _spread(float(np.std(y[assembled], ddof=1)) if n > 1 else 0.0, mean, high)
    pp, ppk = _capability(low, high, mean, spread)
    with np.errstate(invalid="ignore"):
        outside = ((np.abs(y) > high) if two_sided else (y > high)) | ~assembled
    sampled = y[assembled]
    beyond = int(np.sum((sampled < y0 + fall) | (sampled > y0 + rise)))
    return RequirementTolerances(
        req,
        two_sided,
        y0,
        bool(np.any(kink)),
        y0 + fall,
        y0 + rise,
        sigma,
        cp,
        cpk,
        _normal_ppm(low, high, y0, sigma),
        mean,
        spread,
        pp,
        ppk,
        1e6 * float(np.mean(outside)),
        (1e6 * interval[0], 1e6 * interval[1]),
        float(np.min(sampled)) if n else math.nan,
        float(np.max(sampled)) if n else math.nan,
        beyond,
    )


@dataclass(frozen=True)
class TolerancesResult:
    """Per requirement: worst case, RSS and Monte Carlo side by side; the two
    studies they come from are kept (``linear``, ``montecarlo``)."""

    settings: Tolerances
    model_name: str | None
    requirements: tuple[RequirementTolerances, ...]
    linear: ContributionsResult
    montecarlo: MonteCarloResult

    def to_dict(self) -> dict[str, Any]:
        return {
            "study": "tolerances",
            "model": self.model_name,
            "samples": self.montecarlo.samples,
            "unassembled": self.montecarlo.unassembled,
            "seed": self.settings.seed,
            "case": self.settings.case,
            "confidence": self.settings.confidence,
            "requirements": [r.to_dict() for r in self.requirements],
        }

    def to_dataframe(self) -> pd.DataFrame:
        """One row per requirement, the figures as columns."""
        import pandas as pd

        rows = []
        for r in self.requirements:
            rows.append(
                {
                    "requirement": r.requirement.describe(),
                    "nominal": r.nominal,
                    "worst_low": r.worst_low,
                    "worst_high": r.worst_high,
                    "worst_case_passes": r.worst_case_passes,
                    "rss_sigma": r.rss_sigma,
                    "cp": r.cp,
                    "cpk": r.cpk,
                    "rss_ppm": r.rss_ppm,
                    "mc_mean": r.mc_mean,
                    "mc_sigma": r.mc_sigma,
                    "pp": r.pp,
                    "ppk": r.ppk,
                    "mc_ppm": r.mc_ppm,
                    "mc_ppm_low": r.mc_interval_ppm[0],  # the Wilson interval of mc_ppm
                    "mc_ppm_high": r.mc_interval_ppm[1],
                    "mc_low": r.mc_low,
                    "mc_high": r.mc_high,
                    "beyond_worst_case": r.beyond_stack,
                    "kink": r.kink,
                }
            )
        return pd.DataFrame(rows)
