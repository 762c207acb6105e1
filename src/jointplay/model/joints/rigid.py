"""Rigid joint: the two bodies move as one (no relative motion at all).

It has no clearance (``clearance`` may only be 0); it exists so that one
body can be modelled as several parts, or a part fixed to the ground::

      [ a ]##[ b ]        t = 0, w = 0
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import field_validator

from jointplay.model.fields import NonNegativeLength
from jointplay.model.joints.base import (
    AXES_PARALLEL,
    CENTRES_MEET,
    NO_SPIN,
    Contact,
    Coordinate,
    Ideal,
    Joint,
)


class Rigid(Joint):
    type: Literal["rigid"] = "rigid"
    clearance: NonNegativeLength = 0.0

    @field_validator("clearance")
    @classmethod
    def _no_play(cls, value: float) -> float:
        if value != 0.0:
            raise ValueError(
                f"a rigid joint has no play, got clearance {value:g}; remove 'clearance', "
                "or use a joint type with play"
            )
        return value

    @field_validator("stiffness")
    @classmethod
    def _no_spring(cls, value: float | None) -> float | None:
        if value is not None:
            raise ValueError(
                "a rigid joint has no contact to make compliant; remove 'stiffness', "
                "or give the joint a type with play"
            )
        return value

    def contacts(self) -> tuple[Contact, ...]:
        return (Contact("rigid", "fixed", np.eye(6), 0.0, np.zeros(3)),)

    def ideal(self, driven: Coordinate | None = None) -> tuple[Ideal, ...]:
        """No relative motion: the centres coincide and no axis turns."""
        return (*CENTRES_MEET, *AXES_PARALLEL, *NO_SPIN)
