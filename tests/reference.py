"""An independent reading of a model, for the property tests.

Nothing here imports the solver: the joint frames, the clearance domains of
every joint type, the loads' work and the energy are written again from
docs/joints.md and docs/conventions.md, for model dicts whose numbers are
plain (mm, N, N*mm, N/mm). A mechanism state is ``x``: per moving body, in
model order, its translation at the global origin V and its rotation vector
W (global axes), ``x = (V_1, W_1, V_2, W_2, ...)``.

Each contact of a joint is written as ``level(tau) = |rows @ tau| + offset @ tau``
(rows and offset in the joint's relative torsor ``tau = (t, w)``), to compare
with its play ``radius``; fixed contacts (``rigid``) are ``rows @ tau = 0``.
A contact with a ``stiffness`` k may go past its play by p at an energy k p^2 / 2.
A joint's deviation delta (its own ``deviation``, or a shared one of the
``deviations`` section, at their means) moves its domain: every contact bounds
``tau - delta``. A drive's spin row is written at a lever rho (its contact
force times rho is its torque); weights come from ``gravity`` and the bodies'
``mass``; ``case`` adds a load case's loads to the top-level ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import minimize

import jointplay


def frame(axis: Any, up: Any = None) -> np.ndarray:
    """Joint axes as columns (docs/conventions.md, "Joint frame")."""
    x = np.asarray(axis, dtype=float)
    x = x / math.sqrt(float(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]))
    if up is None:
        up = np.array([0.0, 0.0, 1.0])
        # the rule's sine of the angle to Z, rounded as jointplay rounds it:
        # an axis drawn at the threshold (1e-9 off Z) took the other 'up'
        # with |x cross Z| and gave a frame 6e-8 rad away
        if math.hypot(float(x[0]), float(x[1])) < 1e-9:
            up = np.array([-np.sign(x[2]), 0.0, 0.0])
    up = np.asarray(up, dtype=float)
    z = np.cross(x, np.cross(up, x))  # up - (up . x) x, without cancellation
    z = z / np.linalg.norm(z)
    return np.column_stack([x, np.cross(z, x), z])


def default_up(axis: Any) -> np.ndarray:
    """The 'up' vector that a joint without one gets (its frame's z axis)."""
    return frame(axis)[:, 2]


@dataclass
class Contact:
    joint: str
    name: str
    rows: np.ndarray  # (k, 6) on tau
    radius: float  # mm
    offset: np.ndarray | None = None  # (6,) on tau
    fixed: bool = False  # rows @ tau == 0
    stiffness: float = 0.0  # N/mm, 0: hard
    #: the joint's deviation (6,): the domain bounds tau - centre
    centre: np.ndarray = field(default_factory=lambda: np.zeros(6))
    #: mm per unit of the reported play (a drive's lever rho: its play is in rad)
    lever: float = 1.0

    def level(self, tau: np.ndarray) -> float:
        tau = np.asarray(tau, dtype=float) - self.centre
        out = float(np.linalg.norm(self.rows @ tau)) if len(self.rows) else 0.0
        if self.offset is not None:
            out += float(self.offset @ tau)
        return out


def _row(t: tuple[float, float, float], w: tuple[float, float, float]) -> list[float]:
    return [*t, *w]


def contacts_of(joint: dict[str, Any], delta: Any = None) -> list[Contact]:
    """The contacts of one joint, from the domains of docs/joints.md, about
    the joint's deviation ``delta`` (6,: t mm, w rad; None: 0).

    delta(p) = t + w x p; its components, written out:
    delta_x = t_x + w_y p_z - w_z p_y, delta_y = t_y + w_z p_x - w_x p_z,
    delta_z = t_z + w_x p_y - w_y p_x.

    A ball contact (no offset) of radius 0 and no stiffness is fixed: an ideal
    joint in its directions (docs/joints.md)."""
    kind, name = joint["type"], joint["name"]
    J = float(joint.get("clearance", 0.0))
    k = float(joint.get("stiffness", 0.0))
    centre = np.zeros(6) if delta is None else np.asarray(delta, dtype=float)

    def ball(cname: str, rows: list[list[float]], radius: float, **more: Any) -> Contact:
        more.setdefault("stiffness", k)
        rows_array = np.array(rows, dtype=float).reshape(-1, 6)
        fixed = radius == 0.0 and more["stiffness"] == 0.0 and more.get("offset") is None
        return Contact(name, cname, rows_array, radius, centre=centre, fixed=fixed, **more)

    def ends(length: float) -> list[Contact]:
        out = []
        for cname, s in (("end-", -1.0), ("end+", 1.0)):
            h = s * length / 2  # the end point (h, 0, 0)
            out.append(
                ball(cname, [_row((0, 1, 0), (0, 0, h)), _row((0, 0, 1), (0, -h, 0))], J / 2)
            )
        return out

    def axial(key: str = "axial_clearance") -> list[Contact]:
        if key not in joint:
            return []
        return [ball("axial", [_row((1, 0, 0), (0, 0, 0))], float(joint[key]) / 2)]

    def drive() -> list[Contact]:
        """|w_x| <= b/2, written at the lever rho = the joint's length (any
        lever gives the same energy: the row, play and spring scale together)."""
        if "backlash" not in joint:
            return []
        rho = float(joint["length"])
        kt = float(joint.get("torsional_stiffness", 0.0))
        row = [_row((0, 0, 0), (rho, 0, 0))]
        return [
            ball("drive", row, rho * float(joint["backlash"]) / 2, stiffness=kt / rho**2, lever=rho)
        ]

    if kind == "spherical":
        return [
            ball(
                "ball",
                [
                    _row((1, 0, 0), (0, 0, 0)),
                    _row((0, 1, 0), (0, 0, 0)),
                    _row((0, 0, 1), (0, 0, 0)),
                ],
                J / 2,
            )
        ]
    if kind == "cylindrical":
        return [*ends(float(joint["length"])), *axial(), *drive()]
    if kind == "revolute":
        return [*ends(float(joint["length"])), *axial(), *drive()]
    if kind == "sphere_in_cylinder":
        return [ball("radial", [_row((0, 1, 0), (0, 0, 0)), _row((0, 0, 1), (0, 0, 0))], J / 2)]
    if kind == "prismatic":
        jy = float(joint.get("clearance_y", J))
        jz = float(joint.get("clearance_z", J))
        L, w, h = (float(joint[key]) / 2 for key in ("length", "width", "height"))
        out = []
        for x in (-L, L):
            for z in (-h, h):  # delta_y at (x, 0, z)
                cname = f"y x{'+' if x > 0 else '-'} z{'+' if z > 0 else '-'}"
                out.append(ball(cname, [_row((0, 1, 0), (-z, 0, x))], jy / 2))
        for x in (-L, L):
            for y in (-w, w):  # delta_z at (x, y, 0)
                cname = f"z x{'+' if x > 0 else '-'} y{'+' if y > 0 else '-'}"
                out.append(ball(cname, [_row((0, 0, 1), (y, -x, 0))], jz / 2))
        return [*out, *axial()]
    if kind == "slot":
        L = float(joint["length"]) / 2
        out = []
        for cname, x in (("across-", -L), ("across+", L)):  # delta_z at (x, 0, 0)
            out.append(ball(cname, [_row((0, 0, 1), (0, -x, 0))], J / 2))
        if "slot_length" in joint:
            js = float(joint["slot_length"])
            for cname, x in (("along-", -L), ("along+", L)):  # delta_y at (x, 0, 0)
                out.append(ball(cname, [_row((0, 1, 0), (0, 0, x))], js / 2))
        return out
    if kind == "planar":
        if "diameter" in joint:
            R = float(joint["diameter"]) / 2
            tilt = [_row((0, 0, 0), (0, R, 0)), _row((0, 0, 0), (0, 0, R))]
            e_x = np.array(_row((1, 0, 0), (0, 0, 0)), dtype=float)
            return [
                ball("face x+", tilt, J / 2, offset=e_x),
                ball("face x-", tilt, J / 2, offset=-e_x),
            ]
        out = []
        for y in (-float(joint["width"]) / 2, float(joint["width"]) / 2):
            for z in (-float(joint["height"]) / 2, float(joint["height"]) / 2):
                cname = f"corner y{'+' if y > 0 else '-'} z{'+' if z > 0 else '-'}"
                out.append(ball(cname, [_row((1, 0, 0), (0, z, -y))], J / 2))
        return out
    if kind == "point":
        minus_tx = -np.array(_row((1, 0, 0), (0, 0, 0)), dtype=float)
        return [
            ball("plane", np.zeros((0, 6)).tolist(), float(joint.get("gap", 0.0)), offset=minus_tx)
        ]
    if kind == "rigid":
        return [Contact(name, "rigid", np.eye(6), 0.0, fixed=True)]
    raise ValueError(f"unknown joint type {kind!r}")


def joint_axes(joint: dict[str, Any]) -> np.ndarray:
    """A joint's frame: a slot's from its axis and 'along' (x = axis, y = the
    part of 'along' across it, z = x cross y), any other's from axis and up."""
    if joint["type"] != "slot":
        return frame(joint.get("axis", [1, 0, 0]), joint.get("up"))
    x = np.asarray(joint.get("axis", [1, 0, 0]), dtype=float)
    x = x / np.linalg.norm(x)
    y = np.asarray(joint["along"], dtype=float)
    y = y - (y @ x) * x
    y = y / np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def zone_mean(zones: dict[str, Any]) -> np.ndarray:
    """The mean torsor (t mm, w rad) of a deviation's zones (plain numbers):
    a position's ``mean`` or the middle of its per-axis limits, an
    orientation's ``mean``."""
    out = np.zeros(6)
    position = zones.get("position")
    if isinstance(position, dict):
        if "mean" in position:
            out[:3] = np.asarray(position["mean"], dtype=float)
        for i, axis in enumerate("xyz"):
            if axis in position:
                out[i] = (float(position[axis]["min"]) + float(position[axis]["max"])) / 2
    orientation = zones.get("orientation")
    if isinstance(orientation, dict) and "mean" in orientation:
        out[3:] = np.asarray(orientation["mean"], dtype=float)
    return out


def deviation_of(joint: dict[str, Any], R: np.ndarray, shared: dict[str, Any]) -> np.ndarray:
    """The joint's deviation torsor in its frame: its own zones' mean, or a
    shared group's carried to the joint's centre (formulation 3a: the group
    turns as one body; a joint whose b side is the group's body takes minus it)."""
    dev = joint.get("deviation")
    if dev is None:
        return np.zeros(6)
    if isinstance(dev, dict):
        return zone_mean(dev)
    group = shared[dev]
    Rs = frame(group.get("axis", [1, 0, 0]), group.get("up"))
    mean = zone_mean(group)
    t_global, w_global = Rs @ mean[:3], Rs @ mean[3:]
    lever = np.asarray(joint["at"], dtype=float) - np.asarray(group["at"], dtype=float)
    t_global = t_global + np.cross(w_global, lever)
    sign = 1.0 if joint["between"][0] == group["body"] else -1.0
    return sign * np.r_[R.T @ t_global, R.T @ w_global]


def acceleration(value: Any) -> float:
    """mm/s^2 from a plain number or a string '<number> m/s^2' (the only unit
    the campaign writes)."""
    if isinstance(value, str):
        number, unit = value.split(maxsplit=1)
        if unit.replace(" ", "") not in ("m/s^2", "m/s**2"):
            raise ValueError(f"unit {unit!r}: write gravity in m/s^2")
        return float(number) * 1e3
    return float(value)


@dataclass
class RefJoint:
    name: str
    type: str
    a: str
    b: str
    centre: np.ndarray
    R: np.ndarray
    contacts: list[Contact]
    G: np.ndarray = field(default_factory=lambda: np.zeros((6, 0)))  # tau = G @ x


@dataclass
class RefLoad:
    body: str
    at: np.ndarray | None
    force: np.ndarray
    torque: np.ndarray


class Reference:
    """The model re-read from its dict (plain numbers only)."""

    def __init__(self, data: dict[str, Any], case: str | None = None):
        self.data = data
        self.moving = [b["name"] for b in data["bodies"] if not b.get("ground", False)]
        self.index = {name: i for i, name in enumerate(self.moving)}
        self.m = 6 * len(self.moving)
        self.joints: list[RefJoint] = []
        shared = {d["name"]: d for d in data.get("deviations", [])}
        for j in data["joints"]:
            a, b = j["between"]
            R = joint_axes(j)
            delta = deviation_of(j, R, shared)
            rj = RefJoint(
                j["name"], j["type"], a, b, np.array(j["at"], float), R, contacts_of(j, delta)
            )
            rj.G = self._joint_map(rj)
            self.joints.append(rj)
        self.loads = [
            RefLoad(
                load["body"],
                None if "at" not in load else np.array(load["at"], float),
                np.array(load.get("force", [0, 0, 0]), float),
                np.array(load.get("torque", [0, 0, 0]), float),
            )
            for load in [*data.get("loads", []), *data.get("load_cases", {}).get(case, [])]
        ]
        gravity = np.array([acceleration(v) for v in data.get("gravity", [0, 0, 0])])
        for body in data["bodies"]:  # a weight m g (kg mm/s^2 = 1e-3 N) at the centre of mass
            if body["name"] in self.index and body.get("mass") and np.any(gravity):
                weight = float(body["mass"]) * gravity * 1e-3
                at = np.array(body["center_of_mass"], float)
                self.loads.append(RefLoad(body["name"], at, weight, np.zeros(3)))
        self.contacts = [c for rj in self.joints for c in rj.contacts]
        self.hard = [c for c in self.contacts if not c.fixed and c.stiffness == 0.0]
        self.soft = [c for c in self.contacts if not c.fixed and c.stiffness > 0.0]
        self.A_of = {id(c): c.rows @ rj.G for rj in self.joints for c in rj.contacts}
        self.b_of = {
            id(c): c.offset @ rj.G
            for rj in self.joints
            for c in rj.contacts
            if c.offset is not None
        }
        #: the deviation's part of each contact: |A x - a0| + b x - b0
        self.a0_of = {id(c): c.rows @ c.centre for c in self.contacts}
        self.b0_of = {
            id(c): float(c.offset @ c.centre) for c in self.contacts if c.offset is not None
        }
        fixed = [self.A_of[id(c)] for c in self.contacts if c.fixed]
        self.E = np.vstack(fixed) if fixed else np.zeros((0, self.m))
        spread = np.array([rj.centre for rj in self.joints])
        sizes = [
            float(j.get(k, 0.0))
            for j in data["joints"]
            for k in ("length", "width", "height", "diameter")
        ]
        #: mm: a length of the mechanism (how far its joints spread, or its
        #: largest joint): rotations times this length are displacements.
        self.length = max(
            1.0, float(np.max(np.linalg.norm(spread - spread.mean(axis=0), axis=1))), *sizes
        )
        radii = [c.radius for c in self.contacts if not c.fixed]
        #: mm: the largest play.
        self.play = max([r for r in radii if r > 0], default=1.0)
        #: x = D * y: translations in units of the play, rotations of play / length.
        self.D = np.tile(np.r_[np.ones(3), np.full(3, 1.0 / self.length)], len(self.moving))
        self.D *= self.play

    # -- kinematics -----------------------------------------------------------
    def _joint_map(self, rj: RefJoint) -> np.ndarray:
        """tau = (R^T (delta_b(C) - delta_a(C)), R^T (W_b - W_a)), delta(C) = V + W x C."""
        G = np.zeros((6, self.m))
        C = rj.centre
        minus_C_cross = -np.array([[0, -C[2], C[1]], [C[2], 0, -C[0]], [-C[1], C[0], 0]])
        for sign, body in ((-1.0, rj.a), (1.0, rj.b)):
            if body in self.index:
                i = 6 * self.index[body]
                G[:3, i : i + 3] += sign * rj.R.T
                G[:3, i + 3 : i + 6] += sign * rj.R.T @ minus_C_cross
                G[3:, i + 3 : i + 6] += sign * rj.R.T
        return G

    def x_of(self, result: jointplay.Result) -> np.ndarray:
        x = np.zeros(self.m)
        for name, i in self.index.items():
            br = result.bodies[name]
            x[6 * i : 6 * i + 3] = br.translation
            x[6 * i + 3 : 6 * i + 6] = br.rotation
        return x

    def g(self) -> np.ndarray:
        """Work of the loads per unit x: work = g @ x."""
        out = np.zeros(self.m)
        for ld in self.loads:
            i = 6 * self.index[ld.body]
            moment = ld.torque + (np.cross(ld.at, ld.force) if ld.at is not None else 0.0)
            out[i : i + 3] += ld.force
            out[i + 3 : i + 6] += moment
        return out

    def load_size(self) -> float:
        """N: the largest load, a torque counted as a force at the model length."""
        return max(
            [
                max(float(np.linalg.norm(ld.force)), float(np.linalg.norm(ld.torque)) / self.length)
                for ld in self.loads
            ],
            default=0.0,
        )

    # -- contacts -------------------------------------------------------------
    def levels(self, x: np.ndarray, which: list[Contact]) -> np.ndarray:
        out = np.zeros(len(which))
        for n, c in enumerate(which):
            v = self.A_of[id(c)] @ x - self.a0_of[id(c)]
            out[n] = (float(np.linalg.norm(v)) if len(v) else 0.0) + (
                float(self.b_of[id(c)] @ x) - self.b0_of[id(c)] if c.offset is not None else 0.0
            )
        return out

    def energy(self, x: np.ndarray) -> float:
        """N*mm: -(work of the loads) + the springs' energy, each spring at its
        least penetration p = max(level - radius, 0)."""
        out = -float(self.g() @ x)
        if self.soft:
            p = np.maximum(self.levels(x, self.soft) - np.array([c.radius for c in self.soft]), 0)
            out += float(np.sum(0.5 * np.array([c.stiffness for c in self.soft]) * p**2))
        return out

    def restore(self, x: np.ndarray) -> np.ndarray:
        """A feasible point near ``x``: fixed rows projected out, then the whole
        motion shrunk toward the centred position (feasible, and every level
        is convex, so the feasible part of the segment is [0, alpha]; without
        deviations alpha is found at once, every level being positively
        homogeneous) until every hard contact is within its play."""
        y = np.array(x, dtype=float)
        if len(self.E):
            y = y - np.linalg.pinv(self.E) @ (self.E @ y)
        if not self.hard:
            return y
        radii = np.array([c.radius for c in self.hard])
        # past by round-off (1e-13 of the largest play) is within: a point on
        # its plane (gap 0) that a motion leaves 1e-17 mm inside would else
        # shrink the whole motion to nothing
        within = radii + 1e-13 * self.play
        levels = self.levels(y, self.hard)
        over = levels > within
        if not np.any(over):
            return y
        if not any(np.any(c.centre) for c in self.hard) and np.all(radii[over] > 0):
            return y * float(np.min(radii[over] / levels[over])) * (1 - 1e-15)
        lo, hi = 0.0, 1.0
        for _ in range(60):
            mid = (lo + hi) / 2
            if np.all(self.levels(mid * y, self.hard) <= within):
                lo = mid
            else:
                hi = mid
        return lo * y

    def is_feasible(self, x: np.ndarray, tol: float = 0.0) -> bool:
        if len(self.E) and float(np.max(np.abs(self.E @ x))) > tol:
            return False
        radii = np.array([c.radius for c in self.hard])
        return not self.hard or bool(np.all(self.levels(x, self.hard) <= radii + tol))

    # -- the least-norm metric and the length scale (docs/conventions.md) -----
    def metric_length(self) -> float:
        """mm: l of the least-norm metric: the largest distance of a centre of
        a joint with play (not rigid) from those centres' centroid, or the
        largest joint size (a bore's length, a face's width or diameter, a
        slider's largest side) or contact radius if bigger."""
        play = [rj for rj in self.joints if rj.type != "rigid"]
        if not play:
            return max(1.0, self.length)
        centres = np.array([rj.centre for rj in play])
        spread = float(np.max(np.linalg.norm(centres - centres.mean(axis=0), axis=1)))
        sizes = []
        for j in self.data["joints"]:
            if j["type"] in ("cylindrical", "revolute", "slot"):
                sizes.append(float(j["length"]))
            elif j["type"] == "prismatic":
                sizes.append(max(float(j[k]) for k in ("length", "width", "height")))
            elif j["type"] == "planar":
                sizes.append(
                    float(j["diameter"])
                    if "diameter" in j
                    else max(float(j["width"]), float(j["height"]))
                )
        radii = [c.radius for c in self.contacts if not c.fixed]
        return max([spread, *sizes, *radii])

    def metric(self, x: np.ndarray) -> float:
        """mm^2: sum over the joints with play of |t|^2 + l^2 |w|^2."""
        ell = self.metric_length()
        out = 0.0
        for rj in self.joints:
            if rj.type != "rigid":
                tau = rj.G @ x
                out += float(tau[:3] @ tau[:3] + ell * ell * tau[3:] @ tau[3:])
        return out

    # -- recession: the motions no contact holds ------------------------------
    def driven_motion(
        self, zero: str | None = None, along: np.ndarray | None = None
    ) -> tuple[float, np.ndarray]:
        """The largest work of the loads g @ d over the motions d that no
        contact holds (a ball's rows unchanged, a disc face neither shifted
        nor tilted, a point not pushed into its plane, a weld closed; a spring
        holds like a hard contact, its energy growing with the square), d
        within +-1 in the units of ``D`` (a linear program, HiGHS).
        ``zero``: a body held still; ``along``: maximize ``along @ d``
        instead, among the motions on which the loads do at least half the
        largest work. Returns (the largest value, d)."""
        from scipy.optimize import linprog

        eq, ub = [], []
        for c in self.contacts:
            A = self.A_of[id(c)]
            if c.offset is None or c.fixed:
                eq.append(A)
            elif len(c.rows):  # a disc face: with its opposite, rows and offset
                eq += [A, self.b_of[id(c)][None, :]]
            else:  # a point: -t_x <= 0
                ub.append(self.b_of[id(c)][None, :])
        if zero is not None:
            i = 6 * self.index[zero]
            eq.append(np.eye(self.m)[i : i + 6])
        g = self.g() * self.D  # in the unknowns y, d = D y
        A_eq = np.vstack(eq) * self.D if eq else None
        A_ub = np.vstack(ub) * self.D if ub else np.zeros((0, self.m))
        b_ub = np.zeros(len(A_ub))
        objective = -g
        if along is not None:
            best, _ = self.driven_motion()
            A_ub = np.vstack([A_ub, -g[None, :]])
            b_ub = np.r_[b_ub, -0.5 * best]
            objective = -along * self.D
        if A_eq is not None:
            A_eq = A_eq[np.linalg.norm(A_eq, axis=1) > 0]
            A_eq = A_eq / np.linalg.norm(A_eq, axis=1, keepdims=True)
        res = linprog(
            objective,
            A_ub=A_ub if len(A_ub) else None,
            b_ub=b_ub if len(A_ub) else None,
            A_eq=A_eq if A_eq is not None and len(A_eq) else None,
            b_eq=np.zeros(len(A_eq)) if A_eq is not None and len(A_eq) else None,
            bounds=[(-1.0, 1.0)] * self.m,
            method="highs",
        )
        if res.status != 0:
            return 0.0, np.zeros(self.m)
        return float(-res.fun), self.D * res.x

    # -- an independent optimizer --------------------------------------------
    def _program(self) -> dict[str, Any]:
        """The problem written out for SciPy's SLSQP: unknowns z = (y, q), x =
        D y and a penetration q >= 0 per compliant contact (p = play * q); a
        ball of play as (r + p)^2 - |A x - a0|^2 >= 0, a face with its offset as
        r + p - (b x - b0) >= 0 and (r + p - (b x - b0))^2 - |A x - a0|^2 >= 0, a
        point on a plane as r + p - (b x - b0) >= 0, a fixed contact as A x = 0."""
        s, D = self.play, self.D
        cones = [c for c in self.contacts if not c.fixed]
        soft_slot = {id(c): n for n, c in enumerate(self.soft)}
        ns, m = len(self.soft), self.m
        g = self.g() * D
        scale = max(float(np.sum(np.abs(g))), 1e-300)
        k = np.array([c.stiffness for c in self.soft]) * s * s

        def energy(z: np.ndarray) -> float:
            return float(-g @ z[:m] + 0.5 * np.sum(k * z[m:] ** 2)) / scale

        def energy_grad(z: np.ndarray) -> np.ndarray:
            return np.r_[-g, k * z[m:]] / scale

        # per cone: reach (r + p - b x + b0) / s = r0 + dreach @ z, and rows A D / s
        r0 = np.array(
            [(c.radius + (self.b0_of[id(c)] if c.offset is not None else 0.0)) / s for c in cones]
        )
        dreach = np.zeros((len(cones), m + ns))
        blocks, owner, shift = [], [], []
        for n, c in enumerate(cones):
            if id(c) in soft_slot:
                dreach[n, m + soft_slot[id(c)]] = 1.0
            if c.offset is not None:
                dreach[n, :m] = -self.b_of[id(c)] * D / s
            blocks.append(self.A_of[id(c)] * D / s)
            shift.append(self.a0_of[id(c)] / s)
            owner += [n] * len(c.rows)
        AD = np.vstack(blocks) if blocks else np.zeros((0, m))
        a0 = np.concatenate(shift) if shift else np.zeros(0)
        S = np.zeros((len(cones), len(owner)))  # sums the squared rows of each cone
        S[owner, np.arange(len(owner))] = 1.0
        linear = np.array([c.offset is not None for c in cones], dtype=bool)
        rowed = np.array([len(c.rows) > 0 for c in cones], dtype=bool)

        def ineq(z: np.ndarray) -> np.ndarray:
            r = r0 + dreach @ z
            v = AD @ z[:m] - a0
            return np.r_[r[linear], (r * r - S @ (v * v))[rowed]]

        def ineq_jac(z: np.ndarray) -> np.ndarray:
            r = r0 + dreach @ z
            v = AD @ z[:m] - a0
            quad = 2 * r[:, None] * dreach
            quad[:, :m] -= 2 * S @ (v[:, None] * AD)
            return np.vstack([dreach[linear], quad[rowed]])

        constraints: list[dict[str, Any]] = []
        if cones:
            constraints.append({"type": "ineq", "fun": ineq, "jac": ineq_jac})
        if len(self.E):
            ED = self.E * D
            ED = ED / np.linalg.norm(ED, axis=1, keepdims=True)
            EDz = np.hstack([ED, np.zeros((len(ED), ns))])
            constraints.append({"type": "eq", "fun": lambda z: EDz @ z, "jac": lambda z: EDz})
        bounds = [(None, None)] * m + [(0.0, None)] * ns

        def start(x0: np.ndarray) -> np.ndarray:
            q0 = (
                np.maximum(self.levels(x0, self.soft) - [c.radius for c in self.soft], 0) / s
                if ns
                else np.zeros(0)
            )
            return np.r_[x0 / D, q0]

        return {
            "energy": energy,
            "energy_grad": energy_grad,
            "scale": scale,
            "constraints": constraints,
            "bounds": bounds,
            "start": start,
            "cones": cones,
        }

    def slsqp(self, starts: list[np.ndarray], maxiter: int = 400) -> list[np.ndarray]:
        """SLSQP on the energy (``_program``) from each start; returns the end
        point x of each."""
        p = self._program()
        if not p["cones"]:  # rigid joints only: the centred position is the only one
            return [np.zeros(self.m) for _ in starts]
        ends = []
        for x0 in starts:
            res = minimize(
                p["energy"],
                p["start"](x0),
                jac=p["energy_grad"],
                method="SLSQP",
                bounds=p["bounds"],
                constraints=p["constraints"],
                options={"ftol": 1e-15, "maxiter": maxiter},
            )
            ends.append(self.D * res.x[: self.m])
        return ends

    def least_norm(self, x0: np.ndarray, energy: float, maxiter: int = 400) -> np.ndarray:
        """SLSQP on the least-norm metric over the feasible points whose energy
        (loads and springs) is at most ``energy`` (N*mm), from ``x0``: the
        tie rule's answer (docs/conventions.md, "Free motions")."""
        p = self._program()
        if not p["cones"]:
            return np.zeros(self.m)
        ell, m, D = self.metric_length(), self.m, self.D
        weights = np.r_[np.ones(3), np.full(3, ell)]
        rows = [weights[:, None] * rj.G for rj in self.joints if rj.type != "rigid"]
        Mrows = np.vstack(rows) * D / self.play if rows else np.zeros((0, m))
        width = len(p["start"](x0))

        def metric(z: np.ndarray) -> float:
            v = Mrows @ z[:m]
            return float(v @ v)

        def metric_grad(z: np.ndarray) -> np.ndarray:
            out = np.zeros(width)
            out[:m] = 2 * Mrows.T @ (Mrows @ z[:m])
            return out

        bound = energy / p["scale"]
        level = {
            "type": "ineq",
            "fun": lambda z: np.array([bound - p["energy"](z)]),
            "jac": lambda z: -p["energy_grad"](z)[None, :],
        }
        res = minimize(
            metric,
            p["start"](x0),
            jac=metric_grad,
            method="SLSQP",
            bounds=p["bounds"],
            constraints=[*p["constraints"], level],
            options={"ftol": 1e-15, "maxiter": maxiter},
        )
        return D * res.x[:m]
