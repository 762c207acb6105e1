"""Drives with backlash, axial plays of screws, and pins in slots, against closed forms."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import jointplay
from conftest import MM, RAD, force_tol, moment_tol
from jointplay import UnboundedMechanismError
from jointplay.studies.montecarlo import MonteCarlo

ARM = 100.0  # mm, from the pivot to where the force acts


def arm(joint: dict[str, object], force: float = 10.0) -> jointplay.Model:
    """An arm on a pivot about global Z, pushed across at its tip (torque F * ARM)."""
    pivot: dict[str, object] = {
        "name": "pivot",
        "type": "revolute",
        "between": ["ground", "arm"],
        "at": [0, 0, 0],
        "axis": [0, 0, 1],
        "length": 20,
        "clearance": 0.02,
        "axial_clearance": 0.01,
    }
    pivot.update(joint)
    return jointplay.model_from_dict(
        {
            "bodies": [{"name": "ground", "ground": True}, {"name": "arm"}],
            "joints": [pivot],
            "loads": [{"body": "arm", "at": [ARM, 0, 0], "force": [0, force, 0]}],
            "points": [{"name": "tip", "body": "arm", "at": [ARM, 0, 0]}],
        }
    )


def solved(model: jointplay.Model) -> jointplay.Result:
    result = jointplay.solve(model)
    result.check()
    return result


@pytest.mark.parametrize("force", [10.0, -7.0])
def test_an_arm_turns_by_half_its_backlash_and_the_drive_takes_the_torque(force: float) -> None:
    b = math.radians(0.2)
    r = solved(arm({"backlash": "0.2 deg"}, force))
    jr = r.joints["pivot"]
    sign = math.copysign(1.0, force)
    assert jr.rotation[0] == pytest.approx(sign * b / 2, abs=RAD)
    np.testing.assert_allclose(jr.rotation[1:], 0.0, atol=RAD)
    # the bore's play across, then the turn: the tip moves by J/2 + ARM * b/2
    tip = r.points["tip"].displacement
    np.testing.assert_allclose(tip, [0.0, sign * (0.01 + ARM * b / 2), 0.0], atol=MM)
    drive = {c.name: c for c in jr.contacts}["drive"]
    assert drive.in_contact and drive.unit == "rad"
    np.testing.assert_allclose(drive.force, 0.0, atol=force_tol(r))
    # statics: the drive's reaction torque balances F * ARM about the axis (joint x)
    assert drive.torque[0] == pytest.approx(-force * ARM, abs=moment_tol(r))
    np.testing.assert_allclose(drive.torque[1:], 0.0, atol=moment_tol(r))
    assert jr.reaction_moment[0] == pytest.approx(-force * ARM, abs=moment_tol(r))


def test_a_stiff_drive_turns_past_its_backlash_by_torque_over_stiffness() -> None:
    b, k, force = math.radians(0.2), 2e6, 10.0  # N*mm/rad
    r = solved(arm({"backlash": "0.2 deg", "torsional_stiffness": f"{k} N*mm/rad"}, force))
    jr = r.joints["pivot"]
    assert jr.rotation[0] == pytest.approx(b / 2 + force * ARM / k, abs=RAD)
    drive = {c.name: c for c in jr.contacts}["drive"]
    assert drive.penetration == pytest.approx(force * ARM / k, abs=RAD)
    assert drive.torque[0] == pytest.approx(-force * ARM, abs=moment_tol(r))
    # the same stiffness in other units: 2e6 N*mm/rad is 34.9 N*m/deg
    r2 = solved(
        arm({"backlash": "0.2 deg", "torsional_stiffness": f"{k / 1e3 * math.pi / 180} N*m/deg"})
    )
    assert r2.joints["pivot"].rotation[0] == pytest.approx(jr.rotation[0], abs=RAD)


@pytest.mark.parametrize(
    "backlash",
    [
        0.00349065850398866,
        "0.2 deg",
        "12 arcmin",
        {"length": "52.3598775598 um", "radius": "15 mm"},
    ],
)
def test_backlash_in_any_unit_is_the_same_angle(backlash: object) -> None:
    r = solved(arm({"backlash": backlash}))
    assert r.joints["pivot"].rotation[0] == pytest.approx(math.radians(0.1), abs=RAD)


def test_zero_backlash_is_an_ideal_drive_and_no_drive_leaves_the_spin_free() -> None:
    r = solved(arm({"backlash": 0}))
    assert r.joints["pivot"].rotation[0] == pytest.approx(0.0, abs=RAD)
    with pytest.raises(UnboundedMechanismError, match="rotation about the global Z axis"):
        jointplay.solve(arm({}))


def test_a_cylindrical_joint_takes_a_drive_and_an_axial_play() -> None:
    model = arm({"type": "cylindrical", "axial_clearance": 0.04, "backlash": "1 mrad"})
    pushed = model.replace(
        loads=[
            {"body": "arm", "at": [ARM, 0, 0], "force": [0, 10, 0]},
            {"body": "arm", "at": [0, 0, 0], "force": [0, 0, -3]},
        ]
    )
    jr = solved(pushed).joints["pivot"]
    assert jr.translation[0] == pytest.approx(-0.02, abs=MM)  # axial play along joint x = Z
    assert jr.rotation[0] == pytest.approx(0.5e-3, abs=RAD)
    with pytest.raises(UnboundedMechanismError):  # without its axial play the slide is free
        jointplay.solve(
            pushed.replace(
                joints=[
                    {
                        **pushed.joints[0].model_dump(exclude_none=True),
                        "axial_clearance": None,
                    }
                ]
            )
        )


def test_a_screw_nut_on_a_prismatic_slide_holds_it_within_its_axial_play() -> None:
    model = jointplay.model_from_dict(
        {
            "bodies": [{"name": "bed", "ground": True}, {"name": "table"}],
            "joints": [
                {
                    "name": "guide",
                    "type": "prismatic",
                    "between": ["bed", "table"],
                    "at": [0, 0, 0],
                    "length": 200,
                    "width": 60,
                    "height": 30,
                    "clearance": 0.02,
                    "axial_clearance": "30 um",
                }
            ],
            "loads": [{"body": "table", "at": [0, 0, 0], "force": [-50, 0, 0]}],
        }
    )
    r = solved(model)
    jr = r.joints["guide"]
    assert jr.translation[0] == pytest.approx(-0.015, abs=MM)
    axial = {c.name: c for c in jr.contacts}["axial"]
    assert axial.force[0] == pytest.approx(50.0, abs=force_tol(r))


def slot(joint: dict[str, object], force: list[float]) -> jointplay.Model:
    """A pin (body 'pin') in a slot of the ground along X, the pin's axis Z."""
    base: dict[str, object] = {
        "name": "slot",
        "type": "slot",
        "between": ["plate", "pin"],
        "at": [0, 0, 0],
        "axis": [0, 0, 1],
        "along": [1, 0, 0],
        "length": 10,
        "clearance": 0.04,
    }
    base.update(joint)
    return jointplay.model_from_dict(
        {
            "bodies": [{"name": "plate", "ground": True}, {"name": "pin"}],
            "joints": [base],
            "loads": [{"body": "pin", "at": [0, 0, 0], "force": force}],
        }
    )


def test_a_pin_in_a_slot_has_its_play_across_and_is_free_along() -> None:
    r = solved(slot({}, [0, 5, 0]))
    jr = r.joints["slot"]
    # the joint's frame is the model's geometry, not the solve's: unit axes
    # whose cross products are exact in floating point, on any machine
    np.testing.assert_allclose(jr.R_world_joint[:, 1], [1, 0, 0], atol=1e-15)  # y along
    np.testing.assert_allclose(jr.R_world_joint[:, 2], [0, 1, 0], atol=1e-15)  # z = x cross y
    np.testing.assert_allclose(jr.translation, [0, 0, 0.02], atol=MM)
    np.testing.assert_allclose(r.bodies["pin"].translation, [0, 0.02, 0], atol=MM)
    with pytest.raises(UnboundedMechanismError, match="translation along the global X axis"):
        jointplay.solve(slot({}, [1, 5, 0]))


def test_a_slot_length_limits_the_slide_and_the_engagement_the_tilt() -> None:
    r = solved(slot({"slot_length": 0.5}, [2, 0, 0]))
    np.testing.assert_allclose(r.bodies["pin"].translation, [0.25, 0, 0], atol=MM)
    # a moment tilting the pin across the slot: its ends go +-J/2, the tilt is J / L
    tilted = slot({}, [0, 0, 0]).replace(
        loads=[{"body": "pin", "torque": [1, 0, 0]}]  # about X: the ends move along Y
    )
    r = solved(tilted)
    np.testing.assert_allclose(r.bodies["pin"].rotation, [0.04 / 10, 0, 0], atol=RAD)


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"up": [0, 1, 0]}, "remove 'up'"),
        ({"along": [0, 0, 2]}, "parallel to the pin's axis"),
        ({"length": 1e-6}, "less than a thousandth of the clearance"),
    ],
)
def test_a_bad_slot_is_refused(change: dict[str, object], words: str) -> None:
    with pytest.raises(jointplay.ModelError, match=words):
        slot(change, [0, 1, 0])


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"torsional_stiffness": 1e6}, "torsional_stiffness needs a drive"),
        ({"backlash": {"length": 0.02}}, r"expected an angle, \{length, radius\}"),
        ({"backlash": {"length": 0.02, "radius": 0}}, "radius: expected a length > 0"),
        ({"backlash": "2 mm"}, "expected an angle"),
        ({"backlash": "2 percent"}, "expected an angle, got '2 percent', which is dimensionless"),
        ({"backlash": "0.1 deg", "torsional_stiffness": "3e6 N*mm"}, "angle differs from"),
        ({"backlash": -0.001}, "expected a value >= 0"),
        ({"backlash": {"min": "0.3 deg", "max": "0.1 deg"}}, "swap them"),
        ({"backlash": "0.1 deg", "torsional_stiffness": 1e-9}, "holds nothing"),
    ],
)
def test_a_bad_drive_is_refused(change: dict[str, object], words: str) -> None:
    with pytest.raises(jointplay.ModelError, match=words):
        arm(change)


def test_a_toleranced_backlash_is_drawn_and_each_sample_turns_by_its_own_half(
    tmp_path: Path,
) -> None:
    model = arm({"backlash": {"min": "3 arcmin", "max": "9 arcmin"}, "axial_clearance": 0})
    result = MonteCarlo(samples=200, seed=2, chunk=100).run(model)
    assert result.play_labels == ("pivot.backlash",)
    b = result.plays[:, 0]
    assert np.all((b >= math.radians(3 / 60)) & (b <= math.radians(9 / 60)))
    expected_y = 0.01 + ARM * b / 2
    np.testing.assert_allclose(result.displacement[:, 0, 1], expected_y, atol=MM)


GALLERY = Path(__file__).resolve().parents[1] / "examples" / "gallery"


@pytest.mark.parametrize(
    ("name", "point"),
    [
        ("four_bar.yaml", "fingertip"),
        ("spindle.yaml", "tool tip"),
        ("located_plate.yaml", "drilled hole"),
    ],
)
def test_the_real_mechanisms_solve_and_give_an_envelope_and_a_monte_carlo(
    name: str, point: str
) -> None:
    from jointplay.studies.envelope import Envelope

    model = jointplay.load(GALLERY / name)
    solved(model)
    env = Envelope(point, directions=40).run(model)
    assert env.largest > 0 and env.not_held == ()
    mc = MonteCarlo(samples=200, seed=1, chunk=100).run(model)
    assert mc.samples == 200 and len(mc.play_labels) >= 2
    assert mc.feasibility_mm < 1e-9 and mc.equilibrium_residual <= 1e-8


def test_the_spindle_drive_takes_the_cutting_torque() -> None:
    model = jointplay.load(GALLERY / "spindle.yaml")
    r = solved(model)
    drive = {c.name: c for c in r.joints["rear bearing"].contacts}["drive"]
    # the cut: 300 N along Y and -150 N along Z at 20 mm above the axis X
    cut = np.cross([-80.0, 0.0, 20.0], [-50.0, 300.0, -150.0])
    assert drive.torque[0] == pytest.approx(-cut[0], abs=moment_tol(r))
    # past its backlash by T / k: the belt's 40 N*m/deg
    k = 40e3 / math.radians(1.0)
    b = float(model.joint("rear bearing").backlash)  # type: ignore[attr-defined]
    spin = r.joints["rear bearing"].rotation[0]
    assert abs(spin) == pytest.approx(b / 2 + abs(cut[0]) / k, abs=RAD)


def test_the_located_plate_stands_on_its_buttons() -> None:
    r = solved(jointplay.load(GALLERY / "located_plate.yaml"))
    pushes = [r.joints[f"button{i}"].contacts[0].force[0] for i in (1, 2, 3)]
    assert all(p > 0 for p in pushes)
    # weight and drill, to the certificate's balance of the plate
    assert sum(pushes) == pytest.approx(4 * 9.81 + 80.0, abs=force_tol(r))
    slot = {c.name: c for c in r.joints["slot pin"].contacts}
    assert set(slot) == {"across-", "across+"}  # free along the slot: no contact there


def test_the_pictures_show_a_drive_as_a_note_and_a_slot_as_two_walls(tmp_path: Path) -> None:
    from jointplay.present.plot import mechanism_figure, save
    from jointplay.present.scene import joint_view

    for name in ("four_bar.yaml", "located_plate.yaml"):
        model = jointplay.load(GALLERY / name)
        result = solved(model)
        out = save(mechanism_figure(model, result), tmp_path / f"{name}.png")
        assert out.stat().st_size > 10_000
    bar = jointplay.load(GALLERY / "four_bar.yaml")
    motor = joint_view(bar.joint("motor"), solved(bar).joints["motor"])
    assert "drive (spin): +0.001745 rad of ±0.001745 rad (touching)" in motor.note
    assert not any("drive" in p.label for p in motor.points)  # no marker for the drive
    plate = jointplay.load(GALLERY / "located_plate.yaml")
    view = joint_view(plate.joint("slot pin"), solved(plate).joints["slot pin"])
    assert view.rectangle == (math.inf, float(plate.joint("slot pin").clearance) / 2)


def test_a_pin_whose_axial_play_no_load_takes_is_batched_as_a_tie() -> None:
    # The arm's axial play is unloaded: its optimal positions form a face (a tie),
    # and the answer is the face's least-norm point, axial slide 0. The batch
    # solves such rows by Newton with the face's tie rows (``Face.tie_rows``);
    # before, every sample went to the full solver's least-norm program.
    model = arm({"backlash": {"min": "3 arcmin", "max": "9 arcmin"}})
    result = MonteCarlo(samples=300, seed=5, chunk=300).run(model)
    assert result.batched >= 290  # the reason for the tie rows: few full solves
    b = result.plays[:, 0]
    np.testing.assert_allclose(result.displacement[:, 0, 1], 0.01 + ARM * b / 2, atol=MM)
    np.testing.assert_allclose(result.displacement[:, 0, [0, 2]], 0.0, atol=MM)
    for i in range(0, 300, 50):  # the full solver's least-norm answer, sample by sample
        alone = solved(arm({"backlash": float(b[i])}))
        np.testing.assert_allclose(
            result.displacement[i, 0], alone.points["tip"].displacement, atol=MM
        )


def test_a_spin_no_joint_holds_is_told_which_play_would_hold_it() -> None:
    """The message of a free motion the loads drive names the load that works
    most on it and, where the motion turns joints about their own axes
    alone, the backlash that would hold it; the advice taken, the model
    solves. A ball joint's free turn takes no backlash: no such advice."""
    import yaml

    from jointplay.io.modelfile import model_from_dict

    root = Path(__file__).parent.parent / "examples"
    bar = yaml.safe_load((root / "gallery" / "four_bar.yaml").read_text())
    del bar["joints"][0]["backlash"]
    with pytest.raises(UnboundedMechanismError) as info:
        jointplay.solve(model_from_dict(bar))
    said = str(info.value)
    assert "most by loads[0] on 'coupler'" in said
    assert (
        "joints 'motor', 'pin B', 'pin C', 'pin D' each turn about their axes in it: give one "
        'of them a backlash (the play of a drive that holds its spin, e.g. backlash: "0.2 deg")'
    ) in said
    bar["joints"][2]["backlash"] = "0.2 deg"  # on pin C, as the message allows
    assert jointplay.solve(model_from_dict(bar)).certificate.certified

    shaft = yaml.safe_load((root / "paper" / "6.1.6.1.yaml").read_text())
    shaft["loads"].append({"body": "S1", "torque": [1000, 0, 0]})  # about the shaft's axis
    with pytest.raises(UnboundedMechanismError) as info:
        jointplay.solve(model_from_dict(shaft))
    said = str(info.value)
    assert "most by loads[1] on 'S1'" in said and "give joint 'l2' a backlash" in said
    shaft["joints"][1]["backlash"] = "0.2 deg"
    assert jointplay.solve(model_from_dict(shaft)).certificate.certified

    ball = yaml.safe_load((root / "paper" / "6.1.6.1.yaml").read_text())
    del ball["joints"][1]  # S1 on its ball joint alone, turned about Z
    ball["loads"] = [{"body": "S1", "torque": [0, 0, 1000]}]
    with pytest.raises(UnboundedMechanismError) as info:
        jointplay.solve(model_from_dict(ball))
    assert "backlash" not in str(info.value)
    assert "add a joint or a clearance limit that holds this motion" in str(info.value)
