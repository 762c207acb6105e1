"""The HTML report: its content, its self-containment, and a real browser.

The browser test opens the page in Debian's Chromium (headless, driven by
Playwright; ``apt-get install chromium`` is part of the README's test
command), with the network cut off, and checks that the interactive 3D view
and the tables render with no console error and no request leaving the
file; it saves a screenshot in ``build/screenshots/``.
"""

from __future__ import annotations

import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

import jointplay
from conftest import PAPER, ROOT
from jointplay.cli import app
from jointplay.io.modelfile import model_from_dict
from jointplay.present.report import Report
from jointplay.studies.sweep import RotateLoad, Sweep

STUDIES = ROOT / "examples" / "studies"
SCREENSHOTS = ROOT / "build" / "screenshots"
#: Software WebGL: a headless machine has no GPU, and the 3D view needs WebGL.
CHROMIUM_ARGS = [
    "--use-angle=swiftshader",
    "--enable-unsafe-swiftshader",
    "--disable-background-networking",
    "--disable-component-update",
    "--no-first-run",
]


def _chromium() -> str:
    path = shutil.which("chromium") or shutil.which("chromium-browser")
    assert path, (
        "the report's browser test needs Debian's Chromium: run 'apt-get install -y chromium' "
        "(the README's test command does)"
    )
    return path


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        chromium = pw.chromium.launch(
            executable_path=_chromium(), args=CHROMIUM_ARGS, chromium_sandbox=False
        )
        yield chromium
        chromium.close()


def _open(browser: Any, page_path: Path) -> tuple[Any, list[str], list[str]]:
    """The page, opened offline; the console errors and the requests made."""
    context = browser.new_context(viewport={"width": 1280, "height": 900}, offline=True)
    page = context.new_page()
    errors: list[str] = []
    requests: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("requestfailed", lambda r: errors.append(f"failed: {r.url}"))
    page.on("request", lambda r: requests.append(r.url))
    page.goto(page_path.as_uri())
    page.wait_for_selector("body[data-rendered='true']", timeout=60_000)
    return page, errors, requests


def _drawn_pixels(path: Path) -> int:
    image = np.asarray(Image.open(path).convert("RGB")).astype(int)
    # anything neither white nor Plotly's pale grid background
    return int(np.count_nonzero(np.ptp(image, axis=2) > 60))


def test_the_report_renders_in_a_real_browser(browser: Any, tmp_path: Path) -> None:
    out = tmp_path / "report.html"
    run = CliRunner().invoke(
        app, ["report", str(STUDIES / "shaft_fits.yaml"), "-o", str(out), "-n", "2000"]
    )
    assert run.exit_code == 0, run.output
    page, errors, requests = _open(browser, out)
    assert errors == []
    assert page.evaluate("document.body.dataset.errors") is None
    assert requests == [out.as_uri()]  # nothing else: no network, no other file
    # the interactive 3D view: a WebGL canvas, with the mechanism drawn on it
    assert page.locator("#jp-view-0 canvas").count() >= 1
    assert page.evaluate("document.getElementById('jp-view-0').data.length") >= 5
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    view = SCREENSHOTS / "report-3d-view.png"
    page.locator("#jp-view-0").screenshot(path=str(view))
    assert _drawn_pixels(view) > 500
    page.screenshot(path=str(SCREENSHOTS / "report.png"), full_page=True)
    # the tables, with the solution's numbers
    captions = page.locator("table.jp-table caption").all_inner_texts()
    for caption in ("Joints", "Contacts and forces", "Functional points", "What varies"):
        assert caption in captions
    contacts = page.locator("table.jp-table", has_text="Contacts and forces")
    rows = contacts.locator("tbody tr").all_inner_texts()
    assert [r.split("\t")[:2] for r in rows] == [["l1", "ball"], ["l2", "end-"], ["l2", "end+"]]
    result = jointplay.solve(jointplay.load(STUDIES / "shaft_fits.yaml"))
    force = result.joints["l2"].contacts[1].force_magnitude
    assert f"{force:.6g}" in rows[2] and "touching" in rows[2]
    # the figures are in the page
    assert page.locator("img.figure").count() == 5  # mechanism, joints, envelope, MC, contrib.
    for index in range(page.locator("img.figure").count()):
        assert page.locator("img.figure").nth(index).evaluate("i => i.naturalWidth") > 300
    page.context.close()


def test_a_report_with_cases_and_a_sweep_renders(browser: Any, tmp_path: Path) -> None:
    table = jointplay.load(STUDIES / "wobbly_table.yaml")
    out = tmp_path / "table.html"
    out.write_text(Report(studies=False).render(table, "wobbly_table.yaml"), encoding="utf-8")
    page, errors, _ = _open(browser, out)
    assert errors == []
    assert page.locator(".jp-view canvas").count() >= 3  # one view per load case
    headings = page.locator("h2").all_inner_texts()
    assert [h for h in headings if h.startswith("Solution")] == [
        f"Solution, load case '{c}'" for c in table.case_names
    ]
    page.context.close()
    unbalance = jointplay.load(STUDIES / "rotating_unbalance.yaml")
    sweep = Sweep(rotate=RotateLoad(0, (1.0, 0.0, 0.0), 12))
    out = tmp_path / "sweep.html"
    out.write_text(Report(sweep=sweep).render(unbalance, "unbalance"), encoding="utf-8")
    page, errors, _ = _open(browser, out)
    assert errors == []
    steps = page.locator("table.jp-table", has_text="Steps").locator("tbody tr")
    assert steps.count() == 12
    page.context.close()


def test_the_page_is_self_contained() -> None:
    html = Report(studies=False).render(jointplay.load(PAPER / "6.1.6.1.yaml"), "6.1.6.1.yaml")
    assert html.startswith("<!DOCTYPE html>")
    assert not re.search(r"<script[^>]+src=", html)  # every script is inline
    assert not re.search(r"<link[^>]+href=", html)
    assert not re.search(r"""<img[^>]+src=["'](?!data:)""", html)
    assert "Plotly" in html and html.count('<img class="figure"') == 2
    assert "jp-view-0" in html and "data-rendered" not in html.split("<body>")[1][:50]


def test_a_model_without_points_or_tolerances_says_why_no_study() -> None:
    html = Report().render(jointplay.load(PAPER / "6.1.6.1.yaml"), "6.1.6.1.yaml")
    assert "The model has no functional points, so there is nothing to study" in html
    html = Report().render(jointplay.load(STUDIES / "rotating_unbalance.yaml"), "unbalance")
    assert "Worst-case envelope of point &#x27;B&#x27;" in html
    assert "No play, load or deviation varies from part to part" in html


@pytest.mark.parametrize(
    ("args", "code", "message"),
    [
        (["-o", "{tmp}/r.txt"], 2, "a report is an HTML page; name the file .html"),
        (["-o", "{tmp}/no/r.html"], 2, "does not exist; create it"),
        (["-o", "{tmp}/r.html", "--case", "nope"], 2, "no load case 'nope'"),
        (["-o", "{tmp}/r.html", "--magnify", "-2"], 2, "--magnify -2: expected a factor above 0"),
        (["-o", "{tmp}/r.html", "--vary", "joints[9].clearance=1:2:3"], 2, "joints[9]"),
    ],
)
def test_report_bad_input_exits_2(args: list[str], code: int, message: str, tmp_path: Path) -> None:
    argv = ["report", str(PAPER / "6.1.6.1.yaml"), *[a.format(tmp=tmp_path) for a in args]]
    run = CliRunner().invoke(app, argv)
    assert run.exit_code == code, run.output
    assert message in run.output and "Traceback" not in run.output
    assert not list(tmp_path.glob("r.*"))


def test_a_page_that_cannot_be_written_exits_2(tmp_path: Path) -> None:
    (tmp_path / "taken.html").mkdir()
    run = CliRunner().invoke(
        app,
        ["report", str(PAPER / "6.1.6.1.yaml"), "-o", str(tmp_path / "taken.html"), "--no-studies"],
    )
    assert run.exit_code == 2 and "cannot write it" in run.output
    assert "Traceback" not in run.output


def test_the_report_puts_each_requirement_side_by_side() -> None:
    """With plays that vary and requirements, the page carries the worst case,
    RSS and Monte Carlo figures of each requirement, the same numbers as
    ``jointplay tolerances`` on the same samples."""
    from jointplay.studies.tolerances import Tolerances

    model = jointplay.load(STUDIES / "shaft_fits.yaml")
    html = Report(samples=2000, seed=0).render(model, "shaft_fits.yaml")
    assert "Requirements: worst case, RSS and Monte Carlo side by side" in html
    (row,) = Tolerances(samples=2000, seed=0).run(model).requirements
    assert f"{row.rss_ppm:.4g}" in html and f"{row.mc_ppm:.4g}" in html
    # the summary says both verdicts: at the nominal plays, and over the toleranced ones
    summary = html[html.index("<h2>Summary</h2>") : html.index("Model</h2>")]
    assert "requirements (nominal plays)" in summary
    worst = "all pass" if row.worst_case_passes else "1 of 1 FAIL"
    assert f"Over the tolerances: worst case {worst}" in summary
    low, high = row.mc_interval_ppm
    assert f"Monte Carlo: {row.mc_ppm:.4g} ppm out of spec for" in summary
    assert f"({low:.3g} to {high:.3g} ppm at the confidence of the table)" in summary


def test_the_deviation_example_s_report_ranks_deviations_with_plays() -> None:
    """shaft_deviations.yaml (issue 21's example): its bore's position and
    tilt zones stand with its play in the contributions, largest share first
    as in the Pareto beside them; the requirement's row carries the same
    figures as ``jointplay tolerances``, the samples' range among them, and
    says how many samples pass the linear stack."""
    import html as html_lib

    from jointplay.studies.contributions import Contributions
    from jointplay.studies.tolerances import Tolerances

    model = jointplay.load(STUDIES / "shaft_deviations.yaml")
    page = Report(samples=2000, seed=0).render(model, "shaft_deviations.yaml")
    linear = Contributions().run(model)
    k = linear.measures.index("|d B|")
    ranked = [linear.plays[i] for i in np.argsort(-linear.worst_case[k], kind="stable")]
    assert {"l2.deviation.position", "l2.deviation.orientation"} <= set(ranked)
    table = page[page.index("<h3>Contributions") :]
    rows = re.findall(r"<tr><td>\|d B\|</td><td>([^<]+)</td>", table)
    assert rows == ranked
    (row,) = Tolerances(samples=2000, seed=0).run(model).requirements
    side = page[page.index("Requirements: worst case, RSS and Monte Carlo side by side") :]
    assert f"{row.mc_ppm:.4g}" in side and f"{row.rss_ppm:.4g}" in side
    assert f"{row.mc_low:.5g} .. {row.mc_high:.5g}" in side
    if row.beyond_bound:
        assert html_lib.escape(row.beyond_words(2000)) in side
    assert "Over the tolerances: worst case" in page


def test_the_report_opens_with_a_summary_and_the_plays_used() -> None:
    """A summary first (status, the play used most, the requirements' verdict,
    the points' displacements), then the plays the nominal solve used: a
    toleranced play at its mean, with where it comes from."""
    model = jointplay.load(STUDIES / "shaft_fits.yaml")
    html = Report(studies=False).render(model, "shaft_fits.yaml")
    summary = (
        html.index("<h2>Summary</h2>") if "<h2>Summary</h2>" in html else html.index("Summary")
    )
    assert summary < html.index("Model</h2>")
    result = jointplay.solve(model)
    used = max(c.gap_used for j in result.joints.values() for c in j.contacts)
    assert f"{100 * used:.1f} % (touching)" in html
    assert "all pass" in html
    assert "Plays the nominal solve used" in html
    for joint in model.joints:
        used = f"{float(joint.clearance):g} mm"
        assert f"<td>{joint.name}</td><td>clearance</td><td>{used}</td>" in html
    assert "H7/g6 at 25 mm: 0.007 to 0.041 mm (normal)" in html


def test_the_report_draws_each_joint_view_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """The joints seen along their axes appear in the clearance figure only;
    the mechanism figure above it leaves its joint panels out."""
    from jointplay.present import plot

    calls: list[dict[str, Any]] = []
    real = plot.mechanism_figure

    def spy(*args: Any, **kwargs: Any) -> Any:
        calls.append(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(plot, "mechanism_figure", spy)
    Report(studies=False).render(jointplay.load(PAPER / "6.1.6.1.yaml"), "6.1.6.1.yaml")
    assert [c.get("joints") for c in calls] == [False]


def test_the_summary_reads_point_gaps_and_skips_plays_of_zero() -> None:
    """A point joint's play is its gap; a contact with no play (always "full")
    is not the play used most."""
    model = jointplay.load(STUDIES / "wobbly_table.yaml")
    html = Report(studies=False).render(model, "wobbly_table.yaml")
    plays = html[html.index("Plays the nominal solve used") : html.index(">Model</h2>")]
    points = [j for j in model.joints if j.type_name == "point"]
    assert points and all(f"<td>{j.name}</td><td>gap</td>" in plays for j in points)
    assert "<td>clearance</td><td>0 mm</td>" not in plays
    result = jointplay.solve(model)
    with_play = [
        c.gap_used
        for j in model.joints
        for cone, c in zip(j.cones, result.joints[j.name].contacts, strict=True)
        if cone.kind == "ball" and cone.radius > 0
    ]
    assert f"{100 * max(with_play):.1f} %" in html[html.index(">Summary</h2>") :]


def test_a_model_with_a_motion_is_summed_up_over_the_motion_and_at_its_written_pose() -> None:
    """The slider-crank passes at the pose written in the file (0 deg) and
    fails over most of its turn: the summary says how many steps fail and
    the worst, and labels its single-pose figures with their pose (they once
    read "all pass" unqualified); its gas-force table is shown as a table,
    not as the one value a solve at 0 deg reads (-1500 N)."""
    import html as html_lib

    from jointplay.studies.motion import Motion

    crank = ROOT / "examples" / "gallery" / "slider_crank.yaml"
    model = jointplay.load(crank)
    page = html_lib.unescape(Report(samples=500, seed=0).render(model, "slider_crank.yaml"))
    motion = Motion().run(model)
    failing = int(np.sum(motion.measured[:, 0] > motion.limits[0]))
    worst = motion.worst_step(0)
    assert 0 < failing < motion.steps
    summary = page[page.index("<h2>Summary</h2>") : page.index("Model</h2>")]
    assert "At a glance at the pose written in the file" in summary
    assert (
        f"1 of 1 requirements FAIL: piston top at {failing} of {motion.steps} steps, worst at "
        f"step {worst} ({motion.shown_value(worst):g} deg): "
        f"{motion.measured[worst, 0]:.6g} mm against 0.05 mm"
    ) in summary
    assert "At the pose written in the file, over the tolerances: worst case" in summary
    assert "<h2>Solution (at the pose written in the file)</h2>" in page
    assert "The studies below are at the pose written in the file ('main bearing' at 0 deg" in page
    every_pose = page[page.index("Requirements at every pose") :]
    assert f"<td>FAILED at {failing} of {motion.steps} steps</td>" in every_pose
    loads = page[page.index("<caption>Loads</caption>") : page.index("Functional points")]
    assert "<td>x -1500 to -150 over the motion (table below); y 0; z 0</td>" in loads
    assert "(-1500, 0, 0)" not in loads
    row = r"<tr><td>\(every case\)</td><td>piston</td><td>force x \(N\)</td><td>([^<]+)</td>"
    rows = re.findall(row + r"<td>([^<]+)</td></tr>", loads)
    table = model.loads[0].force[0]
    given = zip(table.drive, table.value, strict=True)
    assert rows == [(f"{np.degrees(d):g}", f"{v:g}") for d, v in given]


def test_a_load_range_is_shown_as_its_range() -> None:
    """A load component given as a range is shown as one, not as the mean a
    nominal solve takes."""
    data = jointplay.load(ROOT / "examples" / "gallery" / "four_bar.yaml").model_dump(
        by_alias=True, exclude_none=True
    )
    del data["motion"]
    model = model_from_dict(data, source="four_bar")
    page = Report(studies=False).render(model, "four_bar")
    assert "<td>x 0; y -20 to -10 N (uniform); z -4 to 4 N (uniform)</td>" in page
    assert "pose written" not in page  # one pose only: nothing to tell it from
