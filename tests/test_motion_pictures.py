"""The motion's pictures: the files ``motion --plot`` writes, the data each
panel draws (the motion result's own, and closed forms of the slider-crank),
the report's motion section and its slider, the README's figure."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import jointplay
from conftest import ROOT
from jointplay.cli import app
from jointplay.io.modelfile import model_from_dict
from jointplay.present.motion_plots import (
    MotionPictures,
    contact_switches,
    displacement_series,
    joint_forces,
    motion_figure,
    path_series,
    posed_lines,
    poses_figure,
)
from jointplay.studies.motion import Motion, MotionResult

SLIDER_CRANK = ROOT / "examples" / "gallery" / "slider_crank.yaml"
FOUR_BAR = ROOT / "examples" / "gallery" / "four_bar.yaml"
#: The slider-crank's crank radius, the guide's offset and the wrist pin's x (mm).
R, H, X0 = 40.0, 10.0, 179.6424
#: Two routes to one number agree to this share of the largest value.
SAME = 1e-8
#: Positions against a closed form (mm).
KINEMATICS_TOL = 1e-9


def _slider_crank(force: float, steps: int = 73) -> tuple[jointplay.Model, MotionResult]:
    """The gallery's slider-crank with one constant force along the guide on
    the piston (N): the rod is a two-force member."""
    data = jointplay.load(SLIDER_CRANK).model_dump(by_alias=True, exclude_none=True)
    data["loads"] = [{"body": "piston", "at": [X0, H, 0], "force": [force, 0, 0]}]
    data["motion"]["steps"] = steps
    model = model_from_dict(data, source=str(SLIDER_CRANK))
    return model, Motion().run(model)


@pytest.fixture(scope="module")
def compressed() -> tuple[jointplay.Model, MotionResult]:
    return _slider_crank(-1500.0)


@pytest.fixture(scope="module")
def four_bar() -> tuple[jointplay.Model, MotionResult]:
    model = jointplay.load(FOUR_BAR)
    return model, Motion(steps=25).run(model)


def _rod_angle(values: np.ndarray) -> np.ndarray:
    """The rod's angle to the guide at each crank angle (rad), closed form."""
    length = np.hypot(X0 - R, H)
    x = R * np.cos(values) + np.sqrt(length**2 - (R * np.sin(values) - H) ** 2)
    return np.asarray(np.arctan2(H - R * np.sin(values), x - R * np.cos(values)))


# -- the files ----------------------------------------------------------------
@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_motion_plot_writes_the_figure(suffix: str, tmp_path: Path) -> None:
    out = tmp_path / f"motion{suffix}"
    run = CliRunner().invoke(
        app, ["motion", str(SLIDER_CRANK), "--steps", "13", "--plot", str(out), "--json"]
    )
    assert run.exit_code == 0, run.output
    doc = json.loads(run.stdout)
    assert len(doc["steps"]) == 13
    data = out.read_bytes()
    assert len(data) > 10_000
    if suffix == ".png":
        from PIL import Image

        assert data[:8] == b"\x89PNG\r\n\x1a\n"
        with Image.open(out) as image:
            assert image.width > 1000 and image.height > 800
    else:
        root = ET.fromstring(data)
        assert root.tag.endswith("svg")


def test_motion_plot_with_a_bad_suffix_exits_2_before_the_motion(tmp_path: Path) -> None:
    out = tmp_path / "motion.txt"
    run = CliRunner().invoke(app, ["motion", str(SLIDER_CRANK), "--plot", str(out)])
    assert run.exit_code == 2
    message = " ".join(run.output.split())
    assert f"--plot {out}" in message
    assert "name the file .png, .svg or .pdf" in message
    assert "Traceback" not in run.output
    assert not out.exists()


def test_motion_plot_into_a_missing_folder_exits_2(tmp_path: Path) -> None:
    out = tmp_path / "nowhere" / "motion.png"
    run = CliRunner().invoke(app, ["motion", str(SLIDER_CRANK), "--plot", str(out), "--json"])
    assert run.exit_code == 2
    assert json.loads(run.stdout)["status"] == "invalid"
    assert "does not exist" in run.output


# -- what each panel draws --------------------------------------------------------
def test_the_displacement_panel_draws_the_result_along_its_requirement(
    compressed: tuple[jointplay.Model, MotionResult],
) -> None:
    _, result = compressed
    series = displacement_series(result, "piston top")
    k = result.point_names.index("piston top")
    along = result.displacement[:, k, 0]  # the requirement is along X
    assert np.array_equal(series.curves[0][1], along)
    assert np.allclose(series.drive, np.degrees(result.values), rtol=0, atol=1e-12)
    assert series.limit == pytest.approx(0.05)
    assert series.worst_step == int(np.argmax(np.abs(along)))
    fig = motion_figure(result)
    ax = fig.axes[0]
    assert np.array_equal(ax.lines[0].get_ydata(), along)
    assert np.array_equal(ax.lines[0].get_xdata(), series.drive)
    limits = sorted(float(line.get_ydata()[0]) for line in ax.lines[1:3])
    assert limits == pytest.approx([-0.05, 0.05])


def test_a_point_without_a_direction_draws_its_size_and_components(
    four_bar: tuple[jointplay.Model, MotionResult],
) -> None:
    _, result = four_bar
    series = displacement_series(result, "fingertip")
    d = result.displacement[:, 0]
    labels = [label for label, _ in series.curves]
    assert labels == ["|d|", "dx", "dy", "dz"]
    assert np.array_equal(series.curves[0][1], np.linalg.norm(d, axis=1))
    for i in range(3):
        assert np.array_equal(series.curves[i + 1][1], d[:, i])
    assert series.along is None and series.limit == pytest.approx(0.6)


def test_bands_and_an_envelope_are_drawn_as_given(
    compressed: tuple[jointplay.Model, MotionResult],
) -> None:
    _, result = compressed
    d = result.displacement[:, 0, 0]
    band = ("5-95 %", d - 0.01, d + 0.01)
    envelope = (d - 0.02, d + 0.02)
    extras = MotionPictures(bands={"piston top": [band]}, envelopes={"piston top": envelope})
    ax = motion_figure(result, extras).axes[0]
    assert len(ax.collections) == 1  # the band
    lower, upper = ax.lines[0], ax.lines[1]
    assert np.array_equal(lower.get_ydata(), envelope[0])
    assert np.array_equal(upper.get_ydata(), envelope[1])
    assert np.array_equal(ax.lines[2].get_ydata(), d)
    with pytest.raises(ValueError, match="one value per step"):
        displacement_series(result, "piston top", [("short", d[:3], d[:3])])


def test_the_envelope_s_legend_names_the_loads_it_is_under() -> None:
    """``motion --plot`` draws the envelope with the loads it is under in its
    legend: a constant force (nothing that varies) leaves the default at the
    probes, as the single-pose envelope's, and the legend says 1 N probes
    (the gallery's gas-force table takes the model's loads: its test is in
    test_motion_studies.py)."""
    from jointplay.studies.motion_studies import MotionEnvelope, MotionStudiesResult

    model, result = _slider_crank(-1500.0, steps=3)
    envelope = MotionEnvelope(directions=24, motion=Motion(steps=3)).run(model)
    studies = MotionStudiesResult(result, envelope=envelope)
    extras = MotionPictures(*studies.picture_extras(), envelope_label=studies.envelope_label())
    ax = motion_figure(result, extras).axes[0]
    legend = ax.get_legend()
    assert legend is not None
    assert "worst-case envelope under 1 N probes" in [t.get_text() for t in legend.get_texts()]


def test_no_curve_beside_bands_is_drawn_in_the_limit_s_colour(
    four_bar: tuple[jointplay.Model, MotionResult],
) -> None:
    """Two bands took the colour cycle's first two, and dz came out red: the
    limit's colour (found by a new user's try-out)."""
    from matplotlib.colors import to_hex

    from jointplay.present.plot import TOUCHING

    _, result = four_bar
    d = np.linalg.norm(result.displacement[:, 0], axis=1)
    bands = [("0.135-99.865 %", d - 0.02, d + 0.02), ("2.5-97.5 %", d - 0.01, d + 0.01)]
    ax = motion_figure(result, MotionPictures(bands={"fingertip": bands})).axes[0]
    curves = [line for line in ax.lines if line.get_label() in ("|d|", "dx", "dy", "dz")]
    assert len(curves) == 4
    assert all(to_hex(line.get_color()) != to_hex(TOUCHING) for line in curves)


def test_the_path_is_the_nominal_plus_the_magnified_play(
    compressed: tuple[jointplay.Model, MotionResult],
) -> None:
    _, result = compressed
    series = path_series(result, "piston top", magnify=20.0)
    nominal = result.nominal[:, 0]
    assert np.array_equal(series.nominal, nominal)
    assert np.allclose(
        series.displaced, nominal + 20.0 * result.displacement[:, 0], rtol=0, atol=1e-12
    )
    assert series.axes == (0, 1)  # the stroke along X, the play across it along Y
    # the piston's stroke, closed form
    length = np.hypot(X0 - R, H)
    t = result.values
    x = R * np.cos(t) + np.sqrt(length**2 - (R * np.sin(t) - H) ** 2) + 20.0
    assert np.max(np.abs(nominal[:, 0] - x)) < KINEMATICS_TOL


@pytest.mark.parametrize("force", [-1500.0, 800.0], ids=["compressed", "pulled"])
def test_the_guide_switches_sides_where_the_rod_lies_along_it(force: float) -> None:
    """A two-force rod pushes the piston across the guide by F tan(phi): the
    guide's contacts change sides at the first step past each crank angle
    where the rod lies along the guide (r sin t = h), and nowhere else; the
    pins' forces keep their side."""
    _, result = _slider_crank(force)
    phi = _rod_angle(result.values)
    expected = tuple(s for s in range(1, result.steps) if np.sign(phi[s]) != np.sign(phi[s - 1]))
    assert len(expected) == 2
    switches = contact_switches(result)
    assert switches["guide"] == expected
    assert switches["crank pin"] == switches["wrist pin"] == ()


def test_the_text_json_and_csv_mark_the_guide_switch_where_the_rod_lies_along_it(
    compressed: tuple[jointplay.Model, MotionResult],
) -> None:
    """The plot's rule, in the table (a mark after the contact, a legend
    under the table), in --json's "switched" and the CSV's column: the guide's
    contacts at the steps where the rod crosses the guide's line, the drive's
    backlash where the torque it holds, F r (sin t - cos t tan phi), changes
    sign, nothing else."""
    import io

    from rich.console import Console

    from jointplay.present.textreport import SWITCHED, render_motion

    _, result = compressed
    phi = _rod_angle(result.values)
    expected = {s for s in range(1, result.steps) if np.sign(phi[s]) != np.sign(phi[s - 1])}
    held = np.sign(np.sin(result.values) - np.cos(result.values) * np.tan(phi))
    turned = {s for s in range(1, result.steps) if held[s] != held[s - 1]}
    assert turned and not turned & expected
    buf = io.StringIO()
    render_motion(result, "crank", Console(file=buf, width=100_000, markup=False))
    text = buf.getvalue()
    rows = [line for line in text.splitlines() if "│" in line]
    assert len(rows) == result.steps
    for s, row in enumerate(rows):
        guide = row[row.index("guide (") :]
        assert (SWITCHED in guide) == (s in expected), row
        assert (f"drive{SWITCHED}" in row) == (s in turned), row
        assert row.count(SWITCHED) == guide.count(SWITCHED) + (s in turned), row
    legend = [line for line in text.splitlines() if line.startswith(f"{SWITCHED}: ")]
    assert len(legend) == 1 and "pushes the other way" in legend[0]
    doc = result.to_dict()
    frame = result.to_dataframe()
    for s, step in enumerate(doc["steps"]):
        guide = [name for name in step["switched"] if name.startswith("guide.")]
        assert bool(guide) == (s in expected)
        assert sorted(set(step["switched"]) - set(guide)) == (
            ["main bearing.drive"] if s in turned else []
        )
        assert frame["switched"][s] == "; ".join(step["switched"])


def test_the_joint_forces_are_the_reactions_and_the_rod_s_closed_form(
    compressed: tuple[jointplay.Model, MotionResult],
) -> None:
    _, result = compressed
    forces = joint_forces(result)
    for name, values in forces.items():
        sizes = [np.linalg.norm(r.joints[name].reaction_force) for r in result.results]
        assert np.array_equal(values, sizes)
    # the rod carries 1500 N / cos(phi) along itself
    rod = 1500.0 / np.cos(_rod_angle(result.values))
    assert np.max(np.abs(forces["wrist pin"] - rod)) <= SAME * np.max(rod)
    ax = motion_figure(result).axes[-1]
    curves = {
        str(line.get_label()).split(" (")[0]: line.get_ydata()
        for line in ax.lines
        if len(line.get_ydata()) == result.steps
    }
    assert curves.keys() == forces.keys()
    for name, values in forces.items():
        assert np.array_equal(curves[name], values)


def test_the_mechanism_at_its_poses(four_bar: tuple[jointplay.Model, MotionResult]) -> None:
    model, result = four_bar
    s = 7
    t = result.values[s]
    crank = posed_lines(model, result, s)["crank"][0]
    # the crank's outline turned by the drive's angle about the motor's axis
    outline = np.array(model.body("crank").outline, dtype=float)
    c, n = np.cos(t), np.sin(t)
    turned = outline @ np.array([[c, n, 0], [-n, c, 0], [0, 0, 1]])
    assert np.max(np.abs(crank[:-1] - turned)) < KINEMATICS_TOL
    fig = poses_figure(model, result, [0, s])
    assert len(fig.axes) == 1
    drawn = [np.asarray(line.get_xydata()) for line in fig.axes[0].lines]
    flat = crank[:, :2]
    assert any(P.shape == flat.shape and np.max(np.abs(P - flat)) < KINEMATICS_TOL for P in drawn)


# -- the report -----------------------------------------------------------------
def _views(page: str) -> list[dict[str, Any]]:
    found = re.search(r'<script type="application/json" id="jp-views">(.*?)</script>', page, re.S)
    assert found is not None
    views: list[dict[str, Any]] = json.loads(found.group(1).replace("<\\/", "</"))
    return views


def test_the_report_has_the_motion_and_a_slider_through_every_pose() -> None:
    from jointplay.present.report import Report

    model = jointplay.load(SLIDER_CRANK)
    page = Report(studies=False).render(model, str(SLIDER_CRANK))
    assert "<h2>Motion</h2>" in page
    assert "Requirements at every pose" in page
    # the summary's verdicts are at the file's pose: it says the motion's too
    summary = page[page.index("<h2>Summary</h2>") : page.index("Model</h2>")]
    result = Motion().run(model)
    failing = [
        name
        for q, name in enumerate(result.requirement_names)
        if np.any(result.measured[:, q] > result.limits[q])
    ]
    assert failing  # the gallery's piston strays past its limit late in the turn
    assert "Over the motion (the summary above is at the pose written in the file): " in summary
    assert f"{len(failing)} of {len(result.requirement_names)} requirements FAIL" in summary
    sliders = [v for v in _views(page) if v["figure"]["layout"].get("sliders")]
    assert len(sliders) == 1
    figure = sliders[0]["figure"]
    steps = figure["layout"]["sliders"][0]["steps"]
    assert model.motion is not None
    assert len(steps) == model.motion.steps == 73
    result = Motion().run(model)
    along = result.displacement[:, 0, 0]
    for s in (0, 40, 72):
        change, traces = steps[s]["args"]
        assert len(change["x"]) == len(change["y"]) == len(traces)
        # the last moving trace is the marker on the displacement curve
        assert change["x"][-1] == [pytest.approx(result.shown_value(s))]
        assert change["y"][-1] == [pytest.approx(along[s], abs=SAME * np.max(np.abs(along)))]
        assert steps[s]["label"] == f"{result.shown_value(s):g}"


def test_the_report_slider_moves_the_mechanism_in_a_browser(tmp_path: Path) -> None:
    from playwright.sync_api import sync_playwright

    from test_report import CHROMIUM_ARGS, _chromium

    out = tmp_path / "report.html"
    run = CliRunner().invoke(app, ["report", str(SLIDER_CRANK), "-o", str(out), "--no-studies"])
    assert run.exit_code == 0, run.output
    with sync_playwright() as pw:
        browser = pw.chromium.launch(
            executable_path=_chromium(), args=CHROMIUM_ARGS, chromium_sandbox=False
        )
        page = browser.new_context(viewport={"width": 1280, "height": 900}, offline=True).new_page()
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(out.as_uri())
        page.wait_for_selector("body[data-rendered='true']", timeout=60_000)
        view = page.evaluate(
            "Array.from(document.querySelectorAll('.jp-view')).map(d => d.id)"
            ".find(id => (document.getElementById(id).layout.sliders || []).length)"
        )
        div = f"document.getElementById('{view}')"
        page.locator(f"#{view}").scroll_into_view_if_needed()
        grip = page.locator(f"#{view} .slider-grip-rect").bounding_box()
        rail = page.locator(f"#{view} .slider-rail-rect").bounding_box()
        assert grip is not None and rail is not None
        y = grip["y"] + grip["height"] / 2
        page.mouse.move(grip["x"] + grip["width"] / 2, y)
        page.mouse.down()
        page.mouse.move(rail["x"] + 0.5 * rail["width"], y, steps=10)
        page.mouse.up()
        page.wait_for_timeout(300)
        active = page.evaluate(f"{div}.layout.sliders[0].active")
        marker = page.evaluate(f"{div}.data[{div}.data.length - 1].x")
        browser.close()
    assert errors == []
    assert 20 < active < 52  # about half way through the 73 poses
    assert marker == [pytest.approx(5.0 * active)]


# -- the README ---------------------------------------------------------------------
def test_the_readme_figure_is_what_its_command_draws(tmp_path: Path) -> None:
    from PIL import Image

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    figure = "docs/figures/slider_crank_motion.png"
    command = f"jointplay motion examples/gallery/slider_crank.yaml --plot {figure}"
    assert command in " ".join(text.split())
    assert f"]({figure})" in text
    committed = Image.open(ROOT / figure)
    assert "Matplotlib" in committed.info.get("Software", "")
    drawn_path = tmp_path / "motion.png"
    run = CliRunner().invoke(app, ["motion", str(SLIDER_CRANK), "--plot", str(drawn_path)])
    assert run.exit_code == 0, run.output
    drawn = Image.open(drawn_path)
    # the same figure; a few pixels of slack for font metrics of other versions
    assert abs(drawn.width - committed.width) <= 0.02 * committed.width
    assert abs(drawn.height - committed.height) <= 0.02 * committed.height
