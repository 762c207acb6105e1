"""The planar joint's disc face and the one-sided point joint, against closed forms.

Both are cones with a face row (``|A tau| + B tau <= r``): the disc tilts
about its rim or lies flat (its force then spreads, with a centre of
pressure inside the disc); the point is a one-sided limit that may lift off.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import jointplay
from conftest import MM, RAD, force_tol, moment_tol
from jointplay import UnboundedMechanismError, Workspace, model_from_dict

AT = np.array([10.0, 20.0, 30.0])
# a skew joint frame, so that the tests also check the frames
AXIS = np.array([1.0, 2.0, 2.0]) / 3.0
Z_AXIS = np.array([0.0, 1.0, -1.0]) / np.sqrt(2.0)  # 'up' pins the joint z axis
Y_AXIS = np.cross(Z_AXIS, AXIS)
J, R = 0.2, 20.0  # play, disc radius
DISC = {
    "name": "j",
    "type": "planar",
    "between": ["G", "B"],
    "at": list(AT),
    "axis": list(AXIS),
    "up": list(Z_AXIS),
    "diameter": 2 * R,
    "clearance": J,
}


def model(joints: list[dict[str, Any]], loads: list[dict[str, Any]]) -> jointplay.Model:
    return model_from_dict(
        {
            "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
            "joints": joints,
            "loads": loads,
        }
    )


def solved(m: jointplay.Model) -> jointplay.Result:
    result = jointplay.solve(m)
    result.check()
    return result


def contact(r: jointplay.Result, joint: str, name: str) -> Any:
    return next(c for c in r.joints[joint].contacts if c.name == name)


def test_disc_pushed_inside_its_rim_lies_flat_with_the_centre_of_pressure_under_the_load() -> None:
    where = AT + 7.0 * Y_AXIS + 5.0 * Z_AXIS  # 8.6 mm from the centre, inside R
    r = solved(model([DISC], [{"body": "B", "at": list(where), "force": list(3.0 * AXIS)}]))
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, [J / 2, 0, 0], atol=MM)
    np.testing.assert_allclose(jr.rotation, 0, atol=RAD)
    push = contact(r, "j", "face x+")
    assert push.in_contact and not contact(r, "j", "face x-").in_contact
    np.testing.assert_allclose(push.force, [-3.0, 0, 0], atol=force_tol(r))
    np.testing.assert_allclose(push.point, where, atol=MM)  # the centre of pressure
    assert contact(r, "j", "face x-").force_magnitude <= force_tol(r)


def test_disc_pushed_beyond_its_rim_tilts_onto_both_faces() -> None:
    # a force F along x at e > R from the centre (along the joint y axis):
    # the disc tilts about z by J / (2R), centred, rim points on each face;
    # lever rule: F (e + R) / 2R on the near face, F (e - R) / 2R on the far one
    F, e = 4.0, 30.0
    r = solved(model([DISC], [{"body": "B", "at": list(AT + e * Y_AXIS), "force": list(F * AXIS)}]))
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, 0, atol=MM)
    np.testing.assert_allclose(jr.rotation, [0, 0, -J / (2 * R)], atol=RAD)
    near, far = contact(r, "j", "face x+"), contact(r, "j", "face x-")
    np.testing.assert_allclose(near.force, [-F * (e + R) / (2 * R), 0, 0], atol=force_tol(r))
    np.testing.assert_allclose(far.force, [F * (e - R) / (2 * R), 0, 0], atol=force_tol(r))
    np.testing.assert_allclose(near.point, AT + R * Y_AXIS, atol=MM)
    np.testing.assert_allclose(far.point, AT - R * Y_AXIS, atol=MM)


@pytest.mark.parametrize("angle", [0.0, 0.7, 2.0])
def test_disc_under_a_moment_tilts_about_the_moment_axis(angle: float) -> None:
    M = 50.0
    axis_local = np.array([0.0, np.cos(angle), np.sin(angle)])
    torque = M * (axis_local[1] * Y_AXIS + axis_local[2] * Z_AXIS)
    r = solved(model([DISC], [{"body": "B", "torque": list(torque)}]))
    jr = r.joints["j"]
    np.testing.assert_allclose(jr.translation, 0, atol=MM)
    np.testing.assert_allclose(jr.rotation, J / (2 * R) * axis_local, atol=RAD)
    for c in jr.contacts:
        assert c.in_contact
        assert c.force_magnitude == pytest.approx(M / (2 * R), abs=force_tol(r))
    np.testing.assert_allclose(jr.reaction_moment, -M * axis_local, atol=moment_tol(r))


def test_compliant_disc_goes_past_its_play_by_force_over_stiffness() -> None:
    F, k = 300.0, 1000.0
    soft = {**DISC, "stiffness": k}
    r = solved(model([soft], [{"body": "B", "at": list(AT), "force": list(F * AXIS)}]))
    np.testing.assert_allclose(r.joints["j"].translation, [J / 2 + F / k, 0, 0], atol=MM)
    assert contact(r, "j", "face x+").penetration == pytest.approx(F / k, abs=MM)


def test_disc_with_no_play_holds_its_normal_and_tilts() -> None:
    tight = {**DISC, "clearance": 0}
    r = solved(
        model([tight], [{"body": "B", "at": list(AT + 40 * Y_AXIS), "force": list(5 * AXIS)}])
    )
    np.testing.assert_allclose(r.joints["j"].translation, 0, atol=MM)
    np.testing.assert_allclose(r.joints["j"].rotation, 0, atol=RAD)
    assert r.joints["j"].reaction_force == pytest.approx([-5, 0, 0], abs=force_tol(r))


def test_planar_face_is_a_rectangle_or_a_disc() -> None:
    with pytest.raises(jointplay.ModelError, match="not both"):
        model([{**DISC, "width": 10, "height": 10}], [])
    with pytest.raises(jointplay.ModelError, match="'diameter'"):
        model([{**DISC, "diameter": None, "width": 10}], [])


def test_disc_warm_and_batch_solves_match_fresh_solves() -> None:
    # the disc plus a ball joint that holds the plate's slide: flat and tilted answers
    ball = {
        "name": "s",
        "type": "spherical",
        "between": ["G", "B"],
        "at": list(AT),
        "clearance": 0.1,
    }
    joints = [DISC, ball]
    ws = Workspace.of(model(joints, []))
    where = AT + 10.0 * Y_AXIS
    W = ws.asm.wrench_work("B", list(where))
    rng = np.random.default_rng(4)
    wrenches = np.zeros((40, 6))
    wrenches[:, :3] = rng.normal(size=(40, 3)) + 3.0 * AXIS
    wrenches[:, 3:] = 60.0 * rng.normal(size=(40, 3))
    spin = (wrenches[:, 3:] + np.cross(where - AT, wrenches[:, :3])) @ AXIS
    wrenches[:, 3:] -= np.outer(spin, AXIS)  # nothing holds the spin about the normal
    batch = ws.solve_batch(wrenches @ W.T)
    for i, wrench in enumerate(wrenches):
        loads = [
            {"body": "B", "at": list(where), "force": list(wrench[:3]), "torque": list(wrench[3:])}
        ]
        ref = solved(model(joints, loads))
        warm = ws.solve(loads=[jointplay.Load(**loads[0])])
        warm.check()
        for name in ("j", "s"):
            for other in (warm.joints[name], None):
                got_t = (
                    batch.joint_torsor(name)[i]
                    if other is None
                    else np.r_[other.translation, other.rotation]
                )
                np.testing.assert_allclose(got_t[:3], ref.joints[name].translation, atol=MM)
                np.testing.assert_allclose(got_t[3:], ref.joints[name].rotation, atol=RAD)


# -- the point joint -------------------------------------------------------------------


def point_joint(name: str, at: list[float], axis: list[float], **more: Any) -> dict[str, Any]:
    return {"name": name, "type": "point", "between": ["G", "B"], "at": at, "axis": axis, **more}


def lever(length: float, gap: float) -> list[dict[str, Any]]:
    """A beam on a ball joint (play 0.2) at the origin and a point contact at
    x = length, its plane's normal along +Y."""
    ball = {"type": "spherical", "between": ["G", "B"], "at": [0, 0, 0], "clearance": 0.2}
    return [{"name": "ball", **ball}, point_joint("tip", [length, 0, 0], [0, 1, 0], gap=gap)]


def test_lever_on_a_ball_and_a_point_closed_form() -> None:
    # a beam on a ball joint (play J = 0.2) at x = 0 and a point contact at
    # x = L with gap g below it; a downward load at x = a pivots it about the point
    L, a, g, F = 100.0, 40.0, 0.05, 7.0
    joints = lever(L, g)
    r = solved(model(joints, [{"body": "B", "at": [a, 0, 0], "force": [0, -F, 0]}]))
    body = r.bodies["B"]
    np.testing.assert_allclose(body.translation, [0, -0.1, 0], atol=MM)
    np.testing.assert_allclose(body.rotation, [0, 0, (0.1 - g) / L], atol=RAD)
    tip = contact(r, "tip", "plane")
    assert tip.in_contact
    newtons = force_tol(r)
    np.testing.assert_allclose(tip.force, [F * a / L, 0, 0], atol=newtons)  # along the normal
    np.testing.assert_allclose(tip.point, [L, 0, 0], atol=1e-12)  # the model's 'at', not solved
    np.testing.assert_allclose(r.joints["tip"].translation, [-g, 0, 0], atol=MM)
    np.testing.assert_allclose(
        contact(r, "ball", "ball").force, [0, F * (1 - a / L), 0], atol=newtons
    )


def test_point_lifts_off_freely() -> None:
    joints = lever(100.0, 0.05)
    r = solved(model(joints, [{"body": "B", "at": [0, 0, 0], "force": [0, 7, 0]}]))
    tip = contact(r, "tip", "plane")
    assert not tip.in_contact and tip.force_magnitude <= force_tol(r)
    np.testing.assert_allclose(r.joints["ball"].translation, [0, 0.1, 0], atol=MM)
    np.testing.assert_allclose(contact(r, "ball", "ball").force, [0, -7, 0], atol=force_tol(r))
    # the tip may rise anywhere above its plane (a tie): it is off the plane,
    # at the least-norm point of the joint metric (docs/conventions.md)
    assert r.joints["tip"].translation[0] > -0.05
    # lifting it anywhere else turns the beam about the ball, and nothing stops that
    with pytest.raises(
        UnboundedMechanismError, match=r"rotation about the global \+Z axis is not held"
    ):
        jointplay.solve(model(joints, [{"body": "B", "at": [40, 0, 0], "force": [0, 7, 0]}]))


def table(gap: float, **more: Any) -> list[dict[str, Any]]:
    feet = [
        point_joint(f"foot{i}", [0, 50 * np.cos(t), 50 * np.sin(t)], [1, 0, 0], gap=gap, **more)
        for i, t in enumerate([0.0, 2.0, 4.0])
    ]
    centring = {
        "name": "pin",
        "type": "sphere_in_cylinder",
        "between": ["G", "B"],
        "at": [0, 0, 0],
        "clearance": 0.1,
    }
    return [*feet, centring]


def test_a_plate_on_three_feet_shares_its_weight_by_statics() -> None:
    where = np.array([0.0, 6.0, -4.0])
    r = solved(model(table(0.03), [{"body": "B", "at": list(where), "force": [-12, 0, 0]}]))
    feet = np.array([r.joints[f"foot{i}"].centre for i in range(3)])
    # sum f_i = 12 and sum f_i (y_i, z_i) = 12 (y, z) of the load
    statics = np.vstack([np.ones(3), feet[:, 1], feet[:, 2]])
    expected = np.linalg.solve(statics, 12.0 * np.array([1.0, where[1], where[2]]))
    got = [contact(r, f"foot{i}", "plane").force[0] for i in range(3)]
    np.testing.assert_allclose(got, expected, atol=force_tol(r))
    np.testing.assert_allclose(r.bodies["B"].translation, [-0.03, 0, 0], atol=MM)
    np.testing.assert_allclose(r.bodies["B"].rotation, 0, atol=RAD)


def test_compliant_feet_sink_by_their_share_over_stiffness() -> None:
    # three feet carry a rigid plate statically determinately: the shares of
    # the statics, each foot sinking by its share over k
    k = 500.0
    feet = table(0.0, stiffness=k)
    where = np.mean([f["at"] for f in feet[:3]], axis=0)  # the load at the feet's centroid
    r = solved(model(feet, [{"body": "B", "at": list(where), "force": [-30, 0, 0]}]))
    for i in range(3):
        c = contact(r, f"foot{i}", "plane")
        assert c.force[0] == pytest.approx(10.0, abs=force_tol(r))
        assert c.penetration == pytest.approx(10.0 / k, abs=MM)
    np.testing.assert_allclose(r.bodies["B"].displacement_of(where), [-10.0 / k, 0, 0], atol=MM)


def test_a_load_that_lifts_the_plate_is_a_free_motion_with_its_sense() -> None:
    with pytest.raises(
        UnboundedMechanismError,
        match=r"body 'B': translation along the global \+X axis is not held by any joint",
    ):
        jointplay.solve(model(table(0.0), [{"body": "B", "at": [0, 6, -4], "force": [12, 0, 0]}]))
    # a load outside the feet tips the plate over an edge
    with pytest.raises(UnboundedMechanismError, match="body 'B'"):
        jointplay.solve(model(table(0.0), [{"body": "B", "at": [0, 200, 0], "force": [-12, 0, 0]}]))


def test_a_point_joint_has_a_gap_not_a_clearance() -> None:
    with pytest.raises(jointplay.ModelError, match=r"gap: 0\.1"):
        model([point_joint("p", [0, 0, 0], [1, 0, 0], clearance=0.1)], [])


def test_wobbly_table_example_rocks_onto_the_short_foot_by_hand() -> None:
    """examples/studies/wobbly_table.yaml: four feet, foot4 50 um short. At
    rest the weight (117.72 N at (-10, 5)) is on foot2's side of the diagonal
    foot1-foot3, so feet 1, 2, 3 carry it; leaning 200 N on foot4's corner
    rocks the table about that diagonal until foot4 lands (foot2 lifts)."""
    from conftest import ROOT

    m = jointplay.load(ROOT / "examples" / "studies" / "wobbly_table.yaml")
    feet = {f"foot{i}": np.array(m.joints[i - 1].at[:2]) for i in range(1, 5)}

    def statics(carrying: list[str], loads: list[tuple[float, np.ndarray]]) -> np.ndarray:
        P = np.array([feet[n] for n in carrying])
        lhs = np.vstack([np.ones(3), P[:, 0], P[:, 1]])
        rhs = sum(w * np.array([1.0, *at]) for w, at in loads)
        return np.linalg.solve(lhs, rhs)

    weight = (12 * 9.81, np.array([-10.0, 5.0]))
    cases = jointplay.solve_cases(m)
    rest, lean = cases["resting"], cases["leaning on foot4"]
    for r in cases.values():
        r.check()
    got = [contact(rest, n, "plane").force[0] for n in ("foot1", "foot2", "foot3")]
    expected = statics(["foot1", "foot2", "foot3"], [weight])
    np.testing.assert_allclose(got, expected, atol=force_tol(rest))
    assert not contact(rest, "foot4", "plane").in_contact
    np.testing.assert_allclose(rest.points["probe"].displacement, 0, atol=MM)

    push = (200.0, np.array([100.0, -100.0]))
    got = [contact(lean, n, "plane").force[0] for n in ("foot1", "foot3", "foot4")]
    expected = statics(["foot1", "foot3", "foot4"], [weight, push])
    np.testing.assert_allclose(got, expected, atol=force_tol(lean))
    assert not contact(lean, "foot2", "plane").in_contact
    # foot4 sinks 0.05 mm: a turn about the diagonal, omega = (2.5e-4, 2.5e-4, 0) rad
    omega = np.array([2.5e-4, 2.5e-4, 0.0])
    np.testing.assert_allclose(lean.bodies["table"].rotation, omega, atol=RAD)
    np.testing.assert_allclose(
        lean.points["probe"].displacement, np.cross(omega, [0, 150, 80]), atol=MM
    )


def faintly_pushed_table() -> jointplay.Model:
    # A table turned hard in two centring balls (1e5 N*mm about z) and pushed
    # down by 0.01 N between its two level feet (at x = -2.5) and its low one
    # (x = 5, 0.1 mm down): it rocks about the level feet onto the low one,
    # which carries 0.01 * 1.5 / 7.5 N. The push is 1e-7 of the turn's
    # reactions, so the interior point leaves the low foot short of its
    # limit; an unloaded body beside it makes the optimum a tie (its own play).
    # A polish that missed the low foot once lifted the table off it and kept
    # its force (a property test's drawn case).
    up = [0.0, 0.0, 1.0]
    foot = {"type": "point", "between": ["G", "T"], "axis": up}
    ball = {"type": "sphere_in_cylinder", "between": ["G", "T"], "axis": up, "clearance": 1.0}
    stop = {"type": "point", "between": ["G", "idle"], "at": [5.0, 0.0, 0.0]}
    c, s = np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3)
    return model_from_dict(
        {
            "bodies": [{"name": "G", "ground": True}, {"name": "T"}, {"name": "idle"}],
            "joints": [
                {**foot, "name": "low", "at": [5.0, 0.0, 0.0], "gap": 0.1},
                {**foot, "name": "left", "at": [5.0 * c, 5.0 * s, 0.0]},
                {**foot, "name": "right", "at": [5.0 * c, -5.0 * s, 0.0]},
                {**ball, "name": "ball0", "at": [0.0, 0.0, 0.0]},
                {**ball, "name": "ball5", "at": [5.0, 0.0, 0.0]},
                {
                    "name": "pivot",
                    "type": "revolute",
                    "between": ["G", "idle"],
                    "at": [0.0, 0.0, 0.0],
                    "axis": up,
                    "clearance": 1.0,
                    "length": 5.0,
                    "axial_clearance": 1.0,
                },
                {**stop, "name": "stop", "axis": [0.0, -1.0, 0.0]},
                {**stop, "name": "catch", "axis": [0.0, 1.0, 0.0], "gap": 10**0.5},
            ],
            "loads": [
                {"body": "T", "torque": [0.0, 0.0, -1e5]},
                {"body": "T", "at": [-1.0, 0.0, 0.0], "force": [0.0, 0.0, -0.01]},
            ],
        }
    )


def test_a_faint_push_under_a_large_turn_rocks_the_table_onto_its_low_foot() -> None:
    m = faintly_pushed_table()
    r = solved(m)
    tilt = 0.1 / 7.5  # about y, through the level feet's line x = -2.5
    np.testing.assert_allclose(r.bodies["T"].rotation, [0.0, tilt, -0.2], atol=RAD)
    np.testing.assert_allclose(r.bodies["T"].translation, [0.0, 0.5, -2.5 * tilt], atol=MM)
    low = 0.01 * 1.5 / 7.5
    # forces to 1e-8 of the largest in the balance (the turn's 2e4 N reactions)
    got = [contact(r, j, "plane").force[0] for j in ("low", "left", "right")]
    np.testing.assert_allclose(got, [low, (0.01 - low) / 2, (0.01 - low) / 2], atol=2e-4)
    np.testing.assert_allclose(r.bodies["idle"].translation, 0.0, atol=MM)


def table_moved(
    omega: np.ndarray, v_origin: np.ndarray
) -> tuple[Workspace, np.ndarray, np.ndarray, Any, Any]:
    """The faintly pushed table's workspace, unit loads, softness, its
    certified optimum, and that optimum with the table T moved to the small
    displacement (``omega``, the velocity of the origin ``v_origin``), its
    forces kept, uncertified."""
    from dataclasses import replace

    from jointplay.solver import pipeline

    ws = Workspace.of(faintly_pushed_table())
    g = ws.asm.g
    g_hat = g / np.linalg.norm(g)
    sigma = np.zeros(len(ws.balls))
    right = pipeline.optimum(ws, g_hat, sigma)
    i = ws.asm.body_index["T"]
    x = right.x.copy()
    x[6 * i : 6 * i + 3] = (v_origin + np.cross(omega, ws.asm.body_ref[i])) / ws.asm.s
    x[6 * i + 3 : 6 * i + 6] = omega / ws.asm.turn[i]
    return ws, g_hat, sigma, right, replace(right, x=x, certificate=None)


def test_the_certificate_refuses_the_table_lifted_off_its_loaded_foot() -> None:
    """The wrong answer that was once printed: the table of the test above
    left flat, off its low foot, which keeps its force. It holds every
    clearance and balances every body; only complementarity tells, and only
    per contact over its own play: the foot's force is 1e-7 of the largest,
    its 0.1 mm play all unused (over the largest play, 3.2 mm, that was
    3e-9 and passed)."""
    from jointplay.solver import certificate

    ws, g_hat, sigma, right, moved = table_moved(np.array([0.0, 0.0, -0.2]), np.array([0, 0.5, 0]))
    lifted = certificate.certify(ws, g_hat, sigma, moved)
    st, largest_play = ws.settings, ws.max_radius * ws.asm.s  # what the certificate allows
    assert lifted.feasibility_mm <= st.feasibility_tolerance * largest_play
    assert lifted.equilibrium_residual <= st.equilibrium_tolerance
    assert lifted.complementarity > 1e-8 and not lifted.certified
    assert certificate.certify(ws, g_hat, sigma, right).certified


def test_the_certificate_refuses_a_faint_force_on_a_contact_just_clear() -> None:
    """A contact clear by more than ``clear`` of its play pushes with
    nothing. Weighed by its slack alone, the low foot's faint force (1e-7 of
    the largest) with 2 % of its play unused made 2e-9 and passed: that is
    how a route once printed a contact pushing 7.5e-6 N while 0.000226 mm
    clear (tests/property_cases/force_on_a_contact_just_clear.yaml)."""
    from dataclasses import replace

    from jointplay.solver import certificate

    tilt = 0.98 * 0.1 / 7.5  # rocked back about the level feet's line: the low foot 2 % clear
    omega, v_origin = np.array([0.0, tilt, -0.2]), np.array([0.0, 0.5, -2.5 * tilt])
    ws, g_hat, sigma, _, lifted = table_moved(omega, v_origin)
    x = lifted.x
    joints = ws.asm.model.joints
    low = next(k for k, b in enumerate(ws.balls) if joints[b.joint_index].name == "low")
    _, _, level = ws.stack.levels(x)
    assert 0.019 < 1.0 - level[low] / ws.stack.r[low] < 0.021
    cert = certificate.certify(ws, g_hat, sigma, lifted)
    st, largest_play = ws.settings, ws.max_radius * ws.asm.s  # what the certificate allows
    assert cert.feasibility_mm <= st.feasibility_tolerance * largest_play
    assert cert.equilibrium_residual <= st.equilibrium_tolerance
    assert cert.complementarity > 1e-8 and not cert.certified
    weighed = replace(ws.settings, clear=1.0)  # every slack weighs the force: passes
    ws_weighed = Workspace(ws.asm, weighed)
    assert certificate.certify(ws_weighed, g_hat, sigma, lifted).certified
