"""The motion study against closed forms: Freudenstein's equation for the
four-bar, the slider-crank's piston position; a full turn returns the start;
its failures and bad entries; the clearance answer at a pose is the posed
model's own."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

import jointplay
from jointplay.errors import ModelError, MotionError, OptionError, UnboundedMechanismError
from jointplay.io.modelfile import model_from_dict
from jointplay.studies.kinematics import ReachError, nominal_poses
from jointplay.studies.motion import Motion, posed_model
from test_cli import _missing, run

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
    """The piston pushed 50 mm up its guide, 0.08 mm short of its top dead
    centre (the main bearing without its backlash, which would hold the
    crank and lock the piston): the first step is out of reach."""
    model = _with_motion(GALLERY / "slider_crank.yaml", drive="guide", range=["0 mm", "50 mm"])
    data = model.model_dump(by_alias=True, exclude_none=True)
    [main] = [j for j in data["joints"] if j["name"] == "main bearing"]
    del main["backlash"]
    model = model_from_dict(data, source="slider_crank.yaml")
    with pytest.raises(MotionError, match="unreachable") as err:
        nominal_poses(model, np.linspace(0.0, 50.0, 11))
    assert err.value.exit_code == 2 and err.value.step == 1 and err.value.joints


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
        # each with its fix
        ({"drive": "main bearing", "range": "0 deg:360 deg"}, "give the range as [START, STOP]"),
        ({"drive": "main bearing", "range": ["0 deg"]}, "needs START and STOP"),
        ({"drive": "main bearing", "range": ["0 deg", "1 deg"], "steps": 0}, "at least 2 steps"),
        ({"drvie": "main bearing", "range": ["0 deg", "1 deg"]}, "Did you mean 'drive'?"),
        (
            {"drive": "main bearing", "range": ["0 deg", "1 deg"], "step": 5},
            "Did you mean 'steps'?",
        ),
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


def test_a_slide_driven_in_degrees_is_told_it_takes_a_length() -> None:
    """'0 deg' is an angle (pint calls it dimensionless): the message names
    the entry and says what the drive of a prismatic slide takes."""
    data = jointplay.load(GALLERY / "slider_crank.yaml").model_dump(
        by_alias=True, exclude_none=True
    )
    data["motion"] = {"drive": "guide", "range": ["0 deg", "50 mm"]}
    with pytest.raises(
        ModelError,
        match=r"crank\.yaml: motion: range\[0\]: expected a length, got '0 deg', which is an "
        r"angle; .*; the drive of prismatic joint 'guide' is its slide, which takes a length "
        r"\(mm\), such as '25 mm'",
    ) as err:
        model_from_dict(data, source="crank.yaml")
    assert err.value.exit_code == 2 and "dimensionless" not in str(err.value)


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


def test_every_pose_of_a_turn_is_the_posed_models_solve() -> None:
    """Each pose's Newton starts from the poses before (``batch.follow``,
    ``batch.extrapolated``): two routes to one optimum, which agree to the
    certificate's tolerance, at every step of the four-bar's turn."""
    model = jointplay.load(GALLERY / "four_bar.yaml")
    result = Motion().run(model)
    for s in range(result.steps):
        direct = jointplay.solve(posed_model(model, result.poses, s))
        mine = result.results[s]
        mine.check()
        play = 0.05  # the largest play (mm): the pins' axial clearance
        force = max(c.force_magnitude for j in direct.joints.values() for c in j.contacts)
        assert np.allclose(
            result.displacement[s, 0], direct.points["fingertip"].displacement, atol=1e-8 * play
        )
        for name, joint in direct.joints.items():
            assert np.allclose(mine.joints[name].translation, joint.translation, atol=1e-8 * play)
            assert np.allclose(
                mine.joints[name].reaction_force, joint.reaction_force, atol=1e-8 * force
            )
        assert result.touching[s] == tuple(
            f"{n}.{c.name}" for n, j in direct.joints.items() for c in j.contacts if c.in_contact
        )


def test_a_welded_loop_s_reactions_over_a_turn_are_the_posed_models_solve() -> None:
    """A grip welded to the coupler twice (a weld in a closed loop: the rigid
    joints share the load by the documented split, not as any balance would
    have it): each pose's rigid and contact reactions are the posed model's
    solve, to the certificate's tolerance."""
    data = yaml.safe_load((GALLERY / "four_bar.yaml").read_text())
    data["bodies"].append({"name": "grip", "mass": "0.5 kg", "center_of_mass": [100, 140, 0]})
    for name, at in (("w1", [100, 130, 0]), ("w2", [90, 140, 0])):
        data["joints"].append(
            {"name": name, "type": "rigid", "between": ["coupler", "grip"], "at": at}
        )
    data["loads"][0]["body"] = "grip"
    data["motion"]["steps"] = 13
    model = model_from_dict(data, source="<welded four-bar>")
    result = Motion().run(model)
    for s in range(result.steps):
        direct = jointplay.solve(posed_model(model, result.poses, s))
        force = max(np.linalg.norm(j.reaction_force) for j in direct.joints.values())
        moment = max(np.linalg.norm(j.reaction_moment) for j in direct.joints.values())
        for name, joint in direct.joints.items():
            mine = result.results[s].joints[name]
            assert np.allclose(mine.reaction_force, joint.reaction_force, atol=1e-8 * force)
            assert np.allclose(mine.reaction_moment, joint.reaction_moment, atol=1e-8 * moment)
            for c, d in zip(mine.contacts, joint.contacts, strict=True):
                assert np.allclose(c.force, d.force, atol=1e-8 * force)


# -- the clearance answer over the motion against closed forms ------------------------
#: The clearance answer meets a closed form to this (mm): the brief's promise.
PLAY_TOL = 1e-6
#: ... and, for an angle, to this (rad).
PLAY_ANGLE_TOL = 1e-8
#: A table over a turn: a compressor's gas force (N), always pushing the piston.
GAS = [["0 deg", -1500], ["20 deg", -400], ["40 deg", -150], ["180 deg", -150],
       ["270 deg", -400], ["320 deg", -1000], ["345 deg", -1500], ["360 deg", -1500]]  # fmt: skip
R_CRANK, L_ROD = 40.0, 140.0
#: Diametral clearances (mm): main bearing, crank pin, wrist pin, guide.
SC_PLAYS = (0.020, 0.030, 0.024, 0.036)


def _slider_crank(h: float, force: object, steps: int = 37) -> jointplay.Model:
    """Crank R_CRANK, rod L_ROD, the guide's axis at offset ``h`` along x; the
    crank driven at its main bearing without backlash; one force along the
    guide at the wrist pin (N, or a table): the rod carries no load of its own."""
    xb = R_CRANK + float(np.sqrt(L_ROD**2 - h**2))
    wrist = [xb, h, 0.0]
    o, a, b, g = SC_PLAYS
    pin = {"type": "revolute", "axis": [0, 0, 1], "length": 20, "axial_clearance": 0.1}
    return model_from_dict(
        {
            "bodies": [
                {"name": "frame", "ground": True},
                {"name": "crank"},
                {"name": "rod"},
                {"name": "piston"},
            ],
            "joints": [
                {
                    **pin,
                    "name": "main bearing",
                    "between": ["frame", "crank"],
                    "at": [0, 0, 0],
                    "clearance": o,
                    "backlash": 0,
                },
                {
                    **pin,
                    "name": "crank pin",
                    "between": ["crank", "rod"],
                    "at": [R_CRANK, 0, 0],
                    "clearance": a,
                },
                {
                    **pin,
                    "name": "wrist pin",
                    "between": ["rod", "piston"],
                    "at": wrist,
                    "clearance": b,
                },
                {
                    "name": "guide",
                    "type": "prismatic",
                    "between": ["frame", "piston"],
                    "at": wrist,
                    "axis": [1, 0, 0],
                    "up": [0, 1, 0],
                    "length": 40,
                    "width": 40,
                    "height": 40,
                    "clearance": g,
                },
            ],
            "loads": [{"body": "piston", "at": wrist, "force": [force, 0, 0]}],
            "points": [{"name": "piston top", "body": "piston", "at": [xb + 20, h, 0]}],
            "motion": {"drive": "main bearing", "range": ["0 deg", "360 deg"], "steps": steps},
        },
        source="slider_crank",
    )


@pytest.mark.parametrize("h", [0.0, 10.0, -25.0])
@pytest.mark.parametrize(
    "force", [-1500.0, 800.0, {"table": GAS}], ids=["compressed", "pulled", "gas table"]
)
def test_slider_crank_play_closes_along_the_rod(h: float, force: object) -> None:
    """The rod carries no load: a two-force member, its force N along its
    direction u = (cos phi, sin phi) from the crank pin to the wrist pin,
    sin phi = (h - r sin t) / l. In compression (F < 0) every pin's play
    closes against N: the crank (held in rotation by the drive) shifts by
    -e_O u in the main bearing, the rod's end at the crank pin by a further
    -e_A u, the piston at the wrist pin by a further -e_B u (e: radial plays,
    half the clearances). The guide pushes the piston across with -N sin phi,
    so the piston's offset is dy = e_G sign(sin phi) (e_G half the guide's
    clearance); it turns nothing, the force being at the guide's centre. The
    rod is rigid along u: u . d_piston = u . d_rod(crank pin) - e_B, so
    dx cos phi + dy sin phi = -(e_O + e_A + e_B), and

        dx = -(e_O + e_A + e_B + e_G |sin phi|) / cos phi.

    In tension every play closes the other way: the same with the signs
    turned. The gas table pushes at every step: the compressed answer. The
    drive holds M = -F dx_nominal/dt = F r (sin t - cos t tan phi)
    (virtual work on the nominal geometry, the table's force at t)."""
    model = _slider_crank(h, force)
    result = Motion().run(model)
    t = result.values
    sin_phi = (h - R_CRANK * np.sin(t)) / L_ROD
    cos_phi = np.sqrt(1.0 - sin_phi**2)
    e_o, e_a, e_b, e_g = (c / 2 for c in SC_PLAYS)
    gas = isinstance(force, dict)
    F = np.interp(t, [np.radians(float(x.split()[0])) for x, _ in GAS], [y for _, y in GAS])
    F = F if gas else np.full_like(t, float(force))  # type: ignore[arg-type]
    sign = np.sign(F)
    dx = sign * (e_o + e_a + e_b + e_g * np.abs(sin_phi)) / cos_phi
    d = result.displacement[:, 0]
    assert np.max(np.abs(d[:, 0] - dx)) < PLAY_TOL
    across = np.abs(sin_phi) > 1e-9  # where the guide pushes, the piston's offset
    assert np.max(np.abs(d[across, 1] + sign[across] * e_g * np.sign(sin_phi[across]))) < (PLAY_TOL)
    assert np.max(np.abs(d[:, 2])) < PLAY_TOL
    M = F * R_CRANK * (np.sin(t) - np.cos(t) * sin_phi / cos_phi)
    assert np.max(np.abs(result.drive_reaction - M)) < 1e-8 * np.max(np.abs(M))


#: The four-bar: crank a from O2 = 0, coupler b, rocker c to O4 = (d, 0).
FB_A, FB_B_AT, FB_D = 60.0, (150.0, 110.0), 200.0
#: A four-bar's bodies: the frame, then its crank, coupler and rocker.
FOUR_BAR_BODIES = [
    {"name": "frame", "ground": True},
    {"name": "crank"},
    {"name": "coupler"},
    {"name": "rocker"},
]
#: Diametral clearances (mm): O2 (the motor's bearing), A, B, O4.
FB_PLAYS = (0.010, 0.024, 0.020, 0.030)


def _four_bar(torque: float, drive: str = "motor", turn: object = "360 deg") -> jointplay.Model:
    """The gallery's four-bar's geometry, its crank driven without backlash,
    a torque on the rocker (N*mm): the coupler carries no load of its own.
    ``drive``: "pivot" drives the rocker instead, from 0 to ``turn``."""
    bx, by = FB_B_AT
    o2, a, b, o4 = FB_PLAYS
    pin = {"type": "revolute", "axis": [0, 0, 1], "length": 12, "axial_clearance": 0.05}
    data: dict[str, Any] = {
        "bodies": [dict(b) for b in FOUR_BAR_BODIES],
        "joints": [
            {
                **pin,
                "name": "motor",
                "between": ["frame", "crank"],
                "at": [0, 0, 0],
                "clearance": o2,
            },
            {
                **pin,
                "name": "pin A",
                "between": ["crank", "coupler"],
                "at": [0, FB_A, 0],
                "clearance": a,
            },
            {
                **pin,
                "name": "pin B",
                "between": ["coupler", "rocker"],
                "at": [bx, by, 0],
                "clearance": b,
            },
            {
                **pin,
                "name": "pivot",
                "between": ["frame", "rocker"],
                "at": [FB_D, 0, 0],
                "clearance": o4,
            },
        ],
        "loads": [{"body": "rocker", "torque": [0, 0, torque]}],
        "points": [
            {"name": "rocker pivot", "body": "rocker", "at": [FB_D, 0, 0]},
            {"name": "rocker tip", "body": "rocker", "at": [bx, by, 0]},
        ],
        "motion": {
            "drive": drive,
            "range": [0, f"{turn!r} rad" if isinstance(turn, float) else turn],
            "steps": 37,
        },
    }
    data["joints"][["motor", "pivot"].index(drive) * 3]["backlash"] = 0
    return model_from_dict(data, source="four_bar")


@pytest.mark.parametrize("torque", [2000.0, -3000.0], ids=["counter-clockwise", "clockwise"])
def test_four_bar_play_as_a_coupler_length(torque: float) -> None:
    """The coupler carries no load: a two-force member along u (from pin A to
    pin B). Whatever the sign of its force, each play closes along u: the
    crank (held in rotation by the drive) shifts by its bearing's radial
    play e_1 along u, the coupler by e_2 more at A; at B and at the rocker's
    pivot the plays e_3, e_4 close along u too, so for the rocker's rotation
    the four add up as a change of the coupler's length by E = e_1 + e_2 +
    e_3 + e_4 (a compressed coupler acts shortened, a pulled one
    lengthened). The torque T turns the rocker its way, so its rotation is
    E |d theta_4 / d b| at fixed theta_2, from Freudenstein's equation
    f = K1 cos th4 - K2 cos th2 + K3 - cos(th2 - th4) = 0 with
    K3 = (a^2 - b^2 + c^2 + d^2) / (2 a c):
    d th4/d b = -(df/db) / (df/dth4) = (b / (a c)) / (-K1 sin th4 - sin(th2 - th4)).
    The rocker's pivot shifts by e_4 along u, against the coupler's force on
    the rocker: -sign(T) sign(d th4/d b) e_4 u."""
    model = _four_bar(torque)
    result = Motion().run(model)
    t = result.values
    bx, by = FB_B_AT
    a, b, c, d = FB_A, float(np.hypot(bx, by - FB_A)), float(np.hypot(bx - FB_D, by)), FB_D
    e = [p / 2 for p in FB_PLAYS]
    nominal = result.nominal  # (S, 2, 3): the pivot, the tip (pin B)
    pin_b = nominal[:, 1, :2]
    pin_a = np.stack([-FB_A * np.sin(t), FB_A * np.cos(t)], axis=1)
    th2 = np.pi / 2 + t
    th4 = np.arctan2(pin_b[:, 1], pin_b[:, 0] - d)
    K1 = d / a
    sensitivity = (b / (a * c)) / (-K1 * np.sin(th4) - np.sin(th2 - th4))
    turn = np.sign(torque) * sum(e) * np.abs(sensitivity)
    arm = pin_b - [d, 0.0]
    moved = result.displacement[:, 1, :2] - result.displacement[:, 0, :2]
    rotation = (arm[:, 0] * moved[:, 1] - arm[:, 1] * moved[:, 0]) / np.sum(arm**2, axis=1)
    assert np.max(np.abs(rotation - turn)) < PLAY_ANGLE_TOL
    u = (pin_b - pin_a) / np.linalg.norm(pin_b - pin_a, axis=1)[:, None]
    pivot = -np.sign(torque) * np.sign(sensitivity)[:, None] * e[3] * u
    assert np.max(np.abs(result.displacement[:, 0, :2] - pivot)) < PLAY_TOL
    assert np.max(np.abs(result.displacement[:, :, 2])) < PLAY_TOL
    # the rigid rocker: the tip moves as the pivot's shift and the rotation say
    tip = pivot + turn[:, None] * np.stack([-arm[:, 1], arm[:, 0]], axis=1)
    assert np.max(np.abs(result.displacement[:, 1, :2] - tip)) < PLAY_TOL


def _four_bar_file(tmp_path: Path, model: jointplay.Model) -> Path:
    path = tmp_path / "four_bar.yaml"
    path.write_text(yaml.safe_dump(model.model_dump(by_alias=True, exclude_none=True)))
    return path


def _toggle_turn(sign: float = 1.0) -> float:
    """How far the rocker turns from the written pose to a toggle with the
    crank and coupler in line (rad): there |O2 B| = b + a (``sign`` 1, the
    rocker turned clockwise) or b - a (-1, counter-clockwise), so
    d^2 + c^2 + 2 d c cos th4 = (b + sign a)^2."""
    bx, by = FB_B_AT
    b, c = float(np.hypot(bx, by - FB_A)), float(np.hypot(bx - FB_D, by))
    th4 = np.arccos(((b + sign * FB_A) ** 2 - FB_D**2 - c**2) / (2 * FB_D * c))
    return float(th4 - np.arctan2(by, bx - FB_D))


def test_a_four_bar_driven_through_its_toggle_stops_at_the_dead_point(tmp_path: Path) -> None:
    """Driven by its rocker through the rocker's extreme (a step on it), the
    four-bar stops there: "dead point", the step and the loop's joints; from
    the command line, one line and exit 2."""
    model = _four_bar(1000.0, drive="pivot", turn=2 * _toggle_turn())
    with pytest.raises(MotionError, match="dead point") as err:
        nominal_poses(model, np.linspace(0.0, 2 * _toggle_turn(), 3))
    assert err.value.kind == "dead point" and err.value.step == 1 and err.value.exit_code == 2
    assert {"motor", "pin A", "pin B"} <= set(err.value.joints)
    proc = run("motion", str(_four_bar_file(tmp_path, model)), "--steps", "3")
    assert proc.returncode == 2 and proc.stdout == "" and "Traceback" not in proc.stderr
    assert "dead point: at step 1" in proc.stderr and "'pin A'" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_a_grashof_rocker_turned_a_full_turn_is_out_of_reach(tmp_path: Path) -> None:
    """The crank-rocker driven by its rocker through 360 deg: the rocker
    swings only between its toggles, so a step past one is "unreachable",
    naming the step and the joints; from the command line exit 2."""
    model = _four_bar(1000.0, drive="pivot", turn="360 deg")
    with pytest.raises(MotionError, match="unreachable") as err:
        Motion().run(model)
    swing = _toggle_turn(-1.0)  # the counter-clockwise toggle; steps of 10 deg
    assert err.value.kind == "unreachable" and err.value.step == int(
        np.ceil(swing / np.radians(10))
    )
    assert "pivot" in err.value.joints
    proc = run("motion", str(_four_bar_file(tmp_path, model)))
    assert proc.returncode == 2 and proc.stdout == "" and "Traceback" not in proc.stderr
    assert f"unreachable: at step {err.value.step}" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


#: The located end of a drive's reach meets its closed form to this (rad).
REACH_TOL = 1e-6


@pytest.mark.parametrize(
    ("turn", "sign"), [("360 deg", -1.0), ("-360 deg", 1.0)], ids=["ccw", "cw"]
)
def test_a_rocker_driven_past_its_toggle_is_told_where_its_reach_ends(
    tmp_path: Path, turn: str, sign: float
) -> None:
    """The crank-rocker driven by its rocker, either way: its reach ends
    where crank and coupler are in line, |O2 B| = b - a or b + a (the cosine
    rule, ``_toggle_turn``). A step past it is "unreachable" (the range asks
    for values the linkage cannot reach), its message says where the reach
    ends (6 digits, on the near side), that it is a toggle (a dead point) of
    the crank's and coupler's joints, between which steps, and the fix."""
    import re

    model = _four_bar(1000.0, drive="pivot", turn=turn)
    with pytest.raises(ReachError) as err:
        Motion().run(model)
    limit = _toggle_turn(sign)
    assert abs(err.value.end - limit) < REACH_TOL
    assert err.value.kind == "unreachable" and err.value.exit_code == 2
    n = int(np.ceil(abs(limit) / np.radians(10)))  # steps of 10 deg
    assert err.value.step == n
    assert err.value.value == pytest.approx(np.sign(limit) * np.radians(10 * n))
    assert {"motor", "pin A", "pin B"} <= set(err.value.joints)
    message = str(err.value)
    [shown] = re.findall(r"reach ends at (-?[\d.]+) deg", message)
    assert len(shown.replace("-", "").replace(".", "").lstrip("0")) == 6, shown
    assert abs(float(shown) - np.degrees(limit)) < 1e-4
    assert abs(float(shown)) <= abs(np.degrees(limit))  # a value still reached
    grid = np.degrees(np.sign(limit) * np.radians(10.0) * np.array([n - 1, n]))
    words = [
        f"between step {n - 1} ({grid[0]:g} deg) and step {n} ({grid[1]:g} deg)",
        "at a toggle (a dead point) of joints 'motor', 'pin A', 'pin B'",
        "which the drive cannot pass",
        f"stop the range short of {shown} deg, or drive another joint",
    ]
    assert all(w in message for w in words), message
    proc = run("motion", str(_four_bar_file(tmp_path, model)))
    assert proc.returncode == 2 and proc.stdout == "" and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert f"unreachable: at step {n}" in proc.stderr and all(w in proc.stderr for w in words)


def test_a_non_grashof_crank_driven_past_its_limit_is_told_where_its_reach_ends() -> None:
    """A triple rocker (l + s = 150 + 60 > p + q = 70 + 100): its "crank"
    (a = 150 about O2) swings only as far as coupler (b = 60) and rocker
    (c = 70 about O4, d = 100 from O2) fall in line, |A O4| = b + c, so
    cos th2 = (a^2 + d^2 - (b + c)^2) / (2 a d). Written at th2 = 30 deg and
    driven to 90 deg, the reach ends th2 - 30 deg on, a toggle of the
    coupler's and the rocker's joints."""
    import re

    a, b, c, d = 150.0, 60.0, 70.0, 100.0
    th2 = np.radians(30.0)
    A = a * np.array([np.cos(th2), np.sin(th2)])
    # B: |B - A| = b, |B - O4| = c, above the line A O4
    O4 = np.array([d, 0.0])
    e = float(np.linalg.norm(O4 - A))
    along = (b * b - c * c + e * e) / (2 * e)
    u = (O4 - A) / e
    B = A + along * u + np.sqrt(b * b - along * along) * np.array([-u[1], u[0]])
    pin = {"type": "revolute", "axis": [0, 0, 1], "length": 12, "axial_clearance": 0.05}
    pin["clearance"] = 0.02
    data = {
        "bodies": [dict(b) for b in FOUR_BAR_BODIES],
        "joints": [
            {**pin, "name": "motor", "between": ["frame", "crank"], "at": [0, 0, 0], "backlash": 0},
            {**pin, "name": "pin A", "between": ["crank", "coupler"], "at": [*A, 0]},
            {**pin, "name": "pin B", "between": ["coupler", "rocker"], "at": [*B, 0]},
            {**pin, "name": "pivot", "between": ["frame", "rocker"], "at": [d, 0, 0]},
        ],
        "loads": [{"body": "rocker", "torque": [0, 0, 1000.0]}],
        "motion": {"drive": "motor", "range": ["0 deg", "90 deg"], "steps": 10},
    }
    limit = np.arccos((a * a + d * d - (b + c) ** 2) / (2 * a * d)) - th2
    with pytest.raises(ReachError) as err:
        Motion().run(model_from_dict(data, source="triple_rocker"))
    assert abs(err.value.end - limit) < REACH_TOL
    assert err.value.kind == "unreachable"
    assert err.value.step == int(np.ceil(limit / np.radians(10)))
    assert {"pin A", "pin B", "pivot"} <= set(err.value.joints)
    [shown] = re.findall(r"reach ends at (-?[\d.]+) deg", str(err.value))
    assert 0 <= np.degrees(limit) - float(shown) < 1e-4


def _drive_free(path: Path, name: str, field: str, **motion: object) -> dict[str, Any]:
    """The model file at ``path`` with its joint ``name`` driven and without its ``field``."""
    data: dict[str, Any] = yaml.safe_load(path.read_text())
    for joint in data["joints"]:
        joint.pop("backlash", None)  # no other joint's spin held either: the drive's alone
        if joint["name"] == name:
            joint.pop(field, None)
    data["motion"] = {**data["motion"], "drive": name, **motion}
    if str(motion.get("range", ["deg"])[0]).endswith("mm"):  # type: ignore[index]
        # a gas force's table over the crank's angle reads nothing over a slide
        first = data["loads"][0]
        data["loads"] = [{"body": first["body"], "at": first["at"], "force": [-500.0, 0, 0]}]
    return data


@pytest.mark.parametrize(
    ("name", "joint", "field", "motion", "words"),
    [
        ("four_bar", "motor", "backlash", {}, ("its spin is free", 'backlash: "0.2 deg"')),
        (
            "slider_crank",
            "guide",
            "axial_clearance",
            {"range": ["0 mm", "-60 mm"], "steps": 7},
            ("its slide is free", 'axial_clearance: "50 um"'),
        ),
    ],
    ids=["spin", "slide"],
)
def test_a_drive_that_holds_nothing_is_named_with_its_fix(
    tmp_path: Path,
    name: str,
    joint: str,
    field: str,
    motion: dict[str, object],
    words: tuple[str, str],
) -> None:
    """A spin drive without a backlash (a slide drive without an
    axial_clearance) holds nothing in the clearance model: the loads drive
    the linkage's one free motion. Exit 3 still, with the body and the
    motion, but the message names the drive joint, what it lacks and the
    fix; --json says it too."""
    data = _drive_free(GALLERY / f"{name}.yaml", joint, field, **motion)
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data))
    proc = run("motion", str(path))
    assert proc.returncode == 3 and proc.stdout == "" and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    article = "an" if field == "axial_clearance" else "a"
    expected = [
        "jointplay: not held: at step 0 of the motion",
        f"the drive holds nothing: joint '{joint}' has no {field}",
        words[0],
        "body 'crank': rotation about the global Z axis is not held",
        f"give '{joint}' {article} {field} ({words[1]})",
    ]
    assert all(w in proc.stderr for w in expected), proc.stderr
    doc = json.loads(run("motion", str(path), "--json").stdout)
    assert doc["status"] == "unbounded" and doc["body"] == "crank"
    assert doc["motion"] == "rotation about the global Z axis" and expected[1] in doc["message"]
    with pytest.raises(UnboundedMechanismError) as err:
        Motion().run(model_from_dict(data))
    assert err.value.exit_code == 3 and err.value.body == "crank" and expected[1] in str(err.value)


#: Drives that another joint's held spin locks: (model, drive, the joint
#: whose backlash holds it, --range where the model's motion drives another kind).
LOCKED = [
    ("four_bar", "pin D", "motor", []),
    ("spindle", "front bearing", "rear bearing", ["--range", "0 deg:90 deg"]),
    ("slider_crank", "wrist pin", "main bearing", []),
]


@pytest.mark.parametrize(("name", "drive", "holder", "span"), LOCKED)
def test_a_drive_another_joint_holds_cannot_move(
    name: str, drive: str, holder: str, span: list[str]
) -> None:
    """A joint with a backlash (a drive) holds its spin; driving another
    joint of its loop, no range moves: before any step the message says the
    drive cannot move, names the joint that holds it and the fix; exit 2,
    one line, --json says it too."""
    path = str(GALLERY / f"{name}.yaml")
    proc = run("motion", path, "--drive", drive, *span, "--steps", "3")
    assert proc.returncode == 2 and proc.stdout == "" and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    words = [
        f"the drive '{drive}' cannot move",
        f"joint '{holder}' holds the spin it would turn (its backlash: a drive)",
        f"drive '{holder}' instead, or remove its backlash",
    ]
    assert all(w in proc.stderr for w in words), proc.stderr
    assert "unreachable" not in proc.stderr and "range" not in proc.stderr.split("motion:")[-1]
    doc = json.loads(run("motion", path, "--drive", drive, *span, "--steps", "3", "--json").stdout)
    assert doc["status"] == "invalid" and words[0] in doc["message"]
    model = jointplay.load(path)
    bounds = None if not span else tuple(span[1].split(":"))
    with pytest.raises(MotionError) as err:
        Motion(drive=drive, range=bounds, steps=3).run(model, path)
    assert err.value.kind == "locked" and err.value.joints == (holder,)
    assert err.value.exit_code == 2


def test_two_held_spins_that_lock_together_are_both_named() -> None:
    """Backlash at the motor and at the rocker's pivot: driving the coupler's
    pin, neither alone locks it but both together do; both are named, and
    removing both is the fix (driving one leaves the other's hold). A weld in
    the loop locks it with no play to remove: its joints are named."""
    data = jointplay.load(GALLERY / "four_bar.yaml").model_dump(by_alias=True, exclude_none=True)
    data["joints"] = list(data["joints"])
    [pivot] = [j for j in data["joints"] if j["name"] == "pin D"]
    pivot["backlash"] = "0.2 deg"
    data["motion"] = {"drive": "pin B", "range": ["0 deg", "1 deg"], "steps": 2}
    with pytest.raises(MotionError) as err:
        nominal_poses(model_from_dict(data, source="four_bar"), np.radians([0.0, 1.0]))
    assert err.value.kind == "locked" and set(err.value.joints) == {"motor", "pin D"}
    assert "remove all of: the backlash of 'motor', the backlash of 'pin D'" in str(err.value)
    data["joints"] = [j for j in data["joints"] if j["name"] != "pin D"]
    data["joints"].append(
        {"name": "weld", "type": "rigid", "between": ["frame", "rocker"], "at": [200, 0, 0]}
    )
    del data["joints"][0]["backlash"]
    data["motion"]["drive"] = "motor"
    with pytest.raises(MotionError) as err:
        nominal_poses(model_from_dict(data, source="four_bar"), np.radians([0.0, 1.0]))
    assert err.value.kind == "locked" and "weld" in err.value.joints
    assert "the drive 'motor' cannot move" in str(err.value)
    assert "no joint can drive it" in str(err.value)  # the weld fixes every body


def test_a_linkage_no_joint_can_drive_is_not_told_to_drive_another() -> None:
    """Pin C's axis across the others' (a slip in the file): the four-bar
    cannot move at all, so the fix is the joints' geometry, not another
    drive."""
    data = jointplay.load(GALLERY / "four_bar.yaml").model_dump(by_alias=True, exclude_none=True)
    data["joints"] = list(data["joints"])
    [pin] = [j for j in data["joints"] if j["name"] == "pin C"]
    pin["axis"] = [0, 1, 0]
    with pytest.raises(MotionError) as err:
        nominal_poses(model_from_dict(data, source="four_bar"), np.radians([0.0, 1.0]))
    assert err.value.kind == "locked" and "pin C" in err.value.joints
    words = str(err.value)
    assert "no joint can drive it" in words and "drive another joint" not in words


def test_without_the_backlash_that_held_it_the_drive_moves() -> None:
    """The four-bar's motor without its backlash: driven by its rocker's
    pivot, the linkage moves, and the crank-rocker's rocker swings the
    crank (no lock, the linkage's own kinematics)."""
    data = jointplay.load(GALLERY / "four_bar.yaml").model_dump(by_alias=True, exclude_none=True)
    [motor] = [j for j in data["joints"] if j["name"] == "motor"]
    del motor["backlash"]
    data["motion"] = {"drive": "pin D", "range": ["0 deg", "2 deg"], "steps": 3}
    model = model_from_dict(data, source="four_bar")
    poses = nominal_poses(model, np.radians([0.0, 1.0, 2.0]))
    crank = poses.turn(2, "crank")
    assert abs(np.arctan2(crank[1, 0], crank[0, 0])) > np.radians(1.0)


@pytest.mark.parametrize("force", [-1500.0, 800.0], ids=["compressed", "pulled"])
def test_a_shared_deviation_turns_with_its_body(force: float) -> None:
    """The crank's features made in one setup ('deviations', on the crank):
    its crank pin's seat off by t along the crank (the frame's z, 'up' along
    the crank as written). Carried with the crank, it makes the crank longer
    by t at every angle, so the piston moves by t dx/dr = t (cos t + sin t
    tan phi) besides the plays' closed form (the rod's force, along u, does
    not move the seat: the deviation centres the play, the play still
    closes along u)."""
    h, offset = 10.0, 0.004
    data = _slider_crank(h, force, steps=13).model_dump(by_alias=True, exclude_none=True)
    data["deviations"] = [
        {
            "name": "crank setup",
            "body": "crank",
            "at": [R_CRANK, 0, 0],
            "axis": [0, 0, 1],
            "up": [1, 0, 0],
            "position": {"diameter": "10 um", "mean": [0, 0, offset]},
        }
    ]
    data["joints"][1]["deviation"] = "crank setup"
    result = Motion().run(model_from_dict(data, source="slider_crank"))
    t = result.values
    sin_phi = (h - R_CRANK * np.sin(t)) / L_ROD
    cos_phi = np.sqrt(1.0 - sin_phi**2)
    e_o, e_a, e_b, e_g = (c / 2 for c in SC_PLAYS)
    plays = np.sign(force) * (e_o + e_a + e_b + e_g * np.abs(sin_phi)) / cos_phi
    longer = offset * (np.cos(t) + np.sin(t) * sin_phi / cos_phi)
    assert np.max(np.abs(result.displacement[:, 0, 0] - plays - longer)) < PLAY_TOL


def _motion_numbers(doc: dict[str, Any]) -> list[float]:
    """The numbers of a motion's --json that its text prints to 6 digits:
    the drive's values and reactions, the requirements' worst measures."""
    wanted = [step["drive"] for step in doc["steps"]]
    wanted += [step["drive_reaction"] for step in doc["steps"]]
    return wanted + [q["measured"] for q in doc["requirements"]]


@pytest.mark.parametrize("columns", ["80", "200"])
def test_piped_motion_text_keeps_every_number_whole(columns: str) -> None:
    """Piped (a CI log, a file), the motion's table is one line a step at any
    COLUMNS: every number --json gives that the text prints is whole, and
    every touching contact's joint and name are on its step's line."""
    import os

    env = {**os.environ, "COLUMNS": columns}
    args = ["motion", str(GALLERY / "slider_crank.yaml"), "--steps", "13"]

    def call(*extra: str) -> str:
        proc = subprocess.run(
            [sys.executable, "-m", "jointplay.cli", *args, *extra],
            capture_output=True,
            text=True,
            timeout=300,
            env=env,
        )
        assert proc.returncode == 0, proc.stderr
        return proc.stdout

    doc = json.loads(call("--json"))
    text = call()
    assert not _missing(_motion_numbers(doc), text), text
    assert "…" not in text
    rows = [line for line in text.splitlines() if "│" in line]
    assert len(rows) == len(doc["steps"])
    for row, step in zip(rows, doc["steps"], strict=True):
        touching = [name.split(".", 1) for name in step["touching"]]
        assert all(joint in row and contact in row for joint, contact in touching)


def test_a_narrow_terminal_keeps_the_motion_numbers_whole() -> None:
    """In an 80-column terminal the motion's wide table is printed row by
    row as a list: every line fits, every number whole."""
    import io

    from rich.console import Console

    from jointplay.present.textreport import render_motion

    result = Motion(steps=5).run(jointplay.load(GALLERY / "slider_crank.yaml"))
    buf = io.StringIO()
    render_motion(result, "slider_crank.yaml", Console(file=buf, width=80, markup=False))
    text = buf.getvalue()
    assert all(len(line) <= 80 for line in text.splitlines())
    assert not _missing(_motion_numbers(json.loads(json.dumps(result.to_dict()))), text)


# -- load tables over the drive's value -----------------------------------------------
@pytest.mark.parametrize(
    ("table", "words"),
    [
        ([["0 deg", -200]], "table: expected at least 2 rows"),
        ([["0 deg", -200], "oops"], "table row 1: expected [drive, value]"),
        ([["0 deg", -200], ["180 deg", -1500], ["90 deg", -200]], "increasing order"),
        ([["0 deg", -200], ["360 mm", -200]], "mix angles and lengths"),
        ([["0 deg", -200], ["360 deg", "2 mm"]], "table row 1: the value: expected a force"),
        ([["0 deg", -200], ["360 deg", "lots"]], "table row 1: the value"),
        ([["0 deg", -200], ["a while", -200]], "neither an angle"),
        ([["10 deg", -200], ["360 deg", -200]], "extend it to 0"),
        ([["0 mm", -200], ["360 mm", -200]], "give them in deg"),
        ([["0 deg", -200], ["180 deg", -200]], "extend the table over the motion's range"),
        ([[0, -200], ["3 rad", -200]], "extend the table over the motion's range"),
        ([[0, -200], [7, -200]], "row 1: the drive's value 7 has no unit"),  # 7 would be rad
        ([[0, -200], ["7", -200]], "row 1: the drive's value '7' has no unit"),
        # beside angles, a plain number is a unit left out, not rows out of order
        ([["0 deg", -200], ["345", -200], ["360 deg", -200]], "row 1: the drive's value '345' has"),
    ],
)
def test_bad_load_tables(table: list[Any], words: str) -> None:
    """Each names the file, the load and the component, and says the fix."""
    data = jointplay.load(GALLERY / "slider_crank.yaml").model_dump(
        by_alias=True, exclude_none=True
    )
    data["loads"][0]["force"] = [{"table": table}, 0, 0]
    with pytest.raises(ModelError) as err:
        model_from_dict(data, source="crank.yaml")
    assert err.value.exit_code == 2
    message = str(err.value)
    assert "crank.yaml" in message and "loads[0]" in message and "component x" in message
    assert words in message, message


def test_a_load_table_needs_a_motion(tmp_path: Path) -> None:
    """Without a motion a table has no drive to be read against: exit 2 with
    the fix, one line, from Python and from the command line."""
    data = yaml.safe_load((GALLERY / "slider_crank.yaml").read_text())
    del data["motion"]
    data["loads"][0]["force"] = [{"table": GAS}, 0, 0]
    with pytest.raises(ModelError, match="has no 'motion' section; add motion:"):
        model_from_dict(data, source="crank.yaml")
    path = tmp_path / "crank.yaml"
    path.write_text(yaml.safe_dump(data))
    proc = run("solve", str(path))
    assert proc.returncode == 2 and proc.stdout == "" and "Traceback" not in proc.stderr
    assert "loads[0]" in proc.stderr and "add motion:" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_a_motion_range_past_the_table_is_refused() -> None:
    """--range (Motion(range=...)) past a load's table: the same message."""
    model = jointplay.load(GALLERY / "slider_crank.yaml")
    with pytest.raises(ModelError, match="the motion runs from 0 deg to 720 deg; extend"):
        Motion(range=("0 deg", "720 deg")).run(model)


def test_a_plain_solve_reads_the_table_at_the_written_pose() -> None:
    """A plain solve of a model with a table takes its value at the drive's
    0: the same answer as that value written as a number; through the
    motion, the posed model at each step holds the table's value there."""
    model = jointplay.load(GALLERY / "slider_crank.yaml")
    table = model.loads[0].force[0]  # type: ignore[index]
    data = model.model_dump(by_alias=True, exclude_none=True)
    data["loads"][0]["force"] = [-1500.0, 0, 0]  # the table's first row, at 0 deg
    plain = model_from_dict(data)
    assert float(table) == -1500.0
    ours, theirs = jointplay.solve(model), jointplay.solve(plain)
    assert ours.potential_energy == pytest.approx(theirs.potential_energy, rel=1e-12)
    values = np.radians([0.0, 10.0, 225.0, 300.0, 360.0])
    poses = nominal_poses(model, values)
    expected = [-1500.0, -950.0, -150.0 - 250.0 * 45 / 90, -400.0 - 600.0 * 30 / 50, -1500.0]
    for s, force in enumerate(expected):
        posed = posed_model(model, poses, s)
        assert posed.motion is None
        assert posed.loads[0].force == pytest.approx((force, 0.0, 0.0), rel=1e-12)


def test_the_drive_is_shown_as_given_not_with_the_turn_s_round_off() -> None:
    """The range is given in degrees and solved in radians: 15 deg came back
    as 14.999999999999998 in --csv and --json. Shown, each step's drive is
    the range's own grid, in every output."""
    model = jointplay.load(GALLERY / "four_bar.yaml")
    result = Motion(steps=73).run(model)
    grid = [5.0 * k for k in range(73)]
    assert [result.shown_value(s) for s in range(73)] == grid
    assert [step["drive"] for step in result.to_dict()["steps"]] == grid
    table = result.to_dataframe()
    assert table[table.columns[1]].tolist() == grid


# -- the drive's values as given: a spin's need a unit; an option's errors name it -----
@pytest.mark.parametrize("span", [[0, 90], ["0", "90"], ["0 deg", 1.5]])
def test_a_spin_range_without_a_unit_is_refused_in_the_file(span: list[object]) -> None:
    """A plain number for a spin would be read as rad (90 rad: 14 turns);
    the file's motion.range entry is named with the fix."""
    data = jointplay.load(GALLERY / "four_bar.yaml").model_dump(by_alias=True, exclude_none=True)
    data["motion"]["range"] = span
    with pytest.raises(ModelError) as err:
        model_from_dict(data, source="bar.yaml")
    message = str(err.value)
    assert err.value.exit_code == 2
    assert "bar.yaml: motion: range[1]" in message and "has no unit" in message, message
    assert " deg'" in message and "radians" in message


def test_a_slide_range_reads_a_plain_number_as_mm() -> None:
    plain = _with_motion(GALLERY / "slider_crank.yaml", drive="guide", range=[0, -30])
    given = _with_motion(GALLERY / "slider_crank.yaml", drive="guide", range=["0 mm", "-30 mm"])
    assert plain.motion_drive()[1:] == given.motion_drive()[1:] == ("slide", 0.0, -30.0)


def test_a_spin_range_of_zero_and_radians_with_their_unit_read() -> None:
    model = _with_motion(GALLERY / "four_bar.yaml", range=[0, "1.5 rad"])
    assert model.motion_drive()[1:] == ("spin", 0.0, 1.5)


@pytest.mark.parametrize(
    ("model", "args", "words"),
    [
        ("four_bar", ["--range", "0:90"], ["--range STOP: '90' has no unit", "'0 deg:90 deg'"]),
        ("four_bar", ["--range", "0 mm:1 mm"], ["--range START: expected an angle"]),
        ("four_bar", ["--range", "0 deg"], ["--range 0 deg: expected START:STOP"]),
        ("four_bar", ["--drive", "nothing"], ["--drive nothing: unknown joint", "motor"]),
        ("four_bar", ["--drive", "moter"], ["--drive moter", "motion. Did you mean 'motor'?"]),
        ("slider_crank", ["--drive", "guide"], ["--drive guide:", "give --range"]),
        ("slider_crank", ["--drive", "guide", "--range", "0 deg:9 deg"], ["--range START:"]),
        ("../paper/6.1.6.1", ["--range", "0 deg:9 deg"], ["--range: the model has no", "--drive"]),
        ("../paper/6.1.6.1", ["--drive", "l1"], ["--drive l1: the model has no", "--range"]),
    ],
)
def test_bad_drive_and_range_options_name_the_option(
    model: str, args: list[str], words: list[str]
) -> None:
    """From the command line the message names the option and its fix, not
    the file's motion entry; exit 2, one line, and --json says it too."""
    path = str(GALLERY / f"{model}.yaml")
    proc = run("motion", path, *args, "--steps", "3")
    assert proc.returncode == 2 and proc.stdout == "" and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "invalid option" in proc.stderr and f"{path}: motion" not in proc.stderr
    assert all(w in proc.stderr for w in words), proc.stderr
    doc = json.loads(run("motion", path, *args, "--steps", "3", "--json").stdout)
    assert doc["status"] == "invalid" and words[0] in doc["message"]


@pytest.mark.parametrize("steps", [3, 37])
def test_an_unreachable_step_is_named_by_the_users_values(steps: int) -> None:
    """The rocker turned 360 deg in 180 deg (or 10 deg) steps: each step is
    solved in smaller parts, but the message names only the user's step and
    its value, and the step before: "between step N-1 (A) and step N (B)"."""
    import re

    model = _four_bar(1000.0, drive="pivot", turn="360 deg")
    with pytest.raises(MotionError) as err:
        Motion(steps=steps).run(model)
    message, n = str(err.value), err.value.step
    grid = np.linspace(0.0, 360.0, steps)
    assert err.value.kind == "unreachable" and n >= 1
    assert f"at step {n} (drive 'pivot' at {grid[n]:g} deg)" in message, message
    assert f"between step {n - 1} ({grid[n - 1]:g} deg) and step {n} ({grid[n]:g} deg)" in message
    shown = {float(v) for v in re.findall(r"(-?[\d.]+) deg", message)}
    # the steps' values, and where the reach ends (ReachError.end, 6 digits): no part's
    assert isinstance(err.value, ReachError)
    end = float(re.findall(r"reach ends at (-?[\d.]+) deg", message)[0])
    assert end == pytest.approx(np.degrees(err.value.end), abs=1e-4)
    assert shown <= {float(grid[n - 1]), float(grid[n]), end}, message
    assert err.value.value == pytest.approx(np.radians(grid[n]))


def test_the_text_counts_the_steps_a_requirement_fails_at() -> None:
    """The gallery's piston meets its limit at the file's pose and misses it
    over most of the turn: the sentence says at how many steps, as the
    result measures them."""
    path = GALLERY / "slider_crank.yaml"
    result = Motion().run(jointplay.load(path))
    failing = int(np.sum(result.measured[:, 0] > result.limits[0]))
    assert 0 < failing < result.steps
    assert result.measured[0, 0] <= result.limits[0]  # the file's pose passes
    proc = run("motion", str(path))
    assert proc.returncode == 0, proc.stderr
    assert f"FAILED at {failing} of {result.steps} steps" in proc.stdout


# -- the load case, the options' values and the outputs, as a new user meets them ------
SHAFT = GALLERY.parent / "studies" / "shaft_cases.yaml"
SPIN = ("--drive", "l2", "--range", "0 deg:10 deg", "--steps", "2")


@pytest.mark.parametrize("study", [[], ["--samples", "2"], ["--envelope"], ["--contributions"]])
def test_an_unknown_case_is_the_case_option_s_error(study: list[str]) -> None:
    """As a solve says it: exit 2, one line naming --case; never a KeyError."""
    for path, case, words in (
        (GALLERY / "four_bar.yaml", "foo", "--case: no load case 'foo'; the model has none"),
        (SHAFT, "cuting", "--case: no load case 'cuting'"),
    ):
        spin = SPIN if path == SHAFT else ("--steps", "2")
        proc = run("motion", str(path), *spin, "--case", case, *study)
        assert proc.returncode == 2 and proc.stdout == "" and "Traceback" not in proc.stderr
        assert "invalid option" in proc.stderr and words in proc.stderr, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1
    with pytest.raises(OptionError, match="no load case 'foo'"):
        Motion(case="foo").run(jointplay.load(GALLERY / "four_bar.yaml"))


def test_a_model_with_load_cases_needs_its_case() -> None:
    """Without --case the motion would be under no case the model has: refused,
    naming the cases; with it the header names the case, and the first pose
    is the solve of the model under that case."""
    proc = run("motion", str(SHAFT), *SPIN)
    assert proc.returncode == 2 and proc.stdout == ""
    assert "the model has load cases (cutting, lifting): give --case NAME" in proc.stderr
    proc = run("motion", str(SHAFT), *SPIN, "--case", "lifting")
    assert proc.returncode == 0, proc.stderr
    assert "load case 'lifting'" in proc.stdout.splitlines()[0]
    doc = json.loads(run("motion", str(SHAFT), *SPIN, "--case", "lifting", "--json").stdout)
    assert doc["case"] == "lifting"
    model = jointplay.load(SHAFT)
    result = Motion(drive="l2", range=("0 deg", "10 deg"), steps=2, case="lifting").run(model)
    from jointplay.solver.solve import Workspace

    lifted = Workspace.of(model).solve(loads=model.loads_of("lifting"))
    assert np.allclose(result.displacement[0, 0], lifted.points["tip"].displacement, atol=1e-9)
    with pytest.raises(OptionError, match="cutting, lifting"):
        Motion(drive="l2", range=("0 deg", "10 deg"), steps=2).run(model)


@pytest.mark.parametrize(
    ("model", "args", "words"),
    [
        ("four_bar", ["--steps", "1000000000"], ["--steps 1000000000: give at most 100,000"]),
        ("four_bar", ["--steps", "1"], ["--steps 1: give at least 2 steps"]),
        (
            "slider_crank",
            ["--range", "0 deg:400 deg", "--steps", "3"],
            ["--range '0 deg:400 deg': the model file's loads[0]", "a --range that fits it"],
        ),
        (
            "slider_crank",
            ["--drive", "guide", "--range", "0 mm:-50 mm", "--steps", "3"],
            ["--drive guide --range '0 mm:-50 mm': the model file's loads[0]", "give them in mm"],
        ),
    ],
)
def test_option_values_the_model_cannot_take_name_the_option(
    model: str, args: list[str], words: list[str]
) -> None:
    """An option's value that the model cannot take is the option's error,
    not the file's: 'invalid option', the option and the fix, exit 2."""
    proc = run("motion", str(GALLERY / f"{model}.yaml"), *args)
    assert proc.returncode == 2 and proc.stdout == "" and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "invalid option" in proc.stderr and "invalid model" not in proc.stderr
    assert all(w in proc.stderr for w in words), proc.stderr


def test_the_help_states_the_most_steps() -> None:
    from jointplay.settings import MOST_MOTION_STEPS

    assert f"2 to {MOST_MOTION_STEPS:,}" in run("motion", "--help").stdout


def test_csv_cells_separate_names_that_hold_spaces(tmp_path: Path) -> None:
    """Contact names hold spaces ('main bearing.end-', 'guide.z x- y-'): the
    CSV's touching and switched cells split on '; ' back into the names the
    JSON lists; the CLI says it wrote the file, as --plot does (but with
    --json, whose stderr stays quiet)."""
    import pandas as pd

    path = tmp_path / "crank.csv"
    proc = run("motion", str(GALLERY / "slider_crank.yaml"), "--steps", "5", "--csv", str(path))
    assert proc.returncode == 0 and proc.stderr.strip() == f"jointplay: wrote {path}"
    figure = tmp_path / "crank.svg"
    proc = run("motion", str(GALLERY / "four_bar.yaml"), "--steps", "3", "--plot", str(figure))
    assert proc.returncode == 0 and proc.stderr.strip() == f"jointplay: wrote {figure}"
    args = ("--steps", "3", "--csv", str(tmp_path / "bar.csv"), "--plot", str(figure), "--json")
    proc = run("motion", str(GALLERY / "four_bar.yaml"), *args)
    assert proc.returncode == 0 and proc.stderr == "" and json.loads(proc.stdout)
    frame = pd.read_csv(path, keep_default_na=False)
    result = Motion(steps=5).run(jointplay.load(GALLERY / "slider_crank.yaml"))
    for s, step in enumerate(result.to_dict()["steps"]):
        assert any(" " in name for name in step["touching"])
        assert frame["touching"][s].split("; ") == step["touching"]
        assert frame["switched"][s] == "; ".join(step["switched"])


def test_a_figure_name_without_a_suffix_is_told_the_suffixes() -> None:
    proc = run("motion", str(GALLERY / "four_bar.yaml"), "--plot", "/tmp/figure")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert "--plot /tmp/figure: the name has no suffix" in proc.stderr
    assert ".png, .svg or .pdf" in proc.stderr


def test_the_report_drives_the_motion_under_one_case_and_names_it() -> None:
    """A report solves every case; its motion is under the first, said so."""
    from jointplay.present.report import Report

    data = yaml.safe_load((GALLERY / "four_bar.yaml").read_text())
    data["motion"]["steps"] = 3
    data["load_cases"] = {"light": [], "heavy": []}
    page = Report(studies=False).render(model_from_dict(data), "bar.yaml")
    assert "in 3 poses under load case &#x27;light&#x27; (the first;" in page
