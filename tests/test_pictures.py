"""Pictures: the scene is faithful to the solution, and every figure kind draws.

The scene's geometry is checked against the result (a touching contact's
point lies on its magnified clearance domain, a free one inside); then every
figure kind is rendered on the bundled examples, to PNG, SVG and PDF, from
the API and from the command line.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch
from matplotlib.text import Text
from matplotlib.transforms import Bbox
from PIL import Image
from typer.testing import CliRunner

import jointplay
from conftest import MM, PAPER, ROOT, force_tol
from jointplay.cli import app
from jointplay.present.plot import (
    STRIP,
    clearance_figure,
    contributions_figure,
    envelope_figure,
    mechanism_figure,
    montecarlo_figure,
    most_loaded_joints,
    save,
    sweep_figure,
    tolerances_figure,
    with_play,
)
from jointplay.present.scene import (
    CIRCLE_POINTS,
    auto_magnify,
    joint_view,
    mechanism_scene,
    nice_factor,
)
from jointplay.studies.contributions import Contributions
from jointplay.studies.envelope import Envelope
from jointplay.studies.montecarlo import MonteCarlo
from jointplay.studies.sweep import RotateLoad, Sweep
from jointplay.studies.tolerances import Tolerances

STUDIES = ROOT / "examples" / "studies"
GALLERY = ROOT / "examples" / "gallery"
EVERY_EXAMPLE = (
    sorted(PAPER.glob("*.yaml")) + sorted(STUDIES.glob("*.yaml")) + sorted(GALLERY.glob("*.yaml"))
)


@pytest.fixture(autouse=True)
def _close_figures() -> Iterator[None]:
    """Each test's figures closed after it (a figure left open holds its memory)."""
    yield
    plt.close("all")


def _paper() -> tuple[jointplay.Model, jointplay.Result]:
    model = jointplay.load(PAPER / "6.1.6.1.yaml")
    return model, jointplay.solve(model)


#: Pixels by which two texts' boxes may meet up and down: a box holds the
#: font's blank ascent and descent, so lines this close do not touch; across,
#: a box is as wide as its letters, and one pixel is anti-aliasing.
TEXT_SLACK = 3.0
SIDE_SLACK = 1.0


def _drawn_texts(fig: Figure) -> list[tuple[Text, Bbox]]:
    """Every text the renderer draws (not the tick labels matplotlib keeps
    beyond the axis limits), with its box in pixels."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    drawn: list[Text] = []
    draw_text = renderer.draw_text

    def record(*args: Any, **kwargs: Any) -> Any:
        text = kwargs.get("mtext")
        if isinstance(text, Text) and text.get_text().strip() and text not in drawn:
            drawn.append(text)
        return draw_text(*args, **kwargs)

    renderer.draw_text = record
    try:
        fig.draw(renderer)
    finally:
        del renderer.draw_text
    return [(t, t.get_window_extent(renderer)) for t in drawn]


def _meet(a: Bbox, b: Bbox, up: float = TEXT_SLACK, side: float = SIDE_SLACK) -> bool:
    return min(a.x1, b.x1) - max(a.x0, b.x0) > side and min(a.y1, b.y1) - max(a.y0, b.y0) > up


def layout_faults(fig: Figure) -> list[str]:
    """What a reader would see run together: a text outside the figure; two
    texts over each other (a slanted 3D axis label's box is wider than its
    letters: it is held clear of the other panels' texts only); a panel's
    text over another panel; a legend over a panel; a view at true scale
    thinner than ``STRIP`` of its width."""
    texts = _drawn_texts(fig)
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    owner = {id(t): ax for ax in fig.axes for t in ax.findobj(Text)}
    frames = [(ax, ax.get_window_extent(renderer)) for ax in fig.axes]
    faults = []
    for text, box in texts:
        if not _within(fig.bbox, box, slack=1.0):
            faults.append(f"outside the figure: {text.get_text()!r}")
        for ax, frame in frames:
            if owner.get(id(text)) not in (ax, None) and _meet(box, frame):
                faults.append(f"{text.get_text()!r} over the panel {ax.get_title()!r}")
    for i, (a, box_a) in enumerate(texts):
        for b, box_b in texts[i + 1 :]:
            slanted = a.get_rotation() % 90 or b.get_rotation() % 90
            if slanted and owner.get(id(a)) is owner.get(id(b)):
                continue  # a 3D axis label's box is wider than its letters
            if _meet(box_a, box_b):
                faults.append(f"{a.get_text()!r} over {b.get_text()!r}")
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]
    for legend in legends:
        box = legend.get_window_extent(renderer)
        faults += [
            f"a legend over {ax.get_title()!r}" for ax, f in frames if _meet(box, f, 1.0, 1.0)
        ]
    for ax, frame in frames:
        thin = min(frame.width, frame.height) < STRIP * max(frame.width, frame.height) - 1
        if ax.name == "rectilinear" and ax.get_aspect() == 1.0 and thin:
            faults.append(f"the view {ax.get_title()!r} is a strip")
    return faults


def _not_blank(path: Path) -> None:
    """The PNG has a drawing on it: many pixels that are not the background."""
    image = np.asarray(Image.open(path).convert("L"))
    assert image.shape[0] > 300 and image.shape[1] > 300
    assert np.count_nonzero(image < 200) > 0.01 * image.size


# -- the scene is the solution, exaggerated --------------------------------------------
def test_nice_factors() -> None:
    assert [nice_factor(v) for v in (0.5, 1, 1.9, 2, 4.99, 5, 9.9, 10, 141, 999)] == [
        1,
        1,
        1,
        2,
        2,
        5,
        5,
        10,
        100,
        500,
    ]
    assert auto_magnify(300.0, 0.0) == 1.0  # nothing moves: true size
    # 8 % of 300 mm over 0.177 mm is 136: the round factor below is 100
    assert auto_magnify(300.0, 0.1769621435287896) == 100.0


def test_the_paper_scene_places_every_point_by_the_solution() -> None:
    model, result = _paper()
    m = 100.0
    scene = mechanism_scene(model, result, magnify=m)
    assert scene.magnify == m and scene.size == pytest.approx(300.0, abs=MM)
    d = result.bodies["S1"].displacement_of
    # the shaft is one line O - B along its axis, initial and displaced
    initial = [ln.points for ln in scene.lines if ln.role == "initial"]
    displaced = [ln.points for ln in scene.lines if ln.role == "displaced"]
    assert len(initial) == len(displaced) == 1
    np.testing.assert_allclose(initial[0], [[0, 0, 0], [300, 0, 0]], atol=MM)
    for before, after in zip(initial, displaced, strict=True):
        for P, Q in zip(before, after, strict=True):
            np.testing.assert_allclose(Q, P + m * d(P), atol=MM)
    B = next(mk for mk in scene.markers if mk.role == "load point").at
    np.testing.assert_allclose(B, [300, 0, 0] + m * d(np.array([300.0, 0, 0])), atol=MM)


def test_contact_points_sit_on_or_inside_their_magnified_domains() -> None:
    model, result = _paper()
    m = 100.0
    scene = mechanism_scene(model, result, magnify=m)
    rings = [ln.points for ln in scene.lines if ln.role == "domain" and len(ln.points) == 73]
    marks = {mk.label: mk for mk in scene.markers if mk.role in ("touching", "free")}
    assert set(marks) == {"l1 ball", "l2 end-", "l2 end+"}
    # l2's end+ circle: centre (220, 0, 0) (S0 does not move), radius m J/2 = 10 mm
    end_plus = next(r for r in rings if abs(r[:, 0].mean() - 220.0) < 1e-9)
    centre = end_plus[:-1].mean(axis=0)
    np.testing.assert_allclose(np.linalg.norm(end_plus - centre, axis=1), 10.0, atol=MM)
    # b's axis point is on the circle across the axis (it may slide along it)
    touching = marks["l2 end+"]
    assert touching.role == "touching"
    # (the answer's positions to MM, magnified m times)
    np.testing.assert_allclose(np.linalg.norm((touching.at - centre)[1:]), 10.0, atol=m * MM)
    assert marks["l2 end-"].role == "free"
    assert np.linalg.norm(marks["l2 end-"].at[1:]) == pytest.approx(
        10.0 * result.joints["l2"].contacts[0].gap_used, abs=1e-9 * m
    )
    # l1's sphere: the ball's centre on its surface, m J1/2 from O
    assert marks["l1 ball"].role == "touching"
    assert np.linalg.norm(marks["l1 ball"].at) == pytest.approx(10.0, abs=m * MM)


def test_arrows_are_the_forces_at_one_scale() -> None:
    model, result = _paper()
    scene = mechanism_scene(model, result)
    loads = [a for a in scene.arrows if a.role == "load"]
    forces = [a for a in scene.arrows if a.role == "contact force"]
    assert len(loads) == 1 and loads[0].magnitude == pytest.approx(3**0.5)
    np.testing.assert_allclose(loads[0].vector, scene.force_scale * np.ones(3), atol=MM)
    # the touching contacts' forces, in global axes, balance the load
    total = sum(a.vector for a in forces) / scene.force_scale
    np.testing.assert_allclose(total + np.ones(3), 0.0, atol=force_tol(result))
    assert {a.label for a in forces} == {"l1 ball", "l2 end+"}
    biggest = max(np.linalg.norm(a.vector) for a in scene.arrows)
    assert biggest == pytest.approx(0.18 * scene.size)


def test_joint_views_at_true_size() -> None:
    model, result = _paper()
    l1, l2 = (joint_view(j, result.joints[j.name]) for j in model.joints)
    # a sphere is cut at the contact point's dx: the touching ball lies on that section
    (ball,) = l1.points
    dx = float((result.joints["l1"].translation)[0])
    assert l1.plane == "yz" and l1.circles == (pytest.approx((np.sqrt(0.1**2 - dx**2), True)),)
    assert ball.touching and np.hypot(*ball.at) == pytest.approx(l1.circles[0][0], abs=MM)
    assert l2.circles == ((0.1, False),)
    end_minus, end_plus = l2.points
    assert end_plus.touching and not end_minus.touching
    assert np.hypot(*end_plus.at) == pytest.approx(0.1, abs=MM)
    t, w = result.joints["l2"].translation, result.joints["l2"].rotation
    expected = t + np.cross(w, [20.0, 0, 0])
    np.testing.assert_allclose(end_plus.at, expected[1:], atol=MM)


def test_views_of_every_joint_type() -> None:
    model = jointplay.load(GALLERY / "lathe_slide.yaml")
    result = jointplay.solve(model)
    views = {j.name: joint_view(j, result.joints[j.name]) for j in model.joints}
    guide = views["guide"]  # prismatic: a rectangle of the half plays (y, z)
    assert guide.rectangle == pytest.approx((0.02, 0.015))
    for p in guide.points:
        assert abs(p.at[0]) <= 0.02 + MM and abs(p.at[1]) <= 0.015 + MM
    thrust = views["thrust"]  # planar disc: seen across, walls at +-J/2
    assert thrust.plane == "x-across" and thrust.walls == pytest.approx((-0.03, 0.03))
    assert [p.touching for p in thrust.points] == [
        c.in_contact for c in result.joints["thrust"].contacts
    ]
    bearing = views["bearing"]  # revolute: the circle, and the axial stop in words
    assert bearing.circles == ((0.01, False),) and "axial (along x)" in bearing.note
    assert views["tail"].circles == ((0.015, False),)
    assert views["holder"].plane == "none" and views["holder"].note == "rigid: no play"
    table = jointplay.load(STUDIES / "wobbly_table.yaml")
    leaning = jointplay.solve(table, case="leaning on foot4")
    foot4 = joint_view(table.joint("foot4"), leaning.joints["foot4"])
    assert foot4.walls == pytest.approx((-0.05,))  # the plane, 50 um below the short foot
    assert foot4.points[0].touching and foot4.points[0].at[0] == pytest.approx(-0.05, abs=MM)


def test_magnify_one_is_true_size_and_rings_are_circles() -> None:
    model, result = _paper()
    scene = mechanism_scene(model, result, magnify=1.0)
    for ln in scene.lines:
        if ln.role == "domain" and len(ln.points) == CIRCLE_POINTS:
            r = np.linalg.norm(ln.points - ln.points[:-1].mean(axis=0), axis=1)
            np.testing.assert_allclose(r, 0.1, atol=MM)


# -- every figure kind draws ------------------------------------------------------------
@pytest.mark.parametrize("path", EVERY_EXAMPLE, ids=lambda p: p.name)
def test_the_mechanism_figure_of_every_example(path: Path, tmp_path: Path) -> None:
    model = jointplay.load(path)
    cases = list(model.case_names) or [None]
    for case in cases:
        result = jointplay.solve(model, case=case)
        figure = mechanism_figure(model, result, case=case)
        assert layout_faults(figure) == [], case
        _not_blank(save(figure, tmp_path / "m.png"))
        joints = clearance_figure(model, result)
        assert layout_faults(joints) == [], case
        _not_blank(save(joints, tmp_path / "j.png"))


@pytest.mark.parametrize("suffix", [".png", ".svg", ".pdf"])
def test_every_format(suffix: str, tmp_path: Path) -> None:
    model, result = _paper()
    out = save(mechanism_figure(model, result), tmp_path / f"figure{suffix}")
    head = out.read_bytes()[:200]
    assert {".png": b"\x89PNG", ".svg": b"<?xml", ".pdf": b"%PDF"}[suffix] in head


def test_study_figures(tmp_path: Path) -> None:
    fits = jointplay.load(STUDIES / "shaft_fits.yaml")
    env = Envelope("B").run(fits)
    _not_blank(save(envelope_figure(env), tmp_path / "envelope.png"))
    mc = MonteCarlo(samples=2000, seed=1).run(fits)
    _not_blank(save(montecarlo_figure(mc), tmp_path / "montecarlo.png"))
    co = Contributions().run(fits)
    _not_blank(save(contributions_figure(co), tmp_path / "contributions.png"))
    unbalance = jointplay.load(STUDIES / "rotating_unbalance.yaml")
    sweep = Sweep(rotate=RotateLoad(0, (1.0, 0.0, 0.0), 24)).run(unbalance)
    envelopes = {"B": Envelope("B", plays="mean").run(unbalance)}
    # every step of the turn lies inside (here: on) the point's envelope
    assert np.all(envelopes["B"].contains(sweep.point("B"), tol=1e-9))
    _not_blank(save(sweep_figure(sweep, envelopes), tmp_path / "sweep.png"))
    _not_blank(save(sweep_figure(sweep), tmp_path / "sweep_alone.png"))


# -- the command line -------------------------------------------------------------------------
def test_plot_command(tmp_path: Path) -> None:
    out = tmp_path / "shaft.png"
    run = CliRunner().invoke(app, ["plot", str(PAPER / "6.1.6.1.yaml"), "-o", str(out)])
    assert run.exit_code == 0, run.output
    _not_blank(out)
    joints = tmp_path / "joints.svg"
    run = CliRunner().invoke(
        app, ["plot", str(PAPER / "6.1.6.1.yaml"), "-o", str(joints), "--kind", "joints"]
    )
    assert run.exit_code == 0 and joints.read_text().count("<svg") == 1
    table = tmp_path / "table.pdf"
    run = CliRunner().invoke(app, ["plot", str(STUDIES / "wobbly_table.yaml"), "-o", str(table)])
    assert run.exit_code == 0 and table.read_bytes().startswith(b"%PDF")
    assert "drew load case 'resting', the first" in run.output  # said, not silent


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-o", "{tmp}/a.jpg"], "name the file .png, .svg or .pdf"),
        (["-o", "{tmp}/no/such/a.png"], "does not exist; create it"),
        (["-o", "{tmp}/a.png", "--kind", "3d"], "--kind '3d': expected 'mechanism' or 'joints'"),
        (["-o", "{tmp}/a.png", "--magnify", "0"], "--magnify 0: expected a factor above 0"),
        (["-o", "{tmp}/a.png", "--case", "nope"], "no load case 'nope'"),
    ],
)
def test_plot_bad_input_exits_2(args: list[str], message: str, tmp_path: Path) -> None:
    argv = ["plot", str(PAPER / "6.1.6.1.yaml"), *[a.format(tmp=tmp_path) for a in args]]
    run = CliRunner().invoke(app, argv)
    assert run.exit_code == 2, run.output
    assert message in run.output and "Traceback" not in run.output
    assert not list(tmp_path.glob("a.*"))


def test_plot_of_a_mechanism_not_held_exits_3(tmp_path: Path) -> None:
    path = tmp_path / "spin.yaml"
    path.write_text(
        """
bodies: [{name: housing, ground: true}, {name: shaft}]
joints:
  - {name: l1, type: spherical, between: [housing, shaft], at: [0, 0, 0], clearance: 0.2}
loads:
  - {body: shaft, torque: ["1 N*m", 0, 0]}
"""
    )
    run = CliRunner().invoke(app, ["plot", str(path), "-o", str(tmp_path / "a.png")])
    assert run.exit_code == 3 and "is not held by any joint" in run.output
    assert not (tmp_path / "a.png").exists()


def test_plot_option_of_every_study(tmp_path: Path) -> None:
    fits, unbalance = str(STUDIES / "shaft_fits.yaml"), str(STUDIES / "rotating_unbalance.yaml")
    for argv, name in (
        (["montecarlo", fits, "-n", "500"], "mc.png"),
        (["envelope", fits, "--point", "B"], "env.svg"),
        (["contributions", fits], "co.pdf"),
        (["sweep", unbalance, "--rotate-load", "0", "--about", "x", "--steps", "12"], "sw.png"),
    ):
        out = tmp_path / name
        run = CliRunner().invoke(app, [*argv, "--plot", str(out)])
        assert run.exit_code == 0, run.output
        assert out.stat().st_size > 10_000
    # a bad figure name is refused before the study runs
    run = CliRunner().invoke(app, ["montecarlo", fits, "--plot", str(tmp_path / "x.gif")])
    assert run.exit_code == 2 and "--plot" in run.output and "name the file .png" in run.output


def test_a_large_mechanism_shows_its_most_loaded_joints(tmp_path: Path) -> None:
    from jointplay.io.generate import tube_string
    from jointplay.present.plot import JOINT_VIEWS_SHOWN, most_loaded_joints

    model = tube_string(30, closed=True)
    result = jointplay.solve(model)
    chosen = most_loaded_joints(model, result, JOINT_VIEWS_SHOWN)
    assert len(chosen) == JOINT_VIEWS_SHOWN
    force = {n: float(np.linalg.norm(j.reaction_force)) for n, j in result.joints.items()}
    assert min(force[n] for n in chosen) >= max(force[n] for n in force if n not in chosen)
    assert chosen == [j.name for j in model.joints if j.name in chosen]  # the model's order
    fig = mechanism_figure(model, result)
    assert f"the views of the 8 most loaded of {len(model.joints)} joints" in fig.get_suptitle()
    _not_blank(save(fig, tmp_path / "string.png"))
    some = clearance_figure(model, result, joints=chosen[:3])
    assert "(3 of" in some.get_suptitle()
    _not_blank(save(some, tmp_path / "three.png"))


def test_a_figure_that_cannot_be_written_exits_2(tmp_path: Path) -> None:
    (tmp_path / "taken.png").mkdir()  # a folder where the file should go
    run = CliRunner().invoke(
        app, ["plot", str(PAPER / "6.1.6.1.yaml"), "-o", str(tmp_path / "taken.png")]
    )
    assert run.exit_code == 2 and "cannot write it" in run.output
    assert "Traceback" not in run.output


def test_joint_views_name_their_axes_globally_and_leave_out_rigid_joints(tmp_path: Path) -> None:
    """A joint seen along its axis says which global direction each of its
    axes is; a rigid joint has no play to show and gets no panel."""
    model = jointplay.load(ROOT / "examples" / "gallery" / "lathe_slide.yaml")
    result = jointplay.solve(model)
    bearing = joint_view(model.joint("bearing"), result.joints["bearing"])
    R = result.joints["bearing"].R_world_joint
    expected = []
    for i in range(3):
        (k,) = np.flatnonzero(np.abs(R[:, i]) > 0.5)
        expected.append(f"global {'+' if R[k, i] > 0 else '-'}{'XYZ'[k]}")
    assert bearing.axes == tuple(expected)
    fig = clearance_figure(model, result)
    labels = [ax.get_xlabel() for ax in fig.axes] + [ax.get_ylabel() for ax in fig.axes]
    assert f"y (mm): {expected[1]}" in labels and f"z (mm): {expected[2]}" in labels
    titles = [ax.get_title() for ax in fig.axes]
    assert "holder (rigid)" not in titles and len(titles) == len(model.joints) - 1
    assert "holder" not in most_loaded_joints(model, result, 100)
    _not_blank(save(fig, tmp_path / "joints.png"))


@pytest.mark.parametrize(
    ("largest", "expected"), [(37.0, 20.0), (0.26, 0.2), (5.0, 5.0), (9.99, 5.0)]
)
def test_the_reference_arrow_is_a_round_force(largest: float, expected: float) -> None:
    from jointplay.present.plot import round_force

    assert round_force(largest) == pytest.approx(expected)


def test_the_mechanism_figure_carries_a_reference_arrow() -> None:
    """One black arrow of a round force, in the XY view, as long as that force
    at the arrows' scale."""
    from jointplay.present.plot import round_force

    model = jointplay.load(PAPER / "6.1.6.1.yaml")
    result = jointplay.solve(model)
    scene = mechanism_scene(model, result)
    fig = mechanism_figure(model, result)
    xy = next(ax for ax in fig.axes if ax.get_title() == "XY (along Z)")
    arrows = [t for t in xy.texts if t.arrow_patch is not None]
    assert len(arrows) == 1
    (x1, y1), (x0, y0) = arrows[0].xy, arrows[0].xyann
    label = next(t.get_text() for t in xy.texts if t.get_text().endswith(" N"))
    force = float(label.split()[0])
    assert force == round_force(force * 1.000001)  # a round value
    assert x1 - x0 == pytest.approx(force * scene.force_scale) and y1 == y0


def test_a_body_with_an_outline_is_drawn_as_that_closed_outline() -> None:
    model = jointplay.load(STUDIES / "wobbly_table.yaml")
    result = jointplay.solve(model, case="leaning on foot4")
    m = 200.0
    scene = mechanism_scene(model, result, magnify=m, case="leaning on foot4")
    corners = np.array(model.body("table").outline)
    initial = [ln.points for ln in scene.lines if ln.role == "initial" and ln.label == "table"]
    displaced = [ln.points for ln in scene.lines if ln.role == "displaced" and ln.label == "table"]
    assert len(initial) == len(displaced) == 1  # one line, not a tree through the joints
    np.testing.assert_allclose(initial[0], np.vstack([corners, corners[:1]]), atol=MM)
    d = result.bodies["table"].displacement_of
    for P, Q in zip(initial[0], displaced[0], strict=True):
        np.testing.assert_allclose(Q, P + m * d(P), atol=MM)
    low, high = scene.bounds()
    assert np.all(low <= corners.min(axis=0)) and np.all(high >= corners.max(axis=0))


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"outline": [[0, 0, 0]]}, "'outline' needs at least two points"),
        ({"outline": [[0, 0, 0], [1, 0, 0]], "ground": True}, "a ground body is not drawn"),
        ({"outline": [[0, 0, 0], [1, 0]]}, "outline"),
    ],
)
def test_a_bad_outline_is_refused(changes: dict[str, object], message: str, tmp_path: Path) -> None:
    import yaml

    data = yaml.safe_load((PAPER / "6.1.6.1.yaml").read_text())
    data["bodies"][1].update(changes)
    path = tmp_path / "outline.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(jointplay.ModelError, match=message):
        jointplay.load(path)


def test_an_outline_reads_lengths_with_units(tmp_path: Path) -> None:
    import yaml

    data = yaml.safe_load((PAPER / "6.1.6.1.yaml").read_text())
    data["bodies"][1]["outline"] = [[0, 0, 0], ["0.3 m", 0, "5 cm"]]
    path = tmp_path / "outline.yaml"
    path.write_text(yaml.safe_dump(data))
    body = jointplay.load(path).body(data["bodies"][1]["name"])
    assert body.outline is not None
    np.testing.assert_allclose(np.array(body.outline), [[0, 0, 0], [300, 0, 50]], atol=MM)


@pytest.mark.parametrize(
    ("names", "label"),
    [
        (
            [
                "y x- z-",
                "y x- z+",
                "y x+ z-",
                "y x+ z+",
                "z x- y-",
                "z x- y+",
                "z x+ y-",
                "z x+ y+",
            ],
            "y x± z±, z x± y±",
        ),
        (["end-", "end+"], "end±"),
        (["face x-", "radial"], "face x-, radial"),
        (["y x- z-", "y x+ z+"], "y x- z-, y x+ z+"),  # two words differ: both named
    ],
)
def test_contacts_at_one_place_get_one_short_label(names: list[str], label: str) -> None:
    from jointplay.present.scene import ViewPoint, _merged

    points = [ViewPoint((0.01, -0.02), name, i == 0) for i, name in enumerate(names)]
    (merged,) = _merged(points, 1e-9)
    assert merged.label == label and merged.touching and merged.at == (0.01, -0.02)


@pytest.mark.parametrize(
    ("path", "case"),
    [
        (STUDIES / "carriage.yaml", None),  # eight guide contacts at one corner
        (GALLERY / "lathe_slide.yaml", None),  # labels near the panels' edges
        (STUDIES / "wobbly_table.yaml", "leaning on foot4"),  # a plate, five joints
    ],
    ids=["carriage", "lathe-slide", "wobbly-table"],
)
def test_joint_panel_labels_stay_inside_their_panels(path: Path, case: str | None) -> None:
    """Each contact's label and each note is drawn inside its joint panel (it
    used to run into the next panel, or past the frame)."""
    model = jointplay.load(path)
    result = jointplay.solve(model, case=case)
    fig = clearance_figure(model, result)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    checked = 0
    for ax in fig.axes:
        box = ax.get_window_extent(renderer)
        for text in ax.texts:
            if not text.get_text():
                continue
            inside = text.get_window_extent(renderer)
            slack = 2.0  # pixels: anti-aliasing at the frame
            assert inside.x0 >= box.x0 - slack and inside.x1 <= box.x1 + slack, text.get_text()
            assert inside.y0 >= box.y0 - slack and inside.y1 <= box.y1 + slack, text.get_text()
            checked += 1
    assert checked >= len(with_play(model))  # a label at least per joint panel


# -- the layout: everything inside its panel, nothing over anything else -----------------
def _gear_shaft() -> jointplay.Model:
    """A shaft on two bearings along x, its gear's mesh point 50 mm off the
    axis, with four functional points crowded on the axis at the shaft's end."""
    from jointplay import model_from_dict

    ends = [[300, 0, 0], [301, 0, 0], [300.5, 0, 0], [301.5, 0, 0]]
    names = ["top corner", "latch", "tool", "probe"]
    return model_from_dict(
        {
            "bodies": [{"name": "housing", "ground": True}, {"name": "shaft"}],
            "joints": [
                {
                    "name": "front",
                    "type": "spherical",
                    "between": ["housing", "shaft"],
                    "at": [0, 0, 0],
                    "clearance": 0.02,
                },
                {
                    "name": "rear",
                    "type": "cylindrical",
                    "between": ["housing", "shaft"],
                    "at": [200, 0, 0],
                    "axis": [1, 0, 0],
                    "length": 40,
                    "clearance": 0.03,
                },
            ],
            "loads": [{"body": "shaft", "at": [100, 50, 0], "force": [0, -200, 0]}],
            "points": [
                {"name": n, "body": "shaft", "at": P} for n, P in zip(names, ends, strict=True)
            ],
        }
    )


def _within(frame: object, box: object, slack: float = 2.0) -> bool:
    return bool(
        box.x0 >= frame.x0 - slack  # type: ignore[attr-defined]
        and box.x1 <= frame.x1 + slack  # type: ignore[attr-defined]
        and box.y0 >= frame.y0 - slack  # type: ignore[attr-defined]
        and box.y1 <= frame.y1 + slack  # type: ignore[attr-defined]
    )


def test_crowded_point_labels_stay_in_their_panels_and_clear_of_each_other() -> None:
    """Four points within a millimetre: in each view their labels do not
    overlap and stay inside the panel; those that cannot fit are numbered and
    named in the legend."""
    model = _gear_shaft()
    fig = mechanism_figure(model, jointplay.solve(model), joints=False)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    names = {p.name for p in model.points}
    numbers = {str(k) for k in range(1, len(names) + 1)}
    for ax in fig.axes:
        frame = ax.get_window_extent(renderer)
        labels = [t for t in ax.texts if (t.get_gid() or "").startswith("point ")]
        labels = [t for t in labels if t.get_text()]  # a number may join another's: '3,4'
        if not labels:
            continue
        written = [w for t in labels for w in t.get_text().split(",")]
        assert sorted(written) == sorted(set(written)) and len(written) >= len(names)
        boxes = [t.get_window_extent(renderer) for t in labels]
        for text, box in zip(labels, boxes, strict=True):
            assert set(text.get_text().split(",")) <= names | numbers or text.get_text() in names
            assert _within(frame, box), (ax.get_title(), text.get_text())
        for i, a in enumerate(boxes):
            for b in boxes[i + 1 :]:
                assert not a.overlaps(b), ax.get_title()
        legend = [t.get_text() for t in fig.legends[0].get_texts()]
        for number in set(written) & numbers:  # a number stands for its point, named in the legend
            assert model.points[int(number) - 1].name in legend


def test_the_envelope_arrow_stays_inside_its_view() -> None:
    """The carriage's tool moves a way its envelope does not hold the rest
    position in: the largest displacement's arrow, from the rest position,
    lies inside each view (it used to cross into the 3D panel)."""
    model = jointplay.load(STUDIES / "carriage.yaml")
    fig = envelope_figure(Envelope("tool", directions=24).run(model))
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    arrows = 0
    for ax in fig.axes[1:]:
        frame = ax.get_window_extent(renderer)
        for patch in ax.patches:
            if isinstance(patch, FancyArrowPatch):
                assert patch.get_clip_on() and patch.get_clip_box() is not None
                assert _within(frame, patch.get_window_extent(renderer)), ax.get_title()
                arrows += 1
    assert arrows == len(fig.axes) - 1 >= 1  # one in each view (here the XY view: it is flat)


def test_panels_do_not_overlap() -> None:
    """No panel's drawn box, its tick and axis labels included (the 3D panel's
    'Z (mm)' used to sit on the YZ view's), meets another's."""
    model, result = _paper()
    fig = mechanism_figure(model, result)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    boxes = [(ax.get_title(), ax.get_tightbbox(renderer)) for ax in fig.axes]
    for i, (name, a) in enumerate(boxes):
        for other, b in boxes[i + 1 :]:
            assert not a.overlaps(b), (name, other)


def test_a_planar_mechanism_has_no_edge_on_view() -> None:
    """The four-bar lies in XY: its XZ and YZ views would be lines with every
    arrow on them; only the XY view is drawn beside the 3D panel."""
    model = jointplay.load(GALLERY / "four_bar.yaml")
    fig = mechanism_figure(model, jointplay.solve(model), joints=False)
    titles = [ax.get_title() for ax in fig.axes]
    assert "XY (along Z)" in titles
    assert "XZ (along -Y)" not in titles and "YZ (along X)" not in titles
    carriage = jointplay.load(STUDIES / "carriage.yaml")  # a solid one: every view
    fig = mechanism_figure(carriage, jointplay.solve(carriage), joints=False)
    assert {"XY (along Z)", "XZ (along -Y)", "YZ (along X)"} <= {ax.get_title() for ax in fig.axes}


def test_a_shaft_without_outline_is_drawn_along_its_axis() -> None:
    """The shaft's joints lie on one straight line (its axis), and the load's
    point 50 mm off it hangs on a stub square to the axis: not a V."""
    model = _gear_shaft()
    scene = mechanism_scene(model, jointplay.solve(model))
    initial = [ln.points for ln in scene.lines if ln.role == "initial"]
    axis = max(initial, key=lambda P: float(np.linalg.norm(P[-1] - P[0])))
    u = (axis[-1] - axis[0]) / np.linalg.norm(axis[-1] - axis[0])
    for joint in model.joints:  # every joint on the axis line
        off = joint.centre - axis[0]
        assert np.linalg.norm(off - (off @ u) * u) < MM
    mesh = np.array([100.0, 50.0, 0.0])
    (stub,) = [P for P in initial if np.allclose(P[-1], mesh)]
    assert abs((stub[-1] - stub[0]) @ u) < MM  # square to the axis
    off = stub[0] - axis[0]
    assert np.linalg.norm(off - (off @ u) * u) < MM  # from a point on it
    assert len(initial) == 2  # the axis and the stub: the points on the axis need none


# -- every study figure: texts apart, legends off the panels, no edge-on view -----------------
def _sweep_with_envelopes(path: Path) -> Figure:
    from jointplay.studies.envelope import point_envelopes

    model = jointplay.load(path)
    sweep = Sweep(rotate=RotateLoad(0, (0.0, 0.0, 1.0), 12)).run(model)
    envelopes, _ = point_envelopes(model, "mean")
    return sweep_figure(sweep, envelopes)


@pytest.mark.parametrize(
    "draw",
    [
        lambda: envelope_figure(
            Envelope("fingertip").run(jointplay.load(GALLERY / "four_bar.yaml"))
        ),
        lambda: envelope_figure(Envelope("tool").run(jointplay.load(STUDIES / "carriage.yaml"))),
        lambda: envelope_figure(
            Envelope("probe").run(jointplay.load(STUDIES / "wobbly_table.yaml"))
        ),
        lambda: _sweep_with_envelopes(STUDIES / "carriage.yaml"),
        lambda: _sweep_with_envelopes(GALLERY / "located_plate.yaml"),
        lambda: montecarlo_figure(
            MonteCarlo(samples=300, seed=0).run(jointplay.load(GALLERY / "spindle.yaml"))
        ),
        lambda: tolerances_figure(Tolerances(300, 0).run(jointplay.load(GALLERY / "spindle.yaml"))),
        lambda: tolerances_figure(
            Tolerances(300, 0).run(jointplay.load(GALLERY / "located_plate.yaml"))
        ),
        lambda: contributions_figure(
            Contributions().run(jointplay.load(GALLERY / "four_bar.yaml"))
        ),
    ],
    ids=[
        "envelope-four-bar",
        "envelope-carriage",
        "envelope-table",
        "sweep-carriage",
        "sweep-plate",
        "montecarlo-spindle",
        "tolerances-spindle",
        "tolerances-plate",
        "contributions-four-bar",
    ],
)
def test_study_figures_keep_texts_apart_and_legends_off_the_panels(draw: Any) -> None:
    """No text outside the figure or over another, no legend over a curve's
    panel (the sweep's contact forces, the tolerances' five entries used to
    cover the curves), no view at true scale a strip."""
    figure = draw()
    assert layout_faults(figure) == []


def _views(fig: Figure) -> list[str]:
    """The titles' first lines of a figure's 2D views."""
    return [ax.get_title().split("\n")[0] for ax in fig.axes if ax.name == "rectilinear"]


def test_a_flat_envelope_is_its_outline_in_its_plane() -> None:
    """The carriage's tool moves in a plane normal to Z (the guide's vertical
    play is taken up by the weight): its XZ and YZ views would be lines and
    are left out; the 3D panel draws the envelope as one polygon of its own
    points, in that plane."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from jointplay.present.plot import _flat_polygon

    env = Envelope("tool", directions=24).run(jointplay.load(STUDIES / "carriage.yaml"))
    low, high = env.extent[2]
    assert high - low < 1e-3 * (env.extent[0, 1] - env.extent[0, 0])  # flat, as said
    fig = envelope_figure(env)
    assert _views(fig) == ["XY (along Z)"]
    assert "dz" in fig.axes[1].get_title()  # the displacement along the normal, said
    assert len([c for c in fig.axes[0].collections if isinstance(c, Poly3DCollection)]) == 1
    ring = _flat_polygon(env.hull)  # that polygon's corners
    assert ring is not None and len(ring) >= 3
    for corner in ring:
        assert np.min(np.linalg.norm(env.hull - corner, axis=1)) < MM  # one of its points
        assert low - MM <= corner[2] <= high + MM


def test_an_envelope_long_along_one_axis_keeps_its_views_across() -> None:
    """The four-bar's fingertip moves 0.8 mm along Z (the push across the
    linkage) and hundredths in X and Y: the XZ view, where it is a line, is
    left out; the XY view, where it has an area, is kept."""
    env = Envelope("fingertip").run(jointplay.load(GALLERY / "four_bar.yaml"))
    views = _views(envelope_figure(env))
    assert "XY (along Z)" in views and "XZ (along -Y)" not in views


def test_a_planar_sweep_draws_only_the_view_of_its_plane() -> None:
    """The plate's hole moves in XY at every step, and so does its envelope:
    its row shows the XY view, and says why XZ and YZ are not drawn."""
    fig = _sweep_with_envelopes(GALLERY / "located_plate.yaml")
    views = [v for v in _views(fig) if v.startswith("drilled hole:")]
    assert views == ["drilled hole: XY (along Z)"]
    notes = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert any("XZ and YZ views" in " ".join(n.split()) for n in notes)


def test_a_carriage_without_outline_is_drawn_along_its_guide() -> None:
    """The carriage's joints' centres (guide and nut) sit on a vertical line,
    but the guide reaches 150 mm either way along X: the carriage is drawn
    through the guide's ends, its nut and its tool, not as a vertical stick."""
    model = jointplay.load(STUDIES / "carriage.yaml")
    scene = mechanism_scene(model, jointplay.solve(model))
    initial = np.vstack([ln.points for ln in scene.lines if ln.role == "initial"])
    assert abs(initial[:, 0].min() + 150.0) < MM and abs(initial[:, 0].max() - 150.0) < MM
    assert np.min(np.linalg.norm(initial - [80.0, 0.0, 150.0], axis=1)) < MM  # the tool
