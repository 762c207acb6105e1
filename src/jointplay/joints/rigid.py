"""Rigid joint: the two bodies move as one (no relative motion at all).

Its ``clearance`` is ignored and defaults to 0; it exists so that one body
can be modelled as several parts, or a part fixed to the ground::

      [ a ]##[ b ]        t = 0, w = 0
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ..fields import NonNegativeLength
from .base import Contact, Joint


class Rigid(Joint):
    type: Literal["rigid"] = "rigid"
    clearance: NonNegativeLength = 0.0

    def contacts(self) -> tuple[Contact, ...]:
        return (Contact("rigid", "fixed", np.eye(6), 0.0, np.zeros(3)),)
