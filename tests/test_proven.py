"""Every number of an answer is what its certificate proves: a component
below the certificate's resolution for its quantity is 0 (jointplay.proven)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import jointplay
from conftest import ROOT
from jointplay.proven import Resolution, direction, proven
from jointplay.settings import DEFAULT
from jointplay.studies.montecarlo import _wilson

EXAMPLES = sorted((ROOT / "examples").glob("*/*.yaml"))


def test_a_component_below_the_step_is_zero_and_no_zero_is_negative() -> None:
    v = proven(np.array([-2.4e-50, 600.0, -1e-9, 1e-7, -0.0]), 1e-8)
    assert v.tolist() == [0.0, 600.0, 0.0, 1e-7, 0.0]
    assert not np.signbit(v[[0, 2, 4]]).any()
    assert direction(np.array([-2.22e-16, -1.0, -8.88e-17]), 1e-9).tolist() == [0.0, -1.0, 0.0]
    assert direction(np.zeros(3), 1e-9).tolist() == [0.0, 0.0, 0.0]


def test_the_resolution_follows_the_certificate() -> None:
    res = Resolution.of(0.1, 200.0, 50.0)
    assert res.length == pytest.approx(DEFAULT.feasibility_tolerance * 0.1)
    assert res.angle == pytest.approx(res.length / 200.0)
    assert res.force == pytest.approx(DEFAULT.force_resolution * 50.0)
    assert res.moment == pytest.approx(res.force * 200.0)
    assert res.balance == pytest.approx(DEFAULT.equilibrium_tolerance * 50.0)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: f"{p.parent.name}/{p.stem}")
def test_no_printed_component_lies_between_zero_and_the_resolution(path: Path) -> None:
    """The reactions of a shaft printed [-600, -2.4e-50, 435] and a stop that
    carries nothing 1.3e-14 N: every length, angle, force and moment of the
    --json document is 0 or at least what the certificate resolves."""
    model = jointplay.load(path)
    asm = jointplay.Workspace.of(model).asm
    for case in model.case_names or (None,):
        result = jointplay.solve(model, case=case)
        loads = [np.linalg.norm(ld.force or (0, 0, 0)) for ld in model.loads_of(case)]
        torques = [np.linalg.norm(ld.torque or (0, 0, 0)) / asm.ell for ld in model.loads_of(case)]
        reactions = [np.linalg.norm(j.reaction_force) for j in result.joints.values()]
        moments = [np.linalg.norm(j.reaction_moment) / asm.ell for j in result.joints.values()]
        res = Resolution.of(asm.s, asm.ell, max([0.0, *loads, *torques, *reactions, *moments]))
        doc = result.to_dict()
        lengths = [v for p in doc["points"].values() for v in p["displacement"]]
        angles, forces, torque = [], [], []
        for b in doc["bodies"].values():
            lengths += b["translation"]
            angles += b["rotation"]
        for j in doc["joints"].values():
            lengths += j["translation"]
            angles += j["rotation"]
            forces += j["reaction"]["force"]
            torque += j["reaction"]["moment"]
            for c in j["contacts"]:
                forces += c["force"]
                torque += c["torque"]
        for values, step in (
            (lengths, res.length),
            (angles, res.angle),
            (forces, res.force),
            (torque, res.moment),
        ):
            small = [v for v in values if 0 < abs(v) < step * (1 - 1e-9)]
            assert not small, (case, step, small)


def test_an_interval_at_a_count_of_zero_starts_at_zero() -> None:
    """A ppm interval started at 1.084e-13 where no sample failed."""
    assert _wilson(0, 100_000, 3.0)[0] == 0.0
    assert _wilson(100_000, 100_000, 3.0)[1] == 1.0
    low, high = _wilson(7, 100_000, 3.0)
    assert 0 < low < 7e-5 < high < 1


@pytest.mark.parametrize("name", ["studies/compliant_shaft", "gallery/spindle"])
@pytest.mark.parametrize("exact", [False, True], ids=["linear", "exact"])
def test_a_reaction_is_the_sum_of_its_printed_contacts(name: str, exact: bool) -> None:
    """Both routes print a joint's reaction as the sum of the contact forces
    they print (proven one by one, the two once disagreed by 2.7e-9 N)."""
    model = jointplay.load(ROOT / "examples" / f"{name}.yaml")
    result = jointplay.solve(model, exact=exact)
    for joint in result.joints.values():
        if joint.contacts:
            total = np.sum([c.force for c in joint.contacts], axis=0)
            # to the printed resolution: the order of a sum's terms is round-off
            step = result.resolution.force
            np.testing.assert_allclose(joint.reaction_force, total, rtol=0, atol=step)
