"""Legal but likely slips get a warning (issue 19): a play large against its
joint (meant in um, written as mm) and a model with no loads at all."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
import yaml

import jointplay
from conftest import spherical_shaft
from test_cli import run

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    ("joint", "expected"),
    [
        (1, "joint 'l2': clearance 200 mm is 5 times its size (40 mm)"),  # a bore of length 40
        (0, "joint 'l1': clearance 200 mm is 1 times the diagonal of the box around the joints"),
    ],
)
def test_a_play_large_against_its_joint_warns_it_may_be_in_um(
    joint: int, expected: str, tmp_path: Path
) -> None:
    data = spherical_shaft()
    data["joints"][joint]["clearance"] = 200  # type: ignore[index]
    model = jointplay.model_from_dict(data)
    assert len(model.warnings) == 1
    assert model.warnings[0].startswith(expected) and "write '200 um'" in model.warnings[0]
    path = tmp_path / "model.yaml"
    path.write_text(yaml.safe_dump(data))
    proc = run("solve", str(path), "--json")
    assert proc.returncode == 0, proc.stderr  # it solves: a warning, not an error
    assert json.loads(proc.stdout)["warnings"][0] == model.warnings[0]
    text = " ".join(run("solve", str(path)).stdout.split())  # the report wraps long lines
    assert f"warning: {expected}" in text


def test_the_papers_plays_do_not_warn() -> None:
    for path in sorted((ROOT / "examples").rglob("*.yaml")):
        assert jointplay.load(path).warnings == (), path.name


def test_a_model_with_no_loads_says_so(tmp_path: Path) -> None:
    data = spherical_shaft(loads=[])
    model = jointplay.model_from_dict(data)
    assert model.warnings == (
        "the model has no loads (no 'loads', no load cases, no weight): nothing pushes the "
        "parts, so every displacement and force is 0",
    )
    path = tmp_path / "model.yaml"
    path.write_text(yaml.safe_dump(data))
    out = run("solve", str(path)).stdout
    assert "warning: the model has no loads" in out
    assert "potential energy of the loads: 0 N*mm" in out  # not "-0"
    energy = json.loads(run("solve", str(path), "--json").stdout)["potential_energy"]
    assert energy == 0.0 and math.copysign(1.0, energy) == 1.0  # not -0.0 in the JSON either


def test_a_weight_or_a_load_case_is_a_load() -> None:
    weighed = spherical_shaft(
        loads=[],
        bodies=[
            {"name": "S0", "ground": True},
            {"name": "S1", "mass": 1, "center_of_mass": [1, 0, 0]},
        ],
        gravity=[0, 0, "-9.81 m/s^2"],
    )
    assert jointplay.model_from_dict(weighed).warnings == ()
    cased = spherical_shaft(loads=[], load_cases={"a": [{"body": "S1", "torque": [0, 1, 0]}]})
    assert jointplay.model_from_dict(cased).warnings == ()


def test_warnings_follow_a_copied_model() -> None:
    model = jointplay.model_from_dict(spherical_shaft())
    assert model.warnings == ()
    assert len(model.model_copy(update={"loads": ()}).warnings) == 1  # not cached


def test_a_turn_a_drives_backlash_allows_is_not_blamed_on_coincident_joints() -> None:
    """A crank turning within a large backlash (0.5 written without a unit:
    rad) turns far beyond small displacements: the warning says the plays let
    it, a backlash among them, not that joints sit too close to be apart."""
    data = yaml.safe_load((ROOT / "examples" / "gallery" / "four_bar.yaml").read_text())
    motor = next(j for j in data["joints"] if j["name"] == "motor")
    motor["backlash"] = 0.5
    result = jointplay.solve(jointplay.model_from_dict(data))
    turn = next(w for w in result.warnings if w.startswith("body 'crank' turns by"))
    assert "backlash" in turn and "move them apart" not in turn
