"""Requirements on the nominal solution: ``solve`` says pass or fail for each,
in text and JSON, for every load case, and ``--fail-on-requirements`` makes a
failure exit 4 (issue 19), so that a design repository's CI can gate on it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

import jointplay
from conftest import MM, spherical_shaft
from test_cli import run

ROOT = Path(__file__).resolve().parents[1]


def _shaft_with(requirements: list[dict[str, object]], **over: object) -> dict[str, object]:
    return spherical_shaft(
        points=[{"name": "tip", "body": "S1", "at": [300, 0, 0]}],
        requirements=requirements,
        **over,
    )


def _write(tmp_path: Path, data: dict[str, object]) -> str:
    path = tmp_path / "model.yaml"
    path.write_text(yaml.safe_dump(data))
    return str(path)


def test_each_requirement_is_measured_on_the_solution() -> None:
    """|d| and |d . u| of the point's displacement, against the limit: checked
    from the result's own point displacement, in mm."""
    along = [0.0, 3.0, 4.0]  # not a unit vector: the measure uses its direction
    model = jointplay.model_from_dict(
        _shaft_with(
            [
                {"point": "tip", "max_displacement": 1.0},
                {"point": "tip", "max_displacement": "10 um", "along": along},
            ]
        )
    )
    result = jointplay.solve(model)
    d = result.points["tip"].displacement
    size, component = result.requirements
    assert size.measured == pytest.approx(float(np.linalg.norm(d)), abs=MM)
    assert size.passed and size.margin == pytest.approx(1.0 - size.measured, abs=MM)
    assert component.measured == pytest.approx(abs(float(d @ [0, 0.6, 0.8])), abs=MM)
    assert component.measured > 0.01 and not component.passed
    assert component.margin == pytest.approx(0.01 - component.measured, abs=MM)


def test_solve_prints_and_exports_each_verdict(tmp_path: Path) -> None:
    model = _write(
        tmp_path,
        _shaft_with(
            [
                {"point": "tip", "max_displacement": 1.0},
                {"point": "tip", "max_displacement": 0.001, "along": [0, 0, 1]},
            ]
        ),
    )
    text = run("solve", model)
    assert text.returncode == 0, text.stderr  # without the option a failure is reported only
    assert "requirements on this solution (mm)" in text.stdout
    assert "pass" in text.stdout and "FAIL" in text.stdout
    doc = json.loads(run("solve", model, "--json").stdout)
    verdicts = doc["requirements"]
    assert [v["passed"] for v in verdicts] == [True, False]
    assert verdicts[1]["along"] == [0.0, 0.0, 1.0] and verdicts[1]["max_displacement"] == 0.001
    d = np.array(doc["points"]["tip"]["displacement"])
    assert verdicts[0]["measured"] == pytest.approx(float(np.linalg.norm(d)), abs=MM)
    assert verdicts[1]["measured"] == pytest.approx(abs(float(d[2])), abs=MM)


@pytest.mark.parametrize("as_json", [False, True], ids=["text", "json"])
def test_a_failed_requirement_exits_4_with_the_option(tmp_path: Path, as_json: bool) -> None:
    fails = _write(tmp_path, _shaft_with([{"point": "tip", "max_displacement": 0.001}]))
    extra = ["--json"] if as_json else []
    proc = run("solve", fails, "--fail-on-requirements", *extra)
    assert proc.returncode == 4, proc.stderr
    assert proc.stderr == ""  # a verdict, not an error: everything was printed
    if as_json:
        assert json.loads(proc.stdout)["requirements"][0]["passed"] is False
    holds = _write(tmp_path, _shaft_with([{"point": "tip", "max_displacement": 1.0}]))
    assert run("solve", holds, "--fail-on-requirements", *extra).returncode == 0


def test_every_load_case_gets_its_verdicts(tmp_path: Path) -> None:
    """examples/studies/shaft_cases.yaml with a requirement on its tip that the
    cutting case misses and the lifting case meets (found from the solutions'
    own tip displacements)."""
    data = yaml.safe_load((ROOT / "examples" / "studies" / "shaft_cases.yaml").read_text())
    model = jointplay.model_from_dict(data)
    results = jointplay.solve_cases(model)
    sizes = {n: float(np.linalg.norm(r.points["tip"].displacement)) for n, r in results.items()}
    assert sizes["cutting"] != pytest.approx(sizes["lifting"], abs=1e-3)
    limit = (sizes["cutting"] + sizes["lifting"]) / 2
    data["requirements"] = [{"point": "tip", "max_displacement": limit}]
    path = _write(tmp_path, data)
    doc = json.loads(run("solve", path, "--json").stdout)
    passed = {n: c["requirements"][0]["passed"] for n, c in doc["cases"].items()}
    assert passed == {n: sizes[n] <= limit for n in sizes}
    assert set(passed.values()) == {True, False}
    assert run("solve", path, "--fail-on-requirements").returncode == 4
    one = min(sizes, key=sizes.__getitem__)  # the case that passes, alone
    assert run("solve", path, "--case", one, "--fail-on-requirements").returncode == 0
