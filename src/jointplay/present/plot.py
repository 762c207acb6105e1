"""Figures in the paper's manner, drawn with matplotlib (no screen needed).

``mechanism_figure``: the exaggerated mechanism (3D and the three
orthographic views) with each joint's clearance domain seen along its axis;
``clearance_figure``: those joint views alone; ``sweep_figure``,
``envelope_figure``, ``montecarlo_figure`` and ``contributions_figure`` for
the studies. Each returns a matplotlib ``Figure``; ``save`` writes it as
PNG, SVG or PDF. The geometry comes from ``scene.py``.
"""

from __future__ import annotations

import logging
import math
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")  # files only: no screen on a server or in CI

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.layout_engine import ConstrainedLayoutEngine
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, FancyArrowPatch, Polygon, Rectangle
from matplotlib.text import Annotation
from matplotlib.ticker import MaxNLocator
from matplotlib.transforms import Bbox

from jointplay.errors import OptionError
from jointplay.geometry import FloatArray
from jointplay.indeterminacy import over_steps
from jointplay.present.outputs import check_figure_path
from jointplay.present.scene import JointView, Marker, Scene, joint_view, mechanism_scene

# a stale font cache makes matplotlib log each font it falls back from; the
# figure is drawn all the same, and only jointplay's own words reach stderr
logging.getLogger("matplotlib.font_manager").setLevel(logging.ERROR)

if TYPE_CHECKING:
    from mpl_toolkits.mplot3d.axes3d import Axes3D

    from jointplay.model.mechanism import Model
    from jointplay.result import Result
    from jointplay.studies.contributions import ContributionsResult
    from jointplay.studies.envelope import EnvelopeResult
    from jointplay.studies.montecarlo import MonteCarloResult
    from jointplay.studies.sweep import SweepResult
    from jointplay.studies.tolerances import TolerancesResult

INITIAL = "#9a9a9a"
DOMAIN = "#2f6db5"
TOUCHING = "#d62728"
FREE = "#7f7f7f"
LOAD = "#2ca02c"
POINT = "#111111"
BODY_COLOURS = ("#1f4e79", "#8c564b", "#9467bd", "#17becf", "#bcbd22", "#e377c2")

#: The three orthographic views: (name, horizontal axis, vertical axis).
VIEWS = (("XY (along Z)", 0, 1), ("XZ (along -Y)", 0, 2), ("YZ (along X)", 1, 2))
JOINTS_PER_ROW = 4
#: A view is edge-on when the bodies and points extend less than this share of
#: the mechanism's size along one of its axes (a planar mechanism seen from the
#: side), or when a study's cloud of displacements is thinner than this share
#: of its length across its principal direction in that view (a line).
FLAT = 0.02
#: Where a label may sit around its mark (points across, up), tried in order:
#: the eight ways beside it, then the same farther out (marks close together).
LABEL_OFFSETS = tuple(
    (k * dx, k * dy)
    for k in (1, 3)
    for dx, dy in ((5, 4), (-5, 4), (5, -4), (-5, -4), (7, 0), (-7, 0), (0, 7), (0, -7))
)
#: Pixels kept between two labels, and between a label and its panel's frame.
LABEL_GAP = 3.0
#: A mark's size (pixels) that the other marks' labels keep clear of.
MARK_SIZE = 6.0
#: In the 3D panel a direction spans at least this share of the longest (its
#: ticks need room); the 2D views keep true scale.
THIN_3D = 0.3
#: A 2D view's shorter side spans at least this share of its longer one (true
#: scale kept): a long shaft's side view gets room above and below, not a strip.
STRIP = 0.3
#: The 3D panel's box shrinks (matplotlib's zoom) until its tick and axis
#: labels lie inside its slot, in at most this many tries.
FIT_3D_TRIES = 4
#: An arrow seen nearly end on in a view, shorter there than this share of its
#: length, is left out of that view (it would be a dot with a head).
END_ON = 0.05
#: The arrows' shaft width in the views (inches): the same in every panel.
ARROW_WIDTH = 0.022
#: Joint views under the mechanism figure, and in the joints figure, at most:
#: a larger mechanism shows its most loaded joints.
JOINT_VIEWS_SHOWN = 8
JOINT_PANELS_MOST = 48
#: Bodies named in the legend, at most.
LEGEND_BODIES = 6
#: Contacts drawn in a sweep's contact-force panel, at most (those that carry
#: the largest forces): more would make a legend taller than the figure.
LEGEND_CONTACTS = 12
ARROW = r"$\rightarrow$"  # a legend marker
#: A histogram as one filled outline: bars with white edges turned to stripes
#: where the parts spread over a small share of the axis (a limit far off).
HISTOGRAM: dict[str, Any] = {
    "histtype": "stepfilled",
    "facecolor": "#6f9fd8",
    "edgecolor": "#2f5f9f",
    "linewidth": 0.8,
}
#: Characters per line of a joint panel's note (a panel is about this wide).
NOTE_WIDTH = 34
#: A title's characters are about this share of its font size wide, on
#: average: a figure's title is broken into lines as wide as the figure.
TITLE_CHAR_WIDTH = 0.55
#: A tick label's characters are at most this share of its font size wide
#: (digits and the minus sign).
TICK_CHAR_WIDTH = 0.65


class RoomyLocator(MaxNLocator):
    """Ticks at steps of 1, 2 or 5 x 10^k, as many as the axis holds at its
    labels' width: matplotlib's own estimate gives a label three font sizes,
    and '-0.0025' takes more, so that labels ran into each other."""

    def __init__(self, most: int = 9, symmetric: bool = False) -> None:
        super().__init__(nbins=most, steps=[1, 2, 5, 10], symmetric=symmetric)
        self.most = most

    def tick_values(self, vmin: float, vmax: float) -> Any:
        from matplotlib.axis import Axis

        axis = self.axis
        fig = axis.axes.get_figure(root=True) if isinstance(axis, Axis) else None
        if not isinstance(axis, Axis) or fig is None or not axis.get_major_ticks(1):
            return super().tick_values(vmin, vmax)
        inches = axis.axes.transAxes - fig.dpi_scale_trans
        room = Bbox.unit().transformed(inches).width * 72  # points
        size = float(axis.get_major_ticks(1)[0].label1.get_fontsize())
        low, high = sorted((vmin, vmax))
        for nbins in range(self.most, 0, -1):
            self.set_params(nbins=nbins)
            locs = super().tick_values(vmin, vmax)
            seen = [x for x in locs if low <= x <= high]
            labels = axis.get_major_formatter().format_ticks(seen)
            width = max((len(t) for t in labels), default=0) * TICK_CHAR_WIDTH * size + size
            if len(seen) * width <= room:
                break
        self.set_params(nbins=self.most)
        return locs


def roomy_ticks(fig: Figure) -> None:
    """Every 2D panel's x ticks left to matplotlib no closer than their
    labels' width (``RoomyLocator``)."""
    from matplotlib.ticker import AutoLocator

    for ax in fig.axes:
        if ax.name == "rectilinear" and type(ax.xaxis.get_major_locator()) is AutoLocator:
            ax.xaxis.set_major_locator(RoomyLocator())


def save(fig: Figure, path: Path | str) -> Path:
    """Write ``fig`` as PNG, SVG or PDF, by the file's suffix, and close it."""
    out = Path(path)
    kind = check_figure_path(out)
    try:
        fig.savefig(out, format=kind, dpi=150, bbox_inches="tight")
    except OSError as exc:
        raise OptionError(f"{out}: cannot write it ({exc.strerror})") from None
    finally:
        plt.close(fig)
    return out


# -- the mechanism -------------------------------------------------------------
def mechanism_figure(
    model: Model,
    result: Result,
    *,
    magnify: float | None = None,
    case: str | None = None,
    joints: bool = True,
) -> Figure:
    """The paper's figure of a solved mechanism: the bodies as lines between
    their joints, initial (dashed) and displaced, the clearance domains, the
    contacts (red: touching), the contact forces (red arrows) and the loads
    (green), in 3D and in the three orthographic views; then, with
    ``joints``, each joint seen along its axis at true size."""
    scene = mechanism_scene(model, result, magnify=magnify, case=case)
    chosen = most_loaded_joints(model, result, JOINT_VIEWS_SHOWN) if joints else []
    views = [joint_view(model.joint(name), result.joints[name]) for name in chosen]
    joint_rows = math.ceil(len(views) / JOINTS_PER_ROW)
    shown = shown_views(scene)

    def tall(h: int, v: int) -> float:  # a view's height over its width
        (x0, x1), (y0, y1) = view_limits(scene, h, v)
        return (y1 - y0) / (x1 - x0)

    if len(shown) == 3:
        # the XY and XZ views share a row: as tall as the taller needs at half the width
        heights = [4.6, float(np.clip(6.2 * max(tall(0, 1), tall(0, 2)), 1.6, 6.0))]
    else:  # a planar mechanism: the 3D panel and its plane, side by side
        _, h, v = shown[0]
        heights = [float(np.clip(6.2 * tall(h, v), 3.0, 6.0))]
    heights += [3.2] * joint_rows
    # room between the panels: the 3D panel's axis labels stand out of its box
    layout = ConstrainedLayoutEngine(w_pad=0.1, wspace=0.05)
    fig = plt.figure(figsize=(13, sum(heights) + 1.2), layout=layout)
    # 12 columns: halves for the views; the joint panels share each row evenly,
    # so that two or three of them fill it (no empty quarter)
    grid = fig.add_gridspec(len(heights), 12, height_ratios=heights)
    ax3d: Axes3D = fig.add_subplot(grid[0, :6], projection="3d")
    draw_scene_3d(ax3d, scene)
    slots = {"XY (along Z)": grid[1, :6], "XZ (along -Y)": grid[1, 6:]} if len(shown) == 3 else {}
    for title, h, v in shown:
        ax = fig.add_subplot(slots.get(title, grid[0, 6:]))
        draw_scene_view(ax, scene, h, v, title, reference=title == shown[0][0])
    first_joint_row = len(heights) - joint_rows
    reach = _common_reach(views)
    # as even rows as can be: five panels as 3 + 2, not 4 + 1
    per_row = math.ceil(len(views) / joint_rows) if views else 1
    width = 12 // per_row
    for i, view in enumerate(views):
        column = (i % per_row) * width
        ax = fig.add_subplot(grid[first_joint_row + i // per_row, column : column + width])
        draw_joint_view(ax, view, reach)
    what = model.name or "mechanism"
    if case is not None:
        what += f", case '{case}'"
    if len(chosen) < len(with_play(model)) and joints:
        what += f" (the views of the {len(chosen)} most loaded of {len(with_play(model))} joints)"
    _suptitle(
        fig,
        f"{what}: displacements and plays ×{scene.magnify:g} "
        f"(largest {scene.largest_displacement:.4g} mm); force arrows to the scale of the "
        "black one"
        if scene.force_scale > 0
        else f"{what}: displacements and plays ×{scene.magnify:g}",
        fontsize=12,
    )
    roomy_ticks(fig)
    fig.legend(handles=_legend_handles(scene), loc="outside lower center", ncols=7, fontsize=9)
    fit_3d_panel(fig, ax3d, scene)
    numbered = place_point_labels(fig, model, drawn=True)
    if numbered:  # the points named only by number, named in the legend
        fig.legends[0].remove()
        tags = [
            Line2D([], [], color=POINT, marker=f"${k}$", ls="", label=model.points[k - 1].name)
            for k in sorted(numbered)
        ]
        handles = _legend_handles(scene) + tags
        fig.legend(handles=handles, loc="outside lower center", ncols=7, fontsize=9)
        fit_3d_panel(fig, ax3d, scene)  # the legend took room: again, at the final size
        place_point_labels(fig, model, drawn=True)
    return fig


def shown_views(scene: Scene) -> list[tuple[str, int, int]]:
    """The orthographic views that show something: a view along a plane in
    which everything lies (the edge-on views of a planar mechanism) is left
    out; at least the view of the widest extent stays."""
    span = scene.body_span()
    thick = span >= FLAT * scene.size
    shown = [view for view in VIEWS if thick[view[1]] and thick[view[2]]]
    return shown or [max(VIEWS, key=lambda view: min(span[view[1]], span[view[2]]))]


def with_play(model: Model) -> list[str]:
    """The joints that have play (a rigid joint's view would be an empty panel)."""
    return [j.name for j in model.joints if any(c.kind != "fixed" for c in j.cones)]


def most_loaded_joints(model: Model, result: Result, most: int) -> list[str]:
    """The joints with play when there are at most ``most``; else the ``most``
    that carry the largest reaction forces, in the model's order."""
    names = with_play(model)
    if len(names) <= most:
        return names
    force = {n: float(np.linalg.norm(result.joints[n].reaction_force)) for n in names}
    kept = set(sorted(names, key=lambda n: -force[n])[:most])
    return [n for n in names if n in kept]


def clearance_figure(model: Model, result: Result, joints: Sequence[str] | None = None) -> Figure:
    """Each joint seen along its axis, at true size (the paper's figure 6).
    ``joints``: their names (default: every joint, or the ``JOINT_PANELS_MOST``
    most loaded of a larger mechanism, said in the title)."""
    chosen = (
        list(joints) if joints is not None else most_loaded_joints(model, result, JOINT_PANELS_MOST)
    )
    views = [joint_view(model.joint(name), result.joints[name]) for name in chosen]
    if not views:
        fig, ax = plt.subplots(figsize=(4, 1.5))
        ax.text(0.5, 0.5, "no joint has play", ha="center", va="center")
        ax.set_axis_off()
        return fig
    cols = min(len(views), JOINTS_PER_ROW)
    rows = math.ceil(len(views) / cols)
    fig, axes = plt.subplots(
        rows, cols, figsize=(3.6 * cols, 3.6 * rows), squeeze=False, layout="constrained"
    )
    reach = _common_reach(views)
    for ax, view in zip(axes.flat, views, strict=False):
        draw_joint_view(ax, view, reach)
    for ax in axes.flat[len(views) :]:
        ax.set_axis_off()
    played = with_play(model)
    some = "" if len(chosen) == len(played) else f" ({len(chosen)} of {len(played)} with play)"
    _suptitle(
        fig, f"{model.name or 'mechanism'}: each joint at true size (mm), b relative to a{some}"
    )
    roomy_ticks(fig)
    place_point_labels(fig)
    return fig


def _suptitle(fig: Figure, text: str, fontsize: float = 12.0) -> None:
    """The figure's title, broken into lines as wide as the figure."""
    per_line = int(fig.get_figwidth() * 72 / (TITLE_CHAR_WIDTH * fontsize))
    lines = len(textwrap.wrap(text, per_line))
    even = math.ceil(len(text) / lines) + 8  # lines of about one length: no lone word
    fig.suptitle("\n".join(textwrap.wrap(text, min(even, per_line))), fontsize=fontsize)


def _body_colours(scene: Scene) -> dict[str, str]:
    names = sorted({ln.label for ln in scene.lines if ln.role == "displaced"})
    return {n: BODY_COLOURS[i % len(BODY_COLOURS)] for i, n in enumerate(names)}


def _line_groups(scene: Scene) -> list[tuple[list[FloatArray], dict[str, Any]]]:
    """The scene's lines in a few groups, one style each (drawn as one
    collection: a mechanism of a thousand bodies draws as fast as one)."""
    colours = _body_colours(scene)
    initial = [ln.points for ln in scene.lines if ln.role == "initial"]
    domain = [ln.points for ln in scene.lines if ln.role == "domain"]
    moved = [ln for ln in scene.lines if ln.role == "displaced"]
    return [
        (initial, {"colors": INITIAL, "linestyles": "--", "linewidths": 1.0}),
        (domain, {"colors": DOMAIN, "linewidths": 0.9}),
        (
            [ln.points for ln in moved],
            {"colors": [colours[ln.label] for ln in moved], "linewidths": 2.4},
        ),
    ]


def _arrow_groups(scene: Scene) -> list[tuple[FloatArray, FloatArray, str]]:
    out = []
    for role, colour in (("contact force", TOUCHING), ("load", LOAD)):
        arrows = [a for a in scene.arrows if a.role == role]
        if arrows:
            out.append(
                (np.array([a.start for a in arrows]), np.array([a.vector for a in arrows]), colour)
            )
    return out


def draw_scene_3d(ax: Axes3D, scene: Scene) -> None:
    """The scene in 3D, with equal scales on the three axes."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection

    for lines, style in _line_groups(scene):
        if lines:
            ax.add_collection3d(Line3DCollection(lines, **style))
    for role in ("touching", "free", "point"):
        marks = [m for m in scene.markers if m.role == role]
        if marks:
            P = np.array([m.at for m in marks])
            ax.scatter(P[:, 0], P[:, 1], P[:, 2], **_marker_style(role))
    for start, vector, colour in _arrow_groups(scene):
        ax.quiver(
            start[:, 0],
            start[:, 1],
            start[:, 2],
            vector[:, 0],
            vector[:, 1],
            vector[:, 2],
            color=colour,
            linewidth=1.4,
            arrow_length_ratio=0.2,
        )
    lo, hi = _padded_bounds(scene)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    # true scale, except that a thin direction gets room for its ticks (the
    # three views beside it are at true scale)
    span = hi - lo
    ax.set_box_aspect(tuple(np.maximum(span, THIN_3D * float(np.max(span)))))
    # the points' labels in the projection's plane (fixed by the limits, the
    # box and the view), so that place_point_labels can move them as in the
    # 2D views
    for k, mk in enumerate(_points(scene), start=1):
        _point_label(ax, mk.label, (0.0, 0.0), k)
    _project_labels(ax, scene)
    for axis, span_i in zip((ax.xaxis, ax.yaxis, ax.zaxis), span, strict=True):
        axis.set_major_locator(MaxNLocator(5 if span_i >= 0.5 * np.max(span) else 3))
    ax.set_xlabel("X (mm)", labelpad=12)
    ax.set_ylabel("Y (mm)", labelpad=12)
    ax.set_zlabel("Z (mm)", labelpad=8)
    ax.tick_params(labelsize=7)
    ax.set_label("3D")  # named, not titled: a title would float above a flat box


def _project_labels(ax: Axes3D, scene: Scene) -> None:
    """Each point's label at its mark's place in the 3D panel's projection."""
    from mpl_toolkits.mplot3d import proj3d

    marks = _points(scene)
    for text in ax.texts:
        gid = text.get_gid() or ""
        if gid.startswith("point ") and isinstance(text, Annotation):
            x, y, _ = proj3d.proj_transform(*marks[int(gid.split()[1]) - 1].at, ax.get_proj())
            text.xy = (float(x), float(y))


def fit_3d_panel(fig: Figure, ax: Axes3D, scene: Scene | None = None) -> None:
    """Shrink the 3D panel's box until its tick and axis labels lie inside the
    panel's slot: matplotlib's layout leaves them out of a 3D panel's size,
    and they ran into the next panel ('Z (mm)' over the YZ view, 'X (mm)'
    over the XY view's reference arrow). Leaves the figure drawn as it stands."""
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    aspect = ax.get_box_aspect()
    zoom = 1.0
    for _ in range(FIT_3D_TRIES):
        fig.canvas.draw()
        # the slot the layout gave the panel (its drawn box is a square in it)
        slot = ax.get_position(original=True).transformed(fig.transFigure).padded(-LABEL_GAP)
        drawn = _decorations_3d(ax, renderer)
        if _inside(drawn, slot):
            return
        # the box's share that fits, with a margin: the labels do not shrink with it
        share = min(
            (slot.x1 - slot.x0) / max(drawn.x1 - drawn.x0, 1.0),
            (slot.y1 - slot.y0) / max(drawn.y1 - drawn.y0, 1.0),
        )
        zoom *= max(0.5, 0.95 * min(share, 0.97))
        ax.set_box_aspect(aspect, zoom=zoom)
        if scene is not None:
            _project_labels(ax, scene)
    fig.canvas.draw()


def _decorations_3d(ax: Axes3D, renderer: Any) -> Bbox:
    """The box of the 3D panel's axes, ticks and axis labels (not its texts:
    the points' labels are placed inside it afterwards)."""
    boxes = [axis.get_tightbbox(renderer) for axis in (ax.xaxis, ax.yaxis, ax.zaxis)]
    drawn = [box for box in boxes if box is not None]
    return Bbox.union(drawn) if drawn else ax.get_window_extent(renderer)


def draw_scene_view(
    ax: Axes, scene: Scene, h: int, v: int, title: str, reference: bool = False
) -> None:
    """The scene projected on the plane of global axes ``h`` (across) and ``v`` (up);
    ``reference``: with an arrow of a round force, for the arrows' scale."""
    from matplotlib.collections import LineCollection

    for lines, style in _line_groups(scene):
        if lines:
            ax.add_collection(LineCollection([P[:, [h, v]] for P in lines], **style))
    for role in ("touching", "free", "point"):
        marks = [m for m in scene.markers if m.role == role]
        if marks:
            P = np.array([m.at for m in marks])
            ax.scatter(P[:, h], P[:, v], **_marker_style(role))
    for k, mk in enumerate(_points(scene), start=1):
        _point_label(ax, mk.label, (mk.at[h], mk.at[v]), k)
    for start, vector, colour in _arrow_groups(scene):
        seen = np.hypot(vector[:, h], vector[:, v]) > END_ON * np.linalg.norm(vector, axis=1)
        if not np.any(seen):
            continue
        ax.quiver(
            start[seen, h],
            start[seen, v],
            vector[seen, h],
            vector[seen, v],
            color=colour,
            angles="xy",
            scale_units="xy",
            scale=1.0,
            units="inches",
            width=ARROW_WIDTH,
            zorder=6,
        )
    across, up = view_limits(scene, h, v)
    ax.set_xlim(*across)
    ax.set_ylim(*up)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel(f"{'XYZ'[h]} (mm)")
    ax.set_ylabel(f"{'XYZ'[v]} (mm)")
    ax.set_title(title)
    ax.grid(True, linewidth=0.3)
    if reference and scene.force_scale > 0:
        _reference_arrow(ax, scene.force_scale, across[0], across[1] - across[0])


def _points(scene: Scene) -> list[Marker]:
    """The functional points, in the model's order (their numbers from 1)."""
    return [mk for mk in scene.markers if mk.role == "point"]


def _point_label(ax: Axes, label: str, at: tuple[float, float], number: int) -> None:
    """The point's name beside its mark; ``place_point_labels`` settles where."""
    text = ax.annotate(label, at, xytext=LABEL_OFFSETS[0], **_small)
    text.set_gid(f"point {number}")


def place_point_labels(fig: Figure, model: Model | None = None, drawn: bool = False) -> set[int]:
    """Move each point's label to the first place around its mark where it
    lies inside its panel and clear of the labels placed before it; a label
    that fits nowhere gives way to the point's number. Returns the numbers
    written (for the legend, which names them). The contacts' labels of the
    joint panels the same way, clear of the panel's note; one that fits
    nowhere joins the nearest ('end+, end-'). ``drawn``: the figure was just
    drawn as it stands (else it is drawn first: where every panel sits)."""
    if not drawn:
        fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    numbered: set[int] = set()
    for ax in fig.axes:
        _place_contact_labels(ax, renderer)
        if model is None:
            continue
        labels = [
            t
            for t in ax.texts
            if (t.get_gid() or "").startswith("point ") and isinstance(t, Annotation)
        ]
        placed = _marks(ax, labels)  # a label covers no other mark
        tags: list[Annotation] = []  # the labels that are numbers
        for text in labels:
            gid = text.get_gid() or ""
            number = int(gid.split()[1])
            if not text.get_text():  # its number joined another's
                continue
            name = model.points[number - 1].name
            if text.get_text() == name and _place(text, ax, placed, renderer):
                placed.append(text.get_window_extent(renderer))
                continue
            if text.get_text() == name:
                text.set_text(str(number))
            numbered.update(int(k) for k in text.get_text().split(","))
            if not _place(text, ax, placed, renderer) and tags:
                # no room even for the number: it joins the nearest mark's ('3,4')
                near = min(tags, key=lambda t: math.dist(t.xy, text.xy))
                near.set_text(f"{near.get_text()},{text.get_text()}")
                text.set_text("")
                continue
            tags.append(text)
            placed.append(text.get_window_extent(renderer))
    return numbered


def _place_contact_labels(ax: Axes, renderer: Any) -> None:
    """A joint panel's contact labels around their marks, clear of each other
    and of the panel's note; one with no room joins the nearest placed one."""
    labels = [t for t in ax.texts if t.get_gid() == "contact" and isinstance(t, Annotation)]
    notes = [t.get_window_extent(renderer) for t in ax.texts if t.get_gid() == "note"]
    notes += _marks(ax, labels)  # a label covers no other mark
    done: list[Annotation] = []
    for text in labels:
        first = text.xyann
        boxes = notes + [t.get_window_extent(renderer) for t in done]
        if _place(text, ax, boxes, renderer, first=first) or not done:
            done.append(text)
            continue
        near = min(done, key=lambda t: math.dist(t.xy, text.xy))
        near.set_text(f"{near.get_text()}, {text.get_text()}")
        text.set_text("")
        others = notes + [t.get_window_extent(renderer) for t in done if t is not near]
        _place(near, ax, others, renderer, first=near.xyann)


def _marks(ax: Axes, labels: Sequence[Annotation]) -> list[Bbox]:
    """A small box (pixels) about each labelled mark."""
    half = MARK_SIZE / 2
    out = []
    for text in labels:
        x, y = ax.transData.transform(text.xy)
        out.append(Bbox.from_extents(x - half, y - half, x + half, y + half))
    return out


def _place(
    text: Annotation,
    ax: Axes,
    placed: list[Bbox],
    renderer: Any,
    first: tuple[float, float] | None = None,
) -> bool:
    """Try ``text`` at ``first``, then at each of ``LABEL_OFFSETS``; False
    (and left at the first) if it fits at none."""
    frame = ax.get_window_extent(renderer).padded(-LABEL_GAP)
    start = first or LABEL_OFFSETS[0]
    for dx, dy in (start, *LABEL_OFFSETS, start):
        text.xyann = (dx, dy)
        text.set_horizontalalignment("left" if dx > 0 else "right" if dx < 0 else "center")
        text.set_verticalalignment("bottom" if dy > 0 else "top" if dy < 0 else "center")
        box = text.get_window_extent(renderer)
        if _inside(box, frame) and not any(box.padded(LABEL_GAP).overlaps(b) for b in placed):
            return True
    return False


def _inside(box: Bbox, frame: Bbox) -> bool:
    return bool(
        frame.x0 <= box.x0 <= box.x1 <= frame.x1 and frame.y0 <= box.y0 <= box.y1 <= frame.y1
    )


def round_force(largest: float) -> float:
    """The largest of 1, 2, 5 x 10^k (N) not above ``largest``."""
    power = 10.0 ** math.floor(math.log10(largest))
    return next(s * power for s in (5.0, 2.0, 1.0) if s * power <= largest * (1 + 1e-12))


def _reference_arrow(ax: Axes, mm_per_n: float, left: float, width: float) -> None:
    """A black arrow of a round force, about a fifth of the panel wide, just
    above the panel's upper left corner (outside the drawing, where it can
    cover nothing), labelled with its size."""
    force = round_force(0.2 * width / mm_per_n)
    x0, y0 = left, 1.06  # x in mm, y in the panel's height: clear of its frame
    where = ax.get_xaxis_transform()
    ax.annotate(
        "",
        xy=(x0 + force * mm_per_n, y0),
        xytext=(x0, y0),
        xycoords=where,
        textcoords=where,
        annotation_clip=False,
        arrowprops={"arrowstyle": "-|>", "color": "black", "linewidth": 1.2},
    )
    ax.annotate(
        f"{force:g} N",
        (x0 + force * mm_per_n, y0),
        xycoords=where,
        xytext=(4, 0),
        va="center",
        annotation_clip=False,
        **_small,
    )


_small: dict[str, Any] = {"textcoords": "offset points", "fontsize": 8}


def view_limits(scene: Scene, h: int, v: int) -> tuple[tuple[float, float], tuple[float, float]]:
    """The limits (across, up) of the view on global axes ``h`` and ``v``: the
    scene's padded bounds, the shorter side widened to ``STRIP`` of the longer."""
    lo, hi = _padded_bounds(scene)
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    a = max(float(half[h]), STRIP * float(half[v]))
    b = max(float(half[v]), STRIP * float(half[h]))
    return (mid[h] - a, mid[h] + a), (mid[v] - b, mid[v] + b)


def _padded_bounds(scene: Scene) -> tuple[FloatArray, FloatArray]:
    lo, hi = scene.bounds()
    least = 0.06 * scene.size  # a flat mechanism still gets some depth
    mid = (lo + hi) / 2
    half = np.maximum((hi - lo) / 2, least) * 1.08
    return mid - half, mid + half


def _marker_style(role: str) -> dict[str, Any]:
    if role == "touching":
        return {"color": TOUCHING, "s": 22, "zorder": 5}
    if role == "free":
        return {"facecolors": "white", "edgecolors": FREE, "s": 18, "zorder": 5}
    if role == "point":
        return {"color": POINT, "marker": "x", "s": 30, "zorder": 6}
    return {}


def _legend_handles(scene: Scene) -> list[Line2D]:
    out = [Line2D([], [], color=INITIAL, linestyle="--", label="initial position")]
    for body, colour in list(_body_colours(scene).items())[:LEGEND_BODIES]:
        out.append(Line2D([], [], color=colour, lw=2.4, label=body))
    out += [
        Line2D([], [], color=DOMAIN, lw=0.9, label="clearance domain"),
        Line2D([], [], color=TOUCHING, marker="o", ls="", label="touching contact"),
        Line2D([], [], color=FREE, marker="o", mfc="white", ls="", label="free contact"),
        Line2D([], [], color=TOUCHING, marker=ARROW, ls="", ms=12, label="contact force"),
        Line2D([], [], color=LOAD, marker=ARROW, ls="", ms=12, label="load"),
    ]
    return out


def _common_reach(views: Sequence[JointView]) -> float:
    """The size of a view with nothing of size in it: the largest of the others."""
    return max((v.reach for v in views), default=0.0) or 1.0


def draw_joint_view(ax: Axes, view: JointView, fallback_reach: float = 1.0) -> None:
    """One joint at true size: seen along its axis (y, z of the joint frame),
    or across it for a face or a plane (x the normal)."""
    ax.set_title(f"{view.joint} ({view.type})", fontsize=10)
    if view.plane == "none":
        ax.text(0.5, 0.5, view.note, ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        return
    reach = (view.reach or fallback_reach) * 1.35
    if view.plane == "yz":
        for radius, sphere in view.circles:
            ax.add_patch(
                Circle(
                    (0, 0),
                    radius,
                    fill=False,
                    color=DOMAIN,
                    linestyle="--" if sphere else "-",
                    label="sphere section" if sphere else None,
                )
            )
        if view.rectangle is not None:
            hy, hz = view.rectangle
            if math.isinf(hy):  # free along y: the slot's two walls
                for level in (-hz, hz):
                    ax.axhline(level, color=DOMAIN, linewidth=1.0)
            elif math.isinf(hz):
                for level in (-hy, hy):
                    ax.axvline(level, color=DOMAIN, linewidth=1.0)
            else:
                ax.add_patch(Rectangle((-hy, -hz), 2 * hy, 2 * hz, fill=False, color=DOMAIN))
        if len(view.points) > 1 and not view.rectangle:  # the axis seen end on
            P = np.array([p.at for p in view.points])
            ax.plot(P[:, 0], P[:, 1], color=INITIAL, linewidth=0.8)
        ax.set_xlim(-reach, reach)
        ax.set_ylim(-reach, reach)
        ax.set_aspect("equal")
        ax.xaxis.set_major_locator(RoomyLocator(symmetric=True))  # a narrow panel
        ax.yaxis.set_major_locator(MaxNLocator(4, symmetric=True))
        ax.set_xlabel(f"y (mm): {view.axes[1]}", fontsize=8)
        ax.set_ylabel(f"z (mm): {view.axes[2]}", fontsize=8)
    else:
        for wall in view.walls:  # the side beyond a wall is solid
            ax.axvline(wall, color=DOMAIN, linewidth=1.2)
            outward = 1.0 if wall > 0 else -1.0
            ax.axvspan(wall, outward * 2 * reach, color="#dbe7f5", zorder=0)
        if view.outline:
            P = np.array(view.outline)
            ax.plot(P[:, 0], P[:, 1], color=BODY_COLOURS[0], linewidth=2)
        across = [abs(y) for _, y in view.outline] + [abs(p.at[1]) for p in view.points]
        if max(across, default=0.0) > 0.0:  # room for the end points and their labels
            ax.set_ylim(-1.2 * max(across), 1.2 * max(across))
        ax.set_xlim(-reach, reach)
        ax.xaxis.set_major_locator(RoomyLocator(symmetric=True))  # a narrow panel
        ax.set_xlabel(f"x, the normal (mm): {view.axes[0]}", fontsize=8)
        ax.set_ylabel("across the face (mm)", fontsize=8)
    ax.axhline(0, color=INITIAL, linewidth=0.4)
    ax.axvline(0, color=INITIAL, linewidth=0.4)
    for p in view.points:
        style = _marker_style("touching" if p.touching else "free")
        ax.scatter(*p.at, **style)
        # written toward the middle, so that it stays inside the panel;
        # place_point_labels moves it where it clears the others
        inward = p.at[0] > 0 if view.plane == "yz" else p.at[0] > 0.5 * reach
        side: dict[str, Any] = (
            {"xytext": (-5, 4), "ha": "right"} if inward else {"xytext": (5, 4), "ha": "left"}
        )
        ax.annotate(p.label, p.at, **side, **_small).set_gid("contact")
    ax.tick_params(labelsize=7)
    if view.note:
        note = "\n".join(textwrap.wrap(view.note, NOTE_WIDTH))
        ax.text(0.02, 0.02, note, transform=ax.transAxes, fontsize=7, va="bottom").set_gid("note")


# -- the studies ---------------------------------------------------------------------
def sweep_figure(result: SweepResult, envelopes: dict[str, EnvelopeResult] | None = None) -> Figure:
    """Each functional point's trajectory over the sweep in the three views,
    inside the projection of its worst-case envelope when given (a view along
    a plane that the trajectory and the envelope lie in is left out, said in
    its place); then the contact forces along the sweep (the
    ``LEGEND_CONTACTS`` that carry the most), the points' |d| and the
    potential energy. The legends stand under their panels, off the curves."""
    envelopes = envelopes or {}
    rows = len(result.point_names) + 1
    fig, axes = plt.subplots(rows, 3, figsize=(13, 4.2 * rows), squeeze=False, layout="constrained")
    steps = np.arange(result.steps)
    # one varied value along the x axis; a grid of several goes back and forth in
    # each of them, so it is drawn against the step
    one = len(result.labels) == 1
    x, xlabel = (result.values[:, -1], result.labels[-1]) if one else (steps, "step")
    enveloped = False
    for r, name in enumerate(result.point_names):
        d = result.point(name)
        env = envelopes.get(name)
        cloud = d if env is None else np.vstack([d, env.hull])
        extent = np.column_stack([cloud.min(axis=0), cloud.max(axis=0)])
        shown = thick_views(cloud)
        for ax, (title, h, v) in zip(axes[r], shown, strict=False):
            if env is not None:
                _hull_patch(ax, env.hull[:, [h, v]], "worst-case envelope")
                enveloped = True
            ax.plot(d[:, h], d[:, v], color=BODY_COLOURS[0], linewidth=1.0)
            dots = ax.scatter(d[:, h], d[:, v], c=x, cmap="viridis", s=14, zorder=4)
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(f"{name}: {title}", fontsize=10)
            ax.set_xlabel(f"d{'xyz'[h]} (mm)")
            ax.set_ylabel(f"d{'xyz'[v]} (mm)")
            ax.grid(True, linewidth=0.3)
        if len(shown) < len(VIEWS):
            out = [view[0].split()[0] for view in VIEWS if view not in shown]
            what = "its path and its envelope lie" if env is not None else "its path lies"
            note = (
                f"{name}: the {' and '.join(out)} view{'s' if len(out) > 1 else ''} left out: "
                f"{what} on a line there"
            )
            flat = sorted({_flat_note(extent, h, v) for _, h, v in shown} - {""})
            if flat:
                where = "at every step" + (" and over the envelope" if env is not None else "")
                note += f" ({', '.join(flat)} {where})"
            for ax in axes[r][len(shown) :]:
                ax.set_axis_off()
            axes[r][len(shown)].text(
                0.0,
                0.5,
                "\n".join(textwrap.wrap(note, 40)),
                transform=axes[r][len(shown)].transAxes,
                fontsize=9,
                va="center",
            )
        fig.colorbar(dots, ax=list(axes[r]), label=xlabel, shrink=0.85)
    ax = axes[-1][0]
    carried = [c for c in range(len(result.contact_names)) if np.any(result.force[:, c] > 0)]
    most = sorted(carried, key=lambda c: -float(np.max(result.force[:, c])))[:LEGEND_CONTACTS]
    for c in sorted(most):
        joint, contact = result.contact_names[c]
        ax.plot(x, result.force[:, c], label=f"{joint} {contact}")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("contact force (N)")
    some = f" (the {len(most)} largest of {len(carried)})" if len(most) < len(carried) else ""
    found = over_steps(result.indeterminate, result.joint_names)
    if found.joints:  # their split is a convention (the sweep's text says so in full)
        names = ", ".join(found.joints[:3]) + (" ..." if len(found.joints) > 3 else "")
        how = "split by rule" if found.by_rule else "split as the solver left it"
        some += f"\n{how}: {names}"
    ax.set_title(f"contact forces{some}", fontsize=10)
    ax.grid(True, linewidth=0.3)
    if most:
        _legend_below(ax, ncols=2)
    ax = axes[-1][1]
    for p, name in enumerate(result.point_names):
        ax.plot(x, np.linalg.norm(result.points[:, p], axis=1), label=name)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("|d| (mm)")
    ax.set_title("points' displacement", fontsize=10)
    ax.grid(True, linewidth=0.3)
    if result.point_names:
        _legend_below(ax, ncols=2)
    ax = axes[-1][2]
    ax.plot(x, result.potential_energy, color=POINT)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("potential energy (N·mm)")
    ax.set_title("potential energy", fontsize=10)
    ax.grid(True, linewidth=0.3)
    if enveloped:
        handles = [
            Rectangle(
                (0, 0),
                1,
                1,
                facecolor="#dbe7f5",
                edgecolor=DOMAIN,
                label="worst-case envelope of the model as written (its plays and loads)",
            ),
            Line2D(
                [], [], color=BODY_COLOURS[0], marker="o", ms=4, label="the point over the sweep"
            ),
        ]
        fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=9)
    _suptitle(fig, f"{result.model_name or 'mechanism'}: sweep of {', '.join(result.labels)}")
    roomy_ticks(fig)
    return fig


def _legend_below(ax: Axes, ncols: int = 1, fontsize: float = 8) -> None:
    """The panel's legend under its frame and x label: it covers no curve."""
    ax.legend(
        loc="upper center",
        bbox_to_anchor=(0.5, -0.16),
        ncols=ncols,
        fontsize=fontsize,
        frameon=False,
    )


def _hull_patch(ax: Axes, points: FloatArray, label: str) -> None:
    """The convex hull of 2D ``points`` as a shaded patch (the projection of a
    convex set is the hull of its points' projections)."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):  # a flat or empty envelope: its points alone
        ax.plot(points[:, 0], points[:, 1], color=DOMAIN, linewidth=0.8, label=label)
        return
    ax.add_patch(
        Polygon(
            points[hull.vertices], closed=True, facecolor="#dbe7f5", edgecolor=DOMAIN, label=label
        )
    )
    ax.update_datalim(points)
    ax.autoscale_view()


def _widths(P: FloatArray) -> FloatArray:
    """The extents of 2D points ``P`` (n, 2) along their principal directions,
    the larger first (mm)."""
    if len(P) < 2:
        return np.zeros(2)
    centred = P - P.mean(axis=0)
    _, _, axes = np.linalg.svd(centred, full_matrices=False)
    spans = np.ptp(centred @ axes.T, axis=0)
    return np.asarray(np.pad(spans, (0, 2 - len(spans))))


def thick_views(points: FloatArray) -> list[tuple[str, int, int]]:
    """The views of a cloud of displacements ``points`` (n, 3) (mm) that show
    an area: a view in which the cloud is a line (thinner than ``FLAT`` of its
    length, along any direction: a plane seen edge on) is left out; at least
    the view of the longest line stays."""
    widths = {view: _widths(points[:, [view[1], view[2]]]) for view in VIEWS}
    shown = [view for view in VIEWS if widths[view][1] >= FLAT * max(widths[view][0], 1e-300)]
    return shown or [max(VIEWS, key=lambda view: float(widths[view][0]))]


def _flat_note(extent: FloatArray, h: int, v: int) -> str:
    """The displacement along the axis a view looks along, when the cloud is
    flat that way: 'dz -0.015 mm' (or its small range); '' when not flat."""
    depth = ({0, 1, 2} - {h, v}).pop()
    low, high = (float(x) for x in extent[depth])
    span = extent[:, 1] - extent[:, 0]
    if high - low >= FLAT * max(float(np.max(span)), 1e-300):
        return ""
    name = f"d{'xyz'[depth]}"
    if f"{low:.4g}" == f"{high:.4g}":
        return f"{name} {low:.4g} mm"
    return f"{name} from {low:.4g} to {high:.4g} mm"


def _flat_polygon(H: FloatArray) -> FloatArray | None:
    """The outline (m, 3) of points ``H`` that lie in a plane (or on a line),
    in order; None when they span a volume."""
    from scipy.spatial import ConvexHull, QhullError

    centre = H.mean(axis=0)
    _, sizes, axes = np.linalg.svd(H - centre, full_matrices=False)
    if len(sizes) < 3 or sizes[2] >= FLAT * max(float(sizes[0]), 1e-300):
        return None
    flat = (H - centre) @ axes[:2].T
    try:
        ring = flat[ConvexHull(flat).vertices]
    except (QhullError, ValueError):  # on a line: its two ends
        along = flat[:, 0]
        ring = flat[[int(np.argmin(along)), int(np.argmax(along))]]
    return np.asarray(centre + ring @ axes[:2])


def envelope_figure(result: EnvelopeResult) -> Figure:
    """The worst-case envelope of a point: its hull in 3D, its projections
    with the extent along each axis, and the largest displacement. A flat
    envelope (a point that moves in a plane) is drawn as its outline in 3D;
    a view that sees it edge on (a line) is left out, and a view across a
    plane normal to an axis is titled with the displacement along it."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    from scipy.spatial import ConvexHull, QhullError

    H = result.hull
    ext = result.extent
    shown = thick_views(H)
    if len(shown) == 3:
        fig = plt.figure(figsize=(13, 10), layout="constrained")
        grid = fig.add_gridspec(2, 2)
        slots = [grid[0, 1], grid[1, 0], grid[1, 1]]
    else:  # flat: the 3D panel and the views that are not edge on, side by side
        fig = plt.figure(figsize=(13, 5.6 if len(shown) == 1 else 4.8), layout="constrained")
        grid = fig.add_gridspec(1, 1 + len(shown))
        slots = [grid[0, 1 + k] for k in range(len(shown))]
    ax3d: Axes3D = fig.add_subplot(grid[0, 0], projection="3d")
    ring = _flat_polygon(H) if len(H) >= 3 else None
    style = {"facecolor": "#9fc0e8", "edgecolor": DOMAIN, "alpha": 0.5}
    if ring is not None and len(ring) >= 3:
        ax3d.add_collection3d(Poly3DCollection([ring], linewidth=0.8, **style))
    elif ring is not None:
        ax3d.plot(ring[:, 0], ring[:, 1], ring[:, 2], color=DOMAIN, linewidth=1.2)
    else:
        try:
            hull = ConvexHull(H)
            faces = [H[s] for s in hull.simplices]
            ax3d.add_collection3d(Poly3DCollection(faces, linewidth=0.2, **style))
        except (QhullError, ValueError):  # too few points for a hull: the points alone
            pass
    ax3d.scatter(H[:, 0], H[:, 1], H[:, 2], color=DOMAIN, s=4)
    L = result.largest_vector
    ax3d.quiver(0, 0, 0, *L, color=TOUCHING, arrow_length_ratio=0.1)
    reach = max(float(np.max(np.abs(H))), 1e-12) * 1.1
    for setter in (ax3d.set_xlim, ax3d.set_ylim, ax3d.set_zlim):
        setter(-reach, reach)
    ax3d.set_box_aspect((1, 1, 1))
    for axis in (ax3d.xaxis, ax3d.yaxis, ax3d.zaxis):  # long labels such as -0.025
        axis.set_major_locator(MaxNLocator(4))
    ax3d.tick_params(labelsize=8)
    ax3d.set_xlabel("dx (mm)", labelpad=10)
    ax3d.set_ylabel("dy (mm)", labelpad=10)
    ax3d.set_zlabel("dz (mm)", labelpad=10)
    ax3d.set_title("envelope (3D)")
    for slot, (title, h, v) in zip(slots, shown, strict=True):
        ax = fig.add_subplot(slot)
        # the arrow from the rest position, which may lie outside the envelope:
        # both its ends in the view, and the arrow clipped to it like the rest
        ax.update_datalim([(0.0, 0.0), (L[h], L[v])])
        _hull_patch(ax, H[:, [h, v]], "envelope")
        ax.add_patch(
            FancyArrowPatch(
                (0.0, 0.0), (L[h], L[v]), arrowstyle="-|>", mutation_scale=12, color=TOUCHING
            )
        )
        ax.axvline(ext[h, 0], color=INITIAL, linestyle=":", linewidth=0.8)
        ax.axvline(ext[h, 1], color=INITIAL, linestyle=":", linewidth=0.8)
        ax.axhline(ext[v, 0], color=INITIAL, linestyle=":", linewidth=0.8)
        ax.axhline(ext[v, 1], color=INITIAL, linestyle=":", linewidth=0.8)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"d{'xyz'[h]} (mm)")
        ax.set_ylabel(f"d{'xyz'[v]} (mm)")
        note = _flat_note(ext, h, v)
        ax.set_title(f"{title}\n{note} throughout" if note else title)
        ax.grid(True, linewidth=0.3)
    _suptitle(
        fig,
        f"worst-case envelope of point '{result.settings.point}' (plays at their "
        f"{result.settings.plays}): largest {result.largest:.5g} mm along "
        f"[{', '.join(f'{c:.3g}' for c in L / max(result.largest, 1e-300))}]",
    )
    roomy_ticks(fig)
    fit_3d_panel(fig, ax3d)
    return fig


def montecarlo_figure(result: MonteCarloResult) -> Figure:
    """Histograms of each point's |displacement| over the samples, and of each
    requirement's measure with its limit and the fraction of parts beyond."""
    panels: list[tuple[str, FloatArray, float | None, str]] = []
    limited = {s.requirement.point for s in result.requirements if s.requirement.along is None}
    for p, name in enumerate(result.point_names):
        if name in limited:  # its requirement's panel shows the same |d|
            continue
        size = np.linalg.norm(result.displacement[:, p], axis=1)
        panels.append((f"point '{name}': |d|", size, None, "|d| (mm)"))
    for stats in result.requirements:
        req = stats.requirement
        d = result.displacement[:, result.point_names.index(req.point)]
        if req.along is None:
            measure, unit = np.linalg.norm(d, axis=1), "|d| (mm)"
        else:
            u = np.asarray(req.along, dtype=float) / np.linalg.norm(req.along)
            measure, unit = d @ u, f"d along {list(req.along)} (mm)"
        title = (
            f"{req.describe()}\n{stats.outside} of {result.samples} parts outside "
            f"({100 * stats.fraction:.3g} %)"
            + (f", {result.unassembled} not assembled" if result.unassembled else "")
        )
        panels.append((title, measure, req.max_displacement, unit))
    cols = min(len(panels), 3) or 1
    rows = max(math.ceil(len(panels) / cols), 1)
    fig, axes = plt.subplots(
        rows, cols, figsize=(4.6 * cols, 3.8 * rows), squeeze=False, layout="constrained"
    )
    for ax, (title, every, limit, unit) in zip(axes.flat, panels, strict=False):
        values = every[~np.isnan(every)]  # the parts that can be assembled
        ax.hist(values, bins=_bins(values), **HISTOGRAM)
        if limit is not None:
            ax.axvline(limit, color=TOUCHING, linewidth=1.5, label=f"limit {limit:g} mm")
            if np.min(values) < 0:
                ax.axvline(-limit, color=TOUCHING, linewidth=1.5)
            _legend_below(ax)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel(unit)
        ax.set_ylabel("parts")
        ax.grid(True, linewidth=0.3)
    for ax in axes.flat[len(panels) :]:
        ax.set_axis_off()
    if not panels:
        axes.flat[0].text(0.5, 0.5, "no functional points", ha="center", va="center")
    _suptitle(
        fig,
        f"{result.model_name or 'mechanism'}: Monte Carlo, {result.samples} sets of parts "
        f"(seed {result.settings.seed})",
    )
    roomy_ticks(fig)
    return fig


def _bins(values: FloatArray) -> int:
    return int(min(80, max(10, math.sqrt(len(values)))))


def contributions_figure(result: ContributionsResult) -> Figure:
    """Per measure, a Pareto of the variables (plays, loads, deviation
    zones): each one's share of the worst-case and of the statistical (RSS)
    stack, the largest worst-case share first, with the cumulative worst-case
    share as a line; a hatched bar is a kink (the contacts change at the
    nominal: the slope is one of two). Where the measure is not linear over
    the ranges and the Sobol' indices were taken, its panel shows both: the
    linear shares (faded: they do not hold there) and the shares of the
    variance, first order and total with their intervals, the largest total
    first."""
    M = len(result.measures)
    sobol = result.sobol
    both = [sobol is not None and not result.linear(k) for k in range(M)]
    fig, axes = plt.subplots(
        M,
        1,
        figsize=(9, 1.6 + (0.45 + 0.3 * any(both)) * len(result.plays) * M + 0.8 * M),
        squeeze=False,
        layout="constrained",
    )
    y = np.arange(len(result.plays))
    wc, rss = result.worst_case, result.rss
    for k, (ax, measure) in enumerate(zip(axes[:, 0], result.measures, strict=True)):
        if both[k]:
            assert sobol is not None
            order = np.argsort(-sobol.total[k], kind="stable")
            for row, i in enumerate(order):
                hatch = "//" if result.kink[k, i] else None
                ax.barh(y[row] - 0.3, wc[k, i], height=0.18, color="#2f6db5", alpha=0.35)
                ax.barh(y[row] - 0.1, rss[k, i], height=0.18, color="#f28e2b", alpha=0.35)
                for dy, value, interval, colour in (
                    (0.1, sobol.first[k, i], sobol.first_interval[k, i], "#59a14f"),
                    (0.3, sobol.total[k, i], sobol.total_interval[k, i], "#b07aa1"),
                ):
                    low, high = 100 * interval[0], 100 * interval[1]
                    ax.barh(y[row] + dy, 100 * value, height=0.18, color=colour, hatch=hatch)
                    ax.plot([low, high], [y[row] + dy] * 2, color="black", lw=0.8)
            title = (
                f"{measure}: not linear over the ranges; shares of the variance "
                f"(Sobol', {sobol.settings.samples:,} base sets of parts)"
            )
        else:
            order = np.argsort(-wc[k], kind="stable")
            for row, i in enumerate(order):
                hatch = "//" if result.kink[k, i] else None
                ax.barh(y[row] - 0.2, wc[k, i], height=0.38, color="#2f6db5", hatch=hatch)
                ax.barh(y[row] + 0.2, rss[k, i], height=0.38, color="#f28e2b", hatch=hatch)
            ax.plot(np.cumsum(wc[k, order]), y, color="black", marker="o", markersize=3, lw=0.8)
            title = (
                f"{measure}: worst-case spread {result.worst_case_range[k]:.4g} mm, "
                f"RSS σ {result.rss_sigma[k]:.4g} mm"
            )
        ax.set_yticks(y, labels=_plain_labels([result.plays[i] for i in order]))
        ax.invert_yaxis()
        ax.set_xlim(0, 105)
        ax.set_xlabel("contribution (%)")
        ax.set_title(title, fontsize=10)
        ax.grid(True, axis="x", linewidth=0.3)
    handles: list[Artist] = [
        Rectangle((0, 0), 1, 1, color="#2f6db5", label="worst case"),
        Rectangle((0, 0), 1, 1, color="#f28e2b", label="RSS"),
        Rectangle((0, 0), 1, 1, facecolor="white", edgecolor="black", hatch="//", label="kink"),
    ]
    if not all(both):  # a linear panel draws the cumulative share
        handles.append(
            Line2D(
                [0],
                [0],
                color="black",
                marker="o",
                markersize=3,
                lw=0.8,
                label="cumulative worst case",
            )
        )
    if any(both):
        handles += [
            Rectangle((0, 0), 1, 1, color="#59a14f", label="Sobol' first order"),
            Rectangle((0, 0), 1, 1, color="#b07aa1", label="Sobol' total"),
        ]
    fig.legend(handles=handles, loc="outside lower center", ncols=4, fontsize=8)
    _suptitle(fig, f"{result.model_name or 'mechanism'}: contributions")
    roomy_ticks(fig)
    return fig


def _plain_labels(labels: Sequence[str]) -> list[str]:
    return [label if len(label) <= 40 else label[:37] + "..." for label in labels]


def tolerances_figure(result: TolerancesResult) -> Figure:
    """Per requirement, the Monte Carlo parts' measure as a histogram, with
    its limit, the worst case (the bound no part passes), and, where the
    measure is linear over the ranges, the linear estimate and RSS's normal law."""
    mc = result.montecarlo
    panels = result.requirements
    cols = min(len(panels), 2) or 1
    rows = max(math.ceil(len(panels) / cols), 1)
    fig, axes = plt.subplots(
        rows, cols, figsize=(5.6 * cols, 4.4 * rows), squeeze=False, layout="constrained"
    )
    for ax, r in zip(axes.flat, panels, strict=False):
        req = r.requirement
        d = mc.displacement[:, mc.point_names.index(req.point)]
        if r.two_sided and req.along is not None:
            u = np.asarray(req.along, dtype=float) / np.linalg.norm(req.along)
            every, unit = d @ u, f"d along {list(req.along)} (mm)"
        else:
            every, unit = np.linalg.norm(d, axis=1), "|d| (mm)"
        values = every[~np.isnan(every)]  # the parts that can be assembled
        ax.hist(
            values,
            bins=_bins(values),
            density=True,
            **HISTOGRAM,
            label=f"Monte Carlo, {len(values):,} parts",
        )
        high = req.max_displacement
        # along a direction, the signed range the worst case reaches (one sign, maybe)
        reached, words = [r.worst], f"worst case {r.worst:.4g} mm"
        if r.two_sided and r.worst_low is not None and r.worst_high is not None:
            reached = [r.worst_low, r.worst_high]
            words = f"worst case {r.worst_low + 0.0:.4g} to {r.worst_high + 0.0:.4g} mm"
        ends = [high, *reached, *((values.min(), values.max()) if len(values) else ())]
        for sign in (1, -1) if r.two_sided else (1,):
            ax.axvline(
                sign * high,
                color=TOUCHING,
                linewidth=1.5,
                label=f"limit {high:g} mm" if sign == 1 else None,
            )
        for n, end in enumerate(reached):
            ax.axvline(
                end,
                color="black",
                linestyle="--",
                linewidth=1.2,
                label=words if n == 0 else None,
            )
        if r.linear_agrees:
            ax.axvspan(r.linear_low, r.linear_high, color=LOAD, alpha=0.12, label="linear estimate")
        if r.linear and r.rss_sigma > 0:
            x = np.linspace(min(ends) if r.two_sided else 0.0, max(ends), 200)
            z = (x - r.nominal) / r.rss_sigma
            ax.plot(
                x,
                np.exp(-0.5 * z * z) / (r.rss_sigma * math.sqrt(2 * math.pi)),
                color=DOMAIN,
                linewidth=1.2,
                label="RSS, normal law",
            )
        verdict = (
            f"Cpk {r.cpk:.3g}, Ppk {r.ppk:.3g}"
            if r.linear
            else f"RSS does not apply; Ppk {r.ppk:.3g}"
        )
        ax.set_title(f"{req.describe()}\n{verdict}", fontsize=9)
        ax.set_xlabel(unit)
        ax.set_ylabel("density of parts (1/mm)")
        ax.grid(True, linewidth=0.3)
        _legend_below(ax, ncols=2, fontsize=7)
    for ax in axes.flat[len(panels) :]:
        ax.set_axis_off()
    _suptitle(
        fig,
        f"{result.model_name or 'mechanism'}: tolerances, {mc.samples:,} sets of parts "
        f"(seed {result.settings.seed})",
    )
    roomy_ticks(fig)
    return fig
