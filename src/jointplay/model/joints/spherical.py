"""Spherical joint: a ball in a spherical seat with diametral clearance J.

Clearance domain (paper eq. 18): the centre of the ball stays in a ball of
radius J/2 around the centre of the seat; the three rotations are free::

            .-~~~-.
          /    .    \\      |delta(0)| <= J/2
         |   o--->   |     (t_x, t_y, t_z) in a ball of radius J/2
          \\    .    /      rotations free
            '-___-'
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal, Self

import numpy as np

from jointplay.model.joints.base import Contact, Joint, point_rows, point_rows_of


class Spherical(Joint):
    type: Literal["spherical"] = "spherical"

    def contacts(self) -> tuple[Contact, ...]:
        centre = np.zeros(3)
        return (Contact("ball", "ball", point_rows(centre), self.clearance / 2, centre),)

    @classmethod
    def contacts_of(cls, joints: Sequence[Self]) -> list[tuple[Contact, ...]]:
        centres = np.zeros((len(joints), 3))
        rows = point_rows_of(centres, "xyz")
        radius = (np.array([j.clearance for j in joints], dtype=float) / 2).tolist()
        return [
            (Contact("ball", "ball", r, play, centre),)
            for r, play, centre in zip(list(rows), radius, list(centres), strict=True)
        ]
