"""The solver's plain records, below every layer that makes or reads them.

A ``Point`` is one candidate answer in scaled unknowns with its
multipliers; a ``FaceKey`` an active set and a ``Face`` its equations (the
workspace keeps each face it meets, ``faces.face_of`` builds them); a
``ConeProgram`` is Clarabel's data for one program (``conic`` builds and
runs it). Data only: no algorithm here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import scipy.sparse as sp

from jointplay.assembly import BallStack, IntArray
from jointplay.geometry import FloatArray
from jointplay.numerics.linalg import Matrix
from jointplay.result import Certificate

#: An active set: (cones on their surface, cones whose rows all hold as equalities).
FaceKey = tuple[tuple[int, ...], tuple[int, ...]]


@dataclass
class Point:
    """A candidate optimum in scaled unknowns, with its multipliers."""

    x: FloatArray
    lam: FloatArray  # per ball contact (scaled)
    f: FloatArray  # force vectors, stacked like the rows of BallStack.A (scaled)
    method: str = "interior-point"
    iterations: int = 0
    certificate: Certificate | None = None
    active: FaceKey | None = None  # the active set that determines x, if any
    nu: FloatArray | None = None  # the rigid rows' multipliers (None: least squares)
    #: The active set of a tie: its face holds every optimum, x is its least-norm point.
    tie: FaceKey | None = None
    #: The active set on which Newton's system was regular (``Factors.regular``,
    #: at ``free_motion_rcond``): while ``active`` is that set, its face pins x
    #: and its rows are independent (``pins_by_newton``).
    regular_on: FaceKey | None = None
    #: Whether its forces, where the touching contacts are redundant, are
    #: shown to be the split rule's (``forces.Split.rule``).
    by_rule: bool = True


@dataclass(frozen=True)
class Face:
    """An active set, split by how its cones are held.

    ``surface``: cones on their curved surface, ``|A_i x| + B_i x = r_i``
    with ``A_i x != 0`` (their force is along ``A_i x``). ``linear``: cones
    whose rows all hold as equalities: one-sided limits (no rows) and faces
    resting flat at their apex (``A_i x = c_i``, ``B_i x = r_i``; their force
    vector is free inside ``|f_i| <= lam_i``). The linear cones' rows ``L x = l``
    join the equalities; ``lam_rows`` are the rows of L that carry a cone's
    ``lam`` (and its compliance), ``f_rows`` the rows that carry its ``f``.
    """

    key: FaceKey
    stack: BallStack  # the surface cones
    L: Matrix
    rhs: FloatArray
    lam_rows: IntArray
    f_rows: IntArray
    Eq: Matrix  # the workspace's equalities, then L
    e: FloatArray
    surface_rows: IntArray  # rows of the full stack's A (and f) of the surface cones
    linear_rows: IntArray  # ... and of the linear cones
    #: A surface cone with an offset (a face on its rim): the motions the face
    #: leaves free then depend on x (``is_determined``).
    tilting: bool
    #: Whether the active cones and equalities determine x uniquely; None when
    #: that depends on x (a tilting face: see ``is_determined``).
    #: Computed when first asked (a null space): most trial faces never are.
    _determine: Callable[[], bool | None] = field(repr=False, compare=False)
    _ties: Callable[[], FloatArray | None] = field(repr=False, compare=False)

    @cached_property
    def determined(self) -> bool | None:
        return self._determine()

    @cached_property
    def tie_rows(self) -> FloatArray | None:
        """For a tie: rows ``T^T M`` (T the directions the face leaves free, M
        the least-norm metric) whose zero picks the least-norm point of the
        face's affine hull, as the free motions' rows ``K`` do for the
        mechanism. None for a face that pins x, tilts, or is large (sparse)."""
        return None if self.determined is not False else self._ties()


@dataclass(frozen=True)
class ConeProgram:
    """Clarabel's data for one cone program (``conic.cone_program``); its
    linear cost is given per solve."""

    P: sp.csc_matrix
    A: sp.csc_matrix
    b: FloatArray
    cones: list[Any]
    settings: Any
    soc_first: IntArray  # row of each cone's first entry (its multiplier lam)
    f_rows: IntArray  # rows of the cones' other entries (their force vectors f)
