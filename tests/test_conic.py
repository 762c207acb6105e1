"""Clarabel's statuses, read by an explicit map (never by their suffix)."""

from __future__ import annotations

from types import SimpleNamespace

import clarabel
import pytest

import jointplay
from conftest import BALANCE, MM, PAPER
from jointplay.solver import conic


def test_every_status_of_the_installed_clarabel_is_mapped() -> None:
    names = {s for s in dir(clarabel.SolverStatus) if not s.startswith("_")}
    names -= {"name", "value"}  # enum attributes on some releases, not statuses
    assert names <= set(conic.STATUS), sorted(names - set(conic.STATUS))


@pytest.mark.parametrize(
    ("status", "expected"),
    [
        ("Solved", "optimal"),
        ("AlmostSolved", "inaccurate"),  # not an optimum: our certificate decides
        ("AlmostDualInfeasible", "unbounded"),
        ("PrimalInfeasible", "infeasible"),
        ("InsufficientProgress", "stopped"),
        ("SomethingNew", "stopped"),  # a status a later release adds stops with its name
    ],
)
def test_statuses_mean_what_the_map_says(status: str, expected: str) -> None:
    solution = SimpleNamespace(status=f"SolverStatus.{status}")
    assert conic.status_name(solution) == status
    assert conic.outcome(solution) == expected


def test_check_raises_a_jointplay_error_not_an_assert() -> None:
    """``python -O`` skips ``assert``: an uncertified result must still raise."""
    from dataclasses import replace

    result = jointplay.solve(jointplay.load(PAPER / "6.1.6.1.yaml"))
    result.check()
    bad = replace(result, certificate=replace(result.certificate, certified=False))
    with pytest.raises(jointplay.SolverError, match="uncertified result"):
        bad.check()


@pytest.mark.parametrize("allowed", [True, False], ids=["updated", "made anew"])
def test_a_kept_solver_answers_each_cost_as_a_new_solver_does(
    allowed: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``conic.KeptSolver`` (an envelope's directions): one solver given each
    new cost with ``update``, where Clarabel allows it, else a new solver
    each time; either way each answer is that of a new solver for its cost,
    to the interior-point tolerance (an updated solver's path differs from a
    new one's: 3.5e-12 apart on the paper's shaft, not bit for bit, and
    another machine's paths may differ more). So they are compared to the
    promise: positions to MM, multipliers to the certificate's balance."""
    import numpy as np

    from jointplay.solver.solve import Workspace

    ws = Workspace.of(jointplay.load(PAPER / "6.1.6.1.yaml"))
    prog = conic.interior_program(ws)
    if not allowed:
        monkeypatch.setattr(clarabel.DefaultSolver, "is_data_update_allowed", lambda self: False)
    kept = conic.KeptSolver(prog.P, prog.A, prog.b, prog.cones, prog.settings)
    rng = np.random.default_rng(3)
    for q in [*rng.standard_normal((3, ws.m)), -ws.asm.g / np.linalg.norm(ws.asm.g)]:
        got = kept.solve(q)
        new = clarabel.DefaultSolver(prog.P, q, prog.A, prog.b, prog.cones, prog.settings).solve()
        assert conic.outcome(got) == conic.outcome(new) == "optimal"
        x_got, x_new = np.asarray(got.x), np.asarray(new.x)
        assert np.max(np.abs(x_got - x_new)) * ws.asm.s <= MM  # scaled unknowns, in mm
        z_new = np.asarray(new.z)
        top = max(1.0, float(np.max(np.abs(z_new))))  # unit loads: forces of size 1
        np.testing.assert_allclose(got.z, z_new, rtol=0, atol=BALANCE * top)
    assert (kept.kept is not None) == allowed
