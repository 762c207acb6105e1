"""Each requirement three ways, side by side: worst case, RSS and Monte Carlo.

The figures a tolerance analyst reports (docs/conventions.md, "Tolerance
results side by side"), for each requirement's measure y: |d| of its point
(one-sided: y <= L), or the component d . u along its direction (two-sided:
-L <= y <= L).

- *Worst case*: y's greatest value over the tolerances' limits
  (``worstcase.py``: every combination of the plays' lower and upper limits
  and of the varying loads' limits and mean, or the deviation zones'
  support), with the configuration that reaches it (the inputs that decide
  it) and, along a direction, the least and the greatest d . u; it passes
  only if no Monte Carlo sample goes past it. Beside it the *linear estimate*
  (arithmetic stack) y0 -/+ sum_i |s_i| T_i / 2, from the contributions'
  sensitivities s_i at the nominal and the tolerance widths T_i (where the
  contacts change at the nominal, each side's own slope): shown only where
  it agrees with the worst case.
- *RSS*, only where y is linear over the ranges (``linearity.py``: each
  tolerance at its limits and a small random design against the slopes'
  prediction): sigma = sqrt(sum_i (s_i sigma_i)^2); Cp = (USL - LSL) / (6
  sigma) (two-sided only), Cpk = min(USL - y0, y0 - LSL) / (3 sigma)
  (one-sided: (USL - y0) / (3 sigma)); ppm from the normal law of that mean
  and sigma. Where y is not linear (the touching contacts change over the
  ranges), these are NaN and the check says which tolerance bends y: the
  verdict comes from the worst case and the Monte Carlo.
- *Monte Carlo*: the samples' mean m and standard deviation s; Pp and Ppk as
  Cp and Cpk with m and s; ppm the fraction of samples outside, with its
  Wilson interval (from 0 when no sample fails); the samples' range, and
  how many of them pass the worst case (along a direction, lie outside its
  least to greatest d . u; none, on every bundled example: a test).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from jointplay.errors import StudyError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model, Requirement, check_case
from jointplay.settings import CERTIFIED_MM, LINEAR_ERROR_SHARE, ROUND_OFF_MM, ROUND_OFF_SPREAD
from jointplay.studies.contributions import Contributions, ContributionsResult
from jointplay.studies.montecarlo import MonteCarlo, MonteCarloResult
from jointplay.studies.parts import Measure

if TYPE_CHECKING:
    import pandas as pd

    from jointplay.studies.worstcase import Reach


def _normal_tail(z: float) -> float:
    """P(Z > z) for a standard normal Z."""
    return 0.5 * math.erfc(z / math.sqrt(2.0))


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
    """One requirement's figures, worst case / RSS / Monte Carlo (mm, ppm).

    ``worst``: the worst case (``worstcase.py``), the greatest value of the
    requirement's measure, reached at ``worst_at``. ``linear_low`` to
    ``linear_high``: the linear stack, an estimate, shown where it agrees
    with the worst case. RSS (sigma, Cp, Cpk, ppm) only where the measure is
    linear over the ranges (``linear``; else NaN, and ``linear_why`` says
    why)."""

    requirement: Requirement
    two_sided: bool  # along a direction: -L <= d . u <= L; else |d| <= L
    nominal: float  # the measure at the nominal (mean) plays
    kink: bool  # the contacts change at the nominal: the linear figures are one-sided slopes
    worst: float  # the requirement's measure at its greatest over the limits (mm)
    worst_at: str  # the configuration that reaches it
    worst_over: str  # over which sets of parts and loads
    worst_signed: float | None  # along a direction: d . u at the worst case
    #: Along a direction: the least and the greatest d . u over the worst
    #: case's sets (one sign where the point goes one way only)
    worst_low: float | None
    worst_high: float | None
    linear_low: float  # the linear estimate (the stack at the nominal's slopes)
    linear_high: float
    linear: bool  # the measure is linear over the ranges: RSS applies
    linear_why: str  # why not ('' where linear)
    rss_sigma: float  # NaN where RSS does not apply
    cp: float  # NaN for a one-sided requirement, or where RSS does not apply
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
    #: samples that pass the worst case: the requirement's size (|d|, or
    #: |d . u|) above it
    beyond_bound: int
    #: along a direction, samples outside ``worst_low`` to ``worst_high`` (the
    #: range printed), past it or not
    outside_range: int = 0

    @property
    def limits(self) -> tuple[float | None, float]:
        high = self.requirement.max_displacement
        return (-high if self.two_sided else None), high

    @property
    def linear_agrees(self) -> bool:
        """Whether the linear estimate's greatest value of the requirement's
        measure agrees with the worst case (within what the linearity check
        allows the slopes' prediction): only then is it shown."""
        top = max(abs(self.linear_low), abs(self.linear_high))
        top = top if self.two_sided else self.linear_high
        half = (self.linear_high - self.linear_low) / 2
        return self.linear and abs(top - self.worst) <= LINEAR_ERROR_SHARE * half + ROUND_OFF_MM

    def beyond_words(self, samples: int) -> str:
        """What it means when samples pass the worst case, or lie outside the
        range it prints ('' if none do)."""
        reached = (
            f"they reach {self.mc_low:.6g} to {self.mc_high:.6g} mm"
            if self.worst_low is not None
            else f"up to {self.mc_high:.6g} mm"
        )
        if self.beyond_bound:
            return (
                f"{self.beyond_bound:,} of the {samples:,} samples pass the worst case "
                f"({reached}): it is taken at the tolerances' limits, and these parts "
                "go further between them; the worst case does not pass, and the Monte Carlo "
                "range is the better guide"
            )
        if self.outside_range:
            return (
                f"{self.outside_range:,} of the {samples:,} samples lie outside the worst "
                f"case's range ({reached}): it is taken at the tolerances' limits, and these "
                "parts lie between them; none goes past the worst case's size, so its verdict "
                "holds, but the range is no bound on d . u: the Monte Carlo range is the "
                "better guide"
            )
        return ""

    @property
    def worst_case_passes(self) -> bool:
        """Only a worst case that no sample passes can pass the requirement."""
        return self.worst <= self.requirement.max_displacement and not self.beyond_bound

    @property
    def rss_applies(self) -> bool:
        return self.linear

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
                "worst": num(self.worst),
                "at": self.worst_at,
                "over": self.worst_over,
                "signed": self.worst_signed,
                "low": self.worst_low,
                "high": self.worst_high,
                "passes": self.worst_case_passes,
                "linear_estimate": {
                    "low": self.linear_low,
                    "high": self.linear_high,
                    "agrees": self.linear_agrees,
                },
            },
            "rss": {
                "applies": self.linear,
                "why_not": self.linear_why or None,
                "sigma": num(self.rss_sigma),
                "cp": num(self.cp),
                "cpk": num(self.cpk),
                "ppm": num(self.rss_ppm),
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
                "beyond_worst_case": self.beyond_bound,
                "outside_worst_case_range": self.outside_range,
            },
        }


@dataclass(frozen=True)
class Tolerances:
    """Settings of the side-by-side study; ``run`` returns a ``TolerancesResult``.

    ``samples``, ``seed``, ``confidence``, ``case``: those of the Monte Carlo
    study (``MonteCarlo``); the worst case is the greatest over the limits
    (``worstcase.py``); the linear estimate, RSS and the linearity check
    come from ``Contributions``."""

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
        check_case(model, self.case, source, "the tolerance study")
        linear = Contributions(case=self.case, variance="never", seed=self.seed).run(
            model, source=source
        )
        mc = MonteCarlo(
            samples=self.samples, seed=self.seed, confidence=self.confidence, case=self.case
        ).run(model, workers=workers, source=source)
        rows = side_by_side(model, linear, mc, source=source)
        return TolerancesResult(self, model.name, rows, linear, mc)


def side_by_side(
    model: Model, linear: ContributionsResult, mc: MonteCarloResult, *, source: str
) -> tuple[RequirementTolerances, ...]:
    """Each requirement's figures from a contribution study and a Monte Carlo
    study of the same model and load case (the HTML report has both), and
    the worst case over the envelope (``worstcase.worst_cases``)."""
    from jointplay.studies.worstcase import worst_cases

    measures = [_measure_of(stats.requirement) for stats in mc.requirements]
    reaches = worst_cases(model, measures, mc.settings.case, source=source)
    return tuple(
        _one(stats.requirement, stats.interval, linear, mc, reach)
        for stats, reach in zip(mc.requirements, reaches, strict=True)
    )


def _measure_of(req: Requirement) -> Measure:
    if req.along is None:
        return Measure(req.point)
    u = np.asarray(req.along, dtype=float)
    u = u / np.linalg.norm(u)
    return Measure(req.point, (float(u[0]), float(u[1]), float(u[2])))


def beyond_reach(y: FloatArray, reach: Reach) -> int:
    """How many of the measure's values ``y`` (the assembled samples) pass its
    worst case by more than ``CERTIFIED_MM``: for |d|, above it; along a
    direction, outside the least to the greatest d . u it reached (the range
    the text prints), so that a part below its low end counts too."""
    if reach.low is None or reach.high is None:
        return int(np.sum(np.abs(y) > reach.worst + CERTIFIED_MM))
    return int(np.sum((y < reach.low - CERTIFIED_MM) | (y > reach.high + CERTIFIED_MM)))


def _one(
    req: Requirement,
    interval: tuple[float, float],
    linear: ContributionsResult,
    mc: MonteCarloResult,
    reach: Reach,
) -> RequirementTolerances:
    two_sided = req.along is not None
    measure = _measure_of(req)
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
    is_linear = linear.linear(k)
    why = "" if is_linear else linear.linearity[k].why()
    if is_linear:
        sigma = _spread(float(linear.rss_sigma[k]), y0, high)
        cp, cpk = _capability(low, high, y0, sigma)
        rss_ppm = _normal_ppm(low, high, y0, sigma)
    else:
        sigma = cp = cpk = rss_ppm = math.nan
    y = measure.of(mc.displacement[:, mc.point_names.index(req.point)])
    assembled = ~np.isnan(y)  # parts that cannot be assembled miss the requirement
    mean = float(np.mean(y[assembled]))
    n = int(np.sum(assembled))
    spread = _spread(float(np.std(y[assembled], ddof=1)) if n > 1 else 0.0, mean, high)
    pp, ppk = _capability(low, high, mean, spread)
    with np.errstate(invalid="ignore"):
        outside = ((np.abs(y) > high) if two_sided else (y > high)) | ~assembled
    sampled = y[assembled]
    beyond = int(np.sum(np.abs(sampled) > reach.worst + CERTIFIED_MM))
    outside_range = beyond_reach(sampled, reach) if reach.low is not None else 0
    return RequirementTolerances(
        req,
        two_sided,
        y0,
        bool(np.any(kink)),
        reach.worst,
        reach.at,
        reach.over,
        reach.signed,
        reach.low,
        reach.high,
        y0 + fall,
        y0 + rise,
        is_linear,
        why,
        sigma,
        cp,
        cpk,
        rss_ppm,
        mean,
        spread,
        pp,
        ppk,
        1e6 * float(np.mean(outside)),
        (1e6 * interval[0], 1e6 * interval[1]),
        float(np.min(sampled)) if n else math.nan,
        float(np.max(sampled)) if n else math.nan,
        beyond,
        outside_range,
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
                    "worst_case": r.worst,
                    "worst_case_signed": r.worst_signed,
                    "worst_case_low": r.worst_low,
                    "worst_case_high": r.worst_high,
                    "worst_case_passes": r.worst_case_passes,
                    "worst_case_at": r.worst_at,
                    "linear_low": r.linear_low,
                    "linear_high": r.linear_high,
                    "linear_agrees": r.linear_agrees,
                    "rss_applies": r.linear,
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
                    "beyond_worst_case": r.beyond_bound,
                    "outside_worst_case_range": r.outside_range,
                    "kink": r.kink,
                }
            )
        return pd.DataFrame(rows)
