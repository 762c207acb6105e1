"""Loads that vary from sample to sample: a force or torque component given
as {min, max, distribution}; a single solve uses its mean."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import jointplay
from conftest import MM, spherical_shaft
from jointplay.cli import app
from jointplay.studies.contributions import Contributions
from jointplay.studies.montecarlo import MonteCarlo


def scattered(**over: Any) -> dict[str, Any]:
    data = spherical_shaft(
        loads=[
            {
                "body": "S1",
                "at": [300, 0, 0],
                "force": [{"min": -1, "max": 1}, 1, {"min": "-1 N", "max": "0.001 kN"}],
            }
        ],
        points=[{"name": "B", "body": "S1", "at": [300, 0, 0]}],
    )
    data.update(over)
    return data


def test_a_single_solve_uses_the_mean_load() -> None:
    data = scattered()
    data["loads"][0]["force"] = [
        {"min": -1, "max": 3},
        1,
        {"min": 0, "max": 2, "distribution": "normal"},
    ]
    mean = jointplay.solve(jointplay.model_from_dict(data))
    data["loads"][0]["force"] = [1, 1, 1]
    plain = jointplay.solve(jointplay.model_from_dict(data))
    np.testing.assert_allclose(
        mean.points["B"].displacement, plain.points["B"].displacement, rtol=0, atol=MM
    )


def test_every_sample_is_the_equilibrium_under_its_own_loads() -> None:
    data = scattered()
    model = jointplay.model_from_dict(data)
    result = MonteCarlo(samples=300, seed=4, chunk=100).run(model)
    assert result.load_labels == ("loads[0].force[0]", "loads[0].force[2]")
    assert result.loads.shape == (300, 2)
    assert np.all(np.abs(result.loads) <= 1.0)
    for i in range(0, 300, 37):
        fx, fz = result.loads[i]
        data["loads"][0]["force"] = [float(fx), 1.0, float(fz)]
        alone = jointplay.solve(jointplay.model_from_dict(data))
        alone.check()
        assert np.max(np.abs(result.displacement[i, 0] - alone.points["B"].displacement)) < MM
    assert result.equilibrium_residual < 1e-8


def test_scattering_a_load_leaves_the_plays_streams_alone() -> None:
    band = {"min": 0.1, "max": 0.3}
    plain = spherical_shaft(points=[{"name": "B", "body": "S1", "at": [300, 0, 0]}])
    plain["joints"][1]["clearance"] = band
    loaded = scattered()
    loaded["joints"][1]["clearance"] = band
    study = MonteCarlo(samples=200, seed=8)
    a = study.run(jointplay.model_from_dict(plain))
    b = study.run(jointplay.model_from_dict(loaded))
    assert np.array_equal(a.plays, b.plays)
    assert b.to_dataframe().columns[:3].tolist() == [
        "l2.clearance", "loads[0].force[0]", "loads[0].force[2]"
    ]  # fmt: skip


def test_a_compliant_joint_feels_the_size_of_the_load() -> None:
    # a ball with play 0.5 and 1000 N/mm: |d| = 0.25 + F / 1000
    data = {
        "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
        "joints": [
            {"name": "j", "type": "spherical", "between": ["G", "B"], "at": [0, 0, 0],
             "clearance": {"min": 0.4, "max": 0.6}, "stiffness": 1000},
        ],
        "loads": [{"body": "B", "at": [0, 0, 0], "force": [{"min": 80, "max": 120}, 0, 0]}],
        "points": [{"name": "c", "body": "B", "at": [0, 0, 0]}],
    }  # fmt: skip
    model = jointplay.model_from_dict(data)
    # a step of a tenth of each range (0.02 mm, 4 N), where the positions'
    # promise (MM) pins a slope to 4 * 2 MM over half the step (as in
    # test_contributions.slope_tol)
    result = Contributions(step=0.1).run(model)
    assert result.plays == ("j.clearance", "loads[0].force[0]")
    h = 0.1 * np.array([0.2, 40.0])
    assert np.all(np.abs(result.sensitivity[0] - [0.5, 1e-3]) <= 8 * MM / h)
    assert result.nominal[0] == pytest.approx(0.25 + 0.1, abs=MM)
    mc = MonteCarlo(samples=2000, seed=1).run(model)
    expected = mc.plays[:, 0] / 2 + mc.loads[:, 0] / 1000
    assert np.max(np.abs(mc.displacement[:, 0, 0] - expected)) < MM


def test_bad_load_limits_are_named(tmp_path: Path) -> None:
    data = scattered()
    data["loads"][0]["force"][0] = {"min": 2, "max": 1}
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    out = CliRunner().invoke(app, ["montecarlo", str(path)])
    assert out.exit_code == 2
    assert "loads[0]: force: component x: max (1 N) is below min (2 N)" in out.output
    data["loads"][0]["force"][0] = {"min": "1 mm", "max": 2}
    path.write_text(json.dumps(data))
    out = CliRunner().invoke(app, ["solve", str(path)])
    assert out.exit_code == 2
    assert "component x" in out.output and "force" in out.output
