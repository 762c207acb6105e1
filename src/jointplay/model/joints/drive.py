"""A drive on a joint's axis: the angular backlash of a motor, gearbox or belt.

A revolute or cylindrical joint leaves the spin about its axis free; a drive
holds it, within its backlash b: the spin ``w_x`` stays within +-b/2. The
limit is written as a contact of its own, ``drive``, whose row is the spin
scaled by the drive's lever ``rho`` (half the joint's length), so that it
is a length like every other row: ``|rho w_x| <= rho b / 2``. Its force is a
pure torque about the axis, reported as the contact's ``torque`` (N*mm).

With a ``torsional_stiffness`` k (N*mm/rad) the drive may turn past its
backlash by phi at the cost of an energy k phi^2 / 2: at the lever that is
the contact spring k / rho^2 (N/mm).
"""

from __future__ import annotations

from typing import Self

import numpy as np
from pydantic import model_validator

from jointplay.model.fields import SOFTEST_STIFFNESS, AngularPlay, PositiveTorsionalStiffness
from jointplay.model.joints.base import Contact, Joint
from jointplay.model.tolerance import ANGULAR_PLAYS


class Driven(Joint):
    """A joint whose spin may be held by a drive with ``backlash`` (rad)."""

    #: The drive's total angular play: +-backlash/2 about the joint axis. None: no drive.
    backlash: AngularPlay | None = None
    #: The drive's stiffness past its backlash (N*mm/rad). None: a hard stop.
    torsional_stiffness: PositiveTorsionalStiffness | None = None

    @model_validator(mode="after")
    def _check_drive(self) -> Self:
        if self.torsional_stiffness is not None:
            if self.backlash is None:
                raise ValueError(
                    "torsional_stiffness needs a drive: give its 'backlash' (0 for none), "
                    "or remove 'torsional_stiffness'"
                )
            if self.torsional_stiffness / self.drive_radius**2 < SOFTEST_STIFFNESS:
                least = SOFTEST_STIFFNESS * self.drive_radius**2
                raise ValueError(
                    f"torsional_stiffness: {self.torsional_stiffness:g} N*mm/rad holds "
                    f"nothing at this joint's size; give at least {least:.3g} N*mm/rad, "
                    "or remove it for a hard stop"
                )
        return self

    @property
    def drive_radius(self) -> float:
        """The lever (mm) that turns the drive's angle into a length."""
        return self.size / 2

    def play_length(self, field: str, play: float) -> float:
        return play * self.drive_radius if field in ANGULAR_PLAYS else play

    def drive_contacts(self) -> tuple[Contact, ...]:
        if self.backlash is None:
            return ()
        rho = self.drive_radius
        rows = np.array([[0.0, 0.0, 0.0, rho, 0.0, 0.0]])
        spring = 0.0 if self.torsional_stiffness is None else self.torsional_stiffness / rho**2
        drive = Contact(
            "drive",
            "ball",
            rows,
            rho * self.backlash / 2,
            np.zeros(3),
            stiffness=spring,
            turn_lever=rho,
        )
        return (drive,)
