"""Monte Carlo over real parts: each sample exact, the study reproducible."""

from __future__ import annotations

import json
from collections import OrderedDict
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

import jointplay
from conftest import MM, ROOT, spherical_shaft
from jointplay.cli import app
from jointplay.studies.montecarlo import MonteCarlo


def _shaft() -> dict[str, Any]:
    """The paper's shaft (``conftest.spherical_shaft``) with toleranced plays,
    two functional points and a requirement."""
    data: dict[str, Any] = spherical_shaft(
        name="shaft, plays by limits",
        points=[
            {"name": "B", "body": "S1", "at": [300, 0, 0]},
            {"name": "O", "body": "S1", "at": [0, 0, 0]},
        ],
        requirements=[{"point": "B", "max_displacement": 0.2}],
    )
    data["joints"][0]["clearance"] = {"min": 0.1, "max": 0.3}
    data["joints"][1]["clearance"] = {"min": "100 um", "max": "0.3 mm", "distribution": "normal"}
    return data


SHAFT = _shaft()


def with_plays(data: dict[str, Any], plays: dict[str, float]) -> jointplay.Model:
    """The model with each play fixed (joint name -> clearance, mm)."""
    out = json.loads(json.dumps(data))
    for joint in out["joints"]:
        if joint["name"] in plays:
            joint["clearance"] = plays[joint["name"]]
    return jointplay.model_from_dict(out)


def test_every_sample_is_the_equilibrium_of_its_own_parts() -> None:
    model = jointplay.model_from_dict(SHAFT)
    result = MonteCarlo(samples=300, seed=3, chunk=100).run(model)
    assert result.samples == 300
    assert result.play_labels == ("l1.clearance", "l2.clearance")
    for i in range(0, 300, 23):  # an independent full solve of those parts
        j1, j2 = result.plays[i]
        solved = jointplay.solve(with_plays(SHAFT, {"l1": j1, "l2": j2}))
        solved.check()
        for p, name in enumerate(result.point_names):
            expected = solved.points[name].displacement
            assert np.max(np.abs(result.displacement[i, p] - expected)) < MM  # two routes
    assert result.feasibility_mm < 1e-9
    assert result.equilibrium_residual < 1e-8


def test_ball_joint_closed_form_and_miss_fraction() -> None:
    # one ball joint: the centre goes J/2 along the force, so a requirement
    # of 0.125 mm is missed exactly by the parts whose play exceeds 0.25 mm
    data = {
        "bodies": [{"name": "g", "ground": True}, {"name": "b"}],
        "joints": [
            {
                "name": "ball",
                "type": "spherical",
                "between": ["g", "b"],
                "at": [0, 0, 0],
                "clearance": {"min": 0.1, "max": 0.3},
            },
        ],
        "loads": [{"body": "b", "at": [0, 0, 0], "force": [3, -4, 0]}],
        "points": [{"name": "c", "body": "b", "at": [0, 0, 0]}],
        "requirements": [{"point": "c", "max_displacement": 0.125}],
    }
    model = jointplay.model_from_dict(data)
    result = MonteCarlo(samples=2000, seed=11, chunk=500).run(model)
    play = result.plays[:, 0]
    assert np.all((play >= 0.1) & (play <= 0.3))
    expected = (play / 2)[:, None] * np.array([0.6, -0.8, 0.0])
    assert np.max(np.abs(result.displacement[:, 0] - expected)) < MM
    [req] = result.requirements
    assert req.outside == int(np.sum(play / 2 > 0.125))
    lo, hi = req.interval
    assert lo <= req.fraction <= hi
    assert lo < 0.25 < hi  # the exact fraction of a uniform play above 0.25 mm


def test_same_seed_same_numbers_whatever_the_workers() -> None:
    model = jointplay.model_from_dict(SHAFT)
    study = MonteCarlo(samples=900, seed=5, chunk=300)
    one = study.run(model, workers=1)
    two = study.run(model, workers=2)
    assert np.array_equal(one.plays, two.plays)  # the samples: the seed's, exactly
    # the answers: to the promise, not to the bit (another process may round otherwise)
    np.testing.assert_allclose(one.displacement, two.displacement, rtol=0, atol=MM)
    other = MonteCarlo(samples=900, seed=6, chunk=300).run(model)
    assert not np.array_equal(one.plays, other.plays)


def test_a_chunk_starts_from_the_nominal_answer_and_not_from_its_own_full_solve(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Why ``montecarlo._prepared`` exists: every chunk assembled the model
    and fully solved its own first sample before Newton could start
    (chunks of 10,000 ran 9 to 13 % slower than chunks of 50,000). The
    nominal answer, made once per process, now starts every chunk (how
    many samples still take a full solve is round-off, not asked). It is
    the same in every process, so a chunk's answers are the same (to
    1e-6 mm) whether it ran first in a fresh process or after other chunks."""
    from jointplay.studies import montecarlo

    model = jointplay.load(Path(__file__).parents[1] / "examples" / "studies" / "carriage.yaml")
    monkeypatch.setattr(montecarlo, "_PREPARED", OrderedDict())  # as in a fresh process
    study = MonteCarlo(samples=600, seed=4, chunk=200)
    alone = montecarlo._solve_chunk(model, study, 2, 200, "a run")
    made = montecarlo._PREPARED[("a run", None)]
    after = [montecarlo._solve_chunk(model, study, i, 200, "a run") for i in (0, 1, 2)]
    assert montecarlo._PREPARED[("a run", None)] is made  # assembled and solved once
    np.testing.assert_allclose(alone.displacement, after[2].displacement, rtol=0, atol=MM)
    # the same samples, each solved on its own, give the same displacements
    plain = jointplay.Workspace.of(model)
    asm = plain.asm
    pmap = montecarlo.play_map(asm, model.name)
    radii = pmap.radii(alone.plays)
    lmap = montecarlo.load_map(asm)
    work = lmap.work(alone.loads) if lmap.variables else np.tile(lmap.g0, (len(radii), 1))
    reference = plain.solve_batch(work, radii, forces=False)  # no start: its own full solves
    tip = model.points[0]
    motion = reference.body_displacement(tip.body)
    expected = motion[:, :3] + np.cross(motion[:, 3:], np.asarray(tip.at))
    # two starts, one optimum: they agree to 1e-6 mm
    np.testing.assert_allclose(alone.displacement[:, 0], expected, rtol=0, atol=MM)


def test_dask_cluster_gives_the_local_numbers() -> None:
    import distributed  # the test extra installs it

    model = jointplay.model_from_dict(SHAFT)
    study = MonteCarlo(samples=600, seed=9, chunk=200)
    local = study.run(model, workers=1)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        remote = study.run(model, scheduler=cluster.scheduler_address)
    assert np.array_equal(local.plays, remote.plays)  # the samples: the seed's, exactly
    np.testing.assert_allclose(local.displacement, remote.displacement, rtol=0, atol=MM)


def test_normal_plays_stay_in_their_limits_with_the_stated_spread() -> None:
    model = jointplay.model_from_dict(SHAFT)
    result = MonteCarlo(samples=20000, seed=1).run(model)
    normal = result.plays[:, 1]
    assert normal.min() >= 0.1 and normal.max() <= 0.3
    # +-3 sigma at the limits: sigma = 0.2 / 6, a little less once truncated
    assert abs(normal.mean() - 0.2) < 0.002
    assert 0.030 < normal.std() < 0.2 / 6


def test_convergence_mode_stops_when_the_error_is_small() -> None:
    model = jointplay.model_from_dict({**SHAFT, "requirements": []})
    study = MonteCarlo(samples=200_000, seed=2, chunk=1000, target_rel_error=0.01)
    result = study.run(model, workers=1)
    assert result.samples < 200_000
    assert np.all(result.relative_error <= 0.01)


def test_fit_plays_are_hole_minus_shaft() -> None:
    model = jointplay.load(Path("examples/studies/shaft_fits.yaml"))
    ball = model.joints[0].clearance
    assert ball.fit == "H8/f7" and ball.diameter == 20  # type: ignore[attr-defined]
    # ISO 286-2 at 20 mm: H8 = +0.033/0, f7 = -0.020/-0.041
    # the fit's limits are the table's arithmetic, not a solve's: to round-off
    assert ball.low == pytest.approx(0.020, abs=1e-12)  # type: ignore[attr-defined]
    assert ball.high == pytest.approx(0.074, abs=1e-12)  # type: ignore[attr-defined]
    assert float(ball) == pytest.approx(0.047, abs=1e-12)
    result = MonteCarlo(samples=5000, seed=4).run(model)
    assert np.all((result.plays[:, 0] >= 0.020 - 1e-12) & (result.plays[:, 0] <= 0.074 + 1e-12))


def run_cli(*args: str) -> Any:
    return CliRunner().invoke(app, list(args))


def test_cli_montecarlo_json(tmp_path: Path) -> None:
    out = run_cli(
        "montecarlo",
        "examples/studies/shaft_fits.yaml",
        "-n",
        "3000",
        "--seed",
        "7",
        "--workers",
        "1",
        "--json",
        "--csv",
        str(tmp_path / "s.csv"),
    )
    assert out.exit_code == 0, out.output
    doc = json.loads(out.output)
    assert doc["samples"] == 3000 and doc["seed"] == 7
    assert set(doc["points"]) == {"B"}
    assert doc["certificate"]["feasibility_mm"] < 1e-9
    lines = (tmp_path / "s.csv").read_text().splitlines()
    assert lines[0].split(",") == ["l1.clearance", "l2.clearance", "B.dx", "B.dy", "B.dz", "B.size"]
    assert len(lines) == 3001


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"clearance": {"min": 0.2}}, "'max' is missing"),
        ({"clearance": {"min": 0.3, "max": 0.1}}, "below min"),
        ({"clearance": {"min": -0.1, "max": 0.1}}, "play >= 0"),
        ({"clearance": {"min": 0.1, "max": 0.2, "distribution": "gauss"}}, "'uniform' or 'normal'"),
        ({"clearance": {"min": 0.1, "max": 0.2, "law": "normal"}}, "unknown key 'law'"),
        ({"clearance": {"fit": "H7/k6", "diameter": 20}}, "transition fit"),
        ({"clearance": {"fit": "H7/s6", "diameter": 20}}, "interference fit"),
        ({"clearance": {"fit": "H7/g6"}}, "needs its nominal 'diameter'"),
        ({"clearance": {"fit": "H7g6", "diameter": 20}}, "H7g6"),
        ({"clearance": {"fit": "H7/g6", "diameter": "20 kg"}}, "length"),
        ({"clearance": {"size": 3}}, "expected a length, {min, max} or {fit, diameter}"),
    ],
)
def test_bad_plays_exit_2(tmp_path: Path, change: dict[str, Any], words: str) -> None:
    data = json.loads(json.dumps(SHAFT))
    data["joints"][0].update(change)
    path = tmp_path / "m.json"
    path.write_text(json.dumps(data))
    out = run_cli("solve", str(path))
    assert out.exit_code == 2, out.output
    assert "joints[0] 'l1': clearance" in out.output and words in out.output


def test_a_study_needs_plays_and_points(tmp_path: Path) -> None:
    fixed = json.loads(json.dumps(SHAFT))
    for joint in fixed["joints"]:
        joint["clearance"] = 0.2
    path = tmp_path / "fixed.json"
    path.write_text(json.dumps(fixed))
    out = run_cli("montecarlo", str(path))
    assert out.exit_code == 2 and "nothing to study" in out.output
    assert "varies from part to part" in out.output
    no_points = {**SHAFT, "points": [], "requirements": []}
    path.write_text(json.dumps(no_points))
    out = run_cli("montecarlo", str(path))
    assert out.exit_code == 2 and "has none" in out.output
    out = run_cli("montecarlo", "examples/studies/shaft_fits.yaml", "--target", "2")
    assert out.exit_code == 2 and "between 0 and 1" in out.output


def test_requirement_must_name_a_point(tmp_path: Path) -> None:
    data = {**SHAFT, "requirements": [{"point": "Bee", "max_displacement": 0.1}]}
    path = tmp_path / "m.json"
    path.write_text(json.dumps(data))
    out = run_cli("solve", str(path))
    assert out.exit_code == 2
    assert "requirements[0]: point: unknown point 'Bee'" in out.output
    assert "Did you mean 'B'?" in out.output


# -- a model with load cases: every study is under one of them ----------------------
def _fits_with_cases_data() -> dict[str, Any]:
    data: dict[str, Any] = yaml.safe_load(
        (ROOT / "examples" / "studies" / "shaft_fits.yaml").read_text()
    )
    data["loads"] = [{"body": "S1", "at": [300, 0, 0], "force": [1, 0, 0]}]
    data["load_cases"] = {
        "cutting": [{"body": "S1", "at": [300, 0, 0], "force": [0, 40, 0]}],
        "lifting": [{"body": "S1", "at": [300, 0, 0], "force": [0, 0, 40]}],
    }
    return data


def _fits_with_cases() -> jointplay.Model:
    return jointplay.model_from_dict(_fits_with_cases_data())


def _cases_file() -> Path:
    import tempfile

    path = Path(tempfile.mkdtemp()) / "cases.yaml"
    path.write_text(yaml.safe_dump(_fits_with_cases_data()))
    return path


@pytest.mark.parametrize(
    "command",
    [
        ["montecarlo", "--samples", "20"],
        ["contributions"],
        ["tolerances", "--samples", "20"],
        ["sweep", "--vary", "loads[0].force[0]=0:2:2"],
    ],
)
def test_a_study_of_a_model_with_load_cases_needs_its_case(
    tmp_path: Path, command: list[str]
) -> None:
    """The top-level loads alone are none of the model's cases: a study
    without --case would report parts under a load the model never takes.
    Refused (exit 2, one line naming the cases); with --case, the study is
    that case's: its nominal sample is the solve under the case."""
    path = tmp_path / "cases.yaml"
    path.write_text(yaml.safe_dump(_fits_with_cases_data()))
    out = CliRunner().invoke(app, [command[0], str(path), *command[1:]])
    assert out.exit_code == 2, out.output
    assert "--case: the model has load cases (cutting, lifting): give --case NAME" in out.output
    assert len(out.output.strip().splitlines()) == 1
    out = CliRunner().invoke(app, [command[0], str(path), *command[1:], "--case", "lifting"])
    assert out.exit_code in (0, 4), out.output  # 4: a requirement fails under this case


def test_the_monte_carlo_of_a_case_is_under_that_case() -> None:
    """In Python as on the command line; a case's study equals the study of
    the model whose loads are that case's (the same parts, seed for seed)."""
    model = _fits_with_cases()
    with pytest.raises(jointplay.OptionError, match="the load case the Monte Carlo study is under"):
        MonteCarlo(samples=10).run(model)
    lifting = MonteCarlo(samples=50, seed=3, case="lifting").run(model)
    merged = model.replace(
        loads=[*model.loads, *(model.load_cases or {})["lifting"]], load_cases=None
    )
    alone = MonteCarlo(samples=50, seed=3).run(merged)
    assert np.array_equal(lifting.plays, alone.plays)
    assert np.allclose(lifting.displacement, alone.displacement, rtol=0, atol=1e-9)


def test_a_report_s_studies_are_under_its_first_case_and_say_so() -> None:
    """A report solves every case; its studies are under one (the first,
    unless --case), said on the page, and its Monte Carlo is that case's."""
    from jointplay.present.report import Report

    page = Report(samples=32).render(_fits_with_cases(), "cases.yaml")
    assert "are under load case &#x27;cutting&#x27; (the first;" in page
    page = Report(case="lifting", samples=32).render(_fits_with_cases(), "cases.yaml")
    assert "(the first;" not in page


def test_an_envelope_takes_every_case_or_the_one_given() -> None:
    """The envelope of case 'lifting' is the envelope of the model whose
    loads are that case's; without a case it takes both, so it holds both
    cases' envelopes (its support is their largest in every direction)."""
    from jointplay.studies.envelope import Envelope

    model = _fits_with_cases()
    both = Envelope("B", directions=40).run(model)
    alone = {}
    for case in ("cutting", "lifting"):
        alone[case] = Envelope("B", directions=40, case=case).run(model)
        merged = model.replace(
            loads=[*model.loads, *(model.load_cases or {})[case]], load_cases=None
        )
        plain = Envelope("B", directions=40, loads="model").run(merged)
        np.testing.assert_allclose(alone[case].h, plain.h, rtol=0, atol=1e-9)
        assert f"of load case '{case}'" in alone[case].over
    np.testing.assert_allclose(
        both.h, np.maximum(alone["cutting"].h, alone["lifting"].h), rtol=0, atol=1e-9
    )
    out = CliRunner().invoke(
        app, ["envelope", "--point", "B", "--case", "nope", str(_cases_file())]
    )
    assert out.exit_code == 2 and "--case: no load case 'nope'" in out.output
