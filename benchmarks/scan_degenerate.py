#!/usr/bin/env python
"""Degenerate mechanisms: how many of a fixed set the solver declines.

Not a timing benchmark and not a test: it prints, per family, how many
models were solved, which were declined (exit 1: "could not be certified"),
the worst balance of the certified ones and the time, and exits 0. The
families are degenerate optima that take the retry's other path
(``fine_ipm_regularization``; docs/solver.md, "Known limits"):

* ``bearing``: ``bearing_chain(n)`` for n = 2..60, 70, 80, 90, 100, 120,
  150, 200, 300 (67 chains);
* ``others``: bearing chains of 61..97 shafts (every third), 110, 130, 170,
  250 and 400; chains of 10, 20, 30, 36, 40, 50 and 80 shafts under forces
  (0.3, 1, 1), (0, 1, 0), (0, 0.2, 1) and (0.1, -1, 0.5) N; tube strings of
  20, 50, 200 and 1,000 segments, open and closed, seeds 0 to 2 (70 models);
* ``long``: bearing chains of 350 to 1,000 shafts, every 50 (14 models, about
  20 s; not run unless asked: ``--families long``).

Its answer depends on the installed Clarabel, NumPy and SciPy: run it in
each environment you compare. Run from the repository root:
``python benchmarks/scan_degenerate.py`` (``--families bearing``;
``--families long`` for the long chains).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Iterator

import jointplay
from jointplay.errors import SolverError
from jointplay.io.generate import bearing_chain, bearing_chain_dict, tube_string
from jointplay.io.modelfile import model_from_dict

Case = tuple[str, Callable[[], jointplay.Model]]


def bearing() -> Iterator[Case]:
    for n in [*range(2, 61), 70, 80, 90, 100, 120, 150, 200, 300]:
        yield f"bearing {n}", lambda n=n: bearing_chain(n)


def others() -> Iterator[Case]:
    for n in [*range(61, 100, 3), 110, 130, 170, 250, 400]:
        yield f"bearing {n}", lambda n=n: bearing_chain(n)
    for force in [(0.3, 1.0, 1.0), (0.0, 1.0, 0.0), (0.0, 0.2, 1.0), (0.1, -1.0, 0.5)]:
        for n in (10, 20, 30, 36, 40, 50, 80):
            data = bearing_chain_dict(n, force=force)
            yield f"bearing {n} {force}", lambda d=data: model_from_dict(d, source="<scan>")
    for n in (20, 50, 200, 1000):
        for closed in (False, True):
            for seed in (0, 1, 2):
                name = f"string {n} {'closed' if closed else 'open'} seed {seed}"
                yield name, lambda n=n, c=closed, s=seed: tube_string(n, closed=c, seed=s)


def long() -> Iterator[Case]:
    for n in range(350, 1001, 50):
        yield f"bearing {n}", lambda n=n: bearing_chain(n)


FAMILIES = {"bearing": bearing, "others": others, "long": long}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--families", nargs="+", default=["bearing", "others"], choices=list(FAMILIES)
    )
    args = parser.parse_args(argv)
    import clarabel
    import numpy
    import scipy

    print(f"clarabel {clarabel.__version__}, numpy {numpy.__version__}, scipy {scipy.__version__}")
    for family in args.families:
        start, count, worst = time.perf_counter(), 0, 0.0
        declined: list[str] = []
        for name, build in FAMILIES[family]():
            count += 1
            try:
                result = jointplay.solve(build())
            except SolverError:
                declined.append(name)
            else:
                worst = max(worst, result.equilibrium_residual)
        seconds = time.perf_counter() - start
        print(
            f"{family}: {count} models, {len(declined)} declined {declined}, "
            f"worst balance of the others {worst:.1e}, {seconds:.0f} s"
        )


if __name__ == "__main__":
    main()
