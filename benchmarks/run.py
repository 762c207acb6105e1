#!/usr/bin/env python
"""Every benchmark, one command: prints all the tables.

1. ``bench_paper.py``: section 6.1.6.1 in detail (the paper's own 12-variable
   SLSQP, CVXPY + Clarabel, the raw Clarabel floor; then many loads on one
   mechanism: batch, warm, cold);
2. ``bench_cases.py``: every case of the paper against SLSQP and CVXPY;
3. ``bench_scaling.py``: chains and closed loops of 10 to 10,000 bodies;
4. ``bench_montecarlo.py``: Monte Carlo samples per second against SLSQP;
5. ``bench_startup.py``: a command's wall time against the bare import of
   the solver's dependencies;
6. ``bench_motion.py``: the four-bar's and the slider-crank's 73-step motion
   against one cold solve, and a Monte Carlo over the slider-crank's motion.

Run from the repository root with jointplay installed (CVXPY from the
``bench`` extra): ``python benchmarks/run.py`` (``--quick``: fewer repeats,
sizes to 1,000). Timing is informative: it exits 0 whatever the numbers.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_cases
import bench_montecarlo
import bench_motion
import bench_paper
import bench_scaling
import bench_startup


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats, sizes to 1,000")
    args = parser.parse_args(argv)
    repeat = ["--repeat", "50" if args.quick else "300"]
    steps = ["--steps", "720", "--subset", "40"] if args.quick else []
    print("=" * 100 + "\n1. Section 6.1.6.1 in detail\n" + "=" * 100)
    bench_paper.main([*repeat, *steps])
    print("\n" + "=" * 100 + "\n2. Every case of the paper\n" + "=" * 100)
    bench_cases.main(["--repeat", "10" if args.quick else "30"])
    print("\n" + "=" * 100 + "\n3. Scaling with size\n" + "=" * 100)
    sizes = ["10", "100", "1000"] if args.quick else ["10", "100", "1000", "10000"]
    bench_scaling.main(["--sizes", *sizes])
    print("\n" + "=" * 100 + "\n4. Monte Carlo over real parts\n" + "=" * 100)
    bench_montecarlo.main(["--samples", "200000" if args.quick else "1000000"])
    print("\n" + "=" * 100 + "\n5. Start-up\n" + "=" * 100)
    bench_startup.main(["--runs", "5" if args.quick else "15"])
    print("\n" + "=" * 100 + "\n6. Motion through the cycle\n" + "=" * 100)
    bench_motion.main(["--samples", "200" if args.quick else "2000"])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
