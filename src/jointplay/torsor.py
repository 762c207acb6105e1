"""Small-displacement and force torsors, as two different types.

A small-displacement torsor of a rigid body is a rotation vector ``rotation``
and the translation ``translation`` of the body point at ``point``: any body
point P moves by ``translation + rotation x (P - point)``. A force torsor is a
resultant ``force`` and its ``moment`` about ``point``. ``.at(q)`` moves the
reference point, with the transport rule that belongs to each type.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geometry import FloatArray, Vec3


def _vec(v: FloatArray | Vec3) -> FloatArray:
    return np.asarray(v, dtype=float).reshape(3)


@dataclass(frozen=True)
class SmallDisplacement:
    """Small rigid-body displacement ``{rotation, translation}`` reduced at ``point``."""

    rotation: FloatArray
    translation: FloatArray
    point: FloatArray

    def at(self, point: FloatArray | Vec3) -> SmallDisplacement:
        q = _vec(point)
        return SmallDisplacement(
            self.rotation, self.translation + np.cross(self.rotation, q - self.point), q
        )

    def displacement_of(self, point: FloatArray | Vec3) -> FloatArray:
        """Displacement of the body point currently at ``point``."""
        return self.at(point).translation

    def in_frame(self, R_world_frame: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(translation, rotation) components along the columns of ``R_world_frame``."""
        return R_world_frame.T @ self.translation, R_world_frame.T @ self.rotation


@dataclass(frozen=True)
class ForceTorsor:
    """Force torsor ``{force, moment}`` with the moment taken about ``point``."""

    force: FloatArray
    moment: FloatArray
    point: FloatArray

    def at(self, point: FloatArray | Vec3) -> ForceTorsor:
        q = _vec(point)
        # M(Q) = M(P) + QP x F
        return ForceTorsor(self.force, self.moment + np.cross(self.point - q, self.force), q)

    def power(self, motion: SmallDisplacement) -> float:
        """Virtual work of this force torsor through ``motion`` (reduced at one point)."""
        m = motion.at(self.point)
        return float(self.force @ m.translation + self.moment @ m.rotation)
