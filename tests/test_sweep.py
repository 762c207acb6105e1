"""Sweeps: entries of the model over a range, loads turning; closed forms,
independent solves, the table, the CLI, a local Dask cluster."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import jointplay
from conftest import BALANCE, MM, RAD, ROOT, spherical_shaft
from jointplay.cli import app
from jointplay.errors import OptionError
from jointplay.studies.sweep import RotateLoad, Sweep, Vary, parse_path

UNBALANCE = ROOT / "examples" / "studies" / "rotating_unbalance.yaml"


def shaft(**over: Any) -> dict[str, Any]:
    data = spherical_shaft(**over)
    data.setdefault("points", [{"name": "B", "body": "S1", "at": [300, 0, 0]}])
    return data


def lever(j1: float, j2: float) -> float:
    """|d_B| of the shaft under a radial load at B (x = 300 mm): the ball goes
    J1/2 against the load, the bore end at 220 mm J2/2 with it."""
    return -j1 / 2 + (j1 / 2 + j2 / 2) * 300 / 220


def test_a_turning_radial_load_keeps_the_lever_rule_and_its_direction() -> None:
    model = jointplay.load(UNBALANCE)
    result = Sweep(rotate=RotateLoad(0, (1, 0, 0), 24)).run(model)
    assert result.steps == 24
    angles = np.radians(result.values[:, 0])
    assert np.allclose(result.values[:, 0], 15.0 * np.arange(24))
    d = result.point("B")
    direction = np.column_stack([np.zeros(24), np.cos(angles), np.sin(angles)])
    assert np.max(np.abs(d - lever(0.2, 0.2) * direction)) < MM
    # the ball and the bore end on the load's side touch at every angle
    contacts = {name: k for k, name in enumerate(result.contact_names)}
    assert result.in_contact[:, contacts["l1", "ball"]].all()
    assert result.in_contact[:, contacts["l2", "end+"]].all()
    assert not result.in_contact[:, contacts["l2", "end-"]].any()
    # the forces balance 10 N levered: the bore takes 10 * 300 / 220, the largest
    # force in the balance, to which the certificate balances them
    newtons = BALANCE * 10 * 300 / 220
    assert np.allclose(result.force[:, contacts["l2", "end+"]], 10 * 300 / 220, atol=newtons)
    assert np.allclose(result.force[:, contacts["l1", "ball"]], 10 * 80 / 220, atol=newtons)
    assert result.equilibrium_residual < 1e-8
    assert result.feasibility_mm < 1e-9


def test_each_step_equals_an_independent_solve() -> None:
    data = shaft(loads=[{"body": "S1", "at": [300, 0, 0], "force": [2, 1, 1]}])
    model = jointplay.model_from_dict(data)
    result = Sweep(rotate=RotateLoad(0, (0.3, 0.2, 1.0), 10, 0.0, 270.0)).run(model)
    axis = np.array([0.3, 0.2, 1.0]) / np.linalg.norm([0.3, 0.2, 1.0])
    for s, angle in enumerate(np.radians(result.values[:, 0])):
        f = np.array([2.0, 1, 1])
        turned = (
            f * math.cos(angle)
            + np.cross(axis, f) * math.sin(angle)
            + axis * (axis @ f) * (1 - math.cos(angle))
        )
        alone = jointplay.solve(
            jointplay.model_from_dict(
                {**data, "loads": [{"body": "S1", "at": [300, 0, 0], "force": turned.tolist()}]}
            )
        )
        alone.check()
        for j, name in enumerate(result.joint_names):
            assert np.max(np.abs(result.translation[s, j] - alone.joints[name].translation)) < MM
            assert np.max(np.abs(result.rotation[s, j] - alone.joints[name].rotation)) < RAD
        assert np.max(np.abs(result.point("B")[s] - alone.points["B"].displacement)) < MM


def test_varying_a_clearance_follows_the_closed_form() -> None:
    model = jointplay.model_from_dict(
        shaft(loads=[{"body": "S1", "at": [300, 0, 0], "force": [0, 5, 0]}])
    )
    result = Sweep(vary=(Vary.range("joints[l2].clearance", 0.05, 0.45, 9),)).run(model)
    j2 = np.linspace(0.05, 0.45, 9)
    assert np.allclose(result.values[:, 0], j2)
    assert np.max(np.abs(result.point("B")[:, 1] - lever(0.2, j2))) < MM
    assert np.max(np.abs(result.point("B")[:, [0, 2]])) < MM


def test_a_grid_takes_every_combination_last_parameter_fastest() -> None:
    model = jointplay.model_from_dict(
        shaft(loads=[{"body": "S1", "at": [300, 0, 0], "force": [0, 5, 0]}])
    )
    sweep = Sweep(
        vary=(
            Vary("joints[l1].clearance", (0.1, 0.3)),
            Vary.parse("joints.l2.clearance=0.1,0.2,0.4"),
        )
    )
    result = sweep.run(model)
    assert result.values.tolist() == [
        [0.1, 0.1], [0.1, 0.2], [0.1, 0.4], [0.3, 0.1], [0.3, 0.2], [0.3, 0.4]
    ]  # fmt: skip
    expected = [lever(j1, j2) for j1, j2 in result.values]
    assert np.max(np.abs(result.point("B")[:, 1] - expected)) < MM


def test_values_with_units_are_converted_like_the_model_file() -> None:
    model = jointplay.load(UNBALANCE)
    newtons = Sweep(vary=(Vary.parse("loads[0].force[2]=0:10 N:3"),)).run(model)
    kilo = Sweep(vary=(Vary.parse("loads[0].force[2]=0:0.01 kN:3"),)).run(model)
    assert newtons.labels == ("loads[0].force[2] (N)",)
    assert np.allclose(newtons.values[:, 0], [0, 5, 10])
    np.testing.assert_allclose(newtons.points, kilo.points, rtol=0, atol=MM)
    mm = Sweep(vary=(Vary.parse("joints[l2].clearance=100 um:300 um:3"),)).run(model)
    assert np.max(np.abs(mm.point("B")[:, 1] - lever(0.2, np.array([0.1, 0.2, 0.3])))) < MM


def test_paths_are_read_with_indices_and_names() -> None:
    assert parse_path("loads[0].force[1]") == ["loads", 0, "force", 1]
    assert parse_path("joints[l2].clearance") == ["joints", "l2", "clearance"]
    assert parse_path("joints.l2.at[0]") == ["joints", "l2", "at", 0]
    assert parse_path("load_cases.up[1].torque[2]") == ["load_cases", "up", 1, "torque", 2]


@pytest.mark.parametrize(
    ("vary", "words"),
    [
        ("lods[0].force[1]=0:1:2", "has no 'lods'"),
        ("loads[3].force[1]=0:1:2", "index 3 is out of range"),
        ("joints[l9].clearance=0:1:2", "no entry named 'l9'; names are: l1, l2"),
        ("joints[l2].at=0:1:2", "is not a number"),
        ("loads[0].force[1].x=0:1:2", "is a number, not a section"),
        ("joints[l2].clearance=0:1", "START:STOP:COUNT"),
        ("joints[l2].clearance=0:1:many", "COUNT 'many'"),
        ("joints[l2].clearance", "PATH=START:STOP:COUNT"),
        ("joints[l2].clearance=0 mm:1 um:3", "one unit"),
    ],
)
def test_bad_paths_get_one_message_and_exit_2(vary: str, words: str) -> None:
    out = CliRunner().invoke(app, ["sweep", str(UNBALANCE), "--vary", vary])
    assert out.exit_code == 2, out.output
    assert words in out.output
    assert "Traceback" not in out.output


def test_a_step_that_breaks_the_model_is_named() -> None:
    out = CliRunner().invoke(
        app, ["sweep", str(UNBALANCE), "--vary", "joints[l2].clearance=0.2:-0.2:3"]
    )
    assert out.exit_code == 2
    assert "rotating_unbalance.yaml" in out.output
    assert "at the step joints[l2].clearance = -0.2" in out.output


@pytest.mark.parametrize(
    ("vary", "step"),
    [
        ("joints[l2].clearance=0.1:0.3 kg:5", "joints[l2].clearance = 0.1 kg"),  # every value
        ("joints[l2].clearance=0.1,0.3 kg", "joints[l2].clearance = 0.3 kg"),  # the last
    ],
)
def test_a_value_in_the_wrong_unit_is_the_option_s_error(vary: str, step: str) -> None:
    """The model is valid; the values --vary writes into it are not: the
    option is named, with its value, the entry it does not fit and the fix,
    before any step is solved (exit 2)."""
    out = CliRunner().invoke(app, ["sweep", str(UNBALANCE), "--vary", vary])
    assert out.exit_code == 2, out.output
    assert "invalid option" in out.output and "invalid model" not in out.output
    assert f"--vary: at the step {step}: joints[1] 'l2': clearance: expected a length" in out.output
    assert "which is a mass" in out.output and "rotating_unbalance.yaml" in out.output
    assert "change the values given to --vary (a unit goes after the number" in out.output


def test_values_that_do_not_fit_together_are_the_option_s_error() -> None:
    """The first and the last step are valid models, but the grid's middle
    step writes a joint axis of zeros: that step is named as the option's
    (exit 2) when it is solved."""
    data = shaft()
    joints: Any = data["joints"]
    joints[0]["axis"] = [1, 1, 0]
    model = jointplay.model_from_dict(data)
    sweep = Sweep(
        vary=(Vary.parse("joints[l1].axis[0]=1,0,1"), Vary.parse("joints[l1].axis[1]=1,0,1"))
    )
    with pytest.raises(
        OptionError, match=r"--vary: at the step joints\[l1\]\.axis\[0\] = 0\.0, "
    ) as err:
        sweep.run(model)
    assert err.value.exit_code == 2 and "nonzero direction" in str(err.value)


def heavy_push() -> dict[str, Any]:
    """The shaft pushed by 0.9e9 N along y and z: each component within the
    1e9 N a force component may be, their sum turned onto one axis not."""
    return shaft(loads=[{"body": "S1", "at": [300, 0, 0], "force": [0, 9e8, 9e8]}])


def test_a_turn_that_breaks_the_model_is_the_turn_s_error(tmp_path: Path) -> None:
    """Turned 315 deg about x, the push is 1.27e9 N along y: the step is
    named as --rotate-load's, with a fix for the turn, not --vary's."""
    path = tmp_path / "heavy.json"
    path.write_text(json.dumps(heavy_push()))
    args = ["sweep", str(path), "--rotate-load", "0", "--about", "x", "--steps", "8"]
    out = CliRunner().invoke(app, args)
    assert out.exit_code == 2, out.output
    words = " ".join(out.output.split())
    assert "--rotate-load: at the step loads[0] turned 315 deg: loads[0]: force" in words
    assert "change the turn given to --rotate-load (--about, --from, --to)" in words
    assert "--vary" not in words


@pytest.mark.parametrize(
    ("vary", "option", "fix"),
    [
        ("joints[l2].clearance=0.1:0.3:3", "--rotate-load", "change the turn given to"),
        ("joints[l2].clearance=0.1:0.3 kg:3", "--vary", "change the values given to --vary"),
    ],
)
def test_with_both_options_the_one_whose_values_break_the_step_is_named(
    vary: str, option: str, fix: str
) -> None:
    """Valid --vary values with a turn that breaks the model: the turn's
    error; --vary values in the wrong unit: --vary's, turned or not."""
    sweep = Sweep(vary=(Vary.parse(vary),), rotate=RotateLoad(0, (1, 0, 0), 8))
    with pytest.raises(OptionError) as err:
        sweep.run(jointplay.model_from_dict(heavy_push()))
    assert err.value.entry == option and fix in str(err.value)


def test_a_step_the_joints_do_not_hold_exits_3_and_names_the_step(tmp_path: Path) -> None:
    data = shaft(loads=[{"body": "S1", "torque": [0, 1000, 0]}])
    path = tmp_path / "spin.json"
    path.write_text(json.dumps(data))
    out = CliRunner().invoke(
        app, ["sweep", str(path), "--rotate-load", "0", "--about", "z", "--steps", "4"]
    )
    assert out.exit_code == 3, out.output
    assert "turned 90 deg" in out.output
    assert "S1" in out.output


def test_rotate_load_checks_its_inputs() -> None:
    out = CliRunner().invoke(app, ["sweep", str(UNBALANCE), "--rotate-load", "4"])
    assert out.exit_code == 2
    assert "1 load in 'loads'" in out.output
    out = CliRunner().invoke(app, ["sweep", str(UNBALANCE), "--rotate-load", "0", "--about", "w"])
    assert out.exit_code == 2
    assert "--about 'w'" in out.output
    out = CliRunner().invoke(app, ["sweep", str(UNBALANCE)])
    assert out.exit_code == 2
    assert "nothing to sweep" in out.output


def test_cli_table_json_and_csv(tmp_path: Path) -> None:
    csv = tmp_path / "turn.csv"
    args = ["sweep", str(UNBALANCE), "--rotate-load", "0", "--about", "x", "--steps", "8"]
    out = CliRunner().invoke(app, [*args, "--csv", str(csv)])
    assert out.exit_code == 0, out.output
    assert "sweep of 8 steps" in out.output
    assert "point B: largest displacement 0.172727 mm" in out.output
    import pandas as pd

    table = pd.read_csv(csv)
    assert len(table) == 8
    assert np.allclose(table["B.size"], lever(0.2, 0.2), atol=MM)
    assert {"l1.tx", "l2.rz", "l2.end+.in_contact", "l2.end+.force"} <= set(table.columns)
    out = CliRunner().invoke(app, [*args, "--json"])
    assert out.exit_code == 0
    doc = json.loads(out.output)
    assert doc["study"] == "sweep" and len(doc["steps"]) == 8
    step = doc["steps"][2]
    assert step["values"] == {"loads[0] angle (deg)": 90.0}
    assert step["points"]["B"] == pytest.approx([0, 0, lever(0.2, 0.2)], abs=MM)
    assert [c["name"] for c in step["joints"]["l2"]["contacts"]] == ["end-", "end+"]


def test_processes_and_a_local_dask_cluster_give_the_same_table() -> None:
    import distributed  # the test extra installs it

    model = jointplay.load(UNBALANCE)
    sweep = Sweep(
        vary=(Vary.range("joints[l2].clearance", 0.1, 0.3, 3),),
        rotate=RotateLoad(0, (1, 0, 0), 12),
        chunk=5,
    )
    local = sweep.run(model)
    pooled = sweep.run(model, workers=2)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        remote = sweep.run(model, scheduler=cluster.scheduler_address)
    for other in (pooled, remote):
        assert np.array_equal(local.values, other.values)  # the inputs, exactly
        # the answers to the promise, not to the bit (other processes may round otherwise)
        np.testing.assert_allclose(local.points, other.points, rtol=0, atol=MM)
        np.testing.assert_allclose(local.translation, other.translation, rtol=0, atol=MM)
        assert np.array_equal(local.in_contact, other.in_contact)
    assert local.to_dataframe().shape == (36, len(local.to_dataframe().columns))


def test_a_long_sweep_s_table_shows_each_point_s_largest_step() -> None:
    """Past SWEEP_ROWS steps the table shows one step in k, and always each
    point's largest, which the line under it names."""
    import re

    from test_cli import run

    proc = run(
        "sweep",
        str(ROOT / "examples" / "studies" / "rotating_unbalance.yaml"),
        "--vary",
        "joints[l2].clearance=0.1:0.3:5",
        "--vary",
        "loads[0].force[0]=-5:5 N:11",
    )
    assert proc.returncode == 0, proc.stderr
    said = re.search(r"largest displacement \S+ mm at step (\d+)", proc.stdout)
    assert said is not None
    rows = {int(line.split()[0]) for line in proc.stdout.splitlines() if re.match(r"\s+\d+ ", line)}
    assert int(said.group(1)) in rows and len(rows) < 55
    assert "(one step in 2 of 55 shown, and each point's largest" in proc.stdout
