"""Unit tests of the solver's pieces: the maps from cone-program rows back to
contacts, Newton on an active set, and the KKT solves under it.

The end-to-end tests (paper, properties, fuzz) judge whole answers; these pin
down each piece's own promise, so a change to one shows where it broke.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.sparse as sp

import jointplay
from conftest import BALANCE, MM, assert_same_answer
from jointplay.numerics import linalg
from jointplay.settings import DEFAULT
from jointplay.solver import conic, faces, newton, pipeline, records
from jointplay.solver.solve import Workspace

ROOT = Path(__file__).resolve().parents[1]
#: Exact to round-off: the maps copy entries, they compute nothing.
EXACT = 1e-15


@pytest.fixture(scope="module")
def carriage() -> Workspace:
    """Planar faces (cones with an offset row), one-sided point contacts and
    balls: every kind of cone the program holds."""
    return Workspace.of(jointplay.load(ROOT / "examples" / "studies" / "carriage.yaml"))


@pytest.fixture(scope="module")
def paper() -> Workspace:
    return Workspace.of(jointplay.load(ROOT / "examples" / "paper" / "6.1.6.1.yaml"))


def test_the_cone_program_maps_every_row_back_to_its_contact(carriage: Workspace) -> None:
    """Clarabel's slack ``s = b - A x`` is, row by row: the equalities
    ``e - Eq x`` (zero cone), then per contact ``r_i - B_i x`` at
    ``soc_first[i]`` and ``-A_i x`` at its ``f_rows``; the cones' sizes are
    the contacts' rows plus one."""
    ws = carriage
    prog = conic.interior_program(ws)
    x = np.random.default_rng(1).standard_normal(ws.m)
    s = prog.b - prog.A @ x
    n_eq = ws.Eq.shape[0]
    st = ws.stack
    assert np.allclose(s[:n_eq], -linalg.times(ws.Eq, x), rtol=0, atol=EXACT)
    assert np.allclose(s[prog.soc_first], st.r - linalg.times(st.B, x), rtol=0, atol=EXACT)
    assert np.allclose(s[prog.f_rows], -linalg.times(st.A, x), rtol=0, atol=EXACT)
    covered = np.concatenate([np.arange(n_eq), prog.soc_first, prog.f_rows])
    assert sorted(covered.tolist()) == list(range(prog.A.shape[0]))  # each row once
    contact_cones = prog.cones[1:] if n_eq else prog.cones  # the zero cone first, if any
    assert len(contact_cones) == len(st.k)
    for k, cone in zip(st.k, contact_cones, strict=True):
        assert repr(cone) == (f"SecondOrderConeT({k + 1})" if k else "NonnegativeConeT(1)")


def test_a_face_maps_its_resting_contacts_force_rows(carriage: Workspace) -> None:
    """A face's linear cones (resting flat, or one-sided) become equalities
    ``L x = rhs``: the row at ``lam_rows[j]`` is the cone's ``B`` (rhs its
    radius), those at ``f_rows`` its ``A`` rows (rhs 0)."""
    ws = carriage
    point = pipeline.optimum(ws, ws.asm.g / np.linalg.norm(ws.asm.g), np.zeros(len(ws.balls)))
    assert point.active is not None and point.active[1], "the carriage rests on flat faces"
    face = faces.face_of(ws, point.active)
    _, linear = point.active
    st = ws.stack
    L = linalg.dense(face.L)
    for j, i in enumerate(linear):
        assert np.array_equal(L[face.lam_rows[j]], linalg.dense(st.B[i : i + 1])[0])
        assert face.rhs[face.lam_rows[j]] == st.r[i]
    lin = st.take(linear)
    assert np.array_equal(L[face.f_rows], linalg.dense(lin.A))
    assert not np.any(face.rhs[face.f_rows])
    assert np.array_equal(face.linear_rows, st.rows_of(linear))
    assert faces.face_of(ws, point.active) is face  # built once, then kept


def _newton_one(
    face: Any,
    g_hat: np.ndarray,
    x0: np.ndarray,
    lam0: np.ndarray,
    accept: float = DEFAULT.newton_accept,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, Any] | None:
    """``newton.newton`` on a face, as a single solve runs it (a batch of
    one): (x, lam, nu, steps, factors), or None if it did not converge."""
    x, lam = x0[None].astype(float), np.asarray(lam0, dtype=float)[None].copy()
    nu = np.zeros((1, face.Eq.shape[0]))
    run = newton.newton(
        None,
        -g_hat[None],
        face.Eq,
        face.e[None],
        face.stack,
        x,
        lam,
        nu,
        DEFAULT,
        accept=accept,
        least_squares=True,
    )
    return (x[0], lam[0], nu[0], run.steps, run.factors) if run.converged[0] else None


def test_newton_returns_to_the_optimum_from_a_nearby_start(paper: Workspace) -> None:
    """From a start 1e-3 away (scaled), Newton on the optimum's active set
    comes back in a few steps to the point it finds from the optimum itself,
    to round-off, as quadratic convergence does; that point is the optimum
    to the certificate's tolerances (whichever route gave the optimum)."""
    ws = paper
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    point = pipeline.optimum(ws, g_hat, np.zeros(len(ws.balls)))
    assert point.active is not None
    surface, linear = point.active
    assert surface and not linear  # the paper's shaft leans on both cylinders' surfaces
    face = faces.face_of(ws, point.active)
    rng = np.random.default_rng(7)
    x0 = point.x + 1e-3 * rng.standard_normal(ws.m)
    lam0 = point.lam * (1 + 0.1 * rng.standard_normal(len(point.lam)))
    out = _newton_one(face, g_hat, x0, lam0[list(surface)])
    assert out is not None
    x, lam, _, iterations, factors = out
    assert iterations <= 8
    assert factors is not None and factors.regular(DEFAULT.free_motion_rcond)
    home = _newton_one(face, g_hat, point.x, point.lam[list(surface)])
    assert home is not None
    # a regular face (its LU's pivots 7.8e-3 and up): Newton's quadratic
    # convergence ends at round-off from any nearby start, on every machine
    assert np.max(np.abs(x - home[0])) * ws.asm.s <= 1e-12  # mm
    assert np.allclose(lam, home[1], rtol=1e-10, atol=0)
    # and that is the optimum, to the certificate's tolerances
    assert np.max(np.abs(home[0] - point.x)) * ws.asm.s <= MM
    top = max(1.0, float(np.max(point.lam)))  # the loads have unit norm here
    assert np.allclose(home[1], point.lam[list(surface)], rtol=0, atol=BALANCE * top)


def test_newton_gives_up_where_a_contact_has_no_direction(paper: Workspace) -> None:
    """At x = 0 every ball contact sits at its centre: the force direction
    ``A_i x / |A_i x|`` is undefined, and Newton says so (None) instead of
    dividing by zero."""
    ws = paper
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    point = pipeline.optimum(ws, g_hat, np.zeros(len(ws.balls)))
    assert point.active is not None
    face = faces.face_of(ws, point.active)
    lam0 = point.lam[list(point.active[0])]
    assert _newton_one(face, g_hat, np.zeros(ws.m), lam0) is None


def _kkt(duplicate: bool) -> tuple[np.ndarray, int]:
    """A KKT matrix ``[[H, J^T], [J, 0]]`` with H positive definite; with
    ``duplicate``, J repeats a row (forces statically indeterminate).

    The linear-algebra tests on it hold on every machine: a 6 x 6 or 7 x 7
    system, well conditioned but for its exact repeated row, whose solves'
    round-off is 1e-15, far inside their 1e-12 to 1e-8 bounds, and whose
    refinement counts follow from the factors' contraction, not round-off."""
    rng = np.random.default_rng(3)
    M = rng.standard_normal((4, 4))
    H = M @ M.T + 4 * np.eye(4)
    J = rng.standard_normal((2, 4))
    if duplicate:
        J = np.vstack([J, J[:1]])
    n = 4 + J.shape[0]
    K = np.zeros((n, n))
    K[:4, :4], K[:4, 4:], K[4:, :4] = H, J.T, J
    return K, 4


KKT = {"tol": 1e-13, "refinements": 8}  # round-off of these well-scaled systems: 1e-15
SHIFT = DEFAULT.kkt_round_off


def _solved(K: np.ndarray, rhs: np.ndarray, n: int, sparse: bool, shift: float) -> np.ndarray:
    step, _ = linalg.solve_kkt(sp.csc_matrix(K) if sparse else K, rhs, n, shift=shift, **KKT)
    return step


@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
@pytest.mark.parametrize("shift", [0.0, SHIFT], ids=["plain", "regularized"])
def test_a_regular_kkt_system_is_solved_exactly(sparse: bool, shift: float) -> None:
    K, n = _kkt(duplicate=False)
    rhs = np.arange(1.0, K.shape[0] + 1)
    step = _solved(K, rhs, n, sparse, shift)
    assert np.allclose(step, np.linalg.solve(K, rhs), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_indeterminate_forces_still_give_the_one_position_step(sparse: bool) -> None:
    """A repeated constraint row makes K singular but the system consistent.
    Regularized and refined, the step solves it and its position step is the
    one there is; its split of the multiplier between the copies is any
    (round-off of the regularized pivot decides it: Newton reads the
    positions only, ``forces.py`` splits the forces afterwards)."""
    K, n = _kkt(duplicate=True)
    want = np.r_[1.0, -2.0, 0.5, 3.0, 1.0, 2.0, 0.0]
    rhs = K @ want
    step = _solved(K, rhs, n, sparse, SHIFT)
    assert np.max(np.abs(K @ step - rhs)) <= KKT["tol"]
    assert np.allclose(step[:n], want[:n], rtol=0, atol=1e-9)
    assert step[4] + step[6] == pytest.approx(want[4] + want[6], abs=1e-9)


@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_a_singular_system_is_refused(sparse: bool) -> None:
    """No step solves an inconsistent system (the same row asked for two
    values), plain or regularized, and a K with a NaN cannot be factored:
    each raises ``SingularSystemError``, which Newton handles."""
    K, n = _kkt(duplicate=True)
    rhs = np.zeros(K.shape[0])
    rhs[4], rhs[6] = 1.0, -1.0
    with pytest.raises(linalg.SingularSystemError):
        _solved(K, rhs, n, sparse, SHIFT)
    with pytest.raises(linalg.SingularSystemError):
        _solved(K, rhs, n, sparse, 0.0)
    K[0, 0] = np.nan
    with pytest.raises(linalg.SingularSystemError):
        _solved(K, np.ones(K.shape[0]), n, sparse, SHIFT)


@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_a_badly_scaled_singular_system_is_solved_by_its_regularization(sparse: bool) -> None:
    """A tied face's KKT system holds a metric of lever squared beside rows
    of size 1 and a weak mode, and repeats rows. Its regularization is small
    against every pivot: a few steps of refinement are exact."""
    H = np.diag([1e8, 1.0, 3e-6])  # a lever squared, a unit stiffness, a weak mode
    J = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])  # a repeated row
    K = np.block([[H, J.T], [J, np.zeros((2, 2))]])
    want = np.r_[1.0, 2.0, -1.0, 0.5, 0.5]
    rhs = K @ want
    matrix = sp.csc_matrix(K) if sparse else K
    step, factors = linalg.solve_kkt(matrix, rhs, 3, tol=1e-14, refinements=3, shift=SHIFT)
    assert factors is None  # regularized: its pivots say nothing of K's rank
    assert np.allclose(step[:3], want[:3], rtol=0, atol=1e-12)
    assert step[3] + step[4] == pytest.approx(1.0, abs=1e-12)  # the repeated row's share


def test_sparse_least_squares_are_the_least_norm_ones() -> None:
    """``linalg.lstsq`` on a sparse, rank-deficient A (redundant rigid rows:
    a column repeated) gives the dense SVD's least-norm solution, to 1e-8
    of its largest value (two routes: the certificate's tolerance)."""
    rng = np.random.default_rng(5)
    A = rng.standard_normal((12, 4))
    A = np.hstack([A, A[:, :1]])  # a repeated column: the shares of two copies
    b = rng.standard_normal(12)
    want = np.linalg.lstsq(A, b, rcond=None)[0]
    got = linalg.lstsq(sp.csr_matrix(A), b, DEFAULT.lstsq_rcond, DEFAULT.kkt_refinements)
    top = float(np.max(np.abs(want)))
    assert np.allclose(got, want, rtol=0, atol=1e-8 * top)
    assert got[0] == pytest.approx(got[4], abs=1e-8 * top)


def test_a_sparse_system_with_an_empty_row_or_column_never_reaches_superlu(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """SuperLU, given a sparse system singular by its pattern, fails after
    filling it in and has corrupted memory doing so (a segmentation fault
    in 2 solves of 6 of one such KKT system); a bearing chain's polish meets
    systems with an empty row and column per free spin. ``linalg._factored``
    says None for them without calling it (a stored 0 counts as empty); a
    regular system, and one singular by its values only (which SuperLU
    refuses cleanly), still go to SuperLU."""
    import scipy.sparse.linalg as spla

    calls = calls_to(monkeypatch, spla, "splu")
    empty_column = sp.csc_matrix(np.array([[2.0, 1.0, 0.0], [1.0, 3.0, 0.0], [4.0, 0.0, 0.0]]))
    assert linalg._factored(empty_column) is None
    assert linalg._factored(sp.csr_matrix(empty_column.T)) is None  # an empty row
    stored_zero = sp.csc_matrix(
        (np.array([1.0, 0.0, 1.0]), (np.array([0, 1, 2]), np.array([0, 1, 2]))), shape=(3, 3)
    )
    assert linalg._factored(stored_zero) is None
    assert not calls
    regular = sp.csc_matrix(np.array([[2.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 4.0]]))
    solve = linalg._factored(regular)
    assert solve is not None and len(calls) == 1
    b = np.array([1.0, 2.0, 3.0])
    assert np.allclose(regular @ solve(b), b, rtol=0, atol=1e-14)
    by_values = sp.csc_matrix(np.array([[1.0, 2.0], [2.0, 4.0]]))
    assert linalg._factored(by_values) is None and len(calls) == 2


def test_a_long_string_s_force_split_is_the_same_from_either_start() -> None:
    """The sparse least-squares split refines the route's forces: on a
    500-segment tube string each body's balance rows repeat each other
    (a tube's contacts hold four of its six directions), the multipliers
    are 3,000 against forces of 1, and the refinement's residual sits at
    their round-off. Stopped by it, the split was 2.4e-8 of the largest
    force apart from two starts (the interior point refined or not), and
    the 1,000-segment string's joints carried moments of 0.15 N mm that
    the rule does not give; taken by their span and refined until the
    forces settle, they agree (two routes: to the certificate's balance,
    ``equilibrium_tolerance`` of the largest force)."""
    from dataclasses import replace

    from jointplay.assembly import assemble
    from jointplay.io.generate import tube_string

    asm = assemble(tube_string(500))
    plain = Workspace(asm).solve()
    fine = Workspace(asm, replace(DEFAULT, sparse_interior_refinement=True)).solve()
    pairs = [
        (c.force, d.force)
        for name, joint in fine.joints.items()
        for c, d in zip(plain.joints[name].contacts, joint.contacts, strict=True)
    ]
    top = max(float(np.linalg.norm(d)) for _, d in pairs)
    for c, d in pairs:
        np.testing.assert_allclose(c, d, rtol=0, atol=DEFAULT.equilibrium_tolerance * top)
    for result in (plain, fine):
        result.check()  # certified, and balanced per body to equilibrium_tolerance


TIGHT_DRIVE = {"type": "revolute", "axis": [1, 0, 0], "length": 40, "clearance": 0}
TIGHT_DRIVE |= {"axial_clearance": 0, "backlash": 0}


@pytest.mark.parametrize(
    ("joint", "axis"), [({"type": "rigid"}, 5), (TIGHT_DRIVE, 3)], ids=["weld", "tight drive"]
)
def test_the_certificate_measures_a_rigid_turn_across_the_mechanism(
    joint: dict[str, Any], axis: int
) -> None:
    """A rigid row of a turn alone (a weld's, or a tight drive's: the angle
    times its lever) counts as the opening w * ell that the turn makes
    across the mechanism, as every other feasibility is in mm. The weld's
    turn was counted as if it were mm: a weld left turned by 4.5e-10 rad
    across 10.6 mm (4.7e-9 mm open) was certified
    (open/weld_left_open_by_a_tie, found by the property search). A tight
    drive's row is counted over its own lever first, not times ell twice
    (a review: that declined right answers)."""
    from conftest import spherical_shaft
    from jointplay.solver import certificate

    data = spherical_shaft()
    data["bodies"] = [*data["bodies"], {"name": "S2"}]  # type: ignore[list-item]
    data["joints"] = [  # type: ignore[list-item]
        *data["joints"],  # type: ignore[misc]
        {"name": "tight", "between": ["S1", "S2"], "at": [300, 0, 0], **joint},
    ]
    ws = Workspace.of(jointplay.model_from_dict(data))
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    sigma = np.zeros(len(ws.balls))
    point = pipeline.optimum(ws, g_hat, sigma)
    # certified: inside its play to 1e-9 of it (2e-10 mm), below the opening's 1e-8 mm
    assert point.certificate is not None and point.certificate.certified
    turn = 1e-10  # rad, S2 alone, about the joint's axis (x) or z: only its turn rows see it
    x = point.x.copy()
    x[6 * 1 + axis] += turn / ws.asm.turn[1]
    opened = records.Point(x, point.lam, point.f, point.method)
    got = certificate.certify(ws, g_hat, sigma, opened, point.nu).feasibility_mm
    assert ws.asm.ell >= 100.0  # the shaft: 1e-8 mm or more, not 1e-10 (nor 2e-7 a drive)
    assert got == pytest.approx(turn * ws.asm.ell, rel=1e-6)


def test_the_status_map_and_the_program_agree_on_a_solve(paper: Workspace) -> None:
    """One raw Clarabel call on the workspace's program is ``optimal`` in our
    words, and its dual is the optimum's contact forces before the polish."""
    ws = paper
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    sol = conic.run(ws, conic.interior_program(ws), -g_hat)
    assert conic.outcome(sol) == "optimal"
    point = pipeline.optimum(ws, g_hat, np.zeros(len(ws.balls)))
    z = np.asarray(sol.z)
    assert np.allclose(z[conic.interior_program(ws).soc_first], point.lam, rtol=1e-6, atol=1e-9)


def test_the_batched_rank_test_gives_the_svds_verdict() -> None:
    # stacks of 11 x 6 matrices with chosen singular values: well conditioned,
    # rank deficient, and smallest singular value either side of rcond (which
    # the Gram matrix cannot resolve: the SVD decides those)
    rng = np.random.default_rng(3)
    rcond = 1e-9
    smallest = [1.0, 1e-3, 1e-7, 3e-9, 1e-9 * 1.01, 1e-9 * 0.99, 1e-12, 0.0]
    stacks = []
    for s in smallest:
        U, _ = np.linalg.qr(rng.normal(size=(11, 6)))
        V, _ = np.linalg.qr(rng.normal(size=(6, 6)))
        stacks.append(U @ np.diag([7.0, 3.0, 2.0, 1.0, 0.5, 7.0 * s]) @ V.T)
    J = np.array([*stacks, np.zeros((11, 6))])
    sv = np.linalg.svd(J, compute_uv=False)
    expected = (sv[:, 0] > 0) & (sv[:, 5] > rcond * sv[:, 0])
    np.testing.assert_array_equal(linalg.full_column_rank_rows(J, rcond), expected)
    assert expected.tolist() == [True] * 5 + [False] * 4  # the cases are what they say
    # fewer rows than unknowns never pin them
    assert not np.any(linalg.full_column_rank_rows(J[:, :5], rcond))
    # any two together: both of full rank take the Cholesky route (one
    # factorization of the stack), any other pair the eigenvalues or the SVD
    for i in range(len(J)):
        for j in range(len(J)):
            got = linalg.full_column_rank_rows(J[[i, j]], rcond)
            np.testing.assert_array_equal(got, expected[[i, j]])
            coarse = (sv[[i, j], 0] > 0) & (sv[[i, j], 5] > 3e-3 * sv[[i, j], 0])
            np.testing.assert_array_equal(linalg.full_column_rank_rows(J[[i, j]], 3e-3), coarse)
    # a coarse rcond, which the Gram route alone would not resolve (review):
    # a smallest singular value 1e-3 of the largest is below 3e-3
    coarse = linalg.full_column_rank_rows(J, 3e-3)
    assert coarse.tolist() == [True] + [False] * 8
    # any scale: no overflow or denormals in the Gram matrices; no verdict
    # on a matrix with a non-finite entry
    for scale in (1e-160, 1e155):
        np.testing.assert_array_equal(linalg.full_column_rank_rows(J * scale, rcond), expected)
    bad = J[:2].copy()
    bad[0, 0, 0], bad[1, 0, 0] = np.inf, np.nan
    assert not np.any(linalg.full_column_rank_rows(bad, rcond))


def test_newton_converges_on_a_bearing_chain_s_active_set() -> None:
    """Near its answer, Newton's right side is tiny (7.5e-7) and the step
    large (2e-3): a KKT tolerance relative to the right side alone (7.5e-17)
    lay below the round-off of the step's residual (2.9e-16), every step was
    refused, and no polish of a 100-shaft bearing chain converged. A step is
    solved once its residual is below Newton's own stopping point."""
    from jointplay.io.generate import bearing_chain

    ws = Workspace.of(bearing_chain(100))
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    sigma = np.zeros(len(ws.balls))
    start = pipeline.interior_point(ws, g_hat, sigma)
    key = faces.active_set(ws, start.x, start.lam, start.f, ws.stack)
    found = newton.kkt_point(ws, g_hat, sigma, key, start.x, start.lam, 0, "p", pinned=False)
    assert found is not None
    _, _, level = ws.stack.levels(found.x)
    on = list(key[0])
    assert np.max(np.abs(level[on] - ws.stack.r[on])) <= DEFAULT.newton_accept * ws.max_radius


@pytest.mark.parametrize("kind", ["bearing", "chain"])
def test_a_large_face_s_rank_test_agrees_with_the_free_motions_rows_and_is_quick(
    kind: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A large face's rank test leaves out the rows that pin the free motions
    (``K``): through the least-norm metric they couple each body to its
    neighbours' neighbours, and the elimination then went two bodies a round
    (501 rounds for 1,000 shafts). Without them it halves the chain each
    round, and gives the same verdict: a tie on the bearing chain (its axial
    positions), none on the tube string."""
    from jointplay.io.generate import bearing_chain, tube_string
    from jointplay.numerics import free_motions

    n = 200
    ws = Workspace.of(bearing_chain(n) if kind == "bearing" else tube_string(n))
    assert ws.sparse
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    start = pipeline.interior_point(ws, g_hat, np.zeros(len(ws.balls)))
    key = faces.active_set(ws, start.x, start.lam, start.f, ws.stack)
    face = faces.face_of(ws, key)
    rows = linalg.vstack([face.L, face.stack.A], ws.m)
    with_k = linalg.full_column_rank(
        linalg.vstack([ws.Eq, rows], ws.m), ws.m, DEFAULT.free_motion_rcond
    )
    rounds: list[int] = []
    eliminate = free_motions._eliminate

    def counted(*args: object) -> object:
        out = eliminate(*args)  # type: ignore[arg-type]
        rounds.append(out.rounds)
        return out

    monkeypatch.setattr(free_motions, "_eliminate", counted)
    assert faces.pins_position(ws, rows) == with_k == (kind == "chain")
    assert rounds and max(rounds) <= 2 * np.log2(n) + 2, rounds


def test_a_large_face_s_rank_test_counts_at_the_free_motions_threshold() -> None:
    """The face's count of free motions is compared with ``N``'s, so it is
    taken at ``N``'s threshold (relative to every limit row's scale, not the
    face rows' smaller one). Here one body's direction is held at 3e-9 of a
    stiff row the face leaves out: ``N`` calls it free, the face rows alone
    would call it held, and that count hid a direction the face truly leaves
    free (a review)."""
    from types import SimpleNamespace

    from jointplay.numerics import free_motions
    from jointplay.settings import DEFAULT

    bodies = 41
    m = 6 * bodies
    unit = np.eye(m)
    weak = unit[0] * 3e-9  # body 0's x: held 3e-9 as firmly as the stiff row
    stiff = 20.0 * unit[6 * 5 + 1]
    rows = [weak, *unit[1:]]
    limits = sp.csr_matrix(np.vstack([*rows, stiff]))
    N = linalg.null_space(limits, m, DEFAULT.free_motion_rcond, DEFAULT.round_off)
    assert N.shape[1] == 1  # the weak direction
    ws = SimpleNamespace(
        E=sp.csr_matrix((0, m)),
        N=N,
        m=m,
        sparse=True,
        settings=DEFAULT,
        limit_scale=free_motions.largest_singular_value(limits),
    )
    ws.Eq = linalg.vstack([ws.E, sp.csr_matrix(N.T)], m)
    free = 6 * 7 + 2  # the face leaves body 7's z free
    face = sp.csr_matrix(np.vstack([r for i, r in enumerate(rows) if i != free]))
    with_k = linalg.full_column_rank(linalg.vstack([ws.Eq, face], m), m, DEFAULT.free_motion_rcond)
    assert faces.pins_position(ws, face) is with_k is False  # type: ignore[arg-type]


def test_a_sparse_tie_s_least_norm_polish_never_factors_its_singular_system_plainly(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A sparse face keeps its rows as they are (``ties.independent_rows``),
    and a face's rows repeat each other: the least-norm polish's KKT system
    is then singular by construction, and its Newton steps are regularized
    from the start (``newton(..., repeated_rows=True)``). A plain SuperLU
    factorization of it only fails, after filling in: on a 4,000-shaft
    bearing chain 3.8 s and 1.2 GB of the solve. Here, a 50-shaft chain
    (sparse above 40 bodies): every factorization inside that polish, when
    the route takes it (round-off of a degenerate chain), must succeed, and
    the answer certifies."""
    from jointplay.io.generate import bearing_chain
    from jointplay.solver import ties

    inside, singular = [False], []
    factored, polish = linalg._factored, ties.polish_least_norm

    def watched_factored(K: Any) -> Any:
        out = factored(K)
        if inside[0] and out is None:
            singular.append(K.shape)
        return out

    def watched_polish(*args: Any, **kwargs: Any) -> Any:
        inside[0] = True
        try:
            return polish(*args, **kwargs)
        finally:
            inside[0] = False

    monkeypatch.setattr(linalg, "_factored", watched_factored)
    monkeypatch.setattr(ties, "polish_least_norm", watched_polish)
    jointplay.solve(bearing_chain(50)).check()
    assert singular == []


def test_the_no_load_least_norm_polish_keeps_its_plain_steps() -> None:
    """Only a tied face's rows repeat each other: the no-load route's
    least-norm program holds the workspace's own equalities, independent,
    and its Newton steps stay plain. Regularized from the start (as for a
    face), they fell 1.6e-11 short of their tolerance on this 700-shaft
    chain with bearings moved off their axes by a deviation, and the
    position was declined (a review of ``repeated_rows``)."""
    from jointplay.io.generate import bearing_chain_dict
    from jointplay.io.modelfile import model_from_dict

    data = bearing_chain_dict(700)
    data["loads"] = []
    for joint in data["joints"]:
        if joint["name"].startswith("bearing") and int(joint["name"][7:]) % 3 == 0:
            joint["deviation"] = {"position": {"diameter": 0, "mean": [0, 0.13, 0.039]}}
    result = jointplay.solve(model_from_dict(data, source="<no-load chain>"))
    result.check()  # certified (a no-load answer: feasibility alone)
    assert result.certificate.feasibility_mm <= 1e-6


def test_segment_sums_skip_cones_with_no_rows() -> None:
    """``BallStack.segment_sum`` of cones some of which have no rows (one-sided
    limits): each cone's sum over its rows, 0 for none, for one row of
    weights or a batch, equal to a plain loop over the cones."""
    from jointplay.assembly import BallStack

    rng = np.random.default_rng(3)
    for _ in range(50):
        k = rng.integers(0, 4, size=int(rng.integers(1, 12)))
        start = (np.cumsum(k) - k).astype(np.intp)
        n_rows = int(k.sum())
        stack = BallStack(
            np.zeros((n_rows, 6)),
            start,
            k.astype(np.intp),
            np.ones(len(k)),
            np.zeros(len(k)),
            np.zeros((len(k), 6)),
        )
        w = rng.standard_normal((3, n_rows))
        expected = np.array(
            [[row[s : s + n].sum() for s, n in zip(start, k, strict=True)] for row in w]
        )
        assert np.allclose(stack.segment_sum(w), expected, rtol=0, atol=1e-14)
        assert np.allclose(stack.segment_sum(w[0]), expected[0], rtol=0, atol=1e-14)


def test_a_declined_answer_names_the_checks_it_fails_with_their_limits() -> None:
    """The decline's message names each check of the certificate the answer
    fails, with its value and its own limit, and no check it passes: a
    19-shaft bearing chain was declined on complementarity alone while the
    message listed feasibility, balance and the smallest force, all inside
    their limits; and the force checks' limit is relative to the largest
    force when that is above the loads' size, not the tolerance alone."""
    from jointplay.errors import SolverError
    from jointplay.settings import SolverSettings

    def declined(name: str, settings: SolverSettings) -> str:
        with pytest.raises(SolverError) as caught:
            jointplay.solve(jointplay.load(ROOT / "examples" / name), settings)
        return str(caught.value)

    said = declined("paper/6.1.6.1.yaml", SolverSettings(equilibrium_tolerance=1e-30))
    assert "balance the loads on each body only to" in said and "(1e-30 asked)" in said
    assert "a contact that does not touch pushes" in said
    assert "pulls" not in said and "past its clearance" not in said and "rigid" not in said
    # the four-bar's largest force is 1.58 times its loads' size: so is the limit
    said = declined("gallery/four_bar.yaml", SolverSettings(equilibrium_tolerance=1e-30))
    assert "1.58e-30 allowed" in said
    # a weld's rows that open are named as such, in mm (3e-32 mm: 1e-30 of 0.03 mm)
    said = declined("gallery/lathe_slide.yaml", SolverSettings(feasibility_tolerance=1e-30))
    assert "a rigid joint open by" in said and "mm (3e-32 allowed)" in said


def test_a_route_s_certificate_serves_the_answer_when_the_contacts_carry_the_whole_load() -> None:
    """With no rigid rows the contacts carry the whole load: the route's
    answer is the answer, and its certificate is kept, not computed again;
    it equals the one the answer gets afresh (the same checks of the same
    numbers: equal on every machine)."""
    from jointplay.solver import certificate

    ws = Workspace.of(jointplay.load(ROOT / "examples" / "paper" / "6.1.6.1.yaml"))
    assert not ws.E.shape[0]
    ws.solve()
    ws.solve().check()  # warm
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    sigma = np.zeros(len(ws.balls))
    point = pipeline.optimum(ws, g_hat, sigma)
    fresh = certificate.certify(ws, g_hat, sigma, point, point.nu)
    assert fresh == point.certificate


def test_a_declined_tie_says_the_optimum_is_not_unique() -> None:
    """A tie's answer that fails its certificate is declined with the tie
    named (a degenerate chain of bearings is declined so, and its weakest
    motion alone, held 39 times less firmly than the best, misled); an
    answer that pins the position is not called a tie."""
    from jointplay.errors import SolverError
    from jointplay.settings import SolverSettings

    strict = SolverSettings(equilibrium_tolerance=1e-30)
    said = {}
    for name in ("gallery/four_bar.yaml", "paper/6.1.6.1.yaml"):
        with pytest.raises(SolverError) as caught:
            jointplay.solve(jointplay.load(ROOT / "examples" / name), strict)
        said[name] = str(caught.value)
    assert pipeline.TIE_HINT in said["gallery/four_bar.yaml"]
    assert pipeline.TIE_HINT not in said["paper/6.1.6.1.yaml"]
    jointplay.solve(jointplay.load(ROOT / "examples" / "gallery" / "four_bar.yaml")).check()


@pytest.mark.parametrize("shafts", [19])
def test_a_degenerate_chain_s_rounds_drop_one_contact_at_a_time(shafts: int) -> None:
    """On a bearing chain many contacts touch with no force, and the
    interior point's active set is off along the chain: the active-set
    rounds walk it one contact a round. Dropping every weak contact at
    once, the contacts that touch with no force left and rejoined round
    after round, no start found the optimum and these chains were declined.
    How many rounds a start walks is round-off (5 to 15 Newton runs on the
    newest libraries, 11 on the lowest): the promise is the certificate."""
    from jointplay.io.generate import bearing_chain

    result = jointplay.solve(bearing_chain(shafts))
    result.check()
    assert result.certificate.feasibility_mm <= 1e-6


@pytest.mark.parametrize("shafts", [20, 22, 39])
def test_a_round_whose_positions_pushing_forces_hold_is_the_optimum(shafts: int) -> None:
    """On a bearing chain more contacts touch than the positions need, and
    Newton's forces on such a set are one split of many: some pull, yet the
    split of the touching contacts pushes and balances the loads there, so
    the positions are optimal (``pipeline.split_optimum``); 20 and 22
    shafts depend on the file order here
    (tests/property_cases/bearing_chain_of_20_shafts_declined_in_another_order.yaml).
    Which correction ends the walk is round-off: the promise is the
    certificate."""
    from jointplay.io.generate import bearing_chain

    result = jointplay.solve(bearing_chain(shafts))
    result.check()
    assert result.certificate.feasibility_mm <= 1e-6


def test_a_large_model_s_interior_point_goes_unrefined() -> None:
    """Iterative refinement of Clarabel's steps doubled its time on large
    (sparse) models (10,000-segment chain: 2.0 s against 0.86 s) and buys
    their answer nothing: Newton's polish ends at round-off from either
    start. Small models keep it (degenerate ones need it: bearing chains of
    17 to 21 shafts were declined without it on the lowest versions), and so
    does the retry (``SolverSettings.retry``)."""
    from dataclasses import replace

    from jointplay.assembly import assemble
    from jointplay.io.generate import bearing_chain, tube_string

    small, large = Workspace(assemble(bearing_chain(5))), Workspace(assemble(tube_string(300)))
    assert conic.interior_program(small).settings.iterative_refinement_enable
    assert not conic.interior_program(large).settings.iterative_refinement_enable
    retry = large.with_settings(large.settings.retry())
    assert conic.interior_program(retry).settings.iterative_refinement_enable
    refined = Workspace(large.asm, replace(DEFAULT, sparse_interior_refinement=True))
    plain, fine = large.solve(), refined.solve()
    for result in (plain, fine):
        result.check()
    for name, body in fine.bodies.items():
        np.testing.assert_allclose(plain.bodies[name].translation, body.translation, atol=1e-6)
        np.testing.assert_allclose(plain.bodies[name].rotation, body.rotation, atol=1e-8)
    pairs = [
        (c.force, d.force)
        for name, joint in fine.joints.items()
        for c, d in zip(plain.joints[name].contacts, joint.contacts, strict=True)
    ]
    top = max(float(np.linalg.norm(d)) for _, d in pairs)
    for c, d in pairs:  # N: to the certificate's balance, 1e-8 of the largest force
        np.testing.assert_allclose(c, d, rtol=0, atol=1e-8 * top)


def test_a_large_model_s_tie_program_goes_unrefined(monkeypatch: pytest.MonkeyPatch) -> None:
    """A tie's least-norm program goes without Clarabel's iterative
    refinement on a large (sparse) model too: its answer is where the
    polish starts, and long chains' polish succeeds since its systems are
    equilibrated (``test_a_long_bearing_chain_s_tie_certifies``). Refined,
    it cost twice as much (10,000-shaft bearing chain: 3.7 s in 15 steps
    against 1.8 s in 13); the polished positions moved 1.5e-12 mm (1,000
    shafts). Where the polish fails (a 135-shaft chain) the program's own
    answer is printed if it certifies, else the retry refines. A small
    model's is refined."""
    from jointplay.io.generate import bearing_chain
    from jointplay.solver import ties

    refined: list[bool] = []
    program = ties.conic.cone_program

    def spied(ws: Workspace, P: Any, *args: Any, **kwargs: Any) -> Any:
        if "regularization" in kwargs:  # only the tie's program sets its own
            refined.append(kwargs.get("refine", True))  # cone_program's default
        return program(ws, P, *args, **kwargs)

    monkeypatch.setattr(ties.conic, "cone_program", spied)
    for shafts, want in ((20, True), (135, False), (300, False)):
        refined.clear()
        jointplay.solve(bearing_chain(shafts)).check()
        # the first try's, if its route meets the tie (round-off of a degenerate chain)
        assert refined[:1] in ([], [want])


def test_a_route_that_fails_a_step_takes_the_one_retry(monkeypatch: pytest.MonkeyPatch) -> None:
    """A step of the first try that cannot be done (a tie's least-norm
    program stopping short: the 45-shaft bearing chain on the newest
    versions, once its interior point went unrefined) is retried like an
    answer that fails its certificate (``SolverSettings.retry``); if the
    retry fails too, the first try's error is the one raised."""
    from jointplay.assembly import assemble
    from jointplay.errors import SolverError

    model = jointplay.load(Path(__file__).parents[1] / "examples" / "paper" / "6.1.6.1.yaml")
    route = pipeline.contacts_optimum
    tries: list[float] = []

    def first_fails(ws: Workspace, *args: Any) -> Any:
        tries.append(ws.settings.ipm_tolerance)
        if ws.settings.ipm_tolerance == DEFAULT.ipm_tolerance:
            raise SolverError("the first try's step")
        return route(ws, *args)

    monkeypatch.setattr(pipeline, "contacts_optimum", first_fails)
    result = jointplay.solve(model)
    # the first try fails by hand, so the tries are the same on every machine
    assert tries == [DEFAULT.ipm_tolerance, DEFAULT.fine_ipm_tolerance]
    assert_same_answer(result, Workspace(assemble(model), DEFAULT.retry()).solve())

    def both_fail(ws: Workspace, *args: Any) -> Any:
        raise SolverError(f"step at {ws.settings.ipm_tolerance:g}")

    monkeypatch.setattr(pipeline, "contacts_optimum", both_fail)
    with pytest.raises(SolverError, match="step at 1e-10"):
        jointplay.solve(model)


def test_a_large_model_s_verdict_comes_from_a_refined_solve(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A large model's interior point goes unrefined (Newton's start), but
    "not held" (exit 3) and "cannot be assembled" (exit 2) are verdicts:
    the status that gives one is read again from a refined solve (a review:
    none differed in 332 large models, but a verdict should not rest on
    the cheaper solve). A 45-shaft bearing chain beside a plate on three
    feet pushed down outside them (it tips)."""
    from jointplay.io.generate import bearing_chain_dict
    from jointplay.io.modelfile import model_from_dict

    data = bearing_chain_dict(45)
    data["bodies"].append({"name": "plate"})
    feet = [(-5.0, 0.0), (2.5, 4.330127018922193), (2.5, -4.330127018922193)]
    for i, (x, y) in enumerate(feet):
        data["joints"].append(
            {"name": f"foot{i}", "type": "point", "between": ["ground", "plate"],
             "at": [x, y, -50.0], "axis": [0, 0, 1]}
        )  # fmt: skip
    data["joints"].append(
        {"name": "pin", "type": "sphere_in_cylinder", "between": ["ground", "plate"],
         "at": [0, 0, -50.0], "axis": [0, 0, 1], "clearance": 1.0}
    )  # fmt: skip
    data["loads"].append({"body": "plate", "at": [4.0, 0.0, -50.0], "force": [0.2, 0.0, -1.0]})
    solves: list[tuple[bool, str]] = []
    made = conic.clarabel.DefaultSolver

    class Counted:
        def __init__(self, *args: Any) -> None:
            self.refined = bool(args[-1].iterative_refinement_enable)
            self.solver = made(*args)

        def solve(self) -> Any:
            sol = self.solver.solve()
            solves.append((self.refined, conic.status_name(sol)))
            return sol

    monkeypatch.setattr(conic.clarabel, "DefaultSolver", Counted)
    with pytest.raises(jointplay.UnboundedMechanismError, match="plate"):
        jointplay.solve(model_from_dict(data))
    # the first program is unrefined (a setting), the verdict a refined solve's
    # (Clarabel's words for it, exact or "almost", are its own)
    assert solves[0][0] is False and solves[-1][0] is True
    assert conic.STATUS[solves[-1][1]] == "unbounded"


def test_a_preload_the_first_try_cannot_find_takes_the_one_retry() -> None:
    """A closed 60-segment string whose bearings sit three plays off centre
    on springs of 1e12 N/mm: pressed at no load, by forces the no-load
    compliant program (``pipeline.load_scale``'s preload) did not find at
    the usual settings ("stopped with status MaxIterations"), and the solve
    was declined before its answer's own retry (a review). The preload now
    takes the same one retry (``pipeline.retry_of``), and the answer certifies."""
    from jointplay.io.generate import tube_string_dict
    from jointplay.io.modelfile import model_from_dict

    data = tube_string_dict(60, closed=True)
    rng = np.random.default_rng(0)
    for joint in data["joints"]:
        if joint["name"].startswith("bearing"):
            turn = rng.uniform(0.0, 2.0 * np.pi)
            y, z = 3.0 * joint["clearance"] * np.cos(turn), 3.0 * joint["clearance"] * np.sin(turn)
            joint["deviation"] = {
                "position": {"y": {"min": y, "max": y}, "z": {"min": z, "max": z}}
            }
            joint["stiffness"] = 1e12
    result = jointplay.solve(model_from_dict(data))
    result.check()
    assert result.certificate.certified


def test_a_long_string_s_faint_contacts_join_from_the_interior_point_s_loads() -> None:
    """On a long tube string the interior point's active set misses a
    contact it loads faintly (2,000 segments: one; 10,000: 389), and Newton
    on that set fails. The polish's next start is the set with every contact
    the interior point loads strictly, which holds them (the search for
    holders, ``faces.holders``, is then not needed: 10,000 segments, 5.0-5.4 s
    to 3.7 s). Which start ends the walk is round-off: the promise is the
    certificate."""
    from jointplay.io.generate import tube_string

    result = jointplay.solve(tube_string(2000))
    result.check()
    assert result.certificate.feasibility_mm <= 1e-6


def calls_to(monkeypatch: pytest.MonkeyPatch, owner: Any, name: str) -> list[int]:
    """A list that grows by one at each call of ``owner.name`` (patched)."""
    calls: list[int] = []
    function = getattr(owner, name)

    def counted(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        return function(*args, **kwargs)

    monkeypatch.setattr(owner, name, counted)
    return calls


@pytest.mark.parametrize("shafts", [2000, 3000])
def test_a_long_bearing_chain_s_tie_certifies(shafts: int) -> None:
    """A long chain's tie certifies. Its least-norm point's KKT system
    holds the metric (lever squared: 4e6 on 2,000 shafts) beside rows of
    size 1; before its regularized factorization was equilibrated the
    polish failed on chains of 600 to 2,000 shafts, and the 3,000-shaft
    chain was declined at its first try (its tie's program then ran at
    ``ipm_regularization``). Whether the polish, the program's own answer
    or the retry gives the answer is round-off of a degenerate problem, and
    differs from CPU to CPU (on an EPYC the 2,000-shaft chain's first try is
    declined and its retry certifies): the promise is the certificate."""
    from jointplay.io.generate import bearing_chain

    result = jointplay.solve(bearing_chain(shafts))
    result.check()  # certified, and balanced per body to equilibrium_tolerance
    assert result.certificate.feasibility_mm <= 1e-6


@pytest.mark.parametrize("sparse", [False, True], ids=["dense", "sparse"])
def test_factors_tell_a_regular_system_from_one_singular_but_for_round_off(sparse: bool) -> None:
    """An LU's pivots say whether K is regular (none below the rank cutoff
    ``free_motion_rcond`` of the largest): a KKT system with independent
    rows is; one whose repeated row differs by round-off is not, though it
    factors (its last pivot is round-off, not 0: without a cutoff it would
    pass, and a tie or an indeterminate split would be taken for a unique
    one)."""
    K, _ = _kkt(duplicate=False)
    made = sp.csc_matrix if sparse else np.asarray
    regular = linalg._factored(made(K))
    assert regular is not None and regular.regular(DEFAULT.free_motion_rcond)
    D, _ = _kkt(duplicate=True)
    D[-1, :4] *= 1.0 + 1e-14  # the repeated row, and its column, off by round-off
    D[:4, -1] = D[-1, :4]
    nearly = linalg._factored(made(D))
    assert nearly is not None, "it factors: only its pivots show the rank"
    assert not nearly.regular(DEFAULT.free_motion_rcond)
    assert nearly.regular(0.0)


def test_a_regular_newton_system_answers_for_its_face_and_its_forces(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Newton's last system on a large face is regular (its LU's pivots):
    the face pins the position and its forces are the only ones, so the
    face's elimination (a 1,000-segment loop: 0.09 s; 10,000: 0.65 s) and
    the split's least squares are skipped. The answer is the one they give,
    to the certificate's tolerances (positions to its feasibility, forces to
    its balance), not to the bit. The loop's face is regular by far (pivots
    1.5e-3 against the cutoff 1e-9): its verdict is the same on every machine."""
    from jointplay.io.generate import tube_string

    model = tube_string(60, closed=True)
    ws = Workspace.of(model)
    assert ws.sparse
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    best = pipeline.optimum(ws, g_hat, np.zeros(len(ws.balls)))
    assert faces.pins_by_newton(best) and best.certificate is not None
    assert best.certificate.certified
    # the same faces, tested and split as a face whose system says nothing
    monkeypatch.setattr(newton.linalg.Factors, "regular", lambda self, cutoff: False)
    other = pipeline.optimum(Workspace.of(model), g_hat, np.zeros(len(ws.balls)))
    assert not faces.pins_by_newton(other)
    assert other.certificate is not None and other.certificate.certified
    reach = DEFAULT.feasibility_tolerance * ws.max_radius
    assert np.max(np.abs(best.x - other.x)) <= reach
    top = max(1.0, float(np.max(np.abs(other.lam))))
    assert np.max(np.abs(best.lam - other.lam)) <= DEFAULT.equilibrium_tolerance * top


def test_a_face_without_its_unloaded_contacts_is_tested_for_a_tie(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Newton's system speaks for the face it was solved on. A round that
    drops contacts that touch with no force (they do not bound a tie, and a
    bearing chain's axial plays tie without them) leaves a smaller face,
    which the elimination tests: the answer is not marked regular."""
    from jointplay.io.generate import tube_string

    ws = Workspace.of(tube_string(60, closed=True))
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    weak = newton.weak_forces
    dropped: list[int] = []

    def one_unloaded(ws_: Workspace, point: records.Point, key: records.FaceKey) -> Any:
        out = weak(ws_, point, key)
        if out.size or point.regular_on is None:
            return out
        dropped.append(key[0][0])  # as if its force were round-off
        return np.array(dropped[-1:], dtype=np.intp)

    monkeypatch.setattr(newton, "weak_forces", one_unloaded)
    # the dropped contact is chosen by hand: which test runs follows from it on every machine
    eliminated = calls_to(monkeypatch, faces, "_eliminated")
    best = pipeline.optimum(ws, g_hat, np.zeros(len(ws.balls)))
    assert dropped and best.active is not None and dropped[-1] not in best.active[0]
    assert best.regular_on is not None and dropped[-1] in best.regular_on[0]
    assert not faces.pins_by_newton(best) and eliminated


def test_a_newton_run_that_ends_on_a_failed_step_hands_on_no_factors(
    monkeypatch: pytest.MonkeyPatch, paper: Workspace
) -> None:
    """When a step's system cannot be solved the run ends at its best point,
    and the factors of an earlier system say nothing of it: none are
    returned (a review's find: they were, and a point could be marked as
    pinning its face on another system's word)."""
    g_hat = paper.asm.g / np.linalg.norm(paper.asm.g)
    point = pipeline.optimum(paper, g_hat, np.zeros(len(paper.balls)))
    assert point.active is not None
    surface = list(point.active[0])
    face = faces.face_of(paper, point.active)
    x0 = point.x + 1e-6 * np.random.default_rng(1).standard_normal(paper.m)
    solve = linalg.solve_kkt
    calls: list[int] = []

    def second_fails(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        if len(calls) >= 2:  # the second step's solves, plain and regularized
            raise linalg.SingularSystemError
        return solve(*args, **kwargs)

    # the failure is injected at the second step: the same on every machine
    monkeypatch.setattr(newton.linalg, "solve_kkt", second_fails)
    monkeypatch.setattr(newton.linalg, "lstsq", lambda *a: second_fails())  # the dense fallback
    out = _newton_one(face, g_hat, x0, point.lam[surface], accept=1.0)
    assert out is not None and len(calls) >= 2
    assert out[4] is None


def test_a_small_model_s_proximal_newton_run_factors_its_last_system_once(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A small model's rounds take proximal Newton steps (a tie may be), so
    no plain factors come out of them; the last system is factored once
    more (a few microseconds) to read its pivots, and where it is regular
    the face's rank test and the split's are skipped (0.3 ms of a cold
    solve of the paper's shaft). The answer is the same, to the
    certificate's tolerances (not to the bit). The shaft's face is regular
    by far (pivots 7.8e-3 and up): its verdict is the same on every machine."""

    model = jointplay.load(ROOT / "examples" / "paper" / "6.1.6.1.yaml")
    ws = Workspace.of(model)
    g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
    sigma = np.zeros(len(ws.balls))
    best = pipeline.split(ws, g_hat, sigma, pipeline.contacts_optimum(ws, g_hat, sigma))
    assert not ws.sparse and faces.pins_by_newton(best)
    monkeypatch.setattr(newton.linalg.Factors, "regular", lambda self, cutoff: False)
    fresh = Workspace.of(model)
    other = pipeline.split(fresh, g_hat, sigma, pipeline.contacts_optimum(fresh, g_hat, sigma))
    assert not faces.pins_by_newton(other)
    reach = DEFAULT.feasibility_tolerance * ws.max_radius
    assert np.max(np.abs(best.x - other.x)) <= reach
    top = max(1.0, float(np.max(np.abs(other.lam))))
    assert np.max(np.abs(best.lam - other.lam)) <= DEFAULT.equilibrium_tolerance * top


def test_a_tilting_face_is_not_marked_by_newton_s_factors(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A tilting face (a face resting on its rim) leaves free a motion that
    depends on x, and Newton's factors may be a few steps old: even regular,
    they do not mark it, and the face's own test decides. Here every
    factorization is taken as regular; the flat faces of the paper's shaft
    are marked, the slider's tilting disc face is not."""
    from jointplay.numerics.linalg import Factors

    monkeypatch.setattr(Factors, "regular", lambda self, cutoff: True)
    factored = linalg._factored
    monkeypatch.setattr(
        linalg,
        "_factored",
        lambda K: factored(K) or Factors(lambda b: b, lambda: np.ones(K.shape[0])),
    )
    paper_shaft = ROOT / "examples" / "paper" / "6.1.6.1.yaml"
    slider = ROOT / "tests" / "property_cases" / "slider_and_disc.yaml"
    for path, tilting in ((paper_shaft, False), (slider, True)):
        ws = Workspace.of(jointplay.load(path))
        g_hat = ws.asm.g / np.linalg.norm(ws.asm.g)
        point = pipeline.optimum(ws, g_hat, np.zeros(len(ws.balls)))
        assert point.active is not None
        surface = list(point.active[0])
        assert bool(np.any(ws.stack.has_offset[surface] & (ws.stack.k[surface] > 0))) is tilting
        assert faces.pins_by_newton(point) is not tilting
