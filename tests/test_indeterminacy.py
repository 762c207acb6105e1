"""The degree of static indeterminacy of the touching contacts, and which
contacts share the redundant load (``Result.indeterminate``), against counts
made by hand: force unknowns of the touching contacts less the balance
equations they reach. Each case's count is in its docstring."""

from __future__ import annotations

import json
import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

import jointplay
from conftest import PAPER, ROOT
from jointplay.indeterminacy import DETERMINATE
from jointplay.io.modelfile import model_from_dict
from jointplay.numerics import linalg
from jointplay.present.report import Report
from test_cli import run

STUDIES = ROOT / "examples" / "studies"

#: The sentence of ``jointplay solve`` for the door (the text and the report alike).
DOOR_SENTENCE = (
    "Forces: the load shared by hinge1 and hinge2 is split by the equal-springs rule "
    "(statically indeterminate, degree 1); the rigid parts do not decide it; "
    "give `stiffness` for the real split."
)


def door(stiffness: float | None = None) -> dict[str, Any]:
    """A door on two hinges on one vertical axis, 1 m apart, with equal
    axial plays, its weight 400 mm off the axis."""
    hinge = {
        "type": "revolute",
        "between": ["frame", "door"],
        "axis": [0, 0, 1],
        "length": 40,
        "clearance": 0.1,
        "axial_clearance": 0.2,
    }
    if stiffness is not None:
        hinge["stiffness"] = stiffness
    return {
        "name": "door on two hinges",
        "bodies": [{"name": "frame", "ground": True}, {"name": "door"}],
        "joints": [
            {"name": "hinge1", "at": [0, 0, 0], **hinge},
            {"name": "hinge2", "at": [0, 0, 1000], **hinge},
        ],
        "loads": [{"body": "door", "at": [400, 0, 500], "force": [0, 0, -300]}],
    }


def table_on_four_feet() -> dict[str, Any]:
    """A plate on four equal one-sided feet at (+-100, +-100), centred by a
    pin with play, pressed down off its centre."""
    feet = [(100, 100), (-100, 100), (-100, -100), (100, -100)]
    joints: list[dict[str, Any]] = [
        {
            "name": f"foot{i}",
            "type": "point",
            "between": ["floor", "table"],
            "at": [x, y, 0],
            "axis": [0, 0, 1],
        }
        for i, (x, y) in enumerate(feet, start=1)
    ]
    joints.append(
        {
            "name": "pin",
            "type": "sphere_in_cylinder",
            "between": ["floor", "table"],
            "at": [0, 0, 0],
            "axis": [0, 0, 1],
            "clearance": 0.1,
        }
    )
    return {
        "name": "table on four feet",
        "bodies": [{"name": "floor", "ground": True}, {"name": "table"}],
        "joints": joints,
        "loads": [{"body": "table", "at": [20, 10, 80], "force": [0, 0, -200]}],
    }


def test_a_door_on_two_hinges_has_one_redundant_axial_force() -> None:
    """The weight pulls the door down onto both hinges' axial limits at once
    (equal plays) and tilts it onto the bore ends farthest apart (hinge1's
    lower end, hinge2's upper one). Unknowns: two axial forces, both along
    the axis and on it, and two radial ones in the plane of the tilt: 4.
    Equations they reach: the axial force (1: on the axis, the axial forces
    make no moment), and the radial force and the moment of the tilt (2):
    3. Degree 4 - 3 = 1, and only the two axial contacts share it; the
    rule splits them equally (150 N each)."""
    result = jointplay.solve(model_from_dict(door()))
    result.check()
    found = result.indeterminate
    assert found.degree == 1
    assert found.joints == ("hinge1", "hinge2")
    assert found.contacts == ("hinge1.axial", "hinge2.axial")
    for name in ("hinge1", "hinge2"):
        (axial,) = (c for c in result.joints[name].contacts if c.name == "axial")
        assert axial.force_magnitude == pytest.approx(150.0, rel=1e-8)


def test_springs_decide_the_door_s_split() -> None:
    """With a ``stiffness`` every contact of the hinges is a spring: its
    force is its penetration's, none is rigid redundancy (degree 0)."""
    result = jointplay.solve(model_from_dict(door(stiffness=1e5)))
    assert result.indeterminate == DETERMINATE


def test_the_carriage_on_its_guide_counts_five() -> None:
    """The carriage rests on the guide's four vertical corner contacts and
    is pushed against its four lateral ones, all touching; the nut's face
    lies flat. Unknowns: 8 corner forces, each along its contact's
    direction, and the face's force and centre of pressure (3): 11. The
    carriage's six balance equations are all reached (Fx by the face; Fy
    and Mz by the lateral corners; Fz, Mx, My by the vertical ones): 6.
    Degree 11 - 6 = 5, every touching contact taking part (the face's
    moments share My and Mz with the corners). On a plane alone the four
    vertical corners would be 4 forces against Fz, Mx, My: 1 of the 5."""
    result = jointplay.solve(jointplay.load(STUDIES / "carriage.yaml"))
    result.check()
    found = result.indeterminate
    assert found.degree == 5
    assert found.joints == ("guide", "nut")
    touching = {
        f"{name}.{c.name}"
        for name, jr in result.joints.items()
        for c in jr.contacts
        if c.in_contact
    }
    assert set(found.contacts) == touching and len(touching) == 9


def test_a_table_on_four_equal_feet_counts_one() -> None:
    """Four vertical point forces against the plate's Fz, Mx, My (the pin,
    with play, does not touch under a vertical load): 4 - 3 = 1, the four
    feet sharing it."""
    result = jointplay.solve(model_from_dict(table_on_four_feet()))
    result.check()
    found = result.indeterminate
    assert found.degree == 1
    assert found.joints == ("foot1", "foot2", "foot3", "foot4")
    assert [c.split(".")[0] for c in found.contacts] == list(found.joints)


@pytest.mark.parametrize("case", ["resting", "leaning on foot4"])
def test_the_wobbly_table_rests_on_three_feet(case: str) -> None:
    """One foot 50 um short: the table rocks, three feet carry it: three
    vertical forces not on a line against Fz, Mx, My: degree 0."""
    model = jointplay.load(STUDIES / "wobbly_table.yaml")
    result = jointplay.solve(model, case=case)
    result.check()
    carrying = [
        n for n, jr in result.joints.items() if n.startswith("foot") and jr.contacts[0].in_contact
    ]
    assert len(carrying) == 3
    assert result.indeterminate.degree == 0
    assert result.indeterminate.joints == () and result.indeterminate.contacts == ()


def test_a_welded_closed_loop_counts_six() -> None:
    """Three rigid joints close a loop ground - A - B - ground: 18 force
    unknowns against two bodies' 12 equations, 6 left; all three welds share
    them."""
    model = model_from_dict(
        {
            "name": "welded loop",
            "bodies": [{"name": "G", "ground": True}, {"name": "A"}, {"name": "B"}],
            "joints": [
                {"name": "w1", "type": "rigid", "between": ["G", "A"], "at": [0, 0, 0]},
                {"name": "w2", "type": "rigid", "between": ["A", "B"], "at": [100, 0, 0]},
                {"name": "w3", "type": "rigid", "between": ["B", "G"], "at": [200, 0, 0]},
            ],
            "loads": [{"body": "A", "at": [50, 0, 0], "force": [0, 0, -10]}],
        }
    )
    found = jointplay.solve(model).indeterminate
    assert found.degree == 6
    assert found.joints == ("w1", "w2", "w3")


@pytest.mark.parametrize(
    ("make", "degree"),
    [
        (lambda: model_from_dict(door()), 1),
        (lambda: jointplay.load(STUDIES / "carriage.yaml"), 5),
        (lambda: model_from_dict(table_on_four_feet()), 1),
    ],
    ids=["door", "carriage", "table"],
)
def test_a_large_model_s_count_is_the_same(
    make: Any, degree: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The sparse path (by pairs of bodies, then loops) counts as the dense SVD."""
    dense = jointplay.solve(make()).indeterminate
    monkeypatch.setattr(linalg, "SPARSE_FROM", 0)
    sparse = jointplay.solve(make()).indeterminate
    assert dense.degree == degree
    assert sparse == dense


def test_a_determinate_shaft_says_nothing() -> None:
    """Paper 6.1.6.1: a ball and one end of the bore touch, 3 + 1 unknowns
    against the shaft's 5 held equations (the spin is free): determinate."""
    result = jointplay.solve(jointplay.load(PAPER / "6.1.6.1.yaml"))
    assert result.indeterminate.degree == 0
    proc = run("solve", str(PAPER / "6.1.6.1.yaml"))
    assert proc.returncode == 0, proc.stderr
    assert "Forces:" not in proc.stdout and "indeterminate" not in proc.stdout
    html = Report(studies=False).render(jointplay.load(PAPER / "6.1.6.1.yaml"), "6.1.6.1")
    assert "statically indeterminate" not in html


def test_solve_says_so_in_text_json_and_report(tmp_path: Path) -> None:
    path = tmp_path / "door.yaml"
    path.write_text(yaml.safe_dump(door()), encoding="utf-8")
    proc = run("solve", str(path))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count(DOOR_SENTENCE) == 1
    proc = run("solve", str(path), "--json")
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["indeterminate"] == {
        "degree": 1,
        "joints": ["hinge1", "hinge2"],
        "contacts": ["hinge1.axial", "hinge2.axial"],
        "by_rule": True,
    }
    html = Report(studies=False).render(model_from_dict(door()), "door")
    assert f"<p>{DOOR_SENTENCE}</p>" in html


def test_the_count_travels_with_a_pickled_result() -> None:
    result = jointplay.solve(model_from_dict(door()))
    copy = pickle.loads(pickle.dumps(result))
    assert copy.indeterminate == result.indeterminate
    assert copy.find_indeterminate is None


def test_a_split_not_shown_to_be_the_rule_s_is_not_called_so() -> None:
    """The carriage's split needs the rule's program (its faces' forces reach
    their rims). Starved of the program's iterations, the split falls back
    to the route's own forces: they still balance and certify, but the
    answer no longer claims the equal-springs rule (``by_rule`` False, in
    words and in JSON); with the program's iterations it does."""
    from dataclasses import replace

    import numpy as np

    from jointplay.present.textreport import indeterminacy_words
    from jointplay.solver import pipeline
    from jointplay.solver.solve import Workspace

    ws = Workspace.of(jointplay.load(STUDIES / "carriage.yaml"))
    loads, g = pipeline.loads_and_work(ws, None)
    scale = pipeline.load_scale(ws, float(np.linalg.norm(g)))
    g_hat, sigma = g / scale, ws.softness(scale)
    found = pipeline.optimum(ws, g_hat, sigma)
    assert found.by_rule
    rule = pipeline.result_of(ws, found, scale, loads, g, 0.0)
    assert rule.indeterminate.degree > 0 and rule.indeterminate.by_rule
    starved = ws.with_settings(replace(ws.settings, max_iterations=1))
    own = replace(found, lam=found.lam.copy(), f=found.f.copy(), certificate=None, nu=None)
    left = pipeline.certified(starved, g_hat, sigma, pipeline.split(starved, g_hat, sigma, own))
    assert left.certificate is not None and left.certificate.certified
    assert not left.by_rule
    result = pipeline.result_of(ws, left, scale, loads, g, 0.0)
    result.check()
    assert not result.indeterminate.by_rule
    assert result.indeterminate.degree == rule.indeterminate.degree
    assert result.to_dict()["indeterminate"]["by_rule"] is False
    words = indeterminacy_words(result)
    assert words is not None and "split as the solver left it" in words
    assert "is split by the equal-springs rule" not in words
    assert "is split by the equal-springs rule" in (indeterminacy_words(rule) or "")


def test_a_study_s_steps_together_keep_the_model_s_order() -> None:
    """``over_steps``: the largest degree, each joint and contact once, in
    the model's order of joints (each joint's contacts as found), and the
    rule's split only where every step's is."""
    from jointplay.indeterminacy import Indeterminacy, over_steps

    a = Indeterminacy(1, ("hinge2",), ("hinge2.axial",))
    b = Indeterminacy(2, ("hinge1", "hinge2"), ("hinge1.end-", "hinge1.axial", "hinge2.axial"))
    both = over_steps([a, DETERMINATE, b], ["hinge1", "hinge2"])
    assert both == Indeterminacy(
        2, ("hinge1", "hinge2"), ("hinge1.end-", "hinge1.axial", "hinge2.axial"), True
    )
    left = Indeterminacy(1, ("hinge2",), ("hinge2.axial",), by_rule=False)
    assert not over_steps([a, left], ["hinge1", "hinge2"]).by_rule
    assert over_steps([DETERMINATE, DETERMINATE], ["hinge1"]) == DETERMINATE


def test_a_sweep_says_at_which_steps_its_forces_are_the_rule_s(tmp_path: Path) -> None:
    """The door's weight turned about Y. At 0 and 180 deg it is axial and the
    two hinges share it (degree 1, the door's count); at 90 and 270 deg it
    pushes across the hinges, and both ends of both hinges touch: four
    forces along X against two equations (the force along X, the moment
    about Y), degree 2. Each step's count is that of the door solved alone
    under that step's load (text, JSON, CSV)."""
    from jointplay.studies.sweep import RotateLoad, Sweep

    model = model_from_dict(door())
    swept = Sweep(rotate=RotateLoad(0, (0.0, 1.0, 0.0), steps=4)).run(model)
    alone = []
    for angle in (0.0, 90.0, 180.0, 270.0):
        data = door()
        t = np.radians(angle)
        data["loads"][0]["force"] = [-300.0 * np.sin(t), 0.0, -300.0 * np.cos(t)]
        alone.append(jointplay.solve(model_from_dict(data)).indeterminate)
    assert swept.indeterminate == tuple(alone)
    assert [f.degree for f in alone] == [1, 2, 1, 2]
    assert alone[1].contacts == ("hinge1.end-", "hinge1.end+", "hinge2.end-", "hinge2.end+")
    path = tmp_path / "door.yaml"
    path.write_text(yaml.safe_dump(door()), encoding="utf-8")
    sweep = ("sweep", str(path), "--rotate-load", "0", "--about", "y", "--steps", "4")
    proc = run(*sweep)
    assert proc.returncode == 0, proc.stderr
    assert (
        "Forces: at every step, the load shared by hinge1 and hinge2 is split by the "
        "equal-springs rule (statically indeterminate, degree 1 to 2)"
    ) in " ".join(proc.stdout.split())
    proc = run(*sweep, "--json")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["indeterminate"] == {
        "degree": 2,
        "joints": ["hinge1", "hinge2"],
        "contacts": [
            "hinge1.axial",
            "hinge1.end-",
            "hinge1.end+",
            "hinge2.axial",
            "hinge2.end-",
            "hinge2.end+",
        ],
        "by_rule": True,
        "steps": [0, 1, 2, 3],
    }
    assert [s["indeterminate"] for s in doc["steps"]] == [f.to_dict() for f in alone]
    assert list(swept.to_dataframe()["indeterminate_degree"]) == [1, 2, 1, 2]
    # where some steps' forces are decided, the sentence counts the others
    from jointplay.present.textreport import steps_split_words

    words = steps_split_words([alone[0], DETERMINATE, alone[1], DETERMINATE], ["hinge1", "hinge2"])
    assert words is not None and words.startswith(
        "Forces: at 2 of 4 steps, the load shared by hinge1 and hinge2 is split by the "
        "equal-springs rule (statically indeterminate, degree 1 to 2)"
    )


def test_a_motion_says_whose_forces_are_the_rule_s() -> None:
    """The slider-crank's piston rests on the four corners of its guide at
    every pose, one more than the guide's rows need (the door's count for a
    guide: degree 1, the guide named); the four-bar's pins decide every
    force (degree 0: nothing said). Each step's count is that pose's answer's."""
    from jointplay.present.textreport import steps_split_words

    gallery = ROOT / "examples" / "gallery"
    crank = jointplay.Motion(steps=5).run(jointplay.load(gallery / "slider_crank.yaml"))
    assert [f.degree for f in crank.indeterminate] == [1] * 5
    assert crank.indeterminate == tuple(r.indeterminate for r in crank.results)
    doc = crank.to_dict()
    assert doc["indeterminate"]["joints"] == ["guide"]
    assert doc["indeterminate"]["steps"] == [0, 1, 2, 3, 4]
    assert doc["steps"][2]["indeterminate"] == crank.results[2].indeterminate.to_dict()
    assert steps_split_words(crank.indeterminate, crank.joint_names) == (
        "Forces: at every step, the load shared by the contacts of guide is split by the "
        "equal-springs rule (statically indeterminate, degree 1); the rigid parts do not "
        "decide it; give `stiffness` for the real split."
    )
    assert list(crank.to_dataframe()["indeterminate degree"]) == [1] * 5
    bar = jointplay.Motion(steps=5).run(jointplay.load(gallery / "four_bar.yaml"))
    assert steps_split_words(bar.indeterminate, bar.joint_names) is None
    assert bar.to_dict()["indeterminate"]["degree"] == 0


def test_exact_rotations_say_their_forces_are_not_the_rule_s() -> None:
    """``--exact`` prints its last program's forces: on the lathe slide,
    whose guide's corners are redundant (degree 3, the small-displacement
    answer's count), it says so and does not claim the rule's split."""
    model = jointplay.load(ROOT / "examples" / "gallery" / "lathe_slide.yaml")
    small = jointplay.solve(model).indeterminate
    exact = jointplay.solve(model, exact=True).indeterminate
    assert small.degree == 3 and small.by_rule and small.joints == ("guide",)
    assert (exact.degree, exact.joints, exact.contacts) == (
        small.degree,
        small.joints,
        small.contacts,
    )
    assert not exact.by_rule


def test_steps_split_by_the_rule_and_not_are_counted_apart() -> None:
    """Nine steps split by the rule and one left as the solver left it: two
    sentences, each with its own count (neither speaks for the other's steps)."""
    from jointplay.indeterminacy import Indeterminacy
    from jointplay.present.textreport import steps_split_words

    rule = Indeterminacy(1, ("guide",), ("guide.a", "guide.b"))
    left = Indeterminacy(1, ("guide",), ("guide.a", "guide.b"), by_rule=False)
    words = steps_split_words([rule] * 9 + [left], ["guide"])
    assert words is not None
    assert words.startswith(
        "Forces: at 9 of 10 steps, the load shared by the contacts of guide is split by the "
        "equal-springs rule"
    )
    assert (
        "Forces: at 1 of 10 steps, the load shared by the contacts of guide is split as the "
        "solver left it (statically indeterminate, degree 1), not by the equal-springs rule"
    ) in words
