"""Free motions of large mechanisms: the elimination by bodies against the dense SVD."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
import scipy.sparse as sp

import jointplay
from conftest import ROOT, assert_same_answer
from jointplay.assembly import assemble
from jointplay.errors import SolverError
from jointplay.io.generate import bearing_chain, tube_string
from jointplay.numerics import linalg
from jointplay.numerics.free_motions import Eliminated, null_basis
from jointplay.settings import DEFAULT
from jointplay.solver import pipeline
from jointplay.solver.solve import Workspace

RCOND, ROUND_OFF = DEFAULT.free_motion_rcond, DEFAULT.round_off


def constraint_rows(model: jointplay.Model) -> tuple[sp.csr_matrix, int]:
    """The rows whose null space is the free motions (as ``Workspace`` stacks them)."""
    asm = assemble(model)
    st = asm.stack
    C = sp.vstack(
        [
            sp.csr_matrix(st.A),
            sp.csr_matrix(st.B)[np.flatnonzero(st.has_offset)],
            sp.csr_matrix(asm.E),
        ],
        format="csr",
    )
    return C, asm.m


def assert_same_null_space(C: sp.csr_matrix, m: int) -> None:
    # a linear-algebra helper on the model's exact rows (no solve): its free
    # motions are separated from the rest by far more than round-off, so the
    # subspace, and these round-off bounds, hold on every machine
    N = null_basis(C, m, RCOND, ROUND_OFF).toarray()
    dense = linalg.null_space(C.toarray(), m, RCOND, ROUND_OFF)
    assert N.shape[1] == dense.shape[1] == Eliminated(C, m, RCOND).deficit
    np.testing.assert_allclose(N.T @ N, np.eye(N.shape[1]), rtol=0, atol=1e-12)
    scale = float(abs(C).max())
    assert np.max(np.abs(C @ N), initial=0.0) <= 1e-12 * scale
    # the same subspace: equal projectors
    np.testing.assert_allclose(N @ N.T, dense @ dense.T, rtol=0, atol=1e-10)


MODELS = {
    "bearing chain": lambda: bearing_chain(30),
    "tube string": lambda: tube_string(30),
    "tube loops": lambda: tube_string(30, closed=True),
    **{
        path.stem: (lambda path=path: jointplay.load(path))
        for path in sorted((ROOT / "examples").rglob("*.yaml"))
    },
}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_the_elimination_finds_the_dense_svds_free_motions(name: str) -> None:
    assert_same_null_space(*constraint_rows(MODELS[name]()))


@pytest.mark.parametrize("seed", range(6))
def test_a_free_motion_of_many_bodies_is_found_whole(seed: int) -> None:
    """Rows between random pairs of 12 bodies, made blind to two motions that
    move most bodies at once (as a loop's motion does): back-substitution has
    to carry each free direction through the pivots of the bodies before it."""
    rng = np.random.default_rng(seed)
    n, m = 12, 72
    blocks = []
    for _ in range(40):
        a, b = sorted(rng.choice(n, 2, replace=False))
        rows = np.zeros((3, m))
        rows[:, 6 * a : 6 * a + 6] = rng.standard_normal((3, 6))
        rows[:, 6 * b : 6 * b + 6] = rng.standard_normal((3, 6))
        blocks.append(rows)
    C = np.vstack(blocks)
    V = rng.standard_normal((m, 2))
    V[:6] = 0.0  # not body 0
    Q, _ = np.linalg.qr(V)
    C -= (C @ Q) @ Q.T  # C no longer moves span(V); rows still touch their two bodies only
    C[np.abs(C) < 1e-14] = 0.0
    assert_same_null_space(sp.csr_matrix(C), m)


def test_a_local_free_motion_stays_local_and_none_is_left_out() -> None:
    """1,000 shafts, each free to spin: 1,000 free motions (the randomized
    search this replaced stopped at 256), each on its own shaft."""
    C, m = constraint_rows(bearing_chain(1000))
    N = null_basis(C, m, RCOND, ROUND_OFF)
    assert N.shape[1] == 1000
    bodies_moved = [len(np.unique(N[:, c].indices // 6)) for c in range(N.shape[1])]
    assert max(bodies_moved) == 1


def test_every_free_motion_is_reported() -> None:
    ws = Workspace.of(bearing_chain(300))
    words = ws.free_motions()
    assert len(words) == 300
    assert words[0] == "body 'S1': rotation about the global X axis"


def test_a_mechanism_with_no_free_motion_has_no_deficit() -> None:
    C, m = constraint_rows(tube_string(200, closed=True))
    assert Eliminated(C, m, RCOND).deficit == 0
    assert null_basis(C, m, RCOND, ROUND_OFF).shape == (m, 0)


def test_a_body_with_no_rows_is_free_and_nothing_is_printed(
    capfd: pytest.CaptureFixture[str],
) -> None:
    """A row subset (a face's rows, say) may leave a body untouched: all six
    of its motions are free, and LAPACK, which prints on stdout when given a
    block of no rows, is not called on it."""
    rng = np.random.default_rng(1)
    C = np.zeros((10, 18))
    C[:, :12] = rng.standard_normal((10, 12))  # bodies 0 and 1; body 2 has no rows
    N = null_basis(sp.csr_matrix(C), 18, RCOND, ROUND_OFF)
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert N.shape[1] == 6 + 2  # body 2's six motions and two of 0 and 1 together
    assert_same_null_space(sp.csr_matrix(C), 18)


def test_repeated_entries_add_up_and_the_matrix_is_left_alone() -> None:
    C = sp.csr_matrix(
        (np.array([1.0, 1.0, 2.0]), np.array([0, 0, 1]), np.array([0, 2, 3])), shape=(2, 6)
    )  # row 0 holds column 0 twice: 1 + 1
    before = (C.data.copy(), C.indices.copy(), C.indptr.copy())
    N = null_basis(C, 6, RCOND, ROUND_OFF).toarray()
    assert N.shape[1] == 4
    assert np.allclose(C.toarray() @ N, 0.0)
    for got, kept in zip((C.data, C.indices, C.indptr), before, strict=True):
        assert np.array_equal(got, kept)


def test_columns_that_are_not_six_per_body_are_refused() -> None:
    with pytest.raises(ValueError, match="6 columns per body"):
        null_basis(sp.csr_matrix(np.ones((1, 7))), 7, RCOND, ROUND_OFF)
    with pytest.raises(ValueError, match="6 columns per body"):
        Eliminated(sp.csr_matrix(np.ones((1, 12))), 6, RCOND)


@pytest.mark.parametrize("closed", [False, True])
def test_a_chain_is_eliminated_in_few_rounds_and_without_fill(closed: bool) -> None:
    """Why bodies of up to ELIMINATED_TOGETHER_DEGREE (2) neighbours go in one
    round: a chain then halves each round (about log2 N rounds, not N), and
    every pivot still involves at most two other bodies (no fill, so the cost
    stays linear). With 1, a chain would go two bodies a round."""
    from jointplay.numerics.free_motions import (
        ELIMINATED_TOGETHER_DEGREE,
        _eliminate,
        largest_singular_value,
    )

    assert ELIMINATED_TOGETHER_DEGREE == 2
    n = 256
    C, m = constraint_rows(tube_string(n, closed=closed))
    elim = _eliminate(C, m, 1e-9, largest_singular_value(C))
    assert sorted(elim.order) == list(range(n))
    assert elim.rounds <= 2 * np.log2(n) + 2, elim.rounds
    assert max(len(p.others) for p in elim.pivots.values()) <= 2
    assert_same_null_space(*constraint_rows(tube_string(40, closed=closed)))


def test_free_motions_come_in_body_order_and_a_bearing_chain_is_certified() -> None:
    """The pinning rows of the free motions follow the bodies' order, whatever
    order the elimination found them in: in the order of its rounds, the
    interior point of a 100-shaft bearing chain balanced each body only to
    1.02e-8 of the largest force and the answer was declined; in body order
    (the unknowns' order) it certifies. How far inside its tolerance it
    balances is round-off of a degenerate problem (5e-11 on one CPU, 4e-9 on
    another): the promise is the certificate's."""
    C, m = constraint_rows(bearing_chain(100))
    N = null_basis(C, m, RCOND, ROUND_OFF).tocsc()
    first_body = [int(N.indices[N.indptr[j]]) // 6 for j in range(N.shape[1])]
    assert first_body == sorted(first_body) and len(first_body) == 100  # one spin a shaft
    result = jointplay.solve(bearing_chain(100))
    result.check()  # certified, and balanced per body to equilibrium_tolerance
    assert result.equilibrium_residual <= DEFAULT.equilibrium_tolerance


@pytest.mark.parametrize("shafts", [21, 36, 38, 39])
def test_the_retry_takes_another_path_and_degenerate_bearing_chains_certify(shafts: int) -> None:
    """The one retry of an answer that fails its certificate changes the
    interior point's static regularization as well as its tolerance
    (``fine_ipm_regularization``). Bearing chains are degenerate: the
    interior point stops "almost solved" on an active set whose contacts
    cannot all touch (a loop of contacts over a dozen shafts, 1e-8 apart),
    and its face's least-norm point goes past one of them. With the finer
    tolerance alone the retry stopped on the same set, and these chains were
    declined (21 and 39 shafts on clarabel 0.11; 36, 38 and 39 on 0.10)."""
    result = jointplay.solve(bearing_chain(shafts))
    result.check()  # certified, and balanced per body in newtons
    assert result.certificate.feasibility_mm <= 1e-6


def test_rows_are_grouped_by_the_bodies_they_touch_in_one_documented_order() -> None:
    """The elimination takes each body's rows in the order ``_row_blocks``
    gives them (its round-off depends on it): groups of one body by body,
    then of two by their pair, then the rows of more bodies in the order
    they come; rows keep their order in a group. Checked against a plain
    loop over rows on random block-sparse matrices, with rows of one to
    four bodies and stored zeros."""
    from jointplay.numerics.free_motions import _row_blocks

    rng = np.random.default_rng(7)
    special = [
        sp.csr_matrix((0, 12)),  # no rows
        sp.csr_matrix((3, 12)),  # rows with no entries
        sp.csr_matrix(np.kron(np.eye(2), np.ones((1, 18)))),  # only rows of three bodies
    ]
    for case in range(200 + len(special)):
        if case < len(special):
            C = special[case]
        else:
            n_bodies = int(rng.integers(1, 10))
            dense = np.zeros((int(rng.integers(1, 30)), 6 * n_bodies))
            for row in dense:
                for body in rng.choice(n_bodies, int(rng.integers(1, min(4, n_bodies) + 1)), False):
                    cols = 6 * body + rng.choice(6, int(rng.integers(1, 7)), replace=False)
                    row[cols] = rng.standard_normal(len(cols))
            C = sp.csr_matrix(dense)
            C.data[rng.integers(0, C.nnz)] = 0.0  # a stored zero moves no body
        dense = C.toarray()
        groups: dict[tuple[int, ...], list[int]] = {}
        for i, row in enumerate(dense):
            bodies = tuple(int(b) for b in np.unique(np.flatnonzero(row) // 6))
            if bodies:
                groups.setdefault(bodies, []).append(i)
        keys = sorted(k for k in groups if len(k) == 1) + sorted(k for k in groups if len(k) == 2)
        keys += [k for k in groups if len(k) > 2]
        expected = [
            (k, dense[np.ix_(groups[k], (6 * np.array(k)[:, None] + np.arange(6)).ravel())])
            for k in keys
        ]
        got = _row_blocks(C)
        assert [k for k, _ in got] == keys
        for (_, block), (_, want) in zip(got, expected, strict=True):
            assert np.array_equal(block, want)


def test_the_retry_shares_the_free_motions_and_answers_as_a_new_workspace(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The finer retry runs on ``Workspace.with_settings``: the free motions
    depend on the assembly and their threshold alone, so they are kept (a
    10,000-shaft bearing chain's cost 2.2 s again in its retry), and so are
    the faces, whose rows and ranks depend on nothing else; and the
    answer is the one a workspace made anew with the retry's settings gives
    (to the promise: positions to MM and RAD, forces to the certificate's
    balance; not to the bit, which is round-off of a degenerate chain). A
    solve whose first try is refused takes the retry on the same
    workspace's data: refused here by hand, since which degenerate
    model's first try fails depends on the installed Clarabel (the
    15-shaft bearing chain's does on 0.10, not on 0.11.1)."""
    asm = assemble(bearing_chain(15))
    ws = Workspace(asm)
    ws.solve()  # its faces met, and a warm start, which the retry must not take
    fine_settings = ws.settings.retry()
    fine = ws.with_settings(fine_settings)
    assert fine.N is ws.N and fine.K is ws.K and fine.faces is ws.faces
    assert fine.settings is fine_settings and ws.settings is not fine_settings
    assert_same_answer(fine.solve(), Workspace(asm, fine_settings).solve())
    # the solve's retry makes no second workspace, and it is taken (the first
    # try is refused by hand, so these counts hold on every machine)
    made, retried = [], []
    original_init, original_with = Workspace.__init__, Workspace.with_settings

    def counted_init(self: Workspace, *args: Any, **kwargs: Any) -> None:
        made.append(1)
        original_init(self, *args, **kwargs)

    def counted_with(self: Workspace, settings: Any) -> Workspace:
        retried.append(1)
        return original_with(self, settings)

    first_try = pipeline.answer

    def refused_at_first(ws: Workspace, *args: Any) -> Any:
        if ws.settings.ipm_tolerance > ws.settings.fine_ipm_tolerance:  # the first try's
            raise SolverError("refused, to take the retry")
        return first_try(ws, *args)

    monkeypatch.setattr(Workspace, "__init__", counted_init)
    monkeypatch.setattr(Workspace, "with_settings", counted_with)
    monkeypatch.setattr(pipeline, "answer", refused_at_first)
    jointplay.solve(bearing_chain(15)).check()
    assert made == [1] and retried == [1]


def _arm(**arm: Any) -> jointplay.Model:
    """An arm on one ball joint at the origin: free to swing about it."""
    return jointplay.model_from_dict(
        {
            "bodies": [{"name": "S0", "ground": True}, {"name": "arm", **arm}],
            "joints": [
                {
                    "name": "ball",
                    "type": "spherical",
                    "between": ["S0", "arm"],
                    "at": [0, 0, 0],
                    "clearance": 0.2,
                }
            ],
            "gravity": [0, 0, "-9.81 m/s^2"],
        }
    )


def test_the_verdict_names_a_weight_only_where_a_weight_drives_the_motion() -> None:
    # its weight 300 mm out swings a heavy arm down about the ball
    heavy = _arm(mass="2 kg", center_of_mass=[300, 0, 0])
    with pytest.raises(jointplay.UnboundedMechanismError, match="most by the weight of 'arm'"):
        Workspace.of(heavy).solve()
    # a load given to the solve, none of the model's, was called a weight too
    light = _arm()
    push = jointplay.Load(body="arm", at=(300, 0, 0), force=(0, 1, 0))
    with pytest.raises(jointplay.UnboundedMechanismError) as caught:
        Workspace.of(light).solve([push])
    assert "rotation about the global Z axis" in str(caught.value)
    assert "most by a load on 'arm'" in str(caught.value) and "weight" not in str(caught.value)
