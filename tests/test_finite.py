"""Finite rotations: the exact-rotation check of small-displacement answers."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import jointplay
from conftest import BALANCE, MM, PAPER, force_tol, moment_tol, spherical_shaft
from jointplay.settings import DEFAULT
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
    assert abs(r.linearization_error - expected) < MM
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


def _exact_place(result: jointplay.Result, P: np.ndarray) -> np.ndarray:
    body = result.bodies["S1"]
    R = Rotation.from_rotvec(body.rotation).as_matrix()  # scipy, independent of ours
    return body.translation + R @ P


@pytest.mark.parametrize("name", ["6.1.6.1.yaml", "6.1.6.1-J1_3.yaml"])
def test_exact_answer_holds_the_exact_geometry_and_balances(name: str) -> None:
    model = jointplay.load(PAPER / name)
    linear = jointplay.solve(model)
    exact = jointplay.solve(model, exact=True)
    exact.check()
    past = DEFAULT.exact_tolerance_mm  # what --exact promises of the exact geometry
    assert exact.linearization_error <= past
    J1, J2 = (3.0, 0.1) if "J1_3" in name else (0.2, 0.2)
    # placed with scipy's rotation: the ball centre stays in its 1.5 mm ball,
    # the shaft axis at both bore ends within the bore (joint frames = global)
    ball = _exact_place(exact, np.zeros(3))
    assert np.linalg.norm(ball) <= J1 / 2 + past
    for x in (180.0, 220.0):
        end = _exact_place(exact, np.array([x, 0.0, 0.0]))
        assert np.hypot(end[1], end[2]) <= J2 / 2 + past
    # the contact forces, at their displaced points, balance the load at its
    # displaced point: forces and moments about the origin
    F_load = np.array([1.0, 1.0, 1.0])
    total_force = F_load.copy()
    total_moment = np.cross(_exact_place(exact, np.array([300.0, 0, 0])), F_load)
    for jr in exact.joints.values():
        for c in jr.contacts:
            total_force += jr.R_world_joint @ c.force
            total_moment += np.cross(c.point, jr.R_world_joint @ c.force)
    # to the certificate's balance; the moments about the origin, up to 300 mm
    # from the body, take the forces' imbalance on that lever too
    np.testing.assert_allclose(total_force, 0, atol=force_tol(exact))
    np.testing.assert_allclose(total_moment, 0, atol=moment_tol(exact) + 300 * force_tol(exact))
    # how much exact and linear differ: on the J1 = 3 mm shaft, the ball stays
    # where it was and the bore centre slides back by the turn's second-order
    # term, -theta^2 / 2 * 200 mm along the axis (6.25e-4 mm here)
    theta = float(np.linalg.norm(linear.bodies["S1"].rotation))
    if "J1_3" in name:
        np.testing.assert_allclose(
            exact.joints["l1"].translation, linear.joints["l1"].translation, atol=MM
        )
        shift = exact.joints["l2"].translation - linear.joints["l2"].translation
        np.testing.assert_allclose(shift, [-(theta**2) / 2 * 200, 0, 0], atol=MM)


def test_exact_from_the_command_line() -> None:
    proc = run("solve", str(PAPER / "6.1.6.1-J1_3.yaml"), "--exact", "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["linearization_error"] <= DEFAULT.exact_tolerance_mm
    assert doc["equilibrium_residual"] <= BALANCE
    text = run("solve", str(PAPER / "6.1.6.1-J1_3.yaml"), "--exact").stdout
    assert "exact rotations" in text and "exact placement" in text


@pytest.mark.parametrize("path", sorted(PAPER.parent.rglob("*.yaml")), ids=lambda p: p.name)
def test_every_bundled_example_solves_exactly(path: object) -> None:
    model = jointplay.load(path)  # type: ignore[arg-type]
    for case in model.case_names or (None,):
        exact = jointplay.solve(model, case=case, exact=True)
        exact.check()
        assert exact.linearization_error <= DEFAULT.exact_tolerance_mm
        assert exact.equilibrium_residual <= BALANCE
