"""Made many at a time, as one at a time: the joints' cones (``contacts_of``),
their rows (``point_rows_of``) and frames (``frames_of``), and the matrices
that ``assemble`` builds from its arrays (``JointRows``) rather than from its
objects. Equal means equal to the last bit, signs of zeros included."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest
import scipy.sparse as sp

import jointplay
from conftest import ROOT
from jointplay.assembly import Assembly, assemble
from jointplay.io.generate import bearing_chain, tube_string
from jointplay.model.joints import JOINT_TYPES, Joint
from jointplay.model.joints.base import cones_of, frames_of, point_rows, point_rows_of


def same(a: Any, b: Any) -> bool:
    """Equal values of one kind: arrays bit for bit, sparse ones entry for entry."""
    if sp.issparse(a) or sp.issparse(b):
        if not (sp.issparse(a) and sp.issparse(b)):
            return False
        a, b = sp.csr_matrix(a), sp.csr_matrix(b)
        return (
            a.shape == b.shape
            and np.array_equal(a.indptr, b.indptr)
            and np.array_equal(a.indices, b.indices)
            and same(a.data, b.data)
        )
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return bool(
            a.shape == b.shape
            and a.dtype == b.dtype
            and np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
            and (a.dtype.kind != "f" or np.array_equal(np.signbit(a), np.signbit(b)))
        )
    return type(a) is type(b) and bool(a == b)


def same_contact(a: Any, b: Any) -> bool:
    return type(a) is type(b) and all(
        same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a)
    )


def joint(kind: str, name: str, **fields: Any) -> Joint:
    base = {"name": name, "between": ["G", "B"], "at": [1.0, -2.0, 3.0], "axis": [0, 0, 1]}
    return JOINT_TYPES[kind](type=kind, **{**base, **fields})


#: Joints of each type whose contacts are made together, with their options
#: given and not, and 0 and -0 among their sizes' signs of zero.
MANY = {
    "spherical": [{"clearance": 0.1}, {"clearance": 0.0}, {"clearance": 0.3}],
    "sphere_in_cylinder": [{"clearance": 0.2}, {"clearance": 0.05}],
    "revolute": [
        {"length": 20.0, "clearance": 0.02, "axial_clearance": 0.05},
        {"length": 7.5, "clearance": 0.1, "axial_clearance": 0.0, "backlash": 0.01},
        {"length": 40.0, "clearance": 0.0, "axial_clearance": 0.3},
    ],
    "cylindrical": [
        {"length": 40.0, "clearance": 0.2},
        {"length": 12.0, "clearance": 0.1, "axial_clearance": 0.4},
        {"length": 3.0, "clearance": 0.01, "backlash": 0.02, "torsional_stiffness": 5e4},
    ],
    "prismatic": [
        {"length": 30.0, "width": 10.0, "height": 6.0, "clearance": 0.1},
        {"length": 5.0, "width": 2.0, "height": 9.0, "clearance_y": 0.2, "clearance_z": 0.05},
        {"length": 8.0, "width": 4.0, "height": 4.0, "clearance": 0.1, "axial_clearance": 0.3},
    ],
    "slot": [
        {"along": [1, 0, 0], "length": 10.0, "clearance": 0.1},
        {"along": [0, 1, 0], "length": 4.0, "clearance": 0.2, "slot_length": 1.0},
        {"along": [1, 1, 0], "length": 6.0, "clearance": 0.05, "slot_length": 0.0},
    ],
    "planar": [
        {"width": 10.0, "height": 20.0, "clearance": 0.1},
        {"diameter": 30.0, "clearance": 0.2},
        {"width": 3.0, "height": 1.0, "clearance": 0.0},
        {"diameter": 8.0, "clearance": 0.0},
    ],
}


@pytest.mark.parametrize("kind", sorted(MANY))
def test_a_types_contacts_made_together_are_those_made_one_at_a_time(kind: str) -> None:
    joints = [joint(kind, f"j{i}", **fields) for i, fields in enumerate(MANY[kind])]
    together = JOINT_TYPES[kind].contacts_of(joints)
    assert len(together) == len(joints)
    for j, made in zip(joints, together, strict=True):
        alone = j.contacts()
        assert len(made) == len(alone)
        assert all(same_contact(a, b) for a, b in zip(made, alone, strict=True)), j.name


def test_cones_of_keeps_each_joints_cones_and_makes_them_once() -> None:
    joints = [joint(kind, f"{kind}{i}", **f) for kind in MANY for i, f in enumerate(MANY[kind])]
    first = cones_of(joints)
    assert all(j.cones is cones for j, cones in zip(joints, first, strict=True))
    assert all(a is b for a, b in zip(cones_of(joints), first, strict=True))


@pytest.mark.parametrize("directions", ["x", "y", "z", "yz", "xyz", "zx", ""])
def test_point_rows_of_many_points_are_those_of_each(directions: str) -> None:
    rng = np.random.default_rng(7)
    points = rng.normal(size=(9, 3)) * 10.0 ** rng.integers(-3, 3, size=(9, 1))
    points[0], points[1], points[2, 1] = 0.0, -0.0, -0.0  # signs of zero carried through
    many = point_rows_of(points, directions)
    for p, rows in zip(points, many, strict=True):
        assert same(rows, point_rows(p, directions))


def test_frames_of_gives_each_joints_own_frame() -> None:
    joints = [
        joint("spherical", "a", clearance=0.1, axis=[1, 0, 0]),
        joint("spherical", "b", clearance=0.1, axis=[1, 0, 0], up=[0, 1, 0]),
        joint("spherical", "c", clearance=0.1, axis=[0, 0, -1]),
        joint("slot", "d", axis=[0, 0, 1], along=[1, 0, 0], length=5.0, clearance=0.1),
        joint("slot", "e", axis=[0, 0, 1], along=[0, 1, 0], length=5.0, clearance=0.1),
        joint("spherical", "f", clearance=0.2, axis=[1, 0, 0]),
    ]
    frames = frames_of(joints)
    for j, R in zip(joints, frames, strict=True):
        assert same(R, j.frame())


def models() -> list[tuple[str, jointplay.Model]]:
    out = [(path.name, jointplay.load(path)) for path in sorted(ROOT.glob("examples/**/*.yaml"))]
    out += [("tube string, closed", tube_string(50, closed=True)), ("bearings", bearing_chain(60))]
    return out


def the_arrays_of(asm: Assembly) -> dict[str, Any]:
    """What the solver reads from an assembly, made anew."""
    fresh = dataclasses.replace(asm)  # no cached matrices
    out = {"E": fresh.E, "E_length": fresh.E_length, "metric_matrix": fresh.metric_matrix}
    out |= {
        f"stack.{f.name}": getattr(fresh.stack, f.name) for f in dataclasses.fields(fresh.stack)
    }
    tables = fresh.tables
    out |= {f"tables.{f.name}": getattr(tables, f.name) for f in dataclasses.fields(tables)}
    return out


@pytest.mark.parametrize(("name", "model"), models(), ids=lambda v: v if isinstance(v, str) else "")
def test_the_matrices_from_the_assemblys_arrays_are_those_from_its_objects(
    name: str, model: jointplay.Model
) -> None:
    asm = assemble(model)
    assert asm.joint_rows is not None
    from_arrays = the_arrays_of(asm)
    from_objects = the_arrays_of(dataclasses.replace(asm, joint_rows=None))  # ``JointRows.of``
    assert from_arrays.keys() == from_objects.keys()
    for key, value in from_arrays.items():
        assert same(value, from_objects[key]), key


def test_a_studys_radii_keep_the_arrays() -> None:
    asm = assemble(tube_string(50, closed=True))
    radii = 1.1 * asm.stack.r
    other = asm.with_radii(radii)
    assert other.joint_rows is asm.joint_rows
    assert same(other.stack.r, radii)
    assert same(other.stack.A, asm.stack.A) and same(other.stack.B, asm.stack.B)


#: The two types MANY leaves out, each with its options given and not.
PLACED_TOO = {
    "point": [{"gap": 0.1}, {"gap": 0.0}],
    "rigid": [{}],
}


@pytest.mark.parametrize("kind", sorted({**MANY, **PLACED_TOO}))
def test_a_joint_s_contacts_do_not_depend_on_where_it_is_placed(kind: str) -> None:
    """``Joint.placed`` (a motion's pose) keeps the joint's contacts as they
    are and does not make them again: that holds only if a type's contacts,
    in its joint frame, depend on none of its placement fields. Each joint
    is placed elsewhere and turned, and its contacts made anew from the moved
    fields are the kept ones, to the last bit."""
    from scipy.spatial.transform import Rotation

    turn = Rotation.from_rotvec([0.3, -1.1, 0.7]).as_matrix()
    for i, fields in enumerate({**MANY, **PLACED_TOO}[kind]):
        j = joint(kind, f"j{i}", **fields)
        placement: dict[str, Any] = {"at": (4.0, 5.0, -6.0)}
        for key in ("axis", "up", "along"):
            value = getattr(j, key, None)
            if value is not None:
                placement[key] = tuple(float(c) for c in turn @ np.asarray(value, dtype=float))
        moved = j.placed(**placement)
        data = {**j.model_dump(by_alias=True, exclude_none=True), **placement}
        fresh = type(j).model_validate(data)
        assert len(moved.cones) == len(fresh.contacts()), j.name
        pairs = zip(moved.cones, fresh.contacts(), strict=True)
        assert all(same_contact(a, b) for a, b in pairs), j.name
