"""Deviations of a joint's features: where its play is really centred.

A real bore is off its true position and its axis is tilted: position,
parallelism and perpendicularity tolerances (ISO 1101, ASME Y14.5) bound
that. For the joint it is one small torsor ``delta = (t, w)`` of its
clearance domain, in the joint frame at the joint centre: the deviation of
the features on a's side minus those on b's side, combined. Every contact
``|rows @ tau| + offset @ tau <= r`` of the joint becomes

    |rows @ (tau - delta)| + offset @ (tau - delta) <= r,

so b, centred in its play, sits at ``delta``. It enters the cone program as
data, like the plays (``BallStack.centre`` and the radii).

A deviation has a ``position`` zone and an ``orientation`` zone::

    deviation:
      position: "0.02 mm"                  # a diameter: a disc across the axis
                                           # (a ball for a spherical joint)
      position: {diameter: "20 um", mean: [0, "3 um", 0]}
      position: {y: {min: -0.01, max: 0.01}, x: {min: 0, max: 0.005}}
      orientation: {tolerance: "0.01 mm", over: "40 mm"}   # the axis tilts by
      orientation: "0.2 mrad"                              # at most t / L
      distribution: normal                 # uniform (default) or normal

Features made together (two bores bored in one setup) share one deviation:
a ``SharedDeviation`` in the model's ``deviations`` section, with its own
point and axis, named by each joint (``deviation: setup``); each joint sees
it at its own centre, in its own frame (``transport``).

A zone is centred on its ``mean`` (0 by default: the process's mean shift).
``uniform`` fills the zone evenly (a disc by area, not by radius);
``normal`` puts the zone's edge at 3 sigma in each direction and redraws the
few draws outside it. A single solve takes every deviation at its mean.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Any, Literal, Self

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, WithJsonSchema, model_validator

from jointplay.geometry import is_parallel, joint_frame, skew
from jointplay.model.fields import (
    Direction,
    Length,
    Name,
    NonNegativeLength,
    Point,
    PositiveLength,
    Vec3,
    _quantity_schema,
    _vector,
    _vector_of,
)
from jointplay.model.tolerance import Distribution, quantile
from jointplay.settings import DEFAULT
from jointplay.units import shown, to_base

FloatArray = NDArray[np.float64]

_AXES = "xyz"
#: The largest tilt a zone may reach (rad, about 6 degrees): beyond it a tilt
#: is no small displacement (its linear model is off by over half a percent).
LARGEST_TILT = 0.1
#: The two zones of a deviation, as ``with_deviations`` measures them.
Kind = Literal["position", "orientation"]
#: The components of a small torsor (t, w) of a joint's features, in words.
MOTION_WORDS = (
    "shift along x",
    "shift along y",
    "shift along z",
    "turn about x",
    "tilt about y",
    "tilt about z",
)


def mean_components(mean: FloatArray | Sequence[float]) -> list[int]:
    """The components of a mean (or measured) torsor that are more than its
    round-off (one given in other axes, turned into the joint frame, has some
    on every axis)."""
    size = np.abs(np.asarray(mean, dtype=float))
    floor = DEFAULT.round_off * float(np.max(size, initial=0.0))
    return [int(a) for a in np.flatnonzero(size > floor)]


def _or_plain(dimension: str) -> Any:
    """A zone's schema: its object, or a plain quantity (a diameter, an angle)."""

    def extra(schema: dict[str, Any]) -> None:
        whole = dict(schema)
        schema.clear()
        schema["anyOf"] = [_quantity_schema(dimension), whole]

    return extra


class Limits(BaseModel):
    """A range of one component: ``{min, max}``."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    min: Length
    max: Length

    @model_validator(mode="after")
    def _ordered(self) -> Self:
        if self.min > self.max:
            raise ValueError(f"min {self.min:g} is above max {self.max:g}; swap them")
        return self


class PositionZone(BaseModel):
    """Where the joint centre (or axis) may be: a ``diameter`` (a disc
    across the joint's axis, or a ball for a spherical joint) around
    ``mean``, or limits per joint-frame direction ``x``, ``y``, ``z``."""

    model_config = ConfigDict(frozen=True, extra="forbid", json_schema_extra=_or_plain("length"))

    diameter: NonNegativeLength | None = None
    x: Limits | None = None
    y: Limits | None = None
    z: Limits | None = None
    mean: Annotated[Vec3, _vector_of("length")] = Field(default=(0.0, 0.0, 0.0))

    @model_validator(mode="before")
    @classmethod
    def _plain_diameter(cls, value: Any) -> Any:
        if isinstance(value, Mapping):
            out = dict(value)
            if "mean" in out:
                out["mean"] = _vector("length")(out["mean"])
            return out
        return {"diameter": value}

    @model_validator(mode="after")
    def _one_kind(self) -> Self:
        limits = [a for a in _AXES if getattr(self, a) is not None]
        if self.diameter is not None and limits:
            raise ValueError(
                "give the position zone as a diameter or as limits per direction "
                f"({', '.join(limits)}), not both"
            )
        if self.diameter is None and not limits:
            raise ValueError(
                "a position zone needs a diameter (e.g. '0.02 mm') or limits per "
                "direction, e.g. {y: {min: -0.01, max: 0.01}}"
            )
        if limits and any(self.mean):
            raise ValueError(
                "a zone given by limits is centred between them: leave out 'mean', or "
                "shift the limits"
            )
        return self


class OrientationZone(BaseModel):
    """How far the joint's axis may tilt (about its y and z axes): an angle,
    or a tolerance ``t`` over a length ``L`` (the axis within a cylinder of
    diameter t over L, so a tilt of at most t / L); around ``mean`` (rad,
    joint frame, no component about the axis)."""

    model_config = ConfigDict(frozen=True, extra="forbid", json_schema_extra=_or_plain("angle"))

    angle: Annotated[float | None, WithJsonSchema(_quantity_schema("angle"))] = None
    tolerance: NonNegativeLength | None = None
    over: PositiveLength | None = None
    mean: Annotated[Vec3, _vector_of("angle")] = Field(default=(0.0, 0.0, 0.0))

    @model_validator(mode="before")
    @classmethod
    def _plain_angle(cls, value: Any) -> Any:
        if not isinstance(value, Mapping):
            value = {"angle": value}
        out = dict(value)
        if out.get("angle") is not None:
            angle = to_base(out["angle"], "angle")
            if angle < 0:
                raise ValueError(f"angle: expected a value >= 0, got {shown(out['angle'])}")
            out["angle"] = angle
        if "mean" in out:
            mean = _vector("angle")(out["mean"])
            # a tilt turned from other axes carries round-off about the axis
            if abs(mean[0]) <= DEFAULT.round_off * float(np.linalg.norm(mean)):
                mean = (0.0, mean[1], mean[2])
            out["mean"] = mean
        return out

    @model_validator(mode="after")
    def _one_kind(self) -> Self:
        given = (self.tolerance is not None) + (self.over is not None)
        if self.angle is not None and given:
            raise ValueError("give the orientation zone as an angle or as {tolerance, over}")
        if self.angle is None and given != 2:
            raise ValueError(
                "an orientation zone needs an angle (e.g. '0.2 mrad') or a tolerance over "
                "a length, e.g. {tolerance: '0.01 mm', over: '40 mm'} ('over' is the "
                "joint's length if it has one)"
            )
        if self.mean[0] != 0.0:
            raise ValueError(
                "mean: a tilt has no component about the joint's axis (x); give [0, y, z]"
            )
        reach = self.radius + float(np.linalg.norm(self.mean))
        if reach > LARGEST_TILT:
            raise ValueError(
                f"the axis would tilt by up to {reach:.6g} rad, beyond the {LARGEST_TILT:g} rad "
                "that small displacements describe; an orientation tolerance is a small angle "
                "(a tolerance over a length: check the units)"
            )
        return self

    @property
    def radius(self) -> float:
        """The largest tilt (rad)."""
        if self.angle is not None:
            return self.angle
        assert self.tolerance is not None and self.over is not None
        return self.tolerance / self.over


class Zones(BaseModel):
    """A deviation's zones, a joint's own or shared (module doc)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    position: PositionZone | None = None
    orientation: OrientationZone | None = None
    distribution: Distribution = "uniform"

    @model_validator(mode="after")
    def _something(self) -> Self:
        if self.position is None and self.orientation is None and not self.names_shared:
            raise ValueError("a deviation needs a 'position' zone, an 'orientation' zone or both")
        return self

    @property
    def names_shared(self) -> bool:
        return False

    def describe(self, ball: bool) -> str:
        """In words: 'position: a disc of diameter 0.02 mm ...; uniform'."""
        parts = []
        if self.position is not None:
            p = self.position
            if p.diameter is not None:
                shape = "a ball" if ball else "a disc across the axis"
                parts.append(f"position in {shape} of diameter {p.diameter:.6g} mm")
            else:
                parts += [
                    f"position {axis} in [{lim.min:.6g}, {lim.max:.6g}] mm"
                    for axis in _AXES
                    if (lim := getattr(p, axis)) is not None
                ]
            if any(p.mean):
                parts.append(f"centred at [{', '.join(f'{v:.6g}' for v in p.mean)}] mm")
        if self.orientation is not None:
            o = self.orientation
            parts.append(f"tilt up to {o.radius:.6g} rad")
            if any(o.mean):
                parts.append(f"centred at [{', '.join(f'{v:.6g}' for v in o.mean)}] rad")
        return ", ".join(parts) + f"; {self.distribution}"

    def mean(self) -> FloatArray:
        """The mean torsor ``(t mm, w rad)`` in the joint frame."""
        out = np.zeros(6)
        if self.position is not None:
            out[:3] = self.position.mean
            for a, axis in enumerate(_AXES):
                limits = getattr(self.position, axis)
                if limits is not None:
                    out[a] = (limits.min + limits.max) / 2.0
        if self.orientation is not None:
            out[3:] = self.orientation.mean
        return out

    def zones(self, ball: bool) -> tuple[Zone, ...]:
        """The zones to draw from (``ball``: a diameter is a ball, else a disc
        across the axis x)."""
        out: list[Zone] = []
        if self.position is not None:
            p = self.position
            if p.diameter is not None:
                axes = (0, 1, 2) if ball else (1, 2)
                out.append(Zone("position", axes, p.diameter / 2.0))
            else:
                for a, axis in enumerate(_AXES):
                    limits = getattr(p, axis)
                    if limits is not None:
                        half = (limits.max - limits.min) / 2.0
                        out.append(Zone(f"position.{axis}", (a,), half))
        if self.orientation is not None:
            out.append(Zone("orientation", (4, 5), self.orientation.radius))
        return tuple(out)


@dataclass(frozen=True)
class Zone:
    """One zone of a deviation: the torsor components ``axes`` (0-2 the
    translation, 3-5 the rotation) lie within ``radius`` of their mean (a
    segment, a disc or a ball)."""

    name: str
    axes: tuple[int, ...]
    radius: float

    @property
    def unit(self) -> str:
        return "rad" if self.axes[0] >= 3 else "mm"

    def sigma(self, distribution: Distribution) -> float:
        """The standard deviation of each component (in ``unit``): uniform
        over a segment R/sqrt(3), a disc R/2, a ball R/sqrt(5); normal R/3,
        before truncation (as for plays, ``Toleranced.sigma``)."""
        if distribution == "normal":
            return self.radius / 3.0
        return float(self.radius / np.sqrt(len(self.axes) + 2.0))

    def sample(self, rng: np.random.Generator, n: int, distribution: Distribution) -> FloatArray:
        """(n, len(axes)) draws around 0: uniform over the zone, or normal
        with its edge at 3 sigma per direction, redrawn where outside."""
        d, R = len(self.axes), self.radius
        if R == 0.0:
            return np.zeros((n, d))
        if distribution == "uniform":
            if d == 1:
                return np.asarray(rng.uniform(-R, R, (n, 1)))
            u = rng.normal(size=(n, d))
            u /= np.linalg.norm(u, axis=1, keepdims=True)
            return np.asarray(u * (R * rng.uniform(size=(n, 1)) ** (1.0 / d)))
        out = rng.normal(0.0, R / 3.0, (n, d))
        bad = np.linalg.norm(out, axis=1) > R
        while np.any(bad):
            out[bad] = rng.normal(0.0, R / 3.0, (int(np.sum(bad)), d))
            bad = np.linalg.norm(out, axis=1) > R
        return out

    def from_unit(self, u: FloatArray, distribution: Distribution) -> FloatArray:
        """(n, len(axes)) the draws of ``u`` (n, len(axes)) in [0, 1), the law
        of ``sample`` for independent uniform ``u``: a segment through the
        inverse of its distribution function; a disc or ball by its radius
        (``u[:, 0]``, through the inverse of the radius's law: uniform by
        area or volume, or the truncated normal's chi law) and its direction
        (the angle, or the height and the angle, spread evenly)."""
        d, R = len(self.axes), self.radius
        u = np.asarray(u, dtype=float).reshape(len(u), d)
        if R == 0.0:
            return np.zeros((len(u), d))
        if d == 1:
            return quantile(u[:, 0], -R, R, distribution)[:, None]
        if distribution == "uniform":
            r = R * u[:, 0] ** (1.0 / d)
        else:  # |x| / sigma follows the chi law of d degrees, cut at R / sigma = 3
            from scipy.special import gammainc, gammaincinv

            inside = gammainc(d / 2.0, 4.5)  # P(chi^2_d <= 9)
            r = R / 3.0 * np.sqrt(2.0 * gammaincinv(d / 2.0, u[:, 0] * inside))
        angle = 2.0 * np.pi * u[:, -1]
        if d == 2:
            direction = np.column_stack([np.cos(angle), np.sin(angle)])
        else:
            z = 1.0 - 2.0 * u[:, 1]
            across = np.sqrt(np.maximum(1.0 - z**2, 0.0))
            direction = np.column_stack([across * np.cos(angle), across * np.sin(angle), z])
        return np.asarray(r[:, None] * direction)


def measured(t: Vec3 | None, w: Vec3 | None) -> Deviation:
    """A deviation known exactly (an as-measured part): zones of size 0
    centred on the measured translation ``t`` (mm) and tilt ``w`` (rad)."""
    position = None if t is None else PositionZone(diameter=0.0, mean=t)
    orientation = None if w is None else OrientationZone(angle=0.0, mean=w)
    return Deviation(position=position, orientation=orientation)


@dataclass(frozen=True)
class MeasuredDeviation:
    """A deviation as measured on one part (``with_deviations``): a joint's
    or a shared deviation's ``name``, its ``kind`` and ``value`` (position in
    mm, orientation in rad, in its frame), the ``zones`` the model gave it
    (None: none; kept to check a second measurement against, with ``ball``,
    whether their diameter is a ball: the part measured at 0 has no zones
    left to say it), and the warning when the value lies outside them
    (``outside``)."""

    name: str
    kind: Kind
    value: Vec3
    zones: Zones | None
    ball: bool
    warning: str | None

    @property
    def unit(self) -> str:
        return "mm" if self.kind == "position" else "rad"

    def describe(self) -> str:
        """'l2.position = [0, 0.05, 0] mm'."""
        return f"{self.name}.{self.kind} = {_listed(self.value)} {self.unit}"


def _listed(values: Sequence[float]) -> str:
    """'[0, 0.05, 0]' (no '-0')."""
    return "[" + ", ".join(f"{v + 0.0:.6g}" for v in values) + "]"


def measured_doc(measured: Sequence[MeasuredDeviation]) -> dict[str, dict[str, list[float]]]:
    """``{name: {kind: [x, y, z]}}`` (mm, rad), as ``with_deviations`` takes them."""
    out: dict[str, dict[str, list[float]]] = {}
    for m in measured:
        out.setdefault(m.name, {})[m.kind] = [v + 0.0 for v in m.value]
    return out


def _past(size: float, limit: float, scale: float) -> bool:
    """Whether ``size`` is beyond ``limit``: a value on the edge, written in
    decimals, can land its round-off past it (|(2, 2.1)| um is 2.9000000000000002
    against 2.9): within ``round_off`` of the largest value at hand it is on it."""
    return size - limit > DEFAULT.round_off * scale


def outside(zones: Zones, kind: Kind, value: Vec3, ball: bool) -> str | None:
    """Where a measured ``value`` (mm or rad, in the deviation's frame) lies
    outside the zones of ``kind`` of ``zones`` (``ball``: a diameter is a
    ball, else a disc across the axis x), in words; None inside them, on
    their edge, or where the zones have none of that kind. The zones are
    those the studies draw from (``Zones.zones``): each zone's components
    within its radius of the mean, every other component at its mean."""
    first = 0 if kind == "position" else 3
    mine = [z for z in zones.zones(ball) if first <= z.axes[0] < first + 3]
    if not mine:
        return None
    v = np.zeros(6)
    v[first : first + 3] = value
    mean = zones.mean()
    unit = "mm" if kind == "position" else "rad"
    own = slice(first, first + 3)
    scale = max(
        float(np.linalg.norm(v[own])),
        float(np.linalg.norm(mean[own])) + max(z.radius for z in mine),
    )
    centre = f" {_listed(mean[own].tolist())} {unit}" if any(mean[own]) else ""
    found: list[str] = []
    for a in range(first, first + 3):
        zone = next((z for z in mine if a in z.axes), None)
        if zone is None:  # a component no zone spans: it sits at its mean
            if _past(abs(v[a] - mean[a]), 0.0, scale):
                what = f"position along {_AXES[a]}" if kind == "position" else MOTION_WORDS[a]
                found.append(
                    f"its measured {what} is {v[a]:.6g} {unit}, where its zone "
                    f"({_allowed(mine)}) allows {mean[a] + 0.0:.6g} {unit}"
                )
        elif a == zone.axes[0]:
            size = float(np.linalg.norm((v - mean)[list(zone.axes)]))
            if _past(size, zone.radius, scale):
                found.append(_beyond(zones, zone, v[a], mean[a], size, centre))
    if not found:
        return None
    return "; ".join(found) + ": the part is out of tolerance"


def _shape(zone: Zone) -> str:
    """A diameter's zone in words: 'a ball of diameter 0.02 mm'."""
    shape = "a ball" if len(zone.axes) == 3 else "a disc across the axis"
    return f"{shape} of diameter {2.0 * zone.radius:.6g} mm"


def _allowed(mine: Sequence[Zone]) -> str:
    """What a kind's zones span, in words, for a component none of them spans."""
    if mine[0].name == "position":
        return _shape(mine[0])
    if mine[0].name == "orientation":
        return f"a tilt about y and z of up to {mine[0].radius:.6g} rad"
    return f"limits along {', '.join(z.name.removeprefix('position.') for z in mine)} only"


def _beyond(zones: Zones, zone: Zone, v: float, mean: float, size: float, centre: str) -> str:
    """A measured value ``size`` from the centre of ``zone``, past its radius, in words."""
    R = zone.radius
    if zone.name == "orientation":
        o = zones.orientation
        over = (
            f" ({o.tolerance:.6g} mm over {o.over:.6g} mm)"
            if o is not None and o.tolerance is not None and o.over is not None
            else ""
        )
        return (
            f"its measured tilt is {size:.6g} rad from its zone's centre{centre}, beyond "
            f"the zone's largest tilt of {R:.6g} rad{over}"
        )
    if zone.name == "position":
        return (
            f"its measured position is {size:.6g} mm from its zone's centre{centre}, "
            f"beyond the zone's radius of {R:.6g} mm ({_shape(zone)})"
        )
    axis = _AXES[zone.axes[0]]
    return (
        f"its measured position along {axis} is {v:.6g} mm, outside the zone's "
        f"[{mean - R + 0.0:.6g}, {mean + R + 0.0:.6g}] mm"
    )


def _by_name(schema: dict[str, Any]) -> None:
    """A joint's deviation in the schema: its zones, or a shared one's name."""
    whole = dict(schema)
    schema.clear()
    schema["anyOf"] = [{"type": "string", "description": "a shared deviation's name"}, whole]


class Deviation(Zones):
    """A joint's deviation: its own zones, or ``shared``, the name of a
    deviation of the model's ``deviations`` section (written ``deviation:
    setup`` in a file)."""

    model_config = ConfigDict(frozen=True, extra="forbid", json_schema_extra=_by_name)

    shared: Name | None = None

    @model_validator(mode="before")
    @classmethod
    def _a_name(cls, value: Any) -> Any:
        return {"shared": value} if isinstance(value, str) else value

    @model_validator(mode="after")
    def _zones_or_name(self) -> Self:
        if self.shared is not None and (self.position or self.orientation):
            raise ValueError(
                f"the joint takes the zones of the shared deviation '{self.shared}': leave "
                "out its own 'position' and 'orientation'"
            )
        return self

    @property
    def names_shared(self) -> bool:
        return self.shared is not None


class SharedDeviation(Zones):
    """A deviation of several joints' features made together (two bores
    bored in one setup): one small torsor of the whole group, at ``at`` in
    the frame of ``axis`` (and ``up``), taken by every joint that names it.
    Each joint sees it moved to its own centre and turned into its own frame:
    a tilt ``w`` of the group shifts a joint at ``c`` by ``w x (c - at)``.
    A ``diameter`` is a disc across ``axis``, or a ball without an axis."""

    name: Name
    #: The body on which the features were made (one side of every joint naming it).
    body: Name
    at: Point
    axis: Direction | None = None
    up: Direction | None = None

    @model_validator(mode="after")
    def _axis_for_a_tilt(self) -> Self:
        if self.axis is None and self.orientation is not None:
            raise ValueError(
                "an orientation zone tilts an axis: give the deviation an 'axis' (and the "
                "joints' features share its tilt)"
            )
        if self.axis is None and self.up is not None:
            raise ValueError("'up' turns the frame about its 'axis': give the axis too")
        if (
            self.axis is not None
            and self.up is not None
            and is_parallel(np.array(self.up), np.array(self.axis))
        ):
            raise ValueError(
                f"up {list(self.up)} is parallel to axis {list(self.axis)}; give an 'up' "
                "vector across the axis, or leave it out"
            )
        return self

    @property
    def R(self) -> FloatArray:
        """Its frame's axes (x = ``axis``) as columns, in global axes."""
        if self.axis is None:
            return np.eye(3)
        return joint_frame(self.axis, self.up)


def transport(
    R_from: FloatArray, at: FloatArray, R_to: FloatArray, centre: FloatArray
) -> FloatArray:
    """(6, 6): a small torsor (t, w) at ``at`` in the frame ``R_from`` as
    seen at ``centre`` in the frame ``R_to``: t' = R_to^T (R_from t + R_from w x
    (centre - at)), w' = R_to^T R_from w."""
    T = np.zeros((6, 6))
    lever = np.asarray(centre, dtype=float) - np.asarray(at, dtype=float)
    T[:3, :3] = R_to.T @ R_from
    T[:3, 3:] = -R_to.T @ skew(lever) @ R_from
    T[3:, 3:] = R_to.T @ R_from
    return T
