"""Prismatic joint: a slider of rectangular section in a slot.

The slider has ``length`` L along the joint x axis, ``width`` w along y and
``height`` h along z; the slot leaves a total play ``clearance_y`` (Jy)
across y and ``clearance_z`` (Jz) across z. Each slider edge stays within
the play at both ends of the engagement: the y displacement of the four
points (x = +-L/2, z = +-h/2) and the z displacement of the four points
(x = +-L/2, y = +-w/2). The axial slide along x is free; the rotation about
x (roll) is limited by the corners::

        y ^   +-----------------+  <- slot face y = +(w + Jy)/2
          |   | +-------------+ |
          |   | |   slider    | |   |delta_y(+-L/2, ., +-h/2)| <= Jy/2
          |   | +-------------+ |   |delta_z(+-L/2, +-w/2, .)| <= Jz/2
          |   +-----------------+  <- slot face y = -(w + Jy)/2
          +-----------------------> x (slide free)

Each of the eight contacts is two-sided (|.| <= J/2 covers both faces); a
contact's force acts along y (or z) at its edge point, reported on the
slider's mid-plane (y = 0 for a y contact, z = 0 for a z contact), which
gives the same moment.

An ``axial_clearance`` Ja limits the slide to +-Ja/2 (a ball screw's nut with
axial backlash Ja): contact ``axial``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar, Literal, Self

import numpy as np
from pydantic import model_validator

from jointplay.model.fields import Play, PositiveLength
from jointplay.model.joints.base import (
    AXES_PARALLEL,
    NO_SPIN,
    Contact,
    Coordinate,
    Ideal,
    Joint,
    point_rows,
    point_rows_of,
)
from jointplay.model.joints.cylindrical import axial_contact, axial_contacts_of


def _sign(v: float) -> str:
    return "+" if v > 0 else "-"


#: The contacts' names, in the order ``contacts_of`` makes them (x, then z or y, from - to +).
Y_NAMES = ("y x- z-", "y x- z+", "y x+ z-", "y x+ z+")
Z_NAMES = ("z x- y-", "z x- y+", "z x+ y-", "z x+ y+")


class Prismatic(Joint):
    type: Literal["prismatic"] = "prismatic"
    drivable: ClassVar[tuple[Coordinate, ...]] = ("slide",)
    length: PositiveLength
    width: PositiveLength
    height: PositiveLength
    #: Play across y and across z; ``clearance`` alone sets both.
    clearance: Play | None = None  # type: ignore[assignment]
    clearance_y: Play | None = None
    clearance_z: Play | None = None
    #: Total play along the slide (a screw's axial backlash); None: the slide is free.
    axial_clearance: Play | None = None

    @model_validator(mode="after")
    def _check_play(self) -> Prismatic:
        for axis in "yz":
            if getattr(self, f"clearance_{axis}") is None and self.clearance is None:
                raise ValueError(
                    f"a prismatic joint needs its play across {axis}: give 'clearance_{axis}' "
                    "(mm), or 'clearance' for both y and z"
                )
        return self

    @property
    def play(self) -> tuple[float, float]:
        """(Jy, Jz) in mm."""
        jy = self.clearance_y if self.clearance_y is not None else self.clearance
        jz = self.clearance_z if self.clearance_z is not None else self.clearance
        assert jy is not None and jz is not None
        return jy, jz

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The slider keeps its centre on the slot's axis and does not turn;
        it slides along the axis, unless an ``axial_clearance`` holds it and
        the slide is not the one driven."""
        held = self.axial_clearance is not None and driven != "slide"
        return (
            *((Ideal("offset", 0),) if held else ()),
            Ideal("offset", 1),
            Ideal("offset", 2),
            *AXES_PARALLEL,
            *NO_SPIN,
        )

    def contacts(self) -> tuple[Contact, ...]:
        jy, jz = self.play
        half_l, half_w, half_h = self.length / 2, self.width / 2, self.height / 2
        out = []
        for x in (-half_l, half_l):
            for z in (-half_h, half_h):
                p = np.array([x, 0.0, z])
                name = f"y x{_sign(x)} z{_sign(z)}"
                out.append(Contact(name, "ball", point_rows(p, "y"), jy / 2, p))
        for x in (-half_l, half_l):
            for y in (-half_w, half_w):
                p = np.array([x, y, 0.0])
                name = f"z x{_sign(x)} y{_sign(y)}"
                out.append(Contact(name, "ball", point_rows(p, "z"), jz / 2, p))
        return (*out, *axial_contact(self.axial_clearance))

    @classmethod
    def contacts_of(cls, joints: Sequence[Self]) -> list[tuple[Contact, ...]]:
        half = np.array([-1.0, 1.0])  # times a half length: -L/2, +L/2
        size = np.array([[j.length, j.width, j.height] for j in joints], dtype=float)
        points = np.zeros((len(joints), 8, 3))
        # y contacts at (x, 0, z), then z contacts at (x, y, 0): x, then z or y, from - to +
        points[:, :4, 0] = points[:, 4:, 0] = np.repeat(half * size[:, :1] / 2, 2, axis=1)
        points[:, :4, 2] = np.tile(half * size[:, 2:] / 2, 2)
        points[:, 4:, 1] = np.tile(half * size[:, 1:2] / 2, 2)
        rows_y = point_rows_of(points[:, :4].reshape(-1, 3), "y").reshape(-1, 4, 1, 6)
        rows_z = point_rows_of(points[:, 4:].reshape(-1, 3), "z").reshape(-1, 4, 1, 6)
        plays = (np.array([j.play for j in joints], dtype=float).reshape(-1, 2) / 2).tolist()
        axial = axial_contacts_of([j.axial_clearance for j in joints])
        out = []
        for ry, rz, py, pz, (jy, jz), slide in zip(
            rows_y, rows_z, points[:, :4], points[:, 4:], plays, axial, strict=True
        ):
            y = (Contact(n, "ball", r, jy, p) for n, r, p in zip(Y_NAMES, ry, py, strict=True))
            z = (Contact(n, "ball", r, jz, p) for n, r, p in zip(Z_NAMES, rz, pz, strict=True))
            out.append((*y, *z, *slide))
        return out

    @property
    def size(self) -> float:
        return max(self.length, self.width, self.height)
