"""Deviations of joint features (position and orientation zones): closed forms."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import jointplay
from conftest import MM, RAD
from jointplay.studies.montecarlo import MonteCarlo

J = 0.1  # the bore's diametral play (mm)


def pivoted_shaft(ball: dict[str, Any] | None = None, bore: dict[str, Any] | None = None) -> Any:
    """A shaft on a tight ball at the origin and a ball in a bore at x = 200,
    pushed down (-y) at its tip T, x = 300: the bore's contact sits at its
    centre minus J/2 along y, and T moves 1.5 times as much (the lever)."""
    joints: list[dict[str, Any]] = [
        {"name": "l1", "type": "spherical", "between": ["S0", "S1"], "at": [0, 0, 0]},
        {
            "name": "l2",
            "type": "sphere_in_cylinder",
            "between": ["S0", "S1"],
            "at": [200, 0, 0],
            "axis": [1, 0, 0],
            "clearance": J,
        },
    ]
    joints[0].update({"clearance": 0, **(ball or {})})
    joints[1].update(bore or {})
    return jointplay.model_from_dict(
        {
            "bodies": [{"name": "S0", "ground": True}, {"name": "S1"}],
            "joints": joints,
            "loads": [{"body": "S1", "at": [300, 0, 0], "force": [0, -1, 0]}],
            "points": [{"name": "T", "body": "S1", "at": [300, 0, 0]}],
        }
    )


def tip(model: Any) -> np.ndarray:
    result = jointplay.solve(model)
    result.check()
    return np.asarray(result.points["T"].displacement)


def test_a_bore_off_its_position_moves_the_shaft_with_it() -> None:
    dy, dz = 0.010, -0.020
    model = pivoted_shaft(bore={"deviation": {"position": {"diameter": 0, "mean": [0, dy, dz]}}})
    assert np.allclose(tip(model), 1.5 * np.array([0.0, dy - J / 2, dz]), atol=MM, rtol=0)


def test_a_tight_ball_off_its_position_is_the_shaft_s_new_pivot() -> None:
    d = np.array([0.004, 0.010, -0.006])
    model = pivoted_shaft(ball={"deviation": {"position": {"diameter": 0, "mean": d.tolist()}}})
    # T = d + 1.5 (bore point - d), the bore point at (., -J/2, 0)
    expected = np.array([d[0], d[1] + 1.5 * (-J / 2 - d[1]), d[2] + 1.5 * (0.0 - d[2])])
    assert np.allclose(tip(model), expected, atol=MM, rtol=0)


def test_a_deviation_in_um_in_a_turned_joint_frame_is_the_same_in_mm_in_global_axes() -> None:
    # joint frame with up = Z: y is global Y, z global Z
    plain = pivoted_shaft(
        bore={"up": [0, 0, 1], "deviation": {"position": {"diameter": 0, "mean": [0, 0.01, 0.02]}}}
    )
    # joint frame with up = Y: the frame's y is global -Z, z is global Y (x = X)
    frame = jointplay.solve(pivoted_shaft(bore={"up": [0, 1, 0]})).joints["l2"].R_world_joint
    local = frame.T @ np.array([0.0, 0.01, 0.02]) * 1000
    turned = pivoted_shaft(
        bore={
            "up": [0, 1, 0],
            "deviation": {"position": {"diameter": 0, "mean": [f"{float(v)!r} um" for v in local]}},
        }
    )
    assert np.allclose(tip(plain), tip(turned), atol=MM, rtol=0)


def sleeve(deviation: dict[str, Any]) -> Any:
    """A sleeve on one cylindrical joint (length 40) pressed down at its
    centre: both ends touch the bore's bottom line, so the sleeve follows the
    bore's tilt exactly."""
    return jointplay.model_from_dict(
        {
            "bodies": [{"name": "ground", "ground": True}, {"name": "sleeve"}],
            "joints": [
                {
                    "name": "bore",
                    "type": "cylindrical",
                    "between": ["ground", "sleeve"],
                    "at": [0, 0, 0],
                    "axis": [1, 0, 0],
                    "length": 40,
                    "clearance": J,
                    "deviation": deviation,
                }
            ],
            "loads": [{"body": "sleeve", "at": [0, 0, 0], "force": [0, -5, 0]}],
            "points": [{"name": "P", "body": "sleeve", "at": [100, 0, 0]}],
        }
    )


def test_a_tilted_bore_tilts_the_sleeve_by_its_tilt() -> None:
    wz = 2e-4
    result = jointplay.solve(sleeve({"orientation": {"angle": 0, "mean": [0, 0, wz]}}))
    result.check()
    assert np.allclose(result.bodies["sleeve"].rotation, [0, 0, wz], atol=RAD, rtol=0)
    assert np.allclose(result.points["P"].displacement, [0, -J / 2 + 100 * wz, 0], atol=MM, rtol=0)


def test_monte_carlo_draws_each_bore_position_and_the_tip_follows_the_lever() -> None:
    R = 0.01  # the position zone's radius: diameter 20 um
    model = pivoted_shaft(bore={"deviation": {"position": "20 um"}})
    mc = MonteCarlo(samples=20_000, seed=3).run(model)
    assert mc.deviation_labels == ("l2.deviation.position.y", "l2.deviation.position.z")
    d = mc.deviations
    # every sample is the closed form for its own bore
    expected = 1.5 * np.column_stack([np.zeros(len(d)), d[:, 0] - J / 2, d[:, 1]])
    assert np.allclose(mc.displacement[:, 0], expected, atol=MM, rtol=0)
    # the draws fill the disc by area: inside it, half of them within R / sqrt(2)
    r = np.linalg.norm(d, axis=1)
    assert np.max(r) <= R
    # statistics of 20,000 draws: 5 standard errors of each estimate
    assert abs(np.mean(r <= R / np.sqrt(2)) - 0.5) < 5 * 0.5 / np.sqrt(len(r))
    # the disc's second moment R^2/4 per direction: the tip's sigma is 1.5 R / 2
    sigma = mc.displacement[:, 0, 1:].std(axis=0)
    assert np.allclose(sigma, 1.5 * R / 2, rtol=5 / np.sqrt(2 * len(r)))
    assert abs(mc.points["T"].mean[1] + 1.5 * J / 2) < 5 * 1.5 * R / 2 / np.sqrt(len(r))


def test_monte_carlo_tilts_with_a_parallelism_over_a_length_normal_at_3_sigma() -> None:
    zone = {"tolerance": "10 um", "over": "40 mm"}
    model = sleeve({"orientation": zone, "distribution": "normal"})
    mc = MonteCarlo(samples=4_000, seed=1).run(model)
    w = mc.deviations  # tilts about y and z (rad)
    assert mc.deviation_labels == ("bore.deviation.orientation.y", "bore.deviation.orientation.z")
    assert np.max(np.linalg.norm(w, axis=1)) <= 0.01 / 40
    # the point at x = 100 rises by 100 w_z and sinks by 100 w_y (w x p)
    expected = np.column_stack([np.zeros(len(w)), -J / 2 + 100 * w[:, 1], -100 * w[:, 0]])
    assert np.allclose(mc.displacement[:, 0], expected, atol=MM, rtol=0)
    # normal with the zone's edge at 3 sigma (truncated by 1 %): sigma near t / L / 3
    sigma = w.std(axis=0)
    assert np.allclose(sigma, 0.01 / 40 / 3, rtol=0.05)  # 1 % truncation + 5 standard errors


def test_a_zone_of_no_size_draws_nothing_so_a_study_keeps_its_random_stream() -> None:
    plays = {"clearance": {"min": 0.08, "max": 0.12}}
    without = MonteCarlo(samples=500, seed=7).run(pivoted_shaft(bore=plays))
    zero = {"deviation": {"position": {"diameter": 0}}}
    with_zone = MonteCarlo(samples=500, seed=7).run(pivoted_shaft(bore={**plays, **zero}))
    assert with_zone.deviation_labels == ()
    assert np.array_equal(without.plays, with_zone.plays)
    assert np.allclose(without.displacement, with_zone.displacement, atol=MM, rtol=0)


@pytest.mark.parametrize(
    ("joint", "deviation", "words"),
    [
        ("ball", {"orientation": "1 mrad"}, "moves none of its contacts"),
        ("ball", {"position": {"diameter": 0.01, "y": {"min": 0, "max": 0.01}}}, "not both"),
        ("bore", {"position": {"y": {"min": 0.01, "max": 0}}}, "swap them"),
        ("bore", {}, "needs a 'position' zone"),
        ("bore", {"orientation": {"tolerance": 0.01}}, "tolerance over a length"),
        ("bore", {"orientation": {"angle": "1 mrad", "mean": [1e-4, 0, 0]}}, "about the joint"),
        ("bore", {"position": "2 percent"}, "length"),
    ],
)
def test_bad_deviations_are_named(joint: str, deviation: dict[str, Any], words: str) -> None:
    key = {"ball": "ball", "bore": "bore"}[joint]
    with pytest.raises(jointplay.ModelError, match=words):
        pivoted_shaft(**{key: {"deviation": deviation}})
