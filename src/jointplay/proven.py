"""What an answer proves: the smallest length, angle, force and moment that
its certificate tells from zero.

The certificate holds positions to ``feasibility_tolerance`` of the largest
play and balances forces to ``equilibrium_tolerance`` of the largest force; a
length below the first, or a force below ``force_resolution`` of the largest
(a hundredth of the balance, so that the printed forces still balance), is the
solver's round-off, and every result
(and so the text, ``--json``, CSV and the report) gives it as 0. This module
is the one place where that rule is written.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointplay.geometry import FloatArray
from jointplay.settings import DEFAULT, SolverSettings


@dataclass(frozen=True)
class Resolution:
    """The smallest length (mm), angle (rad), force (N) and moment (N*mm)
    that an answer proves; rotations and moments go with ``ell``, the
    mechanism's length scale (a rotation moves a point ``ell`` away by
    ``angle * ell``)."""

    length: float
    angle: float
    force: float
    moment: float
    #: N: how far the certificate lets a body's forces miss their balance.
    balance: float = 0.0
    #: N*mm: the largest force's work over the smallest length proven.
    energy: float = 0.0

    @classmethod
    def of(
        cls,
        play_mm: float,
        ell_mm: float,
        largest_force: float = 0.0,
        settings: SolverSettings = DEFAULT,
        at_least: float = 0.0,
    ) -> Resolution:
        """``play_mm``: the largest play; ``largest_force``: the largest force
        in the balance (N, a moment counting as moment / ``ell_mm``; 0 where
        only positions are read); ``at_least``: a route's own length
        tolerance (mm) where it certifies positions to less."""
        length = max(settings.feasibility_tolerance * play_mm, at_least)
        force = settings.force_resolution * largest_force
        balance = settings.equilibrium_tolerance * largest_force
        return cls(length, length / ell_mm, force, force * ell_mm, balance, length * largest_force)


#: A resolution that zeroes nothing.
EXACT = Resolution(0.0, 0.0, 0.0, 0.0)


def proven(values: FloatArray | float, step: FloatArray | float) -> FloatArray:
    """``values`` with every component smaller than ``step`` given as 0 (and
    no -0)."""
    v = np.asarray(values, dtype=float)
    return np.where(np.abs(v) < step, 0.0, v) + 0.0


def direction(vector: FloatArray, step: float) -> FloatArray:
    """The unit vector along ``vector`` whose components below ``step`` are
    0 (a vector of zeros for a vector that is 0 to ``step``)."""
    v = proven(vector, step)
    size = float(np.linalg.norm(v))
    return v / size + 0.0 if size > 0 else np.zeros_like(v)
