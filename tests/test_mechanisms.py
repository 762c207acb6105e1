"""Several bodies, closed loops, rigid joints, invariances, and the unbounded case."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

import jointplay
from conftest import BALANCE, MM, RAD, ROOT, spherical_shaft
from jointplay import UnboundedMechanismError
from jointplay.settings import DEFAULT


def solved(data: dict[str, Any]) -> jointplay.Result:
    result = jointplay.solve(jointplay.model_from_dict(data))
    result.check()
    return result


def energy_tol(data: dict[str, Any]) -> float:
    """N*mm: how far two answers' potential energies may differ when their
    positions agree to the promise (MM and RAD): each load's work on its
    point's displacement, that point ``|at|`` from the origin."""
    tol = 0.0
    for load in data["loads"]:
        if "force" in load:
            lever = float(np.linalg.norm(load.get("at", [0, 0, 0])))
            tol += float(np.linalg.norm(load["force"])) * (MM + lever * RAD)
        if "torque" in load:
            tol += float(np.linalg.norm(load["torque"])) * RAD
    return tol


def test_three_spheres_in_a_closed_loop_closed_form() -> None:
    """G-A (J1), A-B (J2), B-G (J3) all centred at one point, F on B: B goes
    min(J1/2 + J2/2, J3/2) along F."""
    force = np.array([1.0, 2.0, 2.0])

    def loop(j3: float) -> dict[str, Any]:
        return {
            "bodies": [{"name": "G", "ground": True}, {"name": "A"}, {"name": "B"}],
            "joints": [
                {
                    "name": "ga",
                    "type": "spherical",
                    "between": ["G", "A"],
                    "at": [0, 0, 0],
                    "clearance": 0.2,
                },
                {
                    "name": "ab",
                    "type": "spherical",
                    "between": ["A", "B"],
                    "at": [0, 0, 0],
                    "clearance": 0.1,
                },
                {
                    "name": "bg",
                    "type": "spherical",
                    "between": ["B", "G"],
                    "at": [0, 0, 0],
                    "clearance": j3,
                },
            ],
            "loads": [{"body": "B", "at": [0, 0, 0], "force": list(force)}],
        }

    f_hat = force / 3.0
    r = solved(loop(0.5))
    np.testing.assert_allclose(r.bodies["B"].translation, 0.15 * f_hat, atol=MM)
    np.testing.assert_allclose(r.bodies["A"].translation, 0.10 * f_hat, atol=MM)
    # B-G holds B at 0.1: A is then free within two balls (a tie); the least-norm
    # position in the joint metric |t_ga|^2 + |t_ab|^2 is half-way.
    r = solved(loop(0.2))
    np.testing.assert_allclose(r.bodies["B"].translation, 0.10 * f_hat, atol=MM)
    np.testing.assert_allclose(r.bodies["A"].translation, 0.05 * f_hat, atol=MM)
    for body in ("A", "B"):
        np.testing.assert_allclose(r.bodies[body].rotation, 0, atol=RAD)
    # the loop closes: B relative to G equals (B rel A) + (A rel G), each
    # joint's torsor printed to what the answer proves
    np.testing.assert_allclose(
        r.joints["bg"].translation,
        -(r.joints["ga"].translation + r.joints["ab"].translation),
        atol=MM,
    )


LOOP = {
    "bodies": [{"name": "G", "ground": True}, {"name": "A"}, {"name": "B"}],
    "joints": [
        {
            "name": "s",
            "type": "spherical",
            "between": ["G", "A"],
            "at": [0, 0, 0],
            "clearance": 0.2,
        },
        {
            "name": "c",
            "type": "cylindrical",
            "between": ["A", "B"],
            "at": [100, 0, 0],
            "length": 30,
            "clearance": 0.1,
        },
        {
            "name": "r",
            "type": "sphere_in_cylinder",
            "between": ["B", "G"],
            "at": [200, 0, 0],
            "clearance": 0.3,
        },
    ],
    "loads": [
        {"body": "B", "at": [150, 0, 0], "force": [0, 1, 1]},
        {"body": "A", "at": [50, 0, 0], "force": [0.3, -1, 0.5]},
        {"body": "A", "torque": [0, 4, 0]},
    ],
}


def _independent_slsqp(data: dict[str, Any]) -> tuple[float, Any]:
    """The LOOP problem written from scratch (global-origin torsors, squared-norm
    constraints) and solved by SciPy's SLSQP from several starts."""

    def disp(x: np.ndarray, body: int, p: np.ndarray) -> np.ndarray:
        v, w = x[6 * body : 6 * body + 3], x[6 * body + 3 : 6 * body + 6]
        return v + np.cross(w, p)

    def energy(x: np.ndarray) -> float:
        e = -np.array([0, 1.0, 1.0]) @ disp(x, 1, np.array([150.0, 0, 0]))
        e -= np.array([0.3, -1.0, 0.5]) @ disp(x, 0, np.array([50.0, 0, 0]))
        e -= np.array([0, 4.0, 0]) @ x[3:6]
        return float(e)

    def constraints(x: np.ndarray) -> np.ndarray:
        """r^2 - |delta|^2 for each contact (radii 0.1, 0.05, 0.05, 0.15 mm)."""
        out = [0.1**2 - np.sum(disp(x, 0, np.zeros(3)) ** 2)]
        for end in (85.0, 115.0):
            p = np.array([end, 0, 0])
            d = disp(x, 1, p) - disp(x, 0, p)
            out.append(0.05**2 - d[1] ** 2 - d[2] ** 2)
        d = disp(x, 1, np.array([200.0, 0, 0]))
        out.append(0.15**2 - d[1] ** 2 - d[2] ** 2)
        return np.array(out)

    # SLSQP works on y = x / D (rotations scaled by 100 mm) and gives up near the
    # optimum with "positive directional derivative": we keep any start that ends
    # feasible after shrinking it onto the constraints, whatever its flag says.
    D = np.tile(np.r_[np.ones(3), np.full(3, 0.01)], 2)
    rng = np.random.default_rng(7)
    best = (np.inf, None)
    for _ in range(6):
        y0 = rng.normal(scale=1e-2, size=12)
        res = minimize(
            lambda y: 100 * energy(D * y),
            y0,
            method="SLSQP",
            constraints=[{"type": "ineq", "fun": lambda y: 100 * constraints(D * y)}],
            options={"ftol": 1e-15, "maxiter": 2000},
        )
        x = D * res.x
        # Every contact is centred at x = 0, so shrinking x makes it exactly feasible.
        radii = np.array([0.1, 0.05, 0.05, 0.15])
        norms = np.sqrt(np.maximum(radii**2 - constraints(x), 0.0))
        x = x * min(1.0, float(np.min(radii / np.maximum(norms, 1e-300))))
        if energy(x) < best[0]:
            best = (energy(x), x)
    assert best[1] is not None
    return best[0], constraints


def test_closed_loop_matches_an_independent_solver() -> None:
    r = solved(LOOP)
    slsqp_energy, constraints = _independent_slsqp(LOOP)
    x = np.r_[
        r.bodies["A"].translation,
        r.bodies["A"].rotation,
        r.bodies["B"].translation,
        r.bodies["B"].rotation,
    ]
    # our point is feasible for the independently written constraints, to the
    # certificate's feasibility (1e-9 of the largest play, 0.15 mm: a squared
    # constraint r^2 - |d|^2 then misses by at most 2 r of that) ...
    past = DEFAULT.feasibility_tolerance * 0.15
    assert np.min(constraints(x)) > -2 * 0.15 * past
    # ... and no (feasible) SLSQP point has a lower energy: ours is the global
    # optimum, to the certificate's complementarity on each of its four contacts
    # (the optimum's energy is minus the sum of their forces times their plays)
    assert r.potential_energy <= slsqp_energy + 4 * BALANCE * abs(slsqp_energy)
    assert r.potential_energy == pytest.approx(slsqp_energy, rel=1e-6)


def test_rigid_joint_splitting_a_body_gives_the_same_answer() -> None:
    whole = solved(spherical_shaft())
    split = spherical_shaft(
        bodies=[{"name": "S0", "ground": True}, {"name": "S1a"}, {"name": "S1b"}],
        joints=[
            {
                "name": "l1",
                "type": "spherical",
                "between": ["S0", "S1a"],
                "at": [0, 0, 0],
                "clearance": 0.2,
            },
            {"name": "weld", "type": "rigid", "between": ["S1a", "S1b"], "at": [100, 0, 0]},
            {
                "name": "l2",
                "type": "cylindrical",
                "between": ["S0", "S1b"],
                "at": [200, 0, 0],
                "length": 40,
                "clearance": 0.2,
            },
        ],
        loads=[{"body": "S1b", "at": [300, 0, 0], "force": [1, 1, 1]}],
    )
    parts = solved(split)
    for name in ("l1", "l2"):
        np.testing.assert_allclose(
            parts.joints[name].translation, whole.joints[name].translation, atol=MM
        )
        np.testing.assert_allclose(
            parts.joints[name].rotation, whole.joints[name].rotation, atol=RAD
        )
    for part in ("S1a", "S1b"):
        np.testing.assert_allclose(
            parts.bodies[part].translation, whole.bodies["S1"].translation, atol=MM
        )
        np.testing.assert_allclose(
            parts.bodies[part].rotation, whole.bodies["S1"].rotation, atol=RAD
        )
    assert parts.potential_energy == pytest.approx(whole.potential_energy, abs=energy_tol(split))


def _moved(data: dict[str, Any], R: np.ndarray, t: np.ndarray) -> dict[str, Any]:
    out = copy.deepcopy(data)
    for j in out["joints"]:
        j["at"] = list(R @ np.array(j["at"], dtype=float) + t)
        j["axis"] = list(R @ np.array(j.get("axis", [1, 0, 0]), dtype=float))
        j["up"] = list(R @ np.array(j.get("up", [0, 0, 1]), dtype=float))
    for load in out["loads"]:
        if "at" in load:
            load["at"] = list(R @ np.array(load["at"], dtype=float) + t)
        for key in ("force", "torque"):
            if key in load:
                load[key] = list(R @ np.array(load[key], dtype=float))
    return out


@pytest.mark.parametrize("data", [LOOP, spherical_shaft()], ids=["loop", "shaft"])
def test_invariance_under_a_rigid_motion_of_the_whole_model(data: dict[str, Any]) -> None:
    R = Rotation.from_euler("zyx", [0.7, -0.4, 1.9]).as_matrix()
    t = np.array([123.0, -45.0, 6.5])
    base = solved(_moved(data, np.eye(3), np.zeros(3)))
    moved = solved(_moved(data, R, t))
    # two models, so two solves: the same answer to the promise (MM, RAD)
    for name, jr in base.joints.items():
        np.testing.assert_allclose(moved.joints[name].translation, jr.translation, atol=MM)
        np.testing.assert_allclose(moved.joints[name].rotation, jr.rotation, atol=RAD)
        # the joint frames are the model's geometry (rotated axes), not the solve's
        np.testing.assert_allclose(
            moved.joints[name].R_world_joint, R @ jr.R_world_joint, atol=1e-12
        )
    probe = np.array([37.0, 11.0, -5.0])
    for name, br in base.bodies.items():
        mb = moved.bodies[name]
        np.testing.assert_allclose(mb.rotation, R @ br.rotation, atol=RAD)
        np.testing.assert_allclose(
            mb.displacement_of(R @ probe + t), R @ br.displacement_of(probe), atol=MM
        )
    assert moved.potential_energy == pytest.approx(base.potential_energy, abs=energy_tol(data))


def test_scaling_all_loads_changes_nothing_but_the_energy() -> None:
    base = solved(LOOP)
    scaled = copy.deepcopy(LOOP)
    for load in scaled["loads"]:
        for key in ("force", "torque"):
            if key in load:
                load[key] = [1e4 * c for c in load[key]]
    big = solved(scaled)
    for name, jr in base.joints.items():
        np.testing.assert_allclose(big.joints[name].translation, jr.translation, atol=MM)
        np.testing.assert_allclose(big.joints[name].rotation, jr.rotation, atol=RAD)
    tol = 1e4 * energy_tol(LOOP)
    assert big.potential_energy == pytest.approx(1e4 * base.potential_energy, abs=tol)


def test_units_in_strings_give_the_same_answer() -> None:
    mm = solved(spherical_shaft())
    metric = spherical_shaft(
        joints=[
            {
                "name": "l1",
                "type": "spherical",
                "between": ["S0", "S1"],
                "at": [0, 0, 0],
                "clearance": "200 um",
            },
            {
                "name": "l2",
                "type": "cylindrical",
                "between": ["S0", "S1"],
                "at": ["0.2 m", 0, 0],
                "length": "4 cm",
                "clearance": "0.02 cm",
            },
        ],
        loads=[{"body": "S1", "at": ["30 cm", 0, 0], "force": ["1 N", "0.001 kN", "1000 mN"]}],
    )
    other = solved(metric)
    for name in ("l1", "l2"):
        np.testing.assert_allclose(
            other.joints[name].translation, mm.joints[name].translation, atol=MM
        )
        np.testing.assert_allclose(other.joints[name].rotation, mm.joints[name].rotation, atol=RAD)


def test_potential_energy_is_minus_the_work_of_the_loads() -> None:
    r = solved(spherical_shaft())
    u_b = r.bodies["S1"].displacement_of(np.array([300.0, 0, 0]))
    # the same answer's work, from its printed position (given to the length
    # and angle it proves): to those, on the load's lever of 300 mm
    res = r.resolution
    tol = np.sqrt(3) * (res.length + 300 * res.angle)
    assert r.potential_energy == pytest.approx(-np.ones(3) @ u_b, abs=tol)


def test_unbounded_internal_mobility_names_body_and_motion() -> None:
    data = copy.deepcopy(LOOP)
    data["joints"][2] = {
        "name": "r",
        "type": "sphere_in_cylinder",
        "between": ["B", "G"],
        "at": [200, 0, 0],
        "clearance": 0.3,
    }
    data["loads"].append({"body": "B", "at": [150, 0, 0], "force": [5, 0, 0]})
    with pytest.raises(UnboundedMechanismError) as info:
        jointplay.solve(jointplay.model_from_dict(data))
    assert info.value.body == "B"
    assert info.value.motion == "translation along the global X axis"
    assert (
        "body 'B': translation along the global X axis is not held by any joint, and the "
        "loads drive it" in str(info.value)
    )


def test_free_unloaded_motions_are_listed_and_zero() -> None:
    r = solved(spherical_shaft())
    assert r.free_motions == ("body 'S1': rotation about the global X axis",)
    # exactly 0: the free motion's part is the solver's round-off, far below the
    # angle the answer proves, and every result gives such a part as 0 (proven.py)
    assert r.joints["l1"].rotation[0] == 0.0
    assert r.bodies["S1"].rotation[0] == 0.0


def test_no_load_leaves_everything_centred() -> None:
    r = solved(spherical_shaft(loads=[]))
    for jr in r.joints.values():
        np.testing.assert_allclose(jr.translation, 0, atol=MM)
    assert r.potential_energy == 0.0  # no load does no work


def test_a_far_away_weld_does_not_change_a_tie() -> None:
    """A tie is resolved in the joints' metric; a rigid joint (no relative motion)
    must not change it, wherever it is."""
    base = {
        "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
        "joints": [
            {
                "name": "j",
                "type": "cylindrical",
                "between": ["G", "B"],
                "at": [0, 0, 0],
                "clearance": 0.2,
                "length": 40,
            }
        ],
        "loads": [{"body": "B", "at": [20, 0, 0], "force": [0, 1, 0]}],
    }
    welded = copy.deepcopy(base)
    welded["bodies"].append({"name": "C"})
    welded["joints"].append(
        {"name": "w", "type": "rigid", "between": ["B", "C"], "at": [1000, 0, 0]}
    )
    a, b = solved(base), solved(welded)
    np.testing.assert_allclose(b.joints["j"].translation, a.joints["j"].translation, atol=MM)
    np.testing.assert_allclose(b.joints["j"].rotation, a.joints["j"].rotation, atol=RAD)


EXAMPLE_FILES = sorted((ROOT / "examples").rglob("*.yaml"))


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=lambda p: p.stem)
def test_a_contact_that_pushes_is_in_contact(path: Any) -> None:
    """Every printed force acts at a touching contact: a contact with no play
    (located_plate's buttons) counts as touching once it is reached to the
    certificate's feasibility, read from the solve's settings; an interior
    point that left it 1e-11 short once printed it free while it pushed 58 N."""
    model = jointplay.load(path)
    for case in model.case_names or [None]:
        result = jointplay.solve(model, case=case)
        for joint in result.joints.values():
            for c in joint.contacts:
                pushes = bool(np.any(c.force) or np.any(c.torque))
                assert c.in_contact or not pushes, (path.stem, case, joint.name, c.name)
