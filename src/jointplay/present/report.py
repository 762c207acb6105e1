"""One HTML file with a whole analysis, for a colleague's browser.

``Report(...).render(model, source)`` solves the model (each load case),
runs the studies asked for, and returns a self-contained page: the model's
summary, the results and contact-force tables, the figures (matplotlib, as
SVG), an interactive 3D view of the exaggerated mechanism (Plotly, its
library inlined: nothing is fetched when the page opens), and the studies.

The page marks itself for tests and for anyone checking it: ``<body
data-rendered="true">`` once every interactive view is drawn, and
``data-errors`` with the messages of any script error.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
import json
import shlex
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from jointplay.errors import UnboundedMechanismError
from jointplay.geometry import FloatArray
from jointplay.model.tables import DriveTable
from jointplay.model.tolerance import Toleranced, play_unit
from jointplay.present.scene import Scene, mechanism_scene
from jointplay.version import __version__

if TYPE_CHECKING:
    import plotly.graph_objects as go
    from matplotlib.figure import Figure

    from jointplay.model.mechanism import Model
    from jointplay.result import Result
    from jointplay.solver.solve import Workspace
    from jointplay.studies.contributions import ContributionsResult
    from jointplay.studies.envelope import EnvelopeResult
    from jointplay.studies.montecarlo import MonteCarloResult
    from jointplay.studies.motion import MotionResult
    from jointplay.studies.sweep import Sweep, SweepResult
    from jointplay.studies.tolerances import RequirementTolerances


#: Above this many moving bodies the 3D view draws them as one trace.
MANY_BODIES = 12
#: Up to this many lines the mechanism figure is SVG (sharp at any zoom); above, PNG.
VECTOR_LINES = 600


@dataclass(frozen=True)
class Report:
    """Settings of a report; ``render`` returns the page (HTML text).

    ``case``: only this load case (default: every case, or the loads of a
    model without cases). ``magnify``: the pictures' factor (None: a round
    one). ``studies``: run the studies that the model calls for: each
    functional point's worst-case envelope, and, when plays or loads vary
    from part to part, a Monte Carlo study of ``samples`` sets of parts
    (``seed``) and the contributions. ``sweep``: a sweep to run and show.
    """

    case: str | None = None
    magnify: float | None = None
    studies: bool = True
    samples: int = 10_000
    seed: int = 0
    sweep: Sweep | None = None
    exact: bool = False

    def __post_init__(self) -> None:
        if self.magnify is not None and not 0.0 < self.magnify < float("inf"):
            raise ValueError("magnify: a factor above 0 (1 draws true size)")
        if self.samples < 1:
            raise ValueError("samples: at least 1")

    def render(
        self,
        model: Model,
        source: str,
        *,
        note: Callable[[str], None] | None = None,
    ) -> str:
        """Solve, study and write the page. ``source``: the model file's name.
        ``note(text)`` hears what is being done (for a progress line)."""
        from jointplay.model.mechanism import check_case
        from jointplay.solver.solve import Workspace

        say = note or (lambda _text: None)
        check_case(model, self.case, source)
        ws = Workspace.of(model)
        cases: list[str | None] = (
            [self.case] if self.case is not None else list(model.case_names) or [None]
        )
        say("solving")
        results = {case: _solved(ws, model, case, self.exact) for case in cases}
        page = _Page(model.name or source)
        page.header(model, source)
        page.summary(model, results)
        page.model_tables(model)
        for case, result in results.items():
            say(f"drawing {'the solution' if case is None else repr(case)}")
            page.solution(model, result, case, self.magnify)
        if model.motion is not None:
            from jointplay.studies.motion import Motion

            say(f"the motion, {model.motion.steps} poses")
            # a motion is under one load case: the one asked for, else the first
            motion = Motion(case=cases[0]).run(model, source)
            page.motion(model, motion, others=len(cases) > 1)
        if self.studies or self.sweep is not None:
            page.section("Studies")
            if model.motion is not None and self.studies:
                page.paragraph(_studies_at_the_written_pose(model, source, cases[0]))
            if len(cases) > 1:
                under = [
                    *(["the Monte Carlo study and the contributions"] if self.studies else []),
                    *(["the sweep"] if self.sweep is not None else []),
                ]
                page.paragraph(
                    ("The envelopes take every load case; " if self.studies else "")
                    + f"{' and '.join(under)} {'are' if self.studies else 'is'} under load case "
                    f"'{cases[0]}' (the first; jointplay report MODEL --case NAME for another)."
                )
        if self.studies:
            self._studies(model, source, page, say, cases[0])
        if self.sweep is not None:
            say("sweeping")
            sweep = replace(self.sweep, case=cases[0]).run(model, source=source)
            page.sweep(model, sweep, source)
        return page.html()

    def _studies(
        self,
        model: Model,
        source: str,
        page: _Page,
        say: Callable[[str], None],
        case: str | None,
    ) -> None:
        """The studies under load case ``case`` (each is under one)."""
        from jointplay.studies.contributions import Contributions
        from jointplay.studies.envelope import point_envelopes
        from jointplay.studies.montecarlo import MonteCarlo
        from jointplay.studies.tolerances import side_by_side

        if not model.points:
            page.paragraph(
                "The model has no functional points, so there is nothing to study: add "
                "'points' (and 'requirements') to see envelopes, Monte Carlo and contributions."
            )
            return
        say("envelopes")
        envelopes, missing = point_envelopes(model, source=source, case=self.case)
        for point in model.points:
            if point.name in envelopes:
                page.envelope(envelopes[point.name])
            else:
                page.paragraph(
                    f"Point '{point.name}': no worst-case envelope: {missing[point.name]}"
                )
        if not _varies(model, case, source):
            page.paragraph(
                "No play, load or deviation varies from part to part, so there is no Monte "
                "Carlo study and no contributions: give clearances as limits or ISO fits, or "
                "joints deviation zones, to see them."
            )
            return
        say(f"Monte Carlo, {self.samples} sets of parts")
        mc = MonteCarlo(samples=self.samples, seed=self.seed, case=case).run(model, source=source)
        page.montecarlo(mc)
        say("contributions")
        # the shares of the variance where a measure is not linear: a Sobol' design
        # of at most as many sets of parts as the Monte Carlo study's, N (D + 2)
        # with N a power of 2 from 8 to 1024
        per_base = self.samples // (_inputs(model, case, source) + 2)
        base = 1 << max(3, min(10, per_base.bit_length() - 1))
        linear = Contributions(case=case, samples=base, seed=self.seed).run(model, source=source)
        page.contributions(linear)
        if model.requirements:
            rows = side_by_side(model, linear, mc, source=source)
            page.tolerances(rows, mc.settings.confidence, mc.samples)


def _studies_at_the_written_pose(model: Model, source: str, case: str | None) -> str:
    """The studies' sentence for a model with a motion: they take one pose."""
    from jointplay.studies.motion import shown_drive

    joint, coordinate, _, _ = model.motion_drive()
    unit = "deg" if coordinate == "spin" else "mm"
    under = "" if case is None else f" --case {shlex.quote(case)}"
    return (
        f"The studies below are at the pose written in the file ('{joint.name}' at "
        f"{shown_drive(coordinate, 0.0):g} {unit}, load tables read there); at every pose: "
        f"jointplay motion {shlex.quote(source)}{under} --envelope --samples N --contributions."
    )


def _solved(ws: Workspace, model: Model, case: str | None, exact: bool) -> Result:
    """The solution under load case ``case`` (None: the model's loads); a
    mechanism not held under it says which case."""
    try:
        return ws.solve(loads=None if case is None else model.loads_of(case), exact=exact)
    except UnboundedMechanismError as exc:
        raise exc if case is None else exc.in_case(case) from None


def _inputs(model: Model, case: str | None, source: str) -> int:
    """How many inputs vary (plays, load components, whole deviation zones)."""
    from jointplay.studies.parts import inputs_of

    return len(inputs_of(model, case, source).groups)


def _varies(model: Model, case: str | None, source: str) -> bool:
    from jointplay.assembly import assemble
    from jointplay.studies.variation import deviation_map, load_map, play_map

    asm = assemble(model)
    return bool(
        play_map(asm, source).variables
        or load_map(asm, case).variables
        or deviation_map(asm).variables
    )


# -- the interactive view --------------------------------------------------------
def scene_figure(scene: Scene, title: str = "") -> go.Figure:
    """The exaggerated mechanism as a Plotly 3D figure (rotate, zoom, hover)."""
    import plotly.graph_objects as go

    from jointplay.present.plot import BODY_COLOURS, DOMAIN, FREE, INITIAL, LOAD, POINT, TOUCHING

    traces: list[Any] = []
    bodies = sorted({ln.label for ln in scene.lines if ln.role == "displaced"})

    def joined(points: Iterable[FloatArray]) -> tuple[list[float | None], ...]:
        xs: list[float | None] = []
        ys: list[float | None] = []
        zs: list[float | None] = []
        for P in points:
            xs += [*P[:, 0].tolist(), None]
            ys += [*P[:, 1].tolist(), None]
            zs += [*P[:, 2].tolist(), None]
        return xs, ys, zs

    def lines(pts: Sequence[FloatArray], name: str, colour: str, width: float, dash: str) -> None:
        if not pts:
            return
        x, y, z = joined(pts)
        traces.append(
            go.Scatter3d(
                x=x,
                y=y,
                z=z,
                mode="lines",
                name=name,
                line={"color": colour, "width": width, "dash": dash},
                hoverinfo="name",
            )
        )

    lines(
        [ln.points for ln in scene.lines if ln.role == "initial"],
        "initial position",
        INITIAL,
        2,
        "dash",
    )
    if len(bodies) > MANY_BODIES:  # one trace: a legend of a thousand bodies helps no one
        pts = [ln.points for ln in scene.lines if ln.role == "displaced"]
        lines(pts, f"{len(bodies)} bodies, displaced", BODY_COLOURS[0], 6, "solid")
    for i, body in enumerate(bodies if len(bodies) <= MANY_BODIES else []):
        pts = [ln.points for ln in scene.lines if ln.role == "displaced" and ln.label == body]
        lines(pts, body, BODY_COLOURS[i % len(BODY_COLOURS)], 6, "solid")
    lines(
        [ln.points for ln in scene.lines if ln.role == "domain"],
        "clearance domains",
        DOMAIN,
        2,
        "solid",
    )
    for role, name, style in (
        ("touching", "touching contacts", {"color": TOUCHING, "size": 5}),
        ("free", "free contacts", {"color": FREE, "size": 3}),
        ("point", "functional points", {"color": POINT, "size": 4, "symbol": "diamond"}),
    ):
        marks = [m for m in scene.markers if m.role == role]
        if not marks:
            continue
        P = np.array([m.at for m in marks])
        traces.append(
            go.Scatter3d(
                x=P[:, 0],
                y=P[:, 1],
                z=P[:, 2],
                mode="markers+text" if role == "point" else "markers",
                text=[m.label for m in marks],
                name=name,
                marker=style,
                hoverinfo="text",
            )
        )
    for role, name, colour in (
        ("contact force", "contact forces", TOUCHING),
        ("load", "loads", LOAD),
    ):
        arrows = [a for a in scene.arrows if a.role == role]
        if not arrows:
            continue
        lines(
            [_arrow_lines(a.start, a.vector, scene.size) for a in arrows], name, colour, 4, "solid"
        )
    fig = go.Figure(traces)
    lo, hi = scene.bounds()
    span = hi - lo
    # at the data's aspect a thin direction is short: a few ticks, or they pile up
    ticks = [6 if s >= 0.3 * float(np.max(span)) else 3 for s in span]
    fig.update_layout(
        title={"text": title, "font": {"size": 14}},
        scene={
            "aspectmode": "data",
            "xaxis": {"title": {"text": "X (mm)"}, "nticks": ticks[0]},
            "yaxis": {"title": {"text": "Y (mm)"}, "nticks": ticks[1]},
            "zaxis": {"title": {"text": "Z (mm)"}, "nticks": ticks[2]},
            # far enough that the whole scene, stretched to its data's aspect, stays in view
            "camera": {"eye": {"x": 2.0, "y": -2.3, "z": 1.5}},
        },
        margin={"l": 0, "r": 0, "t": 40, "b": 0},
        height=620,
        legend={"itemsizing": "constant"},
    )
    return fig


def motion_view(model: Model, mr: MotionResult) -> go.Figure:
    """The mechanism at each pose beside its first point's displacement
    curve, a slider stepping through the poses (it moves the bodies' lines,
    the joints' centres, the points and the curve's marker)."""
    import plotly.graph_objects as go
    from plotly.subplots import make_subplots

    from jointplay.present.motion_plots import (
        displacement_series,
        drawn_plane,
        joint_centres,
        posed_lines,
        shown_points,
    )
    from jointplay.present.plot import BODY_COLOURS, INITIAL, POINT, TOUCHING

    h, v = drawn_plane(model, mr)
    names = "XYZ"
    points = shown_points(mr)
    series = displacement_series(mr, points[0]) if points else None
    fig = make_subplots(rows=1, cols=2, column_widths=[0.55, 0.45], horizontal_spacing=0.08)

    def joined(paths: Iterable[FloatArray], axis: int) -> list[float | None]:
        out: list[float | None] = []
        for P in paths:
            out += [*P[:, axis].tolist(), None]
        return out

    def frame(s: int) -> tuple[list[list[float | None]], list[list[float | None]]]:
        """x and y of each moving trace at step ``s``, in the traces' order."""
        lines = posed_lines(model, mr, s)
        xs = [joined(paths, h) for paths in lines.values()]
        ys = [joined(paths, v) for paths in lines.values()]
        C = joint_centres(model, mr, s)
        xs.append(C[:, h].tolist())
        ys.append(C[:, v].tolist())
        if points:
            P = mr.nominal[s, [mr.point_names.index(n) for n in points]]
            xs.append(P[:, h].tolist())
            ys.append(P[:, v].tolist())
        if series is not None:
            xs.append([float(series.drive[s])])
            ys.append([float(series.curves[0][1][s])])
        return xs, ys

    for name in points:  # each point's whole path, under the moving traces
        P = mr.nominal[:, mr.point_names.index(name)]
        fig.add_trace(
            go.Scatter(
                x=P[:, h],
                y=P[:, v],
                mode="lines",
                name=f"path of '{name}'",
                line={"color": INITIAL, "width": 1, "dash": "dot"},
            ),
            row=1,
            col=1,
        )
    moving = len(fig.data)
    xs, ys = frame(0)
    for i, body in enumerate(posed_lines(model, mr, 0)):
        fig.add_trace(
            go.Scatter(
                x=xs[i],
                y=ys[i],
                mode="lines",
                name=body,
                line={"color": BODY_COLOURS[i % len(BODY_COLOURS)], "width": 3},
            ),
            row=1,
            col=1,
        )
    k = len(fig.data) - moving
    fig.add_trace(
        go.Scatter(
            x=xs[k],
            y=ys[k],
            mode="markers",
            name="joint centres",
            text=[j.name for j in model.joints],
            hoverinfo="text",
            marker={"color": "#333333", "size": 7},
        ),
        row=1,
        col=1,
    )
    if points:
        fig.add_trace(
            go.Scatter(
                x=xs[k + 1],
                y=ys[k + 1],
                mode="markers+text",
                name="functional points",
                text=points,
                textposition="top center",
                marker={"color": POINT, "size": 8, "symbol": "diamond"},
            ),
            row=1,
            col=1,
        )
    if series is not None:
        label, values = series.curves[0]
        fig.add_trace(
            go.Scatter(
                x=series.drive,
                y=values,
                mode="lines",
                name=f"'{series.point}': {label} (mm)",
                line={"color": "#1f77b4", "width": 2},
            ),
            row=1,
            col=2,
        )
        if series.limit is not None:
            for sign in (1.0, -1.0) if series.along is not None else (1.0,):
                fig.add_hline(
                    y=sign * series.limit, line={"color": TOUCHING, "width": 1}, row=1, col=2
                )
        fig.add_trace(
            go.Scatter(
                x=xs[-1],
                y=ys[-1],
                mode="markers",
                name="this pose",
                marker={"color": TOUCHING, "size": 10},
            ),
            row=1,
            col=2,
        )
    # the moving traces: the bodies, the centres, the points, then the marker
    traces = list(range(moving, moving + len(xs) - (series is not None)))
    if series is not None:
        traces.append(len(fig.data) - 1)
    steps = []
    for s in range(mr.steps):
        xs, ys = frame(s)
        steps.append(
            {
                "method": "restyle",
                "label": f"{mr.shown_value(s):g}",
                "args": [{"x": xs, "y": ys}, traces],
            }
        )
    every = np.vstack(
        [P for s in range(mr.steps) for paths in posed_lines(model, mr, s).values() for P in paths]
        + [joint_centres(model, mr, s) for s in range(mr.steps)]
        + [np.asarray(mr.nominal).reshape(-1, 3)]
    )
    lo, hi = every.min(axis=0), every.max(axis=0)
    pad = 0.05 * float(np.max(hi - lo))
    fig.update_xaxes(range=[lo[h] - pad, hi[h] + pad], title_text=f"{names[h]} (mm)", row=1, col=1)
    fig.update_yaxes(
        range=[lo[v] - pad, hi[v] + pad],
        title_text=f"{names[v]} (mm)",
        scaleanchor="x",
        scaleratio=1,
        row=1,
        col=1,
    )
    fig.update_xaxes(title_text=f"{mr.drive} ({mr.unit})", row=1, col=2)
    fig.update_yaxes(title_text="mm", row=1, col=2)
    fig.update_layout(
        title={"text": f"{mr.steps} poses driven by '{mr.drive}'", "font": {"size": 14}},
        sliders=[
            {
                "active": 0,
                "currentvalue": {"prefix": f"{mr.drive} ({mr.unit}): "},
                "pad": {"t": 40},
                "steps": steps,
            }
        ],
        margin={"l": 40, "r": 20, "t": 50, "b": 20},
        height=620,
    )
    return fig


def _arrow_lines(start: FloatArray, vector: FloatArray, size: float) -> FloatArray:
    """An arrow as one polyline: the shaft, then four barbs at the tip (seen
    from any side, where a 3D cone would need a size of its own)."""
    tip = start + vector
    length = float(np.linalg.norm(vector))
    if length == 0.0:
        return np.vstack([start, tip])
    u = vector / length
    side = np.cross(u, np.eye(3)[int(np.argmin(np.abs(u)))])
    side /= np.linalg.norm(side)
    other = np.cross(u, side)
    head = min(0.3 * length, 0.04 * size)
    out = [start, tip]
    for s in (side, -side, other, -other):
        out += [tip - head * u + 0.4 * head * s, tip]
    return np.vstack(out)


# -- the page ------------------------------------------------------------------------
def _svg(fig: Figure, vector: bool = True) -> str:
    """A matplotlib figure as an <img> holding its SVG (each figure kept apart),
    or a PNG when ``vector`` is False (a large mechanism: SVG grows with every line)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    kind, mime = ("svg", "image/svg+xml") if vector else ("png", "image/png")
    try:
        fig.savefig(buf, format=kind, bbox_inches="tight", dpi=110)
    finally:
        plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img class="figure" alt="figure" src="data:{mime};base64,{data}">'


def _capability(v: float) -> str:
    return "–" if v != v else f"{v:.3g}"  # NaN: not defined for a one-sided limit


def _rank(co: ContributionsResult, k: int, i: int) -> float:
    """The order of the contributions' rows: the worst-case share where the
    measure is linear, else the total Sobol' index (as the text sorts them)."""
    if co.sobol is None or co.linear(k):
        return float(co.worst_case[k, i])
    return float(co.sobol.total[k, i])


def _num(v: float, digits: int = 6) -> str:
    v = float(v)
    if v == 0.0:
        return "0"
    return f"{v:.{digits}g}"


def _vec(v: Iterable[float], digits: int = 6) -> str:
    return "(" + ", ".join(_num(c, digits) for c in v) + ")"


def _table(head: Sequence[str], rows: Iterable[Sequence[Any]], caption: str = "") -> str:
    cap = f"<caption>{html.escape(caption)}</caption>" if caption else ""
    th = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows
    )
    return f'<table class="jp-table">{cap}<thead><tr>{th}</tr></thead><tbody>{body}</tbody></table>'


class _Page:
    """The page as it is written, section by section."""

    def __init__(self, title: str):
        self.title = title
        self.parts: list[str] = []
        self.views: list[dict[str, Any]] = []
        #: Where the summary's verdicts over the motion and over the toleranced
        #: plays go, in that order, once known (parts left empty till then).
        self.slots: dict[str, int] = {}
        #: The model has a motion: the summary's single-pose figures say their pose.
        self.moving = False

    def section(self, title: str) -> None:
        self.parts.append(f"<h2>{html.escape(title)}</h2>")

    def subsection(self, title: str) -> None:
        self.parts.append(f"<h3>{html.escape(title)}</h3>")

    def paragraph(self, text: str) -> None:
        self.parts.append(f"<p>{html.escape(text)}</p>")

    def header(self, model: Model, source: str) -> None:
        when = _dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")
        self.parts.append(f"<h1>{html.escape(self.title)}</h1>")
        desc = f"<p>{html.escape(model.description)}</p>" if model.description else ""
        self.parts.append(
            f'<p class="meta">Model file <code>{html.escape(source)}</code>; jointplay '
            f"{html.escape(__version__)}; {html.escape(when)}. Units: mm, N, N·mm, rad. "
            "Contact forces are those of body a on body b for each joint "
            "<code>between: [a, b]</code>, in the joint frame.</p>" + desc
        )

    def summary(self, model: Model, results: dict[str | None, Result]) -> None:
        """What a reader needs first: per load case the status, the play used
        most, the requirements' verdicts and the key numbers; then the plays
        the nominal solve used (a toleranced play: its mean)."""
        self.section("Summary")
        self.moving = model.motion is not None
        rows = []
        for case, result in results.items():
            played = (  # contacts with play: a rigid or zero-play one is always "full"
                (result.joints[joint.name], c)
                for joint in model.joints
                for cone, c in zip(joint.cones, result.joints[joint.name].contacts, strict=True)
                if cone.kind == "ball" and cone.radius > 0
            )
            contact = max(played, key=lambda jc: jc[1].gap_used, default=None)
            most = (
                f"{contact[0].name}.{contact[1].name}: {100 * contact[1].gap_used:.1f} %"
                + (" (touching)" if contact[1].in_contact else "")
                if contact is not None
                else "–"
            )
            failed = [r for r in result.requirements if not r.passed]
            verdict = (
                "–"
                if not result.requirements
                else "all pass"
                if not failed
                else f"{len(failed)} of {len(result.requirements)} FAIL"
            )
            largest = ", ".join(
                f"{p.name} {_num(float(np.linalg.norm(p.displacement)), 4)} mm"
                for p in result.points.values()
            )
            status = result.status + ("" if result.certificate.certified else " (not certified)")
            rows.append(
                (
                    "(model's loads)" if case is None else case,
                    status,
                    most,
                    verdict,
                    largest or "–",
                    len(result.warnings),
                )
            )
        self.parts.append(
            _table(
                [
                    "load case",
                    "status",
                    "play used most",
                    "requirements (nominal plays)",
                    "|d| of the points",
                    "warnings",
                ],
                rows,
                "At a glance"
                + (" at the pose written in the file" if self.moving else "")
                + " (the sections below give every number)",
            )
        )
        for slot in ("motion", "tolerances"):
            self.slots[slot] = len(self.parts)
            self.parts.append("")
        plays = []
        for joint in model.joints:
            for field, value in joint.plays().items():
                if field == "clearance" and joint.type_name == "point":
                    continue  # a point joint's play is its gap
                origin = value.describe() if isinstance(value, Toleranced) else "as given"
                used = "its mean" if isinstance(value, Toleranced) else "as given"
                plays.append(
                    (joint.name, field, f"{_num(float(value))} {play_unit(field)}", used, origin)
                )
        if plays:
            self.parts.append(
                _table(
                    ["joint", "play", "used", "", "from"],
                    [(j, f, v, u, o if o != "as given" else "") for j, f, v, u, o in plays],
                    "Plays the nominal solve used (a toleranced play at its mean)",
                )
            )

    def model_tables(self, model: Model) -> None:
        self.section("Model")
        self.parts.append(
            _table(
                ["body", "ground", "mass (kg)", "centre of mass (mm)"],
                [
                    (
                        b.name,
                        "yes" if b.ground else "",
                        "" if b.mass is None else _num(b.mass),
                        "" if b.center_of_mass is None else _vec(b.center_of_mass),
                    )
                    for b in model.bodies
                ],
                "Bodies",
            )
        )
        self.parts.append(
            _table(
                ["joint", "type", "between (a, b)", "at (mm)", "axis", "play and size"],
                [
                    (
                        j.name,
                        j.type_name,
                        f"{j.between[0]}, {j.between[1]}",
                        _vec(j.at),
                        _vec(j.axis, 4),
                        _joint_sizes(j),
                    )
                    for j in model.joints
                ],
                "Joints",
            )
        )
        loads = [("(every case)", ld) for ld in model.loads] + [
            (case, ld) for case in model.case_names for ld in (model.load_cases or {})[case]
        ]
        loads += [("(weight)", ld) for ld in model.weights()]
        span = _motion_span(model)
        if loads:
            self.parts.append(
                _table(
                    ["case", "body", "at (mm)", "force (N)", "torque (N·mm)"],
                    [
                        (
                            case,
                            ld.body,
                            "" if ld.at is None else _vec(ld.at),
                            _load_vector(ld.force, span),
                            _load_vector(ld.torque, span),
                        )
                        for case, ld in loads
                    ],
                    "Loads",
                )
            )
        tables = _load_tables(model, loads)
        if tables:
            self.parts.append(tables)
        if model.points:
            self.parts.append(
                _table(
                    ["point", "body", "at (mm)"],
                    [(p.name, p.body, _vec(p.at)) for p in model.points],
                    "Functional points",
                )
            )
        if model.requirements:
            self.parts.append(
                _table(
                    ["requirement"], [(r.describe(),) for r in model.requirements], "Requirements"
                )
            )

    def solution(
        self, model: Model, result: Result, case: str | None, magnify: float | None
    ) -> None:
        from jointplay.present.plot import clearance_figure, mechanism_figure

        self.section(
            ("Solution" if case is None else f"Solution, load case '{case}'")
            + (" (at the pose written in the file)" if self.moving else "")
        )
        from jointplay.present.textreport import certificate_words, indeterminacy_words

        self.parts.append(
            f'<p class="certificate">Status <b>{html.escape(result.status)}</b>; '
            f"{html.escape(certificate_words(result))}; potential energy "
            f"{_num(result.potential_energy, 9)} N·mm.</p>"
        )
        for text in result.free_motions:
            self.paragraph(f"Free motion (no load drives it; reported as 0): {text}")
        for text in result.warnings:
            self.paragraph(f"Warning: {text}")
        self.parts.append(
            _table(
                ["joint", "b relative to a", "translation (mm, joint frame)", "rotation (rad)"],
                [
                    (
                        name,
                        f"{jr.between[1]} / {jr.between[0]}",
                        _vec(jr.translation),
                        _vec(jr.rotation),
                    )
                    for name, jr in result.joints.items()
                ],
                "Joints: relative torsor at the joint centre",
            )
        )
        self.parts.append(
            _table(
                [
                    "joint",
                    "contact",
                    "play used",
                    "state",
                    "force (N)",
                    "F (joint frame, N)",
                    "at (mm), or torque (N*mm, joint frame)",
                ],
                [
                    (
                        name,
                        c.name,
                        f"{100 * c.gap_used:.2f} %",
                        "touching" if c.in_contact else "free",
                        _num(c.force_magnitude),
                        _vec(c.force),
                        f"torque {_vec(c.torque)}" if c.unit == "rad" else _vec(c.point),
                    )
                    for name, jr in result.joints.items()
                    for c in jr.contacts
                ],
                "Contacts and forces",
            )
        )
        split = indeterminacy_words(result)
        if split is not None:
            self.paragraph(split)
        self.parts.append(
            _table(
                ["body", "translation at the origin (mm)", "rotation (rad)"],
                [(n, _vec(b.translation), _vec(b.rotation)) for n, b in result.bodies.items()],
                "Bodies (global axes)",
            )
        )
        if result.points:
            self.parts.append(
                _table(
                    ["point", "body", "displacement (mm)", "|d| (mm)"],
                    [
                        (
                            n,
                            p.body,
                            _vec(p.displacement),
                            _num(float(np.linalg.norm(p.displacement))),
                        )
                        for n, p in result.points.items()
                    ],
                    "Functional points",
                )
            )
        scene = mechanism_scene(model, result, magnify=magnify, case=case)
        self.subsection(f"Interactive view (displacements and plays ×{scene.magnify:g})")
        self.view(scene_figure(scene, "drag to turn, scroll to zoom, hover for names"))
        self.subsection("Figures")
        vector = len(scene.lines) <= VECTOR_LINES
        # the joints' views once: in the clearance figure, every joint
        figure = mechanism_figure(model, result, magnify=magnify, case=case, joints=False)
        self.parts.append(_svg(figure, vector))
        self.parts.append(_svg(clearance_figure(model, result)))

    def view(self, fig: go.Figure) -> None:
        import plotly.io as pio

        ident = f"jp-view-{len(self.views)}"
        self.views.append({"id": ident, "figure": json.loads(pio.to_json(fig, validate=False))})
        self.parts.append(f'<div class="jp-view" id="{ident}"></div>')

    def envelope(self, env: EnvelopeResult) -> None:
        from jointplay.present.plot import envelope_figure

        self.subsection(f"Worst-case envelope of point '{env.settings.point}'")
        ext = env.extent
        self.parts.append(
            _table(
                ["largest |d| (mm)", "along", "X extent (mm)", "Y extent (mm)", "Z extent (mm)"],
                [
                    (
                        _num(env.largest),
                        _vec(env.largest_direction, 4),
                        f"{_num(ext[0, 0])} .. {_num(ext[0, 1])}",
                        f"{_num(ext[1, 0])} .. {_num(ext[1, 1])}",
                        f"{_num(ext[2, 0])} .. {_num(ext[2, 1])}",
                    )
                ],
                f"plays at their {env.settings.plays}, under {env.over or 'any load'}",
            )
        )
        for words in env.not_held:
            self.paragraph(f"Not held, left out: {words}.")
        self.parts.append(_svg(envelope_figure(env)))

    def montecarlo(self, mc: MonteCarloResult) -> None:
        from jointplay.present.plot import montecarlo_figure

        self.subsection(f"Monte Carlo: {mc.samples} sets of parts (seed {mc.settings.seed})")
        self.parts.append(
            _table(
                ["play, load or deviation", "distribution"],
                [
                    *mc.plays_described.items(),
                    *mc.loads_described.items(),
                    *mc.deviations_described.items(),
                ],
                "What varies",
            )
        )
        if mc.unassembled:
            self.paragraph(
                f"{mc.unassembled} of the {mc.samples} sets of parts cannot be assembled: their "
                "deviations leave no position inside every clearance. They are left out of the "
                "points' figures and counted as missing every requirement."
            )
        self.parts.append(
            _table(
                ["point", "mean |d| (mm)", "σ |d| (mm)", "99.865 % (+3σ) (mm)", "largest (mm)"],
                [
                    (
                        n,
                        _num(s.size_mean),
                        _num(s.size_std),
                        _num(s.size_percentiles[99.865]),
                        _num(s.size_max),
                    )
                    for n, s in mc.points.items()
                ],
                "Functional points",
            )
        )
        if mc.requirements:
            self.parts.append(
                _table(
                    ["requirement", "parts outside", "fraction", "interval"],
                    [
                        (
                            r.requirement.describe(),
                            r.outside,
                            f"{100 * r.fraction:.4g} %",
                            f"{100 * r.interval[0]:.3g} .. {100 * r.interval[1]:.3g} %",
                        )
                        for r in mc.requirements
                    ],
                    f"Requirements ({100 * mc.settings.confidence:g} % interval)",
                )
            )
        self.parts.append(_svg(montecarlo_figure(mc)))

    def contributions(self, co: ContributionsResult) -> None:
        from jointplay.present.plot import contributions_figure

        self.subsection("Contributions")
        wc, rss = co.worst_case, co.rss
        sobol = co.sobol

        def variance(k: int, i: int) -> tuple[str, str]:
            if sobol is None or co.linear(k):
                return "", ""
            from jointplay.present.textreport import sobol_share

            return (
                sobol_share(float(sobol.first[k, i]), sobol.first_interval[k, i]),
                sobol_share(float(sobol.total[k, i]), sobol.total_interval[k, i]),
            )

        self.parts.append(
            _table(
                [
                    "measure",
                    "variable",
                    "sensitivity",
                    "worst case",
                    "RSS",
                    "Sobol' first order",
                    "Sobol' total",
                    "note",
                ],
                [
                    (
                        m,
                        p,
                        _num(co.sensitivity[k, i], 5),
                        f"{wc[k, i]:.1f} %" if co.linear(k) else "n/a",
                        f"{rss[k, i]:.1f} %" if co.linear(k) else "n/a",
                        *variance(k, i),
                        "kink: the contacts change here" if co.kink[k, i] else "",
                    )
                    for k, m in enumerate(co.measures)
                    for i, p in sorted(enumerate(co.plays), key=lambda ip: -_rank(co, k, ip[0]))
                ],
                "Sensitivities at the nominal, and shares of the stacks (the largest share "
                "first, as in the Pareto); where a measure is not linear over the ranges the "
                "linear shares do not apply (n/a) and the shares of its variance (Sobol' "
                "indices, with their intervals) stand in",
            )
        )
        for k, check in enumerate(co.linearity):
            if not check.linear:
                words = f"{co.measures[k]}: not linear over the ranges: {check.why()}."
                self.parts.append(f"<p>{html.escape(words)}</p>")
        self.parts.append(_svg(contributions_figure(co)))

    def tolerances(
        self, rows: Sequence[RequirementTolerances], confidence: float, samples: int
    ) -> None:
        failing = [r for r in rows if not r.worst_case_passes]
        worst_ppm = max(rows, key=lambda r: r.mc_ppm, default=None)
        if rows and worst_ppm is not None:
            # the summary's verdict is for the nominal plays; say the toleranced one there too
            self.parts[self.slots["tolerances"]] = (
                "<p>"
                + html.escape(
                    ("At the pose written in the file, over" if self.moving else "Over")
                    + " the tolerances: worst case "
                    + (f"{len(failing)} of {len(rows)} FAIL" if failing else "all pass")
                    + f"; Monte Carlo: {worst_ppm.mc_ppm:.4g} ppm out of spec for "
                    f"{worst_ppm.requirement.describe()}, the most of any requirement "
                    f"({worst_ppm.mc_interval_ppm[0]:.3g} to {worst_ppm.mc_interval_ppm[1]:.3g} "
                    "ppm at the confidence of the table). See the side-by-side table."
                )
                + "</p>"
            )
        self.subsection("Requirements: worst case, RSS and Monte Carlo side by side")

        def rss(r: RequirementTolerances, text: str) -> str:
            return text if r.rss_applies else "n/a"

        self.parts.append(
            _table(
                [
                    "requirement",
                    "worst case (mm)",
                    "linear estimate (mm)",
                    "RSS σ (mm)",
                    "Cp",
                    "Cpk",
                    "ppm (RSS)",
                    "MC σ (mm)",
                    "MC range (mm)",
                    "Pp",
                    "Ppk",
                    "ppm (MC)",
                ],
                [
                    (
                        r.requirement.describe(),
                        f"{_num(r.worst, 5)} " + ("pass" if r.worst_case_passes else "FAIL"),
                        f"{_num(r.linear_low, 5)} .. {_num(r.linear_high, 5)}"
                        if r.linear_agrees
                        else "n/a",
                        rss(r, _num(r.rss_sigma, 4)),
                        rss(r, _capability(r.cp)),
                        rss(r, _capability(r.cpk)),
                        rss(r, f"{r.rss_ppm:.4g}"),
                        _num(r.mc_sigma, 4),
                        f"{_num(r.mc_low, 5)} .. {_num(r.mc_high, 5)}",
                        _capability(r.pp),
                        _capability(r.ppk),
                        f"{r.mc_ppm:.4g} [{r.mc_interval_ppm[0]:.3g}, {r.mc_interval_ppm[1]:.3g}]",
                    )
                    for r in rows
                ],
                "Worst case: the measure's greatest value over the worst-case envelope, with "
                "the linear stack as an estimate where it agrees; RSS: a normal law of the "
                "contributions' sigma, only where the measure is linear over the ranges; "
                f"Monte Carlo: the sampled parts ({100 * confidence:g} % interval). "
                "Formulas: docs/conventions.md; which holds when: docs/tolerancing.md.",
            )
        )
        for r in rows:
            words = f"{r.requirement.describe()}: worst case at {r.worst_at}."
            if not r.rss_applies:
                words += f" RSS, Cp, Cpk: not applicable: {r.linear_why}."
            self.parts.append(f"<p>{html.escape(words)}</p>")
            if r.beyond_words(samples):
                words = f"{r.requirement.describe()}: {r.beyond_words(samples)}."
                self.parts.append(f"<p><strong>{html.escape(words)}</strong></p>")

    def motion(self, model: Model, mr: MotionResult, others: bool = False) -> None:
        """The motion's section; ``others``: the model's other load cases are
        solved above but not driven through the motion."""
        from jointplay.present.motion_plots import motion_figure, poses_figure
        from jointplay.present.textreport import steps_split_words

        self.section("Motion")
        under, case = "", "" if mr.case is None else f" --case {shlex.quote(mr.case)}"
        if mr.case is not None:
            under = f" under load case '{mr.case}'" + (
                " (the first; jointplay motion MODEL --case NAME for another)" if others else ""
            )
        self.paragraph(
            f"The mechanism driven by '{mr.drive}' from {mr.shown_value(0):g} to "
            f"{mr.shown_value(mr.steps - 1):g} {mr.unit} in {mr.steps} poses{under}, the "
            "clearance equilibrium solved at each. The table of every step: jointplay motion "
            f"MODEL{case} --csv FILE; these figures: jointplay motion MODEL{case} --plot FILE."
        )
        if mr.requirement_names:
            rows, failing = [], []
            for q, name in enumerate(mr.requirement_names):
                worst = mr.worst_step(q)
                measured = _num(float(mr.measured[worst, q]))
                at = f"{worst} ({mr.shown_value(worst):g} {mr.unit})"
                steps = int(np.sum(mr.measured[:, q] > mr.limits[q]))
                verdict = f"FAILED at {steps} of {mr.steps} steps" if steps else "passed"
                rows.append((name, _num(mr.limits[q]), at, measured, verdict))
                if steps:
                    failing.append(
                        f"{name} at {steps} of {mr.steps} steps, worst at step {at}: "
                        f"{measured} mm against {_num(mr.limits[q])} mm"
                    )
            head = ["point", "limit (mm)", "worst step", "measured there (mm)", "over the motion"]
            self.parts.append(_table(head, rows, "Requirements at every pose"))
            # the summary's verdicts are at the pose written in the file: say the motion's there
            words = (
                "Over the motion (the summary above is at the pose written in the file): "
                + (
                    f"{len(failing)} of {len(rows)} requirements FAIL: " + "; ".join(failing)
                    if failing
                    else "all requirements pass at every pose"
                )
                + ". See the Motion section."
            )
            self.parts[self.slots["motion"]] = "<p>" + html.escape(words) + "</p>"
        split = steps_split_words(mr.indeterminate, mr.joint_names)
        if split is not None:
            self.paragraph(split)
        self.parts.append(_svg(motion_figure(mr)))
        self.parts.append(_svg(poses_figure(model, mr)))
        self.paragraph("Move the slider to step through the poses.")
        self.view(motion_view(model, mr))

    def sweep(self, model: Model, sw: SweepResult, source: str) -> None:
        from jointplay.present.plot import sweep_figure
        from jointplay.present.textreport import steps_split_words
        from jointplay.studies.envelope import point_envelopes

        self.subsection(f"Sweep of {', '.join(sw.labels)}: {sw.steps} steps")
        envelopes, _ = point_envelopes(model, "mean", source=source)
        table = sw.to_dataframe()
        shown = [c for c in table.columns if c == "step" or c in sw.labels or c.endswith(".size")]
        rows = table[shown].head(400).itertuples(index=False)
        self.parts.append(
            _table(
                shown,
                [[_num(v) if isinstance(v, float) else v for v in row] for row in rows],
                "Steps (the first 400); the whole table: jointplay sweep ... --csv FILE",
            )
        )
        split = steps_split_words(sw.indeterminate, sw.joint_names)
        if split is not None:
            self.paragraph(split)
        self.parts.append(_svg(sweep_figure(sw, envelopes)))

    def html(self) -> str:
        from plotly.offline import get_plotlyjs

        views = json.dumps(self.views, separators=(",", ":")).replace("</", "<\\/")
        return _TEMPLATE.format(
            title=html.escape(self.title),
            style=_STYLE,
            watch=_WATCH,
            plotly=get_plotlyjs().replace("</script", "<\\/script"),
            body="\n".join(self.parts),
            views=views,
            draw=_DRAW,
        )


def _motion_span(model: Model) -> tuple[float, float] | None:
    """The drive's range over the motion (rad or mm, low to high), if any."""
    if model.motion is None:
        return None
    _, _, start, stop = model.motion_drive()
    return min(start, stop), max(start, stop)


def _load_vector(vector: Any, span: tuple[float, float] | None) -> str:
    """A load's force or torque: a vector of plain components; where one
    varies (a range, a table over the motion), each component in words, not
    the one value a solve at the pose written takes."""
    if vector is None:
        return ""
    if not any(isinstance(c, Toleranced | DriveTable) for c in vector):
        return _vec(vector)
    words = []
    for axis, c in zip("xyz", vector, strict=True):
        if isinstance(c, DriveTable) and span is not None:
            inside = [d for d in c.drive if span[0] < d < span[1]]
            values = [c.at(d) for d in (*span, *inside)]
            text = f"{_num(min(values))} to {_num(max(values))} over the motion (table below)"
        elif isinstance(c, Toleranced):
            text = c.describe()
        else:
            text = _num(c)
        words.append(f"{axis} {text}")
    return "; ".join(words)


def _load_tables(model: Model, loads: Sequence[tuple[str, Any]]) -> str:
    """The rows of each load table over the motion, as the model gives them."""
    from jointplay.studies.motion import shown_drive

    found = [
        (case, ld.body, f"{key} {axis} ({unit})", c)
        for case, ld in loads
        for key, unit in (("force", "N"), ("torque", "N·mm"))
        for axis, c in zip("xyz", getattr(ld, key) or (None,) * 3, strict=True)
        if isinstance(c, DriveTable)
    ]
    if not found:
        return ""
    joint, coordinate, _, _ = model.motion_drive()
    unit = "deg" if coordinate == "spin" else "mm"
    rows = [
        (case, body, component, _num(shown_drive(coordinate, d)), _num(v))
        for case, body, component, c in found
        for d, v in zip(c.drive, c.value, strict=True)
    ]
    return _table(
        ["case", "body", "component", f"{joint.name} ({unit})", "value"],
        rows,
        "Load tables over the motion: each component linear in the drive's value between "
        "rows; a solve at the pose written in the file reads it at "
        f"{shown_drive(coordinate, 0.0):g} {unit}",
    )


def _joint_sizes(joint: Any) -> str:
    parts = []
    for field in (
        "clearance",
        "clearance_y",
        "clearance_z",
        "axial_clearance",
        "gap",
        "length",
        "width",
        "height",
        "diameter",
        "slot_length",
        "stiffness",
        "backlash",
        "torsional_stiffness",
    ):
        value = getattr(joint, field, None)
        if value is None or (field == "clearance" and joint.type_name in ("rigid", "point")):
            continue
        describe = getattr(value, "describe", None)
        unit = {"backlash": " rad", "stiffness": " N/mm", "torsional_stiffness": " N*mm/rad"}
        text = describe() if callable(describe) else _num(value) + unit.get(field, "")
        parts.append(f"{field} {text}")
    if getattr(joint, "along", None) is not None:
        parts.append(f"along {_vec(np.asarray(joint.along, dtype=float))}")
    if joint.deviation is not None:
        if joint.deviation.shared is not None:
            parts.append(f"deviation: shared '{joint.deviation.shared}'")
        else:
            parts.append(f"deviation: {joint.deviation.describe(joint.type_name == 'spherical')}")
    return ", ".join(parts)


_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 2em auto;
       max-width: 1200px; padding: 0 1em; color: #1b1b1b; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; }
.meta { color: #555; }
table.jp-table { border-collapse: collapse; margin: 1em 0; font-size: 0.9em; }
table.jp-table caption { text-align: left; font-weight: bold; padding: 0.3em 0; }
table.jp-table th, table.jp-table td { border: 1px solid #d0d0d0; padding: 0.25em 0.6em;
       text-align: left; font-variant-numeric: tabular-nums; }
table.jp-table th { background: #f1f4f8; }
img.figure { max-width: 100%; display: block; margin: 1em 0; }
.jp-view { width: 100%; height: 620px; border: 1px solid #ddd; }
"""

# first in the page: whatever goes wrong in a script is recorded on <body>
_WATCH = """
window.jpErrors = [];
function jpRecord(text) {
  window.jpErrors.push(String(text));
  if (document.body) { document.body.dataset.errors = window.jpErrors.join("\\n"); }
}
window.addEventListener("error", function (e) { jpRecord(e.message || e); });
window.addEventListener("unhandledrejection", function (e) { jpRecord(e.reason); });
"""

_DRAW = """
(function () {
  var views = JSON.parse(document.getElementById("jp-views").textContent);
  var drawn = views.map(function (v) {
    return Plotly.newPlot(v.id, v.figure.data, v.figure.layout,
                          {responsive: true, displaylogo: false});
  });
  Promise.all(drawn).then(function () {
    document.body.dataset.rendered = "true";
  }, function (e) { jpRecord(e); });
  if (window.jpErrors.length) { document.body.dataset.errors = window.jpErrors.join("\\n"); }
})();
"""

_TEMPLATE = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{title}: jointplay report</title>
<style>{style}</style>
<script>{watch}</script>
<script>{plotly}</script>
</head>
<body>
{body}
<script type="application/json" id="jp-views">{views}</script>
<script>{draw}</script>
</body>
</html>
"""
