"""Sphere-in-cylinder (linear annular) joint: a ball in a bore.

Clearance domain: the ball centre stays in a disc of radius J/2 across the
bore axis; it slides freely along the axis, and all rotations are free::

      ----------------------
           (o) -->  slide       |(delta_y, delta_z)(0)| <= J/2
      ----------------------    delta_x and all rotations free
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal, Self

import numpy as np

from jointplay.model.joints.base import (
    Contact,
    Coordinate,
    Ideal,
    Joint,
    centred_balls_of,
    point_rows,
)


class SphereInCylinder(Joint):
    type: Literal["sphere_in_cylinder"] = "sphere_in_cylinder"

    def contacts(self) -> tuple[Contact, ...]:
        centre = np.zeros(3)
        return (Contact("radial", "ball", point_rows(centre, "yz"), self.clearance / 2, centre),)

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The ball's centre stays on the bore's axis (it slides along it)."""
        return (Ideal("offset", 1), Ideal("offset", 2))

    @classmethod
    def contacts_of(cls, joints: Sequence[Self]) -> list[tuple[Contact, ...]]:
        return centred_balls_of("radial", "yz", [j.clearance for j in joints])
