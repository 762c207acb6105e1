"""A few mechanisms of the random campaign (benchmarks/campaign.py), checked
as it checks them: every one answered through the command line (exit code
and JSON), checked from the printed numbers and against tests/reference.py,
or reported not held with its motion named where the reference finds a
driven free motion. The full campaign (500 mechanisms) is in
benchmarks/README.md."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import campaign

#: mechanisms per seed: two seeds of ten stay under a minute on two cores
COUNT = 10


@pytest.mark.parametrize("seed", [11, 12])
def test_random_mechanisms_are_answered_right(seed: int) -> None:
    results = campaign.run(COUNT, seed, save=None, quiet=True)
    failing = [
        (mech.design, outcome.verdict, outcome.notes)
        for mech, outcome in results
        if outcome.verdict not in ("ok", "not held")
    ]
    assert not failing, failing
