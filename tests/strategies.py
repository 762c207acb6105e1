"""Hypothesis strategies: random mechanisms whose boundedness is known by design.

A mechanism is a ground body and 1 to 7 moving bodies in a random tree: each
moving body hangs on an earlier body (or the ground) by a *holding set* of
joints, chosen so that together they hold every relative motion (their free
motions intersect in nothing; the geometry is chosen so, never tested):

- ``rigid``: one rigid joint;
- ``three_spheres``: spherical joints at c, c + a e1, c + b e2 (a triangle);
- ``shaft_and_stop``: the paper's shaft (spherical at c, cylindrical along e1
  at c + a e1) whose spin about e1 a sphere_in_cylinder (bore along e1) at
  c + b e2 holds;
- ``hinge_and_stop``: a revolute about e1 whose spin a sphere_in_cylinder
  (bore along e1) at c + b e2 holds;
- ``hinge_and_points``: a revolute about e1 whose spin two opposed point
  contacts at c + b e2 (plane normals +e3 and -e3) hold;
- ``slider_and_face``: a prismatic along e1 whose slide a planar joint
  (normal e1, rectangle or disc) holds;
- ``plate_and_pins``: a planar joint (normal e1, rectangle or disc) with two
  sphere_in_cylinder pins (bores along e1) at two points of its plane;
- ``crossed_bores``: cylindrical joints along e1 at c and along e3 at c + a e2.

A held tree is bounded under any loads, and so is it with more joints: up
to three *extra* joints of random types between random bodies close loops
and only shrink the feasible set. A leaf may instead be a ``table``: a body
on three point contacts (plane normal e1) with two sphere_in_cylinder pins in
the feet's plane; pushed down (along -e1) inside the feet's triangle it is
held, pulled up or pushed outside the triangle it lifts or tips.

An *unbounded* mechanism is a held tree plus one leaf that its joints leave
free along a known motion (a spin, a slide, lifting or tipping), which a load
drives; no extra joint touches that leaf.

Numbers are plain (mm, N, N*mm, N/mm): positions within 300 mm of the origin,
clearances log-uniform from 1 um to 5 mm, forces from 0.01 to 1000 N,
stiffnesses from 10 to 1e6 N/mm.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from hypothesis import strategies as st

from reference import default_up, frame

Vec = np.ndarray
Draw = Callable[[st.SearchStrategy[Any]], Any]

JOINT_TYPES = (
    "spherical",
    "cylindrical",
    "revolute",
    "sphere_in_cylinder",
    "prismatic",
    "planar",
    "point",
    "rigid",
)


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: float(10.0**e))


def reals(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False, allow_subnormal=False)


plays = log_uniform(1e-3, 5.0)  # mm: diametral clearance, 1 um to 5 mm
lengths = reals(5.0, 150.0)  # mm: joint lengths, faces, lever arms
stiffnesses = log_uniform(10.0, 1e6)  # N/mm
magnitudes = log_uniform(1e-2, 1e3)  # N
points = st.tuples(reals(-300, 300), reals(-300, 300), reals(-300, 300)).map(np.array)


def _unit(polar: float, azimuth: float) -> Vec:
    return np.array(
        [math.sin(polar) * math.cos(azimuth), math.sin(polar) * math.sin(azimuth), math.cos(polar)]
    )


#: Unit vectors: +Z (a special case of the default 'up') is the simplest.
directions = st.builds(_unit, reals(0, math.pi), reals(-math.pi, math.pi))


@st.composite
def across(draw: Draw, axis: Vec) -> Vec:
    """A direction at least ~17 degrees (asin 0.3) away from ``axis`` and its opposite."""
    R = frame(axis)
    tilt = draw(reals(math.asin(0.3), math.pi - math.asin(0.3)))
    turn = draw(reals(-math.pi, math.pi))
    return math.cos(tilt) * R[:, 0] + math.sin(tilt) * (
        math.cos(turn) * R[:, 1] + math.sin(turn) * R[:, 2]
    )


@st.composite
def frames(draw: Draw) -> tuple[Vec, Vec, Vec]:
    """Three orthonormal directions (the frame of a holding set)."""
    axis = draw(directions)
    R = frame(axis, draw(across(axis)))
    return R[:, 0], R[:, 1], R[:, 2]


def _list(v: Vec) -> list[float]:
    return [float(c) for c in v]


@dataclass
class Build:
    """Draws joints and loads with the model's shared choices."""

    draw: Draw
    compliant: bool

    def joint(self, kind: str, a: str, b: str, at: Vec, axis: Vec, **more: Any) -> dict[str, Any]:
        out: dict[str, Any] = {"type": kind, "between": [a, b], "at": _list(at)}
        out["axis"] = _list(axis)
        if self.draw(st.booleans()):  # else the default 'up' (docs/conventions.md)
            out["up"] = _list(self.draw(across(axis)))
        if kind in ("spherical", "cylindrical", "revolute", "sphere_in_cylinder", "planar"):
            out["clearance"] = self.draw(plays)
        if kind in ("cylindrical", "revolute"):
            out["length"] = self.draw(lengths)
        if kind == "revolute":
            out["axial_clearance"] = self.draw(plays)
        if kind == "prismatic":
            for key in ("length", "width", "height"):
                out[key] = self.draw(lengths)
            out["clearance_y"], out["clearance_z"] = self.draw(plays), self.draw(plays)
        if kind == "planar":
            if self.draw(st.booleans()):
                out["diameter"] = self.draw(lengths)
            else:
                out["width"], out["height"] = self.draw(lengths), self.draw(lengths)
        if kind == "point" and self.draw(st.booleans()):
            out["gap"] = self.draw(plays)
        if kind != "rigid" and self.compliant and self.draw(st.booleans()):
            out["stiffness"] = self.draw(stiffnesses)
        out.update(more)
        return out

    def load(
        self,
        body: str,
        *,
        at: Vec | None = None,
        force: Vec | None = None,
        torque: Vec | None = None,
    ) -> dict[str, Any]:
        out: dict[str, Any] = {"body": body}
        if force is not None:
            out["at"], out["force"] = _list(at if at is not None else np.zeros(3)), _list(force)
        if torque is not None:
            out["torque"] = _list(torque)
        return out

    def random_load(self, body: str) -> dict[str, Any]:
        """A force at a point, a torque (N*mm, a force at 100 mm), or both."""
        which = self.draw(st.sampled_from(["force", "torque", "both"]))
        force = self.draw(magnitudes) * self.draw(directions) if which != "torque" else None
        torque = 100 * self.draw(magnitudes) * self.draw(directions) if which != "force" else None
        return self.load(body, at=self.draw(points), force=force, torque=torque)


# -- holding sets: every relative motion held ------------------------------------


def _rigid(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[dict[str, Any]]:
    return [bd.joint("rigid", a, b, c, e[0])]


def _three_spheres(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[Any]:
    corners = [c, c + bd.draw(lengths) * e[0], c + bd.draw(lengths) * e[1]]
    return [bd.joint("spherical", a, b, p, bd.draw(directions)) for p in corners]


def _shaft(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[Any]:
    return [
        bd.joint("spherical", a, b, c, e[0]),
        bd.joint("cylindrical", a, b, c + bd.draw(lengths) * e[0], e[0]),
    ]


def _shaft_and_stop(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[Any]:
    stop = bd.joint("sphere_in_cylinder", a, b, c + bd.draw(lengths) * e[1], e[0])
    return [*_shaft(bd, a, b, c, e), stop]


def _hinge_and_stop(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[Any]:
    return [
        bd.joint("revolute", a, b, c, e[0]),
        bd.joint("sphere_in_cylinder", a, b, c + bd.draw(lengths) * e[1], e[0]),
    ]


def _hinge_and_points(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[Any]:
    arm = c + bd.draw(lengths) * e[1]
    return [
        bd.joint("revolute", a, b, c, e[0]),
        bd.joint("point", a, b, arm, e[2]),
        bd.joint("point", a, b, arm, -e[2]),
    ]


def _slider_and_face(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[Any]:
    face = c + bd.draw(reals(-150, 150)) * e[1] + bd.draw(reals(-150, 150)) * e[2]
    return [bd.joint("prismatic", a, b, c, e[0]), bd.joint("planar", a, b, face, e[0])]


def _plate_and_pins(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[Any]:
    pins = [c + bd.draw(lengths) * e[1], c + bd.draw(lengths) * e[2]]
    return [
        bd.joint("planar", a, b, c, e[0]),
        *(bd.joint("sphere_in_cylinder", a, b, p, e[0]) for p in pins),
    ]


def _crossed_bores(bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]) -> list[Any]:
    return [
        bd.joint("cylindrical", a, b, c, e[0]),
        bd.joint("cylindrical", a, b, c + bd.draw(lengths) * e[1], e[2]),
    ]


HOLDING = {
    "rigid": _rigid,
    "three_spheres": _three_spheres,
    "shaft_and_stop": _shaft_and_stop,
    "hinge_and_stop": _hinge_and_stop,
    "hinge_and_points": _hinge_and_points,
    "slider_and_face": _slider_and_face,
    "plate_and_pins": _plate_and_pins,
    "crossed_bores": _crossed_bores,
}


# -- leaves with a known free motion ----------------------------------------------

#: A free twist of a leaf: (rotation W, translation V at the origin), global axes.
Twist = tuple[Vec, Vec]


def _spin(axis: Vec, through: Vec) -> Twist:
    return axis, np.cross(through, axis)  # V at O = W x (O - p)


def _slide(direction: Vec) -> Twist:
    return np.zeros(3), direction


def _free_leaf(
    bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]
) -> tuple[str, list[Any], Twist]:
    """Joints that leave one known motion free (both ways), and that motion."""
    kind = bd.draw(
        st.sampled_from(
            [
                "shaft",
                "hinge",
                "two_spheres",
                "slider",
                "bore",
                "plate_and_pin",
                "ball",
                "parallel_bores",
                "slider_and_pins",
            ]
        )
    )
    far = c + bd.draw(lengths) * e[1]
    if kind == "shaft":  # the paper's shaft: spin about the line through both centres
        return kind, _shaft(bd, a, b, c, e), _spin(e[0], c)
    if kind == "hinge":
        return kind, [bd.joint("revolute", a, b, c, e[0])], _spin(e[0], c)
    if kind == "two_spheres":  # three_spheres less one: spin about the line through two
        joints = [bd.joint("spherical", a, b, p, bd.draw(directions)) for p in (c, far)]
        return kind, joints, _spin(e[1], c)
    if kind == "slider":
        return kind, [bd.joint("prismatic", a, b, c, e[0])], _slide(e[0])
    if kind == "bore":  # a lone cylindrical: slide or spin
        motion = _slide(e[0]) if bd.draw(st.booleans()) else _spin(e[0], c)
        return kind, [bd.joint("cylindrical", a, b, c, e[0])], motion
    if kind == "plate_and_pin":  # plate_and_pins less one: spin about the pin's bore
        joints = [
            bd.joint("planar", a, b, c, e[0]),
            bd.joint("sphere_in_cylinder", a, b, far, e[0]),
        ]
        return kind, joints, _spin(e[0], far)
    if kind == "ball":  # any rotation about the ball's centre
        return kind, [bd.joint("spherical", a, b, c, e[0])], _spin(bd.draw(directions), c)
    if kind == "parallel_bores":  # two parallel cylindricals: slide along them
        joints = [bd.joint("cylindrical", a, b, p, e[0]) for p in (c, far)]
        return kind, joints, _slide(e[0])
    # slider_and_pins: a prismatic along e1 and pins whose bores are along e1
    joints = [
        bd.joint("prismatic", a, b, c, e[0]),
        bd.joint("sphere_in_cylinder", a, b, far, e[0]),
    ]
    return kind, joints, _slide(e[0])


def _table(
    bd: Build, a: str, b: str, c: Vec, e: tuple[Vec, Vec, Vec]
) -> tuple[list[Any], list[Vec]]:
    """Three point contacts (plane normal e1) around c and two pins (bores along
    e1) in the feet's plane; returns the joints and the feet."""
    phase = bd.draw(reals(0, 2 * math.pi))
    feet = []
    for i in range(3):
        angle = phase + 2 * math.pi * i / 3 + bd.draw(reals(-0.5, 0.5))
        feet.append(c + bd.draw(lengths) * (math.cos(angle) * e[1] + math.sin(angle) * e[2]))
    pins = [c, c + bd.draw(lengths) * bd.draw(st.sampled_from([e[1], e[2], -e[1], -e[2]]))]
    joints = [bd.joint("point", a, b, f, e[0]) for f in feet]
    joints += [bd.joint("sphere_in_cylinder", a, b, p, e[0]) for p in pins]
    return joints, feet


def _table_loads(
    bd: Build, body: str, c: Vec, e: tuple[Vec, Vec, Vec], feet: list[Vec], how: str
) -> list[dict[str, Any]]:
    """``how``: 'push' inside the feet (held), 'lift' or 'tip' (driven). The
    other loads, in-plane forces in the feet's plane and torques about e1,
    do no work on lifting or tilting."""
    out = []
    for _ in range(bd.draw(st.integers(0, 2))):
        in_plane = bd.draw(magnitudes) * (
            bd.draw(reals(-1, 1)) * e[1] + bd.draw(reals(-1, 1)) * e[2]
        )
        at = c + bd.draw(reals(-200, 200)) * e[1] + bd.draw(reals(-200, 200)) * e[2]
        out.append(bd.load(body, at=at, force=in_plane))
    if bd.draw(st.booleans()):
        out.append(
            bd.load(
                body, torque=100 * bd.draw(magnitudes) * bd.draw(st.sampled_from([-1, 1])) * e[0]
            )
        )
    weights = np.array([bd.draw(reals(0.05, 1.0)) for _ in range(3)])
    weights /= weights.sum()
    if how == "tip":  # one barycentric coordinate negative: outside the triangle
        k = bd.draw(st.integers(0, 2))
        weights[k] = -bd.draw(reals(0.05, 2.0))
        others = [i for i in range(3) if i != k]
        weights[others] *= (1 - weights[k]) / weights[others].sum()
    where = sum(w * f for w, f in zip(weights, feet, strict=True)) + bd.draw(reals(-50, 50)) * e[0]
    sense = 1.0 if how == "lift" else -1.0
    if how == "lift":
        where = bd.draw(points)
    out.append(bd.load(body, at=where, force=sense * bd.draw(magnitudes) * e[0]))
    return out


@dataclass
class Mechanism:
    """A model dict (plain numbers) and what its design says about it."""

    data: dict[str, Any]
    unbounded: bool
    design: list[str]


@st.composite
def mechanisms(
    draw: Draw,
    *,
    min_bodies: int = 2,
    max_bodies: int = 8,
    compliant: bool | None = None,
    unbounded: bool = False,
    tables: bool = True,
) -> Mechanism:
    """A random mechanism of ``min_bodies`` to ``max_bodies`` bodies (ground
    included), held by design, or (``unbounded``) with one leaf whose free
    motion the loads drive. ``compliant``: whether joints may have stiffness
    (None: drawn)."""
    if compliant is None:
        compliant = draw(st.booleans())
    bd = Build(draw, compliant)
    n = draw(st.integers(min_bodies, max_bodies))
    names = ["G"] + [f"B{i}" for i in range(1, n)]
    joints: list[dict[str, Any]] = []
    loads: list[dict[str, Any]] = []
    design: list[str] = []
    twist: Twist | None = None  # the free leaf's driven motion
    # the last body is a special leaf: free (unbounded) or a table (maybe)
    special = unbounded or (tables and n > 1 and draw(st.booleans()))
    held = names[1:-1] if special else names[1:]
    for i, body in enumerate(held, start=1):
        parent = draw(st.sampled_from(names[:i]))
        how = draw(st.sampled_from(sorted(HOLDING)))
        joints += HOLDING[how](bd, parent, body, draw(points), draw(frames()))
        design.append(f"{body} on {parent}: {how}")
    leaf = names[-1]
    if special:
        parent = draw(st.sampled_from(names[:-1]))
        c, e = draw(points), draw(frames())
        if unbounded and draw(st.booleans()):  # a bilateral free motion, driven
            kind, leaf_joints, twist = _free_leaf(bd, parent, leaf, c, e)
            joints += leaf_joints
            design.append(f"{leaf} on {parent}: {kind} (free, driven)")
        else:
            how = draw(st.sampled_from(["lift", "tip"])) if unbounded else "push"
            table, feet = _table(bd, parent, leaf, c, e)
            joints += table
            loads += _table_loads(bd, leaf, c, e, feet, how)
            design.append(f"{leaf} on {parent}: table, {how}")
    # extra joints close loops (never on a free leaf)
    pool = names[:-1] if unbounded else names
    for _ in range(draw(st.integers(0, 3)) if len(pool) > 1 else 0):
        a = draw(st.sampled_from(pool))
        b = draw(st.sampled_from([p for p in pool if p != a]))
        kind = draw(st.sampled_from(JOINT_TYPES))
        joints.append(bd.joint(kind, a, b, draw(points), draw(directions)))
        design.append(f"extra {kind} {a}-{b}")
    movers = [b for b in names[1:] if not (special and b == leaf)]
    for _ in range(draw(st.integers(0 if special else 1, 4)) if movers else 0):
        loads.append(bd.random_load(draw(st.sampled_from(movers))))
    if twist is not None:
        loads.append(_drive(bd, leaf, twist, loads))
    for k, joint in enumerate(joints):
        joint["name"] = f"j{k}"
    data = {"bodies": [{"name": "G", "ground": True}] + [{"name": b} for b in names[1:]]}
    data["joints"] = [{"name": j.pop("name"), **j} for j in joints]
    data["loads"] = loads
    return Mechanism(data, unbounded, design)


def work_on(loads: list[dict[str, Any]], body: str, twist: Twist) -> float:
    """N*mm per unit twist: the loads on ``body`` working on its motion ``twist``."""
    W, V = twist
    out = 0.0
    for ld in loads:
        if ld["body"] != body:
            continue
        if "force" in ld:
            out += float(np.dot(ld["force"], V + np.cross(W, ld["at"])))
        if "torque" in ld:
            out += float(np.dot(ld["torque"], W))
    return out


def _drive(bd: Build, body: str, twist: Twist, loads: list[dict[str, Any]]) -> dict[str, Any]:
    """A load whose work on ``twist``, with the other loads on ``body``, is
    positive and at least half of the drive's own work."""
    W, V = twist
    rest = work_on(loads, body, twist)
    if np.any(W) and bd.draw(st.booleans()):  # a torque about the spin axis
        unit = bd.load(body, torque=100 * W)
    else:  # a force at a random point whose work on the twist is not small
        at = bd.draw(points)
        velocity = V + np.cross(W, at)
        if np.linalg.norm(velocity) < 1e-3:
            at = at + 50 * frame(W)[:, 1]
            velocity = V + np.cross(W, at)
        unit = bd.load(body, at=at, force=velocity / np.linalg.norm(velocity))
    own = work_on([unit], body, twist)
    size = (2 * abs(rest) + bd.draw(magnitudes) * own) / own
    for key in ("force", "torque"):
        if key in unit:
            unit[key] = [size * v for v in unit[key]]
    return unit


# -- the same model, moved or in other units -----------------------------------------


def moved(data: dict[str, Any], R: Vec, t: Vec) -> dict[str, Any]:
    """The whole model turned by R and shifted by t: joint centres, axes and
    'up' vectors (a default one turned too), load points and vectors."""
    out = copy.deepcopy(data)
    for j in out["joints"]:
        axis = np.array(j.get("axis", [1.0, 0.0, 0.0]))
        up = np.array(j["up"]) if "up" in j else default_up(axis)
        j["at"] = _list(R @ np.array(j["at"]) + t)
        j["axis"], j["up"] = _list(R @ axis), _list(R @ up)
    for ld in out["loads"]:
        if "at" in ld:
            ld["at"] = _list(R @ np.array(ld["at"]) + t)
        for key in ("force", "torque"):
            if key in ld:
                ld[key] = _list(R @ np.array(ld[key]))
    return out


#: unit -> size in the base unit of its dimension
UNITS = {
    "length": {"um": 1e-3, "mm": 1.0, "cm": 10.0, "m": 1e3, "inch": 25.4},
    "force": {"N": 1.0, "mN": 1e-3, "kN": 1e3},
    "torque": {"N*mm": 1.0, "N*m": 1e3, "mN*m": 1.0, "kN*mm": 1e3},
    "stiffness": {"N/mm": 1.0, "N/um": 1e3, "kN/mm": 1e3, "N/m": 1e-3},
}
LENGTH_KEYS = (
    "clearance",
    "axial_clearance",
    "clearance_y",
    "clearance_z",
    "gap",
    "length",
    "width",
    "height",
    "diameter",
)


@st.composite
def in_units(draw: Draw, data: dict[str, Any]) -> dict[str, Any]:
    """The same model with every quantity a string in a randomly chosen unit
    (each number rewritten as value / unit size, full precision)."""
    rng = draw(st.randoms(use_true_random=False))

    def text(value: float, dimension: str) -> str:
        unit, size = rng.choice(sorted(UNITS[dimension].items()))
        return f"{float(value) / size!r} {unit}"

    out = copy.deepcopy(data)
    for j in out["joints"]:
        j["at"] = [text(v, "length") for v in j["at"]]
        for key in LENGTH_KEYS:
            if key in j:
                j[key] = text(j[key], "length")
        if "stiffness" in j:
            j["stiffness"] = text(j["stiffness"], "stiffness")
    for ld in out["loads"]:
        if "at" in ld:
            ld["at"] = [text(v, "length") for v in ld["at"]]
        for key, dimension in (("force", "force"), ("torque", "torque")):
            if key in ld:
                ld[key] = [text(v, dimension) for v in ld[key]]
    return out
