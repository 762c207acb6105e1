"""Parametric mechanisms of any size, for scaling studies and benchmarks.

``tube_string(n)`` is a string of ``n`` tube segments along X, each 100 mm
long, each coupled to the one before (the first to the ground) by a spigot
fit and a dowel pin, both with play:

* a ``revolute`` joint at the coupling (spigot length 20 mm, radial play
  ``clearance``, axial play ``axial_clearance``) holds everything but the
  spin about X;
* a ``sphere_in_cylinder`` dowel 15 mm off the axis, parallel to it, holds
  the spin (and, redundantly, the spigot's radial play).

The last segment carries a side force, a torque about X and an axial pull at
its free end, so play adds up along the string. ``closed=True`` also rests
every segment in a bearing of its own at its middle (a ``sphere_in_cylinder``
in the ground, closing a loop through the ground at every segment, as in a
line shaft) and loads every segment with a side force there.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from jointplay.io.modelfile import model_from_dict
from jointplay.model.mechanism import Model

SEGMENT_MM = 100.0


def tube_string_dict(
    n: int,
    *,
    closed: bool = False,
    clearance: float = 0.02,
    axial_clearance: float = 0.05,
    dowel_clearance: float = 0.03,
    seed: int = 0,
) -> dict[str, Any]:
    """The model file's content (a plain dict) of an ``n``-segment string.
    Each joint's play is the nominal value times a factor in [0.7, 1.3), drawn
    with ``seed`` (a batch of real parts; equal plays everywhere would make
    many contact states exact ties)."""
    if n < 1:
        raise ValueError("a tube string needs at least one segment")
    rng = np.random.default_rng(seed)

    def play(nominal: float) -> float:
        return round(nominal * float(rng.uniform(0.7, 1.3)), 6)

    bodies: list[dict[str, Any]] = [{"name": "ground", "ground": True}]
    joints: list[dict[str, Any]] = []
    loads: list[dict[str, Any]] = []
    for i in range(1, n + 1):
        name, before = f"T{i}", ("ground" if i == 1 else f"T{i - 1}")
        x0 = (i - 1) * SEGMENT_MM
        bodies.append({"name": name})
        joints.append(
            {
                "name": f"spigot{i}",
                "type": "revolute",
                "between": [before, name],
                "at": [x0, 0, 0],
                "axis": [1, 0, 0],
                "length": 20,
                "clearance": play(clearance),
                "axial_clearance": play(axial_clearance),
            }
        )
        joints.append(
            {
                "name": f"dowel{i}",
                "type": "sphere_in_cylinder",
                "between": [before, name],
                "at": [x0, 15, 0],
                "axis": [1, 0, 0],
                "clearance": play(dowel_clearance),
            }
        )
        if closed:
            middle = [x0 + SEGMENT_MM / 2, 0, 0]
            joints.append(
                {
                    "name": f"bearing{i}",
                    "type": "sphere_in_cylinder",
                    "between": ["ground", name],
                    "at": middle,
                    "axis": [1, 0, 0],
                    "clearance": play(clearance),
                }
            )
            turn = float(rng.uniform(0, 2 * np.pi))
            side = [0.0, round(np.cos(turn), 6), round(np.sin(turn), 6)]
            loads.append({"body": name, "at": middle, "force": side})
    last = f"T{n}"
    loads.append({"body": last, "at": [n * SEGMENT_MM, 0, 0], "force": [50, 0, 0]})
    loads.append({"body": last, "torque": [2000, 0, 0]})
    return {"bodies": bodies, "joints": joints, "loads": loads}


def bearing_chain_dict(
    n: int, *, force: tuple[float, float, float] = (0.0, 1.0, 1.0)
) -> dict[str, Any]:
    """The model file's content of an ``n``-shaft bearing chain (see the
    module's docstring); ``force`` (N) acts on every shaft."""
    if n < 1:
        raise ValueError("a bearing chain needs at least one shaft")
    bodies: list[dict[str, Any]] = [{"name": "ground", "ground": True}]
    joints: list[dict[str, Any]] = []
    loads: list[dict[str, Any]] = []
    for i in range(1, n + 1):
        name, before = f"S{i}", ("ground" if i == 1 else f"S{i - 1}")
        x = (i - 1) * SEGMENT_MM
        bodies.append({"name": name})
        joints.append(
            {
                "name": f"bearing{i}",
                "type": "cylindrical",
                "between": ["ground", name],
                "at": [x, 0, 0],
                "axis": [1, 0, 0],
                "length": 40,
                "clearance": 0.2,
            }
        )
        joints.append(
            {
                "name": f"coupling{i}",
                "type": "revolute",
                "between": [before, name],
                "at": [x - SEGMENT_MM / 2, 0, 0],
                "axis": [1, 0, 0],
                "length": 40,
                "clearance": 0.1,
                "axial_clearance": 0.05,
            }
        )
        loads.append({"body": name, "at": [x + 30, 0, 0], "force": list(force)})
    return {
        "name": f"bearing chain, {n} shafts",
        "bodies": bodies,
        "joints": joints,
        "loads": loads,
    }


def bearing_chain(n: int, *, force: tuple[float, float, float] = (0.0, 1.0, 1.0)) -> Model:
    """An ``n``-shaft bearing chain (see the module's docstring) as a ``Model``."""
    return model_from_dict(bearing_chain_dict(n, force=force), source=f"<bearing chain, {n}>")


def tube_string(n: int, *, closed: bool = False, seed: int = 0) -> Model:
    """An ``n``-segment tube string (see the module's docstring) as a ``Model``."""
    kind = "closed" if closed else "open"
    data = tube_string_dict(n, closed=closed, seed=seed)
    return model_from_dict(data, source=f"<tube string, {n} segments, {kind}>")
