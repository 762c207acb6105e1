"""Finite rotations: the exact-rotation check of small-displacement answers."""

from __future__ import annotations

import json

import numpy as np
from scipy.spatial.transform import Rotation

import jointplay
from conftest import PAPER, spherical_shaft
from test_cli import run


def exact_overshoot(result: jointplay.Result, ref: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Exact displacement of ``point`` when the body turns by R(Omega) about
    its reference point ``ref`` (scipy's rotation, independent of ours)."""
    body = result.bodies["S1"]
    R = Rotation.from_rotvec(body.rotation).as_matrix()
    v_ref = body.displacement_of(ref)
    return ref + v_ref + R @ (point - ref) - point


def test_paper_shaft_with_a_large_ball_clearance_by_hand() -> None:
    # 6.1.6.1 with J1 = 3 mm: the shaft turns about c = (100, 0, 0), the
    # centroid of its joint centres; placed exactly, the ball centre goes past
    # its 1.5 mm play by what the turn's second-order term adds
    r = jointplay.solve(jointplay.load(PAPER / "6.1.6.1-J1_3.yaml"))
    ref = np.array([100.0, 0.0, 0.0])
    ball = exact_overshoot(r, ref, np.zeros(3))
    past_ball = float(np.linalg.norm(ball)) - 1.5
    ends = [exact_overshoot(r, ref, np.array([x, 0.0, 0.0]))[1:] for x in (180.0, 220.0)]
    past_ends = [float(np.linalg.norm(e)) - 0.05 for e in ends]
    expected = max(past_ball, *past_ends, 0.0)
    assert expected > 1e-4  # a real effect, about 3e-4 mm
    assert abs(r.linearization_error - expected) < 1e-12
    assert r.linearization.worst == ("l1", "ball")
    assert r.warnings == ()  # 0.01 % of the play: no warning
    assert r.to_dict()["linearization_error"] == r.linearization_error


def test_small_rotations_have_a_negligible_linearization_error() -> None:
    r = jointplay.solve(jointplay.load(PAPER / "6.1.6.1.yaml"))
    assert 0.0 <= r.linearization_error < 1e-4 * 0.2


def test_a_large_turn_warns_and_names_the_contact(tmp_path: object) -> None:
    # a loose ball and a short bore near one end of a long part, a far stop
    # that does not touch: the part turns by 0.025 rad about its reference
    # point (the centroid of its joint centres, 207 mm from the ball), and the
    # exactly placed ball centre goes about 2 % past its play
    data = spherical_shaft()
    ball, bore = data["joints"]  # type: ignore[misc]
    stop = {**ball, "name": "stop", "at": [600, 0, 0], "clearance": 40}
    data["joints"] = [
        {**ball, "clearance": 3},
        {**bore, "at": [20, 0, 0], "length": 4, "clearance": 0.1},
        stop,
    ]
    data["loads"] = [{"body": "S1", "at": [30, 0, 0], "force": [1, 1, 0]}]
    r = jointplay.solve(jointplay.model_from_dict(data))
    assert r.linearization_error > 0.01 * 3
    assert len(r.warnings) >= 1
    assert "joint 'l1', contact 'ball'" in r.warnings[0] and "--exact" in r.warnings[0]
    path = tmp_path / "turn.json"  # type: ignore[operator]
    path.write_text(json.dumps(data))
    proc = run("solve", str(path), "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["linearization_error"] == r.linearization_error
    assert doc["warnings"] == list(r.warnings)
    text = run("solve", str(path)).stdout
    assert "warning: joint 'l1'" in text
