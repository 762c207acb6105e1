"""Planar joint: a plate between two parallel faces (normal = joint x axis).

The faces leave a total play ``clearance`` J along x. The plate's contact
face is centred on the joint centre and is either a rectangle of ``width``
(along y) and ``height`` (along z), or a disc of ``diameter`` D. The plate
may slide in y and z and spin about x freely; its shift along x and its tilt
about y and z are limited by the face's edge::

        |<-J->|
        |  |  |     rectangle: each corner, |delta_x(0, +-w/2, +-h/2)| <= J/2
        |  |  |     disc: every rim point,  |delta_x(0, R cos t, R sin t)| <= J/2
        |  |  |           i.e. R |(w_y, w_z)| +- t_x <= J/2   (R = D/2)
      face   face

Rectangle: four two-sided corner contacts (|.| <= J/2 covers both faces).
Disc: one contact per face, a cone: the rim point that touches is the one
the tilt pushes furthest, and when the plate lies flat on a face the force
spreads over it; the reported point is the centre of pressure, which stays
inside the disc.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Self

import numpy as np
from pydantic import model_validator

from jointplay.geometry import FloatArray
from jointplay.model.fields import PositiveLength
from jointplay.model.joints.base import (
    AXES_PARALLEL,
    Contact,
    Coordinate,
    Ideal,
    Joint,
    Parts,
    point_rows,
    point_rows_of,
)


@dataclass(frozen=True)
class RimContact(Contact):
    """A disc face's contact: its rim point furthest along the normal."""

    def exact_parts(self, R_rel: FloatArray, phi: FloatArray, t_rel: FloatArray) -> Parts:
        # rim point p(t) = R (0, cos t, sin t) moves along x by
        # t_x + R ((R_rel)_xy cos t + (R_rel)_xz sin t): its largest excursion
        # is the norm of the vector part plus the scalar part
        assert self.offset is not None and self.lever is not None
        sign = float(self.offset[0])
        radius = float(self.lever[1, 0])
        vector = sign * radius * np.array([R_rel[0, 1], R_rel[0, 2]])
        return vector, sign * float(t_rel[0])

    def exact_jacobian(self, R_rel: FloatArray, phi: FloatArray, t_rel: FloatArray) -> FloatArray:
        assert self.offset is not None and self.lever is not None
        sign = float(self.offset[0])
        radius = float(self.lever[1, 0])
        out = np.zeros((3, 6))
        for k in range(3):  # d R_rel = [e_k]x R_rel per unit turn about e_k
            turned = np.cross(np.eye(3)[k], R_rel.T).T  # e_k x (each column)
            out[0, 3 + k] = sign * radius * turned[0, 1]
            out[1, 3 + k] = sign * radius * turned[0, 2]
        out[2, 0] = sign  # t_x; a turn about the centre moves t by dtheta x t
        out[2, 3:] = -sign * np.cross(t_rel, np.eye(3))[:, 0]
        return out


#: A rectangle's corners, in the order ``_corner_contacts`` makes them (y, then z, from - to +).
CORNER_NAMES = ("corner y- z-", "corner y- z+", "corner y+ z-", "corner y+ z+")


def _corner_contacts(faces: Sequence[Planar]) -> list[tuple[Contact, ...]]:
    """The four corner contacts of rectangular faces, a tuple per face."""
    half = np.array([-1.0, 1.0])  # times a half length: -w/2, +w/2
    size = np.array([[face.width, face.height] for face in faces], dtype=float).reshape(-1, 2)
    points = np.zeros((len(faces), 4, 3))
    points[:, :, 1] = np.repeat(half * size[:, :1] / 2, 2, axis=1)
    points[:, :, 2] = np.tile(half * size[:, 1:] / 2, 2)
    rows = point_rows_of(points.reshape(-1, 3), "x").reshape(-1, 4, 1, 6)
    plays = (np.array([face.clearance for face in faces], dtype=float) / 2).tolist()
    return [
        tuple(
            Contact(name, "ball", r, play, p)
            for name, r, p in zip(CORNER_NAMES, face_rows, face_points, strict=True)
        )
        for face_rows, face_points, play in zip(rows, points, plays, strict=True)
    ]


class Planar(Joint):
    type: Literal["planar"] = "planar"
    width: PositiveLength | None = None
    height: PositiveLength | None = None
    diameter: PositiveLength | None = None

    @model_validator(mode="after")
    def _check_face(self) -> Planar:
        rectangle = self.width is not None or self.height is not None
        if self.diameter is not None and rectangle:
            raise ValueError(
                "a planar joint's face is a rectangle ('width' and 'height') or a disc "
                "('diameter'), not both; remove one"
            )
        if self.diameter is None and (self.width is None or self.height is None):
            raise ValueError(
                "a planar joint needs its contact face: 'width' and 'height' (mm) for a "
                "rectangle, or 'diameter' (mm) for a disc"
            )
        return self

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """The faces stay in their plane: no offset along the normal, the
        normals parallel; the plate slides and spins in the plane."""
        return (Ideal("offset", 0), *AXES_PARALLEL)

    def contacts(self) -> tuple[Contact, ...]:
        if self.diameter is not None:
            return self._disc(self.diameter / 2)
        assert self.width is not None and self.height is not None
        out = []
        for y in (-self.width / 2, self.width / 2):
            for z in (-self.height / 2, self.height / 2):
                p = np.array([0.0, y, z])
                name = f"corner y{'+' if y > 0 else '-'} z{'+' if z > 0 else '-'}"
                out.append(Contact(name, "ball", point_rows(p, "x"), self.clearance / 2, p))
        return tuple(out)

    @classmethod
    def contacts_of(cls, joints: Sequence[Self]) -> list[tuple[Contact, ...]]:
        rectangles = [j for j in joints if j.diameter is None]
        corners = iter(_corner_contacts(rectangles))
        return [next(corners) if j.diameter is None else j._disc(j.diameter / 2) for j in joints]

    def _disc(self, R: float) -> tuple[Contact, ...]:
        # rim point p(t) = (0, R cos t, R sin t): delta_x = t_x + a . (cos t, sin t)
        # with a = R (-w_z, w_y); the face at +x is reached first where a points.
        tilt = np.zeros((2, 6))
        tilt[0, 5], tilt[1, 4] = -R, R
        lever = np.zeros((3, 2))
        lever[1, 0] = lever[2, 1] = R  # centre of pressure = R f / lam, in the face plane
        if self.clearance == 0.0 and self.stiffness is None:
            rows = np.vstack([point_rows(np.zeros(3), "x"), tilt / R])
            return (Contact("face", "fixed", rows, 0.0, np.zeros(3)),)
        e_x = np.eye(6)[0]
        return tuple(
            RimContact(
                name, "ball", sign * tilt, self.clearance / 2, np.zeros(3), sign * e_x, lever
            )
            for name, sign in (("face x+", 1.0), ("face x-", -1.0))
        )

    @property
    def size(self) -> float:
        if self.diameter is not None:
            return self.diameter
        assert self.width is not None and self.height is not None
        return max(self.width, self.height)
