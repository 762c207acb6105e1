"""Each joint type alone, against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

import jointplay
from conftest import MM, RAD
from jointplay import UnboundedMechanismError


def one_joint(joint: dict[str, object], *loads: dict[str, object]) -> jointplay.Model:
    base = {"name": "j", "between": ["G", "B"], "at": [10, 20, 30]}
    base.update(joint)
    return jointplay.model_from_dict(
        {
            "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
            "joints": [base],
            "loads": list(loads),
        }
    )


def solved(model: jointplay.Model) -> jointplay.Result:
    result = jointplay.solve(model)
    result.check()
    return result


AT = [10.0, 20.0, 30.0]


def test_spherical_moves_its_centre_by_half_the_clearance_along_the_force() -> None:
    force = np.array([3.0, -4.0, 12.0])
    r = solved(
        one_joint(
            {"type": "spherical", "clearance": 0.5}, {"body": "B", "at": AT, "force": list(force)}
        )
    )
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, 0.25 * force / np.linalg.norm(force), atol=MM)
    np.testing.assert_allclose(jr.rotation, 0, atol=RAD)  # free, unloaded
    assert [c.in_contact for c in jr.contacts] == [True]
    # the energy is the load's work on its point's displacement, proven to MM
    assert r.potential_energy == pytest.approx(
        -0.25 * np.linalg.norm(force), abs=MM * np.linalg.norm(force)
    )


def test_spherical_does_not_hold_a_torque() -> None:
    model = one_joint({"type": "spherical", "clearance": 0.5}, {"body": "B", "torque": [0, 1, 0]})
    with pytest.raises(
        UnboundedMechanismError,
        match=r"body 'B': rotation about an axis parallel to "
        r"global Y through \(10, 0, 30\) mm is not held by any joint",
    ):
        jointplay.solve(model)


def test_cylindrical_radial_force_at_centre() -> None:
    r = solved(
        one_joint(
            {"type": "cylindrical", "clearance": 0.2, "length": 40},
            {"body": "B", "at": AT, "force": [0, 0, -5]},
        )
    )
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, [0, 0, -0.1], atol=MM)
    np.testing.assert_allclose(jr.rotation, 0, atol=RAD)
    assert [c.in_contact for c in jr.contacts] == [True, True]


def test_cylindrical_tilts_by_clearance_over_length_under_a_moment() -> None:
    r = solved(
        one_joint(
            {"type": "cylindrical", "clearance": 0.2, "length": 40},
            {"body": "B", "torque": [0, 0, 7]},
        )
    )
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, 0, atol=MM)
    np.testing.assert_allclose(jr.rotation, [0, 0, 0.2 / 40], atol=RAD)


def test_cylindrical_force_beyond_the_bore_tilts_the_shaft() -> None:
    """F across the axis at x = a > L/2: both ends touch, gamma = J/L, v = 0."""
    at = [10.0 + 100.0, 20.0, 30.0]
    r = solved(
        one_joint(
            {"type": "cylindrical", "clearance": 0.2, "length": 40},
            {"body": "B", "at": at, "force": [0, 2, 0]},
        )
    )
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, 0, atol=MM)
    np.testing.assert_allclose(jr.rotation, [0, 0, 0.2 / 40], atol=RAD)
    disp = r.bodies["B"].displacement_of(np.array(at))
    np.testing.assert_allclose(disp, [0, 100 * 0.2 / 40, 0], atol=MM)


def test_cylindrical_does_not_hold_axial_force() -> None:
    model = one_joint(
        {"type": "cylindrical", "clearance": 0.2, "length": 40, "axis": [0, 1, 0]},
        {"body": "B", "at": AT, "force": [0, 1, 0]},
    )
    with pytest.raises(UnboundedMechanismError, match="translation along the global Y axis"):
        jointplay.solve(model)


def test_cylindrical_on_a_skew_axis_follows_its_frame() -> None:
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    r = solved(
        one_joint(
            {"type": "cylindrical", "clearance": 0.2, "length": 40, "axis": list(axis)},
            {"body": "B", "at": AT, "force": [0, 0, 1]},
        )
    )
    jr = r.joints["j"]
    # the frame is the model's geometry (a normalized axis, cross products), not
    # the solve's: to a few units in the last place on any machine
    np.testing.assert_allclose(jr.R_world_joint[:, 0], axis, atol=1e-15)
    np.testing.assert_allclose(jr.R_world_joint[:, 2], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(jr.translation, [0, 0, 0.1], atol=MM)


def test_revolute_axial_force_takes_the_axial_play_and_stays_centred() -> None:
    """A pure axial load leaves the radial position open (a tie); the least-norm
    equilibrium is the centred one."""
    r = solved(
        one_joint(
            {"type": "revolute", "clearance": 0.2, "length": 40, "axial_clearance": 0.06},
            {"body": "B", "at": AT, "force": [-3, 0, 0]},
        )
    )
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, [-0.03, 0, 0], atol=MM)
    np.testing.assert_allclose(jr.rotation, 0, atol=RAD)
    states = {c.name: c.in_contact for c in jr.contacts}
    assert states == {"end-": False, "end+": False, "axial": True}
    r.check()  # a tie (the radial play): its least-norm point is the closed form above


def test_revolute_does_not_hold_a_torque_about_its_axis() -> None:
    model = one_joint(
        {"type": "revolute", "clearance": 0.2, "length": 40, "axial_clearance": 0.1},
        {"body": "B", "torque": [1, 0, 0]},
    )
    with pytest.raises(
        UnboundedMechanismError, match="rotation about an axis parallel to global X"
    ):
        jointplay.solve(model)


def test_revolute_combined_load() -> None:
    r = solved(
        one_joint(
            {"type": "revolute", "clearance": 0.2, "length": 40, "axial_clearance": 0.06},
            {"body": "B", "at": AT, "force": [1, 0, 1]},
        )
    )
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, [0.03, 0, 0.1], atol=MM)
    np.testing.assert_allclose(jr.rotation, 0, atol=RAD)


def test_sphere_in_cylinder_radial_force() -> None:
    r = solved(
        one_joint(
            {"type": "sphere_in_cylinder", "clearance": 0.3, "axis": [0, 0, 1]},
            {"body": "B", "at": AT, "force": [3, 4, 0]},
        )
    )
    jr = r.joints["j"]
    # joint frame for axis +Z: x = Z, y = Y, z = -X (unit axes: exact, not solved)
    np.testing.assert_allclose(jr.R_world_joint, [[0, 0, -1], [0, 1, 0], [1, 0, 0]], atol=1e-15)
    disp = r.bodies["B"].displacement_of(np.array(AT))
    np.testing.assert_allclose(disp, [0.09, 0.12, 0], atol=MM)


def test_sphere_in_cylinder_slides_freely() -> None:
    model = one_joint(
        {"type": "sphere_in_cylinder", "clearance": 0.3},
        {"body": "B", "at": AT, "force": [1, 0, 0]},
    )
    with pytest.raises(UnboundedMechanismError, match="translation along the global X axis"):
        jointplay.solve(model)


def test_rigid_joint_holds_everything() -> None:
    r = solved(
        one_joint(
            {"type": "rigid"},
            {"body": "B", "at": AT, "force": [1, 2, 3]},
            {"body": "B", "torque": [4, 5, 6]},
        )
    )
    np.testing.assert_allclose(r.bodies["B"].translation, 0, atol=MM)
    np.testing.assert_allclose(r.bodies["B"].rotation, 0, atol=RAD)
    assert [c.in_contact for c in r.joints["j"].contacts] == [True]


def test_zero_clearance_spherical_is_a_fixed_point() -> None:
    r = solved(
        one_joint(
            {"type": "spherical", "clearance": 0}, {"body": "B", "at": AT, "force": [1, 0, 0]}
        )
    )
    np.testing.assert_allclose(r.joints["j"].translation, 0, atol=MM)
    assert r.joints["j"].contacts[0].in_contact


def test_cylindrical_tie_on_the_end_face_picks_the_least_norm_point() -> None:
    """A force across the axis exactly at the end x = L/2 ties a whole edge of
    positions (v + gamma L/2 = J/2); the least-norm one in the metric
    |t|^2 + l^2 |w|^2 (here l = L) is v = (J/2) / (1 + L^2 / (4 l^2))."""
    L, J = 40.0, 0.2
    r = solved(
        one_joint(
            {"type": "cylindrical", "clearance": J, "length": L, "at": [0, 0, 0]},
            {"body": "B", "at": [L / 2, 0, 0], "force": [0, 1, 0]},
        )
    )
    jr = r.joints["j"]
    v = (J / 2) / (1 + L**2 / (4 * L**2))
    gamma = v * L / (2 * L**2)
    np.testing.assert_allclose(jr.translation, [0, v, 0], atol=MM)
    np.testing.assert_allclose(jr.rotation, [0, 0, gamma], atol=RAD)
    assert jr.translation[1] + jr.rotation[2] * L / 2 == pytest.approx(J / 2, abs=MM)


PRISM = {
    "type": "prismatic",
    "length": 40,
    "width": 20,
    "height": 10,
    "clearance_y": 0.2,
    "clearance_z": 0.1,
    "axis": [0, 1, 0],  # joint x = global Y: the frame is not the global one
}


def _prism_loads(force_joint: list[float], torque_joint: list[float]) -> dict[str, object]:
    """A load given in the prismatic joint's frame (x = Y, z = Z, y = -X), at its centre."""
    R = (
        jointplay.model_from_dict(
            {
                "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
                "joints": [{"name": "j", "between": ["G", "B"], "at": AT, **PRISM}],
            }
        )
        .joints[0]
        .R_world_joint
    )
    return {
        "body": "B",
        "at": AT,
        "force": list(R @ np.array(force_joint, float)),
        "torque": list(R @ np.array(torque_joint, float)),
    }


@pytest.mark.parametrize(
    ("force", "torque", "translation", "rotation"),
    [
        ([0, 1, 0], [0, 0, 0], [0, 0.1, 0], [0, 0, 0]),  # across y: Jy/2
        ([0, 0, -1], [0, 0, 0], [0, 0, -0.05], [0, 0, 0]),  # across z: Jz/2
        ([0, 0, 0], [1, 0, 0], [0, 0, 0], [min(0.2 / 10, 0.1 / 20), 0, 0]),  # roll
        ([0, 0, 0], [0, 0, 1], [0, 0, 0], [0, 0, 0.2 / 40]),  # yaw: y play over L
        ([0, 0, 0], [0, -1, 0], [0, 0, 0], [0, -0.1 / 40, 0]),  # pitch: z play over L
    ],
)
def test_prismatic_closed_forms(
    force: list[float], torque: list[float], translation: list[float], rotation: list[float]
) -> None:
    r = solved(one_joint(PRISM, _prism_loads(force, torque)))
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, translation, atol=MM)
    np.testing.assert_allclose(jr.rotation, rotation, atol=RAD)
    assert "translation along the global Y axis" in r.free_motions[0]  # the slide
    assert len(jr.contacts) == 8


def test_prismatic_slide_is_free_and_clearance_sets_both_plays() -> None:
    with pytest.raises(UnboundedMechanismError, match="translation along the global Y axis"):
        jointplay.solve(one_joint(PRISM, _prism_loads([1, 0, 0], [0, 0, 0])))
    both = {k: v for k, v in PRISM.items() if not k.startswith("clearance")}
    r = solved(one_joint({**both, "clearance": 0.3}, _prism_loads([0, 0, 1], [0, 0, 0])))
    np.testing.assert_allclose(r.joints["j"].translation, [0, 0, 0.15], atol=MM)
    with pytest.raises(jointplay.ModelError, match="clearance_z"):
        one_joint({**both, "clearance_y": 0.3}, _prism_loads([0, 0, 1], [0, 0, 0]))


def test_planar_closed_forms() -> None:
    plate = {"type": "planar", "width": 20, "height": 10, "clearance": 0.2}
    r = solved(one_joint(plate, {"body": "B", "at": AT, "force": [-2, 0, 0]}))
    np.testing.assert_allclose(r.joints["j"].translation, [-0.1, 0, 0], atol=MM)
    np.testing.assert_allclose(r.joints["j"].rotation, 0, atol=RAD)
    # tilt about y is held by the corners at z = +-h/2: w_y = J / h
    r = solved(one_joint(plate, {"body": "B", "torque": [0, 3, 0]}))
    np.testing.assert_allclose(r.joints["j"].rotation, [0, 0.2 / 10, 0], atol=RAD)
    np.testing.assert_allclose(r.joints["j"].translation, 0, atol=MM)
    forces = [c.force for c in r.joints["j"].contacts if c.in_contact]
    assert len(forces) == 4  # a pure tilt presses all four corners (two per face)
    # sliding in the plane and spinning about the normal are free
    assert len(r.free_motions) == 3
    with pytest.raises(UnboundedMechanismError, match="translation along the global Y axis"):
        jointplay.solve(one_joint(plate, {"body": "B", "at": AT, "force": [0, 1, 0]}))
