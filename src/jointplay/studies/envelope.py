"""The worst-case envelope of a functional point: where the plays let it go.

Under every possible load, a functional point P can reach exactly the
displacements ``d_P(x)`` of the positions x that every clearance allows: a
convex set (a linear image of the intersection of the joints' cones). Its
support function in a direction u, ``h(u) = max u . d_P(x)``, is one cone
program: the equilibrium under a unit force along u applied at P (with rigid
contacts only the load's direction matters). ``Envelope`` evaluates it in
many directions spread evenly over the sphere, all in one batch, then climbs
from the farthest support points to the largest displacement (each step
``u <- d / |d|`` can only increase |d|).

The envelope is that of the plays alone: a contact's stiffness is left out
(it would let the point go further the harder it is pushed). With toleranced
plays it is taken at their upper limits (``plays="max"``: every part of the
batch is inside) or at their means (``plays="mean"``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from jointplay.assembly import assemble
from jointplay.errors import OptionError, UnboundedMechanismError
from jointplay.geometry import FloatArray
from jointplay.model.mechanism import Model
from jointplay.solver.workspace import Workspace
from jointplay.studies.variation import play_map

if TYPE_CHECKING:
    import pandas as pd

#: The directions always taken first: +-X, +-Y, +-Z (the exact extents).
AXES = np.vstack([np.eye(3), -np.eye(3)])
#: Steps of the climb from a support point to the largest displacement.
CLIMB_STEPS = 30


def sphere_directions(n: int) -> FloatArray:
    """``n`` unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5.0**0.5) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


@dataclass(frozen=True)
class Envelope:
    """Settings of a worst-case envelope; ``run`` returns an ``EnvelopeResult``."""

    point: str
    directions: int = 200
    plays: Literal["max", "mean"] = "max"

    def __post_init__(self) -> None:
        if self.directions < 6:
            raise ValueError("directions: at least 6")

    def run(self, model: Model, *, source: str | None = None) -> EnvelopeResult:
        """``source``: the model file's name, for messages."""
        source = source or model.name or "<model>"
        names = [p.name for p in model.points]
        if self.point not in names:
            known = ", ".join(names) if names else "none; add a 'points' section"
            raise OptionError(
                f"--point: unknown point '{self.point}'; the points are: {known}", source=source
            )
        point = model.points[names.index(self.point)]
        rigid = model.model_copy(
            update={"joints": tuple(j.model_copy(update={"stiffness": None}) for j in model.joints)}
        )
        asm = assemble(rigid)
        ws = Workspace(asm)
        pmap = play_map(asm, source)
        if self.plays == "max" and pmap.variables:
            highs = np.array([v.value.high for v in pmap.variables])
            ws = ws.with_radii(pmap.radii(highs)[0])
        if point.body not in asm.body_index:  # a point of the ground does not move
            u = np.vstack([AXES, sphere_directions(self.directions)])
            zero = np.zeros_like(u)
            return EnvelopeResult(self, point.body, u, np.zeros(len(u)), zero, zero[0], 0.0)
        W = asm.wrench_work(point.body, point.at)[:, :3]
        at = np.asarray(point.at)

        def support(u: FloatArray) -> FloatArray:
            batch = ws.solve_batch(u @ W.T)
            motion = batch.body_displacement(point.body)
            return np.asarray(motion[:, :3] + np.cross(motion[:, 3:], at))

        u = np.vstack([AXES, sphere_directions(self.directions)])
        d = support(u)
        # climb from the farthest few to the largest displacement
        size = np.linalg.norm(d, axis=1)
        best = np.argsort(size)[-4:]
        far, far_d = float(size[best[-1]]), d[best[-1]]
        for start in best:
            cur = d[start]
            for _ in range(CLIMB_STEPS):
                n = float(np.linalg.norm(cur))
                if n == 0.0:
                    break
                nxt = support((cur / n)[None, :])[0]
                grown = float(np.linalg.norm(nxt))
                if grown <= n * (1 + 1e-13):
                    break
                cur = nxt
            if float(np.linalg.norm(cur)) > far:
                far, far_d = float(np.linalg.norm(cur)), cur
        h = np.einsum("ij,ij->i", u, d)
        return EnvelopeResult(self, point.body, u, h, d, far_d, far)


@dataclass(frozen=True)
class EnvelopeResult:
    """Support values ``h`` in ``directions`` (mm), the support points
    ``hull`` (mm, global: on the envelope's boundary) and the largest
    displacement ``largest`` (mm) with its vector ``largest_vector``."""

    settings: Envelope
    body: str
    directions: FloatArray  # (n, 3) unit
    h: FloatArray  # (n,) mm
    hull: FloatArray  # (n, 3) mm
    largest_vector: FloatArray  # (3,) mm
    largest: float  # mm

    @property
    def extent(self) -> FloatArray:
        """(3, 2): per global axis, the least and the greatest displacement (mm)
        (exact: the support values along -X, +X, ...)."""
        return np.column_stack([-self.h[3:6], self.h[0:3]])

    def contains(self, displacement: FloatArray, tol: float = 1e-9) -> FloatArray:
        """(N,) bool: each displacement (N, 3) is inside every supporting plane."""
        d = np.atleast_2d(displacement)
        return np.asarray(np.all(d @ self.directions.T <= self.h + tol, axis=1))

    def to_dict(self) -> dict[str, Any]:
        ext = self.extent
        direction = (self.largest_vector / self.largest).tolist() if self.largest > 0 else [0.0] * 3
        return {
            "study": "envelope",
            "point": self.settings.point,
            "body": self.body,
            "plays": self.settings.plays,
            "largest_displacement": self.largest,
            "largest_direction": direction,
            "largest_vector": self.largest_vector.tolist(),
            "extent": {axis: ext[i].tolist() for i, axis in enumerate("xyz")},
            "directions": self.directions.tolist(),
            "support": self.h.tolist(),
            "hull": self.hull.tolist(),
        }

    def to_dataframe(self) -> pd.DataFrame:
        """One row per direction: u, the support value and the support point."""
        import pandas as pd

        return pd.DataFrame(
            {
                "ux": self.directions[:, 0],
                "uy": self.directions[:, 1],
                "uz": self.directions[:, 2],
                "support": self.h,
                "dx": self.hull[:, 0],
                "dy": self.hull[:, 1],
                "dz": self.hull[:, 2],
            }
        )


def point_envelopes(
    model: Model, plays: Literal["max", "mean"] = "max", *, source: str | None = None
) -> tuple[dict[str, EnvelopeResult], dict[str, str]]:
    """Every functional point's envelope, and why a point has none: its joints
    leave it free along some direction (the message names the motion)."""
    found: dict[str, EnvelopeResult] = {}
    missing: dict[str, str] = {}
    for point in model.points:
        try:
            found[point.name] = Envelope(point.name, plays=plays).run(model, source=source)
        except UnboundedMechanismError as exc:
            missing[point.name] = str(exc)
    return found, missing
