"""The mechanism as a picture, in the paper's manner: geometry only.

The paper draws each part as lines between its joints (no transverse size)
and each joint as its clearance domain, with the play exaggerated against
the other dimensions. ``mechanism_scene`` builds that picture in 3D from a
model and a result: each moving body's lines in the initial position and in
the displaced one, the displacements multiplied by ``magnify``; each
contact's clearance domain (a sphere, a circle across the axis, an interval)
on body a, its radius multiplied by the same factor, so that b's axis point
sits inside it exactly as in the solution; the contact points (touching or
not); the contact forces and the loads as arrows.

``joint_view`` gives the picture of one joint seen along its axis, in its
own frame and at true size (mm): the clearance circle, rectangle or sphere
section, and where each contact point of b went.

Nothing here draws: ``plot.py`` (matplotlib) and ``report.py`` (Plotly)
render these shapes.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Literal

import numpy as np

from jointplay.geometry import FloatArray, describe_direction

if TYPE_CHECKING:
    from jointplay.model.joints.base import Contact, Joint
    from jointplay.model.mechanism import Body, Load, Model
    from jointplay.result import JointResult, Result

#: The largest displacement of the picture, as a fraction of the mechanism's size.
SHOWN_FRACTION = 0.08
#: The largest arrow, as a fraction of the mechanism's size.
ARROW_FRACTION = 0.18
#: Points on a drawn circle.
CIRCLE_POINTS = 73
#: A body without outline is drawn along the line of its joints' centres (a
#: shaft, a link between two pins) when its joints' engagement ends lie within
#: this share of the line's length off it (a pin's ends across a link); a body
#: whose joints reach farther off (a carriage on a long guide, over its nut) is
#: drawn as the tree of its joints and points.
ACROSS_SHARE = 0.25

LineRole = Literal["initial", "displaced", "domain"]
MarkerRole = Literal["touching", "free", "point", "load point"]
ArrowRole = Literal["contact force", "load"]


@dataclass(frozen=True)
class Polyline:
    """A line through ``points`` (n, 3), mm, global axes."""

    points: FloatArray
    role: LineRole
    label: str  # the body or the joint it belongs to


@dataclass(frozen=True)
class Marker:
    at: FloatArray  # (3,) mm, global
    role: MarkerRole
    label: str


@dataclass(frozen=True)
class Arrow:
    start: FloatArray  # (3,) mm, global
    vector: FloatArray  # (3,) mm, drawn length (force x force_scale)
    role: ArrowRole
    label: str
    magnitude: float  # N


@dataclass(frozen=True)
class Scene:
    """Everything to draw, in mm and global axes, already exaggerated."""

    magnify: float  # drawn displacement per real displacement
    force_scale: float  # mm of arrow per N
    size: float  # the mechanism's size (mm): the diagonal of its key points
    lines: tuple[Polyline, ...]
    markers: tuple[Marker, ...]
    arrows: tuple[Arrow, ...]
    largest_displacement: float  # mm, real (not magnified)

    def body_span(self) -> FloatArray:
        """The extent (3,) along each axis of the bodies' lines, initial and
        displaced, and of the points and load points: what a view shows,
        without the domains and arrows drawn about it (mm)."""
        pts = [ln.points for ln in self.lines if ln.role != "domain"]
        pts += [m.at[None, :] for m in self.markers if m.role in ("point", "load point")]
        if not pts:
            return np.zeros(3)
        every = np.vstack(pts)
        return np.asarray(every.max(axis=0) - every.min(axis=0))

    def bounds(self) -> tuple[FloatArray, FloatArray]:
        """Least and greatest corner of everything drawn (mm)."""
        pts = [ln.points for ln in self.lines]
        pts += [m.at[None, :] for m in self.markers]
        pts += [np.vstack([a.start, a.start + a.vector]) for a in self.arrows]
        every = np.vstack(pts) if pts else np.zeros((1, 3))
        return every.min(axis=0), every.max(axis=0)


# -- the factor ---------------------------------------------------------------
def nice_factor(value: float) -> float:
    """The largest of 1, 2, 5 x 10^k not above ``value`` (at least 1)."""
    if not math.isfinite(value) or value <= 1.0:
        return 1.0
    power = 10.0 ** math.floor(math.log10(value))
    for step in (5.0, 2.0, 1.0):
        if step * power <= value * (1 + 1e-12):
            return step * power
    return power  # pragma: no cover - the loop always returns


def auto_magnify(size: float, largest: float) -> float:
    """A round factor that shows the largest displacement (or play) ``largest``
    as about ``SHOWN_FRACTION`` of the mechanism's ``size``."""
    if largest <= 0.0:
        return 1.0
    return nice_factor(SHOWN_FRACTION * size / largest)


# -- the mechanism ------------------------------------------------------------
def mechanism_scene(
    model: Model,
    result: Result,
    *,
    magnify: float | None = None,
    case: str | None = None,
) -> Scene:
    """The exaggerated picture of ``result`` (a solution of ``model``, of its
    load case ``case``). ``magnify``: None picks a round factor."""
    loads = model.loads_of(case)
    nodes = {b.name: _body_nodes(model, loads, b.name) for b in model.moving_bodies}
    every = [n for pts in nodes.values() for n in pts] + [j.centre for j in model.joints]
    every += [np.asarray(P) for b in model.moving_bodies for P in b.outline or ()]
    size = _size(np.array(every), model)

    def moved(body: str, P: FloatArray) -> FloatArray:
        b = result.bodies.get(body)
        return np.zeros(3) if b is None else b.displacement_of(P)

    largest = max(
        [float(np.linalg.norm(moved(b, P))) for b, pts in nodes.items() for P in pts]
        + [c.radius for j in model.joints for c in j.cones if c.kind == "ball"],
        default=0.0,
    )
    m = auto_magnify(size, largest) if magnify is None else float(magnify)

    lines: list[Polyline] = []
    markers: list[Marker] = []
    for body in nodes:
        for path in _body_paths(model, loads, model.body(body)):
            lines.append(Polyline(path, "initial", body))
            shifted = np.array([P + m * moved(body, P) for P in path])
            lines.append(Polyline(shifted, "displaced", body))

    # the arrows: contact forces on b at its displaced acting points, and loads
    arrows: list[tuple[FloatArray, FloatArray, ArrowRole, str]] = []
    for joint in model.joints:
        jr = result.joints[joint.name]
        a_name, b_name = joint.between
        rings: list[FloatArray] = []
        for cone, contact in zip(joint.cones, jr.contacts, strict=True):
            at = joint.centre + joint.R_world_joint @ cone.point
            on_a = at + m * moved(a_name, at)
            glyphs = _domain_glyph(joint, cone, on_a, m, size)
            lines.extend(Polyline(p, "domain", joint.name) for p in glyphs)
            rings.extend(g for g in glyphs if len(glyphs) == 1 and len(g) == CIRCLE_POINTS)
            on_b = at + m * moved(b_name, at)
            role: MarkerRole = "touching" if contact.in_contact else "free"
            markers.append(Marker(on_b, role, f"{joint.name} {contact.name}"))
            if contact.in_contact and contact.force_magnitude > 0.0:
                force = jr.R_world_joint @ contact.force
                start = contact.point + m * moved(b_name, contact.point)
                arrows.append((start, force, "contact force", f"{joint.name} {contact.name}"))
        if len(rings) == 2:  # a bore's two end circles: draw the bore
            quarter = (CIRCLE_POINTS - 1) // 4
            lines.extend(
                Polyline(np.vstack([rings[0][i], rings[1][i]]), "domain", joint.name)
                for i in range(0, CIRCLE_POINTS - 1, quarter)
            )
    for load in loads:
        if load.at is None or load.force is None:
            continue
        P = np.asarray(load.at, dtype=float)
        start = P + m * moved(load.body, P)
        arrows.append((start, np.asarray(load.force, dtype=float), "load", f"load on {load.body}"))
        markers.append(Marker(start, "load point", f"load on {load.body}"))
    for point in model.points:
        P = np.asarray(point.at, dtype=float)
        markers.append(Marker(P + m * moved(point.body, P), "point", point.name))

    biggest = max((float(np.linalg.norm(f)) for _, f, _, _ in arrows), default=0.0)
    scale = ARROW_FRACTION * size / biggest if biggest > 0.0 else 0.0
    drawn = tuple(
        Arrow(start, scale * f, role, label, float(np.linalg.norm(f)))
        for start, f, role, label in arrows
    )
    return Scene(m, scale, size, tuple(lines), tuple(markers), drawn, largest)


def body_lines(model: Model, case: str | None = None) -> dict[str, list[FloatArray]]:
    """Each moving body's lines at rest (mm, global), as the mechanism's
    picture draws them: its outline, else the line of its joints."""
    loads = model.loads_of(case)
    return {b.name: _body_paths(model, loads, b) for b in model.moving_bodies}


def _body_nodes(model: Model, loads: tuple[Load, ...], body: str) -> list[FloatArray]:
    """The points that draw a body: its joints' centres and the ends of their
    engagement on the axis, its load points, functional points and centre
    of mass; without repeats."""
    return _unique(_joint_nodes(model, body) + _attached_nodes(model, loads, body))


def _joint_nodes(model: Model, body: str) -> list[FloatArray]:
    """The centres of the body's joints and the ends of their engagement on
    their axes."""
    out: list[FloatArray] = []
    for joint in model.joints:
        if body not in joint.between:
            continue
        out.append(joint.centre)
        axis = joint.R_world_joint[:, 0]
        out.extend(joint.centre + float(c.point[0]) * axis for c in joint.cones)
    return out


def _attached_nodes(model: Model, loads: tuple[Load, ...], body: str) -> list[FloatArray]:
    """The body's load points, functional points and centre of mass."""
    out = [np.asarray(ld.at, dtype=float) for ld in loads if ld.body == body and ld.at]
    out.extend(np.asarray(p.at, dtype=float) for p in model.points if p.body == body)
    com = model.body(body).center_of_mass
    if com is not None:
        out.append(np.asarray(com, dtype=float))
    return out


def _unique(points: list[FloatArray]) -> list[FloatArray]:
    unique: list[FloatArray] = []
    for p in points:
        if not any(np.allclose(p, q, rtol=0.0, atol=1e-9) for q in unique):
            unique.append(np.asarray(p, dtype=float))
    return unique


def _body_paths(model: Model, loads: tuple[Load, ...], body: Body) -> list[FloatArray]:
    """The lines that draw ``body`` at rest: its outline, closed, if the model
    gives one. Else, when its joints sit on one line (a shaft, a link between
    two pins), that line through them, with a stub square to it out to each
    point off it (a gear's mesh point, a lever's load): the centre line and
    arms a designer sketches, where a tree through the points would draw a
    shaft as a V. Else (a plate on joints all about, a carriage whose guide
    reaches far off the line of its joints' centres: ``ACROSS_SHARE``) the
    shortest tree through its joints and points."""
    if body.outline is not None:
        corners = np.array(body.outline, dtype=float)
        return [np.vstack([corners, corners[:1]]) if len(corners) > 2 else corners]
    joints = _unique(_joint_nodes(model, body.name))
    attached = _unique(_attached_nodes(model, loads, body.name))
    every = _unique(joints + attached)
    tol = 1e-6 * max(_span(every), 1.0)
    axis = _axis_line(model, body.name, tol)
    if axis is None:
        return [np.vstack([every[i], every[k]]) for i, k in _tree_edges(every)]
    origin, u = axis

    def foot(P: FloatArray) -> FloatArray:
        return np.asarray(origin + float((P - origin) @ u) * u)

    # a pin's engagement ends lie across a link's line: the link is the line;
    # a guide's ends far off the line of the centres are not a line's
    ends = [float((P - origin) @ u) for P in joints]
    across = max(float(np.linalg.norm(P - foot(P))) for P in joints)
    if across > ACROSS_SHARE * (max(ends) - min(ends)) + tol:
        return [np.vstack([every[i], every[k]]) for i, k in _tree_edges(every)]
    on_line = [P for P in joints if np.linalg.norm(P - foot(P)) <= tol]
    arms = [(foot(P), P) for P in attached if np.linalg.norm(P - foot(P)) > tol]
    along = [float((P - origin) @ u) for P in on_line + [f for f, _ in arms] + attached]
    paths = [np.vstack([a, b]) for a, b in arms]
    if max(along) - min(along) > tol:
        paths.insert(0, np.vstack([origin + min(along) * u, origin + max(along) * u]))
    return paths


def _axis_line(model: Model, body: str, tol: float) -> tuple[FloatArray, FloatArray] | None:
    """The line (a point, a unit direction) the body's joint centres sit on:
    through the two farthest apart, or a lone joint's axis; None when they do
    not sit on one line."""
    joints = [j for j in model.joints if body in j.between]
    centres = _unique([j.centre for j in joints])
    if not centres:
        return None
    if len(centres) == 1:
        return centres[0], joints[0].R_world_joint[:, 0]
    C = np.array(centres)
    d = np.linalg.norm(C[:, None, :] - C[None, :, :], axis=2)
    i, k = np.unravel_index(int(np.argmax(d)), d.shape)
    u = (C[k] - C[i]) / d[i, k]
    off = C - C[i] - np.outer((C - C[i]) @ u, u)
    return (C[i], u) if float(np.max(np.linalg.norm(off, axis=1))) <= tol else None


def _span(points: list[FloatArray]) -> float:
    P = np.array(points)
    return float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))) if len(P) else 0.0


def _tree_edges(points: list[FloatArray]) -> list[tuple[int, int]]:
    """Edges of the shortest tree through ``points`` (a plate's become a frame)."""
    if len(points) < 2:
        return []
    from scipy.sparse.csgraph import minimum_spanning_tree

    P = np.array(points)
    d = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=2)
    tree = minimum_spanning_tree(d).tocoo()
    return sorted((int(min(i, k)), int(max(i, k))) for i, k in zip(tree.row, tree.col, strict=True))


def _size(points: FloatArray, model: Model) -> float:
    span = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 0.0
    joint_size = max((j.size for j in model.joints), default=0.0)
    return max(span, joint_size, 1.0)


def circle(centre: FloatArray, u: FloatArray, v: FloatArray, radius: float) -> FloatArray:
    """(CIRCLE_POINTS, 3): a circle in the plane of the unit vectors u, v."""
    t = np.linspace(0.0, 2.0 * np.pi, CIRCLE_POINTS)
    return np.asarray(centre + radius * (np.outer(np.cos(t), u) + np.outer(np.sin(t), v)))


def _domain_glyph(
    joint: Joint, cone: Contact, at: FloatArray, m: float, size: float
) -> list[FloatArray]:
    """The contact's clearance domain drawn at ``at`` (mm, global), its play
    multiplied by m: a sphere (three great circles), a circle across the
    directions it limits, an interval, a face's disc or a plane's square."""
    R = joint.R_world_joint
    if cone.kind == "fixed":
        return []
    if cone.offset is not None:  # a face (disc rim) or a one-sided plane
        # offset @ tau <= radius: the wall is where the motion along the offset reaches the play
        normal = R @ cone.offset[:3]
        n = normal / np.linalg.norm(normal) if np.linalg.norm(normal) > 0 else R[:, 0]
        u, v = R[:, 1], R[:, 2]
        if cone.lever is not None:  # a disc face: its rim, at the play from the centre
            rim = float(cone.lever[1, 0])
            return [circle(at + n * m * cone.radius, u, v, rim)]
        half = 0.06 * size  # a plane: a square the point may not go through
        c = at + n * m * cone.radius
        corners = [c + half * (su * u + sv * v) for su, sv in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
        return [np.vstack([*corners, corners[0]])]
    if cone.turn_lever is not None:  # a drive limits a spin, no point's position
        return []
    directions = cone.rows[:, :3]
    r = m * cone.radius
    world = directions @ R.T  # each limited direction in global axes
    k = len(directions)
    if k == 3:
        x, y, z = R[:, 0], R[:, 1], R[:, 2]
        return [circle(at, y, z, r), circle(at, x, y, r), circle(at, x, z, r)]
    if k == 2:
        u = world[0] / np.linalg.norm(world[0])
        v = world[1] / np.linalg.norm(world[1])
        return [circle(at, u, v, r)]
    if k == 1:
        u = world[0] / np.linalg.norm(world[0])
        return [np.vstack([at - r * u, at + r * u])]
    return []


# -- one joint, seen along its axis ------------------------------------------------
@dataclass(frozen=True)
class ViewPoint:
    """Where a contact point of b went, in the view's plane (mm)."""

    at: tuple[float, float]
    label: str
    touching: bool


@dataclass(frozen=True)
class JointView:
    """One joint at true size, in its own frame.

    ``plane == "yz"``: seen along the joint axis (the paper's figure 6):
    ``circles`` are clearance circles (radius, mm; ``sphere`` marks a
    sphere's section, cut at the contact point's x), ``rectangle`` the half
    plays (y, z) of a slider (``inf``: free that way, a pin in a slot).
    ``plane == "x-across"``: seen across the axis,
    for a face or a plane: ``walls`` are the positions along x that b may not
    pass; ``outline`` is b's face. ``note`` says what the view cannot show (a
    revolute joint's axial play).
    """

    joint: str
    type: str
    plane: Literal["yz", "x-across", "none"]
    circles: tuple[tuple[float, bool], ...]  # (radius, is a sphere's section)
    rectangle: tuple[float, float] | None
    walls: tuple[float, ...]
    points: tuple[ViewPoint, ...]
    outline: tuple[tuple[float, float], ...]
    note: str
    #: The joint frame's x, y, z in global words ('global +Z', or a vector).
    axes: tuple[str, str, str] = ("x", "y", "z")

    @property
    def reach(self) -> float:
        """Half the size of the view (mm); 0 when nothing in it has a size (a
        point touching its plane with no gap)."""
        spans = [r for r, _ in self.circles] + [abs(w) for w in self.walls]
        if self.rectangle is not None:
            spans += [h for h in self.rectangle if math.isfinite(h)]
        spans += [max(abs(p.at[0]), abs(p.at[1])) for p in self.points if self.plane == "yz"]
        spans += [abs(p.at[0]) for p in self.points]
        return max(spans, default=0.0)


def joint_view(joint: Joint, jr: JointResult) -> JointView:
    """The picture of one joint at true size: its clearance domain seen along
    its axis (or across it, for a face or a plane) and where b's contact
    points went, with the joint frame's axes named in global terms."""
    axes = tuple(describe_direction(jr.R_world_joint[:, i], signed=True) for i in range(3))
    return replace(_joint_view(joint, jr), axes=(axes[0], axes[1], axes[2]))


def _joint_view(joint: Joint, jr: JointResult) -> JointView:
    t, w = np.asarray(jr.translation), np.asarray(jr.rotation)

    def delta(p: FloatArray) -> FloatArray:
        return np.asarray(t + np.cross(w, p))

    cones = joint.cones
    if all(c.kind == "fixed" for c in cones):
        return JointView(
            joint.name, joint.type_name, "none", (), None, (), (), (), "rigid: no play"
        )
    across = [c for c in cones if c.offset is not None or _limits_only_x(c)]
    if across and len(across) == len([c for c in cones if c.kind == "ball"]):
        return _across_view(joint, jr, delta)

    circles: list[tuple[float, bool]] = []
    half_y: float | None = None
    half_z: float | None = None
    points: list[ViewPoint] = []
    notes: list[str] = []
    for cone, contact in zip(cones, jr.contacts, strict=True):
        d = delta(cone.point)
        if cone.turn_lever is not None:  # a drive: the spin, which no picture of a point shows
            notes.append(
                f"{contact.name} (spin): {w[0]:+.4g} rad of ±{cone.radius / cone.turn_lever:.4g} "
                "rad" + (" (touching)" if contact.in_contact else "")
            )
            continue
        dirs = "".join(_axis_name(row) for row in cone.rows[:, :3]) if cone.kind == "ball" else ""
        if dirs == "x":  # an axial stop: not seen along the axis
            notes.append(
                f"{contact.name} (along x): {d[0]:+.4g} mm of ±{cone.radius:.4g} mm"
                + (" (touching)" if contact.in_contact else "")
            )
            continue
        if dirs in ("xyz", "yz"):
            # a sphere is cut where the contact point is (x = dx): a touching
            # point lies on that section, not on the sphere's equator
            radius = (
                math.sqrt(max(cone.radius**2 - d[0] ** 2, 0.0)) if dirs == "xyz" else cone.radius
            )
            entry = (radius, dirs == "xyz")
            if entry not in circles:
                circles.append(entry)
        elif dirs == "y":
            half_y = cone.radius
        elif dirs == "z":
            half_z = cone.radius
        label = contact.name + (f" (δx {d[0]:+.3g})" if dirs == "xyz" else "")
        points.append(ViewPoint((float(d[1]), float(d[2])), label, contact.in_contact))
    points = _merged(points, 1e-6 * max((r for r, _ in circles), default=1.0))
    rectangle = None
    if half_y is not None or half_z is not None:  # a direction with no limit is free (a slot)
        rectangle = (
            math.inf if half_y is None else half_y,
            math.inf if half_z is None else half_z,
        )
    return JointView(
        joint.name,
        joint.type_name,
        "yz",
        tuple(circles),
        rectangle,
        (),
        tuple(points),
        (),
        "; ".join(notes),
    )


def _merged(points: list[ViewPoint], tol: float) -> list[ViewPoint]:
    """One marker for the contacts that sit at the same place (a slider's
    edges seen end on), their names joined in short (``_joined``)."""
    groups: list[tuple[ViewPoint, list[str], bool]] = []
    for p in points:
        for i, (q, names, touching) in enumerate(groups):
            if math.dist(p.at, q.at) <= tol:
                groups[i] = (q, [*names, p.label], touching or p.touching)
                break
        else:
            groups.append((p, [p.label], p.touching))
    return [ViewPoint(q.at, _joined(names), touching) for q, names, touching in groups]


def _joined(names: list[str]) -> str:
    """Contact names joined, those that differ only in one word's sign written
    once with ±: a slider's eight edges seen end on read 'y x± z±, z x± y±'."""
    words = [name.split(" ") for name in names]
    merged = True
    while merged:
        merged = False
        for i, a in enumerate(words):
            for k in range(i + 1, len(words)):
                b = words[k]
                differ = [n for n in range(len(a)) if len(a) == len(b) and a[n] != b[n]]
                if len(differ) == 1 and {a[differ[0]][-1:], b[differ[0]][-1:]} == {"-", "+"}:
                    n = differ[0]
                    if a[n][:-1] == b[n][:-1]:
                        words[i] = [*a[:n], a[n][:-1] + "±", *a[n + 1 :]]
                        del words[k]
                        merged = True
                        break
            if merged:
                break
    return ", ".join(" ".join(w) for w in words)


def _axis_name(row: FloatArray) -> str:
    k = int(np.argmax(np.abs(row)))
    return "xyz"[k] if abs(abs(row[k]) - 1.0) < 1e-12 and np.sum(np.abs(row)) - 1.0 < 1e-12 else "?"


def _limits_only_x(cone: Contact) -> bool:
    return cone.kind == "ball" and cone.rows.shape[0] == 1 and _axis_name(cone.rows[0, :3]) == "x"


def _across_view(
    joint: Joint, jr: JointResult, move: Callable[[FloatArray], FloatArray]
) -> JointView:
    """A face or a plane seen across the axis: x (the normal) across the page,
    the position on the face up the page."""
    walls: set[float] = set()
    points: list[ViewPoint] = []
    outline: list[tuple[float, float]] = []
    w = np.asarray(jr.rotation)
    for cone, contact in zip(joint.cones, jr.contacts, strict=True):
        if cone.kind == "fixed":
            continue
        if cone.one_sided:  # a point on a plane: -dx <= gap
            walls.add(-cone.radius)
            d = move(cone.point)
            points.append(ViewPoint((float(d[0]), 0.0), contact.name, contact.in_contact))
        elif cone.offset is not None and cone.lever is not None:  # a disc face
            walls.update((cone.radius, -cone.radius))
            rim = float(cone.lever[1, 0])
            tilt = np.array([-w[2], w[1]])  # where the rim goes furthest along +x
            n = float(np.linalg.norm(tilt))
            u = tilt / n if n > 1e-15 else np.array([1.0, 0.0])
            ends = [np.array([0.0, s * rim * u[0], s * rim * u[1]]) for s in (-1.0, 1.0)]
            outline = [(float(move(p)[0]), s * rim) for p, s in zip(ends, (-1.0, 1.0), strict=True)]
            side = float(np.sign(cone.offset[0]))
            top = ends[1] if side > 0 else ends[0]
            points.append(
                ViewPoint(
                    (float(move(top)[0]), rim if side > 0 else -rim),
                    contact.name,
                    contact.in_contact,
                )
            )
        else:  # a corner of a rectangular face
            walls.update((cone.radius, -cone.radius))
            d = move(cone.point)
            points.append(
                ViewPoint((float(d[0]), float(cone.point[1])), contact.name, contact.in_contact)
            )
    return JointView(
        joint.name,
        joint.type_name,
        "x-across",
        (),
        None,
        tuple(sorted(walls)),
        tuple(points),
        tuple(outline),
        "",
    )
