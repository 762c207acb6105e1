"""Re-solving a prepared mechanism: solves on one workspace and batches agree with fresh solves."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import jointplay
from conftest import BALANCE, FEET, MM, RAD, force_tol, spherical_shaft, table_on_feet
from jointplay import Load, Workspace, model_from_dict
from jointplay.settings import DEFAULT


def rotated_forces(n: int) -> np.ndarray:
    """The paper's F = (1, 1, 1) N turned about the shaft axis X in n steps."""
    th = np.linspace(0.0, 2 * np.pi, n, endpoint=False) + np.pi / 4
    return np.stack([np.ones(n), np.sqrt(2) * np.cos(th), np.sqrt(2) * np.sin(th)], axis=1)


def fresh(data: dict[str, Any], loads: list[dict[str, Any]]) -> jointplay.Result:
    result = jointplay.solve(model_from_dict({**data, "loads": loads}))
    result.check()
    return result


def assert_same_rows(a: Any, b: Any, bodies: Any) -> None:
    """Two batches of one problem (two routes) agree to the promise: each
    moving body's position to MM and RAD, every force to the certificate's
    balance of its row."""
    for name in bodies:
        da, db = a.body_displacement(name), b.body_displacement(name)
        np.testing.assert_allclose(da[:, :3], db[:, :3], rtol=0, atol=MM, err_msg=name)
        np.testing.assert_allclose(da[:, 3:], db[:, 3:], rtol=0, atol=RAD, err_msg=name)
    top = np.maximum(1.0, np.max(np.abs(b.forces), axis=1, keepdims=True))
    assert np.all(np.abs(a.forces - b.forces) <= BALANCE * top)


def test_wrench_work_is_the_work_of_the_same_load() -> None:
    ws = Workspace.of(model_from_dict(spherical_shaft()))
    load = Load(body="S1", at=(300.0, 10.0, -5.0), force=(1.0, -2.0, 3.0), torque=(4.0, 5.0, 6.0))
    W = ws.asm.wrench_work("S1", load.at)
    np.testing.assert_allclose(W @ np.r_[load.force, load.torque], ws.asm.work_of([load]))


def test_solves_again_on_one_workspace_match_fresh_solves() -> None:
    data = spherical_shaft()
    ws = Workspace.of(model_from_dict(data))
    for force in rotated_forces(12):
        loads = [{"body": "S1", "at": [300, 0, 0], "force": list(force)}]
        again = ws.solve(loads=[Load(**loads[0])])
        again.check()
        ref = fresh(data, loads)
        for name in ("l1", "l2"):
            np.testing.assert_allclose(
                again.joints[name].translation, ref.joints[name].translation, atol=MM
            )
            np.testing.assert_allclose(
                again.joints[name].rotation, ref.joints[name].rotation, atol=RAD
            )
        # the energy is the load's work on its point's displacement, 300 mm out
        tol = np.linalg.norm(force) * (MM + 300 * RAD)
        assert again.potential_energy == pytest.approx(ref.potential_energy, abs=tol)


def test_a_tie_after_a_unique_optimum_on_one_workspace_gets_the_least_norm_answer() -> None:
    """After a unique optimum, a load that ties positions on the same
    workspace still gets the least-norm answer of a fresh solve."""
    data = spherical_shaft()
    ws = Workspace.of(model_from_dict(data))
    ws.solve()
    tie = [{"body": "S1", "at": [220, 0, 0], "force": [0, 1, 0]}]
    again = ws.solve(loads=[Load(**tie[0])])
    ref = fresh(data, tie)
    np.testing.assert_allclose(
        again.joints["l2"].translation, ref.joints["l2"].translation, atol=MM
    )
    np.testing.assert_allclose(again.joints["l2"].rotation, ref.joints["l2"].rotation, atol=RAD)


def test_batch_matches_one_by_one_solves() -> None:
    data = spherical_shaft()
    ws = Workspace.of(model_from_dict(data))
    forces = rotated_forces(360)
    W = ws.asm.wrench_work("S1", [300, 0, 0])
    batch = ws.solve_batch(np.hstack([forces, np.zeros_like(forces)]) @ W.T)
    assert len(batch) == 360
    assert batch.full_solves < 10  # one active set: nearly all rows solved together
    assert np.all(batch.feasibility_mm <= 1e-9 * 0.1)
    assert np.all(batch.equilibrium_residual <= 1e-8)
    for i in range(0, 360, 37):
        loads = [{"body": "S1", "at": [300, 0, 0], "force": list(forces[i])}]
        ref = fresh(data, loads)
        for name in ("l1", "l2"):
            tau = batch.joint_torsor(name)[i]
            np.testing.assert_allclose(tau[:3], ref.joints[name].translation, atol=MM)
            np.testing.assert_allclose(tau[3:], ref.joints[name].rotation, atol=RAD)
        body = batch.body_displacement("S1")[i]
        np.testing.assert_allclose(body[:3], ref.bodies["S1"].translation, atol=MM)
        np.testing.assert_allclose(body[3:], ref.bodies["S1"].rotation, atol=RAD)
        tol = np.linalg.norm(forces[i]) * (MM + 300 * RAD)  # the load's work, 300 mm out
        assert batch.potential_energy[i] == pytest.approx(ref.potential_energy, abs=tol)
        forces_ref = [c.force_magnitude for j in ref.joints.values() for c in j.contacts]
        np.testing.assert_allclose(batch.forces[i], forces_ref, rtol=0, atol=force_tol(ref))
    # every contact of the rotating load: l1 and the end of l2 near the load
    # touch (the project's 'touching'; none past its play but by the feasibility)
    np.testing.assert_allclose(batch.gap_used()[:, [0, 2]], 1.0, atol=1 - DEFAULT.touching)


def test_a_turned_load_starts_newton_at_its_answer(monkeypatch: pytest.MonkeyPatch) -> None:
    """Why ``batch._load_predicted`` exists: from its neighbour's answer,
    Newton on a turned load converged only where the turn was small (the
    paper's force turned about the shaft in 360 steps: three passes of up
    to eight steps, 34 us per load). The balance is linear in the contacts'
    force vectors; on a set whose balance fixes them, the forces of the new
    load give the directions of contact and these the position: the start
    is the answer (to MM and RAD: checked here on every row it starts), and
    the answers are those without it. How many passes and Newton steps
    either takes is the route's (round-off), not asked."""
    import jointplay.solver.batch as batch_module

    data = spherical_shaft()
    forces = rotated_forces(360)
    reference = Workspace.of(model_from_dict(data))
    W = reference.asm.wrench_work("S1", [300, 0, 0])
    work = np.hstack([forces, np.zeros_like(forces)]) @ W.T

    predicted: list[np.ndarray] = []
    checked: list[int] = []
    real_batch, real_predicted = batch_module._newton_batch, batch_module._load_predicted

    def kept(*args: Any) -> Any:
        x, lam = real_predicted(*args)
        predicted.append(x)
        return x, lam

    def compared(ws: Any, key: Any, g_hat: np.ndarray, *rest: Any, **kw: Any) -> Any:
        predicted.clear()
        out = real_batch(ws, key, g_hat, *rest, **kw)
        g_near = rest[7] if len(rest) > 7 else kw.get("g_near")  # after sigma ... near
        if predicted and g_near is not None:
            ok, x = out[0], out[1]
            turned = np.flatnonzero(np.any(g_hat != g_near, axis=1))
            for row, start in zip(turned, predicted[0], strict=True):
                if ok[row]:  # the start against the row's answer: mm, and a turn over ell
                    move = (start - x[row]).reshape(-1, 6)
                    assert np.max(np.abs(move[:, :3])) * ws.asm.s <= MM
                    assert np.max(np.abs(move[:, 3:] * ws.asm.turn[:, None])) <= RAD
                    checked.append(row)
        return out

    monkeypatch.setattr(batch_module, "_newton_batch", compared)
    monkeypatch.setattr(batch_module, "_load_predicted", kept)
    got = Workspace.of(model_from_dict(data)).solve_batch(work)
    assert len(checked) >= 300  # nearly every row started from a prediction

    monkeypatch.setattr(batch_module, "_load_predicted", lambda face, Eq, x0, lam0, *_: (x0, lam0))
    plain = Workspace.of(model_from_dict(data)).solve_batch(work)
    assert_same_rows(got, plain, ["S1"])
    assert np.all(got.feasibility_mm <= 1e-9 * 0.1)
    assert np.all(got.equilibrium_residual <= BALANCE)


def test_a_start_solved_before_the_batch_starts_its_newton() -> None:
    """``batch.solved_start``: a sample solved before the batch starts its
    rows, the answers are those of a batch without it (to the certificate),
    and a start from another model is refused in words."""
    from jointplay.solver import batch as batch_module

    data = spherical_shaft()
    ws = Workspace.of(model_from_dict(data))
    forces = rotated_forces(24)
    W = ws.asm.wrench_work("S1", [300, 0, 0])
    work = np.hstack([forces, np.zeros_like(forces)]) @ W.T
    start = batch_module.solved_start(ws, ws.asm.g)
    assert start is not None
    got = ws.solve_batch(work, starts=[start])
    plain = Workspace.of(model_from_dict(data)).solve_batch(work)
    assert_same_rows(got, plain, ["S1"])
    other = Workspace.of(model_from_dict(table_on_feet([0.0, 0.0, 0.0])))
    with pytest.raises(ValueError, match="this workspace's model"):
        other.solve_batch(other.asm.g[None], starts=[start])


def test_batch_with_ties_and_zero_rows() -> None:
    data = spherical_shaft()
    ws = Workspace.of(model_from_dict(data))
    W = ws.asm.wrench_work("S1", [220, 0, 0])
    wrenches = np.array([[0, 1, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0], [0, 0, 2, 0, 0, 0]], float)
    batch = ws.solve_batch(wrenches @ W.T)
    assert np.all(batch.x[1] == 0)
    ref = fresh(data, [{"body": "S1", "at": [220, 0, 0], "force": [0, 1, 0]}])
    np.testing.assert_allclose(
        batch.joint_torsor("l2")[0, :3], ref.joints["l2"].translation, atol=MM
    )


def test_batch_reports_a_driven_free_motion() -> None:
    ws = Workspace.of(model_from_dict(spherical_shaft()))
    W = ws.asm.wrench_work("S1", [300, 0, 0])
    wrenches = np.array([[1, 1, 1, 0, 0, 0], [0, 0, 0, 5, 0, 0]], float)
    with pytest.raises(jointplay.UnboundedMechanismError, match="rotation about the global X"):
        ws.solve_batch(wrenches @ W.T)


def test_a_singular_row_drops_only_itself() -> None:
    """The batched Newton solves its rows' KKT systems together; one exactly
    singular system (a fresh clarabel's answer one ulp off can start a row on
    one) is masked out and the others are still solved, together."""
    from jointplay.numerics.linalg import solve_rows

    rng = np.random.default_rng(0)
    K = rng.standard_normal((5, 4, 4))
    K[2, 3, :] = 0.0  # an equation that says nothing: exactly singular
    rhs = rng.standard_normal((5, 4))
    step, regular = solve_rows(K, rhs)
    assert regular.tolist() == [True, True, False, True, True]
    # an LU's residual is round-off of |K| |step| (these 4 x 4 systems'
    # conditions are 6 to 2e3): far inside 1e-12 on any machine
    for b in (0, 1, 3, 4):
        np.testing.assert_allclose(K[b] @ step[b], rhs[b], rtol=0, atol=1e-12)
    assert np.all(step[2] == 0.0)


def test_rows_dropped_in_the_middle_of_a_batch_are_solved_after_all(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The per-row bookkeeping of the batched Newton: rows that a step finds
    singular leave the stack and the others go on; the dropped rows get their
    answer later (from another start, or the full solver), the same answer."""
    import jointplay.solver.batch as batch_module
    import jointplay.solver.newton as newton_module

    data = spherical_shaft()
    forces = rotated_forces(40)
    reference = Workspace.of(model_from_dict(data))
    W = reference.asm.wrench_work("S1", [300, 0, 0])
    work = np.hstack([forces, np.zeros_like(forces)]) @ W.T
    expected = reference.solve_batch(work)

    solve_rows = newton_module.solve_rows
    calls = []

    def singular_sometimes(K: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        step, regular = solve_rows(K, rhs)
        calls.append(len(K))
        if len(calls) == 1 and len(K) > 4:  # the first batched step: rows 1 and 4 "singular"
            regular = regular.copy()
            regular[[1, 4]] = False
        return step, regular

    monkeypatch.setattr(newton_module, "solve_rows", singular_sometimes)
    # with the loads' prediction the starts are the answers and Newton takes no
    # step: off, it starts from the neighbour's answer and takes several
    monkeypatch.setattr(batch_module, "_load_predicted", lambda face, Eq, x0, lam0, *_: (x0, lam0))
    ws = Workspace.of(model_from_dict(data))
    got = ws.solve_batch(work)
    assert calls[0] > 4  # the rows were stacked, and two of them dropped
    assert got.full_solves < 5
    assert_same_rows(got, expected, ["S1"])


def test_a_row_that_starts_at_a_contacts_centre_drops_only_itself() -> None:
    """A start where a contact's relative position is exactly 0 has no
    direction for its force; that row leaves the batch, the others converge."""
    from jointplay.solver import faces, pipeline
    from jointplay.solver.newton import newton

    ws = Workspace.of(model_from_dict(spherical_shaft()))
    forces = rotated_forces(3)
    W = ws.asm.wrench_work("S1", [300, 0, 0])
    work = np.hstack([forces, np.zeros_like(forces)]) @ W.T
    solved = ws.solve_batch(work)
    g_hat = work / np.linalg.norm(work, axis=1)[:, None]
    point = pipeline.optimum(ws, g_hat[0])
    face = faces.face_of(ws, point.active)
    surface = list(point.active[0])
    assert not point.active[1] and surface  # the shaft's contacts are on their surfaces
    x = solved.x.copy()
    x[1] = 0.0  # every contact at its centre
    lam = np.zeros((3, len(surface))) + 1.0
    nu = np.zeros((3, face.Eq.shape[0]))
    conv = newton(
        None,
        -g_hat,
        face.Eq,
        np.repeat(face.e[None, :], 3, axis=0),
        face.stack,
        x,
        lam,
        nu,
        ws.settings,
        c=np.zeros((3, face.stack.A.shape[0])),
        accept=ws.settings.newton_accept,
    ).converged
    assert conv.tolist() == [True, False, True]
    # from their answers, the others end on them (Newton's point and the
    # batch's may be two routes: to MM, a turn counting as its move at ell)
    assert np.max(np.abs(x[[0, 2]] - solved.x[[0, 2]])) * ws.asm.s <= MM


def test_a_row_is_not_retried_without_end(monkeypatch: pytest.MonkeyPatch) -> None:
    """When no row converges from another's active set, every sample ends
    in a full solve (the carriage example did so before its redundant
    contacts were batched: here every batched row is made to fail). Each
    full solve adds a start; before, every pending row was then tried again
    from every known set: Newton work quadratic in the samples (82 samples/s
    at 300 samples, 56 at 1,000). A row now leaves a set after
    ``batch_give_up`` failures from it."""
    from pathlib import Path

    import jointplay.solver.batch as batch_module
    from jointplay.studies.montecarlo import MonteCarlo

    real = batch_module._newton_batch
    tried: list[tuple[Any, int]] = []

    def counting(ws: Any, key: Any, g_hat: np.ndarray, *rest: Any) -> Any:
        tried.append((key, len(g_hat)))
        ok, *out = real(ws, key, g_hat, *rest)
        return (np.zeros_like(ok), *out)

    monkeypatch.setattr(batch_module, "_newton_batch", counting)
    model = jointplay.load(Path(__file__).parents[1] / "examples" / "studies" / "carriage.yaml")
    samples = 120
    MonteCarlo(samples=samples, seed=0).run(model)
    sets = {key for key, _ in tried}
    assert sum(n for _, n in tried) <= DEFAULT.batch_give_up * samples * len(sets)


def test_redundant_contacts_are_batched_and_split_like_single_solves() -> None:
    """The carriage's guide corners and nut face are redundant: the active
    rows depend on each other and the KKT systems are singular. The batch
    runs Newton on an independent part of them (the same positions), then
    splits the forces by the documented rule from the nearest solved
    sample's split (``forces.least_squares_rows``): here it leaves a corner
    unloaded and the nut's centre of pressure on its rim. Every row, with
    its own plays and tool force, matches its own full solve; nearly all
    are batched."""
    from pathlib import Path

    from jointplay.studies.variation import play_map

    model = jointplay.load(Path(__file__).parents[1] / "examples" / "studies" / "carriage.yaml")
    ws = Workspace.of(model)
    rng = np.random.default_rng(3)
    B = 120
    pmap = play_map(ws.asm, model.name)
    radii = pmap.radii(pmap.sample(rng, B))
    tool = np.array([-300.0, 200.0, -500.0])
    extra = 0.2 * tool * rng.standard_normal((B, 3))  # added to the file's tool force
    W = ws.asm.wrench_work("carriage", [80, 0, 150])
    work = ws.asm.g[None] + np.hstack([extra, np.zeros((B, 3))]) @ W.T
    batch = ws.solve_batch(work, radii)
    assert np.sum(batch.batched) >= 0.75 * B
    for i in range(0, B, 11):
        tool_i = Load(body="carriage", at=(80, 0, 150), force=tuple(extra[i]))
        loads = [*model.loads_of(None), tool_i]
        ref = ws.with_radii(radii[i]).solve(loads=loads)
        ref.check()
        body = batch.body_displacement("carriage")[i]
        np.testing.assert_allclose(body[:3], ref.bodies["carriage"].translation, atol=MM)
        np.testing.assert_allclose(body[3:], ref.bodies["carriage"].rotation, atol=RAD)
        expected = np.array([c.force_magnitude for j in ref.joints.values() for c in j.contacts])
        np.testing.assert_allclose(batch.forces[i], expected, rtol=0, atol=BALANCE * expected.max())
        # a touching corner left unloaded (to the balance)
        assert np.sum(expected <= BALANCE * expected.max()) >= 1


def test_a_large_sparse_mechanism_is_solved_row_by_row() -> None:
    """Above 40 bodies the workspace is sparse; a batch on it gives every
    row certified and scaled with its load (a Monte Carlo or a batch on
    such a mechanism once stopped with a traceback from the dense code)."""
    from jointplay.io.generate import tube_string

    model = tube_string(42)
    ws = Workspace.of(model)
    assert ws.asm.sparse
    scales = np.array([1.0, 1.3, 0.7])
    batch = ws.solve_batch(scales[:, None] * ws.asm.g[None])
    assert np.all(batch.equilibrium_residual <= BALANCE)
    last = model.bodies[-1].name

    def scaled(v: Any, s: float) -> Any:
        return None if v is None else tuple(s * np.asarray(v, dtype=float))

    for i, s in enumerate(scales):
        loads = [
            Load(body=ld.body, at=ld.at, force=scaled(ld.force, s), torque=scaled(ld.torque, s))
            for ld in model.loads_of(None)
        ]
        ref = Workspace.of(model).solve(loads=loads)
        ref.check()
        body = batch.body_displacement(last)[i]
        np.testing.assert_allclose(body[:3], ref.bodies[last].translation, atol=MM)
        np.testing.assert_allclose(body[3:], ref.bodies[last].rotation, atol=RAD)


def test_a_singular_row_is_found_when_lu_and_determinant_disagree(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """numpy 1.26's LAPACK gave a nonzero determinant sign for a system its
    LU then found singular (a force split's KKT system), and the batched
    solve of the 'regular' rows raised. Simulated here: the rows are then
    solved one at a time, and only the singular one is dropped."""
    from jointplay.numerics.linalg import solve_rows

    rng = np.random.default_rng(1)
    K = rng.standard_normal((4, 3, 3))
    K[1, 2, :] = 0.0
    rhs = rng.standard_normal((4, 3))
    monkeypatch.setattr(np.linalg, "slogdet", lambda a: (np.ones(len(a)), np.zeros(len(a))))
    step, regular = solve_rows(K, rhs)
    assert regular.tolist() == [True, False, True, True]
    for b in (0, 2, 3):  # conditions 25 to 33: an LU's residual is round-off
        np.testing.assert_allclose(K[b] @ step[b], rhs[b], rtol=0, atol=1e-12)
    assert np.all(step[1] == 0.0)


def test_rows_that_pose_the_same_split_solve_it_once_and_alike() -> None:
    """With only the plays varying, the carriage's rows pose the same force
    split (same loads, contact directions and start): it is solved once
    (``linalg.distinct_rows``) and given to every row; each row still
    matches its own full solve."""
    from pathlib import Path

    from jointplay.numerics.linalg import distinct_rows
    from jointplay.studies.variation import play_map

    a = np.array([[1.0, 2.0], [3.0, 4.0], [1.0, 2.0], [1.0, 2.0 + 1e-15]])
    first, same = distinct_rows(a)
    np.testing.assert_array_equal(a[first][same], a)
    assert len(first) == 3

    model = jointplay.load(Path(__file__).parents[1] / "examples" / "studies" / "carriage.yaml")
    ws = Workspace.of(model)
    pmap = play_map(ws.asm, model.name)
    radii = pmap.radii(pmap.sample(np.random.default_rng(5), 60))
    batch = ws.solve_batch(np.tile(ws.asm.g, (60, 1)), radii)
    assert np.sum(batch.batched) >= 55
    for i in (0, 29, 59):
        ref = ws.with_radii(radii[i]).solve()
        body = batch.body_displacement("carriage")[i]
        np.testing.assert_allclose(body[:3], ref.bodies["carriage"].translation, atol=MM)
        np.testing.assert_allclose(body[3:], ref.bodies["carriage"].rotation, atol=RAD)
        expected = np.array([c.force_magnitude for j in ref.joints.values() for c in j.contacts])
        np.testing.assert_allclose(batch.forces[i], expected, rtol=0, atol=BALANCE * expected.max())


def test_a_touching_contact_outside_the_set_still_gets_the_documented_split() -> None:
    """Four feet, no play. A load near a corner leaves foot 3 unloaded, so
    its active set holds feet 1, 2 and 4. The next row (load near the
    centre) converged on that set with a unique three-foot split that
    certifies, and the batch kept it, although foot 3 touches and the
    documented split (equal springs) loads it. Rows with touching contacts
    outside their set now take the split rule, like redundant ones (found
    by review)."""
    feet = FEET[:4]
    data = table_on_feet([0.0, 0.0, 0.0])
    ws = Workspace.of(model_from_dict(data))
    at = [(110.0, 70.0), (50.0, 30.0), (-20.0, 10.0)]
    down = np.r_[0.0, 0.0, -100.0, 0.0, 0.0, 0.0]
    batch = ws.solve_batch(np.array([ws.asm.wrench_work("plate", [*p, 0.0]) @ down for p in at]))
    for i, (x0, y0) in enumerate(at[1:], start=1):
        springs = [100 / 4 * (1 + x0 * x / 120**2 + y0 * y / 80**2) for x, y in feet]
        np.testing.assert_allclose(batch.forces[i], springs, rtol=0, atol=BALANCE * 100)


@pytest.mark.parametrize("forces", [False, True])
def test_a_slider_crank_s_redundant_guide_is_batched_like_single_solves(forces: bool) -> None:
    """The slider-crank's piston rests on four corners of its guide
    (redundant: the positions are unique, the forces shared) while nothing
    sets the rod's axial place in its pins' plays (a tie: the least-norm
    point). At poses through the cycle, each sample's plays batched from
    the nominal answer match its own single solve: positions to MM and RAD,
    contact forces to the balance of the largest."""
    from pathlib import Path

    from jointplay.assembly import assemble
    from jointplay.solver.batch import solved_start
    from jointplay.studies.kinematics import nominal_poses
    from jointplay.studies.motion import posed_model
    from jointplay.studies.variation import load_map, play_map

    model = jointplay.load(Path(__file__).parents[1] / "examples/gallery/slider_crank.yaml")
    _, _, start, stop = model.motion_drive()
    values = np.linspace(start, stop, 7)
    poses = nominal_poses(model, values)
    B = 12
    for step in range(len(values)):
        posed = posed_model(model, poses, step)
        asm = assemble(posed)
        pmap = play_map(asm, model.name)
        radii = pmap.radii(pmap.sample(np.random.default_rng(step), B))
        work = np.tile(load_map(asm, None).g0, (B, 1))
        ws = Workspace(asm)
        nominal = solved_start(ws, work[0])
        assert nominal is not None
        batch = ws.solve_batch(work, radii, forces=forces, starts=[nominal])
        for i in range(0, B, 5):
            ref = ws.with_radii(radii[i]).solve()
            ref.check()
            for body in ("crank", "rod", "piston"):
                moved = batch.body_displacement(body)[i]
                np.testing.assert_allclose(moved[:3], ref.bodies[body].translation, atol=MM)
                np.testing.assert_allclose(moved[3:], ref.bodies[body].rotation, atol=RAD)
            if forces:  # against the single solve's own split (a drive's is a torque there)
                one = ws.solve_batch(work[i : i + 1], radii[i : i + 1])
                assert batch.forces is not None and one.forces is not None
                top = np.max(np.abs(one.forces))
                assert np.all(np.abs(batch.forces[i] - one.forces[0]) <= BALANCE * top)
