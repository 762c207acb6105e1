"""Plays that vary from part to part: a clearance given by its limits or an ISO fit.

A joint's play (``clearance``, ``axial_clearance``, ``clearance_y``,
``clearance_z``, a point's ``gap``; a drive's ``backlash``, an angle) may be
a plain value, or one of::

    clearance: {fit: "H7/g6", diameter: 20}                    # ISO 286 limits
    clearance: {fit: "H7/g6", diameter: 20, distribution: normal}
    clearance: {min: 0.02, max: 0.06}                          # uniform by default
    clearance: {min: "20 um", max: "60 um", distribution: normal}

The value is then a ``Toleranced``: a float equal to the *mean* play, which a
single solve uses, that also knows how the play is spread over a batch of
parts:

* ``{min, max}``: the play itself is drawn, ``uniform`` on [min, max] or
  ``normal`` with mean (min + max) / 2 and sigma (max - min) / 6 (min and max
  are the +-3 sigma limits), truncated to [min, max];
* a fit: the hole's and the shaft's diameters are drawn, each within its ISO
  286 tolerance zone (``uniform``, or ``normal`` with sigma = zone / 6,
  truncated), and the play is their difference, as for real parts. Only
  clearance fits are accepted: a transition or interference fit presses some
  parts together, which a joint with play does not model.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from jointplay.units import shown, to_base

Distribution = Literal["uniform", "normal"]
DISTRIBUTIONS: tuple[Distribution, ...] = ("uniform", "normal")
#: Joint fields that hold a play and may be toleranced.
PLAY_FIELDS = ("clearance", "axial_clearance", "clearance_y", "clearance_z", "gap", "backlash")
#: Those of ``PLAY_FIELDS`` that are angles (rad), not lengths.
ANGULAR_PLAYS = ("backlash",)


def play_unit(field: str) -> str:
    """The unit of a play field's values: rad for an angular play, else mm."""
    return "rad" if field in ANGULAR_PLAYS else "mm"


_FIT_KEYS = {"fit", "diameter", "distribution"}
_RANGE_KEYS = {"min", "max", "distribution"}


class Toleranced(float):
    """A play (mm) that varies from part to part; as a float, its mean.

    ``low``/``high``: the play's limits (mm). ``fit``: the ISO fit it comes
    from (``"H7/g6"``) with ``diameter`` (mm), whose hole and shaft limits
    (mm, deviations from the nominal diameter) are ``hole`` and ``shaft``.
    """

    low: float
    high: float
    distribution: Distribution
    fit: str | None
    diameter: float | None
    hole: tuple[float, float] | None
    shaft: tuple[float, float] | None
    unit: str  # "mm" for a play; "N" or "N*mm" for a load's component

    def __new__(
        cls,
        low: float,
        high: float,
        distribution: Distribution = "uniform",
        fit: str | None = None,
        diameter: float | None = None,
        hole: tuple[float, float] | None = None,
        shaft: tuple[float, float] | None = None,
        unit: str = "mm",
    ) -> Toleranced:
        self = super().__new__(cls, (low + high) / 2.0)
        for name, value in (
            ("low", low),
            ("high", high),
            ("distribution", distribution),
            ("fit", fit),
            ("diameter", diameter),
            ("hole", hole),
            ("shaft", shaft),
            ("unit", unit),
        ):
            object.__setattr__(self, name, value)
        return self

    def __reduce__(self) -> tuple[Any, ...]:  # pickled whole (to worker processes)
        return (
            Toleranced,
            (
                self.low,
                self.high,
                self.distribution,
                self.fit,
                self.diameter,
                self.hole,
                self.shaft,
                self.unit,
            ),
        )

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("a Toleranced play is immutable")

    def __repr__(self) -> str:
        source = f"fit {self.fit} at {self.diameter:g} mm, " if self.fit else ""
        return (
            f"Toleranced({source}{self.low:g} to {self.high:g} {self.unit}, {self.distribution}, "
            f"mean {float(self):g})"
        )

    def describe(self) -> str:
        """'H7/g6 at 20 mm: 0.007 to 0.041 mm (uniform)' style words."""
        source = f"{self.fit} at {self.diameter:g} mm: " if self.fit else ""
        return f"{source}{self.low:.6g} to {self.high:.6g} {self.unit} ({self.distribution})"

    @property
    def sigma(self) -> float:
        """The standard deviation (in ``unit``), before truncation for ``normal``."""
        if self.fit is None:
            width = self.high - self.low
            return width / 6.0 if self.distribution == "normal" else width / np.sqrt(12.0)
        assert self.hole is not None and self.shaft is not None
        zones = np.array([self.hole[1] - self.hole[0], self.shaft[1] - self.shaft[0]])
        each = zones / 6.0 if self.distribution == "normal" else zones / np.sqrt(12.0)
        return float(np.sqrt(np.sum(each**2)))

    def sample(self, rng: np.random.Generator, n: int) -> NDArray[np.float64]:
        """``n`` plays (mm) of real parts, drawn with ``rng``."""
        if self.fit is None:
            return _draw(rng, n, self.low, self.high, self.distribution)
        assert self.hole is not None and self.shaft is not None
        hole = _draw(rng, n, self.hole[0], self.hole[1], self.distribution)
        shaft = _draw(rng, n, self.shaft[0], self.shaft[1], self.distribution)
        return np.asarray(hole - shaft)

    @property
    def draws(self) -> int:
        """How many numbers in [0, 1) make one play (``from_unit``): two for
        a fit (the hole and the shaft), else one."""
        return 1 if self.fit is None else 2

    def from_unit(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """The plays of ``u`` (n, ``draws``) in [0, 1), through the inverse of
        each drawn diameter's (or the play's) distribution function:
        independent uniform ``u`` give the law ``sample`` draws from."""
        u = np.asarray(u, dtype=float).reshape(len(u), self.draws)
        if self.fit is None:
            return quantile(u[:, 0], self.low, self.high, self.distribution)
        assert self.hole is not None and self.shaft is not None
        hole = quantile(u[:, 0], self.hole[0], self.hole[1], self.distribution)
        shaft = quantile(u[:, 1], self.shaft[0], self.shaft[1], self.distribution)
        return np.asarray(hole - shaft)


def quantile(
    u: NDArray[np.float64], low: float, high: float, distribution: Distribution
) -> NDArray[np.float64]:
    """The values at probabilities ``u`` of ``_draw``'s law on [low, high]:
    uniform, or normal with the limits at +-3 sigma, truncated to them."""
    if distribution == "uniform":
        return np.asarray(low + u * (high - low))
    from scipy.special import ndtr, ndtri

    mean, sigma = (low + high) / 2.0, (high - low) / 6.0
    below = ndtr(-3.0)  # the normal law's probability below the low limit
    return np.asarray(mean + sigma * ndtri(below + u * (1.0 - 2.0 * below)))


def _draw(
    rng: np.random.Generator, n: int, low: float, high: float, distribution: Distribution
) -> NDArray[np.float64]:
    if high == low:
        return np.full(n, low)
    if distribution == "uniform":
        return np.asarray(rng.uniform(low, high, n))
    # normal, +-3 sigma at the limits, truncated by redrawing the few outside
    mean, sigma = (low + high) / 2.0, (high - low) / 6.0
    out = rng.normal(mean, sigma, n)
    bad = (out < low) | (out > high)
    while np.any(bad):
        out[bad] = rng.normal(mean, sigma, int(np.sum(bad)))
        bad = (out < low) | (out > high)
    return np.asarray(out)


def parse_play(value: Any) -> float:
    """A play field's value: a length (float) or a ``Toleranced`` from a mapping."""
    if isinstance(value, Toleranced):
        return value  # a validated model's own value, dumped and read again
    if not isinstance(value, Mapping):
        return to_base(value, "length")
    keys = set(value)
    if "fit" in keys:
        unknown = keys - _FIT_KEYS
        if unknown:
            raise ValueError(
                f"unknown key {shown(sorted(map(str, unknown))[0])} in a fit; write "
                "{fit: 'H7/g6', diameter: 20} (and optionally distribution: uniform|normal)"
            )
        return _from_fit(value)
    if keys & {"min", "max"}:
        return _from_limits(value, "length", "a play")
    raise ValueError(
        f"expected a length, {{min, max}} or {{fit, diameter}}, got {shown(dict(value))}; "
        "write e.g. 0.2, '20 um', {min: 0.02, max: 0.06} or {fit: 'H7/g6', diameter: 20}"
    )


def parse_angular_play(value: Any) -> float:
    """A drive's backlash: an angle (rad; ``"0.2 deg"``, ``"3 arcmin"``), the
    play ``{length, radius}`` at a radius (a gear's flank, a screw's lead),
    or ``{min, max}`` angles (a ``Toleranced`` in rad)."""
    if isinstance(value, Toleranced):
        return value
    if not isinstance(value, Mapping):
        return to_base(value, "angle")
    keys = set(value)
    if keys & {"min", "max"}:
        limits = {
            key: _at_radius(v) if key in ("min", "max") and isinstance(v, Mapping) else v
            for key, v in value.items()
        }
        return _from_limits(limits, "angle", "a backlash")
    if keys == {"length", "radius"}:
        return _at_radius(value)
    raise ValueError(
        f"expected an angle, {{length, radius}} or {{min, max}}, got {shown(dict(value))}; "
        "write e.g. '0.2 deg', '3 arcmin', {length: '20 um', radius: '15 mm'} or "
        "{min: '0.1 deg', max: '0.3 deg'}"
    )


def _at_radius(value: Mapping[str, Any]) -> float:
    """The angle (rad) of a play ``{length, radius}`` along an arc."""
    if set(value) != {"length", "radius"}:
        raise ValueError(
            f"expected an angle or {{length, radius}}, got {shown(dict(value))}; write e.g. "
            "{length: '20 um', radius: '15 mm'}"
        )
    length, radius = to_base(value["length"], "length"), to_base(value["radius"], "length")
    if not radius > 0:
        raise ValueError(f"radius: expected a length > 0, got {radius:g} mm")
    return length / radius


def parse_scattered(value: Any, dimension: str) -> float:
    """A load's component: a number (``to_base``), or ``{min, max,
    distribution}`` for one that varies from sample to sample in a Monte
    Carlo study (a ``Toleranced`` whose float value, the mean, a single
    solve uses)."""
    if isinstance(value, Toleranced):
        return value
    if isinstance(value, Mapping) and set(value) & {"min", "max"}:
        return _from_limits(value, dimension, f"a {dimension}")
    return to_base(value, dimension)


def _from_limits(value: Mapping[str, Any], dimension: str, what: str) -> Toleranced:
    from jointplay.units import BASE_UNITS

    unit = BASE_UNITS[dimension]
    example = {"length": "{min: 0.02, max: 0.06}", "angle": "{min: '0.1 deg', max: '0.3 deg'}"}.get(
        dimension, "{min: 8, max: 12}"
    )
    unknown = set(value) - _RANGE_KEYS
    if unknown:
        raise ValueError(
            f"unknown key {shown(sorted(map(str, unknown))[0])} in {what}'s limits; write "
            f"{example} (and optionally distribution: uniform|normal)"
        )
    missing = {"min", "max"} - set(value)
    if missing:
        raise ValueError(
            f"{what}'s limits need both 'min' and 'max'; '{sorted(missing)[0]}' is missing"
        )
    low, high = to_base(value["min"], dimension), to_base(value["max"], dimension)
    if dimension in ("length", "angle") and low < 0:
        raise ValueError(f"min: expected a play >= 0 {unit}, got {low:g} {unit}")
    if high < low:
        raise ValueError(f"max ({high:g} {unit}) is below min ({low:g} {unit}); swap them")
    return Toleranced(low, high, _distribution(value), unit=unit)


def _distribution(value: Mapping[str, Any]) -> Distribution:
    d = value.get("distribution", "uniform")
    for name in DISTRIBUTIONS:
        if d == name:
            return name
    raise ValueError(f"distribution: expected 'uniform' or 'normal', got {shown(d)}")


def _from_fit(value: Mapping[str, Any]) -> Toleranced:
    from jointplay.model.fits import fit as iso_fit

    spec = value["fit"]
    if not isinstance(spec, str):
        raise ValueError(f"fit: expected a fit such as 'H7/g6', got {shown(spec)}")
    if "diameter" not in value:
        raise ValueError(f"fit {spec!r} needs its nominal 'diameter' (mm), e.g. diameter: 20")
    diameter = to_base(value["diameter"], "length")
    found = iso_fit(spec, diameter)  # ValueError with its own words
    low, high = found.min_clearance, found.max_clearance
    if low < 0:
        kind = "an interference" if high <= 0 else "a transition"
        raise ValueError(
            f"fit {spec!r} at {diameter:g} mm is {kind} fit (clearance {low:+.4g} to "
            f"{high:+.4g} mm): some parts are pressed together, which a joint with play "
            "does not model; choose a clearance fit (such as H7/g6 or H8/f7), or make the "
            "joint rigid"
        )
    hole = (found.hole_limits.lower, found.hole_limits.upper)
    shaft = (found.shaft_limits.lower, found.shaft_limits.upper)
    return Toleranced(
        low, high, _distribution(value), found.hole + "/" + found.shaft, diameter, hole, shaft
    )
