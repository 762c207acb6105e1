#!/usr/bin/env python
"""A random campaign: N seeded mechanisms through the CLI, each answer checked
independently.

Not a timing benchmark: it draws ``--n`` mechanisms (500 by default) from
``--seed``, over every joint type (spherical, cylindrical, revolute,
sphere_in_cylinder, prismatic, slot, planar with a rectangle or a disc, point,
rigid) and every feature: drives with and without backlash play and
``torsional_stiffness``, screws (``axial_clearance`` on prismatic and
cylindrical), a slot's ``slot_length``, contact ``stiffness``, gravity with
masses, deviations (a joint's own and shared), several load cases, chains
and closed loops, one-sided point contacts that the loads press or lift off,
and ties (free motions that no load drives, held only by the least-norm
convention). Each is written to a YAML file and solved by the command line,
``jointplay solve FILE --json`` (in-process through Typer's runner, or with
``--subprocess`` a process each), and classified from its exit code and
JSON alone, against tests/reference.py (SciPy only, no solver import):

* exit 0 on a held mechanism: checked from the printed numbers (every contact
  within its play, a spring past it by force / stiffness; each body's
  contact forces and loads in balance; each force in its contact's cone; the
  duality gap of the printed positions and forces) and against the
  reference's positions and energy (its SLSQP minimum, then its least-norm
  point among the minima); a difference counts as wrong only when one side is
  shown better: a lower energy, or at the same energy a lower least-norm
  metric, at the certificate's tolerance. ``ok``, else ``wrong``.
* exit 3: must name a moving body and its motion, and the reference's linear
  program must find a motion that no contact holds, which the loads drive and
  in which that body moves: ``not held``; on a held mechanism ``wrong``.
* exit 1 on a held mechanism: ``declined``; on one that is not held: ``wrong``.
* exit 2: a generator bug (the campaign stops).

Every failing model is saved under ``campaign_failures/`` (not committed)
with what failed. Run from the repository root:
``python benchmarks/campaign.py`` (``--n 500 --seed 0``).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from reference import Reference, frame  # noqa: E402

FAILURES = ROOT / "campaign_failures"

# -- the promises checked (the certificate's, docs/formulation.md section 12) ---------

#: of the largest play (at least 1 mm): how far a contact may go past its play.
FEASIBLE = 1e-9
#: of the largest force in the balance (a load or a joint's reaction): each
#: body's force and moment sums (moments over the metric length).
BALANCE = 1e-8
#: of the energy scale sum(|force| * reach), per touching contact: the duality
#: gap and energy comparisons (tests/test_properties.py, ENERGY).
ENERGY = 2e-8
#: positions against the reference: mm, and rad times the model length, each
#: times the largest play (at least 1 mm).
SAME_MM = 1e-6
SAME_RAD = 1e-8
#: the work of the loads on a motion that no contact holds, relative to the
#: loads times the motion's size: above it the reference calls the mechanism
#: not held; below HELD it is held; in between, undecided (a generator slip).
DRIVEN = 1e-6
HELD = 1e-10


# -- the generator --------------------------------------------------------------------


def unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def frame_of(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    R = frame(unit(rng), unit(rng))
    return R[:, 0], R[:, 1], R[:, 2]


def plain(value: Any) -> Any:
    """``value`` with NumPy numbers and arrays made plain Python (for YAML)."""
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def lst(v: Any) -> list[float]:
    return [float(c) for c in np.asarray(v, dtype=float)]


@dataclass
class Gen:
    """Draws joints and loads; records which features a mechanism has."""

    rng: np.random.Generator
    compliant: bool
    features: set[str] = field(default_factory=set)
    joints: list[dict[str, Any]] = field(default_factory=list)

    def play(self) -> float:
        return float(10 ** self.rng.uniform(-3, math.log10(2.0)))  # mm, 1 um to 2 mm

    def length(self) -> float:
        return float(self.rng.uniform(8.0, 120.0))

    def point(self) -> np.ndarray:
        return self.rng.uniform(-250, 250, size=3)

    def joint(self, kind: str, a: str, b: str, at: Any, axis: Any, **more: Any) -> dict[str, Any]:
        out: dict[str, Any] = {"type": kind, "between": [a, b], "at": lst(at), "axis": lst(axis)}
        if kind != "slot" and self.rng.random() < 0.5:
            up = unit(self.rng)
            while abs(float(up @ axis)) > 0.9:
                up = unit(self.rng)
            out["up"] = lst(up)
        if kind in ("spherical", "cylindrical", "revolute", "sphere_in_cylinder", "planar", "slot"):
            out["clearance"] = self.play()
        if kind in ("cylindrical", "revolute", "slot"):
            out["length"] = self.length()
        if kind == "revolute":
            out["axial_clearance"] = self.play()
        if kind == "prismatic":
            for key in ("length", "width", "height"):
                out[key] = self.length()
            out["clearance_y"], out["clearance_z"] = self.play(), self.play()
        if kind == "planar":
            if self.rng.random() < 0.5:
                out["diameter"] = self.length()
                self.features.add("planar disc")
            else:
                out["width"], out["height"] = self.length(), self.length()
        if kind == "slot" and "along" not in more:
            along = unit(self.rng)
            while abs(float(along @ axis)) > 0.9:
                along = unit(self.rng)
            out["along"] = lst(along)
        if kind == "point" and self.rng.random() < 0.5:
            out["gap"] = self.play()
        if kind != "rigid" and self.compliant and self.rng.random() < 0.4:
            out["stiffness"] = float(10 ** self.rng.uniform(1, 6))
            self.features.add("stiffness")
        out.update(more)
        self.features.add(f"joint {kind}")
        self.joints.append(out)
        return out

    def drive(self, joint: dict[str, Any], ideal: bool = False) -> None:
        """A drive on a revolute or cylindrical joint: backlash 0 (ideal), or
        a play of 0.01 to 2 mrad, perhaps with a torsional stiffness."""
        if ideal:
            joint["backlash"] = 0.0
            self.features.add("drive ideal")
            return
        joint["backlash"] = float(10 ** self.rng.uniform(-5, math.log10(2e-3)))
        self.features.add("drive backlash")
        if self.rng.random() < 0.5:
            joint["torsional_stiffness"] = float(10 ** self.rng.uniform(4, 8))  # N*mm/rad
            self.features.add("drive torsional_stiffness")

    def force(self) -> float:
        return float(10 ** self.rng.uniform(-2, 3))  # N

    def load(self, body: str) -> dict[str, Any]:
        which = self.rng.choice(["force", "torque", "both"])
        out: dict[str, Any] = {"body": body}
        if which != "torque":
            out["at"], out["force"] = lst(self.point()), lst(self.force() * unit(self.rng))
        if which != "force":
            out["torque"] = lst(100 * self.force() * unit(self.rng))
        return out


Frame = tuple[np.ndarray, np.ndarray, np.ndarray]


def holding_set(gen: Gen, a: str, b: str, c: np.ndarray, e: Frame) -> str:
    """Joints between a and b that hold every relative motion; returns its name."""
    rng = gen.rng
    how = str(
        rng.choice(
            [
                "rigid",
                "three_spheres",
                "shaft_and_stop",
                "driven_shaft",
                "hinge_and_stop",
                "driven_hinge",
                "hinge_and_points",
                "screw_slide",
                "nut_and_drive",
                "slider_and_face",
                "plate_and_pins",
                "located_plate",
                "hinge_and_slot",
                "crossed_bores",
            ]
        )
    )
    lever = lambda: float(rng.uniform(20, 150))  # noqa: E731
    if how == "rigid":
        gen.joint("rigid", a, b, c, e[0])
    elif how == "three_spheres":
        for p in (c, c + lever() * e[0], c + lever() * e[1]):
            gen.joint("spherical", a, b, p, unit(rng))
    elif how in ("shaft_and_stop", "driven_shaft"):
        gen.joint("spherical", a, b, c, e[0])
        bore = gen.joint("cylindrical", a, b, c + lever() * e[0], e[0])
        if how == "shaft_and_stop":
            gen.joint("sphere_in_cylinder", a, b, c + lever() * e[1], e[0])
        else:
            gen.drive(bore, ideal=rng.random() < 0.15)
    elif how in ("hinge_and_stop", "driven_hinge"):
        hinge = gen.joint("revolute", a, b, c, e[0])
        if how == "hinge_and_stop":
            gen.joint("sphere_in_cylinder", a, b, c + lever() * e[1], e[0])
        else:
            gen.drive(hinge, ideal=rng.random() < 0.15)
            if rng.random() < 0.2:
                hinge["axial_clearance"] = 0.0
                gen.features.add("axial_clearance 0")
    elif how == "hinge_and_points":
        arm = c + lever() * e[1]
        gen.joint("revolute", a, b, c, e[0])
        gen.joint("point", a, b, arm, e[2])
        gen.joint("point", a, b, arm, -e[2])
    elif how == "screw_slide":
        gen.joint("prismatic", a, b, c, e[0], axial_clearance=gen.play())
        gen.features.add("screw prismatic")
    elif how == "nut_and_drive":
        nut = gen.joint("cylindrical", a, b, c, e[0], axial_clearance=gen.play())
        gen.drive(nut)
        gen.features.add("screw cylindrical")
    elif how == "slider_and_face":
        face = c + rng.uniform(-150, 150) * e[1] + rng.uniform(-150, 150) * e[2]
        gen.joint("prismatic", a, b, c, e[0])
        gen.joint("planar", a, b, face, e[0])
    elif how == "plate_and_pins":
        gen.joint("planar", a, b, c, e[0])
        for p in (c + lever() * e[1], c + lever() * e[2]):
            gen.joint("sphere_in_cylinder", a, b, p, e[0])
    elif how == "located_plate":  # a hole pin, a slot pin pointing at it, a face
        gen.joint("planar", a, b, c + lever() * e[2], e[0])
        gen.joint("sphere_in_cylinder", a, b, c, e[0])
        gen.joint("slot", a, b, c + lever() * e[1], e[0], along=lst(e[1]))
    elif how == "hinge_and_slot":  # a hinge whose spin a slot pin with a travel holds
        gen.joint("revolute", a, b, c, e[0])
        gen.joint("slot", a, b, c + lever() * e[1], e[0], along=lst(e[1]), slot_length=gen.play())
        gen.features.add("slot_length")
    else:  # crossed_bores
        gen.joint("cylindrical", a, b, c, e[0])
        gen.joint("cylindrical", a, b, c + lever() * e[1], e[2])
    return how


#: A free motion of a leaf: (rotation W, translation V at the origin), global axes.
Twist = tuple[np.ndarray, np.ndarray]


def free_leaf(gen: Gen, a: str, b: str, c: np.ndarray, e: Frame) -> tuple[str, Twist, Any]:
    """Joints that leave known motions free; returns the kind, one of its
    free motions, and a maker of loads that do no work on any of them (a
    force through the free axis, or across the free slides)."""
    rng = gen.rng
    kind = str(
        rng.choice(["hinge", "shaft", "slider", "bore", "ball", "slot", "parallel_bores", "sic"])
    )
    far = c + float(rng.uniform(20, 150)) * e[1]
    spin = (e[0], np.cross(c, e[0]))  # V at O = W x (O - c)
    slide = (np.zeros(3), e[0])

    def load(at: np.ndarray, force: np.ndarray) -> dict[str, Any]:
        return {"body": b, "at": lst(at), "force": lst(gen.force() * force)}

    def anywhere(direction: np.ndarray) -> Any:
        return lambda: load(gen.point(), direction)

    def on_axis(direction: np.ndarray) -> Any:
        return lambda: load(c + rng.uniform(-100, 100) * e[0], direction)

    across = (
        math.cos(rng.uniform(0, 2 * math.pi)) * e[1] + math.sin(rng.uniform(0, 2 * math.pi)) * e[2]
    )
    across /= np.linalg.norm(across)
    if kind == "hinge":  # the spin about e1 through c
        gen.joint("revolute", a, b, c, e[0])
        return kind, spin, anywhere(e[0])
    if kind == "shaft":  # the spin about the line through both centres
        gen.joint("spherical", a, b, c, e[0])
        gen.joint("cylindrical", a, b, c + float(rng.uniform(20, 150)) * e[0], e[0])
        return kind, spin, anywhere(e[0])
    if kind == "slider":  # the slide along e1
        gen.joint("prismatic", a, b, c, e[0])
        return kind, slide, anywhere(across)
    if kind == "bore":  # slide along and spin about the axis
        gen.joint("cylindrical", a, b, c, e[0])
        return kind, slide if rng.random() < 0.5 else spin, on_axis(across)
    if kind == "ball":  # any rotation about the centre
        w = unit(rng)
        gen.joint("spherical", a, b, c, e[0])
        return kind, (w, np.cross(c, w)), lambda: load(c, unit(rng))
    if kind == "slot":  # a pin in a slot and a ball in a bore on its axis: slide
        # along the axis (e1) and the slot (e2), spin about the axis
        gen.joint("slot", a, b, c, e[0], along=lst(e[1]))
        gen.joint("sphere_in_cylinder", a, b, c + float(rng.uniform(20, 150)) * e[0], e[0])
        motion = (np.zeros(3), e[1]) if rng.random() < 0.5 else spin
        return kind, motion, on_axis(e[2])
    if kind == "parallel_bores":  # the slide along e1
        for p in (c, far):
            gen.joint("cylindrical", a, b, p, e[0])
        return kind, slide, anywhere(across)
    # a ball in a bore and a bore off its axis, both along e1: the slide along e1
    gen.joint("sphere_in_cylinder", a, b, c, e[0])
    gen.joint("cylindrical", a, b, far, e[0])
    return kind, slide, anywhere(across)


def work_on(loads: list[dict[str, Any]], body: str, twist: Twist) -> float:
    W, V = twist
    out = 0.0
    for ld in loads:
        if ld["body"] == body:
            if "force" in ld:
                out += float(np.dot(ld["force"], V + np.cross(W, ld["at"])))
            if "torque" in ld:
                out += float(np.dot(ld["torque"], W))
    return out


def drive_load(gen: Gen, body: str, twist: Twist, others: list[dict[str, Any]]) -> dict[str, Any]:
    """A load whose work on ``twist``, with ``others``, is clearly positive."""
    W, V = twist
    rest = work_on(others, body, twist)
    if np.any(W) and gen.rng.random() < 0.5:
        out: dict[str, Any] = {"body": body, "torque": lst(100 * W)}
    else:
        at = gen.point()
        velocity = V + np.cross(W, at)
        if np.linalg.norm(velocity) < 1e-3:
            at = at + 50 * frame(W)[:, 1]
            velocity = V + np.cross(W, at)
        out = {"body": body, "at": lst(at), "force": lst(velocity / np.linalg.norm(velocity))}
    own = work_on([out], body, twist)
    size = (2 * abs(rest) + gen.force() * own) / own
    for key in ("force", "torque"):
        if key in out:
            out[key] = [size * v for v in out[key]]
    return out


def table(gen: Gen, a: str, b: str, c: np.ndarray, e: Frame) -> list[np.ndarray]:
    """Three point contacts (plane normal e1) and two pins in the feet's plane."""
    rng = gen.rng
    phase = rng.uniform(0, 2 * math.pi)
    feet = []
    for i in range(3):
        angle = phase + 2 * math.pi * i / 3 + rng.uniform(-0.5, 0.5)
        feet.append(c + rng.uniform(20, 150) * (math.cos(angle) * e[1] + math.sin(angle) * e[2]))
    for f in feet:
        gen.joint("point", a, b, f, e[0])
    gen.joint("sphere_in_cylinder", a, b, c, e[0])
    gen.joint("sphere_in_cylinder", a, b, c + rng.uniform(20, 150) * e[1], e[0])
    return feet


def table_loads(
    gen: Gen, body: str, c: np.ndarray, e: Frame, feet: list[np.ndarray], how: str
) -> list[dict[str, Any]]:
    """'push' inside the feet (held), 'lift' or 'tip' (lifts off), 'idle' (in
    the plane only: the height is a tie)."""
    rng = gen.rng
    out: list[dict[str, Any]] = []
    for _ in range(int(rng.integers(0 if how != "idle" else 1, 3))):
        in_plane = gen.force() * (rng.uniform(-1, 1) * e[1] + rng.uniform(-1, 1) * e[2])
        at = c + rng.uniform(-200, 200) * e[1] + rng.uniform(-200, 200) * e[2]
        out.append({"body": body, "at": lst(at), "force": lst(in_plane)})
    if how == "idle":
        return out
    weights = rng.uniform(0.05, 1.0, size=3)
    weights /= weights.sum()
    if how == "tip":
        k = int(rng.integers(0, 3))
        weights[k] = -rng.uniform(0.1, 2.0)
        others = [i for i in range(3) if i != k]
        weights[others] *= (1 - weights[k]) / weights[others].sum()
    where = sum(w * f for w, f in zip(weights, feet, strict=True)) + rng.uniform(-50, 50) * e[0]
    sense = 1.0 if how == "lift" else -1.0
    out.append({"body": body, "at": lst(where), "force": lst(sense * gen.force() * e[0])})
    return out


@dataclass
class Mechanism:
    data: dict[str, Any]
    held: bool  # by design
    features: set[str]
    design: list[str]


def deviate(gen: Gen, data: dict[str, Any]) -> None:
    """Deviations on a few bores and balls (their means shift the domains),
    and perhaps one shared by two joints of one body pair; each kept to a
    third of its joint's play, so that the parts still go together."""
    rng = gen.rng
    joints = [
        j
        for j in data["joints"]
        if j["type"] in ("cylindrical", "revolute", "sphere_in_cylinder", "spherical")
        and "stiffness" not in j
    ]
    if not joints or rng.random() < 0.6:
        return
    for j in rng.permutation(len(joints))[: int(rng.integers(1, 3))]:
        joint = joints[int(j)]
        r = float(joint["clearance"]) / 2
        if joint["type"] == "spherical":
            joint["deviation"] = {
                "position": {"diameter": 0.5 * r, "mean": lst(0.15 * r * unit(rng))}
            }
        else:
            shift = 0.12 * r * frame(unit(rng))[:, 1]
            zones: dict[str, Any] = {
                "position": {
                    "y": {"min": shift[1] - 0.01 * r, "max": shift[1] + 0.01 * r},
                    "z": {"min": shift[2] - 0.01 * r, "max": shift[2] + 0.01 * r},
                }
            }
            if joint["type"] != "sphere_in_cylinder" and rng.random() < 0.6:
                tilt = 0.12 * r / (float(joint["length"]) / 2)
                turn = rng.uniform(0, 2 * math.pi)
                zones["orientation"] = {
                    "angle": 2 * tilt,
                    "mean": [0.0, tilt * math.cos(turn), tilt * math.sin(turn)],
                }
            joint["deviation"] = zones
        gen.features.add("deviation")
    # a shared one: two bores or balls of one pair, made in one setup
    pairs: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
    for joint in joints:
        if "deviation" not in joint:
            pairs[tuple(joint["between"])].append(joint)
    twins = [group for group in pairs.values() if len(group) >= 2]
    if twins and rng.random() < 0.6:
        group = twins[int(rng.integers(0, len(twins)))][:2]
        r = min(float(j["clearance"]) for j in group) / 2
        spread = max(1.0, float(np.linalg.norm(np.subtract(group[0]["at"], group[1]["at"]))))
        body = group[0]["between"][int(rng.integers(0, 2))]
        axis = unit(rng)
        data.setdefault("deviations", []).append(
            {
                "name": "setup",
                "body": body,
                "at": group[0]["at"],
                "axis": lst(axis),
                "position": {"diameter": 0.5 * r, "mean": lst(0.1 * r * frame(axis)[:, 1])},
                "orientation": {"angle": 0.2 * r / spread, "mean": [0.0, 0.05 * r / spread, 0.0]},
            }
        )
        for joint in group:
            joint["deviation"] = "setup"
        gen.features.add("deviation shared")


def mechanism(rng: np.random.Generator, index: int) -> Mechanism:
    """One random mechanism: a ground and 1 to 6 moving bodies in a random
    tree of holding sets, perhaps one special leaf (free and driven, a tie,
    or a table pressed, lifted or tipped), extra joints closing loops, loads,
    weights, load cases and deviations."""
    gen = Gen(rng, compliant=bool(rng.random() < 0.5))
    n = int(rng.integers(2, 8))
    names = ["G"] + [f"B{i}" for i in range(1, n)]
    design: list[str] = []
    loads: list[dict[str, Any]] = []
    special = str(rng.choice(["none", "none", "free", "tie", "push", "lift", "tip", "idle"]))
    held_bodies = names[1:-1] if special != "none" else names[1:]
    for i, body in enumerate(held_bodies, start=1):
        parent = names[int(rng.integers(0, i))]
        how = holding_set(gen, parent, body, gen.point(), frame_of(rng))
        design.append(f"{body} on {parent}: {how}")
    leaf = names[-1]
    twist: Twist | None = None
    idle: Any = None
    held = True
    if special != "none":
        parent = names[int(rng.integers(0, n - 1))]
        c, e = gen.point(), frame_of(rng)
        if special in ("free", "tie"):
            kind, twist, idle = free_leaf(gen, parent, leaf, c, e)
            design.append(
                f"{leaf} on {parent}: {kind} ({'free, driven' if special == 'free' else 'tie'})"
            )
            gen.features.add("not held: free motion" if special == "free" else "tie: free motion")
            held = special == "tie"
        else:
            feet = table(gen, parent, leaf, c, e)
            loads += table_loads(gen, leaf, c, e, feet, special)
            design.append(f"{leaf} on {parent}: table, {special}")
            gen.features.add(
                {
                    "push": "point pressed",
                    "lift": "not held: lift-off",
                    "tip": "not held: tipping",
                    "idle": "tie: lifted height",
                }[special]
            )
            held = special in ("push", "idle")
    # extra joints close loops, never on the special leaf
    pool = names[:-1] if special != "none" else names
    if len(pool) > 2 or (len(pool) == 2 and rng.random() < 0.5):
        for _ in range(int(rng.integers(0, 3))):
            a, b = (str(v) for v in rng.choice(pool, size=2, replace=False))
            if a == "G" and b == "G":
                continue
            kind = str(
                rng.choice(
                    [
                        "spherical",
                        "cylindrical",
                        "revolute",
                        "sphere_in_cylinder",
                        "prismatic",
                        "slot",
                        "planar",
                        "point",
                        "rigid",
                    ]
                )
            )
            joint = gen.joint(kind, a, b, gen.point(), unit(rng))
            if kind in ("revolute", "cylindrical") and rng.random() < 0.3:
                gen.drive(joint)
            design.append(f"extra {kind} {a}-{b}")
            gen.features.add("closed loop")
    if len(held_bodies) >= 2:
        gen.features.add("chain")
    movers = list(held_bodies)
    if movers:
        for _ in range(int(rng.integers(0 if special != "none" else 1, 4))):
            loads.append(gen.load(str(rng.choice(movers))))
    bodies: list[dict[str, Any]] = [{"name": "G", "ground": True}] + [
        {"name": b} for b in names[1:]
    ]
    data: dict[str, Any] = {"name": f"campaign {index}", "bodies": bodies}
    weighed = rng.random() < 0.3
    if weighed:
        data["gravity"] = [0, 0, "-9.81 m/s^2"]
        for body in bodies[1:]:  # the special leaf's loads are its design's alone
            if body["name"] in movers and rng.random() < 0.7:
                body["mass"] = float(rng.uniform(0.01, 20.0))
                body["center_of_mass"] = lst(gen.point())
        gen.features.add("gravity")
    cases = rng.random() < 0.3 and movers
    driven_case = False
    if twist is not None:
        on_leaf = [idle() for _ in range(int(rng.integers(0, 3)))]
        if special == "free":
            if cases and rng.random() < 0.5:
                driven_case = True
            else:
                on_leaf.append(drive_load(gen, leaf, twist, on_leaf))
        loads += on_leaf
    for k, joint in enumerate(gen.joints):
        joint["name"] = f"j{k}"
    data["joints"] = [{"name": j.pop("name"), **j} for j in gen.joints]
    if loads:
        data["loads"] = loads
    if cases:
        data["load_cases"] = {}
        for name in ("case a", "case b", "case c")[: int(rng.integers(2, 4))]:
            data["load_cases"][name] = [
                gen.load(str(rng.choice(movers))) for _ in range(int(rng.integers(1, 3)))
            ]
        if driven_case:
            assert twist is not None
            data["load_cases"]["case b"].append(drive_load(gen, leaf, twist, loads))
        gen.features.add("load cases")
    deviate(gen, data)
    return Mechanism(plain(data), held, gen.features, design)


# -- the CLI ----------------------------------------------------------------------------


def solve_cli(path: Path, in_process: bool) -> tuple[int, dict[str, Any] | None, str]:
    """(exit code, JSON document or None, stderr) of ``jointplay solve PATH --json``."""
    if not in_process:
        proc = subprocess.run(
            [
                sys.executable,
                "-c",
                "from jointplay.cli import main; main()",
                "solve",
                str(path),
                "--json",
            ],
            capture_output=True,
            text=True,
            timeout=600,
        )
        code, out, err = proc.returncode, proc.stdout, proc.stderr
    else:
        from typer.testing import CliRunner

        from jointplay.cli import app

        result = CliRunner().invoke(app, ["solve", str(path), "--json"])
        code, out = result.exit_code, result.stdout
        try:
            err = result.stderr
        except ValueError:
            err = ""
    try:
        doc = json.loads(out) if out.strip() else None
    except json.JSONDecodeError:
        doc = None
    return code, doc, err


# -- the checks -------------------------------------------------------------------------


def reported_x(ref: Reference, doc: dict[str, Any]) -> np.ndarray:
    x = np.zeros(ref.m)
    for name, i in ref.index.items():
        x[6 * i : 6 * i + 3] = doc["bodies"][name]["translation"]
        x[6 * i + 3 : 6 * i + 6] = doc["bodies"][name]["rotation"]
    return x


def wrench_of(rj: Any, contact: dict[str, Any]) -> np.ndarray:
    """(force, moment about the joint centre) of a printed contact, joint frame."""
    F = np.asarray(contact["force"], dtype=float)
    p = rj.R.T @ (np.asarray(contact["point"], dtype=float) - rj.centre)
    return np.r_[F, np.cross(p, F) + np.asarray(contact["torque"], dtype=float)]


def check_answer(ref: Reference, doc: dict[str, Any]) -> list[str]:
    """What is wrong with one printed answer (empty: nothing)."""
    problems: list[str] = []
    x = reported_x(ref, doc)
    play = max(1.0, ref.play)
    ell = ref.metric_length()
    # print rounding: a length below 1e-9 of the largest play, an angle below
    # that over the model's length, is printed 0 (jointplay.proven)
    step_mm = FEASIBLE * ref.play
    step_rad = step_mm / ell
    tol_mm = FEASIBLE * play
    # -- feasibility, on the printed joint torsors ------------------------------------
    for rj in ref.joints:
        jd = doc["joints"][rj.name]
        axes = np.column_stack([jd["axes"][k] for k in "xyz"])
        if np.max(np.abs(axes - rj.R)) > 1e-9:
            problems.append(f"joint {rj.name}: axes {axes.tolist()}, expected {rj.R.tolist()}")
        tau = np.r_[jd["translation"], jd["rotation"]]
        from_bodies = rj.G @ x
        slack = 3 * (step_mm + step_rad * 300) + tol_mm
        if (
            np.max(np.abs(tau[:3] - from_bodies[:3])) > slack
            or np.max(np.abs(tau[3:] - from_bodies[3:])) * ell > slack
        ):
            problems.append(
                f"joint {rj.name}: torsor {tau.tolist()} is not the bodies' {from_bodies.tolist()}"
            )
        printed = {c["name"]: c for c in jd["contacts"]}
        if sorted(printed) != sorted(c.name for c in rj.contacts):
            problems.append(
                f"joint {rj.name}: contacts {sorted(printed)},"
                f" expected {sorted(c.name for c in rj.contacts)}"
            )
            continue
        for c in rj.contacts:
            rounding = (
                (np.sum(np.abs(c.rows[:, :3])) * step_mm + np.sum(np.abs(c.rows[:, 3:])) * step_rad)
                if len(c.rows)
                else 0.0
            )
            if c.offset is not None:
                rounding += (
                    np.sum(np.abs(c.offset[:3])) * step_mm + np.sum(np.abs(c.offset[3:])) * step_rad
                )
            tol = tol_mm + rounding
            level = c.level(tau)
            if c.fixed:
                if np.max(np.abs(c.rows @ (tau - c.centre))) > tol:
                    problems.append(f"joint {rj.name} {c.name}: fixed, moves {c.rows @ tau}")
                continue
            lam = (
                float(np.linalg.norm(printed[c.name]["force"]))
                + float(np.linalg.norm(printed[c.name]["torque"])) / c.lever
            )
            past = lam / c.stiffness if c.stiffness else 0.0
            if level > c.radius + past + tol + BALANCE * 10 * max(past, 0.0):
                problems.append(
                    f"joint {rj.name} {c.name}: {level - c.radius - past:.3g} mm past its play"
                )
    # -- balance and cones -----------------------------------------------------------
    loads_size = ref.load_size()
    reactions = [
        float(np.linalg.norm(doc["joints"][rj.name]["reaction"]["force"])) for rj in ref.joints
    ]
    size = max([loads_size, *reactions])
    lam_of: dict[int, float] = {}
    dual = 0.0
    touching = 0
    scale_energy = 0.0
    if size > 0:
        F = {b: np.zeros(3) for b in ref.moving}
        M = {b: np.zeros(3) for b in ref.moving}
        count = dict.fromkeys(ref.moving, 0)
        for ld in ref.loads:
            F[ld.body] += ld.force
            M[ld.body] += ld.torque + (np.cross(ld.at, ld.force) if ld.at is not None else 0.0)
        for rj in ref.joints:
            jd = doc["joints"][rj.name]
            printed = {c["name"]: c for c in jd["contacts"]}
            total = np.zeros(6)
            for c in rj.contacts:
                W = wrench_of(rj, printed[c.name])
                total += W
                if c.fixed:
                    # held at its centre (a deviation moves it): its part of the dual bound
                    dual += float(W @ c.centre)
                    continue
                # in the contact's rows: the wrench on b is -(rows^T f + lam offset), |f| <= lam
                basis = c.rows.T if c.offset is None else np.column_stack([c.rows.T, c.offset])
                coef, *_ = np.linalg.lstsq(basis, -W, rcond=None)
                off = float(np.linalg.norm(basis @ coef + W))
                if off > BALANCE * size * max(1.0, ell):
                    problems.append(
                        f"joint {rj.name} {c.name}: force {W.tolist()} outside its"
                        f" contact's directions ({off:.3g})"
                    )
                if c.offset is None:
                    lam = float(np.linalg.norm(coef))
                else:
                    f, lam = coef[:-1], float(coef[-1])
                    if lam < -BALANCE * size or float(np.linalg.norm(f)) > lam + BALANCE * size:
                        problems.append(
                            f"joint {rj.name} {c.name}: force {W.tolist()} pulls or slides"
                            f" (lam {lam:.3g}, |f| {np.linalg.norm(f):.3g})"
                        )
                    lam = max(lam, 0.0)
                lam_of[id(c)] = lam
                # its part of the dual bound -(lam r + lam^2 / 2k + (rows^T f + lam o) . delta)
                dual -= (
                    lam * c.radius
                    + (lam * lam / (2 * c.stiffness) if c.stiffness else 0.0)
                    + float(-W @ c.centre)
                )
                level = c.level(np.r_[jd["translation"], jd["rotation"]])
                scale_energy += lam * max(c.radius, abs(level))
                touching += bool(printed[c.name]["in_contact"])
            if rj.type != "rigid":
                reaction = np.r_[jd["reaction"]["force"], jd["reaction"]["moment"]]
                if np.max(np.abs(reaction - total)) > 1e-9 * size * max(1.0, ell):
                    problems.append(
                        f"joint {rj.name}: reaction {reaction.tolist()} is not its"
                        f" contacts' sum {total.tolist()}"
                    )
            else:
                total = np.r_[jd["reaction"]["force"], jd["reaction"]["moment"]]
            force, moment = (
                rj.R @ total[:3],
                rj.R @ total[3:] + np.cross(rj.centre, rj.R @ total[:3]),
            )
            for body, sign in ((rj.b, 1.0), (rj.a, -1.0)):
                if body in F:
                    F[body] += sign * force
                    M[body] += sign * moment
                    count[body] += len(rj.contacts)
        for b in ref.moving:
            centre = np.mean([rj.centre for rj in ref.joints if b in (rj.a, rj.b)], axis=0)
            moment = M[b] - np.cross(centre, F[b])  # about the body's joint centroid
            rounding = 3 * count[b] * 1e-10 * size  # forces below 1e-10 of the largest print 0
            f = float(np.linalg.norm(F[b]))
            mm = float(np.linalg.norm(moment)) / ell
            if max(f, mm) > BALANCE * size + rounding:
                problems.append(
                    f"body {b}: unbalanced, force {f / size:.3g}, moment {mm / size:.3g}"
                    f" of the largest force {size:.6g} N"
                )
    # -- energy: the printed one, the duality gap ---------------------------------------
    energy = ref.energy(ref.restore(x))
    e_loads = -float(ref.g() @ x)
    levers = [float(np.linalg.norm(ld.at)) for ld in ref.loads if ld.at is not None]
    printed_tol = (
        loads_size * max(1, len(ref.loads)) * (step_mm + max([*levers, ell]) * step_rad) * 3
    )
    scale = max(scale_energy, abs(energy), loads_size * ref.play, 1e-300)
    e_tol = ENERGY * scale * max(1, touching)
    if abs(doc["potential_energy"] - e_loads) > e_tol + printed_tol:
        problems.append(
            f"energy {doc['potential_energy']!r} printed, the loads' work gives {-e_loads!r}"
        )
    gap = ref.energy(x) - dual
    if not problems and abs(gap) > e_tol + printed_tol:
        problems.append(f"duality gap {gap:.3g} N*mm (tolerance {e_tol + printed_tol:.3g})")
    return problems


def compare_reference(
    ref: Reference, doc: dict[str, Any], rng: np.random.Generator
) -> tuple[str, list[str]]:
    """('ok' | 'wrong' | 'unsure', notes): the printed positions against the
    reference's. Its SLSQP minimum (three starts: the centred position, the
    printed answer, a random one) must not be lower than the printed energy
    (at the certificate's tolerance); where its positions differ by more than
    SAME_MM / SAME_RAD (a tie), its least-norm point among the minima decides:
    the same positions, or a smaller metric (the printed answer is not the
    tie rule's point: wrong), or neither (the reference did not settle: unsure)."""
    x = reported_x(ref, doc)
    play = max(1.0, ref.play)
    e_jp, m_jp = ref.energy(x), ref.metric(x)
    scale = max(abs(e_jp), ref.load_size() * ref.play, 1e-300)
    touching = sum(c["in_contact"] for j in doc["joints"].values() for c in j["contacts"])
    e_tol = ENERGY * scale * max(1, touching)
    tiny = 1e-11 * scale

    def usable(y: np.ndarray) -> bool:
        return ref.is_feasible(y, tol=1e-12 * ref.play)

    starts = [np.zeros(ref.m), x, ref.restore(ref.D * rng.normal(size=ref.m))]
    ends = [e for e in (ref.restore(e) for e in ref.slsqp(starts)) if usable(e)]
    if not ends:
        return "unsure", ["the reference's SLSQP found no feasible point"]
    energies = [ref.energy(e) for e in ends]
    e_ref = min(energies)
    if e_ref < e_jp - e_tol:
        return "wrong", [f"the reference finds energy {e_ref!r} N*mm, below the printed {e_jp!r}"]

    def close(y: np.ndarray) -> bool:
        return close_to(y, x)

    def close_to(y: np.ndarray, z: np.ndarray) -> bool:
        for rj in ref.joints:
            d = rj.G @ (y - z)
            if np.max(np.abs(d[:3])) > SAME_MM * play or np.max(np.abs(d[3:])) > SAME_RAD * play:
                return False
        return True

    if any(close(e) for e, en in zip(ends, energies, strict=True) if en <= e_ref + tiny):
        return "ok", []
    bound = min(e_ref, e_jp) + tiny
    best = ends[int(np.argmin(energies))]
    tries = [ref.restore(ref.least_norm(s, bound)) for s in (best, x)]
    tries = [y for y in tries if usable(y) and ref.energy(y) <= bound + tiny]
    if any(close(y) for y in tries):
        return "ok", []
    if len(tries) == 2 and close_to(tries[0], tries[1]):
        apart = max(float(np.max(np.abs(rj.G @ (tries[0] - x)))) for rj in ref.joints)
        return "wrong", [
            f"the reference's least-norm minimum (energy {ref.energy(tries[0])!r} N*mm, the"
            f" same from two starts) is {apart:.3g} apart from the printed one (energy {e_jp!r})"
        ]
    notes = []
    for y in tries:
        e_y, m_y = ref.energy(y), ref.metric(y)
        if m_y < m_jp - max(2 * SAME_MM * play * math.sqrt(max(m_jp, 0.0)), 1e-12 * play**2):
            return "wrong", [
                f"not the least-norm minimum: a feasible point of energy {e_y!r} N*mm (printed"
                f" {e_jp!r}) has the metric {m_y:.12g} mm^2 (printed {m_jp:.12g}); joints"
                f" {max(np.max(np.abs(rj.G @ (y - x))) for rj in ref.joints):.3g} apart"
            ]
        notes.append(
            f"reference point differs: energy {e_y!r} vs {e_jp!r}, metric {m_y:.12g} vs {m_jp:.12g}"
        )
    return "unsure", notes or ["the reference's least-norm SLSQP did not settle"]


def check_not_held(ref: Reference, doc: dict[str, Any]) -> list[str]:
    """An exit 3: a moving body and its motion named; the reference finds a
    driven motion no contact holds, in which that body moves."""
    body, motion = doc.get("body"), doc.get("motion")
    if body not in ref.index or not motion:
        return [f"exit 3 names body {body!r}, motion {motion!r}"]
    work, _ = ref.driven_motion()
    size = float(np.linalg.norm(ref.g() * ref.D)) or 1.0
    if work <= DRIVEN * size:
        return [f"the reference finds no driven free motion (work {work:.3g} of {size:.3g})"]
    i = 6 * ref.index[body]
    for k in range(6):
        for sign in (1.0, -1.0):
            along = np.zeros(ref.m)
            along[i + k] = sign / ref.D[i + k]
            value, _ = ref.driven_motion(along=along)
            if value > 1e-6:
                return []
    return [f"body {body!r} does not move in any driven free motion the reference finds"]


def held_verdict(ref: Reference) -> str:
    """'held', 'not held' or 'undecided', from the reference's linear program."""
    work, _ = ref.driven_motion()
    size = float(np.linalg.norm(ref.g() * ref.D)) or 1.0
    if work > DRIVEN * size:
        return "not held"
    if work <= HELD * size:
        return "held"
    return "undecided"


def cases_of(data: dict[str, Any]) -> list[str | None]:
    return list(data["load_cases"]) if data.get("load_cases") else [None]


@dataclass
class Outcome:
    verdict: str  # ok, wrong, declined, not held, unsure
    notes: list[str]


def classify(
    mech: Mechanism, code: int, doc: dict[str, Any] | None, err: str, rng: np.random.Generator
) -> Outcome:
    data = mech.data
    refs = {case: Reference(data, case) for case in cases_of(data)}
    verdicts = {case: held_verdict(ref) for case, ref in refs.items()}
    held = all(v == "held" for v in verdicts.values())
    if any(v == "undecided" for v in verdicts.values()):
        return Outcome("unsure", [f"the reference cannot tell: {verdicts}"])
    if held != mech.held:
        return Outcome(
            "unsure",
            [f"by design {'held' if mech.held else 'not held'}, the reference says {verdicts}"],
        )
    if code == 2:
        raise SystemExit(f"exit 2 on a generated model (a generator bug): {err.strip()}")
    if code == 3:
        if held:
            return Outcome("wrong", [f"exit 3 on a held mechanism: {doc and doc.get('message')}"])
        driven = [case for case, v in verdicts.items() if v == "not held"]
        notes = check_not_held(refs[driven[0]], doc or {})
        if notes and len(driven) > 1:
            notes = min((check_not_held(refs[c], doc or {}) for c in driven), key=len)
        return Outcome("wrong" if notes else "not held", notes)
    if code == 1:
        if held:
            return Outcome("declined", [(doc or {}).get("message", err.strip())])
        return Outcome("wrong", [f"exit 1 on a mechanism that is not held: {err.strip()}"])
    if code != 0 or doc is None:
        return Outcome("wrong", [f"exit {code}, no JSON: {err.strip()}"])
    if not held:
        return Outcome(
            "wrong", [f"answered (exit 0) but the reference finds a driven free motion: {verdicts}"]
        )
    answers = doc.get("cases", {None: doc})
    notes: list[str] = []
    unsure: list[str] = []
    for case, answer in answers.items():
        ref = refs[case]
        problems = check_answer(ref, answer)
        if problems:
            notes += [f"case {case}: {p}" for p in problems]
            continue
        verdict, more = compare_reference(ref, answer, rng)
        if verdict == "wrong":
            notes += [f"case {case}: {p}" for p in more]
        elif verdict == "unsure":
            unsure += [f"case {case}: {p}" for p in more]
    if notes:
        return Outcome("wrong", notes)
    if unsure:
        return Outcome("unsure", unsure)
    return Outcome("ok", [])


# -- the campaign -------------------------------------------------------------------------


def run(
    n: int, seed: int, in_process: bool = True, save: Path | None = FAILURES, quiet: bool = False
) -> list[tuple[Mechanism, Outcome]]:
    import warnings

    warnings.filterwarnings("ignore")
    rng = np.random.default_rng(seed)
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(n):
            mech = mechanism(rng, i)
            path = Path(tmp) / f"m{i:04d}.yaml"
            text = yaml.safe_dump(mech.data, sort_keys=False, default_flow_style=None, width=110)
            path.write_text(text)
            code, doc, err = solve_cli(path, in_process)
            outcome = classify(mech, code, doc, err, np.random.default_rng([seed, i]))
            out.append((mech, outcome))
            if outcome.verdict not in ("ok", "not held") and save is not None:
                save.mkdir(exist_ok=True)
                head = [f"# campaign seed {seed}, mechanism {i}: {outcome.verdict} (exit {code})"]
                head += [f"# design: {d}" for d in mech.design]
                head += [f"# {line}" for note in outcome.notes for line in note.splitlines()]
                (save / f"seed{seed}_m{i:04d}_{outcome.verdict.replace(' ', '_')}.yaml").write_text(
                    "\n".join(head) + "\n" + text
                )
            if not quiet and (i + 1) % 25 == 0:
                counts = Counter(o.verdict for _, o in out)
                print(f"  {i + 1} / {n}: {dict(counts)}", flush=True)
    return out


VERDICTS = ("ok", "not held", "wrong", "declined", "unsure")


def summary(results: list[tuple[Mechanism, Outcome]]) -> str:
    by: dict[str, Counter[str]] = defaultdict(Counter)
    for mech, outcome in results:
        by["all"][outcome.verdict] += 1
        for feature in mech.features:
            by[feature][outcome.verdict] += 1
    width = max(len(k) for k in by)
    lines = [f"{'feature':<{width}}  " + "  ".join(f"{v:>8}" for v in VERDICTS)]
    for key in ["all", *sorted(k for k in by if k != "all")]:
        lines.append(f"{key:<{width}}  " + "  ".join(f"{by[key][v]:>8}" for v in VERDICTS))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--n", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--subprocess", action="store_true", help="a process per solve (slower)")
    args = parser.parse_args(argv)
    import clarabel
    import scipy

    import jointplay

    print(
        f"jointplay {jointplay.__version__}, clarabel {clarabel.__version__},"
        f" numpy {np.__version__}, scipy {scipy.__version__}"
    )
    start = time.perf_counter()
    results = run(args.n, args.seed, in_process=not args.subprocess)
    seconds = time.perf_counter() - start
    print(f"{len(results)} mechanisms, seed {args.seed}, {seconds:.0f} s")
    print(summary(results))
    bad = [(m, o) for m, o in results if o.verdict in ("wrong", "declined", "unsure")]
    if bad:
        print(f"failing models saved in {FAILURES}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
