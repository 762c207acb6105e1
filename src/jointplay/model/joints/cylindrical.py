"""Cylindrical joint: a shaft of length L in a bore, diametral clearance J.

Clearance domain (paper eqs. 19-20): at each end of the engaged length,
x = -L/2 and x = +L/2 on the joint axis, the shaft's axis point stays in a
disc of radius J/2 across the axis. Axial slide and spin are free::

        end-            end+
      |  .  |---------|  .  |      |(delta_y, delta_z)(-L/2 x)| <= J/2
      | (o) |  shaft  | (o) |      |(delta_y, delta_z)(+L/2 x)| <= J/2
      |  .  |---------|  .  |      slide along x and spin about x free
      <------- L ------->
"""

from __future__ import annotations

from typing import Literal, Self

import numpy as np
from pydantic import model_validator

from jointplay.model.fields import PositiveLength
from jointplay.model.joints.base import Contact, Joint, point_rows

#: An engaged length below this fraction of the clearance holds no tilt: its
#: two end discs are one circle, to round-off (and the cone program's rows
#: nearly repeat each other, which no solver resolves to 1e-9 mm).
SHORTEST_ENGAGEMENT = 1e-3


def check_engagement(length: float, clearance: float) -> None:
    if length < SHORTEST_ENGAGEMENT * clearance:
        raise ValueError(
            f"length: {length:.3g} mm is less than a thousandth of the clearance "
            f"({clearance:.3g} mm), so the bore holds no tilt; model this contact as a "
            "'sphere_in_cylinder', or give the length the bore really engages"
        )


def end_contacts(length: float, clearance: float) -> tuple[Contact, ...]:
    """The two end discs of a cylindrical engagement of ``length``."""
    out = []
    for name, sign in (("end-", -1.0), ("end+", 1.0)):
        p = np.array([sign * length / 2, 0.0, 0.0])
        out.append(Contact(name, "ball", point_rows(p, "yz"), clearance / 2, p))
    return tuple(out)


class Cylindrical(Joint):
    type: Literal["cylindrical"] = "cylindrical"
    length: PositiveLength

    @model_validator(mode="after")
    def _check_length(self) -> Self:
        check_engagement(self.length, self.clearance)
        return self

    def contacts(self) -> tuple[Contact, ...]:
        return end_contacts(self.length, self.clearance)

    @property
    def size(self) -> float:
        return self.length
