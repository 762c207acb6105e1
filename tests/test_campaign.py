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
import yaml

import jointplay
from jointplay import UnboundedMechanismError

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import campaign
from reference import Reference

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


#: The campaign's failure shapes, pared down (tests/campaign_cases/)
CASES = Path(__file__).resolve().parent / "campaign_cases"


@pytest.mark.parametrize(("name", "body"), [("lifted", "B6"), ("tipped", "B3")])
def test_a_table_its_loads_lift_or_tip_off_its_point_contacts_is_not_held(
    name: str, body: str
) -> None:
    path = CASES / f"{name}.yaml"
    with pytest.raises(UnboundedMechanismError, match=f"body '{body}'") as info:
        jointplay.solve(jointplay.load(path))
    assert info.value.body == body and info.value.motion
    code, doc, err = campaign.solve_cli(path, in_process=True)
    assert code == 3, err
    assert doc is not None and doc["body"] == body and doc["motion"]
    # the reference's linear program finds a driven motion no contact holds, moving that body
    data = yaml.safe_load(path.read_text())
    assert campaign.check_not_held(Reference(data, None), doc) == []
