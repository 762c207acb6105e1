"""Clarabel's statuses, read by an explicit map (never by their suffix)."""

from __future__ import annotations

from types import SimpleNamespace

import clarabel
import pytest

import jointplay
from conftest import PAPER
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
