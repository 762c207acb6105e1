"""Cylindrical joint: a shaft of length L in a bore, diametral clearance J.

Clearance domain (paper eqs. 19-20): at each end of the engaged length,
x = -L/2 and x = +L/2 on the joint axis, the shaft's axis point stays in a
disc of radius J/2 across the axis. Axial slide and spin are free::

        end-            end+
      |  .  |---------|  .  |      |(delta_y, delta_z)(-L/2 x)| <= J/2
      | (o) |  shaft  | (o) |      |(delta_y, delta_z)(+L/2 x)| <= J/2
      |  .  |---------|  .  |      slide along x and spin about x free
      <------- L ------->

An ``axial_clearance`` Ja limits the slide to +-Ja/2 (a ball screw's nut, a
shoulder): contact ``axial``. A ``backlash`` b holds the spin by a drive
within +-b/2 (``drive.py``): contact ``drive``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar, Literal, Protocol, Self

import numpy as np
from pydantic import model_validator

from jointplay.model.fields import Play, PositiveLength
from jointplay.model.joints.base import (
    AXES_PARALLEL,
    NO_SPIN,
    Contact,
    Coordinate,
    Ideal,
    point_rows,
    point_rows_of,
)
from jointplay.model.joints.drive import Driven

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


def axial_contact(axial_clearance: float | None) -> tuple[Contact, ...]:
    """The centre's slide along the axis within +-Ja/2 (none if Ja is None)."""
    if axial_clearance is None:
        return ()
    centre = np.zeros(3)
    return (Contact("axial", "ball", point_rows(centre, "x"), axial_clearance / 2, centre),)


def end_contacts_of(
    length: Sequence[float], clearance: Sequence[float]
) -> list[tuple[Contact, Contact]]:
    """The two end discs of cylindrical engagements of ``length``, a pair per joint."""
    points = np.zeros((len(length), 2, 3))
    points[:, :, 0] = np.array([-1.0, 1.0]) * np.asarray(length, dtype=float)[:, None] / 2
    rows = point_rows_of(points.reshape(-1, 3), "yz").reshape(-1, 2, 2, 6)
    radius = (np.asarray(clearance, dtype=float) / 2).tolist()
    minus, plus = list(rows[:, 0]), list(rows[:, 1])  # list(): NumPy makes the views at once
    at_minus, at_plus = list(points[:, 0]), list(points[:, 1])
    return [
        (Contact("end-", "ball", r0, play, p0), Contact("end+", "ball", r1, play, p1))
        for r0, p0, r1, p1, play in zip(minus, at_minus, plus, at_plus, radius, strict=True)
    ]


def axial_contacts_of(axial_clearance: Sequence[float | None]) -> list[tuple[Contact, ...]]:
    """Each centre's slide along its axis within +-Ja/2 (none where Ja is None)."""
    slides = [play / 2 for play in axial_clearance if play is not None]
    if not slides:
        return [() for _ in axial_clearance]
    centres = np.zeros((len(slides), 3))
    made = iter(
        [
            (Contact("axial", "ball", r, play, centre),)
            for r, play, centre in zip(
                list(point_rows_of(centres, "x")), slides, list(centres), strict=True
            )
        ]
    )
    return [() if play is None else next(made) for play in axial_clearance]


class Bore(Protocol):
    """What ``bore_contacts_of`` reads of a joint: a cylindrical's or a
    revolute's fields (``revolute.py`` imports this module, not the reverse)."""

    @property
    def length(self) -> float: ...
    @property
    def clearance(self) -> float: ...
    @property
    def axial_clearance(self) -> float | None: ...
    def drive_contacts(self) -> tuple[Contact, ...]: ...


def bore_contacts_of(joints: Sequence[Bore]) -> list[tuple[Contact, ...]]:
    """``contacts()`` of many cylindrical or revolute joints at once (the
    same contacts: end discs, axial play if any, drive)."""
    ends = end_contacts_of([j.length for j in joints], [j.clearance for j in joints])
    axial = axial_contacts_of([j.axial_clearance for j in joints])
    return [
        (*end, *slide, *joint.drive_contacts())
        for joint, end, slide in zip(joints, ends, axial, strict=True)
    ]


class Cylindrical(Driven):
    type: Literal["cylindrical"] = "cylindrical"
    drivable: ClassVar[tuple[Coordinate, ...]] = ("spin", "slide")
    length: PositiveLength
    #: Total play along the axis; None: the slide is free.
    axial_clearance: Play | None = None

    @model_validator(mode="after")
    def _check_length(self) -> Self:
        check_engagement(self.length, self.clearance)
        return self

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The shaft's centre stays on the bore's axis and the axes stay
        parallel; it slides and spins, unless an ``axial_clearance`` holds the
        slide or a drive (``backlash``) the spin, and that is not the one driven."""
        slide = (Ideal("offset", 0),) if self.axial_clearance is not None else ()
        spin = NO_SPIN if self.backlash is not None else ()
        return (
            *(slide if driven != "slide" else ()),
            Ideal("offset", 1),
            Ideal("offset", 2),
            *AXES_PARALLEL,
            *(spin if driven != "spin" else ()),
        )

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
