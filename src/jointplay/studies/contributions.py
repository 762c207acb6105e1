"""Which play drives the functional deviation: sensitivities and contributions.

(Load components that vary, ``force: [{min: 8, max: 12}, 0, 0]``, take part
like plays, and so do the joints' deviation zones: see below.)

For each functional measure y (a point's displacement size |d|, or its
component along a requirement's ``along``) and each toleranced play p_i,
the sensitivity ``s_i = dy/dp_i`` at the nominal plays (their means) comes
from central differences on the exact equilibrium, all solved in one batch:
the equilibrium is piecewise linear in the plays (exactly linear while the
contacts stay the same), so a step of a thousandth of each tolerance gives
the slope to round-off; where the contact directions turn with the plays the
curve is smooth, and central differences at h and h/2 with Richardson's
extrapolation give the slope to O(h^4). Both one-sided slopes are kept; where
they differ by a jump that does not shrink with the step, the nominal sits on
a change of contacts (a kink), and the result says so.

From the slopes, the two contributions tolerance analysts use:

- worst case (arithmetic stack): ``|s_i| T_i / sum_k |s_k| T_k``, with T_i
  the width of the play's tolerance (max - min);
- statistical (RSS): ``(s_i sigma_i)^2 / sum_k (s_k sigma_k)^2``, with
  sigma_i the play's standard deviation (uniform: T/sqrt(12); normal: T/6; a
  fit: the hole's and the shaft's zones combined).

A deviation zone that is a disc or a ball of radius R (a position or an
orientation zone) counts as one variable: its components' slopes form a
gradient s, the measure's worst case over the zone is ``R |s|`` (the linear
worst case exactly, where the per-component sum would overstate it), and its
variance ``(sigma |s|)^2`` with sigma each component's standard deviation
(the zone's draws are isotropic). So its sensitivity is ``|s|`` (mm per mm,
or per rad, in its worst direction) and its tolerance T = 2R; both stacks
keep their formulas. A zone of limits per direction is one variable per
direction, as a play.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from jointplay.assembly import assemble
from jointplay.errors import UnassembledError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model, check_case
from jointplay.proven import proven
from jointplay.settings import KINK
from jointplay.solver.solve import Workspace
from jointplay.studies.linearity import Linearity, check_linearity
from jointplay.studies.parts import Inputs, measures_of, proven_length
from jointplay.studies.sobol import Sobol, SobolResult, check_samples
from jointplay.studies.variation import (
    DeviationMap,
    LoadVariable,
    PlayVariable,
    deviation_map,
    load_map,
    nothing_varies,
    play_map,
)

if TYPE_CHECKING:
    import pandas as pd


@dataclass(frozen=True)
class Contributions:
    """Settings of a contribution study; ``run`` returns a ``ContributionsResult``.

    ``step``: the difference step as a fraction of each play's tolerance
    width. ``case``: the load case (needed when the model has load cases).
    ``variance``: when to take the shares of the variance (Sobol' indices,
    ``sobol.py``) besides the linear shares: ``"auto"`` where a measure is
    not linear over the ranges (``linearity.py``), ``"always"``, or
    ``"never"``. ``samples``: the Sobol' study's base sets of parts, a
    power of 2 (it solves samples (D + 2) for D inputs); ``seed``: its random streams and the
    linearity check's."""

    step: float = 1e-3
    case: str | None = None
    variance: Literal["auto", "always", "never"] = "auto"
    samples: int = 1024
    seed: int = 0

    def __post_init__(self) -> None:
        if not 0 < self.step <= 0.1:
            raise ValueError("step: a fraction of the tolerance, above 0 and at most 0.1")
        if self.variance not in ("auto", "always", "never"):
            raise ValueError("variance: 'auto', 'always' or 'never'")
        check_samples(self.samples)

    def run(
        self, model: Model, *, source: str | None = None, workers: int | None = 1
    ) -> ContributionsResult:
        """``workers``: local processes for the Sobol' study (None: one per core)."""
        source = source or model.name or "<model>"
        asm = assemble(model)
        pmap = play_map(asm, source)
        check_case(model, self.case, source, "the contributions study")
        lmap = load_map(asm, self.case)
        dmap = deviation_map(asm)
        variables: list[PlayVariable | LoadVariable] = [*pmap.variables, *lmap.variables]
        if not variables and not dmap.variables:
            raise nothing_varies("nothing contributes to a spread", source)
        measures = measures_of(model, source)
        nv = len(variables) + len(dmap.variables)
        width = np.array(
            [v.value.high - v.value.low for v in variables]
            + [2.0 * v.zone.radius for v in dmap.variables]
        )
        sigma = np.array(
            [v.value.sigma for v in variables]
            + [v.zone.sigma(v.distribution) for v in dmap.variables]
        )
        h = self.step * width
        # rows: the nominal, then each variable up and down by h, then by h / 2
        nominal = np.concatenate([pmap.nominal, lmap.nominal, dmap.nominal])
        eye = np.eye(nv)
        values = np.vstack(
            [nominal[None, :]]
            + [nominal + sign * frac * eye * h for frac in (1.0, 0.5) for sign in (1, -1)]
        )
        n_plays, n_loads = len(pmap.variables), len(lmap.variables)
        work = lmap.work(values[:, n_plays : n_plays + n_loads])
        deviations = values[:, n_plays + n_loads :]
        radii = pmap.radii(values[:, :n_plays]) + dmap.radii_shift(deviations)
        centres = dmap.centres(deviations) if dmap.variables else None
        ws = Workspace(asm)
        ws.check_held(self.case)  # the nominal row's verdict, in a solve's words
        batch = ws.solve_batch(work, radii, centres, forces=False)
        names = [p.name for p in model.points]
        y = np.zeros((len(measures), len(values)))
        for k, m in enumerate(measures):
            point = model.points[names.index(m.point)]
            motion = batch.body_displacement(point.body)
            d = motion[:, :3] + np.cross(motion[:, 3:], np.asarray(point.at))
            y[k] = m.of(d)
        if np.isnan(y[:, 0]).any():
            raise UnassembledError(
                "the parts at the nominal (the deviations' means) cannot be assembled, so "
                "nothing contributes; check the deviations' means against the plays",
                joints=(),
                source=source,
            )
        if np.isnan(y).any():
            raise UnassembledError(
                f"parts within {self.step:g} of a tolerance of the nominal cannot be "
                "assembled: the nominal sits on the edge of assembly, where no slope is "
                "defined; move the deviations' means inward",
                joints=(),
                source=source,
            )
        y0 = y[:, :1]
        up_h, down_h, up_half, down_half = (y[:, 1 + q * nv : 1 + (q + 1) * nv] for q in range(4))
        safe = np.where(h > 0, h, 1.0)
        up = np.where(h > 0, (up_half - y0) / (safe / 2), 0.0)
        down = np.where(h > 0, (y0 - down_half) / (safe / 2), 0.0)
        central_h = np.where(h > 0, (up_h - down_h) / (2 * safe), 0.0)
        central_half = (up + down) / 2
        # Richardson: the central slope to O(h^4) where y is smooth
        slope = (4 * central_half - central_h) / 3
        # a kink keeps its jump of slope as the step halves; a curve's halves with it
        jump_h = np.abs((up_h - y0) / safe - (y0 - down_h) / safe)
        jump_half = np.abs(up - down)
        kink = (jump_half > 0.75 * jump_h) & (
            jump_half > KINK * np.maximum(np.abs(up), np.abs(down)) + 1e-9
        )
        sensitivity = np.where(kink, central_half, slope)
        per_column = sensitivity
        labels = [v.label for v in variables]
        described = {v.label: v.value.describe() for v in variables}
        groups = [[i] for i in range(len(variables))]
        for first, label, text in _zones(dmap):
            groups.append(list(range(len(variables) + first, len(variables) + first + len(text))))
            labels.append(label)
            described[label] = text[0]
        sensitivity, up, down, kink = _grouped(groups, sensitivity, up, down, kink)
        width = np.array([width[g[0]] for g in groups])
        sigma = np.array([sigma[g[0]] for g in groups])
        # a slope whose effect over its whole tolerance is below the length the
        # positions prove is their round-off: 0 (jointplay.proven)
        length = proven_length(asm, ws.settings)
        step = length / np.where(width > 0, width, 1.0)
        sensitivity, up, down = (proven(v, step) for v in (sensitivity, up, down))
        nominal = proven(y[:, 0], length)  # a measure below the proven length is 0, not -0
        half_width = np.sum(np.abs(sensitivity) * width, axis=1) / 2
        linearity = check_linearity(
            model,
            self.case,
            Inputs(pmap, lmap, dmap, length),
            measures,
            nominal,
            per_column,
            half_width,
            seed=self.seed,
        )
        sobol = None
        if self.variance == "always" or (
            self.variance == "auto" and not all(c.linear for c in linearity)
        ):
            sobol = Sobol(self.samples, self.seed, case=self.case).run(
                model, workers=workers, source=source
            )
        return ContributionsResult(
            self,
            model.name,
            tuple(m.label for m in measures),
            tuple(labels),
            described,
            nominal,
            sensitivity,
            up,
            down,
            kink,
            width,
            sigma,
            float(np.max(batch.feasibility_mm, initial=0.0)),
            float(np.max(batch.equilibrium_residual, initial=0.0)),
            linearity,
            sobol,
        )


def _zones(dmap: DeviationMap) -> list[tuple[int, str, list[str]]]:
    """Each deviation zone: its first component in ``dmap``, its label (a
    disc or ball: ``l2.deviation.position``; a direction's limits: with the
    direction) and its components' descriptions."""
    out: list[tuple[int, str, list[str]]] = []
    j = 0
    while j < len(dmap.variables):
        var = dmap.variables[j]
        width = len(var.zone.axes)
        label = var.label if width == 1 else var.label.rsplit(".", 1)[0]
        out.append((j, label, [v.describe() for v in dmap.variables[j : j + width]]))
        j += width
    return out


def _grouped(
    groups: list[list[int]], *slopes_and_kink: Any
) -> tuple[FloatArray, FloatArray, FloatArray, np.ndarray[Any, np.dtype[np.bool_]]]:
    """Per group of components (a zone's), the slopes' norm (one component:
    the signed slope) and whether any has a kink."""
    sensitivity, up, down, kink = slopes_and_kink
    out = []
    for slope in (sensitivity, up, down):
        cols = [
            slope[:, g[0]] if len(g) == 1 else np.linalg.norm(slope[:, g], axis=1) for g in groups
        ]
        out.append(np.column_stack(cols) if cols else slope[:, :0])
    kinks = [np.any(kink[:, g], axis=1) for g in groups]
    return out[0], out[1], out[2], np.column_stack(kinks) if kinks else kink[:, :0]


@dataclass(frozen=True)
class ContributionsResult:
    """Per measure and play: the sensitivity (mm of the measure per mm of
    play, or per N or N*mm of a load's varying component) and the worst-case
    and statistical (RSS) contributions in %. ``plays`` lists the plays, then
    the load components."""

    settings: Contributions
    model_name: str | None
    measures: tuple[str, ...]
    plays: tuple[str, ...]
    plays_described: dict[str, str]
    nominal: FloatArray  # (M,) mm: each measure at the nominal plays
    sensitivity: FloatArray  # (M, nv): central slopes
    slope_up: FloatArray  # (M, nv): one-sided slopes (step h / 2)
    slope_down: FloatArray
    kink: np.ndarray[Any, np.dtype[np.bool_]]  # (M, nv): the contacts change at the nominal
    width: FloatArray  # (nv,) tolerance widths (max - min): mm, N or N*mm
    sigma: FloatArray  # (nv,) standard deviations
    feasibility_mm: float
    equilibrium_residual: float
    #: Per measure: whether it is linear over the ranges (``linearity.py``).
    linearity: tuple[Linearity, ...] = ()
    #: The shares of the variance (``sobol.py``), where taken.
    sobol: SobolResult | None = None

    def linear(self, k: int) -> bool:
        """Whether measure ``k``'s linear shares and RSS hold over the ranges."""
        return not self.linearity or self.linearity[k].linear

    @property
    def worst_case(self) -> FloatArray:
        """(M, nv) % of the arithmetic stack ``sum |s| T``."""
        part = np.abs(self.sensitivity) * self.width
        return _percent(part)

    @property
    def rss(self) -> FloatArray:
        """(M, nv) % of the statistical stack ``sum (s sigma)^2``."""
        return _percent((self.sensitivity * self.sigma) ** 2)

    @property
    def worst_case_range(self) -> FloatArray:
        """(M,) mm: the measure's linear worst-case spread, ``sum |s| T``."""
        return np.asarray(np.sum(np.abs(self.sensitivity) * self.width, axis=1))

    @property
    def rss_sigma(self) -> FloatArray:
        """(M,) mm: the measure's standard deviation, ``sqrt(sum (s sigma)^2)``."""
        return np.asarray(np.sqrt(np.sum((self.sensitivity * self.sigma) ** 2, axis=1)))

    def to_dataframe(self) -> pd.DataFrame:
        """One row per measure and play."""
        import pandas as pd

        rows = []
        wc, rss, kink = self.worst_case, self.rss, self.kink
        for k, measure in enumerate(self.measures):
            for i, play in enumerate(self.plays):
                rows.append(
                    {
                        "measure": measure,
                        "play": play,
                        "tolerance": self.width[i],
                        "sigma": self.sigma[i],
                        "unit": unit_of(play),
                        "sensitivity": self.sensitivity[k, i],
                        "worst_case_pct": wc[k, i],
                        "rss_pct": rss[k, i],
                        "kink": bool(kink[k, i]),
                        "linear": self.linear(k),
                        **self._variance_row(k, i),
                    }
                )
        return pd.DataFrame(rows)

    def _variance_row(self, k: int, i: int) -> dict[str, float]:
        """Measure ``k``'s and input ``i``'s Sobol' indices (NaN: not taken)."""
        names: tuple[str, ...] = ("sobol_first", "sobol_first_low", "sobol_first_high")
        names += ("sobol_total", "sobol_total_low", "sobol_total_high")
        if self.sobol is None:
            return dict.fromkeys(names, float("nan"))
        s = self.sobol
        values = (s.first[k, i], *s.first_interval[k, i], s.total[k, i], *s.total_interval[k, i])
        return {n: float(v) for n, v in zip(names, values, strict=True)}

    def to_dict(self) -> dict[str, Any]:
        wc, rss, kink = self.worst_case, self.rss, self.kink
        return {
            "study": "contributions",
            "model": self.model_name,
            "case": self.settings.case,
            "plays": self.plays_described,
            "measures": {
                measure: {
                    "nominal": float(self.nominal[k]),
                    "worst_case_range": float(self.worst_case_range[k]),
                    "rss_sigma": float(self.rss_sigma[k]),
                    "linearity": self.linearity[k].to_dict() if self.linearity else None,
                    "plays": {
                        play: {
                            "tolerance": float(self.width[i]),
                            "sigma": float(self.sigma[i]),
                            "sensitivity": float(self.sensitivity[k, i]),
                            "worst_case_pct": float(wc[k, i]),
                            "rss_pct": float(rss[k, i]),
                            "kink": bool(kink[k, i]),
                        }
                        for i, play in enumerate(self.plays)
                    },
                }
                for k, measure in enumerate(self.measures)
            },
            "sobol": None if self.sobol is None else self.sobol.to_dict(),
            "certificate": {
                "feasibility_mm": self.feasibility_mm,
                "equilibrium_residual": self.equilibrium_residual,
            },
        }


def _percent(part: FloatArray) -> FloatArray:
    total = np.sum(part, axis=1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray(np.where(total > 0, 100.0 * part / total, 0.0))


def unit_of(variable: str) -> str:
    """The unit of a varying play or load component, from its label:
    ``l2.clearance`` mm, ``motor.backlash`` rad, ``loads[0].force[1]`` N,
    ``l2.deviation.position`` mm, ``l2.deviation.orientation`` rad."""
    from jointplay.model.tolerance import play_unit

    if ".deviation." in variable:
        return "rad" if ".deviation.orientation" in variable else "mm"
    last = variable.rsplit(".", 1)[-1]
    if last.startswith("force["):
        return "N"
    if last.startswith("torque["):
        return "N*mm"
    return play_unit(last)
