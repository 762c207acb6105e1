"""Issue 53: tolerance figures that hold where the contacts change. The worst
case is the requirement's measure over the worst-case envelope, never passed
by a Monte Carlo sample; RSS only where the measure is linear over the
ranges; ppm intervals from 0 when no sample fails."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import jointplay
from conftest import MM, ROOT, spherical_shaft
from jointplay.studies.montecarlo import MonteCarlo, _wilson
from jointplay.studies.parts import inputs_of, measured, measures_of
from jointplay.studies.tolerances import Tolerances
from jointplay.studies.worstcase import worst_cases
from test_cli import run

FOUR_BAR = ROOT / "examples" / "gallery" / "four_bar.yaml"
J1, J2_LOW, J2_HIGH = 0.2, 0.15, 0.25


def side_pushed_shaft() -> jointplay.Model:
    """The paper's shaft pushed sideways at B (x = 300, beyond the bore at
    200) by a force along y that changes sign, -1 to 2 N. The ball goes
    against the push and the bore's far end with it: d_B = sign(F) D along y,
    D = -J1/2 + (J1 + J2)/2 * 300/220 (the lever of the bore's end at 220)."""
    data = spherical_shaft(
        loads=[{"body": "S1", "at": [300, 0, 0], "force": [0, {"min": -1, "max": 2}, 0]}],
        points=[{"name": "B", "body": "S1", "at": [300, 0, 0]}],
        requirements=[{"point": "B", "along": [0, 1, 0], "max_displacement": 0.25}],
    )
    joints: Any = data["joints"]
    joints[1]["clearance"] = {"min": J2_LOW, "max": J2_HIGH}
    return jointplay.model_from_dict(data)


def lever(j2: float) -> float:
    return -J1 / 2 + (J1 + j2) / 2 * 300 / 220


def test_a_side_force_that_changes_sign_has_an_exact_bound_and_no_linear_stack() -> None:
    """Closed form: d_B . y = sign(F) D(J2). The slopes at the nominal (F = 0.5
    N) see only the bore's play, so the linear stack says d_B . y stays within
    D(J2) -/+ its spread, all positive: wrong for every part pushed the other
    way. The bound is exact: D at the bore's upper limit, reached with F at a
    limit. RSS does not apply, and the check names the force."""
    model = side_pushed_shaft()
    result = Tolerances(samples=600, seed=2).run(model)
    (r,) = result.requirements
    mc = result.montecarlo
    y = mc.displacement[:, 0, 1]
    force = mc.loads[:, 0]
    j2 = mc.plays[:, mc.play_labels.index("l2.clearance")]
    assert np.max(np.abs(y - np.sign(force) * lever(j2))) < MM  # the closed form, per sample
    assert r.worst == pytest.approx(lever(J2_HIGH), abs=MM)
    assert abs(r.worst_signed) == pytest.approx(lever(J2_HIGH), abs=MM)
    assert f"l2.clearance = {J2_HIGH:g} mm" in r.worst_at  # the bore's upper limit
    # any push reaches it (|d_B| = D either way), so the force is not named as deciding it
    assert "loads[0].force[1]" not in r.worst_at and "the others do not change it" in r.worst_at
    # d_B . y goes both ways: -D to D, not one side of it
    assert (r.worst_low, r.worst_high) == pytest.approx((-lever(J2_HIGH), lever(J2_HIGH)), abs=MM)
    assert np.max(np.abs(y)) <= r.worst + MM and r.beyond_bound == 0
    # the linear stack: D(J2 mean) -/+ 0.5 * 300/220 * (J2 range) / 2, all above 0
    half = 0.5 * 300 / 220 * (J2_HIGH - J2_LOW) / 2
    assert (r.linear_low, r.linear_high) == pytest.approx(
        (lever(0.2) - half, lever(0.2) + half), abs=MM
    )
    assert np.sum(y < r.linear_low) > 0.2 * len(y)  # a third of the parts go the other way
    assert not r.linear and not r.linear_agrees and not r.rss_applies
    assert "loads[0].force[1]" in r.linear_why
    assert all(math.isnan(v) for v in (r.rss_sigma, r.cp, r.cpk, r.rss_ppm))
    doc = r.to_dict()
    assert doc["rss"]["applies"] is False and doc["rss"]["sigma"] is None
    assert "loads[0].force[1]" in doc["rss"]["why_not"]


def test_a_point_between_the_joints_is_worst_at_the_tighter_bore() -> None:
    """A gear between two bearings: the shaft pushed sideways at x = 300 tilts
    about the bore (x = 180 to 220), so a point at x = 50, between the ball
    and the bore, moves most where the bore's play is smallest. The worst case
    takes the lower limits too: no sample passes it, and it names the bore at
    its lower limit (at the upper limits alone it read 0.0489 mm, below every
    sample, and passed a requirement 29 % of the parts fail)."""
    data = spherical_shaft(
        loads=[{"body": "S1", "at": [300, 0, 0], "force": [0, {"min": 1, "max": 2}, 0]}],
        points=[{"name": "P", "body": "S1", "at": [50, 0, 0]}],
        requirements=[{"point": "P", "max_displacement": 0.065}],
    )
    joints: Any = data["joints"]
    joints[1]["clearance"] = {"min": 0.05, "max": 0.25}
    (r,) = Tolerances(samples=400, seed=1).run(jointplay.model_from_dict(data)).requirements
    assert "l2.clearance = 0.05 mm" in r.worst_at
    assert r.mc_high <= r.worst + MM and r.beyond_bound == 0
    assert not r.worst_case_passes  # past 0.065 mm at the tight bore


def test_the_four_bar_s_worst_case_is_the_envelope_s_and_passes() -> None:
    """Issue 53's example: the linear stack said 6.48 mm (FAIL); the worst case
    over the envelope is 0.409 mm (the envelope's largest displacement), at
    most that and at least every sample, passing 0.6 mm, reached at the plays'
    upper limits with the loads at named limits; RSS is not applicable
    because the out-of-plane force changes the touching contacts."""
    from jointplay.studies.envelope import Envelope

    model = jointplay.load(FOUR_BAR)
    (r,) = Tolerances(samples=300, seed=0).run(model).requirements
    envelope = Envelope("fingertip").run(model)
    assert r.worst == pytest.approx(envelope.largest, abs=MM)
    assert r.worst <= 0.409102 + MM and r.mc_high <= r.worst + MM
    assert r.worst_case_passes
    for pin in "BCD":  # every pin at its upper limit, H7/g6 at 8 mm
        assert f"pin {pin}.clearance = 0.029 mm" in r.worst_at
    assert "loads[0].force[2] = " in r.worst_at
    assert not r.rss_applies and "loads[0].force[2]" in r.linear_why
    assert not r.linear_agrees  # the stack's 6.48 mm is not shown as the worst case


def test_the_four_bar_s_table_and_json_say_rss_does_not_apply() -> None:
    proc = run("tolerances", str(FOUR_BAR), "-n", "200")
    assert proc.returncode == 0, proc.stderr
    words = " ".join(proc.stdout.split())
    assert "up to 0.4091" in words and "FAIL" not in words
    assert "RSS, Cp, Cpk: not applicable: loads[0].force[2] changes the touching contacts" in words
    assert "worst case 0.409102 mm, at pin B.clearance = 0.029 mm" in words
    doc = json.loads(run("tolerances", str(FOUR_BAR), "-n", "200", "--json").stdout)
    (req,) = doc["requirements"]
    assert req["rss"]["applies"] is False and req["rss"]["sigma"] is None
    assert req["worst_case"]["passes"] is True and req["worst_case"]["worst"] <= 0.409102 + MM


def _examples_with_tolerances() -> list[Path]:
    out = []
    for path in sorted((ROOT / "examples").glob("*/*.yaml")):
        model = jointplay.load(path)
        if model.points and inputs_of(model, None, str(path)).groups:
            out.append(path)
    return out


@pytest.mark.parametrize("path", _examples_with_tolerances(), ids=lambda p: p.stem)
def test_no_sample_passes_the_worst_case_on_any_bundled_example(path: Path) -> None:
    """Every bundled example whose plays, loads or deviations vary: each
    point's |d| and each requirement's measure stay within the worst case in
    every sample (300 a model: the suite stays fast); along a direction, within
    the least to the greatest d . u it reached."""
    model = jointplay.load(path)
    measures = measures_of(model, str(path))
    reaches = worst_cases(model, measures, None, source=str(path))
    mc = MonteCarlo(samples=300, seed=5).run(model)
    y = measured(model, measures, mc.displacement)
    for k, reach in enumerate(reaches):
        assert np.nanmax(np.abs(y[k])) <= reach.worst + MM, (path.name, reach.measure)
        if reach.low is not None and reach.high is not None:
            inside = (reach.low - MM <= y[k]) & (y[k] <= reach.high + MM)
            assert np.all(inside | np.isnan(y[k])), (path.name, reach.measure)


def test_the_ppm_interval_starts_at_exactly_0_when_no_sample_fails() -> None:
    z = 1.959963984540054
    assert _wilson(0, 2000, z)[0] == 0.0 and _wilson(0, 2000, z)[1] > 0
    assert _wilson(2000, 2000, z)[1] == 1.0
    low, high = _wilson(3, 2000, z)
    assert 0 < low < 3 / 2000 < high
    (r,) = Tolerances(samples=300, seed=0).run(jointplay.load(FOUR_BAR)).requirements
    assert r.mc_ppm == 0 and r.mc_interval_ppm[0] == 0.0
