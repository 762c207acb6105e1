"""Extreme scales: micrometre plays on metre-long parts, kilonewton loads,
nearly coincident joints, nearly free mechanisms. Each gives the right answer
(checked against a scaled closed form and by its certificate) or a clear
message; never a silent inaccurate number."""

from __future__ import annotations

import copy
from typing import Any

import numpy as np
import pytest

import jointplay
from conftest import MM, RAD, solve_file, spherical_shaft
from jointplay.io.modelfile import model_from_dict


def _scaled_shaft(length: float, play: float, force: float) -> dict[str, Any]:
    """The paper's 6.1.6.1 shaft with every length times ``length``, both
    plays times ``play`` and the force times ``force``."""
    data = spherical_shaft()
    joints = copy.deepcopy(data["joints"])
    assert isinstance(joints, list)
    for j in joints:
        j["at"] = [c * length for c in j["at"]]
        j["clearance"] = j["clearance"] * play
        if "length" in j:
            j["length"] = j["length"] * length
    data["joints"] = joints
    data["loads"] = [{"body": "S1", "at": [300 * length, 0, 0], "force": [force] * 3}]
    return data


@pytest.mark.parametrize(
    ("length", "play", "force"),
    [(10.0, 0.005, 1000.0), (10.0, 0.005, 1e-3), (0.01, 1.0, 1.0), (5.0, 25.0, 5e4)],
    ids=["1 um play on a 2 m shaft, 1 kN", "same, 1 mN", "2 mm shaft", "5 mm play, 50 kN"],
)
def test_scaled_paper_shaft_is_the_scaled_paper_answer(
    length: float, play: float, force: float
) -> None:
    """Without springs the answer depends on the geometry only: translations
    scale with the play, rotations with play / length, whatever the force."""
    reference = solve_file("6.1.6.1.yaml")
    result = jointplay.solve(model_from_dict(_scaled_shaft(length, play, force)))
    result.check()
    for name in ("l1", "l2"):
        ref, got = reference.joints[name], result.joints[name]
        # relative to the scaled answer: a 1 um play gives 5e-4 mm translations,
        # where the absolute 1e-6 mm of the other tests would check nothing
        assert np.allclose(got.translation, play * ref.translation, rtol=0, atol=MM * play)
        assert np.allclose(got.rotation, play / length * ref.rotation, rtol=0, atol=RAD * play)
    assert result.certificate.feasibility_mm <= 1e-9 * 0.1 * play
    assert result.accuracy()["certified"]


def test_kilonewton_loads_on_springs_sink_by_force_over_stiffness() -> None:
    """A compliant ball under 20 kN: the penetration is F/k on top of the play."""
    data = spherical_shaft()
    data["joints"] = [
        {
            "name": "ball",
            "type": "spherical",
            "between": ["S0", "S1"],
            "at": [0, 0, 0],
            "clearance": "2 um",
            "stiffness": "5e5 N/mm",
        },
        {
            "name": "ring",
            "type": "sphere_in_cylinder",
            "between": ["S0", "S1"],
            "at": [1000, 0, 0],
            "clearance": 0.5,
        },
        {
            "name": "stop",
            "type": "spherical",
            "between": ["S0", "S1"],
            "at": [0, 0, 500],
            "clearance": 0.5,
        },
    ]
    data["loads"] = [{"body": "S1", "at": [0, 0, 0], "force": ["20 kN", 0, 0]}]
    result = jointplay.solve(model_from_dict(data))
    result.check()
    ball = result.joints["ball"]
    assert ball.translation[0] == pytest.approx(0.001 + 20000 / 5e5, abs=MM)
    assert ball.contacts[0].penetration == pytest.approx(20000 / 5e5, abs=MM)


def _shaft_with_ring_at(x_mm: float) -> dict[str, object]:
    data = spherical_shaft()
    data["joints"][1] = {  # type: ignore[index]
        "name": "l2",
        "type": "sphere_in_cylinder",
        "between": ["S0", "S1"],
        "at": [x_mm, 0, 0],
        "clearance": 0.2,
    }
    return data


def test_nearly_coincident_joints_are_flagged_not_hidden() -> None:
    """A shaft tilting about a ball 1 um from its ring: the play allows a
    turn of 200 rad, far beyond small displacements. The answer is the linear
    model's, and the result says how far it is from the exact geometry."""
    result = jointplay.solve(model_from_dict(_shaft_with_ring_at(0.001)))
    result.check()
    assert result.warnings, "a turn of radians must not pass silently"
    assert "body 'S1' turns by" in result.warnings[-1]


def test_joints_a_nanometre_apart_hold_nothing() -> None:
    """The same ring 1 nm from the ball: the linear answer turns the shaft by
    2e5 rad. That is no answer: the shaft is reported as not held (exit 3),
    with the turn and the motion named."""
    with pytest.raises(jointplay.UnboundedMechanismError) as info:
        jointplay.solve(model_from_dict(_shaft_with_ring_at(1e-6)))
    message = str(info.value)
    assert "body 'S1'" in message
    assert "held only weakly" in message
    assert "2e+05 rad" in message


def test_a_nearly_free_spin_is_held_or_reported() -> None:
    """A revolute whose anti-rotation dowel sits 1 nm off the axis: the spin
    is held, by a play of 0.1 mm at 1e-6 mm, i.e. 1e5 rad. A torque drives it
    to that limit: the linear answer is certified and flagged."""
    data = {
        "bodies": [{"name": "ground", "ground": True}, {"name": "rotor"}],
        "joints": [
            {
                "name": "hinge",
                "type": "revolute",
                "between": ["ground", "rotor"],
                "at": [0, 0, 0],
                "length": 50,
                "clearance": 0.02,
                "axial_clearance": 0.02,
            },
            {
                "name": "dowel",
                "type": "sphere_in_cylinder",
                "between": ["ground", "rotor"],
                "at": [0, 1e-6, 0],
                "clearance": 0.1,
            },
        ],
        "loads": [{"body": "rotor", "torque": [1, 0, 0]}],
    }
    try:
        result = jointplay.solve(model_from_dict(data))
    except jointplay.JointplayError as err:  # a clear message is acceptable
        assert "rotor" in str(err)
        return
    result.check()
    assert result.warnings


def test_a_load_on_a_free_motion_below_the_rank_tolerance_is_ignored() -> None:
    """A torque about the shaft axis of 1e-12 of the load: round-off, not a
    drive (settings.free_motion_rcond = 1e-9). At 1e-6 it drives the spin."""
    data = spherical_shaft()
    data["loads"] = [
        {"body": "S1", "at": [300, 0, 0], "force": [1, 1, 1]},
        {"body": "S1", "torque": [1e-12 * 300, 0, 0]},
    ]
    jointplay.solve(model_from_dict(data)).check()
    data["loads"][1]["torque"] = [1e-6 * 300, 0, 0]  # type: ignore[index]
    with pytest.raises(jointplay.UnboundedMechanismError, match="rotation about the global X"):
        jointplay.solve(model_from_dict(data))


def test_units_from_micrometres_to_metres_give_one_answer() -> None:
    """The same shaft written in um, mm and m (and forces in mN, N, kN)."""
    answers = []
    for length_unit, k_len, force_unit, k_force in (
        ("um", 1e3, "mN", 1e3),
        ("mm", 1.0, "N", 1.0),
        ("m", 1e-3, "kN", 1e-3),
    ):
        data = _scaled_shaft(1.0, 1.0, 1.0)
        for j in data["joints"]:  # type: ignore[union-attr]
            j["at"] = [f"{c * k_len} {length_unit}" for c in j["at"]]
            j["clearance"] = f"{j['clearance'] * k_len} {length_unit}"
            if "length" in j:
                j["length"] = f"{j['length'] * k_len} {length_unit}"
        data["loads"] = [
            {
                "body": "S1",
                "at": [f"{300 * k_len} {length_unit}", 0, 0],
                "force": [f"{k_force} {force_unit}"] * 3,
            }
        ]
        answers.append(jointplay.solve(model_from_dict(data)))
    for other in answers[1:]:
        for name in ("l1", "l2"):
            assert np.allclose(
                other.joints[name].translation, answers[0].joints[name].translation, atol=MM
            )
            assert np.allclose(
                other.joints[name].rotation, answers[0].joints[name].rotation, atol=RAD
            )
