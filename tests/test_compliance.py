"""Compliant contacts: past the clearance at the cost of an elastic energy k p^2 / 2."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import jointplay
from conftest import MM, RAD, force_tol
from jointplay import Workspace, model_from_dict


def mechanism(joints: list[dict[str, Any]], loads: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
        "joints": [{"between": ["G", "B"], **j} for j in joints],
        "loads": loads,
    }


def solved(data: dict[str, Any]) -> jointplay.Result:
    result = jointplay.solve(model_from_dict(data))
    result.check()
    return result


AT = [10.0, 20.0, 30.0]
SPHERE = {"name": "j", "type": "spherical", "at": AT, "clearance": 0.5, "stiffness": "1000 N/mm"}


@pytest.mark.parametrize("size", [1.0, 13.0, 130.0, 1.3e4])
def test_one_spherical_joint_moves_half_the_clearance_plus_force_over_stiffness(
    size: float,
) -> None:
    direction = np.array([3.0, -4.0, 12.0]) / 13.0
    force = size * direction
    r = solved(mechanism([SPHERE], [{"body": "B", "at": AT, "force": list(force)}]))
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, (0.25 + size / 1000) * direction, atol=MM)
    contact = jr.contacts[0]
    assert contact.penetration == pytest.approx(size / 1000, abs=MM)
    assert contact.in_contact and contact.gap_used == 1.0
    np.testing.assert_allclose(contact.force, -force, atol=force_tol(r))
    assert r.equilibrium_residual < 1e-8


def test_the_answer_depends_on_the_size_of_the_load_and_stiffness_units() -> None:
    small = solved(mechanism([SPHERE], [{"body": "B", "at": AT, "force": [0, 0, 1]}]))
    big = solved(mechanism([SPHERE], [{"body": "B", "at": AT, "force": [0, 0, 100]}]))
    assert big.joints["j"].translation[2] - small.joints["j"].translation[2] == pytest.approx(
        99 / 1000, abs=MM
    )
    same = {**SPHERE, "stiffness": "1 N/um"}  # = 1000 N/mm
    again = solved(mechanism([same], [{"body": "B", "at": AT, "force": [0, 0, 100]}]))
    np.testing.assert_allclose(again.joints["j"].translation, big.joints["j"].translation, atol=MM)


def test_two_springs_in_parallel_engage_one_after_the_other() -> None:
    """Clearances 0.2 and 0.4 (radii 0.1, 0.2), stiffnesses 100 and 300 N/mm, at
    one point: below 100 * (0.2 - 0.1) = 10 N only the first works; above, both:
    100 (d - 0.1) + 300 (d - 0.2) = F."""
    joints = [
        {"name": "a", "type": "spherical", "at": [0, 0, 0], "clearance": 0.2, "stiffness": 100},
        {"name": "b", "type": "spherical", "at": [0, 0, 0], "clearance": 0.4, "stiffness": 300},
    ]
    for force, d, fa, fb in ((5.0, 0.15, 5.0, 0.0), (100.0, 0.425, 32.5, 67.5)):
        r = solved(mechanism(joints, [{"body": "B", "at": [0, 0, 0], "force": [0, 0, force]}]))
        np.testing.assert_allclose(r.bodies["B"].translation, [0, 0, d], atol=MM)
        assert r.joints["a"].contacts[0].force[2] == pytest.approx(-fa, abs=force_tol(r))
        assert r.joints["b"].contacts[0].force[2] == pytest.approx(-fb, abs=force_tol(r))
        assert r.joints["b"].contacts[0].in_contact == (fb > 0)


def test_compliant_cylinder_ends_share_a_centred_load() -> None:
    """A force across the axis at the centre of a cylindrical joint: both end
    springs (per contact point) carry half: d = J/2 + F / (2 k), no tilt."""
    cyl = {
        "name": "j",
        "type": "cylindrical",
        "at": [0, 0, 0],
        "length": 40,
        "clearance": 0.2,
        "stiffness": 500,
    }
    r = solved(mechanism([cyl], [{"body": "B", "at": [0, 0, 0], "force": [0, 50, 0]}]))
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation[1:], [0.1 + 50 / 1000, 0], atol=MM)
    np.testing.assert_allclose(jr.rotation[1:], 0, atol=RAD)
    for c in jr.contacts:
        np.testing.assert_allclose(c.force, [0, -25, 0], atol=force_tol(r))


def test_zero_clearance_spring_is_a_plain_spring() -> None:
    spring = {**SPHERE, "clearance": 0}
    r = solved(mechanism([spring], [{"body": "B", "at": AT, "force": [0, 20, 0]}]))
    np.testing.assert_allclose(r.joints["j"].translation, [0, 0.02, 0], atol=MM)


def test_batch_and_warm_solves_with_compliance_match_fresh_solves() -> None:
    data = mechanism(
        [
            {**SPHERE, "name": "l1", "at": [0, 0, 0], "clearance": 0.2},
            {
                "name": "l2",
                "type": "cylindrical",
                "at": [200, 0, 0],
                "length": 40,
                "clearance": 0.2,
                "stiffness": 2000,
            },
        ],
        [{"body": "B", "at": [300, 0, 0], "force": [1, 1, 1]}],
    )
    ws = Workspace.of(model_from_dict(data))
    W = ws.asm.wrench_work("B", [300, 0, 0])
    sizes = np.array([1.0, 10.0, 100.0, 1000.0, 3000.0])
    wrenches = np.zeros((len(sizes), 6))
    wrenches[:, :3] = sizes[:, None] * np.array([1.0, 1.0, 1.0])
    batch = ws.solve_batch(wrenches @ W.T)
    for i, size in enumerate(sizes):
        loads = [{"body": "B", "at": [300, 0, 0], "force": [size] * 3}]
        ref = solved({**data, "loads": loads})
        warm = ws.solve(loads=[jointplay.Load(**loads[0])])
        for name in ("l1", "l2"):
            np.testing.assert_allclose(
                batch.joint_torsor(name)[i, :3], ref.joints[name].translation, atol=MM
            )
            np.testing.assert_allclose(
                warm.joints[name].translation, ref.joints[name].translation, atol=MM
            )
            np.testing.assert_allclose(
                batch.joint_torsor(name)[i, 3:], ref.joints[name].rotation, atol=RAD
            )
    # the bigger the load, the further past the clearance
    pen = [c.penetration for c in ref.joints["l1"].contacts]
    assert pen[0] > 0


def test_rigid_joints_take_no_stiffness() -> None:
    with pytest.raises(jointplay.ModelError, match="stiffness"):
        model_from_dict(
            mechanism([{"name": "w", "type": "rigid", "at": [0, 0, 0], "stiffness": 5}], [])
        )
    with pytest.raises(jointplay.ModelError, match="stiffness"):
        model_from_dict(mechanism([{**SPHERE, "stiffness": "3 kg"}], []))


def test_compliant_shaft_example_by_hand() -> None:
    """examples/studies/compliant_shaft.yaml: statics give 50 N at l1 and 150 N
    at l2; each centre moves J/2 + R/k: l1 by -0.15, l2 by +0.25 mm, so the tip
    at 300 mm moves -0.15 + 0.4 * 300/200 = 0.45 mm (rigid: 0.2 mm)."""
    from conftest import ROOT

    model = jointplay.load(ROOT / "examples" / "studies" / "compliant_shaft.yaml")
    r = jointplay.solve(model)
    r.check()
    np.testing.assert_allclose(r.points["tip"].displacement, [0, 0.45, 0], atol=MM)
    np.testing.assert_allclose(r.joints["l1"].contacts[0].force, [0, 50, 0], atol=force_tol(r))
    np.testing.assert_allclose(r.joints["l2"].contacts[0].force, [0, -150, 0], atol=force_tol(r))
    assert r.joints["l1"].contacts[0].penetration == pytest.approx(0.05, abs=MM)
    assert r.joints["l2"].contacts[0].penetration == pytest.approx(0.15, abs=MM)
    rigid = model.replace(
        joints=[{k: v for k, v in j.model_dump().items() if k != "stiffness"} for j in model.joints]
    )
    np.testing.assert_allclose(
        jointplay.solve(rigid).points["tip"].displacement, [0, 0.2, 0], atol=MM
    )
