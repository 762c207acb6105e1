"""Issue 53: contributions by variance. Sobol' first-order and total indices
from the batch solver, against a closed form; on a linear example they equal
the linear (RSS) shares; on the four-bar, whose contacts change with the
out-of-plane force, that force leads by total index, where the linear
shares gave it 0 %."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.stats import ks_2samp

import jointplay
from conftest import ROOT
from jointplay.model.deviations import Zone
from jointplay.model.tolerance import Distribution, Toleranced
from jointplay.studies.contributions import Contributions
from jointplay.studies.parts import inputs_of
from jointplay.studies.sobol import Sobol
from test_cli import run

FITS = ROOT / "examples" / "studies" / "shaft_fits.yaml"
FOUR_BAR = ROOT / "examples" / "gallery" / "four_bar.yaml"
DEVIATIONS = ROOT / "examples" / "studies" / "shaft_deviations.yaml"
#: Draws of each law, and the largest Kolmogorov-Smirnov distance between the
#: Monte Carlo's draws and the design's of the same law: the two-sample test's
#: 99.9 % critical value, sqrt(ln(2 / 0.001) / 2) sqrt(2 / DRAWS) = 0.0195.
DRAWS = 20_000
KS_LIMIT = 0.0195


def _same_law(a: np.ndarray, b: np.ndarray) -> None:
    """Each column of (n, k) draws, and their size, alike in law."""
    a, b = a.reshape(len(a), -1), b.reshape(len(b), -1)
    sizes = (np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1))
    for x, y in [*zip(a.T, b.T, strict=True), sizes]:
        assert ks_2samp(x, y).statistic < KS_LIMIT


@pytest.mark.parametrize("distribution", ["uniform", "normal"])
def test_the_design_s_sets_of_parts_follow_the_monte_carlo_s_laws(
    distribution: Distribution,
) -> None:
    """Sobol's design maps numbers in [0, 1) to sets of parts: uniform
    numbers must give the laws the Monte Carlo study draws from (a play's
    limits, a fit's hole and shaft, a segment, disc or ball zone)."""
    rng = np.random.default_rng(3)
    plays = [
        Toleranced(0.01, 0.05, distribution),
        Toleranced(0.007, 0.041, distribution, "H7/g6", 20.0, (0.0, 0.021), (-0.02, -0.007)),
    ]
    for play in plays:
        _same_law(play.sample(rng, DRAWS), play.from_unit(rng.uniform(size=(DRAWS, play.draws))))
    for axes in ((1,), (1, 2), (3, 4, 5)):
        zone = Zone("z", axes, 0.05)
        u = rng.uniform(size=(DRAWS, len(axes)))
        _same_law(zone.sample(rng, DRAWS, distribution), zone.from_unit(u, distribution))
    # and so does a whole model's design, a fit and two disc zones
    inputs = inputs_of(jointplay.load(DEVIATIONS), None, "shaft_deviations.yaml")
    assert [len(g) for g in inputs.unit_groups] == [2, 2, 2]
    u = rng.uniform(size=(DRAWS, 6))
    _same_law(inputs.sample(rng, DRAWS), inputs.from_unit(u))


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
    assert result.solves == 512 * (2 + 2)  # N (D + 2)
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
    base sets of parts, 896 solves)."""
    result = Contributions(samples=128, seed=0).run(jointplay.load(FOUR_BAR))
    (check,) = result.linearity
    assert not check.linear and check.culprit == "loads[0].force[2]"
    sobol = result.sobol
    assert sobol is not None and sobol.solves == 128 * (5 + 2)
    ranked = [sobol.inputs[i] for i in np.argsort(-sobol.total[0])]
    assert "loads[0].force[2]" in ranked[:2]
    frame = result.to_dataframe()
    row = frame[frame.play == "loads[0].force[2]"].iloc[0]
    assert row.sobol_total == sobol.total[0, sobol.inputs.index("loads[0].force[2]")]
    assert not row.linear


def test_the_command_prints_the_variance_shares_where_not_linear() -> None:
    proc = run("contributions", str(FOUR_BAR), "-n", "32")
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr  # no library's warning
    words = " ".join(proc.stdout.split())
    assert "not linear over the ranges: loads[0].force[2] changes the touching contacts" in words
    assert "Sobol' indices from 32 base sets of parts (224 solves" in words
    proc = run("contributions", str(FOUR_BAR), "-n", "100")
    assert proc.returncode == 2 and proc.stdout == ""
    assert "--samples: a power of 2" in proc.stderr and "got 100" in proc.stderr
    doc = json.loads(run("contributions", str(FOUR_BAR), "-n", "32", "--json").stdout)
    assert doc["sobol"]["samples"] == 32
    (measure,) = doc["measures"].values()
    assert measure["linearity"]["linear"] is False
    linear = json.loads(run("contributions", str(FITS), "--json").stdout)
    assert linear["sobol"] is None
    assert all(m["linearity"]["linear"] for m in linear["measures"].values())
