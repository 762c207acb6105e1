"""Contact forces, reactions and the equilibrium they prove; weights, points, load cases."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import jointplay
from conftest import (
    BALANCE,
    FEET,
    MM,
    PAPER,
    RAD,
    force_tol,
    moment_tol,
    spherical_shaft,
    table_on_feet,
)
from jointplay import model_from_dict

EXAMPLES = sorted(Path(PAPER).parent.rglob("*.yaml"))


def solved(data: dict[str, Any], **kw: Any) -> jointplay.Result:
    result = jointplay.solve(model_from_dict(data), **kw)
    result.check()
    return result


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_example_reports_forces_that_balance_the_loads(path: Path) -> None:
    model = jointplay.load(path)
    results = (
        jointplay.solve_cases(model).values() if model.load_cases else [jointplay.solve(model)]
    )
    for result in results:
        assert result.equilibrium_residual <= BALANCE
        for jr in result.joints.values():
            for c in jr.contacts:
                if not c.in_contact:  # a free contact pushes nothing, to the balance
                    assert c.force_magnitude <= force_tol(result)
            # the reaction is the sum of the printed contacts (``build_result``):
            # the same few additions, equal to the round-off of a sum
            size = max([float(np.max(np.abs(jr.reaction_force))), 1e-300])
            total = sum((c.force for c in jr.contacts), np.zeros(3))
            np.testing.assert_allclose(jr.reaction_force, total, rtol=0, atol=1e-12 * size)


def test_paper_6_1_6_1_forces_closed_form() -> None:
    """Moments about the ball at O: 220 * F_end+ + 300 * F = 0 across the axis;
    the ball takes the rest, including all of the axial force."""
    r = solved(spherical_shaft())
    end_plus = r.joints["l2"].contacts[1]
    assert end_plus.in_contact and end_plus.name == "end+"
    newtons = force_tol(r)
    np.testing.assert_allclose(end_plus.force, [0, -300 / 220, -300 / 220], atol=newtons)
    # the end's point is the model's geometry (200 + 20 along a unit axis), not the solve's
    np.testing.assert_allclose(end_plus.point, [220, 0, 0], atol=1e-12)
    np.testing.assert_allclose(r.joints["l2"].contacts[0].force, 0, atol=newtons)
    ball = r.joints["l1"].contacts[0]
    np.testing.assert_allclose(ball.force, [-1, 80 / 220, 80 / 220], atol=newtons)
    # the reaction of l2 about its centre (200, 0, 0): the end+ force at x = +20
    np.testing.assert_allclose(
        r.joints["l2"].reaction_moment, np.cross([20, 0, 0], end_plus.force), atol=moment_tol(r)
    )
    # a contact force pushes back against the displacement that closed its play
    u = r.bodies["S1"].displacement_of(end_plus.point)
    assert float(np.dot(u[1:], end_plus.force[1:])) < 0


def test_forces_scale_with_the_loads_positions_do_not() -> None:
    a = solved(spherical_shaft())
    data = spherical_shaft(loads=[{"body": "S1", "at": [300, 0, 0], "force": [7, 7, 7]}])
    b = solved(data)
    for name in ("l1", "l2"):
        np.testing.assert_allclose(b.joints[name].translation, a.joints[name].translation, atol=MM)
        np.testing.assert_allclose(
            b.joints[name].reaction_force, 7 * a.joints[name].reaction_force, atol=force_tol(b)
        )


def test_a_rigid_joint_carries_the_whole_load() -> None:
    data = {
        "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
        "joints": [{"name": "w", "type": "rigid", "between": ["G", "B"], "at": [10, 0, 0]}],
        "loads": [{"body": "B", "at": [10, 0, 50], "force": [3, 0, 0], "torque": [0, 0, 5]}],
    }
    r = solved(data)
    w = r.joints["w"]
    np.testing.assert_allclose(w.reaction_force, [-3, 0, 0], atol=force_tol(r))
    # moment of the load about the joint centre: (0,0,50) x (3,0,0) + (0,0,5)
    np.testing.assert_allclose(w.reaction_moment, [0, -150, -5], atol=moment_tol(r))


def test_gravity_is_a_weight_at_the_centre_of_mass() -> None:
    base = spherical_shaft(loads=[])
    weighed = copy.deepcopy(base)
    weighed["bodies"][1].update(mass="2 kg", center_of_mass=[300, 0, 0])
    weighed["gravity"] = [0, 0, "-9.81 m/s^2"]
    explicit = spherical_shaft(loads=[{"body": "S1", "at": [300, 0, 0], "force": [0, 0, -19.62]}])
    a, b = solved(weighed), solved(explicit)
    for name in ("l1", "l2"):
        np.testing.assert_allclose(a.joints[name].translation, b.joints[name].translation, atol=MM)
        np.testing.assert_allclose(a.joints[name].rotation, b.joints[name].rotation, atol=RAD)
        np.testing.assert_allclose(
            a.joints[name].reaction_force, b.joints[name].reaction_force, atol=force_tol(b)
        )
    # the energy is the load's work on its point's displacement, 300 mm out:
    # the same to MM and 300 mm times RAD
    assert a.potential_energy == pytest.approx(b.potential_energy, abs=19.62 * (MM + 300 * RAD))


def test_functional_points_move_with_their_body() -> None:
    data = spherical_shaft(points=[{"name": "tip", "body": "S1", "at": [300, 0, 0]}])
    r = solved(data)
    tip = r.points["tip"]
    np.testing.assert_allclose(tip.displacement, r.bodies["S1"].displacement_of([300, 0, 0]))
    assert r.to_dict()["points"] == {"tip": {"body": "S1", "displacement": list(tip.displacement)}}
    # from the paper's printed l2 values (6.1.6.1): the tip at x = 300 is 100 mm
    # past l2's centre, so it moves by (u2, v2 + 100 gamma2, w2 - 100 beta2)
    u2, v2, w2, beta2, gamma2 = 8.892973e-2, 6.134259e-2, 6.134259e-2, -4.684034e-4, 4.684034e-4
    expected = [u2, v2 + 100 * gamma2, w2 - 100 * beta2]
    np.testing.assert_allclose(tip.displacement, expected, atol=1e-6)  # paper: 7 digits


def test_load_cases_add_to_the_common_loads() -> None:
    data = spherical_shaft(
        loads=[{"body": "S1", "at": [300, 0, 0], "force": [1, 0, 0]}],
        load_cases={
            "up": [{"body": "S1", "at": [300, 0, 0], "force": [0, 0, 5]}],
            "side": [{"body": "S1", "at": [300, 0, 0], "force": [0, 5, 0]}],
        },
    )
    model = model_from_dict(data)
    cases = jointplay.solve_cases(model)
    assert list(cases) == ["up", "side"]
    for name, force in (("up", [1, 0, 5]), ("side", [1, 5, 0])):
        alone = solved(spherical_shaft(loads=[{"body": "S1", "at": [300, 0, 0], "force": force}]))
        np.testing.assert_allclose(
            cases[name].joints["l2"].translation, alone.joints["l2"].translation, atol=MM
        )
        single = jointplay.solve(model, case=name)
        np.testing.assert_allclose(
            single.joints["l2"].translation, alone.joints["l2"].translation, atol=MM
        )
    with pytest.raises(KeyError, match="Did you mean 'side'"):
        jointplay.solve(model, case="sied")


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"bodies": [{"name": "S0", "ground": True}, {"name": "S1", "mass": 2}]}, "center_of_mass"),
        ({"gravity": [0, 0, "9.81 kg"]}, "acceleration"),
        # a plain number would be mm/s^2: -9.81 would be a thousandth of g
        (
            {"gravity": [0, 0, -9.81]},
            r'component z: .* write the unit, e.g. \[0, 0, "-9.81 m/s\^2"\]',
        ),
        ({"gravity": [0, "-9810", 0]}, "component y: a plain number"),
        ({"points": [{"name": "p", "body": "S2", "at": [0, 0, 0]}]}, "Did you mean 'S1'"),
        (
            {"load_cases": {"a": [{"body": "S9", "torque": [1, 0, 0]}]}},
            r"load_cases\.a\[0\]: body: unknown body",
        ),
        ({"load_cases": {}}, "no cases given"),
    ],
)
def test_bad_new_entries_are_model_errors(change: dict[str, Any], message: str) -> None:
    with pytest.raises(jointplay.ModelError, match=message):
        model_from_dict(spherical_shaft(**change))


def test_the_certificate_refuses_forces_that_leave_a_body_unbalanced() -> None:
    """The one certificate (``certificate.check``, shared by every route and
    by batches) checks each body's balance in newtons: forces off by 3e-8 of
    the largest force fail it, on the one body they act on."""
    from jointplay.solver import certificate, pipeline
    from jointplay.solver.solve import Workspace

    ws = Workspace.of(model_from_dict(spherical_shaft()))
    g = ws.asm.g / np.linalg.norm(ws.asm.g)
    point = pipeline.optimum(ws, g)
    args = (g[None], point.x[None], point.lam[None], point.f[None], np.zeros((1, len(ws.balls))))
    good = certificate.check(ws, *args)
    assert good.passed(ws.settings, ws.max_radius)[0]  # balanced to BALANCE, at most
    # the ball l1 pushes 3e-8 (of the largest force) harder, along its direction:
    # off by 3e-8, give or take the good answer's BALANCE
    lam, f = point.lam.copy(), point.f.copy()
    grow = 1 + 3 * BALANCE * float(np.max(point.lam)) / lam[0]
    lam[0] *= grow
    f[: ws.stack.k[0]] *= grow
    bad = certificate.check(
        ws, g[None], point.x[None], lam[None], f[None], np.zeros((1, len(ws.balls)))
    )
    assert not bad.passed(ws.settings, ws.max_radius)[0]
    assert BALANCE < bad.balance[0] < 10 * BALANCE


@pytest.mark.parametrize("at", [[0, 0, 30], [30, -20, 5], [-60, 10, 0]])
def test_redundant_feet_share_the_load_as_equal_springs_would(at: list[float]) -> None:
    """A rigid plate on four touching feet at (+-a, +-b) under F at (x0, y0)
    (free to slide and turn in its plane: no load does): three balance
    equations for four forces. The least-squares split (the documented rule)
    is the classic one of four equal springs:
    F_i = F/4 (1 + x0 x_i / a^2 + y0 y_i / b^2)."""
    a, b, F = 120.0, 80.0, 100.0
    r = solved(table_on_feet(at))
    x0, y0 = at[0], at[1]
    for i, (x, y) in enumerate(FEET[:4]):
        expected = F / 4 * (1 + x0 * x / a**2 + y0 * y / b**2)
        np.testing.assert_allclose(
            r.joints[f"foot{i + 1}"].contacts[0].force, [expected, 0, 0], atol=force_tol(r)
        )  # joint frame: x is the floor's normal


def test_the_split_pulls_on_no_foot() -> None:
    """Far off centre the least-squares split would pull on the far feet:
    the split is then the least-squares one among pushing forces (a small
    cone program)."""
    from itertools import combinations

    at = [110.0, 75.0]
    r = solved(table_on_feet([*at, 0.0], feet=6))
    forces = np.array([r.joints[f"foot{i}"].contacts[0].force[0] for i in range(1, 7)])
    M = np.array([[1.0] * 6, [y for _, y in FEET], [x for x, _ in FEET]])
    w = np.array([100.0, 100.0 * at[1], 100.0 * at[0]])  # sum F, moments about x and y
    assert np.min(np.linalg.lstsq(M, w, rcond=None)[0]) < -1.0  # it would pull
    # independent reference: the least-norm split on every set of pushing
    # feet; the best one that balances and pushes is the optimum (convexity)
    best = None
    for n in range(1, 7):
        for feet in combinations(range(6), n):
            f = np.zeros(6)
            f[list(feet)] = np.linalg.lstsq(M[:, feet], w, rcond=None)[0]
            balances = np.allclose(M @ f, w, rtol=1e-12) and f.min() >= -1e-12
            if balances and (best is None or f @ f < best @ best):
                best = f
    assert best is not None
    np.testing.assert_allclose(forces, best, rtol=0, atol=force_tol(r))
    assert np.min(forces) >= 0.0


def _shuffled(data: dict[str, Any], seed: int) -> dict[str, Any]:
    import random

    out = copy.deepcopy(data)
    rng = random.Random(seed)
    for key in ("bodies", "joints", "loads", "points"):
        if isinstance(out.get(key), list):
            rng.shuffle(out[key])
    return out


def _answers(result: jointplay.Result) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    positions, forces = {}, {}
    for name, jr in result.joints.items():
        positions[f"{name}.t"] = jr.translation
        positions[f"{name}.w"] = jr.rotation
        for c in jr.contacts:
            forces[f"{name}.{c.name}"] = c.force
    for name, pr in result.points.items():
        positions[f"point {name}"] = pr.displacement
    return positions, forces


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_answers_do_not_depend_on_the_order_of_the_file(path: Path) -> None:
    """Bodies, joints, loads and points in another order: the same positions
    and the same force at every contact, redundant ones included, to the
    certificate's promise: positions to MM and RAD, forces to its balance
    (round-off is 1e-13 here where the route is the same, but the order may
    change the route on another machine)."""
    import yaml

    data = yaml.safe_load(path.read_text())
    model = model_from_dict(data)
    cases = model.case_names if model.load_cases else [None]
    for seed in (1, 2):
        other = model_from_dict(_shuffled(data, seed))
        for case in cases:
            a = jointplay.solve(model, case=case)
            pos_a, force_a = _answers(a)
            pos_b, force_b = _answers(jointplay.solve(other, case=case))
            for key, value in force_a.items():
                np.testing.assert_allclose(force_b[key], value, rtol=0, atol=force_tol(a))
            for key, value in pos_a.items():
                tol = RAD if key.endswith(".w") else MM
                np.testing.assert_allclose(pos_b[key], value, rtol=0, atol=tol, err_msg=key)


def test_a_result_pickles_as_plain_data() -> None:
    """Results travel between processes (Dask, multiprocessing) as plain data:
    the lazy free-motion words and exact-rotation check go along as values,
    not as closures over the solver's workspace (which holds Clarabel's
    objects, which do not pickle)."""
    import pickle

    model = jointplay.load(Path(PAPER).parent / "studies" / "wobbly_table.yaml")
    result = jointplay.solve(model, case="leaning on foot4")
    copy_ = pickle.loads(pickle.dumps(result))
    assert (
        copy_.free_motions
        == result.free_motions
        == ("body 'table': rotation about the global Z axis",)
    )
    assert copy_.linearization == result.linearization
    assert copy_.to_dict() == result.to_dict()
    copy_.check()


@pytest.mark.parametrize("name", ["lathe_slide", "spindle", "four_bar"])
def test_a_result_s_rows_come_in_file_order_and_are_made_when_read(name: str) -> None:
    """``Result.bodies`` and ``Result.joints`` are read-only mappings in file
    order whose rows are made from the answer's stacked arrays when first
    read (``result.Rows``): a 10,000-segment string's answer made 80,000
    objects (0.9 s) for readers that often look at a few. Each joint lists
    its own contacts, in its type's order, and they add up to its reaction."""
    from collections.abc import Mapping

    model = jointplay.load(Path(PAPER).parent / "gallery" / f"{name}.yaml")
    result = jointplay.solve(model)
    assert isinstance(result.joints, Mapping) and isinstance(result.bodies, Mapping)
    assert list(result.joints) == [j.name for j in model.joints]
    assert list(result.bodies) == [b.name for b in model.bodies]
    for joint in model.joints:
        jr = result.joints[joint.name]
        assert jr is result.joints[joint.name]  # made once
        assert (jr.type, jr.between) == (joint.type_name, joint.between)
        assert [c.name for c in jr.contacts] == [c.name for c in joint.cones]
        # the reaction is the sum of the printed contacts: round-off of a sum
        size = max([float(np.max(np.abs(jr.reaction_force))), 1e-300])
        total = sum((c.force for c in jr.contacts), np.zeros(3))
        np.testing.assert_allclose(total, jr.reaction_force, rtol=0, atol=1e-12 * size)
    with pytest.raises(KeyError):
        result.joints["no such joint"]


def test_a_split_that_does_not_certify_leaves_the_routes_forces(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The least-squares split is computed from the positions; on a long
    sparse chain its linear solve may balance the bodies less well than the
    certificate needs. The solver then keeps its route's forces (certified),
    rather than decline: here a split off by 1e-6 is refused, and the answer
    is the one the route found."""
    from jointplay.solver import forces
    from jointplay.solver.forces import Split

    data = table_on_feet([30, -20, 5])
    expected = solved(data)
    real = forces.least_squares_split

    def off(*args: Any, **kw: Any) -> Split | None:
        split = real(*args, **kw)
        assert split is not None  # four feet: the split is not determined
        return Split(split.lam * (1 + 1e-6), split.f * (1 + 1e-6), split.nu)

    monkeypatch.setattr(forces, "least_squares_split", off)
    got = solved(data)
    assert got.certificate.certified
    assert got.equilibrium_residual < 1e-8
    total = sum(got.joints[f"foot{i}"].contacts[0].force[0] for i in range(1, 5))
    assert total == pytest.approx(100.0, abs=force_tol(got))
    for name in expected.joints:
        np.testing.assert_allclose(
            got.joints[name].translation, expected.joints[name].translation, atol=MM
        )


def test_a_face_whose_force_reaches_its_rim_gets_the_rule_s_split() -> None:
    """The carriage's least-squares split would pull on a guide corner and
    put the nut face's centre of pressure outside its disc. The rule's
    split then leaves that corner unloaded and the centre of pressure on the
    rim (``|f| = lam``). Checked here by the optimality conditions of the
    rule's convex program, found independently (least squares): the
    gradient of |P y|^2 / 2 is balanced by multipliers of the balance, of
    the rim (>= 0) and of the unloaded corner (>= 0). The split program's
    answer is good to its tolerance there (a rim is not a linear limit the
    least-squares finish can hold), so the limits are
    checked to the certificate's balance and the gradient to 1e-6."""
    from jointplay.solver import forces, pipeline
    from jointplay.solver.solve import Workspace

    model = jointplay.load(Path(__file__).parents[1] / "examples" / "studies" / "carriage.yaml")
    ws = Workspace.of(model)
    g = ws.asm.g
    point = pipeline.optimum(ws, g / np.linalg.norm(g))
    x, lam, f = point.x, point.lam, point.f
    st = ws.settings
    surface, apex, _, u = forces._classes(ws.stack, x, ws.stack.r, st.feasibility_tolerance, st)
    Z, owner = forces._unknowns(ws.stack, surface, apex, u, ws.asm.E.shape[0], False)
    P, G = forces._wrenches(ws.asm, Z), forces._work(ws.asm, Z)
    y = np.linalg.lstsq(Z, np.concatenate([f, lam]), rcond=None)[0]
    # a split's forces are Z y by its construction (any route), and Z's columns
    # are unit vectors of separate contacts: least squares gives them back to
    # the round-off of its largest entry
    top = max(1.0, float(np.max(lam)))  # the loads have unit norm here
    np.testing.assert_allclose(Z @ y, np.concatenate([f, lam]), rtol=0, atol=1e-13 * top)
    b = g / np.linalg.norm(g)
    np.testing.assert_allclose(G @ y, b, rtol=0, atol=BALANCE * top)
    unloaded = [j for j in range(len(y)) if owner[j] >= 0 and ws.stack.k[owner[j]] == 1]
    unloaded = [j for j in unloaded if abs(y[j]) <= BALANCE * top]
    assert len(unloaded) == 1  # one guide corner left unloaded
    nut = next(i for i, ball in enumerate(ws.balls) if ball.contact.name == "face x-")
    assert model.joints[ws.balls[nut].joint_index].name == "nut"
    cols = np.flatnonzero(owner == nut)  # lam, then f
    f_nut = y[cols[1:]]
    assert np.linalg.norm(f_nut) == pytest.approx(y[cols[0]], abs=BALANCE * top)  # on its rim
    # KKT: P^T P y + G^T mu + eta (0.., f/|f|, -1 ..) - nu e_unloaded = 0
    rim = np.zeros(len(y))
    rim[cols[0]], rim[cols[1:]] = -1.0, f_nut / np.linalg.norm(f_nut)
    held = np.zeros((len(y), 1))
    held[unloaded[0]] = -1.0
    M = np.hstack([G.T, rim[:, None], held])
    grad = P.T @ (P @ y)
    mult, *_ = np.linalg.lstsq(M, -grad, rcond=None)
    np.testing.assert_allclose(M @ mult + grad, 0.0, atol=1e-6 * np.max(np.abs(grad)))
    assert mult[-2] > 0.0 and mult[-1] > 0.0  # the rim and the corner both bind


def welded_beside_a_touching_point(force_y: float) -> dict[str, Any]:
    """B welded to the ground, and a point contact with no gap at the weld's
    centre, pushing along +y; an idle body D on a revolute joint with play."""
    return {
        "bodies": [{"name": "G", "ground": True}, {"name": "B"}, {"name": "D"}],
        "joints": [
            {"name": "w", "type": "rigid", "between": ["G", "B"], "at": [10, 0, 0]},
            {
                "name": "p",
                "type": "point",
                "between": ["G", "B"],
                "at": [10, 0, 0],
                "axis": [0, 1, 0],
                "gap": 0.0,
            },
            {
                "name": "r",
                "type": "revolute",
                "between": ["G", "D"],
                "at": [-50, 0, 0],
                "axis": [0, 0, 1],
                "clearance": 0.01,
                "length": 5.0,
                "axial_clearance": 1.0,
            },
        ],
        "loads": [{"body": "B", "at": [10, 0, 0], "force": [0, force_y, 0]}],
    }


def test_a_load_the_weld_holds_alone_leaves_the_contacts_unloaded() -> None:
    """Pulling B off its point contact: the weld holds the load alone, so
    the contacts carry nothing (the route: no contact load), and every
    position is the no-load one. The wrong answer this route removed, an
    idle body's tie resolved where round-off forces put it, is the case
    tests/property_cases/tie_least_norm_point_moves_with_the_file.yaml;
    here the old route happened to find 0 too."""
    r = solved(welded_beside_a_touching_point(4.0))
    r.check()
    np.testing.assert_allclose(r.joints["w"].reaction_force, [0, -4, 0], atol=force_tol(r))
    # the touching point's split comes from a cone program (it would pull):
    # its force is 0 to that program's tolerance, the certificate's 1e-8 of 4 N
    for name in ("p", "r"):
        np.testing.assert_allclose(r.joints[name].reaction_force, 0.0, atol=4e-8)
    np.testing.assert_allclose(r.bodies["D"].translation, 0.0, atol=MM)
    np.testing.assert_allclose(r.bodies["D"].rotation, 0.0, atol=RAD)


def test_a_weld_and_a_touching_contact_share_by_the_rule() -> None:
    """Pushing B onto its point contact: the positions come from the
    contacts' share of the loads (none here), the forces from the split
    rule on the whole load, which shares it equally between the weld and
    the contact (both at one point: least sum of squared forces), as before
    the share was introduced."""
    r = solved(welded_beside_a_touching_point(-4.0))
    np.testing.assert_allclose(r.joints["w"].reaction_force, [0, 2, 0], atol=force_tol(r))
    assert r.joints["p"].contacts[0].force_magnitude == pytest.approx(2.0, abs=force_tol(r))


#: B's ball ``s`` at the origin, a spring of 1000 N/mm beyond 0.005 mm of radial play
COMPLIANT_BALL = {
    "name": "s",
    "type": "spherical",
    "between": ["G", "B"],
    "at": [0, 0, 0],
    "clearance": 0.01,
    "stiffness": 1000.0,
}


def test_a_compliant_contact_pressed_by_a_deviation_pushes_beside_a_weld() -> None:
    """A deviation presses B's compliant ball 0.04 mm past its play; the
    load on B is the weld's alone. The ball pushes anyway (its spring), so
    the contacts' share of the loads is not all they carry: with compliant
    contacts the routes keep the whole load (solved as "no contact load" it
    was not assembled at all, a review's find)."""
    model = jointplay.with_deviations(
        jointplay.model_from_dict(
            {
                "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
                "joints": [
                    COMPLIANT_BALL,
                    {"name": "w", "type": "rigid", "between": ["G", "B"], "at": [10, 0, 0]},
                ],
                "loads": [{"body": "B", "at": [10, 0, 0], "force": [0, 4.0, 0]}],
            }
        ),
        {"s": {"position": [0, 0.05, 0]}},
    )
    r = jointplay.solve(model)
    # B is welded at 0: the ball is 0.05 - 0.005 mm into its spring
    assert r.joints["s"].contacts[0].force_magnitude == pytest.approx(45.0, abs=force_tol(r))
    np.testing.assert_allclose(r.joints["w"].reaction_force, [0, -49.0, 0], atol=force_tol(r))


def ball_pressed_between_two_stops(stop_play: float, force_y: float | None) -> jointplay.Model:
    """B on three balls along X: ``s`` at 0 compliant (1000 N/mm, play
    0.005 mm in radius) whose bore a deviation moves 0.05 mm up, and two hard
    ``stops`` at x = ±10 mm (radial play ``stop_play / 2``). Nothing moves B
    0.05 mm up, so the spring is pressed with no load at all."""
    joints: list[dict[str, Any]] = [COMPLIANT_BALL]
    for name, x in (("t", 10), ("u", -10)):
        joints.append(
            {
                "name": name,
                "type": "spherical",
                "between": ["G", "B"],
                "at": [x, 0, 0],
                "clearance": stop_play,
            }
        )
    loads = [] if force_y is None else [{"body": "B", "at": [10, 0, 0], "force": [0, force_y, 0]}]
    data = {"bodies": [{"name": "G", "ground": True}, {"name": "B"}], "joints": joints}
    return jointplay.with_deviations(
        model_from_dict({**data, "loads": loads}), {"s": {"position": [0, 0.05, 0]}}
    )


@pytest.mark.parametrize("force_y", [None, 0.0, 1e-9, 1e-3], ids=str)
@pytest.mark.parametrize("exact", [False, True], ids=["linear", "exact"])
def test_a_spring_a_deviation_presses_pushes_with_no_load_or_a_faint_one(
    force_y: float | None, exact: bool
) -> None:
    """The stops let B rise 0.01 mm: the spring is 0.05 - 0.005 - 0.01 mm in,
    35 N, the stops 17.5 N each (plus the load on t). Scaled by the load's
    size alone, these springs were made 1e7 times too stiff or infinitely
    so, and the parts reported "not assembled" (``pipeline.load_scale``)."""
    r = jointplay.solve(ball_pressed_between_two_stops(0.02, force_y), exact=exact)
    r.check()
    load = force_y or 0.0
    tol = 1e-8 * 35.0  # the certificate's resolution: 1e-8 of the largest force
    assert r.joints["s"].contacts[0].force_magnitude == pytest.approx(35.0, abs=tol)
    assert r.joints["t"].contacts[0].force_magnitude == pytest.approx(17.5 + load, abs=tol)
    assert r.joints["u"].contacts[0].force_magnitude == pytest.approx(17.5, abs=tol)
    np.testing.assert_allclose(r.bodies["B"].translation, [0, 0.01, 0], atol=MM)
    np.testing.assert_allclose(r.bodies["B"].rotation, 0.0, atol=RAD)


def test_a_batch_row_with_no_load_keeps_its_spring_pressed() -> None:
    """A sweep through zero load: the unloaded row, and one whose stops'
    play is drawn wider (0.03 mm: the spring 30 N), are solved with the
    springs' preload as their scale, like a single solve."""
    from jointplay.assembly import assemble
    from jointplay.solver.solve import Workspace

    asm = assemble(ball_pressed_between_two_stops(0.02, 1.0))
    ws = Workspace(asm)
    force = np.array([[0, f, 0, 0, 0, 0] for f in (1.0, 0.0, 0.0, -1.0)])
    work = force @ asm.wrench_work("B", [10, 0, 0]).T
    radii = np.tile(ws.stack.r, (4, 1))
    names = [asm.model.joints[ball.joint_index].name for ball in asm.balls]
    wider = [i for i, name in enumerate(names) if name in ("t", "u")]
    radii[2, wider] *= 1.5
    batch = ws.solve_batch(work, radii=radii)
    assert np.all(batch.assembled)
    spring = names.index("s")
    assert batch.forces is not None
    np.testing.assert_allclose(batch.forces[:, spring], [35, 35, 30, 35], atol=1e-8 * 35)
    np.testing.assert_allclose(batch.x[:, 1] * asm.s, [0.01, 0.01, 0.015, 0.01], atol=MM)


def test_a_preload_with_no_load_is_still_balanced_by_the_certificate() -> None:
    """With no load, the springs' preload is all the forces there are: an
    answer whose stops push three times too hard (70 N unbalanced) is
    refused. The balance check skipped every row with no load, which was
    harmless while such rows had no forces (a review's find)."""
    from dataclasses import replace

    from jointplay.assembly import assemble
    from jointplay.solver import certificate, pipeline
    from jointplay.solver.solve import Workspace

    ws = Workspace(assemble(ball_pressed_between_two_stops(0.02, None)))
    scale = pipeline.load_scale(ws, 0.0)
    g_hat, sigma = np.zeros(ws.m), ws.softness(scale)
    point = pipeline.optimum(ws, g_hat, sigma)
    assert certificate.certify(ws, g_hat, sigma, point).certified
    names = [ws.asm.model.joints[ball.joint_index].name for ball in ws.asm.balls]
    stops = [i for i, name in enumerate(names) if name != "s"]
    lam, f = point.lam.copy(), point.f.copy()
    lam[stops] *= 3
    f[ws.stack.rows_of(stops)] *= 3
    bad = certificate.certify(ws, g_hat, sigma, replace(point, lam=lam, f=f, nu=None))
    assert not bad.certified
    # the stops' forces are the good answer's, balanced to BALANCE of 35 N:
    # tripled, the imbalance is 70 N give or take three times that
    assert bad.equilibrium_residual == pytest.approx(70 / 52.5, abs=3 * BALANCE * 35 / 52.5)
    # and the printed result's own check measures it too
    r = jointplay.solve(ball_pressed_between_two_stops(0.02, None))
    reactions = np.array([np.r_[j.reaction_force, j.reaction_moment] for j in r.joints.values()])
    order = list(r.joints)
    reactions[[order.index("t"), order.index("u")]] *= 3
    residual = jointplay.result.equilibrium_residual(ws.asm, reactions, ())
    assert residual == pytest.approx(70 / 52.5, abs=3 * BALANCE * 35 / 52.5)


def test_a_batch_s_faint_loads_beside_a_preload_are_batched() -> None:
    """Rows of 1e-9 to 3e-4 N, and none, beside a 35 N preload: every row's
    forces are the closed form's to the balance of the preload, whichever
    route a row takes."""
    from jointplay.assembly import assemble
    from jointplay.solver.solve import Workspace

    asm = assemble(ball_pressed_between_two_stops(0.02, 1.0))
    loads = [1.0, 1e-4, 2e-4, 1e-9, 0.0, -1e-4, 3e-4]
    work = np.array([[0, f, 0, 0, 0, 0] for f in loads]) @ asm.wrench_work("B", [10, 0, 0]).T
    batch = Workspace(asm).solve_batch(work)
    assert batch.forces is not None
    expected = np.column_stack([np.full(7, 35.0), 17.5 + np.array(loads), np.full(7, 17.5)])
    np.testing.assert_allclose(batch.forces, expected, atol=1e-8 * 35)


def test_a_compliant_face_pressed_flat_has_its_centre_of_pressure_split_by_the_rule() -> None:
    """A compliant face pressed flat pushes with the force its penetration
    makes, but where that force acts on the face (its force vector) is not
    fixed by the positions. The split chooses it by the same rule as every
    other force; it kept the route's before, and the route's depends on the
    file's order (tests/property_cases/order_compliant_face_pressed_flat.yaml:
    4e-4 N on the guide's corners). Here: two routes' forces that both
    balance the loads, with the face's centre of pressure elsewhere, give the
    same split, and the face keeps its force."""
    from jointplay.solver import forces, pipeline
    from jointplay.solver.solve import Workspace

    path = Path(__file__).parent / "property_cases" / "order_compliant_face_pressed_flat.yaml"
    ws = Workspace.of(jointplay.load(path))
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    point = pipeline.optimum(ws, g_hat, ws.softness(1.0))
    st = ws.settings
    apex = st.feasibility_tolerance * ws.max_radius
    face = next(i for i, b in enumerate(ws.balls) if b.contact.name == "face x+")
    _, rho, _ = ws.stack.levels(point.x)
    assert ws.stack.spring[face] > 0 and point.lam[face] > 0 and rho[face] <= apex
    # another route: the face's force vector moved inside its cone, and the
    # touching contacts' forces changed to balance the loads again (along the
    # balance's null space, found here with numpy)
    n_rows = ws.stack.A.shape[0]
    balance = np.hstack([np.asarray(ws.stack.A).T, np.asarray(ws.stack.B).T])
    rows = np.arange(ws.stack.start[face], ws.stack.start[face] + ws.stack.k[face])
    touching = [i for i in range(len(ws.balls)) if point.lam[i] > 0]
    cols = [*np.concatenate([ws.stack.rows_of(np.array([i])) for i in touching])]
    cols += [n_rows + i for i in touching]
    null = np.linalg.svd(balance[:, cols])[2][np.linalg.matrix_rank(balance[:, cols]) :]
    move = (
        null.T @ np.linalg.lstsq(null.T[[cols.index(r) for r in rows]], [0.1, -0.1], rcond=None)[0]
    )
    y = np.concatenate([point.f, point.lam])
    y[cols] += 0.05 * point.lam[face] * move / np.max(np.abs(move[[cols.index(r) for r in rows]]))
    other_f, other_lam = y[:n_rows], y[n_rows:]
    # the move is in the null space of the balance (numpy's SVD of this
    # order-1 matrix): it keeps the balance to round-off
    np.testing.assert_allclose(
        balance @ y, balance @ np.concatenate([point.f, point.lam]), atol=1e-13
    )
    assert not np.allclose(other_f[rows], point.f[rows])
    nu = pipeline.rigid_multipliers(ws, g_hat, point)
    first = forces.least_squares_split(ws.asm, point.x, point.lam, point.f, nu, g_hat, apex, st)
    then = forces.least_squares_split(ws.asm, point.x, other_lam, other_f, nu, g_hat, apex, st)
    assert first is not None and then is not None
    # to the certificate's balance (the loads have unit norm here)
    tol = BALANCE * max(1.0, float(np.max(point.lam)))
    np.testing.assert_allclose(then.f, first.f, rtol=0, atol=tol)
    np.testing.assert_allclose(then.lam, first.lam, rtol=0, atol=tol)
    assert first.lam[face] == pytest.approx(point.lam[face], abs=tol)  # its penetration's


@pytest.mark.parametrize("block_load", [0.0, 1e5, 1e8])
def test_a_heavy_part_elsewhere_leaves_a_light_part_s_split_as_it_is(block_load: float) -> None:
    """A table on four point feet (a pin holds it sideways) under 100 N at
    (51.5, 51.5) mm: the least squares over four feet would pull on foot3,
    so the rule leaves it unloaded and statics give the other three (51.5,
    24.25, 24.25 N). Beside it, a block welded to the ground under up to
    1e8 N shares no body with the table. The split's program is posed with
    each such part's forces at their own size (``forces._parts``):
    posed at the size of all the loads, the block decided the table's split
    to its own tolerance, and foot3 pushed 0.046 N (1e5 N block) or 8.02 N
    (1e8 N). Judging the least squares' dips against all the loads (as the
    certificate does) instead of against the forces, foot3 pulled 0.75 N.
    So the table's forces hold to the balance of its own 100 N, not of the
    block's load (the certificate's, up to 1 N)."""
    feet = {
        "foot1": (100, 100),
        "foot2": (-100, 100),
        "foot3": (-100, -100),
        "foot4": (100, -100),
    }
    joints: list[dict[str, Any]] = [
        {
            "name": n,
            "type": "point",
            "between": ["floor", "table"],
            "at": [x, y, 0],
            "axis": [0, 0, 1],
        }
        for n, (x, y) in feet.items()
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
    bodies = [{"name": "floor", "ground": True}, {"name": "table"}]
    loads: list[dict[str, Any]] = [{"body": "table", "at": [51.5, 51.5, 0], "force": [0, 0, -100]}]
    if block_load:
        bodies.append({"name": "block"})
        joints.append(
            {"name": "weld", "type": "rigid", "between": ["floor", "block"], "at": [0, 0, 200]}
        )
        loads.append({"body": "block", "at": [0, 0, 200], "force": [0, 0, -block_load]})
    result = solved({"name": "table", "bodies": bodies, "joints": joints, "loads": loads})
    pushes = [result.joints[n].contacts[0].force[0] for n in feet]
    np.testing.assert_allclose(pushes, [51.5, 24.25, 0.0, 24.25], rtol=0, atol=BALANCE * 100)


def test_a_face_s_cone_is_one_part_of_the_split_s_program() -> None:
    """A shaft pushed along its axis 30 mm off it, on two thrust collars of
    20 and 100 mm (a bearing holds it sideways): the collars can hold the
    100 N * 30 mm moment only with their centres of pressure on their rims
    and 50 N each (10 * 50 + 50 * 50 = 3,000 N mm), which is also the
    split of least squares. A face's force touches the balance rows of
    the axial force, its force vector those of the tilts: by the balance
    alone they fell in two parts of the split's program, each part sized
    on its own (``forces._parts``), and their cone was scaled apart:
    44.28 and 55.72 N, certified (a review's find). A cone is one part."""
    bodies = [{"name": "G", "ground": True}, {"name": "shaft"}]
    joints = [
        {"name": f"collar{i}", "type": "planar", "between": ["G", "shaft"], "at": [x, 0, 0]}
        | {"axis": [1, 0, 0], "diameter": d, "clearance": 0.01}
        for i, (x, d) in enumerate([(0, 20), (100, 100)], start=1)
    ]
    joints.append(
        {"name": "bearing", "type": "cylindrical", "between": ["G", "shaft"], "at": [50, 0, 0]}
        | {"axis": [1, 0, 0], "length": 40, "clearance": 0.01}
    )
    loads = [{"body": "shaft", "at": [0, 0, 30], "force": [-100, 0, 0]}]
    result = solved({"name": "collars", "bodies": bodies, "joints": joints, "loads": loads})
    for name, rim in (("collar1", 10.0), ("collar2", 50.0)):
        (face,) = [c for c in result.joints[name].contacts if c.force_magnitude > 0]
        assert face.force_magnitude == pytest.approx(50.0, abs=force_tol(result))
        assert np.hypot(face.point[1], face.point[2]) == pytest.approx(rim, abs=MM)


def test_the_split_s_parts_are_joined_by_balance_wrench_and_cone() -> None:
    """``forces._parts`` on a hand-made split: unknowns 0 and 1 share a
    balance row; 2 shares none with them but is 1's cone's force vector;
    3 and 4 share only a wrench row; 5 is alone and carries nothing. Each
    part's size is the largest ``|b|`` on its balance rows: the cone keeps 2
    with 0 and 1 (alone, it was sized on its own row and its cone scaled
    apart), and the unloaded part stays at 0 (its split is 0)."""
    import scipy.sparse as sp

    from jointplay.solver import forces

    G = sp.csr_matrix(np.array([[1.0, 2, 0, 0, 0, 0], [0, 0, 3, 0, 0, 0], [0, 0, 0, 1, 0, 0]]))
    P = sp.csr_matrix(np.array([[0.0, 0, 0, 1, 1, 0], [0, 0, 0, 0, 0, 1]]))
    owner = np.array([0, 1, 1, 2, 3, -1])
    b = np.array([-5.0, 2.0, 10.0])
    parts = forces._parts(G, P, owner)  # each row's, then each unknown's
    rows, unknowns = parts[:3], parts[3:]
    assert rows[0] == rows[1] == unknowns[0] == unknowns[1] == unknowns[2]
    assert rows[2] == unknowns[3] == unknowns[4] != rows[0]
    assert unknowns[5] not in rows  # alone, with no load: size 0
    sizes = {int(p): 0.0 for p in parts}
    for p, b_i in zip(rows, b, strict=True):
        sizes[int(p)] = max(sizes[int(p)], abs(b_i))
    assert [sizes[int(p)] for p in unknowns] == [5.0, 5.0, 5.0, 10.0, 10.0, 0.0]


def test_the_lathe_slide_s_split_meets_the_rule_s_optimality_conditions() -> None:
    """The lathe slide's guide corners: the least squares over all of them
    would pull on two, and at the rule's optimum those two carry nothing
    while their multipliers vanish too (a degenerate optimum). An interior
    point stops 5e-5 of the largest force off such a point (its forces and
    multipliers there shrink alike); the split program's answer is finished
    by the least squares on the contacts it loads, kept only where it meets
    the program's conditions. Checked independently here (least squares on
    the printed forces): the two corners carry no force, the gradient of
    ``|P y|^2 / 2`` is balanced by multipliers of the balance and of the
    unloaded corners (>= 0), to 1e-9 of its largest entry."""
    from jointplay.solver import forces, pipeline
    from jointplay.solver.solve import Workspace

    model = jointplay.load(Path(__file__).parents[1] / "examples" / "gallery" / "lathe_slide.yaml")
    ws = Workspace.of(model)
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    point = pipeline.optimum(ws, g_hat)
    st = ws.settings
    x, lam, f = point.x, point.lam, point.f
    surface, apex, _, u = forces._classes(ws.stack, x, ws.stack.r, st.feasibility_tolerance, st)
    Z, owner = forces._unknowns(ws.stack, surface, apex, u, ws.asm.E.shape[0], False)
    P, G = forces._wrenches(ws.asm, Z), forces._work(ws.asm, Z)
    nu = point.nu if point.nu is not None else np.zeros(ws.asm.E.shape[0])
    multipliers = np.concatenate([f, lam, nu])
    y = np.linalg.lstsq(Z, multipliers, rcond=None)[0]
    top = float(np.max(np.abs(y)))
    np.testing.assert_allclose(G @ y, g_hat, rtol=0, atol=BALANCE * top)
    unloaded = [j for j in np.flatnonzero(owner >= 0) if abs(y[j]) <= BALANCE * top]
    assert len(unloaded) == 2
    assert np.all(y[owner >= 0] >= -BALANCE * top)
    held = np.zeros((len(y), len(unloaded)))
    held[unloaded, np.arange(len(unloaded))] = -1.0
    M = np.hstack([G.T, held])
    grad = P.T @ (P @ y)
    mult = np.linalg.lstsq(M, -grad, rcond=None)[0]
    np.testing.assert_allclose(M @ mult + grad, 0.0, rtol=0, atol=1e-9 * np.max(np.abs(grad)))
    assert np.all(mult[-len(unloaded) :] >= -1e-9 * np.max(np.abs(grad)))


def test_a_batch_of_loads_on_four_feet_shares_each_as_equal_springs_would() -> None:
    """A sweep of 40 loads across the plate on four feet (each inside the
    feet, so no foot would pull): every row's split is the equal springs'
    closed form (``test_redundant_feet_share_the_load_as_equal_springs_would``).
    The split's least squares exists for such batches: one stacked solve
    splits every row where it lies in every cone, instead of one cone
    program per row (the rows it does not settle take the program)."""
    from jointplay.assembly import assemble
    from jointplay.solver.solve import Workspace

    a, b, F = 120.0, 80.0, 100.0
    asm = assemble(model_from_dict(table_on_feet([0.0, 0.0, 0.0])))
    rng = np.random.default_rng(3)
    at = np.column_stack([rng.uniform(-60, 60, 40), rng.uniform(-40, 40, 40), np.zeros(40)])
    work = np.array([np.r_[0, 0, -F, 0, 0, 0] @ asm.wrench_work("plate", list(p)).T for p in at])
    batch = Workspace(asm).solve_batch(work)
    assert batch.forces is not None and np.all(batch.assembled)
    names = [asm.model.joints[ball.joint_index].name for ball in asm.balls]
    for i, (x, y) in enumerate(FEET[:4]):
        expected = F / 4 * (1 + at[:, 0] * x / a**2 + at[:, 1] * y / b**2)
        got = batch.forces[:, names.index(f"foot{i + 1}")]
        np.testing.assert_allclose(got, expected, rtol=0, atol=BALANCE * F)
