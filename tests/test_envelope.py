"""Worst-case envelope: exact support values, closed forms, Monte Carlo inside."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import jointplay
from conftest import MM
from jointplay.cli import app
from jointplay.studies.envelope import Envelope, sphere_directions
from jointplay.studies.montecarlo import MonteCarlo
from test_montecarlo import SHAFT


def test_ball_joint_envelope_is_the_ball_of_its_play() -> None:
    data = {
        "bodies": [{"name": "g", "ground": True}, {"name": "b"}],
        "joints": [
            {
                "name": "ball",
                "type": "spherical",
                "between": ["g", "b"],
                "at": [5, 6, 7],
                "clearance": 0.4,
            },
        ],
        "points": [{"name": "c", "body": "b", "at": [5, 6, 7]}],
    }
    env = Envelope("c", directions=50).run(jointplay.model_from_dict(data))
    assert np.max(np.abs(env.h - 0.2)) < MM
    assert np.max(np.abs(env.hull - 0.2 * env.directions)) < MM
    assert env.largest == pytest.approx(0.2, abs=MM)
    assert np.max(np.abs(env.extent - np.array([[-0.2, 0.2]] * 3))) < MM


def test_shaft_extent_matches_the_lever_rule() -> None:
    # plays at their upper limits (0.3 mm): the point at 300 mm reaches, across
    # the axis, the ball's 0.15 mm one way plus the bore end's (at 220 mm)
    # 0.15 mm the other, levered: 0.15 * (300 + 80) / 220
    model = jointplay.model_from_dict(SHAFT)
    env = Envelope("B", directions=100).run(model)
    across = 0.15 * 380 / 220
    assert env.extent[1] == pytest.approx([-across, across], abs=MM)
    assert env.extent[2] == pytest.approx([-across, across], abs=MM)
    assert env.extent[0] == pytest.approx([-0.15, 0.15], abs=MM)
    # identities of the study's arithmetic, not of a solve (so to round-off):
    # the largest is the farthest of the hull points and of the climb from them
    sizes = np.linalg.norm(env.hull, axis=1)
    assert env.largest >= sizes.max() - 1e-12  # the climb only goes up
    # support values are the hull points' projections (the same dot products)
    assert np.allclose(env.h, np.einsum("ij,ij->i", env.directions, env.hull), atol=1e-12)
    mean = Envelope("B", directions=100, plays="mean").run(model)
    assert mean.extent[1][1] == pytest.approx(0.1 * 380 / 220, abs=MM)


def test_no_monte_carlo_sample_leaves_the_envelope() -> None:
    model = jointplay.model_from_dict(SHAFT)
    env = Envelope("B", directions=300).run(model)
    mc = MonteCarlo(samples=5000, seed=8).run(model)
    inside = env.contains(mc.displacement[:, 0], tol=MM)  # two solves of each: to MM
    assert inside.all()
    assert np.linalg.norm(mc.displacement[:, 0], axis=1).max() <= env.largest + MM


def test_fibonacci_directions_are_unit_and_spread() -> None:
    u = sphere_directions(500)
    assert np.allclose(np.linalg.norm(u, axis=1), 1.0)
    assert np.linalg.norm(u.mean(axis=0)) < 0.01


def test_cli_envelope(tmp_path: Path) -> None:
    runner = CliRunner()
    out = runner.invoke(
        app,
        [
            "envelope",
            "examples/studies/shaft_fits.yaml",
            "--point",
            "B",
            "--json",
            "--csv",
            str(tmp_path / "e.csv"),
        ],
    )
    assert out.exit_code == 0, out.output
    doc: dict[str, Any] = json.loads(out.output)
    assert doc["point"] == "B" and doc["plays"] == "max"
    assert doc["largest_displacement"] > 0
    assert len(doc["hull"]) == 206
    assert (tmp_path / "e.csv").read_text().splitlines()[0] == "ux,uy,uz,support,dx,dy,dz"
    bad = runner.invoke(app, ["envelope", "examples/studies/shaft_fits.yaml", "--point", "Q"])
    assert bad.exit_code == 2 and "unknown point 'Q'" in bad.output
    bad = runner.invoke(
        app, ["envelope", "examples/studies/shaft_fits.yaml", "--point", "B", "--plays", "min"]
    )
    assert bad.exit_code == 2 and "'max' or 'mean'" in bad.output


# -- envelopes on real mechanisms: one-sided supports, free motions, the model's loads

ROOT = Path(__file__).resolve().parents[1]


def door(gravity: bool) -> jointplay.Model:
    """A door on two hinges about global Z, 1,600 mm apart; its handle 800 mm out."""
    data: dict[str, Any] = {
        "bodies": [{"name": "frame", "ground": True}, {"name": "door"}],
        "joints": [
            {
                "name": "upper",
                "type": "revolute",
                "between": ["frame", "door"],
                "at": [0, 0, 1800],
                "axis": [0, 0, 1],
                "length": 40,
                "clearance": 0.1,
                "axial_clearance": 0.5,
            },
            {
                "name": "lower",
                "type": "cylindrical",
                "between": ["frame", "door"],
                "at": [0, 0, 200],
                "axis": [0, 0, 1],
                "length": 40,
                "clearance": 0.1,
            },
        ],
        "points": [{"name": "handle", "body": "door", "at": [800, 0, 1000]}],
    }
    if gravity:
        data["bodies"][1].update({"mass": "20 kg", "center_of_mass": [400, 0, 1000]})
        data["gravity"] = [0, 0, "-9.81 m/s^2"]
    return jointplay.model_from_dict(data)


def test_a_door_is_bounded_in_the_directions_its_hinges_hold() -> None:
    env = Envelope("handle", directions=60).run(door(gravity=False))
    # a force at the handle with a part along Y turns the door: not held, and said so
    # (the held directions are the complement of the driven one in an SVD of a
    # 1 x 3 matrix, not a solve: to its round-off)
    np.testing.assert_allclose(env.directions[:, 1], 0.0, atol=1e-12)
    [words] = env.not_held
    assert "rotation about the global Z axis" in words and "door" in words
    # in the held plane XZ: the hinges' play J/2 across, and along Z the upper hinge's
    # axial play Ja/2 plus the tilt (J / (1,600 + 40) mm, both bores' ends) at 800 mm
    tilt = 0.1 / 1640
    assert env.largest == pytest.approx(0.25 + 800 * tilt, abs=MM)
    np.testing.assert_allclose(env.extent[0], [-0.05, 0.05], atol=MM)
    np.testing.assert_allclose(env.extent[1], [0.0, 0.0], atol=MM)
    np.testing.assert_allclose(env.extent[2], [-0.25 - 800 * tilt, 0.25 + 800 * tilt], atol=MM)


def test_a_heavy_door_rests_where_its_weight_puts_it() -> None:
    heavy = door(gravity=True)
    env = Envelope("handle", directions=60).run(heavy)
    assert "rotation about the global Z axis" in env.not_held[0]
    assert "against the standing loads" in env.over
    # a 1 N probe does not lift 20 kg: every support point is the resting position
    rest = jointplay.solve(heavy).points["handle"].displacement
    np.testing.assert_allclose(env.hull, np.tile(rest, (len(env.hull), 1)), atol=MM)
    # and it lies in the envelope of the door without weight
    assert np.all(Envelope("handle", directions=60).run(door(gravity=False)).contains(env.hull))


def test_the_located_plate_envelope_is_the_lever_rule_of_its_two_pins() -> None:
    model = jointplay.load(ROOT / "examples" / "gallery" / "located_plate.yaml")
    env = Envelope("drilled hole", directions=100).run(model)
    assert env.not_held == ()  # the weight keeps the plate on its buttons
    # at (100, 50): the hole pin at (40, 60) plays R = J1/2 in any direction, the slot pin
    # at (170, 60) c = J2/2 across (Y); a turn w moves the point by (10 w, 60 w), the slot
    # pin by 130 w across; so the greatest X is max of sqrt(R^2 - e^2) + 10 (c + e) / 130
    R = model.joint("hole pin").clearance.high / 2
    c = model.joint("slot pin").clearance.high / 2
    k = 10 / 130
    assert env.extent[0, 1] == pytest.approx(R * np.hypot(1, k) + k * c, abs=MM)
    np.testing.assert_allclose(env.extent[2], [0.0, 0.0], atol=MM)  # on its buttons
    # without its weight the plate lifts off its buttons under some probes: left out
    weightless = model.model_copy(update={"gravity": None})
    light = Envelope("drilled hole", directions=100).run(weightless)
    assert len(light.not_held) == 1 and "lift a part off its supports" in light.not_held[0]
    assert len(light.directions) < 106


def ball_at_origin(*loads: dict[str, Any]) -> jointplay.Model:
    """A body on a ball joint of play J = 0.4 at the origin, its point 'c' there."""
    return jointplay.model_from_dict(
        {
            "bodies": [{"name": "g", "ground": True}, {"name": "b"}],
            "joints": [
                {
                    "name": "ball",
                    "type": "spherical",
                    "between": ["g", "b"],
                    "at": [0, 0, 0],
                    "clearance": 0.4,
                }
            ],
            "loads": list(loads),
            "points": [{"name": "c", "body": "b", "at": [0, 0, 0]}],
        }
    )


def test_an_envelope_over_load_ranges_takes_every_corner() -> None:
    model = ball_at_origin({"body": "b", "at": [0, 0, 0], "force": [{"min": -5, "max": 5}, 3, 0]})
    env = Envelope("c", directions=50, levels=2).run(model)
    assert "2 load sets" in env.over
    corner = 0.2 * np.array([5.0, 3.0, 0.0]) / np.hypot(5, 3)
    np.testing.assert_allclose(env.extent[0], [-corner[0], corner[0]], atol=MM)
    np.testing.assert_allclose(env.extent[1], [corner[1], corner[1]], atol=MM)
    # the default third level adds the mean load, straight along Y: the ball's full J/2
    finer = Envelope("c", directions=50).run(model)
    assert "3 load sets" in finer.over
    assert finer.extent[1, 1] == pytest.approx(0.2, abs=MM)
    # asked for probes instead: the ball of the play
    probes = Envelope("c", directions=50, loads="probes").run(model)
    assert probes.largest == pytest.approx(0.2, abs=MM)


def test_an_envelope_over_load_cases_holds_each_case() -> None:
    path = ROOT / "examples" / "studies" / "wobbly_table.yaml"
    model = jointplay.load(path)
    env = Envelope("probe", directions=40).run(model)
    assert "over 3 load cases" in env.over
    for case, result in jointplay.solve_cases(model).items():
        d = result.points["probe"].displacement
        assert np.any(np.all(np.abs(env.hull - d) < MM, axis=1)), case
        assert np.all(env.contains(d[None, :]))


def test_no_direction_held_is_exit_3(tmp_path: Path) -> None:
    data = {
        "bodies": [{"name": "g", "ground": True}, {"name": "b"}],
        "joints": [
            {
                "name": "ring",
                "type": "sphere_in_cylinder",
                "between": ["g", "b"],
                "at": [0, 0, 0],
                "clearance": 0.1,
            }
        ],
        "points": [{"name": "p", "body": "b", "at": [10, 10, 0]}],
    }
    path = tmp_path / "ring.yaml"
    path.write_text(json.dumps(data))
    out = CliRunner().invoke(app, ["envelope", str(path), "--point", "p"])
    assert out.exit_code == 3, out.output
    assert "no force at point 'p' is held" in out.output


def test_a_load_set_the_mechanism_does_not_hold_is_left_out_and_listed(tmp_path: Path) -> None:
    model = jointplay.load(ROOT / "examples" / "gallery" / "located_plate.yaml")
    drill = model.loads[0].model_dump()
    drill["force"] = [-30.0, 15.0, {"min": -80, "max": 50}]  # at +50 N it lifts the plate
    lifting = model.replace(loads=[drill])
    env = Envelope("drilled hole", directions=40, plays="mean").run(lifting)
    [words] = env.not_held
    assert "1 of 3 load sets of the loads (e.g. loads[0].force[2] = 50)" in words
    assert "translation along the global +Z axis" in words
    held = [
        jointplay.solve(lifting.replace(loads=[{**drill, "force": [-30, 15, f]}]))
        for f in (-80, -15)
    ]
    for r in held:  # the load sets held are in it (two solves: to MM)
        d = r.points["drilled hole"].displacement
        assert np.any(np.all(np.abs(env.hull - d) < MM, axis=1))


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--probe", "inf"], "--probe inf: expected a force of 1e-06 to 1e+09 N"),
        (["--probe", "0"], "--probe 0: expected a force of 1e-06 to 1e+09 N"),
        (["--probe", "1.0000001e9"], "--probe 1000000100: expected"),
        (["--loads", "some"], "expected 'auto', 'model' or 'probes'"),
        (["--loads", "model"], "--loads model: the model has no loads"),
    ],
)
def test_bad_envelope_options_exit_2(tmp_path: Path, args: list[str], words: str) -> None:
    path = tmp_path / "door.yaml"
    path.write_text(json.dumps(door(gravity=False).model_dump(mode="json", exclude_none=True)))
    out = CliRunner().invoke(app, ["envelope", str(path), "--point", "handle", *args])
    assert out.exit_code == 2, out.output
    assert words in out.output


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_probes_that_drive_no_free_motion_are_all_kept() -> None:
    # the lathe slide's probes drive nothing free: all 206 directions, none listed.
    # Some rows diverge from far starts in the batch; their overflow stays
    # inside it (it printed nine RuntimeWarnings through the API before)
    # (judged against the probe itself, as a solve judges a load: not against
    # the round-off of the probes' part on the free motions)
    model = jointplay.load(ROOT / "examples" / "gallery" / "lathe_slide.yaml")
    env = Envelope("tip", directions=200).run(model)
    assert len(env.directions) == 206 and env.not_held == ()


def test_a_case_without_loads_is_its_rest_position_and_many_loads_take_two_levels() -> None:
    model = jointplay.load(ROOT / "examples" / "studies" / "wobbly_table.yaml")
    env = Envelope("probe", directions=40).run(model)  # its case 'resting' has no own loads
    assert "3 load sets over 3 load cases" in env.over
    many = ball_at_origin(
        *({"body": "b", "at": [0, 0, 0], "force": [{"min": -1, "max": 1}, 1, 0]} for _ in range(11))
    )  # 3^11 is over the cap: 2^11 sets
    wide = Envelope("c", directions=20).run(many)
    assert "2,048 load sets, both limits" in wide.over
    with pytest.raises(jointplay.OptionError, match="3\\^11 load combinations"):
        Envelope("c", directions=20, levels=3).run(many)


def test_probes_push_against_a_standing_preload() -> None:
    # a ball joint (J/2 = 0.2) whose centre a spring presses with 10 N along -Y:
    # a 1 N probe along u leaves the centre at 0.2 (u - 10 Y) / |u - 10 Y|
    def ball(standing: bool) -> jointplay.Model:
        return ball_at_origin(
            {"body": "b", "at": [0, 0, 0], "force": [0, -10, 0], "standing": standing}
        )

    env = Envelope("c", directions=60).run(ball(standing=True))
    assert "against the standing loads" in env.over
    total = env.directions - np.array([0.0, 10.0, 0.0])
    expected = 0.2 * total / np.linalg.norm(total, axis=1)[:, None]
    np.testing.assert_allclose(env.hull, expected, atol=MM)
    assert env.extent[1, 1] < 0  # a 1 N probe never lifts the centre off the preloaded side
    # the same load, not standing: the probes alone, the ball of the play
    free = Envelope("c", directions=60).run(ball(standing=False))
    assert free.largest == pytest.approx(0.2, abs=MM)
    np.testing.assert_allclose(free.extent, [[-0.2, 0.2]] * 3, atol=MM)


# -- a mechanism its joints do not hold: every study says so, as solve does


def arm(tmp_path: Path, *loads: dict[str, Any], cases: dict[str, Any] | None = None) -> Path:
    """An arm held by one ball joint (J = 0.2 mm, or 0.2 to 0.4 mm part to part)
    at the origin, its functional point 'tip' at its far end, 300 mm along X:
    it swings freely about the ball, held only along X."""
    data: dict[str, Any] = {
        "name": "arm on one ball",
        "bodies": [{"name": "S0", "ground": True}, {"name": "arm"}],
        "joints": [
            {
                "name": "ball",
                "type": "spherical",
                "between": ["S0", "arm"],
                "at": [0, 0, 0],
                "clearance": {"min": 0.2, "max": 0.4},
            }
        ],
        "points": [{"name": "tip", "body": "arm", "at": [300, 0, 0]}],
        "requirements": [{"point": "tip", "max_displacement": "0.3 mm"}],
        "loads": list(loads),
    }
    if cases is not None:
        data["load_cases"] = cases
    path = tmp_path / "arm.json"
    path.write_text(json.dumps(data))
    return path


SIDE_LOAD = {"body": "arm", "at": [300, 0, 0], "force": [0, 10, 0]}


@pytest.mark.parametrize(
    "study",
    [
        ["envelope", "--point", "tip"],  # probes: the side load is no probe, and was left out
        ["envelope", "--point", "tip", "--loads", "model"],
        ["montecarlo", "--samples", "50"],
        ["montecarlo", "--samples", "50", "--chunk", "25", "--workers", "2"],  # from a worker
        ["contributions"],
        ["tolerances", "--samples", "50"],
    ],
)
def test_a_study_of_an_arm_its_ball_does_not_hold_exits_3_as_solve(
    tmp_path: Path, study: list[str]
) -> None:
    # a side load at the end of an arm on one ball turns it about Z: solve exits 3.
    # The envelope printed extents (0 across) and exited 0; a Monte Carlo from
    # worker processes died unpickling the verdict (exit 1)
    path = arm(tmp_path, SIDE_LOAD)
    runner = CliRunner()
    solved = runner.invoke(app, ["solve", str(path)])
    assert solved.exit_code == 3
    assert "body 'arm': rotation about the global Z axis is not held by any joint" in (
        solved.output
    )
    assert "most by loads[0] on 'arm'" in solved.output
    out = runner.invoke(app, [study[0], str(path), *study[1:]])
    assert out.exit_code == 3, out.output
    assert out.stdout == ""  # no number
    assert out.stderr == solved.stderr  # the same verdict, word for word
    as_json = runner.invoke(app, [study[0], str(path), *study[1:], "--json"])
    assert as_json.exit_code == 3
    doc = json.loads(as_json.stdout)
    assert doc["status"] == "unbounded" and doc["body"] == "arm"
    assert doc["motion"] == "rotation about the global Z axis"


def test_an_envelope_under_a_load_case_the_joints_do_not_hold_exits_3_naming_it(
    tmp_path: Path,
) -> None:
    # one case pulls along the arm (held), the other across it (not held): solve
    # prints the first and exits 3 naming the second; the envelope over both cases
    # listed the second and gave the first's numbers with exit 0
    along = {"body": "arm", "at": [300, 0, 0], "force": [10, 0, 0]}
    path = arm(tmp_path, cases={"pulled": [along], "pushed aside": [SIDE_LOAD]})
    runner = CliRunner()
    solved = runner.invoke(app, ["solve", str(path), "--case", "pushed aside"])
    assert solved.exit_code == 3
    verdict = "jointplay: not held: under load case 'pushed aside': body 'arm': rotation"
    assert solved.output.startswith(verdict)
    out = runner.invoke(app, ["envelope", str(path), "--point", "tip"])
    assert out.exit_code == 3, out.output
    assert out.stdout == "" and out.stderr == solved.stderr
    # the case the ball holds has its envelope: the tip pulled out by J/2 at most
    held = runner.invoke(app, ["envelope", str(path), "--point", "tip", "--case", "pulled"])
    assert held.exit_code == 0, held.output
    assert "largest displacement: 0.2 mm along [1, 0, 0]" in held.output


def test_a_free_motion_no_load_drives_keeps_the_envelope_and_each_probe_names_its_axis(
    tmp_path: Path,
) -> None:
    # the arm pulled along itself: its swing is free but nothing drives it, so a
    # solve answers (the swing at 0 by convention) and so does the envelope, over
    # the probes that drive no swing: along X only
    along = {"body": "arm", "at": [300, 0, 0], "force": [10, 0, 0]}
    path = arm(tmp_path, along)
    runner = CliRunner()
    assert runner.invoke(app, ["solve", str(path)]).exit_code == 0
    env = Envelope("tip", directions=20, loads="probes").run(jointplay.load(path))
    np.testing.assert_allclose(env.extent, [[-0.2, 0.2], [0.0, 0.0], [0.0, 0.0]], atol=MM)
    # a probe across the arm along Y turns it about Z, one along Z about Y: the note
    # named the Z axis for both
    [words] = env.not_held
    assert "along [0, 1, 0] drives body 'arm': rotation about the global Z axis" in words
    assert "along [0, 0, 1] drives body 'arm': rotation about the global Y axis" in words


def test_a_probe_across_an_arm_off_the_origin_names_the_axis_it_turns_about() -> None:
    # the ball at (100, 50, 0), the point at (400, 150, 0): a probe along Z turns
    # the arm about the horizontal axis across the lever (300, 100, 0), through the
    # ball; one in the plane, across the lever, about the Z axis through the ball
    model = ball_at_origin().model_copy(deep=True)
    data = model.model_dump(mode="json", exclude_none=True)
    data["joints"][0]["at"] = [100, 50, 0]
    data["points"][0]["at"] = [400, 150, 0]
    env = Envelope("c", directions=20).run(jointplay.model_from_dict(data))
    [words] = env.not_held
    assert (
        "along [0, 0, 1] drives body 'b': rotation about an axis along [0.3162, -0.9487, 0]"
        in words
    )
    assert "along [-0.316, 0.949, 0] drives body 'b': rotation about an axis parallel to " in (
        words
    )
    assert "global Z through (100, 50, 0) mm" in words
    # the probes held: along the lever, where the ball's J/2 = 0.2 mm is the reach
    assert env.largest == pytest.approx(0.2, abs=MM)


def test_a_worst_case_over_deviation_zones_is_refused_where_the_loads_swing_the_arm(
    tmp_path: Path,
) -> None:
    # over zones, the worst case along a direction is the support of every
    # position the zones allow, whatever the loads: it took no verdict on them
    from jointplay.studies.parts import Measure
    from jointplay.studies.worstcase import worst_cases

    data = json.loads(arm(tmp_path, SIDE_LOAD).read_text())
    data["joints"][0]["deviation"] = {"position": "0.02 mm"}
    model = jointplay.model_from_dict(data)
    with pytest.raises(jointplay.UnboundedMechanismError, match="most by loads\\[0\\] on 'arm'"):
        worst_cases(model, [Measure("tip", (0.0, 1.0, 0.0))], None, source="arm.json")


#: A ram in a guide, on a one-sided point stop below it, pushed up: the load
#: lifts it off the stop, which nothing else holds along the guide.
RAM_LIFTED = {
    "name": "press",
    "bodies": [{"name": "frame", "ground": True}, {"name": "ram"}],
    "joints": [
        {"name": "guide", "type": "prismatic", "between": ["frame", "ram"], "at": [0, 0, 0],
         "axis": [0, 0, 1], "length": 200, "width": 80, "height": 80,
         "clearance_y": {"min": "10 um", "max": "30 um"},
         "clearance_z": {"min": "10 um", "max": "30 um"}},
        {"name": "stop", "type": "point", "between": ["frame", "ram"], "at": [0, 0, -100],
         "axis": [0, 0, 1]},
    ],
    "loads": [{"body": "ram", "at": [0, 0, -150], "force": [0, 0, "1000 N"]}],
    "points": [{"name": "die", "body": "ram", "at": [0, 0, -150]}],
    "requirements": [{"point": "die", "max_displacement": "20 um", "along": [1, 0, 0]}],
}  # fmt: skip


@pytest.mark.parametrize(
    "study",
    [
        ["envelope", "--point", "die"],
        ["envelope", "--point", "die", "--loads", "model"],
        ["montecarlo", "--samples", "50"],
        ["contributions"],
        ["tolerances", "--samples", "50"],
    ],
)
def test_a_study_of_a_ram_its_loads_lift_off_its_stop_exits_3_as_solve(
    tmp_path: Path, study: list[str]
) -> None:
    # no free motion of the joints' rows: a one-sided contact the loads lift a
    # part off, found by the cone program; the probe envelope printed a Z extent
    # of 0 to 0 and exited 0, and --loads model named no body
    path = tmp_path / "press.json"
    path.write_text(json.dumps(RAM_LIFTED))
    runner = CliRunner()
    solved = runner.invoke(app, ["solve", str(path)])
    assert solved.exit_code == 3
    assert "body 'ram': translation along the global +Z axis is not held" in solved.output
    out = runner.invoke(app, [study[0], str(path), *study[1:]])
    assert out.exit_code == 3, out.output
    assert out.stdout == "" and out.stderr == solved.stderr
