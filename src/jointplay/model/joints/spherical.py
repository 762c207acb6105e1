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

from jointplay.model.joints.base import (
    CENTRES_MEET,
    Contact,
    Coordinate,
    Ideal,
    Joint,
    centred_balls_of,
    point_rows,
)


class Spherical(Joint):
    type: Literal["spherical"] = "spherical"

    def contacts(self) -> tuple[Contact, ...]:
        centre = np.zeros(3)
        return (Contact("ball", "ball", point_rows(centre), self.clearance / 2, centre),)

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The centres coincide; every rotation is free."""
        return CENTRES_MEET

    @classmethod
    def contacts_of(cls, joints: Sequence[Self]) -> list[tuple[Contact, ...]]:
        return centred_balls_of("ball", "xyz", [j.clearance for j in joints])
