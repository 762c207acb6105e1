"""Large mechanisms: the sparse path gives the dense path's answers, and
strings of hundreds of bodies solve with a certificate."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import jointplay
from conftest import MM, RAD, ROOT, force_tol
from jointplay.io.generate import tube_string, tube_string_dict
from jointplay.io.modelfile import LARGEST_MODEL_BODIES, model_from_dict
from jointplay.numerics import linalg

EXAMPLES = sorted((ROOT / "examples").rglob("*.yaml"))


def _solve_all(model: jointplay.Model) -> dict[str, jointplay.Result]:
    return jointplay.solve_cases(model)


def _assert_same(a: jointplay.Result, b: jointplay.Result) -> None:
    for name, body in a.bodies.items():
        other = b.bodies[name]
        assert np.allclose(body.translation, other.translation, rtol=0, atol=MM)
        assert np.allclose(body.rotation, other.rotation, rtol=0, atol=RAD)
    for name, joint in a.joints.items():
        for c, d in zip(joint.contacts, b.joints[name].contacts, strict=True):
            assert c.in_contact == d.in_contact
            # forces: to the certificate's balance (of the largest force in it)
            assert np.allclose(c.force, d.force, rtol=0, atol=force_tol(a))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_sparse_path_gives_the_dense_answers(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    model = jointplay.load(path)
    dense = _solve_all(model)
    monkeypatch.setattr(linalg, "SPARSE_FROM", 0)
    sparse = _solve_all(model)
    for case, result in sparse.items():
        result.check()
        _assert_same(dense[case], result)


@pytest.mark.parametrize("closed", [False, True], ids=["chain", "loops"])
def test_string_sparse_matches_dense(closed: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    model = tube_string(30, closed=closed)  # 180 unknowns: dense
    dense = jointplay.solve(model)
    monkeypatch.setattr(linalg, "SPARSE_FROM", 0)
    sparse = jointplay.solve(model)
    sparse.check()
    _assert_same(dense, sparse)


@pytest.mark.parametrize("closed", [False, True], ids=["chain", "loops"])
def test_long_string_is_certified(closed: bool) -> None:
    model = tube_string(300, closed=closed)
    result = jointplay.solve(model)
    result.check()
    assert result.certificate.feasibility_mm <= 1e-9
    assert result.equilibrium_residual <= 1e-8
    # the open string's axial play adds up: every spigot pulled to its limit
    if not closed:
        data = tube_string_dict(300)
        plays = [j["axial_clearance"] / 2 for j in data["joints"] if j["type"] == "revolute"]
        tip = result.bodies["T300"].translation[0]
        assert tip == pytest.approx(sum(plays), abs=MM)


@pytest.mark.parametrize("n", [3000, 10_000])
def test_a_long_string_is_polished(n: int) -> None:
    """Long chains make ill-conditioned KKT systems: their plain sparse LU
    steps, refined, must keep the answer polished. (A round-off shift of the
    factored matrix once cost the 3,000-segment string its certificate.)
    Issue 18: chains of 10,000 bodies are certified. The interior point
    left 377 spigot ends of that string open (``faces.holders``), and it
    was declined after 74 s; now it is polished (8 s, 454 MB, in bench_scaling)."""
    result = jointplay.solve(tube_string(n))
    result.check()
    assert result.certificate.feasibility_mm <= 1e-9
    data = tube_string_dict(n)
    plays = [j["axial_clearance"] / 2 for j in data["joints"] if j["type"] == "revolute"]
    assert result.bodies[f"T{n}"].translation[0] == pytest.approx(sum(plays), abs=MM)


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_a_model_file_of_the_largest_size_is_read(tmp_path: Path, suffix: str) -> None:
    """The reader takes every model the solver does: the largest, a string of
    LARGEST_MODEL_BODIES bodies, written as a file (YAML with one entry a
    line, as the examples are written, or indented JSON), reads back as the
    model that ``test_a_long_string_is_polished`` certifies."""
    n = LARGEST_MODEL_BODIES
    data = tube_string_dict(n)
    path = tmp_path / f"chain{suffix}"
    if suffix == ".json":
        path.write_text(json.dumps(data, indent=2))
    else:
        path.write_text(
            "".join(
                f"{section}:\n" + "".join(f"  - {json.dumps(entry)}\n" for entry in data[section])
                for section in ("bodies", "joints", "loads")
            )
        )
    model = jointplay.load(path)
    assert len(model.bodies) == n + 1 and len(model.moving_bodies) == n
    assert len(model.joints) == 2 * n
    assert model == tube_string(n)


def test_free_spins_of_a_long_string_come_out_zero(monkeypatch: pytest.MonkeyPatch) -> None:
    """Without dowels every segment spins freely: 60 free motions, none
    loaded, each left at zero (the least-norm answer)."""
    data = tube_string_dict(60)
    data["joints"] = [j for j in data["joints"] if j["type"] != "sphere_in_cylinder"]
    data["loads"] = [ld for ld in data["loads"] if "torque" not in ld]
    model = model_from_dict(data)
    result = jointplay.solve(model)
    result.check()
    assert len(result.free_motions) == 60
    for body in result.bodies.values():
        assert abs(body.rotation[0]) <= RAD


def test_a_driven_spin_in_a_long_string_is_reported() -> None:
    data = tube_string_dict(60)
    data["joints"] = [j for j in data["joints"] if j["name"] != "dowel40"]
    with pytest.raises(jointplay.UnboundedMechanismError) as err:
        jointplay.solve(model_from_dict(data))
    assert err.value.body in {f"T{i}" for i in range(40, 61)}
    assert "rotation about the global X axis" in str(err.value)


def test_welded_parts_lifting_off_a_long_string_are_named_alone() -> None:
    """Two parts welded together, each on three point contacts, loaded off
    them along a leaning axis, next to a 400-segment string: the interior
    point's ray of unboundedness moves every body by round-off (the string's
    by 4e-11 of the parts'). The error names the two parts, which must move
    together, and no other body; the motion named lifts each off its points.
    On the way, ``held.needed_only`` tries the most moved part alone (the
    weld holds it), drops the string's bodies at once, then tries the other
    part alone (``_rows_by_body``). Point contacts are cones with no rows:
    their sums (``BallStack.segment_sum``) no longer go through a (rows,
    cones) matrix that grows with the square of the size."""
    data = tube_string_dict(400)
    axis = [0.3, 0.2, 1.0]
    points = ([0, 0, -500], [10, 0, -500], [0, 10, -500])
    for part in ("part", "part2"):
        data["bodies"].append({"name": part})
        for i, at in enumerate(points):
            data["joints"].append(
                {
                    "name": f"p{i}{part}",
                    "type": "point",
                    "between": ["ground", part],
                    "at": at,
                    "axis": axis,
                }
            )
        for i, at in enumerate(points[:2]):
            data["joints"].append(
                {
                    "name": f"s{i}{part}",
                    "type": "sphere_in_cylinder",
                    "between": ["ground", part],
                    "at": at,
                    "axis": axis,
                    "clearance": 0.1,
                }
            )
    data["joints"].append(
        {"name": "weld", "type": "rigid", "between": ["part", "part2"], "at": [0, 0, -500]}
    )
    data["loads"].append({"body": "part", "at": [0, 0, -500], "force": [1.5, 1.0, 5.0]})
    with pytest.raises(jointplay.UnboundedMechanismError) as err:
        jointplay.solve(model_from_dict(data))
    assert set(err.value.direction) == {"part", "part2"}
    n = np.array(axis) / np.linalg.norm(axis)
    moves = {}
    for part, (rotation, translation) in err.value.direction.items():
        moves[part] = (np.array(rotation), np.array(translation))
        for at in points:  # first order: off every point contact, along the axis
            moved = np.array(translation) + np.cross(rotation, at)
            assert float(moved @ n) >= -1e-9 * float(np.linalg.norm(moved))
    # welded: the same motion
    np.testing.assert_allclose(moves["part"][0], moves["part2"][0], atol=1e-9)
    np.testing.assert_allclose(moves["part"][1], moves["part2"][1], atol=1e-9)
