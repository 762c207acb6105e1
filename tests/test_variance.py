"""Issue 53: contributions by variance. Sobol' first-order and total indices
from the batch solver, against a closed form; on a linear example they equal
the linear (RSS) shares; on the four-bar, whose contacts change with the
out-of-plane force, that force leads by total index, where the linear
shares gave it 0 %."""

from __future__ import annotations

import json

import numpy as np

import jointplay
from conftest import ROOT
from jointplay.studies.contributions import Contributions
from jointplay.studies.sobol import Sobol
from test_cli import run

FITS = ROOT / "examples" / "studies" / "shaft_fits.yaml"
FOUR_BAR = ROOT / "examples" / "gallery" / "four_bar.yaml"


def test_the_indices_of_a_compliant_ball_follow_the_closed_form() -> None:
    """A ball with play J (0.4 to 0.6) and 1000 N/mm under F (80 to 120 N):
    |d| = J/2 + F/1000, additive, so S = S_T = each term's variance over the
    sum: (0.1^2/12) / (0.1^2/12 + 0.04^2/12) for the play."""
    data = {
        "bodies": [{"name": "G", "ground": True}, {"name": "B"}],
        "joints": [
            {"name": "j", "type": "spherical", "between": ["G", "B"], "at": [0, 0, 0],
             "clearance": {"min": 0.4, "max": 0.6}, "stiffness": 1000},
        ],
        "loads": [{"body": "B", "at": [0, 0, 0], "force": [{"min": 80, "max": 120}, 0, 0]}],
        "points": [{"name": "c", "body": "B", "at": [0, 0, 0]}],
    }  # fmt: skip
    result = Sobol(samples=512, seed=1).run(jointplay.model_from_dict(data))
    share = np.array([0.1**2, 0.04**2]) / (0.1**2 + 0.04**2)
    assert result.inputs == ("j.clearance", "loads[0].force[0]")
    assert result.solves == 512 * (2 * 2 + 2)
    for est, interval in (
        (result.first, result.first_interval),
        (result.total, result.total_interval),
    ):
        assert np.all(interval[0, :, 0] <= share) and np.all(share <= interval[0, :, 1])
        assert np.max(np.abs(est[0] - share)) < 0.05
    assert result.variance[0] == np.float64(result.variance[0])  # mm^2
    assert abs(result.variance[0] - (0.1**2 + 0.04**2) / 12) < 0.1 * (0.1**2 + 0.04**2) / 12


def test_on_shaft_fits_the_linear_shares_equal_the_first_order_indices() -> None:
    """shaft_fits is linear over its fits: the linear shares stay, and each
    input's RSS share lies within its first-order index's interval."""
    result = Contributions(variance="always", samples=512, seed=0).run(jointplay.load(FITS))
    assert all(c.linear for c in result.linearity)
    sobol = result.sobol
    assert sobol is not None and sobol.inputs == result.plays
    for k in range(len(result.measures)):
        share = result.rss[k] / 100
        low, high = sobol.first_interval[k, :, 0], sobol.first_interval[k, :, 1]
        assert np.all(low <= share) and np.all(share <= high), (result.measures[k], share)
    # by default (auto) a linear model takes no Sobol' study at all
    assert Contributions().run(jointplay.load(FITS)).sobol is None


def test_the_four_bar_s_out_of_plane_force_leads_by_variance() -> None:
    """The linear shares gave the out-of-plane force 0 %; it is the largest
    source of variation: first or second by total Sobol' index (here 128
    base sets of parts, 1,536 solves)."""
    result = Contributions(samples=128, seed=0).run(jointplay.load(FOUR_BAR))
    (check,) = result.linearity
    assert not check.linear and check.culprit == "loads[0].force[2]"
    sobol = result.sobol
    assert sobol is not None and sobol.solves == 128 * 12
    ranked = [sobol.inputs[i] for i in np.argsort(-sobol.total[0])]
    assert "loads[0].force[2]" in ranked[:2]
    frame = result.to_dataframe()
    row = frame[frame.play == "loads[0].force[2]"].iloc[0]
    assert row.sobol_total == sobol.total[0, sobol.inputs.index("loads[0].force[2]")]
    assert not row.linear


def test_the_command_prints_the_variance_shares_where_not_linear() -> None:
    proc = run("contributions", str(FOUR_BAR), "-n", "32")
    assert proc.returncode == 0, proc.stderr
    words = " ".join(proc.stdout.split())
    assert "not linear over the ranges: loads[0].force[2] changes the touching contacts" in words
    assert "Sobol' indices from 32 base sets of parts (384 solves" in words
    doc = json.loads(run("contributions", str(FOUR_BAR), "-n", "32", "--json").stdout)
    assert doc["sobol"]["samples"] == 32
    (measure,) = doc["measures"].values()
    assert measure["linearity"]["linear"] is False
    linear = json.loads(run("contributions", str(FITS), "--json").stdout)
    assert linear["sobol"] is None
    assert all(m["linearity"]["linear"] for m in linear["measures"].values())
