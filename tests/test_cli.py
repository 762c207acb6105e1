"""The command line: report, JSON schema, exit codes."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

import jointplay
from conftest import MM, PAPER, RAD, ROOT


def run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "jointplay.cli", *args], capture_output=True, text=True, timeout=120
    )


def test_solve_prints_the_paper_like_report() -> None:
    proc = run("solve", str(PAPER / "6.1.6.1.yaml"))
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert "status: optimal" in out
    assert "certificate: holds" in out
    assert "joint l2 (cylindrical) at (200, 0, 0) mm: S1 relative to S0" in out
    assert "8.89297292e-02" in out  # u1, as the paper prints 8.892973e-2
    assert "end+: TOUCHING" in out and "end-: free (73.50% of play)" in out
    assert "body 'S1': rotation about the global X axis" in out


def test_solve_json_has_exactly_the_documented_schema() -> None:
    proc = run("solve", str(PAPER / "6.1.6.1.yaml"), "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    # the core schema, plus the force additions (reaction, force, point, residual, points)
    # and the exact-rotation check (linearization error and its warnings)
    assert set(doc) == {
        "status",
        "potential_energy",
        "bodies",
        "joints",
        "points",
        "equilibrium_residual",
        "linearization_error",
        "warnings",
        "accuracy",
        "requirements",
        "indeterminate",
        "free_motions",
    }
    assert doc["indeterminate"] == {"degree": 0, "joints": [], "contacts": [], "by_rule": True}
    # the shaft's spin: no joint holds it and no load drives it (the text's line, reported as 0)
    assert doc["free_motions"] == ["body 'S1': rotation about the global X axis"]
    assert doc["bodies"]["S1"]["rotation"][0] == 0.0
    assert 0.0 <= doc["linearization_error"] < 1e-4 and doc["warnings"] == []
    assert doc["accuracy"]["certified"]
    assert doc["accuracy"]["feasibility_mm"] <= 1e-9
    assert doc["equilibrium_residual"] < 1e-8
    assert doc["points"] == {} and doc["requirements"] == []
    assert doc["status"] == "optimal"
    assert set(doc["bodies"]) == {"S0", "S1"}
    for body in doc["bodies"].values():
        assert set(body) == {"translation", "rotation"}
    assert set(doc["joints"]) == {"l1", "l2"}
    l2 = doc["joints"]["l2"]
    assert set(l2) == {"axes", "translation", "rotation", "contacts", "reaction"}
    assert set(l2["reaction"]) == {"force", "moment"}
    assert l2["axes"] == {"x": [1.0, 0.0, 0.0], "y": [0.0, 1.0, 0.0], "z": [0.0, 0.0, 1.0]}
    keys = {"name", "gap_used", "in_contact", "force", "point", "penetration", "torque", "unit"}
    assert [set(c) for c in l2["contacts"]] == [keys] * 2
    assert l2["contacts"][0]["force"] == [0.0, 0.0, 0.0]  # free: no force
    assert l2["contacts"][1]["point"] == [220.0, 0.0, 0.0]
    assert [c["in_contact"] for c in l2["contacts"]] == [False, True]
    assert all(0.0 <= c["gap_used"] <= 1.0 for c in l2["contacts"])
    assert l2["translation"][1] == pytest.approx(6.134259e-2, abs=MM)
    assert l2["rotation"][2] == pytest.approx(4.684034e-4, abs=RAD)
    # the JSON is Result.to_dict(), the Python API's answer
    api = jointplay.solve(jointplay.load(PAPER / "6.1.6.1.yaml")).to_dict()
    assert api == doc


def test_unbounded_exits_3_naming_body_and_motion(tmp_path: Path) -> None:
    path = tmp_path / "free.yaml"
    path.write_text(
        """
bodies:
  - {name: housing, ground: true}
  - {name: shaft}
joints:
  - {name: l1, type: spherical, between: [housing, shaft], at: [0, 0, 0], clearance: 0.2}
  - {name: l2, type: cylindrical, between: [housing, shaft], at: [200, 0, 0],
     length: 40, clearance: 0.2}
loads:
  - {body: shaft, torque: ["1 N*m", 0, 0]}
"""
    )
    proc = run("solve", str(path))
    assert proc.returncode == 3
    assert proc.stdout == ""
    assert (
        "body 'shaft': rotation about the global X axis is not held by any joint, and the "
        "loads drive it"
    ) in proc.stderr
    assert "Traceback" not in proc.stderr
    proc = run("solve", str(path), "--json")
    assert proc.returncode == 3
    doc = json.loads(proc.stdout)
    assert doc["status"] == "unbounded"
    assert doc["body"] == "shaft"
    assert doc["motion"] == "rotation about the global X axis"


def test_version_and_help() -> None:
    assert run("--version").stdout.strip() == f"jointplay {jointplay.__version__}"
    assert "solve" in run("--help").stdout


def test_python_dash_m_runs_the_command_line() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "jointplay", "solve", str(PAPER / "6.1.6.1.yaml"), "--json"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0 and proc.stderr == ""
    assert json.loads(proc.stdout) == json.loads(
        run("solve", str(PAPER / "6.1.6.1.yaml"), "--json").stdout
    )


def test_every_bundled_example_solves() -> None:
    for path in sorted((PAPER.parent).rglob("*.yaml")):
        proc = run("solve", str(path), "--json")
        assert proc.returncode == 0, (path, proc.stderr)
        assert json.loads(proc.stdout)["status"] == "optimal"


def test_load_cases_each_reported_and_one_by_name() -> None:
    path = ROOT / "examples" / "studies" / "shaft_cases.yaml"
    proc = run("solve", str(path), "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["status"] == "optimal" and list(doc["cases"]) == ["cutting", "lifting"]
    model = jointplay.load(path)
    for name, case in doc["cases"].items():
        assert case == jointplay.solve(model, case=name).to_dict()
        assert case["equilibrium_residual"] < 1e-8
        assert set(case["points"]) == {"tip"}
    proc = run("solve", str(path), "--case", "lifting")
    assert proc.returncode == 0, proc.stderr
    assert "load case 'lifting'" in proc.stdout and "cutting" not in proc.stdout
    assert "tip" in proc.stdout and "reaction" in proc.stdout


def test_unknown_case_exits_2_with_a_suggestion() -> None:
    path = ROOT / "examples" / "studies" / "shaft_cases.yaml"
    proc = run("solve", str(path), "--case", "lifitng")
    assert proc.returncode == 2
    assert "shaft_cases.yaml" in proc.stderr and "Did you mean 'lifting'?" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_a_tied_chain_prints_json_and_nothing_else(tmp_path: Path) -> None:
    """50 shafts whose axial positions tie: the least-norm point is found on a
    singular KKT system, which no library may print about (SuperLU, given one
    exactly singular, fails inside BLAS, and OpenBLAS prints on stdout)."""
    import yaml

    from jointplay.io.generate import bearing_chain_dict

    model = tmp_path / "chain.yaml"
    model.write_text(yaml.safe_dump(bearing_chain_dict(50)), encoding="utf-8")
    proc = run("solve", str(model), "--json")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    doc = json.loads(proc.stdout)
    assert doc["status"] == "optimal" and doc["accuracy"]["certified"]
    assert len(doc["bodies"]) == 51


STUDIES = {
    "montecarlo": (["-n", "50"], "jointplay.studies.montecarlo.MonteCarlo.run"),
    "envelope": (["--point", "B"], "jointplay.studies.envelope.Envelope.run"),
    "sweep": (["--vary", "joints[l2].clearance=0.01:0.03:3"], "jointplay.studies.sweep.Sweep.run"),
    "contributions": ([], "jointplay.studies.contributions.Contributions.run"),
}


@pytest.mark.parametrize("study", sorted(STUDIES))
@pytest.mark.parametrize("option", ["--csv", "--plot"])
def test_an_output_in_a_missing_folder_exits_2_before_any_solving(
    study: str, option: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from typer.testing import CliRunner

    from jointplay.cli import app

    args, run_method = STUDIES[study]

    def no_work(*_: object, **__: object) -> None:
        raise AssertionError("the study ran before its output path was checked")

    monkeypatch.setattr(run_method, no_work)
    missing = tmp_path / "no such folder" / ("out.csv" if option == "--csv" else "out.png")
    fits = ROOT / "examples" / "studies" / "shaft_fits.yaml"
    out = CliRunner().invoke(app, [study, str(fits), *args, option, str(missing)])
    assert out.exit_code == 2, out.output
    assert f"invalid option: {option} {missing}: the folder '{missing.parent}' does not exist" in (
        " ".join(out.output.split())
    )


@pytest.mark.parametrize("command", ["sweep", "report"])
def test_the_help_examples_run_when_copied(command: str, tmp_path: Path) -> None:
    """Help texts are plain text: Rich markup once ate 'joints[l2]' into 'joints'."""
    import re

    from jointplay.studies.sweep import Sweep, Vary

    proc = run(command, "--help")
    assert proc.returncode == 0, proc.stderr
    text = " ".join(proc.stdout.split())  # the help wraps its lines
    examples = re.findall(r"'(\w+\[\w+\][\w.\[\]]*=[\d.:]+)'", text)
    assert examples == ["loads[0].force[1]=0:10:11", "joints[l2].clearance=0.1:0.3:5"]
    path = ROOT / "examples" / "studies" / "rotating_unbalance.yaml"
    model = jointplay.load(path)
    for example in examples:
        table = Sweep(vary=(Vary.parse(example),)).run(model)
        assert len(table.to_dataframe()) == int(example.rsplit(":", 1)[1])
    # and as typed on the command line
    proc = run("sweep", str(path), "--vary", examples[1], "--json")
    assert proc.returncode == 0, proc.stderr
    assert len(json.loads(proc.stdout)["steps"]) == 5


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("solve", str(PAPER / "6.1.6.1.yaml"), "--bogus"), "No such option: --bogus"),
        (("montecarlo", str(PAPER / "6.1.6.1.yaml"), "-n", "0"), "'--samples' / '-n'"),
        (("solve",), "Missing argument 'MODEL'"),
        (
            ("solve", str(ROOT / "examples" / "studies" / "shaft_cases.yaml"), "--case", "x"),
            "--case",
        ),
        (("envelope", str(PAPER / "6.1.6.1.yaml"), "--point", "tip"), "--point: unknown point"),
    ],
    ids=["unknown", "out-of-range", "missing", "unknown-case", "unknown-point"],
)
def test_an_option_error_says_invalid_option(args: tuple[str, ...], message: str) -> None:
    """What is wrong on the command line is labelled as such (not "invalid
    model", not Click's usage block): one line on stderr, exit 2."""
    proc = run(*args)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith("jointplay: invalid option: ") and message in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr


def test_no_command_prints_the_help() -> None:
    proc = run()
    assert proc.returncode == 0 and "Commands" in proc.stdout and proc.stderr == ""


NUMBER = re.compile(r"-?\d[\d,]*(?:\.\d+)?(?:e[+-]?\d+)?%?")


def _printed(text: str) -> list[float]:
    """Every number in ``text`` as it reads there ('2,000' as 2000, '5.00%' as 0.05)."""
    out = []
    for token in NUMBER.findall(text):
        scale = 0.01 if token.endswith("%") else 1.0
        out.append(float(token.rstrip("%").replace(",", "")) * scale)
    return out


def _missing(wanted: list[float], text: str) -> list[float]:
    """The numbers of ``wanted`` that ``text`` does not print whole, to the
    digits it prints (6 significant at least)."""
    shown = np.array(_printed(text))
    return [
        v
        for v in wanted
        if not np.any(np.isclose(shown, v, rtol=1e-5, atol=1e-12 * max(1, abs(v))))
    ]


def _json_numbers(command: str, doc: dict[str, Any]) -> list[float]:
    """The numbers of a --json document that the text report prints."""
    if command == "solve":
        wanted = [v for p in doc["points"].values() for v in p["displacement"]]
        for j in doc["joints"].values():
            wanted += [*j["translation"], *j["rotation"]]
        return wanted
    if command == "sweep":
        return [
            float(np.linalg.norm(d)) for step in doc["steps"] for d in step["points"].values()
        ] + [v for step in doc["steps"] for v in step["values"].values()]
    sizes = [p["size"] for p in doc["points"].values()]  # montecarlo
    return [s[k] for s in sizes for k in ("mean", "std", "max")] + [
        s["percentiles"][k] for s in sizes for k in ("0.135", "50", "99.865")
    ]


PIPED_RUNS = [
    ("solve", str(ROOT / "examples" / "gallery" / "located_plate.yaml")),
    ("solve", str(ROOT / "examples" / "studies" / "carriage.yaml")),
    (
        "sweep",
        str(ROOT / "examples" / "studies" / "rotating_unbalance.yaml"),
        "--rotate-load",
        "0",
        "--about",
        "x",
        "--steps",
        "12",
    ),
    ("montecarlo", str(ROOT / "examples" / "studies" / "shaft_fits.yaml"), "-n", "500"),
]


@pytest.mark.parametrize("columns", ["60", "200"])
@pytest.mark.parametrize("args", PIPED_RUNS, ids=lambda a: f"{a[0]}-{Path(a[1]).stem}")
def test_piped_text_prints_every_json_number_whole(args: tuple[str, ...], columns: str) -> None:
    """Piped (a CI log, a file), the text is not wrapped at any width: every
    number that --json gives is in the text whole (a |u| of 0.0102892 once
    read '1.028920e-0' on one line and '2' on the next at 80 columns)."""
    import os

    env = {**os.environ, "COLUMNS": columns}

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

    wanted = _json_numbers(args[0], json.loads(call("--json")))
    assert wanted
    text = call()
    assert not _missing(wanted, text), text
    assert "…" not in text


@pytest.mark.parametrize("width", [50, 60, 80])
def test_a_narrow_terminal_keeps_every_number_and_name_whole(width: int) -> None:
    """In a terminal narrower than a table, a table closes up its padding,
    then prints each row as a list: every line fits, and every number and
    every name is whole on one line."""
    import io

    from rich.console import Console

    from jointplay.present.textreport import render, render_contributions
    from jointplay.studies.contributions import Contributions

    plate = jointplay.load(ROOT / "examples" / "gallery" / "located_plate.yaml")
    result = jointplay.solve(plate)
    buf = io.StringIO()
    console = Console(file=buf, width=width, highlight=False, markup=False)
    render(plate, result, "located_plate.yaml", console)
    text = buf.getvalue()
    assert all(len(line) <= width for line in text.splitlines())
    wanted = _json_numbers("solve", json.loads(json.dumps(result.to_dict())))
    assert not _missing(wanted, text)
    lines = text.splitlines()
    for name in ("drilled hole", "slot pin", "hole pin"):
        assert any(name in line for line in lines)

    deviations = jointplay.load(ROOT / "examples" / "studies" / "shaft_deviations.yaml")
    study = Contributions().run(deviations)
    buf = io.StringIO()
    render_contributions(study, "shaft_deviations.yaml", Console(file=buf, width=width))
    text = buf.getvalue()
    assert all(len(line) <= width for line in text.splitlines())
    assert f"RSS sigma {study.rss_sigma[0]:.6g} mm" in " ".join(text.split())
    for share in (*study.rss[0], *study.worst_case[0]):
        assert f"{share:5.1f} %".strip() in text


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (("montecarlo", "examples/gallery/lathe_slide.yaml"), "varies from part to part"),
        (("contributions", "examples/paper/6.1.6.1.yaml"), "varies from part to part"),
        (("tolerances", "examples/paper/6.1.6.1.yaml"), "add 'requirements:"),
        (("envelope", "examples/paper/6.1.6.1.yaml"), "add 'points:"),
    ],
    ids=["montecarlo", "contributions", "tolerances", "envelope"],
)
def test_a_valid_model_with_nothing_to_study_is_not_called_invalid(
    args: tuple[str, ...], words: str
) -> None:
    """A valid model in which the study has nothing to work on is told so,
    with what to add: one line, exit 2, and not "invalid model"."""
    proc = run(args[0], str(ROOT / args[1]))
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith("jointplay: nothing to study: "), proc.stderr
    assert words in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


def test_envelope_without_a_point_bounds_the_only_one_or_lists_them(tmp_path: Path) -> None:
    """Without --point, a model with one point has nothing to choose: it is
    bounded (as with --point tip); with two, the message names the file and
    lists them (exit 2)."""
    path = ROOT / "examples" / "studies" / "shaft_cases.yaml"
    alone = run("envelope", str(path), "--case", "cutting", "--json")
    named = run("envelope", str(path), "--case", "cutting", "--point", "tip", "--json")
    assert alone.returncode == 0, alone.stderr
    assert json.loads(alone.stdout) == json.loads(named.stdout)
    data = yaml.safe_load(path.read_text())
    data["points"].append({"name": "mid", "body": "S1", "at": [150, 0, 0]})
    two = tmp_path / "two_points.yaml"
    two.write_text(yaml.safe_dump(data))
    proc = run("envelope", str(two))
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith(f"jointplay: invalid option: {two}: --point: "), proc.stderr
    assert "'tip'" in proc.stderr and "'mid'" in proc.stderr


# -- load cases a mechanism does not hold, sweeps of another case, usage errors in --json ---
def _table_with_cases(path: Path) -> Path:
    """A plate on four feet: pressed down in case 'pressed', lifted off them
    in case 'lifted' (not held: nothing stops it going up)."""
    from conftest import table_on_feet

    data = table_on_feet([10.0, 20.0, 0.0])
    data["loads"] = []
    data["load_cases"] = {
        "pressed": [{"body": "plate", "at": [10, 20, 0], "force": [0, 0, -100]}],
        "lifted": [{"body": "plate", "at": [0, 0, 0], "force": [0, 0, 50]}],
    }
    path.write_text(json.dumps(data), encoding="utf-8")
    return path


def test_a_load_case_not_held_is_named_and_the_held_ones_are_printed(tmp_path: Path) -> None:
    """Exit 3 names the case whose loads the joints do not hold; the cases
    they hold are printed still (text and --json, whose document parses)."""
    path = _table_with_cases(tmp_path / "table.json")
    proc = run("solve", str(path))
    assert proc.returncode == 3, proc.stderr
    assert "jointplay: not held: under load case 'lifted': body 'plate'" in proc.stderr
    assert "load case 'pressed'" in proc.stdout and "load case 'lifted'" not in proc.stdout
    proc = run("solve", str(path), "--json")
    assert proc.returncode == 3
    doc = json.loads(proc.stdout)
    assert doc["status"] == "unbounded" and doc["case"] == "lifted" and doc["body"] == "plate"
    assert doc["cases"]["pressed"]["status"] == "optimal"
    lifted = doc["cases"]["lifted"]
    assert lifted["status"] == "unbounded" and lifted["body"] == "plate"
    assert lifted["message"].startswith("under load case 'lifted': ")
    proc = run("solve", str(path), "--case", "pressed")
    assert proc.returncode == 0, proc.stderr


def test_a_sweep_of_another_case_s_load_is_refused(tmp_path: Path) -> None:
    """Varying a load of case 'lifted' while solving 'pressed' would print
    the same step again and again: refused, naming the case to give."""
    path = _table_with_cases(tmp_path / "table.json")
    vary = "load_cases.lifted[0].force[2]=10:30:3"
    proc = run("sweep", str(path), "--case", "pressed", "--vary", vary)
    assert proc.returncode == 2 and proc.stdout == ""
    assert "acts in load case 'lifted' only, and the sweep is under 'pressed'" in proc.stderr
    assert "give --case lifted" in proc.stderr
    vary = "load_cases.pressed[0].force[2]=-50:-150:3"
    proc = run("sweep", str(path), "--case", "pressed", "--vary", vary, "--json")
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize(
    "args", [["solve", "--bogus"], ["montecarlo", "-n", "abc"], ["sweep", "--steps", "x"]]
)
def test_json_output_parses_even_on_a_usage_error(args: list[str]) -> None:
    proc = run(args[0], str(PAPER / "6.1.6.1.yaml"), *args[1:], "--json")
    assert proc.returncode == 2
    doc = json.loads(proc.stdout)
    assert doc["status"] == "invalid" and doc["kind"] == "invalid option"
    assert proc.stderr.startswith("jointplay: invalid option: ")


def test_a_report_names_the_load_case_not_held(tmp_path: Path) -> None:
    path = _table_with_cases(tmp_path / "table.json")
    proc = run("report", str(path), "-o", str(tmp_path / "r.html"), "--no-studies")
    assert proc.returncode == 3
    assert proc.stderr.startswith("jointplay: not held: under load case 'lifted': body 'plate'")
    proc = run("report", str(path), "-o", str(tmp_path / "r.html"), "--case", "pressed")
    assert proc.returncode == 0, proc.stderr
    # progress shows on a terminal only: a pipe gets the one line of what was written
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith(f"jointplay: wrote {tmp_path / 'r.html'} (")


GALLERY = ROOT / "examples" / "gallery"


@pytest.mark.parametrize("as_json", [False, True], ids=["text", "json"])
def test_motion_fail_on_requirements_exits_4_where_a_step_fails(as_json: bool) -> None:
    """The slider-crank's 0.05 mm limit on its piston holds at the pose
    written (0 deg) and fails over most of the turn: exit 4 after printing
    everything, as solve does; the four-bar's limit holds at every step: 0."""
    extra = ["--json"] if as_json else []
    proc = run("motion", str(GALLERY / "slider_crank.yaml"), "--fail-on-requirements", *extra)
    assert proc.returncode == 4, proc.stderr
    assert proc.stderr == ""  # a verdict, not an error
    if as_json:
        doc = json.loads(proc.stdout)
        passed = [step["requirements"][0]["passed"] for step in doc["steps"]]
        assert passed[0] and not all(passed)
        assert doc["requirements"][0]["passed"] is False
    else:
        assert "requirement on piston top: FAILED at" in proc.stdout
    holds = run("motion", str(GALLERY / "four_bar.yaml"), "--fail-on-requirements", *extra)
    assert holds.returncode == 0, holds.stderr
    if as_json:
        assert json.loads(holds.stdout)["requirements"][0]["passed"] is True
    # without the option a failed requirement is reported, not an exit code
    assert run("motion", str(GALLERY / "slider_crank.yaml"), *extra).returncode == 0


def test_motion_fail_on_requirements_is_decided_by_the_nominal_motion(tmp_path: Path) -> None:
    """With --samples the nominal motion decides: the slider-crank's limit set
    just above its nominal worst step passes (exit 0) though Monte Carlo parts
    with wider plays miss it; just below, it fails (exit 4)."""
    nominal = json.loads(run("motion", str(GALLERY / "slider_crank.yaml"), "--json").stdout)
    worst = nominal["requirements"][0]["measured"]
    data = yaml.safe_load((GALLERY / "slider_crank.yaml").read_text())
    codes = {}
    for factor in (1.005, 0.995):
        data["requirements"][0]["max_displacement"] = worst * factor
        path = tmp_path / f"slider_crank_{factor}.json"
        path.write_text(json.dumps(data))
        args = ["--samples", "40", "--workers", "1", "--json", "--fail-on-requirements"]
        proc = run("motion", str(path), *args)
        doc = json.loads(proc.stdout)
        assert doc["requirements"][0]["passed"] is (factor > 1)
        assert doc["monte_carlo"]["requirements"][0]["outside"] > 0
        codes[factor] = proc.returncode
    assert codes == {1.005: 0, 0.995: 4}


def test_montecarlo_json_parses_strictly_where_no_part_fails() -> None:
    """JSON has no Infinity: an estimate's relative error with no failing
    part is written null, and every parser reads the output."""
    from typer.testing import CliRunner

    from jointplay.cli import app

    out = CliRunner().invoke(
        app, ["montecarlo", "examples/gallery/four_bar.yaml", "-n", "200", "--json"]
    )
    assert out.exit_code == 0, out.output

    def refuse(constant: str) -> None:
        raise AssertionError(f"not JSON: {constant}")

    doc = json.loads(out.stdout, parse_constant=refuse)
    assert doc["relative_error"] == [None]


@pytest.mark.parametrize("command", ["solve", "tolerances", "montecarlo"])
def test_a_study_of_the_written_pose_says_the_motion_checks_every_pose(command: str) -> None:
    """The slider-crank's requirement passes at the pose written (0 deg) and
    fails over most of its turn: a study of that one pose says so, and how to
    check every pose, on stderr (its report and its --json stay as they are)."""
    extra = ["-n", "200"] if command != "solve" else []
    proc = run(command, str(GALLERY / "slider_crank.yaml"), *extra)
    assert proc.returncode == 0, proc.stderr
    note = " ".join(proc.stderr.split())
    assert "checked at the pose written in" in note
    assert f"`jointplay motion {GALLERY / 'slider_crank.yaml'}`" in note
    assert "73 steps" in note
    as_json = run(command, str(GALLERY / "slider_crank.yaml"), *extra, "--json")
    assert as_json.returncode == 0 and as_json.stderr == ""
    json.loads(as_json.stdout)
    plain = run(command, str(ROOT / "examples" / "studies" / "shaft_fits.yaml"), *extra)
    assert "jointplay motion" not in plain.stderr  # no motion: nothing to say


def test_the_motion_command_suggested_for_a_path_with_a_space_runs_as_printed(
    tmp_path: Path,
) -> None:
    """The suggested command quotes the path as a shell needs it: pasted, it
    names the model file, not two words of it."""
    import shlex

    path = tmp_path / "my models" / "slider crank.yaml"
    path.parent.mkdir()
    path.write_text((GALLERY / "slider_crank.yaml").read_text())
    proc = run("solve", str(path))
    assert proc.returncode == 0, proc.stderr
    command = proc.stderr.split("`")[1]
    assert command == f"jointplay motion '{path}'"
    assert shlex.split(command) == ["jointplay", "motion", str(path)]


def test_a_sweep_step_its_joints_do_not_hold_names_its_load_as_solve_does(
    tmp_path: Path,
) -> None:
    # an arm on one ball, pushed aside at its end by a load the sweep raises from 0:
    # from the second step it swings about the ball. The steps share the first
    # step's workspace, whose model had the load at 0, and the verdict called the
    # load "the weight of 'arm'" (the arm has no mass)
    data = {
        "bodies": [{"name": "S0", "ground": True}, {"name": "arm"}],
        "joints": [
            {"name": "ball", "type": "spherical", "between": ["S0", "arm"], "at": [0, 0, 0],
             "clearance": 0.2},
        ],
        "loads": [{"body": "arm", "at": [300, 0, 0], "force": [0, 5, 0]}],
    }  # fmt: skip
    path = tmp_path / "arm.json"
    path.write_text(json.dumps(data))
    solved = run("solve", str(path))
    assert solved.returncode == 3
    proc = run("sweep", str(path), "--vary", "loads[0].force[1]=0:10:3")
    assert proc.returncode == 3 and proc.stdout == ""
    assert proc.stderr == solved.stderr.replace(
        "jointplay: not held: ", "jointplay: not held: at the step loads[0].force[1] = 5.0: "
    )
    assert "most by loads[0] on 'arm'" in proc.stderr


def test_motion_contributions_take_the_variance_mode_and_the_sobol_samples() -> None:
    """The four-bar's fingertip is not linear over its ranges at any pose: by
    default each pose takes 1,024 Sobol' base sets (minutes); --variance
    never gives the linear shares alone, --variance always with
    --sobol-samples 16 the shares of the variance from 16 base sets. Given
    without --contributions, or not a power of 2, they are option errors."""
    path = str(GALLERY / "four_bar.yaml")
    base = ["motion", path, "--steps", "3", "--contributions", "--json"]
    never = json.loads(run(*base, "--variance", "never").stdout)["contributions"]
    assert "variance" not in never["measures"][0]["shares_of"]
    always = run(*base, "--variance", "always", "--sobol-samples", "16")
    assert always.returncode == 0, always.stderr
    shares = json.loads(always.stdout)["contributions"]["measures"][0]
    assert shares["shares_of"] == ["variance"] * 3
    for extra, words in [
        (["--variance", "never"], "--variance never: a setting of the contributions"),
        (["--sobol-samples", "16"], "--sobol-samples 16: a setting of the contributions"),
    ]:
        proc = run("motion", path, "--steps", "3", *extra)
        assert (
            proc.returncode == 2 and words in proc.stderr and "add --contributions" in proc.stderr
        )
    proc = run("motion", path, "--steps", "3", "--contributions", "--sobol-samples", "100")
    assert proc.returncode == 2 and "--sobol-samples 100: a power of 2" in proc.stderr
    proc = run("motion", path, "--steps", "3", "--contributions", "--variance", "sometimes")
    assert proc.returncode == 2 and "expected 'auto', 'always' or 'never'" in proc.stderr
