"""Revolute joint: a cylindrical joint whose axial slide is also limited.

Clearance domain: the two end discs of the cylindrical joint (radius J/2 at
x = -L/2 and x = +L/2), plus an axial play: the centre moves along the axis
by at most Ja/2 either way (``axial_clearance`` = Ja). Only the spin about x
is free::

      |<-Ja/2->|<-Ja/2->|
      |  .  |---------|  .  |      |(delta_y, delta_z)(+-L/2 x)| <= J/2
      | (o) |  shaft  | (o) |      |delta_x(0)| <= Ja/2
      |  .  |---------|  .  |      spin about x free

A ``backlash`` b holds the spin by a drive within +-b/2 (``drive.py``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar, Literal, Self

from pydantic import model_validator

from jointplay.model.fields import Play, PositiveLength
from jointplay.model.joints.base import (
    AXES_PARALLEL,
    CENTRES_MEET,
    NO_SPIN,
    Contact,
    Coordinate,
    Ideal,
)
from jointplay.model.joints.cylindrical import (
    axial_contact,
    bore_contacts_of,
    check_engagement,
    end_contacts,
)
from jointplay.model.joints.drive import Driven


class Revolute(Driven):
    type: Literal["revolute"] = "revolute"
    drivable: ClassVar[tuple[Coordinate, ...]] = ("spin",)
    length: PositiveLength
    axial_clearance: Play

    @model_validator(mode="after")
    def _check_length(self) -> Self:
        check_engagement(self.length, self.clearance)
        return self

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The centres coincide and the axes stay parallel; the spin is free
        unless a drive (``backlash``) holds it and it is not the one driven."""
        held = NO_SPIN if self.backlash is not None and driven != "spin" else ()
        return (*CENTRES_MEET, *AXES_PARALLEL, *held)

    def contacts(self) -> tuple[Contact, ...]:
        return (
            *end_contacts(self.length, self.clearance),
            *axial_contact(self.axial_clearance),
            *self.drive_contacts(),
        )

    @classmethod
    def contacts_of(cls, joints: Sequence[Self]) -> list[tuple[Contact, ...]]:
        return bore_contacts_of(joints)

    @property
    def size(self) -> float:
        return self.length
