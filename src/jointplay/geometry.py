"""Frames, vectors and the joint-frame rule.

Naming: ``R_world_joint`` has the joint's x, y, z axes as columns, in global
axes, so ``R_world_joint @ v_joint`` gives a joint-frame vector in global axes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

Vec3 = tuple[float, float, float]
FloatArray = NDArray[np.float64]

GLOBAL_AXES: dict[str, FloatArray] = {
    "X": np.array([1.0, 0.0, 0.0]),
    "Y": np.array([0.0, 1.0, 0.0]),
    "Z": np.array([0.0, 0.0, 1.0]),
}

#: Below this sine of the angle, two directions count as parallel.
PARALLEL_SINE = 1e-9


def skew(v: FloatArray) -> FloatArray:
    """The matrix ``[v]x`` with ``[v]x @ w == cross(v, w)``."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """``a x b`` for 3-vectors, or row by row for stacks (..., 3) that
    broadcast (``np.cross`` costs 20 us on small arrays)."""
    if np.ndim(a) == 1 and np.ndim(b) == 1:
        return np.array(
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        )
    a, b = np.asarray(a), np.asarray(b)
    return np.asarray(
        a.take(_NEXT, axis=-1) * b.take(_AFTER, axis=-1)
        - a.take(_AFTER, axis=-1) * b.take(_NEXT, axis=-1)
    )


_NEXT = np.array([1, 2, 0])  # the cyclic components of a cross product
_AFTER = np.array([2, 0, 1])


def unit(v: FloatArray) -> FloatArray:
    v = np.asarray(v, dtype=float)
    return v / math.sqrt(float(v @ v))


def is_parallel(a: FloatArray, b: FloatArray) -> bool:
    c = cross(unit(a), unit(b))
    return math.sqrt(float(c @ c)) < PARALLEL_SINE


def joint_frame(
    axis: FloatArray | Sequence[float], up: FloatArray | Sequence[float] | None = None
) -> FloatArray:
    """Return ``R_world_joint`` for a joint whose x axis is ``axis``.

    The rule (documented in docs/conventions.md): x = axis; z = the part of
    ``up`` perpendicular to x, normalized; y = z cross x. ``up`` defaults to
    the global Z axis; when the axis itself is along global Z, the default
    ``up`` is global -X for +Z and +X for -Z, so that the frame is the global
    frame turned about global Y. With axis = global X and the default ``up``
    the joint frame is the global frame, as in the paper.
    """
    # plain floats: numpy's overhead on 3-vectors dominates for thousands of joints
    ax, ay, az = (float(c) for c in axis)
    x = _unit3((ax, ay, az))
    if up is None:
        up3: Vec3 = (0.0, 0.0, 1.0)
        if math.hypot(x[0], x[1]) < PARALLEL_SINE:  # along global Z
            up3 = (-math.copysign(1.0, x[2]), 0.0, 0.0)
    else:
        ux, uy, uz = (float(c) for c in up)
        up3 = (ux, uy, uz)
    # z = up - (up . x) x, written as x cross (up cross x): accurate also
    # when up is nearly along x (the subtraction would lose its digits)
    z = _unit3(_cross3(x, _cross3(up3, x)))
    y = _cross3(z, x)
    return np.array([x, y, z]).T.copy()


def _unit3(v: Vec3) -> Vec3:
    n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    return (v[0] / n, v[1] / n, v[2] / n)


def _cross3(a: Vec3, b: Vec3) -> Vec3:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def describe_direction(direction: FloatArray, signed: bool = False) -> str:
    """'the global X axis' style names for axis-aligned directions (with its
    sense, '+X' or '-X', when ``signed``), else the vector."""
    d = unit(direction)
    for name, axis in GLOBAL_AXES.items():
        if is_parallel(d, axis):
            sense = ("+" if float(d @ axis) > 0 else "-") if signed else ""
            return f"global {sense}{name}"
    return "[" + ", ".join(f"{c:.4g}" for c in d) + "]"


def fmt_point(p: FloatArray) -> str:
    return "(" + ", ".join(f"{0.0 if abs(c) < 1e-12 else c:.6g}" for c in p) + ") mm"


def describe_motion(
    omega: FloatArray, v_origin: FloatArray, ell: float, signed: bool = False
) -> str:
    """A small rigid motion in words: a translation, a rotation about an axis,
    or a screw (``signed``: name the sense of a translation, for a motion
    that is free one way only)."""
    w = float(np.linalg.norm(omega))
    v = float(np.linalg.norm(v_origin))
    if w * ell <= 1e-9 * v:
        return f"translation along {_axis_words(v_origin, signed)}"
    axis_point = cross(omega, v_origin) / w**2
    axis_point = np.where(np.abs(axis_point) <= 1e-9 * ell, 0.0, axis_point) + 0.0  # round-off
    pitch = float(omega @ v_origin) / w**2
    if np.linalg.norm(axis_point) <= 1e-9 * ell:
        where = f"rotation about {_axis_words(omega, signed)}"
    else:
        name = describe_direction(omega, signed)
        along = f"parallel to {name}" if name.startswith("global") else f"along {name}"
        where = f"rotation about an axis {along} through {fmt_point(axis_point)}"
    if abs(pitch) > 1e-9 * ell:
        where = f"screw motion ({where}, {pitch:.4g} mm of slide per rad)"
    return where


def _axis_words(direction: FloatArray, signed: bool = False) -> str:
    name = describe_direction(direction, signed)
    return f"the {name} axis" if name.startswith("global") else f"the direction {name}"


# -- finite rotations (the exact placement of a body: finite.py, solver/exact.py)


def rotation_matrix(omega: FloatArray) -> FloatArray:
    """``exp([omega]x)``: the rotation by |omega| rad about omega (Rodrigues)."""
    theta = float(np.linalg.norm(omega))
    K = skew(np.asarray(omega, dtype=float))
    if theta < 1e-8:
        return np.asarray(np.eye(3) + K + 0.5 * K @ K)
    return np.asarray(
        np.eye(3) + np.sin(theta) / theta * K + (1.0 - np.cos(theta)) / theta**2 * K @ K
    )


def rotation_vector(R: FloatArray) -> FloatArray:
    """The inverse of ``rotation_matrix`` (angles below pi)."""
    cos = float(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))
    theta = float(np.arccos(cos))
    axis_sin = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if theta < 1e-6:
        return np.asarray(axis_sin * (1.0 + theta**2 / 6.0))
    return np.asarray(axis_sin * theta / np.sin(theta))


def left_jacobian(phi: FloatArray) -> FloatArray:
    """``J_l``: exp(phi + d) = exp(J_l d) exp(phi) to first order."""
    theta = float(np.linalg.norm(phi))
    K = skew(np.asarray(phi, dtype=float))
    if theta < 1e-6:
        return np.asarray(np.eye(3) + 0.5 * K + K @ K / 6.0)
    a = (1.0 - np.cos(theta)) / theta**2
    b = (theta - np.sin(theta)) / theta**3
    return np.asarray(np.eye(3) + a * K + b * K @ K)


def left_jacobian_inverse(phi: FloatArray) -> FloatArray:
    theta = float(np.linalg.norm(phi))
    K = skew(np.asarray(phi, dtype=float))
    if theta < 1e-6:
        return np.asarray(np.eye(3) - 0.5 * K + K @ K / 12.0)
    c = 1.0 / theta**2 - (1.0 + np.cos(theta)) / (2.0 * theta * np.sin(theta))
    return np.asarray(np.eye(3) - 0.5 * K + c * K @ K)
