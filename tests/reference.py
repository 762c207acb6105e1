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

    def level(self, tau: np.ndarray) -> float:
        out = float(np.linalg.norm(self.rows @ tau)) if len(self.rows) else 0.0
        if self.offset is not None:
            out += float(self.offset @ tau)
        return out


def _row(t: tuple[float, float, float], w: tuple[float, float, float]) -> list[float]:
    return [*t, *w]


def contacts_of(joint: dict[str, Any]) -> list[Contact]:
    """The contacts of one joint, from the domains of docs/joints.md.

    delta(p) = t + w x p; its components, written out:
    delta_x = t_x + w_y p_z - w_z p_y, delta_y = t_y + w_z p_x - w_x p_z,
    delta_z = t_z + w_x p_y - w_y p_x."""
    kind, name = joint["type"], joint["name"]
    J = float(joint.get("clearance", 0.0))
    k = float(joint.get("stiffness", 0.0))

    def ball(cname: str, rows: list[list[float]], radius: float, **more: Any) -> Contact:
        return Contact(
            name, cname, np.array(rows, dtype=float).reshape(-1, 6), radius, stiffness=k, **more
        )

    def ends(length: float) -> list[Contact]:
        out = []
        for cname, s in (("end-", -1.0), ("end+", 1.0)):
            h = s * length / 2  # the end point (h, 0, 0)
            out.append(
                ball(cname, [_row((0, 1, 0), (0, 0, h)), _row((0, 0, 1), (0, -h, 0))], J / 2)
            )
        return out

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
        return ends(float(joint["length"]))
    if kind == "revolute":
        axial = ball("axial", [_row((1, 0, 0), (0, 0, 0))], float(joint["axial_clearance"]) / 2)
        return [*ends(float(joint["length"])), axial]
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

    def __init__(self, data: dict[str, Any]):
        self.data = data
        self.moving = [b["name"] for b in data["bodies"] if not b.get("ground", False)]
        self.index = {name: i for i, name in enumerate(self.moving)}
        self.m = 6 * len(self.moving)
        self.joints: list[RefJoint] = []
        for j in data["joints"]:
            a, b = j["between"]
            R = frame(j.get("axis", [1, 0, 0]), j.get("up"))
            rj = RefJoint(j["name"], j["type"], a, b, np.array(j["at"], float), R, contacts_of(j))
            rj.G = self._joint_map(rj)
            self.joints.append(rj)
        self.loads = [
            RefLoad(
                load["body"],
                None if "at" not in load else np.array(load["at"], float),
                np.array(load.get("force", [0, 0, 0]), float),
                np.array(load.get("torque", [0, 0, 0]), float),
            )
            for load in data.get("loads", [])
        ]
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
            v = self.A_of[id(c)] @ x
            out[n] = (float(np.linalg.norm(v)) if len(v) else 0.0) + (
                float(self.b_of[id(c)] @ x) if c.offset is not None else 0.0
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
        motion shrunk toward the centred position (every level is positively
        homogeneous and the centred position is feasible) until every hard
        contact is within its play."""
        y = np.array(x, dtype=float)
        if len(self.E):
            y = y - np.linalg.pinv(self.E) @ (self.E @ y)
        if self.hard:
            levels = self.levels(y, self.hard)
            radii = np.array([c.radius for c in self.hard])
            over = levels > radii
            if np.any(over):
                alpha = float(np.min(radii[over] / levels[over]))
                y = y * alpha * (1 - 1e-15)
        return y

    def is_feasible(self, x: np.ndarray, tol: float = 0.0) -> bool:
        if len(self.E) and float(np.max(np.abs(self.E @ x))) > tol:
            return False
        radii = np.array([c.radius for c in self.hard])
        return not self.hard or bool(np.all(self.levels(x, self.hard) <= radii + tol))

    # -- an independent optimizer --------------------------------------------
    def slsqp(self, starts: list[np.ndarray], maxiter: int = 400) -> list[np.ndarray]:
        """The problem written out for SciPy's SLSQP: unknowns y (x = D y) and a
        penetration q >= 0 per compliant contact (p = play * q); a ball of play
        as (r + p)^2 - |A x|^2 >= 0, a face with its offset as r + p - b x >= 0
        and (r + p - b x)^2 - |A x|^2 >= 0, a point on a plane as r + p - b x >= 0,
        a rigid joint as A x = 0. Returns the end point x of each start."""
        s, D = self.play, self.D
        cones = [c for c in self.contacts if not c.fixed]
        if not cones:  # rigid joints only: the centred position is the only one
            return [np.zeros(self.m) for _ in starts]
        soft_slot = {id(c): n for n, c in enumerate(self.soft)}
        ns, m = len(self.soft), self.m
        g = self.g() * D
        scale = max(float(np.sum(np.abs(g))), 1e-300)
        k = np.array([c.stiffness for c in self.soft]) * s * s

        def energy(z: np.ndarray) -> float:
            return float(-g @ z[:m] + 0.5 * np.sum(k * z[m:] ** 2)) / scale

        def energy_grad(z: np.ndarray) -> np.ndarray:
            return np.r_[-g, k * z[m:]] / scale

        # per cone: reach (r + p - b x) / s = r0 + dreach @ z, and rows A D / s
        r0 = np.array([c.radius / s for c in cones])
        dreach = np.zeros((len(cones), m + ns))
        blocks, owner = [], []
        for n, c in enumerate(cones):
            if id(c) in soft_slot:
                dreach[n, m + soft_slot[id(c)]] = 1.0
            if c.offset is not None:
                dreach[n, :m] = -self.b_of[id(c)] * D / s
            blocks.append(self.A_of[id(c)] * D / s)
            owner += [n] * len(c.rows)
        AD = np.vstack(blocks)
        S = np.zeros((len(cones), len(owner)))  # sums the squared rows of each cone
        S[owner, np.arange(len(owner))] = 1.0
        linear = np.array([c.offset is not None for c in cones], dtype=bool)
        rowed = np.array([len(c.rows) > 0 for c in cones], dtype=bool)

        def ineq(z: np.ndarray) -> np.ndarray:
            r = r0 + dreach @ z
            v = AD @ z[:m]
            return np.r_[r[linear], (r * r - S @ (v * v))[rowed]]

        def ineq_jac(z: np.ndarray) -> np.ndarray:
            r = r0 + dreach @ z
            v = AD @ z[:m]
            quad = 2 * r[:, None] * dreach
            quad[:, :m] -= 2 * S @ (v[:, None] * AD)
            return np.vstack([dreach[linear], quad[rowed]])

        constraints: list[dict[str, Any]] = [{"type": "ineq", "fun": ineq, "jac": ineq_jac}]
        if len(self.E):
            ED = self.E * D
            ED = ED / np.linalg.norm(ED, axis=1, keepdims=True)
            EDz = np.hstack([ED, np.zeros((len(ED), ns))])
            constraints.append({"type": "eq", "fun": lambda z: EDz @ z, "jac": lambda z: EDz})
        bounds = [(None, None)] * m + [(0.0, None)] * ns
        ends = []
        for x0 in starts:
            q0 = (
                np.maximum(self.levels(x0, self.soft) - [c.radius for c in self.soft], 0) / s
                if ns
                else np.zeros(0)
            )
            res = minimize(
                energy,
                np.r_[x0 / D, q0],
                jac=energy_grad,
                method="SLSQP",
                bounds=bounds,
                constraints=constraints,
                options={"ftol": 1e-15, "maxiter": maxiter},
            )
            ends.append(D * res.x[:m])
        return ends
