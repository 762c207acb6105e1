#!/usr/bin/env python
"""Sobol' indices against a Monte Carlo of as many samples (issue 53).

SALib's Saltelli design for D inputs and N base sets of parts (first-order
and total indices) is a Monte Carlo of N (D + 2) sets of parts: it should
cost what a Monte Carlo study of as many samples costs on the same model,
both going through the batch solver (the design's mapping to sets of parts
and SALib's estimators add little). On examples/gallery/four_bar.yaml (five
inputs: three pin fits, two load components), with N = 1,024: 7,168 solves
each, side by side.

Printed: each one's seconds and solves per second, and their ratio (Sobol'
over Monte Carlo), and the four-bar's indices (first order, total, with
their intervals). After a warm-up of both, the two studies take turns
``--repeat`` times and the medians are compared (the machine's speed drifts
by tens of percent within a minute).

Run from the repository root: ``python benchmarks/bench_sobol.py``
(``--samples N`` to change the base sets, a power of 2; ``--workers`` for
processes; ``--repeat``).
Timing is informative: exits 0.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import jointplay
from jointplay.studies.montecarlo import MonteCarlo
from jointplay.studies.sobol import Sobol

ROOT = Path(__file__).resolve().parents[1]
FOUR_BAR = ROOT / "examples" / "gallery" / "four_bar.yaml"
#: Issue 53's comparison: the four-bar's five inputs and 1,024 base sets of parts.
BASE_SAMPLES = 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=BASE_SAMPLES)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    model = jointplay.load(FOUR_BAR)
    sobol = Sobol(samples=args.samples, seed=0)
    # warm-up: imports, the assembly's caches, Clarabel's first call
    Sobol(samples=8, seed=1).run(model)
    MonteCarlo(samples=100, seed=1).run(model)

    sobol_times, mc_times = [], []
    for _ in range(args.repeat):
        start = time.perf_counter()
        indices = sobol.run(model, workers=args.workers)
        sobol_times.append(time.perf_counter() - start)
        solves = indices.solves
        start = time.perf_counter()
        mc = MonteCarlo(samples=solves, seed=0).run(model, workers=args.workers)
        mc_times.append(time.perf_counter() - start)
    sobol_s, mc_s = statistics.median(sobol_times), statistics.median(mc_times)

    print(f"{FOUR_BAR.name}: {len(indices.inputs)} inputs, {args.samples:,} base sets of parts")
    print(f"medians of {args.repeat} turns each")
    print(f"{'study':<24}{'solves':>10}{'seconds':>10}{'solves/s':>11}")
    for name, n, seconds in (
        ("Sobol' (SALib)", solves, sobol_s),
        ("Monte Carlo", mc.samples, mc_s),
    ):
        print(f"{name:<24}{n:>10,}{seconds:>10.2f}{n / seconds:>11,.0f}")
    print(f"ratio Sobol' / Monte Carlo: {sobol_s / mc_s:.2f} (1 is the same cost per solve)")
    print()
    print(f"{'input':<20}{'first order':>22}{'total':>22}")
    for i, name in enumerate(indices.inputs):
        f, ft = indices.first[0, i], indices.first_interval[0, i]
        t, tt = indices.total[0, i], indices.total_interval[0, i]
        print(
            f"{name:<20}{f:>8.3f} [{ft[0]:6.3f}, {ft[1]:6.3f}]"
            f"{t:>8.3f} [{tt[0]:6.3f}, {tt[1]:6.3f}]"
        )


if __name__ == "__main__":
    main()
