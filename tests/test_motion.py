"""The motion study against closed forms: Freudenstein's equation for the
four-bar, the slider-crank's piston position; a full turn returns the start;
its failures and bad entries; the clearance answer at a pose is the posed
model's own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import jointplay
from jointplay.errors import ModelError, MotionError, UnboundedMechanismError
from jointplay.io.modelfile import model_from_dict
from jointplay.studies.kinematics import nominal_poses
from jointplay.studies.motion import Motion, posed_model

GALLERY = Path(__file__).parent.parent / "examples" / "gallery"
#: The closed forms are met to this (mm, rad): the brief's kinematic promise.
KINEMATICS_TOL = 1e-9
TURN = np.linspace(0.0, 2 * np.pi, 73)


def _with_motion(path: Path, **motion: object) -> jointplay.Model:
    """The model at ``path`` with its motion changed, and one constant force
    on its first load's point in place of its loads (a table over one drive
    reads nothing over another)."""
    data = jointplay.load(path).model_dump(by_alias=True, exclude_none=True)
    data["motion"] = {**data.get("motion", {}), **motion}
    first = data["loads"][0]
    data["loads"] = [{"body": first["body"], "at": first["at"], "force": [-1500.0, 0, 0]}]
    return model_from_dict(data, source=str(path))


def test_four_bar_output_angle_meets_freudenstein() -> None:
    model = jointplay.load(GALLERY / "four_bar.yaml")
    poses = nominal_poses(model, TURN)
    a, b, c, d = 60.0, np.hypot(150, 50), np.hypot(50, 110), 200.0
    C = np.array([poses.place(s, "rocker", np.array([150.0, 110, 0])) for s in range(len(TURN))])
    th2 = np.pi / 2 + TURN
    th4 = np.arctan2(C[:, 1], C[:, 0] - d)
    K1, K2, K3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    assert np.max(np.abs(K1 * np.cos(th4) - K2 * np.cos(th2) + K3 - np.cos(th2 - th4))) < (
        KINEMATICS_TOL
    )


def test_slider_crank_piston_position() -> None:
    model = jointplay.load(GALLERY / "slider_crank.yaml")
    poses = nominal_poses(model, TURN)
    r, h, x0 = 40.0, 10.0, 179.6424
    l = np.hypot(x0 - r, h)  # noqa: E741 - the rod's length, as the formula names it
    x = np.array([poses.place(s, "piston", np.array([x0, h, 0]))[0] for s in range(len(TURN))])
    ref = r * np.cos(TURN) + np.sqrt(l**2 - (r * np.sin(TURN) - h) ** 2)
    assert np.max(np.abs(x - ref)) < KINEMATICS_TOL


def test_a_full_turn_returns_the_start_pose() -> None:
    model = jointplay.load(GALLERY / "four_bar.yaml")
    poses = nominal_poses(model, TURN)
    assert np.max(np.abs(poses.R[-1] - poses.R[0])) < KINEMATICS_TOL
    assert np.max(np.abs(poses.p[-1] - poses.p[0])) < KINEMATICS_TOL


def test_unreachable_range_names_step_and_joints() -> None:
    model = _with_motion(GALLERY / "slider_crank.yaml", drive="guide", range=["0 mm", "50 mm"])
    with pytest.raises(MotionError, match="unreachable") as err:
        nominal_poses(model, np.linspace(0.0, 50.0, 11))
    assert err.value.exit_code == 2 and err.value.step >= 0 and err.value.joints


def test_undriven_names_the_free_body() -> None:
    data = jointplay.load(GALLERY / "slider_crank.yaml").model_dump(
        by_alias=True, exclude_none=True
    )
    data["joints"][1]["type"] = "spherical"  # the rod may now spin about its own length
    for key in ("length", "axial_clearance", "axis"):
        data["joints"][1].pop(key, None)
    data["joints"][1]["clearance"] = 0.02
    data["joints"][2]["type"] = "spherical"
    for key in ("length", "axial_clearance", "axis"):
        data["joints"][2].pop(key, None)
    data["joints"][2]["clearance"] = 0.02
    model = model_from_dict(data)
    with pytest.raises(UnboundedMechanismError, match="rod") as err:
        nominal_poses(model, TURN[:3])
    assert err.value.exit_code == 3


@pytest.mark.parametrize(
    ("motion", "words"),
    [
        ({"drive": "nothing", "range": ["0 deg", "1 deg"]}, "unknown joint 'nothing'"),
        ({"drive": "main bearing", "range": ["0 mm", "1 mm"]}, "range[0]: expected an angle"),
        ({"drive": "guide", "range": ["0 deg", "1 deg"]}, "range[0]: expected a length"),
        ({"drive": "main bearing", "range": ["0 deg", "1 deg"], "steps": 1}, "motion.steps"),
    ],
)
def test_bad_motion_entries(motion: dict[str, object], words: str) -> None:
    data = jointplay.load(GALLERY / "slider_crank.yaml").model_dump(
        by_alias=True, exclude_none=True
    )
    data["motion"] = motion
    with pytest.raises(ModelError) as err:
        model_from_dict(data, source="crank.yaml")
    assert err.value.exit_code == 2
    assert "crank.yaml" in str(err.value) and "motion" in str(err.value)
    assert words in str(err.value)


def test_answer_at_a_pose_is_the_posed_models() -> None:
    model = jointplay.load(GALLERY / "slider_crank.yaml")
    result = Motion(steps=5).run(model)
    posed = posed_model(model, result.poses, 1)
    direct = jointplay.solve(posed)
    direct.check()
    play = 0.03  # the largest play's order (mm): the certificate's feasibility scale
    assert np.allclose(
        result.displacement[1, 0], direct.points["piston top"].displacement, atol=1e-9 * play
    )
    assert result.to_dict()["study"] == "motion"
    assert len(result.to_dataframe()) == 5
