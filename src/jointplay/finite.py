"""Finite rotations: how far the small-displacement answer is from exact geometry.

The cone program is written for small displacements: a point P of body b
moves by ``V + Omega x (P - c_b)``. Placed exactly, the body turns by the
rotation ``R(Omega)`` (the rotation vector's exponential) about its reference
point ``c_b`` (the centroid of its joint centres) and shifts by ``V``:

    P  ->  c_b + V + R(Omega) (P - c_b)

Of all exact placements with the rotation ``R(Omega)``, this one is the
closest, in least squares over the body's joint centres, to the small
displacements. Each contact's cone is then evaluated on the exact relative
placement of b in a's joint frame (``Contact.exact_level``); what it goes
past its clearance (and past its penetration, for a compliant contact) is the
*linearization error*.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointplay.assembly import Assembly
from jointplay.geometry import FloatArray, rotation_matrix, rotation_vector

#: Warn when the exact contacts go past their play by more than this share of it.
#: A body turning by more than this (rad, about 3 degrees) is warned about:
#: the small-displacement model's points then drift by about theta^2 / 2
#: (0.1%) of their lever.
LARGE_TURN_RAD = 0.05
WARN_SHARE = 0.01


@dataclass(frozen=True)
class Placement:
    """An exact rigid placement ``P -> R @ P + shift`` (global, mm)."""

    R: FloatArray
    shift: FloatArray

    def __call__(self, P: FloatArray) -> FloatArray:
        return self.R @ P + self.shift

    def inverse(self) -> Placement:
        return Placement(self.R.T, -self.R.T @ self.shift)


IDENTITY = Placement(np.eye(3), np.zeros(3))


def placements(asm: Assembly, x: FloatArray) -> dict[str, Placement]:
    """Exact placement of every moving body for the scaled unknowns ``x``."""
    out = {}
    for i, name in enumerate(asm.body_names):
        v_ref = asm.s * x[6 * i : 6 * i + 3]
        omega = asm.turn[i] * x[6 * i + 3 : 6 * i + 6]
        R = rotation_matrix(omega)
        c = asm.body_ref[i]
        out[name] = Placement(R, c + v_ref - R @ c)
    return out


def relative_in_joint(
    asm: Assembly, place: dict[str, Placement], joint_index: int
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(R_rel, phi, t_rel): b placed relative to a, in a's joint frame at the
    centre (``phi``: the rotation vector of ``R_rel``)."""
    joint = asm.model.joints[joint_index]
    a, b = (place.get(name, IDENTITY) for name in joint.between)
    Rw, C = joint.R_world_joint, joint.centre
    R_rel = Rw.T @ a.R.T @ b.R @ Rw
    t_rel = Rw.T @ (a.inverse()(b(C)) - C)
    return R_rel, rotation_vector(R_rel), t_rel


@dataclass(frozen=True)
class Linearization:
    """How far the exact geometry is from the small-displacement answer.

    ``error_mm``: the largest amount by which an exactly placed contact goes
    past its clearance (plus its penetration, when compliant); 0 when every
    contact stays within. ``worst``: (joint, contact) where that happens.
    ``warnings``: one line per contact past ``WARN_SHARE`` of its play.
    """

    error_mm: float
    worst: tuple[str, str] | None
    warnings: tuple[str, ...]


def linearization(asm: Assembly, x: FloatArray, reach_mm: FloatArray) -> Linearization:
    """The linearization error of the answer ``x``; ``reach_mm``: how far each
    clearance contact (``asm.balls`` order) may go (clearance + penetration)."""
    place = placements(asm, x)
    model = asm.model
    relative = {}
    ball_index = {id(c): i for i, c in enumerate(asm.balls)}
    largest_play = max((2.0 * c.contact.radius for c in asm.contacts), default=0.0)
    worst, where = 0.0, None
    warnings = []
    for c in asm.contacts:
        jdx = c.joint_index
        if jdx not in relative:
            relative[jdx] = relative_in_joint(asm, place, jdx)
        R_rel, phi, t_rel = relative[jdx]
        joint = model.joints[jdx]
        i = ball_index.get(id(c))
        if i is None:  # fixed rows: any exact relative displacement of its point is past
            d = t_rel + R_rel @ c.contact.point - c.contact.point
            past = float(np.linalg.norm(c.contact.rows[:, :3] @ d))
            play = 0.0
        else:
            past = max(c.exact_level(asm.s, R_rel, phi, t_rel) - float(reach_mm[i]), 0.0)
            play = 2.0 * c.radius * asm.s  # its deviation's shift included
        if past > worst:
            worst, where = past, (joint.name, c.contact.name)
        limit = WARN_SHARE * (play if play > 0 else largest_play)
        if past > limit and past > 1e-12:
            share = f"{100 * past / play:.3g}% of its play" if play > 0 else "it has no play"
            warnings.append(
                f"joint '{joint.name}', contact '{c.contact.name}': placed with exact "
                f"rotations it goes {past:.3g} mm past its clearance ({share}); the "
                "small-displacement answer is not accurate here: solve with --exact"
            )
    for i, name in enumerate(asm.body_names):
        turn = float(np.linalg.norm(asm.turn[i] * x[6 * i + 3 : 6 * i + 6]))
        if turn > LARGE_TURN_RAD:
            warnings.append(
                f"body '{name}' turns by {turn:.3g} rad ({np.degrees(turn):.3g} deg): far "
                "beyond small displacements, so points away from its joints move much "
                "less than printed. Its joints' plays let it turn that far: a large play "
                "or backlash (check its units), joints nearly coincident, or a contact "
                "almost on an axis; solve with --exact for the exact geometry"
            )
    return Linearization(worst, where, tuple(warnings))
