"""Planar joint: a plate between two parallel faces (normal = joint x axis).

The plate's contact face is a rectangle of ``width`` (along y) and
``height`` (along z) centred on the joint centre; the faces leave a total
play ``clearance`` J along x. Each corner of the rectangle stays within the
play, so the plate may slide in y and z and spin about x freely, while its
tilt about y and z is limited by the corners::

        |<-J->|
        |  |  |          |delta_x(0, +-w/2, +-h/2)| <= J/2
        |  |  |  plate   slide along y, z and spin about x free
        |  |  |
      face   face

Each corner contact is two-sided (|.| <= J/2 covers both faces).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..fields import PositiveLength
from .base import Contact, Joint, point_rows


class Planar(Joint):
    type: Literal["planar"] = "planar"
    width: PositiveLength
    height: PositiveLength

    def contacts(self) -> tuple[Contact, ...]:
        out = []
        for y in (-self.width / 2, self.width / 2):
            for z in (-self.height / 2, self.height / 2):
                p = np.array([0.0, y, z])
                name = f"corner y{'+' if y > 0 else '-'} z{'+' if z > 0 else '-'}"
                out.append(Contact(name, "ball", point_rows(p, "x"), self.clearance / 2, p))
        return tuple(out)

    @property
    def size(self) -> float:
        return max(self.width, self.height)
