"""Point joint: a point of body b on a plane of body a, one-sided.

The plane's normal is the joint x axis, pointing from the plane towards the
point; ``at`` is the point's position. It starts at a distance ``gap`` (>= 0)
from the plane and may not go through it; it may lift off freely, and it
slides on the plane freely::

          o  <- point of b, at 'at'
          |  gap                  -delta_x(0) <= gap
     -----+-----  plane of a      (no limit on lifting off or sliding)
          ^ x

The contact pushes b along +x only (a plane cannot pull). A mechanism held
only by point contacts is held in some load directions and not in others:
a load that lifts it off is reported as a free motion the loads drive.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import field_validator

from jointplay.model.fields import Play
from jointplay.model.joints.base import Contact, Coordinate, Ideal, Joint


class PointOnPlane(Joint):
    type: Literal["point"] = "point"
    gap: Play = 0.0
    clearance: Play = 0.0

    @field_validator("clearance")
    @classmethod
    def _gap_not_clearance(cls, value: float) -> float:
        if value != 0.0:
            raise ValueError(
                "a point joint has a one-sided 'gap' to its plane, not a 'clearance'; "
                f"write gap: {value:g}"
            )
        return value

    def contacts(self) -> tuple[Contact, ...]:
        offset = -np.eye(6)[0]  # -t_x <= gap: the point does not go through the plane
        return (Contact("plane", "ball", np.zeros((0, 6)), self.gap, np.zeros(3), offset),)

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The point stays on its plane at its written gap (a follower kept on
        its cam): the distance along the normal is kept; it slides and turns
        freely. A point that should lift off in the motion is not a joint of
        its large motion: leave it out of the motion's loops."""
        return (Ideal("offset", 0),)
