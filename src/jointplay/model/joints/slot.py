"""Slot joint: a pin of engagement ``length`` L in a slot along ``along``.

Joint frame: x = the pin's ``axis``, y = ``along`` (its part across the
axis), z = x cross y, across the slot. At both ends of the engagement,
x = -L/2 and x = +L/2, the pin's axis point stays within the slot's width:
the displacement across, delta_z, within +-J/2 (``clearance`` = J, the slot's
width less the pin's diameter). Along the slot the pin is free, or, with
``slot_length`` Js (the slot's length less the pin's diameter), within
+-Js/2 of its place at both ends. The spin about the pin is free, and so is
the tilt along the slot unless ``slot_length`` is given; the tilt across it
is limited by the engagement::

          y (along) ^
                    |     ___________________
                    |    (    (o) -> free    )   |delta_z(+-L/2 x)| <= J/2
                    |     -------------------    delta_y free, or
                    +---------------------> z    |delta_y(+-L/2 x)| <= Js/2
                  (pin axis x out of the page)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Literal, Self

import numpy as np
from pydantic import model_validator

from jointplay.geometry import FloatArray, cross, is_parallel, joint_frame
from jointplay.model.fields import Direction, NonNegativeLength, PositiveLength
from jointplay.model.joints.base import (
    Contact,
    Coordinate,
    Ideal,
    Joint,
    point_rows,
    point_rows_of,
)
from jointplay.model.joints.cylindrical import check_engagement


class Slot(Joint):
    type: Literal["slot"] = "slot"
    along: Direction
    length: PositiveLength
    #: Total play along the slot; None: the pin slides freely along it.
    slot_length: NonNegativeLength | None = None

    @model_validator(mode="after")
    def _check_slot(self) -> Self:
        if self.up is not None:
            raise ValueError("a slot's joint frame is set by 'axis' and 'along'; remove 'up'")
        if is_parallel(np.array(self.along), np.array(self.axis)):
            raise ValueError(
                f"along {list(self.along)} is parallel to the pin's axis {list(self.axis)}; "
                "give the slot's direction across the pin"
            )
        check_engagement(self.length, self.clearance)
        return self

    def frame(self) -> FloatArray:
        """x = axis, y = along (across the axis), z = x cross y."""
        return joint_frame(self.axis, cross(np.array(self.axis), np.array(self.along)))

    def frame_inputs(self) -> tuple[Any, ...]:
        return (self.axis, self.along)

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The pin stays in the slot: no offset across it (z), its axis not
        tilted across it; it slides along the slot, along its own axis and
        spins, unless a ``slot_length`` holds it along the slot."""
        out: tuple[Ideal, ...] = (Ideal("offset", 2), Ideal("axes", k=0, j=2))
        if self.slot_length is not None:
            out += (Ideal("offset", 1), Ideal("axes", k=0, j=1))
        return out

    def contacts(self) -> tuple[Contact, ...]:
        out = []
        for end, sign in (("-", -1.0), ("+", 1.0)):
            p = np.array([sign * self.length / 2, 0.0, 0.0])
            out.append(Contact(f"across{end}", "ball", point_rows(p, "z"), self.clearance / 2, p))
        if self.slot_length is not None:
            for end, sign in (("-", -1.0), ("+", 1.0)):
                p = np.array([sign * self.length / 2, 0.0, 0.0])
                rows = point_rows(p, "y")
                out.append(Contact(f"along{end}", "ball", rows, self.slot_length / 2, p))
        return tuple(out)

    @classmethod
    def contacts_of(cls, joints: Sequence[Self]) -> list[tuple[Contact, ...]]:
        ends = np.zeros((len(joints), 2, 3))  # the pin's axis point at x = -L/2, +L/2
        ends[:, :, 0] = np.array([-1.0, 1.0]) * np.array([j.length for j in joints])[:, None] / 2
        across = point_rows_of(ends.reshape(-1, 3), "z").reshape(-1, 2, 1, 6)
        along = point_rows_of(ends.reshape(-1, 3), "y").reshape(-1, 2, 1, 6)
        out = []
        for joint, p, z_rows, y_rows in zip(joints, ends, across, along, strict=True):
            width = joint.clearance / 2
            cones = [
                Contact("across-", "ball", z_rows[0], width, p[0]),
                Contact("across+", "ball", z_rows[1], width, p[1]),
            ]
            if joint.slot_length is not None:
                reach = joint.slot_length / 2
                cones.append(Contact("along-", "ball", y_rows[0], reach, p[0]))
                cones.append(Contact("along+", "ball", y_rows[1], reach, p[1]))
            out.append(tuple(cones))
        return out

    @property
    def size(self) -> float:
        return self.length
