"""Contributions of the plays: closed-form slopes, kinks where the contacts
change, independent differences of full solves, the CLI."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import jointplay
from conftest import MM, ROOT, press, spherical_shaft
from jointplay.cli import app
from jointplay.studies.contributions import Contributions

FITS = ROOT / "examples" / "studies" / "shaft_fits.yaml"

#: mm: how far a measure may be from the exact one: its displacement's
#: components are proven to MM, so its size to sqrt(3) MM.
MEASURE = 2 * MM
#: The difference step of the closed-form tests, a fraction of each tolerance:
#: at the default (a thousandth) a slope is as good as the positions' round-off,
#: which is more than the certificate promises; at a tenth, positions to MM pin
#: it to a few 1e-4 (the measures are linear there, or smooth: Richardson's).
STEP = 0.1


def slope_tol(h: float) -> float:
    """A slope's error from measures off by MEASURE at steps h and h / 2: a
    one-sided slope over h / 2 (4 MEASURE / h), or Richardson's central one
    (3 MEASURE / h)."""
    return 4 * MEASURE / h


def shaft(j1: Any, j2: Any, at: float, force: list[float], **over: Any) -> dict[str, Any]:
    data = spherical_shaft(
        loads=[{"body": "S1", "at": [at, 0, 0], "force": force}],
        points=[{"name": "B", "body": "S1", "at": [at, 0, 0]}],
        **over,
    )
    joints: Any = data["joints"]
    joints[0]["clearance"], joints[1]["clearance"] = j1, j2
    return data


def test_radial_load_beyond_the_bore_has_the_lever_slopes() -> None:
    # |d_B| = -J1/2 + (J1 + J2)/2 * 300/220: the ball goes against the load
    j1 = {"min": 0.1, "max": 0.3}
    j2 = {"min": 0.15, "max": 0.25, "distribution": "normal"}
    model = jointplay.model_from_dict(shaft(j1, j2, 300, [0, 0, 3]))
    result = Contributions(step=STEP).run(model)
    s = np.array([-0.5 + 150 / 220, 150 / 220])
    assert result.measures == ("|d B|",)
    assert result.plays == ("l1.clearance", "l2.clearance")
    width = np.array([0.2, 0.1])
    tol = slope_tol(STEP * float(width.min()))
    assert np.max(np.abs(result.sensitivity[0] - s)) < tol
    assert not result.kink.any()
    assert result.nominal[0] == pytest.approx(-0.1 + 0.2 * 300 / 220, abs=MEASURE)
    sigma = np.array([0.2 / np.sqrt(12), 0.1 / 6])
    assert np.allclose(result.width, width) and np.allclose(result.sigma, sigma)
    assert result.worst_case_range[0] == pytest.approx(
        np.sum(np.abs(s) * width), abs=tol * float(width.sum())
    )
    sigma_tol = tol * float(np.linalg.norm(sigma))
    assert result.rss_sigma[0] == pytest.approx(np.sqrt(np.sum((s * sigma) ** 2)), abs=sigma_tol)
    # the shares: the formulas, from the study's own slopes (arithmetic, to round-off)
    got = result.sensitivity[0]
    wc = np.abs(got) * width / np.sum(np.abs(got) * width) * 100
    rss = (got * sigma) ** 2 / np.sum((got * sigma) ** 2) * 100
    assert np.max(np.abs(result.worst_case[0] - wc)) < 1e-6
    assert np.max(np.abs(result.rss[0] - rss)) < 1e-6


def test_a_load_between_the_joints_at_equal_plays_sits_on_a_kink() -> None:
    # the paper's 6.1.6.2 at J1 = J2: the ball and both bore ends touch; a
    # larger J1 leaves the end at 180 mm touching, a smaller one the end at 220
    band = {"min": 0.15, "max": 0.25}
    model = jointplay.model_from_dict(shaft(band, band, 100, [0, 1, 1]))
    result = Contributions(step=STEP).run(model)
    assert result.kink.all()
    tol = slope_tol(STEP * 0.1)
    assert result.slope_up[0] == pytest.approx([0.5 * 80 / 180, 0.5 * 100 / 220], abs=tol)
    assert result.slope_down[0] == pytest.approx([0.5 * 120 / 220, 0.5 * 100 / 180], abs=tol)
    # on a kink the slope is the mean of the one-sided ones (the study's arithmetic)
    mean = (result.slope_up[0] + result.slope_down[0]) / 2
    assert np.max(np.abs(result.sensitivity[0] - mean)) < 1e-12


def test_smooth_slopes_match_differences_of_independent_full_solves() -> None:
    # a load with an axial part: the contact directions turn with the plays.
    # The same differences (Richardson's, at h and h / 2) of independent full
    # solves: each measure to MEASURE, so the two slopes to twice slope_tol
    model = jointplay.load(FITS)
    result = Contributions(step=STEP).run(model)
    data = json.loads(json.dumps(model.model_dump(by_alias=True, exclude_none=True)))
    for i, joint in enumerate(("l1", "l2")):
        h = STEP * float(result.width[i])
        sizes = {}
        for offset in (h, -h, h / 2, -h / 2):
            changed = json.loads(json.dumps(data))
            entry = changed["joints"][i]
            entry["clearance"] = float(model.joint(joint).clearance) + offset
            alone = jointplay.solve(jointplay.model_from_dict(changed))
            alone.check()
            sizes[offset] = float(np.linalg.norm(alone.points["B"].displacement))
        central_h = (sizes[h] - sizes[-h]) / (2 * h)
        central_half = (sizes[h / 2] - sizes[-h / 2]) / h
        slope = (4 * central_half - central_h) / 3
        assert result.sensitivity[0, i] == pytest.approx(slope, abs=2 * slope_tol(h))
    assert not result.kink.any()
    assert result.worst_case.sum() == pytest.approx(100.0)
    assert result.rss.sum() == pytest.approx(100.0)


def test_requirements_along_a_direction_are_measured_too() -> None:
    band = {"min": 0.1, "max": 0.3}
    data = shaft(band, band, 300, [0, 0, 3])
    data["requirements"] = [{"point": "B", "max_displacement": 0.2, "along": [0, 0, -2]}]
    result = Contributions(step=STEP).run(jointplay.model_from_dict(data))
    assert result.measures == ("|d B|", "d B along [0, 0, -1]")
    # two measures of the same rows: B moves along z, so its size and its part
    # along -z differ (in size) by its other parts squared over twice its size,
    # at most MM^2 / 0.3 mm (its size is above 0.15 mm), over steps of 0.01 mm
    # or more: 3e-10 at most
    assert np.allclose(result.sensitivity[1], -result.sensitivity[0], atol=1e-9)


def test_cli_prints_json_csv_and_the_table(tmp_path: Path) -> None:
    csv = tmp_path / "c.csv"
    out = CliRunner().invoke(app, ["contributions", str(FITS), "--csv", str(csv)])
    assert out.exit_code == 0, out.output
    assert "l1.clearance" in out.output and "RSS" in out.output
    import pandas as pd

    table = pd.read_csv(csv)
    assert list(table["play"]) == ["l1.clearance", "l2.clearance"]
    assert table["rss_pct"].sum() == pytest.approx(100.0)
    out = CliRunner().invoke(app, ["contributions", str(FITS), "--json"])
    doc = json.loads(out.output)
    assert doc["study"] == "contributions"
    plays = doc["measures"]["|d B|"]["plays"]
    assert set(plays) == {"l1.clearance", "l2.clearance"}
    assert plays["l1.clearance"]["tolerance"] == pytest.approx(0.054)


def test_without_toleranced_plays_or_points_the_message_says_what_to_add(
    tmp_path: Path,
) -> None:
    path = tmp_path / "fixed.json"
    path.write_text(json.dumps(shaft(0.2, 0.2, 300, [0, 0, 1])))
    out = CliRunner().invoke(app, ["contributions", str(path)])
    assert out.exit_code == 2
    assert "nothing to study" in out.output and "varies from part to part" in out.output
    assert "fixed.json" in out.output
    data = shaft({"min": 0.1, "max": 0.2}, 0.2, 300, [0, 0, 1])
    del data["points"]
    path.write_text(json.dumps(data))
    out = CliRunner().invoke(app, ["contributions", str(path)])
    assert out.exit_code == 2
    assert "add 'points:" in out.output
    out = CliRunner().invoke(app, ["contributions", str(FITS), "--step", "2"])
    assert out.exit_code == 2
    assert "step" in out.output


def test_a_slope_below_what_the_positions_prove_is_zero() -> None:
    """The four-bar's out-of-plane force sits on a kink at its nominal 0 N: the
    mean of its one-sided slopes is round-off (it printed 5.2e-15 mm/N), and
    its effect over the whole 8 N range is below the length the positions
    prove, so it is 0 and its linear shares are 0."""
    from jointplay.assembly import assemble
    from jointplay.proven import Resolution

    model = jointplay.load(ROOT / "examples" / "gallery" / "four_bar.yaml")
    co = Contributions(variance="never").run(model)
    asm = assemble(model)
    length = Resolution.of(asm.s, asm.ell).length
    effect = np.abs(co.sensitivity) * co.width
    assert np.all((effect == 0) | (effect >= length))
    i = co.plays.index("loads[0].force[2]")
    assert co.sensitivity[0, i] == 0.0 and co.kink[0, i]


def test_variance_always_prints_the_sobol_shares_on_a_linear_measure() -> None:
    fits = ROOT / "examples" / "studies" / "shaft_fits.yaml"
    out = CliRunner().invoke(app, ["contributions", str(fits), "--variance", "always", "-n", "64"])
    assert out.exit_code == 0, out.output
    assert "RSS" in out.output and "the shares of its variance (Sobol' indices):" in out.output
    assert "first order %" in out.output


def test_round_off_prints_as_zero_and_a_measure_that_does_not_vary_has_no_shares(
    tmp_path: Path,
) -> None:
    """The press pushed off its axis with a side force that changes sign: the
    contacts change, so the shares are of the variance (Sobol'). Nothing
    pushes the ram across y, so the die's d . y is 0 in every set of parts:
    to round-off, which the positions do not prove, so 0 exactly (the one
    rule of ``jointplay.proven``). It has no variance, so no input has a
    share of it; an input with no effect on |d die| has a share of 0.0, and
    no cell shows -0.0 (nor 'nan')."""
    data = press(
        loads=[
            {"body": "ram", "at": [20, 10, -150], "force": [0, 0, "-1000 N"]},
            {"body": "ram", "at": [20, 10, -150], "force": [{"min": -5, "max": 5}, 0, 0]},
        ],
        points=[{"name": "die", "body": "ram", "at": [20, 10, -150]}],
        requirements=[{"point": "die", "max_displacement": "20 um", "along": [0, -1, 0]}],
    )
    path = tmp_path / "press.json"
    path.write_text(json.dumps(data))
    args = ["contributions", str(path), "-n", "16", "--workers", "1"]
    out = CliRunner().invoke(app, args)
    assert out.exit_code == 0, out.output
    assert "Sobol' indices from 16 base sets" in out.output  # |d die| is not linear
    assert not re.search(r"(?<![\d.])-0(\.0*)?(?![\d.e])", out.output), out.output
    assert "nan" not in out.output
    assert "the shares of its variance (Sobol' indices): none, it does not vary" in out.output
    doc = json.loads(CliRunner().invoke(app, [*args, "--json"]).output)
    across = "d die along [0, -1, 0]"
    nominal = doc["measures"][across]["nominal"]
    assert nominal == 0.0 and math.copysign(1.0, nominal) == 1.0
    assert doc["sobol"]["measures"][across]["variance"] == 0.0


def test_a_share_that_rounds_to_zero_prints_without_a_sign() -> None:
    """A Sobol' estimate's noise about 0 (an input with no effect) is 0.0 to
    the one decimal printed, not -0.0; a share that is below 0 stays so."""
    from jointplay.present.textreport import sobol_share

    assert sobol_share(-4e-4, (-1e-3, 2e-4)) == "0.0 [-0.1, 0.0]"
    assert sobol_share(-0.0, (-0.0, 0.0)) == "0.0 [0.0, 0.0]"
    assert sobol_share(-0.028, (-0.142, 0.086)) == "-2.8 [-14.2, 8.6]"


def test_a_measure_that_stays_put_but_not_at_0_has_no_shares_and_stderr_stays_quiet(
    tmp_path: Path,
) -> None:
    # the stop's play fixed (10 um): the die sits 5 um down in every set of parts,
    # but its variance was the solver's round-off (3e-36), shares were drawn from
    # it, and SALib's "constant values" warnings reached stderr
    data = press()
    data["joints"][1]["clearance"] = "10 um"  # type: ignore[index]
    data["loads"].append(  # type: ignore[attr-defined]
        {"body": "ram", "at": [0, 0, -150], "force": [{"min": -5, "max": 5}, 0, 0]}
    )
    path = tmp_path / "press.json"
    path.write_text(json.dumps(data))
    proc = CliRunner().invoke(app, ["contributions", str(path), "-n", "16"])
    assert proc.exit_code == 0, proc.output
    assert proc.stderr == ""
    text = " ".join(proc.stdout.split())
    assert "d die along [0, 0, -1]: 0.005 mm at the nominal" in text
    assert "the shares of its variance (Sobol' indices): none, it does not vary" in text
    doc = json.loads(
        CliRunner().invoke(app, ["contributions", str(path), "-n", "16", "--json"]).stdout
    )
    assert doc["sobol"]["measures"]["d die along [0, 0, -1]"]["variance"] == 0.0
