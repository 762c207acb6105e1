"""Studies over the motion: each set of parts carried through the cycle gives,
at every pose, the answer of a direct motion of a model built with those
parts; the nominal parts give the motion's own answer; the bands hold it; a
seed reproduces the parts; the fraction failing is the direct count; the
envelope and the contributions at a pose are those of the posed model."""

from __future__ import annotations

import json
import pickle
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import jointplay
from jointplay.assembly import assemble
from jointplay.io.modelfile import model_from_dict
from jointplay.model.fits import fit
from jointplay.studies.contributions import Contributions
from jointplay.studies.envelope import Envelope
from jointplay.studies.kinematics import nominal_poses
from jointplay.studies.motion import Motion, posed_model
from jointplay.studies.motion_studies import (
    MotionContributions,
    MotionEnvelope,
    MotionMonteCarlo,
    MotionStudiesResult,
    tied_largest,
)
from jointplay.studies.variation import load_map, play_map

GALLERY = Path(__file__).parent.parent / "examples" / "gallery"
#: Two routes to one answer agree to this fraction of the largest value.
AGREE = 1e-8
#: Steps of the motions solved here: a full turn in 60-degree steps.
STEPS = 7
ALONG_X = (1.0, 0.0, 0.0)


def _load(name: str, **changes: Any) -> jointplay.Model:
    data = jointplay.load(GALLERY / name).model_dump(by_alias=True, exclude_none=True)
    data.update(changes)
    return model_from_dict(data, source=name)


def _close(a: Any, b: Any) -> None:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    scale = max(float(np.max(np.abs(a))), float(np.max(np.abs(b))), 1e-300)
    assert np.max(np.abs(a - b)) <= AGREE * scale


def _with_plays(model: jointplay.Model, labels: tuple[str, ...], plays: Any) -> jointplay.Model:
    """``model`` built with one set of parts: each play (``joint.field``) as a length."""
    data = model.model_dump(by_alias=True, exclude_none=True)
    for label, value in zip(labels, plays, strict=True):
        joint, field = label.rsplit(".", 1)
        [entry] = [j for j in data["joints"] if j["name"] == joint]
        entry[field] = float(value)
    return model_from_dict(data, source="parts")


@pytest.fixture(scope="module")
def slider_crank() -> jointplay.Model:
    # a limit the parts fall on both sides of (their worst error: 0.064 to 0.081 mm)
    return _load(
        "slider_crank.yaml",
        requirements=[{"point": "piston top", "max_displacement": 0.07, "along": list(ALONG_X)}],
    )


@pytest.fixture(scope="module")
def crank_parts(slider_crank: jointplay.Model) -> jointplay.MotionMonteCarloResult:
    study = MotionMonteCarlo(samples=12, seed=3, motion=Motion(steps=STEPS))
    return study.run(slider_crank)


def test_each_set_of_parts_is_a_direct_motion_of_its_model(
    slider_crank: jointplay.Model, crank_parts: jointplay.MotionMonteCarloResult
) -> None:
    r = crank_parts
    assert r.displacement.shape == (STEPS, 12, 1, 3)
    assert r.play_labels == ("crank pin.clearance", "wrist pin.clearance")
    failing = []
    for i in range(r.samples):
        direct = Motion(steps=STEPS).run(_with_plays(slider_crank, r.play_labels, r.plays[i]))
        _close(r.displacement[:, i], direct.displacement)
        failing.append(bool(np.any(direct.measured[:, 0] > direct.limits[0])))
    assert 0 < sum(failing) < r.samples  # the limit splits the parts
    assert list(r.failing(0)) == failing
    assert r.fraction_failing(0) == pytest.approx(sum(failing) / r.samples, abs=0)
    assert 0.0 <= r.fraction_failing(0) <= 1.0
    per_step = r.failing_per_step(0)
    assert np.all((per_step >= 0) & (per_step <= r.fraction_failing(0)))


def test_bands_hold_the_nominal_parts_answer(
    slider_crank: jointplay.Model, crank_parts: jointplay.MotionMonteCarloResult
) -> None:
    nominal = Motion(steps=STEPS).run(slider_crank)
    d = nominal.displacement[:, 0]
    for direction, value in ((ALONG_X, d[:, 0]), (None, np.linalg.norm(d, axis=1))):
        lower, upper = crank_parts.band("piston top", 0.0, 100.0, direction)
        assert lower.shape == upper.shape == (STEPS,)
        assert np.all(lower <= value) and np.all(value <= upper)
        inner = crank_parts.band("piston top", 2.5, 97.5, direction)
        assert np.all(lower <= inner[0]) and np.all(inner[0] <= inner[1])
        assert np.all(inner[1] <= upper)


def test_nominal_parts_give_the_motion_answer() -> None:
    model = _load("four_bar.yaml")
    asm = assemble(model)
    plays, loads = play_map(asm).nominal, load_map(asm).nominal
    study = MotionMonteCarlo(motion=Motion(steps=STEPS))
    r = study.run_parts(model, plays[None], loads[None])
    nominal = Motion(steps=STEPS).run(model)
    _close(r.displacement[:, 0], nominal.displacement)
    assert r.samples == 1 and r.steps == STEPS


def test_a_seed_reproduces_the_parts_and_another_draws_others() -> None:
    model = _load("four_bar.yaml")
    motion = Motion(steps=3)
    a = MotionMonteCarlo(samples=20, seed=5, motion=motion).run(model)
    b = MotionMonteCarlo(samples=20, seed=5, motion=motion).run(model, workers=2)
    c = MotionMonteCarlo(samples=20, seed=6, motion=motion).run(model)
    assert np.array_equal(a.plays, b.plays) and np.array_equal(a.loads, b.loads)
    # two processes split the poses into two runs, each part starting from its
    # answer at the pose before: the same answers, to the certificate's tolerance
    _close(a.displacement, b.displacement)
    assert not np.array_equal(a.plays, c.plays)
    # the parts MonteCarlo draws with the same seed, solved at the same pose
    poses = nominal_poses(model, np.linspace(0.0, 2 * np.pi, 3))
    posed = posed_model(model, poses, 1)
    one = jointplay.MonteCarlo(samples=20, seed=5).run(posed)
    assert np.array_equal(one.plays, a.plays) and np.array_equal(one.loads, a.loads)
    _close(one.displacement, a.displacement[1])


def test_result_converts_and_pickles(crank_parts: jointplay.MotionMonteCarloResult) -> None:
    doc = json.loads(json.dumps(crank_parts.to_dict()))
    size = doc["points"]["piston top"]["size"]
    assert set(size) == {"0.135", "2.5", "50", "97.5", "99.865"}
    assert all(len(v) == STEPS for v in size.values())
    [along] = doc["points"]["piston top"]["along"]
    assert along["direction"] == list(ALONG_X)
    [req] = doc["requirements"]
    assert req["outside"] == int(np.sum(crank_parts.failing(0)))
    frame = crank_parts.to_frame()
    assert len(frame) == STEPS
    lower, _ = crank_parts.band("piston top", 2.5, 97.5, ALONG_X)
    assert np.array_equal(frame["piston top along [1, 0, 0] p2.5 (mm)"].to_numpy(), lower)
    again = pickle.loads(pickle.dumps(crank_parts))
    assert np.array_equal(again.displacement, crank_parts.displacement)
    with pytest.raises(ValueError, match="percentiles"):
        crank_parts.band("piston top", 60, 40)


def test_envelope_at_a_pose_is_the_posed_models_envelope() -> None:
    model = _load("four_bar.yaml")
    motion = Motion(steps=3)
    result = MotionEnvelope(directions=24, motion=motion).run(model)
    poses = nominal_poses(model, np.linspace(0.0, 2 * np.pi, 3))
    for s in range(3):
        direct = Envelope("fingertip", directions=24).run(posed_model(model, poses, s))
        found = result.at(s, "fingertip")
        _close(found.h, direct.h)
        _close(found.hull, direct.hull)
        lower, upper = result.extent("fingertip", ALONG_X)
        assert lower[s] == pytest.approx(float(direct.hull[:, 0].min()), abs=0)
        assert upper[s] == pytest.approx(float(direct.hull[:, 0].max()), abs=0)
        assert result.extent("fingertip")[1][s] == direct.largest
    json.loads(json.dumps(result.to_dict()))


def test_a_load_table_puts_the_motion_s_envelope_under_the_model_s_loads() -> None:
    """The slider-crank's gas force is a table over the crank's angle, always
    toward the crank (-X): over the motion the envelope's default is that
    load, as the single-pose envelope's is for load ranges, and it is
    one-sided at every step; the 1 N probes it once took by default pushed
    the piston both ways (half of that band never happens). The text and
    the figure's legend name the loads; the probes stay at hand."""
    model = _load("slider_crank.yaml")
    motion = Motion(steps=STEPS)
    nominal = motion.run(model)
    under_model = MotionEnvelope(directions=24, motion=motion).run(model)
    assert under_model.loads == "model" and under_model.under == "the model's loads"
    lower, upper = under_model.extent("piston top", ALONG_X)
    assert np.all(upper < 0.0)  # never pushed away from the crank
    assert np.all(lower <= nominal.displacement[:, 0, 0])  # the plays at their upper limits
    poses = nominal_poses(model, np.linspace(0.0, 2 * np.pi, STEPS))
    for s in (0, 4):  # each step: the posed model's envelope under its loads
        direct = Envelope("piston top", directions=24, loads="model").run(
            posed_model(model, poses, s)
        )
        _close(under_model.at(s, "piston top").hull, direct.hull)
    said = MotionStudiesResult(nominal, envelope=under_model)
    assert "envelope of piston top (along [1, 0, 0]) under the model's loads: farthest" in (
        " ".join(said.findings())
    )
    assert said.envelope_label() == "worst-case envelope under the model's loads"
    probed = MotionEnvelope(directions=24, loads="probes", motion=motion).run(model)
    assert probed.loads == "probes" and probed.under == "1 N probes"
    lower, upper = probed.extent("piston top", ALONG_X)
    assert np.all(lower < 0.0) and np.all(upper > 0.0)
    said = MotionStudiesResult(nominal, envelope=probed)
    assert "(along [1, 0, 0]) under 1 N probes: farthest" in " ".join(said.findings())
    # at one pose the table is one load: the single-pose default stays the probes
    assert Envelope("piston top", directions=24).run(model).over.startswith("probe forces of 1 N")


def test_a_motion_envelope_of_points_without_requirements_names_its_loads() -> None:
    """Without a requirement there is no sentence per requirement: one line
    still says what the envelope columns are under."""
    model = _load("slider_crank.yaml", requirements=[])
    motion = Motion(steps=3)
    found = MotionEnvelope(directions=24, motion=motion).run(model)
    said = MotionStudiesResult(motion.run(model), envelope=found).findings()
    assert said == ["envelopes (their columns above) under the model's loads"]


def test_probes_against_a_weight_say_so() -> None:
    """A probe envelope pushes against the weights: its words say it."""
    model = _load("four_bar.yaml")  # its links' weights
    found = MotionEnvelope(directions=24, loads="probes", motion=Motion(steps=2)).run(model)
    assert found.under == "1 N probes against the standing loads"


#: Sobol' base sets of parts in the contributions tests: fewer than the
#: default, the same on both sides of each comparison.
SOBOL_SAMPLES = 64


def test_contributions_per_step_are_the_posed_models() -> None:
    """At every pose the motion's contributions are ``jointplay
    contributions`` on the posed model: its slopes, its linearity check and,
    where the measure is not linear, its shares of the variance. The
    four-bar's out-of-plane push changes the contacts at its nominal value
    (slopes of opposite signs): its linear share is 0, but it drives the
    fingertip, and the motion says so."""
    model = _load("four_bar.yaml")
    study = MotionContributions(samples=SOBOL_SAMPLES, motion=Motion(steps=3))
    result = study.run(model)
    poses = nominal_poses(model, np.linspace(0.0, 2 * np.pi, 3))
    for s in range(3):
        direct = Contributions(samples=SOBOL_SAMPLES).run(posed_model(model, poses, s))
        found = result.results[s]
        _close(found.sensitivity, direct.sensitivity)
        assert found.linearity == direct.linearity
        assert result.linear(0)[s] == direct.linear(0)
        assert not direct.linear(0) and direct.sobol is not None and found.sobol is not None
        _close(found.sobol.total, direct.sobol.total)
        _close(result.shares(0)[s], 100 * direct.sobol.total[0])
        assert np.isnan(result.spread(0)[s])
        assert result.sigma(0)[s] == pytest.approx(float(np.sqrt(direct.sobol.variance[0])))
        k = int(np.argmax(direct.sobol.total[0]))
        assert result.leading(0, s) == direct.plays[k] == "loads[0].force[2]"
        assert result.shares(0)[s, k] > 50.0
        assert result.why(0, s) == direct.linearity[0].why() != ""
    worst = result.worst_step(0)
    assert result.sigma(0)[worst] == max(result.sigma(0))
    doc = json.loads(json.dumps(result.to_dict()))
    [measure] = doc["measures"]
    assert measure["linear"] == [False] * 3 and all(measure["not_linear_why"])
    assert measure["shares_of"] == ["variance"] * 3
    assert min(measure["share_percent"]["loads[0].force[2]"]) > 50.0
    nominal = Motion(steps=3).run(model)
    findings = " ".join(MotionStudiesResult(nominal, contributions=result).findings())
    assert "driven by loads[0].force[2]" in findings
    assert "not linear over the ranges at 3 of 3 steps" in findings


def test_linear_contributions_at_a_pose_are_the_linear_study() -> None:
    """Where the measure is linear over the ranges (the slider-crank's
    piston under its gas force), the shares at a pose are the plain study's
    worst-case shares and its spread the linear stack."""
    model = _load("slider_crank.yaml")
    study = MotionContributions(samples=SOBOL_SAMPLES, motion=Motion(steps=3))
    result = study.run(model)
    assert all(result.linear(k).all() for k in range(len(result.measures)))
    poses = nominal_poses(model, np.linspace(0.0, 2 * np.pi, 3))
    for s in range(3):
        direct = Contributions(samples=SOBOL_SAMPLES).run(posed_model(model, poses, s))
        for k in range(len(direct.measures)):
            assert result.linear(k)[s] == direct.linear(k)
            if direct.linear(k):
                _close(result.shares(k)[s], direct.worst_case[k])
                assert result.spread(k)[s] == direct.worst_case_range[k]
                assert result.sigma(k)[s] == direct.rss_sigma[k]


def test_plays_that_tie_for_the_lead_are_named_together() -> None:
    """The slider-crank's crank pin (16 mm) and wrist pin (12 mm) are both
    H7/g6 in ISO 286's 10-18 mm band: the same limits, 6 to 35 um, and in a
    rod that carries no moment the same slope, so each holds half of the
    piston's stack. The sentence names both, not the first; with the wrist
    pin on H7/f7 (16 to 52 um) the crank pin no longer ties and is not named."""
    fits = [fit("H7/g6", d) for d in (16.0, 12.0)]
    assert fits[0].min_clearance == fits[1].min_clearance == pytest.approx(0.006)
    assert fits[0].max_clearance == fits[1].max_clearance == pytest.approx(0.035)
    tied = _load("slider_crank.yaml")
    found = MotionContributions(motion=Motion(steps=3)).run(tied)
    crank, wrist = (found.plays.index(f"{j} pin.clearance") for j in ("crank", "wrist"))
    for k in range(len(found.measures)):
        s = found.worst_step(k)
        assert found.shares(k)[s, crank] == pytest.approx(50.0, abs=0.05)
        assert found.shares(k)[s, wrist] == pytest.approx(50.0, abs=0.05)
        assert found.leading_plays(k) == ("crank pin.clearance", "wrist pin.clearance")
    nominal = Motion(steps=3).run(tied)
    findings = MotionStudiesResult(nominal, contributions=found).findings()
    both = "driven by crank pin.clearance and wrist pin.clearance (each 50 % of the worst-case"
    assert sum(both in line for line in findings) == len(found.measures) == 2

    data = tied.model_dump(by_alias=True, exclude_none=True)
    [wrist_pin] = [j for j in data["joints"] if j["name"] == "wrist pin"]
    wrist_pin["clearance"] = {"fit": "H7/f7", "diameter": 12}
    apart = model_from_dict(data, source="slider_crank.yaml")
    found = MotionContributions(motion=Motion(steps=3)).run(apart)
    nominal = Motion(steps=3).run(apart)
    findings = MotionStudiesResult(nominal, contributions=found).findings()
    for k in range(len(found.measures)):
        assert found.leading_plays(k) == ("wrist pin.clearance",) == (found.leading(k),)
    said = [line for line in findings if line.startswith("contributions to")]
    assert len(said) == 2
    assert all("driven by wrist pin.clearance (" in line for line in said)
    assert not any("crank pin" in line or "each" in line for line in said)


def test_a_tie_is_to_the_printed_resolution() -> None:
    """Shares tie where they print alike (3 significant digits): 49.96 is
    '50', 49.9 is not; three thirds tie; nothing to share names one."""
    assert tied_largest([50.0, 49.96, 0.04]) == [0, 1]
    assert tied_largest([50.0, 49.9, 0.1]) == [0]
    assert tied_largest([0.01, 33.33, 33.34, 33.32]) == [1, 2, 3]
    assert tied_largest([0.0, 0.0]) == [0]


def run_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "jointplay.cli", *args], capture_output=True, text=True, timeout=300
    )


def test_cli_motion_with_studies_json_and_csv(tmp_path: Path) -> None:
    csv = tmp_path / "motion.csv"
    proc = run_cli(
        "motion",
        str(GALLERY / "four_bar.yaml"),
        "--steps",
        "3",
        "--samples",
        "16",
        "--seed",
        "2",
        "--workers",
        "1",
        "--envelope",
        "--contributions",
        "--json",
        "--csv",
        str(csv),
    )
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["study"] == "motion" and len(doc["steps"]) == 3
    assert doc["monte_carlo"]["samples"] == 16 and doc["monte_carlo"]["seed"] == 2
    assert len(doc["monte_carlo"]["points"]["fingertip"]["size"]["2.5"]) == 3
    assert len(doc["envelope"]["points"]["fingertip"]["largest"]) == 3
    assert doc["contributions"]["measures"][0]["leading"] in doc["contributions"]["plays"]
    header = csv.read_text().splitlines()[0]
    assert "fingertip |d| p97.5 (mm)" in header and "leading play" in header


def test_cli_motion_loads_chooses_the_envelope_s_loads_and_names_them() -> None:
    """``--loads`` as ``jointplay envelope`` takes it; the sentence under the
    table says which loads the envelope is under; without --envelope, or
    with another word, it is an option error (exit 2), not ignored."""
    crank = str(GALLERY / "slider_crank.yaml")
    default = run_cli("motion", crank, "--steps", "3", "--envelope")
    assert default.returncode == 0, default.stderr
    assert "(along [1, 0, 0]) under the model's loads: farthest at step" in default.stdout
    probes = run_cli("motion", crank, "--steps", "3", "--envelope", "--loads", "probes")
    assert probes.returncode == 0, probes.stderr
    assert "(along [1, 0, 0]) under 1 N probes: farthest at step" in probes.stdout
    alone = run_cli("motion", crank, "--steps", "3", "--loads", "probes")
    assert alone.returncode == 2 and alone.stdout == ""
    assert "--loads probes: the loads of the envelope at every pose; add --envelope" in (
        " ".join(alone.stderr.split())
    )
    wrong = run_cli("motion", crank, "--steps", "3", "--envelope", "--loads", "gas")
    assert wrong.returncode == 2 and "expected 'auto', 'model' or 'probes'" in wrong.stderr


def _stderr_on_a_terminal(*args: str) -> tuple[int, str, str]:
    """Run the command line with stderr on a pseudo-terminal, stdout piped."""
    import os
    import pty

    master, slave = pty.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "jointplay.cli", *args], stdout=subprocess.PIPE, stderr=slave
    )
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 65536)
        except OSError:  # the child has closed its end
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    out, _ = proc.communicate(timeout=300)
    return proc.returncode, out.decode(), b"".join(chunks).decode(errors="replace")


def test_cli_motion_progress_is_on_a_terminal_only() -> None:
    """The studies over the motion take minutes: on a terminal stderr shows
    their progress; piped, stderr stays empty and stdout is the same, and
    --json is clean either way."""
    args = ("motion", str(GALLERY / "four_bar.yaml"), "--steps", "3", "--envelope")
    piped = run_cli(*args, "--contributions")
    assert piped.returncode == 0 and piped.stderr == "", piped.stderr
    as_json = run_cli(*args, "--json")
    assert as_json.returncode == 0 and as_json.stderr == ""
    assert json.loads(as_json.stdout)["study"] == "motion"
    code, out, err = _stderr_on_a_terminal(*args, "--contributions")
    assert code == 0 and out == piped.stdout
    assert "envelopes at every pose" in err and "contributions at every pose" in err
    code, out, err = _stderr_on_a_terminal(*args, "--json")
    assert code == 0 and json.loads(out) == json.loads(as_json.stdout)
    assert "every pose" not in err


def test_cli_motion_with_samples_prints_band_columns_and_the_fraction() -> None:
    proc = run_cli("motion", str(GALLERY / "slider_crank.yaml"), "--steps", "3", "--samples", "8")
    assert proc.returncode == 0, proc.stderr
    assert "piston top along [1, 0, 0] p97.5 (mm)" in proc.stdout
    assert "Monte Carlo (8 sets of parts, seed 0):" in proc.stdout
    assert "miss the requirement on piston top" in proc.stdout  # how many, or none


def test_cli_motion_samples_on_a_model_where_nothing_varies(tmp_path: Path) -> None:
    import re

    text = (GALLERY / "slider_crank.yaml").read_text()
    path = tmp_path / "fixed.yaml"
    path.write_text(re.sub(r"clearance: \{fit: [^}]*\}", 'clearance: "20 um"', text))
    proc = run_cli("motion", str(path), "--steps", "3", "--samples", "8")
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "fixed.yaml" in proc.stderr and "the same" in proc.stderr


def test_a_slide_drive_places_the_piston_and_closes_the_loop() -> None:
    # the kinematics the studies pose their models by, driven by a slide:
    # the piston at the drive's value, the crank pin r from the main bearing
    # and l from the wrist pin (closed forms, 1e-9 mm)
    data = jointplay.load(GALLERY / "slider_crank.yaml").model_dump(
        by_alias=True, exclude_none=True
    )
    data["motion"] = {"drive": "guide", "range": ["0 mm", "-30 mm"], "steps": 7}
    for joint in data["joints"]:
        joint.pop("backlash", None)  # the motor's backlash would hold the crank
    data.pop("loads", None)  # the gas table is read against the crank's angle
    model = model_from_dict(data, source="slide")
    slide = np.linspace(0.0, -30.0, 7)
    poses = nominal_poses(model, slide)
    wrist, crank_pin = np.array([179.6424, 10.0, 0.0]), np.array([40.0, 0.0, 0.0])
    for s, value in enumerate(slide):
        C = poses.place(s, "piston", wrist)
        B = poses.place(s, "crank", crank_pin)
        assert np.max(np.abs(C - wrist - np.array([value, 0.0, 0.0]))) < 1e-9
        assert abs(np.linalg.norm(B) - 40.0) < 1e-9
        assert abs(np.linalg.norm(C - B) - np.linalg.norm(wrist - crank_pin)) < 1e-9
        assert abs(poses.place(s, "rod", crank_pin)[2]) < 1e-9


def test_each_part_started_from_its_last_pose_is_the_monte_carlo_at_each_pose() -> None:
    """Over a motion, each part's Newton starts from its own answer at the
    pose before (``own_starts``: its touching contacts seldom change over a
    step, and the four-bar's parts then mostly skip the full solve; measured
    in benchmarks/bench_motion.py). Whatever start a part takes, its answer
    at every pose is the Monte Carlo's of the posed model with the same parts,
    to the certificate's tolerance, in one process or two (runs of poses)."""
    model = _load("four_bar.yaml")
    steps = 13
    values = np.linspace(0.0, 2 * np.pi, steps)
    study = MotionMonteCarlo(samples=30, seed=3, motion=Motion(steps=steps))
    one, two = study.run(model), study.run(model, workers=2)
    poses = nominal_poses(model, values)
    for k in (1, 5, 6, 7, 12):
        alone = jointplay.MonteCarlo(samples=30, seed=3).run(posed_model(model, poses, k))
        _close(one.displacement[k], alone.displacement)
        _close(two.displacement[k], alone.displacement)


def test_own_starts_are_one_per_row() -> None:
    from jointplay.solver.solve import Workspace

    asm = assemble(_load("four_bar.yaml"))
    work = np.tile(load_map(asm, None).g0, (2, 1))
    with pytest.raises(ValueError, match="own_starts must have one entry per row"):
        Workspace(asm).solve_batch(work, own_starts=(None,))
    solved = Workspace(asm).solve_batch(work, own_starts=(None, None))
    assert solved.own_starts is not None and len(solved.own_starts) == 2
    again = Workspace(asm).solve_batch(work, own_starts=solved.own_starts)
    _close(again.x, solved.x)


def test_bands_are_drawn_where_the_samples_reach_them_and_no_miss_is_said_so(
    slider_crank: jointplay.Model, crank_parts: jointplay.MotionMonteCarloResult
) -> None:
    """12 sets of parts put none beyond 0.135 % or 2.5 % on average: no band
    is drawn from them; with 40 the 2.5-97.5 % band is. A limit no part misses
    is said so, not as 0 % at step 0."""
    nominal = Motion(steps=STEPS).run(slider_crank)
    bands, _ = MotionStudiesResult(nominal, monte_carlo=crank_parts).picture_extras()
    assert bands["piston top"] == []
    more = MotionMonteCarlo(samples=40, seed=3, motion=Motion(steps=STEPS)).run(slider_crank)
    bands, _ = MotionStudiesResult(nominal, monte_carlo=more).picture_extras()
    assert [label for label, _, _ in bands["piston top"]] == ["2.5-97.5 %"]
    loose = _load(
        "slider_crank.yaml",
        requirements=[{"point": "piston top", "max_displacement": 1.0, "along": list(ALONG_X)}],
    )
    parts = MotionMonteCarlo(samples=12, seed=3, motion=Motion(steps=STEPS)).run(loose)
    [said] = MotionStudiesResult(Motion(steps=STEPS).run(loose), monte_carlo=parts).findings()
    assert "none miss the requirement on piston top at any step" in said


def test_the_shares_of_the_variance_at_every_pose_are_each_pose_s_own() -> None:
    """The motion carries the Sobol' design's sets of parts through the
    poses (each Newton from the same set's answers before); the plain study
    solves each posed model on its own. The four-bar is not linear over its
    pins' ranges, so both take the shares of the variance at every pose: the
    same indices. The displacements of the two routes agree to the
    certificate (1e-9 of the largest play); the indices, ratios of their
    variances, to far inside 1e-6."""
    model = jointplay.load(GALLERY / "four_bar.yaml")
    motion = Motion(steps=4)
    carried = MotionContributions(samples=32, motion=motion).run(model)
    poses = nominal_poses(model, np.radians([0.0, 120.0, 240.0, 360.0]))
    for s, at_pose in enumerate(carried.results):
        alone = Contributions(samples=32).run(posed_model(model, poses, s))
        assert alone.sobol is not None and at_pose.sobol is not None
        assert at_pose.settings == alone.settings
        np.testing.assert_allclose(at_pose.sobol.first, alone.sobol.first, atol=1e-6)
        np.testing.assert_allclose(at_pose.sobol.total, alone.sobol.total, atol=1e-6)
        np.testing.assert_allclose(at_pose.sensitivity, alone.sensitivity, rtol=0, atol=1e-9)


def test_a_load_that_follows_its_body_keeps_its_ranges_along_the_turned_axes() -> None:
    """A ``follows: body`` load whose components are ranges: at every pose
    they vary along the body's axes as the pose has turned them, so a set of
    parts drawn with given load values is the motion of the model whose load
    is those values, turning with its body (each pose turned by its own)."""
    ranged = {
        "body": "coupler",
        "at": [100, 150, 0],
        "force": [0, {"min": -20, "max": -10}, {"min": -4, "max": 4}],
        "follows": "body",
    }
    model = _load("four_bar.yaml", loads=[ranged])
    asm = assemble(model)
    plays, lmap = play_map(asm).nominal, load_map(asm)
    assert lmap.labels == ("loads[0].force[1]", "loads[0].force[2]")
    study = MotionMonteCarlo(motion=Motion(steps=STEPS))
    for values in ((-20.0, 4.0), (-10.0, -4.0)):
        r = study.run_parts(model, plays[None], np.array([values]))
        fixed = {**ranged, "force": [0.0, *values]}
        direct = Motion(steps=STEPS).run(_load("four_bar.yaml", loads=[fixed]))
        _close(r.displacement[:, 0], direct.displacement)
    # the ranges themselves turn: at a pose the coupler has turned, the axis
    # a component was given along is no longer the global one
    poses = nominal_poses(model, np.linspace(0.0, 2 * np.pi, STEPS))
    posed = posed_model(model, poses, 1)
    turn = poses.turn(1, "coupler")
    directions = [part.direction for part in posed.loads[0].ranges()]
    np.testing.assert_allclose(directions, turn[:, 1:].T, atol=1e-15)
    assert not np.allclose(directions[0], (0.0, 1.0, 0.0))
