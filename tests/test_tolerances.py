"""Each requirement three ways, side by side (issue 19): worst case, RSS with
Cp/Cpk, Monte Carlo with Pp/Ppk and ppm. Each figure is checked against its
documented formula computed here from the underlying numbers (the Monte
Carlo samples themselves, the contributions' slopes), and against SciPy's
normal law for the RSS ppm. Issue 53: the worst case is the bound over the
envelope (never passed by a sample), the linear stack an estimate, and RSS
only where the measure is linear over the ranges."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from scipy import stats

import jointplay
from conftest import MM, press, spherical_shaft
from jointplay.studies.tolerances import Tolerances
from test_cli import run

ROOT = Path(__file__).resolve().parents[1]
FITS = ROOT / "examples" / "studies" / "shaft_fits.yaml"
SAMPLES = 20_000


@pytest.fixture(scope="module")
def two_requirements() -> tuple[jointplay.Model, object]:
    """shaft_fits with its |d| requirement and a two-sided one along y."""
    data = yaml.safe_load(FITS.read_text())
    data["requirements"].append({"point": "B", "max_displacement": "20 um", "along": [0, 1, 0]})
    model = jointplay.model_from_dict(data)
    return model, Tolerances(samples=SAMPLES, seed=3).run(model)


def test_each_figure_follows_its_formula(two_requirements: tuple[jointplay.Model, object]) -> None:
    model, result = two_requirements
    linear, mc = result.linear, result.montecarlo  # type: ignore[attr-defined]
    size, along = result.requirements  # type: ignore[attr-defined]
    d = mc.displacement[:, mc.point_names.index("B")]
    # the nominal from an independent single solve at the mean plays
    d0 = jointplay.solve(model).points["B"].displacement
    nominal = {"|d B|": float(np.linalg.norm(d0)), "d B along [0, 1, 0]": float(d0[1])}
    for r, y, k in (
        (size, np.linalg.norm(d, axis=1), linear.measures.index("|d B|")),
        (along, d[:, 1], linear.measures.index("d B along [0, 1, 0]")),
    ):
        high = r.requirement.max_displacement
        low = -high if r.two_sided else None
        # the linear estimate: the linear stack of the tolerances around the nominal
        half = float(np.sum(np.abs(linear.sensitivity[k]) * linear.width)) / 2
        assert r.nominal == pytest.approx(nominal[linear.measures[k]], abs=1e-6)  # mm
        assert (r.linear_low, r.linear_high) == pytest.approx((r.nominal - half, r.nominal + half))
        # the worst case: an independent solve at the plays' upper limits (the
        # load does not vary), the requirement's own measure
        at_max = jointplay.solve(
            model.replace(
                joints=[{**j.model_dump(), "clearance": j.clearance.high} for j in model.joints]
            )
        )
        top = float(r.requirement.measure(at_max.points["B"].displacement))
        assert r.worst == pytest.approx(top, abs=1e-6)  # mm
        assert r.linear and r.linear_agrees and r.rss_applies
        # RSS: sigma from the slopes and the plays' sigmas, a normal law
        sigma = float(np.sqrt(np.sum((linear.sensitivity[k] * linear.sigma) ** 2)))
        assert r.rss_sigma == pytest.approx(sigma, rel=1e-12)
        tail = stats.norm.sf((high - r.nominal) / sigma)
        if low is not None:
            tail += stats.norm.cdf((low - r.nominal) / sigma)
        assert r.rss_ppm == pytest.approx(1e6 * tail, rel=1e-9)
        # Monte Carlo: the samples' own mean, sigma and share outside
        assert r.mc_mean == pytest.approx(float(np.mean(y)), rel=1e-12)
        assert r.mc_sigma == pytest.approx(float(np.std(y, ddof=1)), rel=1e-12)
        outside = np.abs(y) > high if r.two_sided else y > high
        assert r.mc_ppm == pytest.approx(1e6 * float(np.mean(outside)), rel=1e-12)
        lo, hi = r.mc_interval_ppm
        assert lo <= r.mc_ppm <= hi
        # the samples' range, and none passes the worst case
        assert (r.mc_low, r.mc_high) == (float(np.min(y)), float(np.max(y)))
        assert float(np.max(np.abs(y))) <= r.worst + 1e-6  # mm
        assert r.beyond_bound == 0 and r.beyond_words(SAMPLES) == ""
        # capability: two-sided Cp, Cpk = nearest limit over 3 sigma
        if r.two_sided:
            assert r.cp == pytest.approx(2 * high / (6 * sigma))
            assert r.pp == pytest.approx(2 * high / (6 * r.mc_sigma))
            near = min(high - r.nominal, r.nominal + high)
            near_mc = min(high - r.mc_mean, r.mc_mean + high)
        else:
            assert np.isnan(r.cp) and np.isnan(r.pp)
            near, near_mc = high - r.nominal, high - r.mc_mean
        assert r.cpk == pytest.approx(near / (3 * sigma))
        assert r.ppk == pytest.approx(near_mc / (3 * r.mc_sigma))


def test_rss_and_monte_carlo_agree_where_the_stack_is_nearly_linear(
    two_requirements: tuple[jointplay.Model, object],
) -> None:
    """The two spreads come from different computations (slopes at the nominal;
    20,000 solved parts): within 3 % (sampling error about 0.5 %, the rest the
    stack's curvature over the plays' ranges)."""
    _, result = two_requirements
    for r in result.requirements:  # type: ignore[attr-defined]
        assert r.mc_sigma == pytest.approx(r.rss_sigma, rel=0.03)
        assert r.mc_mean == pytest.approx(r.nominal, abs=0.1 * r.rss_sigma)


def test_the_linear_estimate_holds_the_monte_carlo_parts_of_a_linear_measure(
    two_requirements: tuple[jointplay.Model, object],
) -> None:
    """For the component along y, every sampled part lies within the linear
    estimate's range (the sampled extremes stay about 11 % of the range inside
    it: random parts seldom reach the corners, and the stack's curvature over
    the plays' ranges is smaller than that)."""
    _, result = two_requirements
    along = result.requirements[1]  # type: ignore[attr-defined]
    mc = result.montecarlo  # type: ignore[attr-defined]
    y = mc.displacement[:, mc.point_names.index("B"), 1]
    assert not along.kink
    assert along.linear_low <= y.min() and y.max() <= along.linear_high


def test_the_command_prints_json_csv_and_the_table(tmp_path: Path) -> None:
    proc = run("tolerances", str(FITS), "-n", "2000", "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["study"] == "tolerances" and doc["samples"] == 2000
    (req,) = doc["requirements"]
    assert set(req) >= {"worst_case", "rss", "monte_carlo", "nominal", "two_sided"}
    assert req["rss"]["cp"] is None and req["rss"]["cpk"] > 0  # one-sided: no Cp
    csv = tmp_path / "t.csv"
    text = run("tolerances", str(FITS), "-n", "2000", "--csv", str(csv))
    assert text.returncode == 0, text.stderr
    assert "worst case" in text.stdout and "Monte Carlo" in text.stdout and "Cpk" in text.stdout
    assert csv.read_text().splitlines()[0].startswith("requirement,nominal,worst_case,")
    assert "linear estimate" in text.stdout and "at most" in text.stdout


def test_the_figure_shows_the_parts_the_limit_and_the_worst_case(tmp_path: Path) -> None:
    """``tolerances --plot`` (the README says every study takes it): per
    requirement, the parts' histogram with the limit and the bound drawn
    where they are, inside the panel."""
    import matplotlib

    matplotlib.use("Agg")
    from jointplay.present.plot import tolerances_figure

    out = tmp_path / "t.png"
    proc = run("tolerances", str(FITS), "-n", "500", "--plot", str(out))
    assert proc.returncode == 0, proc.stderr
    assert out.read_bytes()[:4] == b"\x89PNG"
    result = Tolerances(samples=500).run(jointplay.load(FITS))
    (r,) = result.requirements
    (ax,) = [a for a in tolerances_figure(result).axes if a.get_title()]
    drawn = {
        round(float(line.get_xdata()[0]), 9)
        for line in ax.get_lines()
        if len(line.get_xdata()) == 2
    }
    assert {round(r.requirement.max_displacement, 9), round(r.worst, 9)} <= drawn
    low, high = ax.get_xlim()
    assert low <= r.mc_low and r.worst <= high


def test_a_model_without_requirements_is_told_what_to_add() -> None:
    proc = run("tolerances", str(ROOT / "examples" / "paper" / "6.1.6.1.yaml"))
    assert proc.returncode == 2
    assert "requirements" in proc.stderr and "max_displacement" in proc.stderr


def test_plays_that_do_not_vary_give_json_that_parses(tmp_path: Path) -> None:
    """Zero-width tolerances: no spread at all, so the capability indices are
    unbounded; the JSON says null (it has no infinity), and a round-off spread
    of the samples counts as none rather than as an absurd Ppk."""
    data = yaml.safe_load(FITS.read_text())
    for joint in data["joints"]:
        joint["clearance"] = {"min": "10 um", "max": "10 um"}
    data["requirements"].append({"point": "B", "max_displacement": 1.0, "along": [0, 1, 0]})
    path = tmp_path / "zero.yaml"
    path.write_text(yaml.safe_dump(data))
    proc = run("tolerances", str(path), "-n", "200", "--json")
    assert proc.returncode == 0, proc.stderr

    def refuse(name: str) -> None:
        raise AssertionError(f"not JSON: {name}")

    doc = json.loads(proc.stdout, parse_constant=refuse)
    for req in doc["requirements"]:
        assert req["rss"]["sigma"] == 0.0 and req["monte_carlo"]["sigma"] == 0.0
        assert req["rss"]["cpk"] is None and req["monte_carlo"]["ppk"] is None
        linear = req["worst_case"]["linear_estimate"]
        assert linear["low"] == linear["high"] == req["nominal"]
        assert req["worst_case"]["worst"] == pytest.approx(abs(req["nominal"]), abs=1e-6)  # mm


def test_the_dataframe_carries_what_the_json_does(
    two_requirements: tuple[jointplay.Model, object],
) -> None:
    _, result = two_requirements
    frame = result.to_dataframe()  # type: ignore[attr-defined]
    for row, r in zip(frame.itertuples(), result.requirements, strict=True):  # type: ignore[attr-defined]
        as_json = r.to_dict()
        assert (row.mc_ppm_low, row.mc_ppm_high) == tuple(as_json["monte_carlo"]["interval_ppm"])
        assert (row.linear_low, row.linear_high) == (
            as_json["worst_case"]["linear_estimate"]["low"],
            as_json["worst_case"]["linear_estimate"]["high"],
        )
        assert (row.worst_case, row.worst_case_at) == (
            as_json["worst_case"]["worst"],
            as_json["worst_case"]["at"],
        )
        for column, key in (
            ("worst_case_signed", "signed"),
            ("worst_case_low", "low"),
            ("worst_case_high", "high"),
        ):  # along a direction only: |d| has none (null, NaN)
            value, expected = getattr(row, column), as_json["worst_case"][key]
            assert (value is None or np.isnan(value)) if expected is None else value == expected
        assert row.rss_ppm == as_json["rss"]["ppm"] and row.mc_ppm == as_json["monte_carlo"]["ppm"]
        mc = as_json["monte_carlo"]
        assert (row.mc_low, row.mc_high, row.beyond_worst_case) == (
            mc["low"],
            mc["high"],
            mc["beyond_worst_case"],
        )


def test_samples_pass_the_linear_stack_but_never_the_worst_case() -> None:
    """Reading a position zone as a distance |d|, the bore's tilt and shift bend
    the response: 108 of 100,000 parts of shaft_deviations lie past the linear
    stack's high end (review of issue 21; this test draws 20,000). The worst
    case is the envelope's support over the plays and the zones, and holds
    every sample; it is the envelope's own largest displacement."""
    from jointplay.studies.envelope import Envelope

    path = ROOT / "examples" / "studies" / "shaft_deviations.yaml"
    model = jointplay.load(path)
    result = Tolerances(samples=SAMPLES, seed=0).run(model)
    (r,) = result.requirements
    mc = result.montecarlo
    d = mc.displacement[:, mc.point_names.index(r.requirement.point)]
    y = np.linalg.norm(d, axis=1)
    assert r.mc_high == float(np.max(y)) > r.linear_high
    assert float(np.max(y)) <= r.worst + 1e-6 and r.beyond_bound == 0  # mm
    env = Envelope(r.requirement.point).run(model)
    assert np.all(env.contains(d, tol=1e-6))  # mm
    assert r.worst == pytest.approx(env.largest, abs=1e-6)  # mm


def test_a_one_signed_deviation_prints_its_signed_range_and_what_decides_it(
    tmp_path: Path,
) -> None:
    """The press's ram drops by half the stop's play, 2.5 to 7.5 um, whatever
    the guide's plays: along -z the worst case reaches 0.0025 to 0.0075 mm,
    one sign only, not -/+0.0075; it is decided by the stop alone, so the
    guide's plays are not named; across (x) nothing moves the die, and no
    input decides it. The CSV carries the signed figures the JSON does."""
    path = tmp_path / "press.json"
    path.write_text(json.dumps(press()))
    result = Tolerances(samples=200, seed=0).run(jointplay.load(path))
    down, across = result.requirements
    assert down.worst == pytest.approx(0.0075, abs=1e-6)  # mm
    assert down.worst_signed == pytest.approx(0.0075, abs=1e-6)
    assert (down.worst_low, down.worst_high) == pytest.approx((0.0025, 0.0075), abs=1e-6)
    assert down.worst_at == "stop.clearance = 0.015 mm; the others do not change it"
    assert across.worst == 0.0 and (across.worst_low, across.worst_high) == (0.0, 0.0)
    assert across.worst_at == "every combination alike (no input changes it)"
    csv = tmp_path / "t.csv"
    text = run("tolerances", str(path), "-n", "200", "--csv", str(csv))
    assert text.returncode == 0, text.stderr
    assert "-/+" not in text.stdout.replace("y0 -/+ sum", "")  # the legend's linear stack
    assert f"{down.worst_low:.5g} to {down.worst_high:.5g}" in text.stdout
    assert "at stop.clearance = 0.015 mm; the others do not change it" in text.stdout
    import pandas as pd

    doc = json.loads(run("tolerances", str(path), "-n", "200", "--json").stdout)
    for row, req in zip(pd.read_csv(csv).itertuples(), doc["requirements"], strict=True):
        worst = req["worst_case"]
        assert (row.worst_case_signed, row.worst_case_low, row.worst_case_high) == (
            worst["signed"],
            worst["low"],
            worst["high"],
        )
    assert doc["requirements"][0]["worst_case"]["low"] == pytest.approx(0.0025, abs=1e-6)
    import matplotlib

    matplotlib.use("Agg")
    from jointplay.present.plot import tolerances_figure

    # the figure draws the worst case where it is reached: at its two ends, not at -0.0075
    panel, _ = [a for a in tolerances_figure(result).axes if a.get_title()]  # down, across
    drawn = {round(float(line.get_xdata()[0]), 9) for line in panel.get_lines()}
    assert {0.0025, 0.0075, 0.02, -0.02} <= drawn and -0.0075 not in drawn


def test_the_spindle_s_depth_of_cut_is_one_signed_and_decided_by_the_bearings() -> None:
    """examples/gallery/spindle.yaml: along Z, the depth of cut, the tool tip
    goes one way only (down, under the cutting force), and only the bearings'
    radial plays count: the belt's backlash turns the tip across Y and the
    front bearing's axial play moves it along X, so neither is named."""
    path = ROOT / "examples" / "gallery" / "spindle.yaml"
    doc = json.loads(run("tolerances", str(path), "-n", "200", "--json").stdout)
    worst = doc["requirements"][0]["worst_case"]
    assert worst["low"] < worst["high"] < 0 and worst["signed"] == worst["low"]
    assert worst["worst"] == pytest.approx(-worst["low"])
    text = run("tolerances", str(path), "-n", "200").stdout
    assert f"{worst['low']:.5g} to {worst['high']:.5g}" in text
    assert (
        "front bearing.clearance = " in worst["at"] and "rear bearing.clearance = " in worst["at"]
    )
    assert "backlash" not in worst["at"] and "axial_clearance" not in worst["at"]


def test_a_sample_below_the_printed_low_end_is_counted_and_the_verdict_stays() -> None:
    """Along a direction the worst case prints the least to the greatest d . u
    it reached; a part outside that range is counted and said, and only one
    past its size (|d . u| above it) makes the worst case fail. Here
    10 N down at the ball (0.4 mm of play) drops the shaft's left end, and a
    push (F, 1 N) up into the bore (0.1 mm) lifts its right end by less the
    more F tilts the push: P, halfway, drops least at F = 0, between the
    limits and the mean (-1, 1 and 3 N) the worst case takes. Those parts lie
    below its low end, though |d . u| stays under its greatest value."""
    data = spherical_shaft(
        loads=[
            {"body": "S1", "at": [0, 0, 0], "force": [0, 0, -10]},
            {"body": "S1", "at": [200, 0, 0], "force": [0, {"min": -1, "max": 3}, 1]},
        ],
        points=[{"name": "P", "body": "S1", "at": [100, 0, 0]}],
        requirements=[{"point": "P", "along": [0, 0, -1], "max_displacement": 0.2}],
    )
    joints: Any = data["joints"]
    joints[0]["clearance"], joints[1]["clearance"] = 0.4, 0.1
    model = jointplay.model_from_dict(data)
    result = Tolerances(samples=300, seed=0).run(model)
    (r,) = result.requirements
    mc = result.montecarlo
    y = -mc.displacement[:, mc.point_names.index("P"), 2]
    push = mc.loads[:, mc.load_labels.index("loads[1].force[1]")]
    # an independent solve at F = 0 drops P less than the worst case's low end
    level = model.replace(
        loads=[model.loads[0].model_dump(), {**model.loads[1].model_dump(), "force": [0, 0, 1]}]
    )
    assert -jointplay.solve(level).points["P"].displacement[2] < r.worst_low - MM
    below = y < r.worst_low - MM
    assert np.all(np.abs(push[below]) < 1) and np.sum(below) > 0.3 * len(y)
    assert float(np.max(np.abs(y))) <= r.worst + MM  # none passes |d . u|'s greatest value
    assert r.outside_range == int(np.sum(below)) and r.mc_low == float(np.min(y))
    # they lie between the limits, not past the worst case's size: its verdict holds
    assert r.beyond_bound == 0 and r.worst <= r.requirement.max_displacement
    assert r.worst_case_passes
    words = r.beyond_words(300)
    assert f"they reach {r.mc_low:.6g} to {r.mc_high:.6g} mm" in words
    assert "lie outside the worst case's range" in words and "its verdict holds" in words


def test_samples_pass_the_worst_case_outside_its_range_or_above_its_size() -> None:
    """The count: along a direction, a value below the low end or above the
    high end by more than the certified margin; for |d|, one above the worst
    case by more than it. A value within the margin is the answers' round-off."""
    from jointplay.settings import CERTIFIED_MM
    from jointplay.studies.tolerances import beyond_reach
    from jointplay.studies.worstcase import Reach

    along = Reach("d P along [0, 0, 1]", 0.3, "", "", 0.3, 0.1, 0.3)
    c = CERTIFIED_MM
    y = np.array([0.1 - 2 * c, 0.1 - c / 2, 0.2, 0.3 + c / 2, 0.3 + 2 * c, -0.2])
    # -0.2: |y| is under 0.3, yet it is outside 0.1 to 0.3
    assert beyond_reach(y, along) == 3
    size = Reach("|d P|", 0.3, "", "")
    assert beyond_reach(np.array([0.1, 0.3 + c / 2, 0.3 + 2 * c]), size) == 1
