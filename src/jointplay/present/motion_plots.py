"""Pictures of a motion study (``jointplay.studies.motion.MotionResult``).

Each picture has a function that returns its data (plain arrays, read from
the result and nothing else) and one that draws it with matplotlib:

- ``displacement_series`` / ``draw_displacement``: a functional point's
  displacement due to the play against the drive's value, along its
  requirement's direction if it has one, else its size and components; with
  optional percentile bands, an envelope and the requirement's limit;
- ``path_series`` / ``draw_path``: the point's path, nominal and with the
  play's effect magnified;
- ``joint_forces`` and ``contact_switches`` / ``draw_joint_forces``: each
  joint's reaction force against the drive's value, marked where its
  touching contacts change (a contact starts or stops touching, or pushes
  the other way: the play is crossed, an impact in a running machine);
- ``poses_figure``: the mechanism drawn at chosen poses.

``motion_figure`` puts the first three in one figure (what ``jointplay
motion --plot FILE`` writes). matplotlib is imported inside the drawing
functions only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from jointplay.geometry import FloatArray
from jointplay.present.scene import auto_magnify, body_lines

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from jointplay.model.mechanism import Model, Requirement
    from jointplay.studies.motion import MotionResult

#: A band: its label ("5-95 %") and its lower and upper values per step (mm).
Band = tuple[str, FloatArray, FloatArray]

#: ``motion_figure`` gives a row to each of at most this many functional
#: points (the required ones first): more rows would shrink every panel.
POINTS_SHOWN = 4
#: The path is drawn at equal scales on its two axes when its narrower span
#: is at least this share of the wider (a coupler curve); a straighter path
#: (a piston's stroke) gets scales of its own, or its play would not show.
EQUAL_ASPECT_SHARE = 0.1
#: The displacement's curves: the measure, then the X, Y, Z components (no
#: red: that is the limit's).
CURVE_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd")
#: The joints' force curves cycle through these dashes.
LINE_STYLES = ("-", "--", "-.", ":")
#: ``poses_figure`` draws this many poses by default, spread over the motion.
POSES_SHOWN = 5


# -- (a) the displacement against the drive --------------------------------------
@dataclass(frozen=True)
class DisplacementSeries:
    """What the displacement panel draws: ``curves`` (label, values per step,
    mm) against ``drive`` (per step, in ``unit``); ``along`` the requirement's
    unit direction (None: the size and components are drawn); ``limit`` the
    requirement's bound (mm; drawn at +-limit along a direction)."""

    point: str
    drive: FloatArray
    unit: str
    curves: tuple[tuple[str, FloatArray], ...]
    along: FloatArray | None
    limit: float | None
    bands: tuple[Band, ...] = ()
    envelope: tuple[FloatArray, FloatArray] | None = None
    worst_step: int | None = None
    #: The envelope's legend: what loads it is under ("... under 1 N probes").
    envelope_label: str = "worst-case envelope"


def requirement_of(result: MotionResult, point: str) -> Requirement | None:
    """The first requirement on ``point`` (one along a direction first)."""
    if not result.results:
        return None
    found = [r.requirement for r in result.results[0].requirements if r.requirement.point == point]
    found.sort(key=lambda r: r.along is None)
    return found[0] if found else None


def shown_drive(result: MotionResult) -> FloatArray:
    """The drive's values as the motion section writes them (deg or mm)."""
    return np.array([result.shown_value(s) for s in range(result.steps)], dtype=float)


def displacement_series(
    result: MotionResult,
    point: str,
    bands: Sequence[Band] = (),
    envelope: tuple[FloatArray, FloatArray] | None = None,
    envelope_label: str = "worst-case envelope",
) -> DisplacementSeries:
    """The displacement panel's data for ``point``. ``bands`` and
    ``envelope`` are per step (mm), along the requirement's direction when
    it has one, else of the displacement's size; ``envelope_label`` its
    legend, naming the loads it is under."""
    k = _point_index(result, point)
    d = result.displacement[:, k]
    req = requirement_of(result, point)
    worst = None
    if req is not None:
        q = [r.requirement for r in result.results[0].requirements].index(req)
        worst = result.worst_step(q)
    S = result.steps
    checked = tuple((label, _per_step(lo, S), _per_step(hi, S)) for label, lo, hi in bands)
    env = None if envelope is None else (_per_step(envelope[0], S), _per_step(envelope[1], S))
    if req is not None and req.along is not None:
        u = np.asarray(req.along, dtype=float)
        u = u / np.linalg.norm(u)
        curves: tuple[tuple[str, FloatArray], ...] = (
            (f"d along {_direction(u)}", np.asarray(d @ u)),
        )
        return DisplacementSeries(
            point,
            shown_drive(result),
            result.unit,
            curves,
            u,
            req.max_displacement,
            checked,
            env,
            worst,
            envelope_label,
        )
    curves = (
        ("|d|", np.linalg.norm(d, axis=1)),
        *((f"d{axis}", np.asarray(d[:, i])) for i, axis in enumerate("xyz")),
    )
    limit = None if req is None else req.max_displacement
    return DisplacementSeries(
        point,
        shown_drive(result),
        result.unit,
        curves,
        None,
        limit,
        checked,
        env,
        worst,
        envelope_label,
    )


def draw_displacement(ax: Axes, series: DisplacementSeries, drive: str) -> None:
    from jointplay.present.plot import TOUCHING

    for label, lower, upper in series.bands:
        ax.fill_between(series.drive, lower, upper, alpha=0.25, linewidth=0, label=label)
    if series.envelope is not None:
        lower, upper = series.envelope
        ax.plot(series.drive, lower, "--", color="#555555", lw=1.0, label=series.envelope_label)
        ax.plot(series.drive, upper, "--", color="#555555", lw=1.0)
    for i, (label, values) in enumerate(series.curves):
        main = i == 0  # the measure; the components thinner
        colour = CURVE_COLOURS[i % len(CURVE_COLOURS)]  # not the cycle: bands take its first
        ax.plot(
            series.drive,
            values,
            label=label,
            color=colour,
            lw=1.8 if main else 0.9,
            alpha=1 if main else 0.8,
        )
    if series.limit is not None:
        ax.axhline(series.limit, color=TOUCHING, linewidth=1.2, label=f"limit {series.limit:g} mm")
        if series.along is not None:
            ax.axhline(-series.limit, color=TOUCHING, linewidth=1.2)
    if series.worst_step is not None:
        s = series.worst_step
        ax.plot(
            [series.drive[s]],
            [series.curves[0][1][s]],
            "o",
            color=TOUCHING,
            markersize=5,
            label=f"worst: {series.drive[s]:g} {series.unit}",
        )
    ax.set_title(f"point '{series.point}': displacement due to the play", fontsize=10)
    ax.set_xlabel(f"{drive} ({series.unit})")
    ax.set_ylabel("mm")
    ax.grid(True, linewidth=0.3)
    ax.legend(fontsize=7, loc="best")


# -- (b) the path ------------------------------------------------------------------
@dataclass(frozen=True)
class PathSeries:
    """The path panel's data: the point's nominal path and its path with the
    play's displacement times ``magnify`` (S, 3) mm; ``axes``: the two
    global axes drawn (0, 1, 2 for X, Y, Z)."""

    point: str
    nominal: FloatArray
    displaced: FloatArray
    magnify: float
    axes: tuple[int, int]


def path_series(result: MotionResult, point: str, magnify: float | None = None) -> PathSeries:
    """``point``'s path; ``magnify`` None picks a round factor that shows the
    largest displacement as a visible share of the path's span."""
    k = _point_index(result, point)
    nominal = np.asarray(result.nominal[:, k])
    d = np.asarray(result.displacement[:, k])
    span = float(np.linalg.norm(np.ptp(nominal, axis=0)))
    largest = float(np.max(np.linalg.norm(d, axis=1), initial=0.0))
    m = auto_magnify(max(span, 1.0), largest) if magnify is None else float(magnify)
    displaced = nominal + m * d
    extent = np.ptp(np.vstack([nominal, displaced]), axis=0)
    h, v = sorted(int(i) for i in np.argsort(-extent, kind="stable")[:2])
    return PathSeries(point, nominal, displaced, m, (h, v))


def draw_path(ax: Axes, series: PathSeries) -> None:
    from jointplay.present.plot import INITIAL

    h, v = series.axes
    ax.plot(series.nominal[:, h], series.nominal[:, v], color=INITIAL, ls="--", label="nominal")
    ax.plot(
        series.displaced[:, h],
        series.displaced[:, v],
        linewidth=1.6,
        label=f"with the play x{series.magnify:g}",
    )
    ax.plot([series.nominal[0, h]], [series.nominal[0, v]], "k>", markersize=6, label="step 0")
    spans = np.ptp(np.vstack([series.nominal, series.displaced])[:, [h, v]], axis=0)
    if np.min(spans) >= EQUAL_ASPECT_SHARE * np.max(spans) > 0.0:
        ax.set_aspect("equal", adjustable="datalim")
    names = "XYZ"
    ax.set_title(f"point '{series.point}': path (play x{series.magnify:g})", fontsize=10)
    ax.set_xlabel(f"{names[h]} (mm)")
    ax.set_ylabel(f"{names[v]} (mm)")
    ax.grid(True, linewidth=0.3)
    ax.legend(fontsize=7, loc="best")


# -- (c) the joints' forces --------------------------------------------------------
def joint_forces(result: MotionResult) -> dict[str, FloatArray]:
    """Each joint's reaction force (its size, N) per step."""
    names = list(result.results[0].joints) if result.results else []
    return {
        name: np.array(
            [float(np.linalg.norm(r.joints[name].reaction_force)) for r in result.results]
        )
        for name in names
    }


def contact_switches(result: MotionResult) -> dict[str, tuple[int, ...]]:
    """Per joint, the steps whose touching contacts switch from the step
    before's (``MotionResult.switched``: a contact starts or stops touching,
    or one touching at both pushes the other way: the play crossed)."""
    return {
        name: tuple(s for s in range(1, result.steps) if name in result.switched[s])
        for name in joint_forces(result)
    }


def draw_joint_forces(ax: Axes, result: MotionResult) -> None:
    drive = shown_drive(result)
    switches = contact_switches(result)
    for i, (name, force) in enumerate(joint_forces(result).items()):
        steps = list(switches[name])
        label = name + (f" ({len(steps)} switches)" if steps else "")
        # joints in one load path carry one force: dashes keep each curve in sight
        dash = LINE_STYLES[i % len(LINE_STYLES)]
        (line,) = ax.plot(drive, force, linewidth=1.4, linestyle=dash, label=label)
        if steps:
            ax.plot(drive[steps], force[steps], "v", color=line.get_color(), markersize=7)
    if any(switches.values()):
        ax.plot([], [], "v", color="#444444", label="contacts switch sides")
    ax.set_title(
        "each joint's reaction force; marks where its touching contacts change", fontsize=10
    )
    ax.set_xlabel(f"{result.drive} ({result.unit})")
    ax.set_ylabel("N")
    ax.grid(True, linewidth=0.3)
    ax.legend(fontsize=7, loc="best", ncols=2)


# -- the figure of ``--plot`` ----------------------------------------------------------
@dataclass(frozen=True)
class MotionPictures:
    """Optional extras of ``motion_figure``, per point name: percentile
    ``bands`` and a worst-case ``envelope`` (per step, mm, as
    ``displacement_series`` takes them); ``envelope_label`` the envelopes'
    legend, naming the loads they are under."""

    bands: dict[str, Sequence[Band]] = field(default_factory=dict)
    envelopes: dict[str, tuple[FloatArray, FloatArray]] = field(default_factory=dict)
    envelope_label: str = "worst-case envelope"


def shown_points(result: MotionResult) -> list[str]:
    """The points ``motion_figure`` draws: the required ones first."""
    required = [n for n in result.point_names if n in result.requirement_names]
    others = [n for n in result.point_names if n not in result.requirement_names]
    return (required + others)[:POINTS_SHOWN]


def motion_figure(
    result: MotionResult, extras: MotionPictures | None = None, magnify: float | None = None
) -> Figure:
    """A row per functional point (its displacement against the drive, its
    path), then a row of the joints' reaction forces with their switches."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from jointplay.present.plot import roomy_ticks

    extras = extras or MotionPictures()
    points = shown_points(result)
    rows = len(points) + 1
    fig = plt.figure(figsize=(12, 3.9 * rows), layout="constrained")
    grid = fig.add_gridspec(rows, 5)
    for i, name in enumerate(points):
        series = displacement_series(
            result,
            name,
            extras.bands.get(name, ()),
            extras.envelopes.get(name),
            extras.envelope_label,
        )
        draw_displacement(fig.add_subplot(grid[i, :3]), series, result.drive)
        draw_path(fig.add_subplot(grid[i, 3:]), path_series(result, name, magnify))
    draw_joint_forces(fig.add_subplot(grid[rows - 1, :]), result)
    fig.suptitle(
        f"{result.model_name or 'mechanism'}: {result.steps} poses driven by '{result.drive}'",
        fontsize=12,
    )
    roomy_ticks(fig)
    return fig


# -- (d) the mechanism at chosen poses ----------------------------------------------
def posed_lines(model: Model, result: MotionResult, step: int) -> dict[str, list[FloatArray]]:
    """Each moving body's lines (its outline, else the line of its joints) as
    the body sits at ``step`` (mm, global)."""
    return {
        body: [np.array([result.poses.place(step, body, P) for P in path]) for path in paths]
        for body, paths in body_lines(model).items()
    }


def joint_centres(model: Model, result: MotionResult, step: int) -> FloatArray:
    """The joints' centres at ``step`` (J, 3): carried by their second body."""
    return np.array(
        [
            result.poses.place(step, j.between[1], np.asarray(j.at, dtype=float))
            for j in model.joints
        ]
    ).reshape(-1, 3)


def drawn_plane(model: Model, result: MotionResult) -> tuple[int, int]:
    """The two global axes along which the mechanism moves the most."""
    every = np.vstack(
        [joint_centres(model, result, s) for s in range(result.steps)]
        + [np.asarray(result.nominal).reshape(-1, 3)]
    )
    extent = np.ptp(every, axis=0)
    h, v = sorted(int(i) for i in np.argsort(-extent, kind="stable")[:2])
    return h, v


def spread_steps(result: MotionResult, count: int = POSES_SHOWN) -> list[int]:
    """``count`` steps spread over the motion; over a closed cycle (the last
    pose is the first) the last is left out."""
    from jointplay.settings import MOTION

    last = result.steps - 1
    R, p = result.poses.R, result.poses.p
    # the same pose to what the kinematics closes a loop to
    size = max(float(np.max(np.abs(p), initial=0.0)), 1.0)
    off = max(
        float(np.max(np.abs(R[last] - R[0]), initial=0.0)) * size,
        float(np.max(np.abs(p[last] - p[0]), initial=0.0)),
    )
    closed = off <= MOTION.closure * size
    end = last + 1 if closed else last
    parts = count if closed else count - 1
    return sorted({round(end * i / max(parts, 1)) for i in range(count)} - {end})


def poses_figure(model: Model, result: MotionResult, steps: Sequence[int] | None = None) -> Figure:
    """The mechanism at ``steps`` (default: ``POSES_SHOWN`` spread over the
    motion), drawn over each other in its plane, the later poses darker."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from jointplay.present.plot import BODY_COLOURS, POINT

    if steps is None:
        steps = spread_steps(result)
    h, v = drawn_plane(model, result)
    fig, ax = plt.subplots(figsize=(9, 6), layout="constrained")
    bodies = list(body_lines(model))
    for n, s in enumerate(steps):
        shade = 0.3 + 0.7 * (n + 1) / len(steps)
        for body, paths in posed_lines(model, result, s).items():
            colour = BODY_COLOURS[bodies.index(body) % len(BODY_COLOURS)]
            for k, P in enumerate(paths):
                ax.plot(
                    P[:, h],
                    P[:, v],
                    color=colour,
                    alpha=shade,
                    linewidth=1.5,
                    label=body if n == len(steps) - 1 and k == 0 else None,
                )
        C = joint_centres(model, result, s)
        ax.plot(C[:, h], C[:, v], "o", color="#333333", markersize=3, alpha=shade)
        for k in range(len(result.point_names)):
            P = result.nominal[s, k]
            ax.plot([P[h]], [P[v]], "D", color=POINT, markersize=3, alpha=shade)
        tag = result.nominal[s, 0] if result.point_names else C[-1]
        ax.annotate(
            f"{result.shown_value(s):g} {result.unit}",
            (float(tag[h]), float(tag[v])),
            fontsize=7,
            alpha=shade,
        )
    ax.plot([], [], "o", color="#333333", markersize=3, label="joint centres")
    if result.point_names:
        ax.plot([], [], "D", color=POINT, markersize=3, label="functional points")
    ax.set_aspect("equal", adjustable="datalim")
    names = "XYZ"
    ax.set_xlabel(f"{names[h]} (mm)")
    ax.set_ylabel(f"{names[v]} (mm)")
    ax.grid(True, linewidth=0.3)
    ax.legend(fontsize=8, loc="best")
    shown = ", ".join(f"{result.shown_value(s):g}" for s in steps)
    ax.set_title(
        f"{result.model_name or 'mechanism'} at {result.drive} = {shown} {result.unit}",
        fontsize=11,
    )
    return fig


# -- helpers -------------------------------------------------------------------------
def _point_index(result: MotionResult, point: str) -> int:
    if point not in result.point_names:
        names = ", ".join(repr(n) for n in result.point_names) or "none"
        raise KeyError(f"no functional point {point!r} (the model's: {names})")
    return result.point_names.index(point)


def _per_step(values: FloatArray, steps: int) -> FloatArray:
    out = np.asarray(values, dtype=float)
    if out.shape != (steps,):
        raise ValueError(f"a band or envelope needs one value per step ({steps}), got {out.shape}")
    return out


def _direction(u: FloatArray) -> str:
    return "[" + ", ".join(f"{c:g}" for c in np.round(u, 4)) + "]"
