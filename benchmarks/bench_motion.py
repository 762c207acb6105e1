#!/usr/bin/env python
"""Motion: the bundled four-bar turned through its cycle, beside one cold solve.

Printed, in one run (the machine's speed drifts: compare within a run):

* one cold solve of examples/gallery/four_bar.yaml: the file loaded and
  solved (``jointplay.solve``: assembly, free motions, Clarabel, polishing,
  certificate), the median of ``--repeats``;
* its 73-step motion (``jointplay.Motion().run``: the kinematics, then one
  solve per pose), the median of ``--repeats``, split into the kinematics,
  the posing (each pose's model, assembly and workspace) and the solves, and
  its ratio to the cold solve (target: at most 30);
* a Monte Carlo over the motion (``jointplay.MotionMonteCarlo``):
  ``--samples`` sets of parts carried through the 73 poses, with 1 and
  ``--workers`` processes (target: 2,000 parts in at most 60 s on 2 cores),
  with how many samples the batched Newton solved and how many went through
  the full solver, and the worst certificate over every sample and pose.

Run from the repository root: ``python benchmarks/bench_motion.py``.
Timing is informative: exits 0.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

import jointplay
from jointplay.assembly import assemble
from jointplay.solver.solve import Workspace
from jointplay.studies.kinematics import nominal_poses
from jointplay.studies.motion import posed_model

ROOT = Path(__file__).resolve().parents[1]
FOUR_BAR = ROOT / "examples" / "gallery" / "four_bar.yaml"
RATIO_TARGET = 30.0
MONTE_CARLO_TARGET_S = 60.0


def _median_time(fn: object, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()  # type: ignore[operator]
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def nominal(repeats: int) -> None:
    jointplay.solve(jointplay.load(FOUR_BAR))  # imports, once
    cold = _median_time(lambda: jointplay.solve(jointplay.load(FOUR_BAR)), 5 * repeats)
    model = jointplay.load(FOUR_BAR)
    motion = _median_time(lambda: jointplay.Motion().run(jointplay.load(FOUR_BAR)), repeats)
    assert model.motion is not None
    _, _, start, stop = model.motion_drive()
    values = np.linspace(start, stop, model.motion.steps)
    kinematics = _median_time(lambda: nominal_poses(model, values), repeats)
    poses = nominal_poses(model, values)

    def posing() -> None:
        for s in range(len(values)):
            Workspace(assemble(posed_model(model, poses, s)))

    posed = _median_time(posing, repeats)
    print(f"four-bar, cold solve (load + solve):   {cold * 1e3:8.1f} ms")
    print(
        f"four-bar, {model.motion.steps}-step motion:          {motion * 1e3:8.1f} ms "
        f"(kinematics {kinematics * 1e3:.1f} ms; posing: the posed models, their "
        f"assemblies and workspaces {posed * 1e3:.1f} ms; the poses' solves "
        f"{(motion - kinematics - posed) * 1e3:.1f} ms)"
    )
    print(f"  kinematics and posing alone: {(kinematics + posed) / cold:.1f} cold solves")
    ratio = motion / cold
    verdict = "met" if ratio <= RATIO_TARGET else "missed"
    print(f"  ratio motion / cold solve: {ratio:8.1f}  (target <= {RATIO_TARGET:g}: {verdict})")


def monte_carlo(samples: int, workers: int) -> None:
    model = jointplay.load(FOUR_BAR)
    for n_workers in sorted({1, workers}):
        start = time.perf_counter()
        result = jointplay.MotionMonteCarlo(samples=samples, seed=0).run(model, workers=n_workers)
        elapsed = time.perf_counter() - start
        verdict = "met" if elapsed <= MONTE_CARLO_TARGET_S * samples / 2000 else "missed"
        print(
            f"four-bar, Monte Carlo {samples:,} parts x {result.steps} poses, "
            f"{n_workers} process(es): {elapsed:6.1f} s "
            f"({samples * result.steps / elapsed:,.0f} samples/s; target 2,000 parts <= "
            f"{MONTE_CARLO_TARGET_S:g} s on 2 cores: {verdict})"
        )
        print(
            f"  batched {result.batched:,}, full solves {result.full_solves:,}; worst "
            f"certificate: feasibility {result.feasibility_mm:.2e} mm, balance "
            f"{result.equilibrium_residual:.2e}"
        )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--samples", type=int, default=2000)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--no-monte-carlo", action="store_true")
    args = parser.parse_args(argv)
    nominal(args.repeats)
    if not args.no_monte_carlo:
        monte_carlo(args.samples, args.workers)


if __name__ == "__main__":
    main()
