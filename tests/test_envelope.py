"""Worst-case envelope: exact support values, closed forms, Monte Carlo inside."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import jointplay
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
    assert np.max(np.abs(env.h - 0.2)) < 1e-9
    assert np.max(np.abs(env.hull - 0.2 * env.directions)) < 1e-9
    assert env.largest == pytest.approx(0.2, abs=1e-9)
    assert np.max(np.abs(env.extent - np.array([[-0.2, 0.2]] * 3))) < 1e-9


def test_shaft_extent_matches_the_lever_rule() -> None:
    # plays at their upper limits (0.3 mm): the point at 300 mm reaches, across
    # the axis, the ball's 0.15 mm one way plus the bore end's (at 220 mm)
    # 0.15 mm the other, levered: 0.15 * (300 + 80) / 220
    model = jointplay.model_from_dict(SHAFT)
    env = Envelope("B", directions=100).run(model)
    across = 0.15 * 380 / 220
    assert env.extent[1] == pytest.approx([-across, across], abs=1e-9)
    assert env.extent[2] == pytest.approx([-across, across], abs=1e-9)
    assert env.extent[0] == pytest.approx([-0.15, 0.15], abs=1e-9)
    sizes = np.linalg.norm(env.hull, axis=1)
    assert env.largest >= sizes.max() - 1e-12  # the climb only goes up
    # support values are the hull points' projections
    assert np.allclose(env.h, np.einsum("ij,ij->i", env.directions, env.hull), atol=1e-12)
    mean = Envelope("B", directions=100, plays="mean").run(model)
    assert mean.extent[1][1] == pytest.approx(0.1 * 380 / 220, abs=1e-9)


def test_no_monte_carlo_sample_leaves_the_envelope() -> None:
    model = jointplay.model_from_dict(SHAFT)
    env = Envelope("B", directions=300).run(model)
    mc = MonteCarlo(samples=5000, seed=8).run(model)
    inside = env.contains(mc.displacement[:, 0], tol=1e-9)
    assert inside.all()
    assert np.linalg.norm(mc.displacement[:, 0], axis=1).max() <= env.largest + 1e-9


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
