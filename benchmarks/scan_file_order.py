#!/usr/bin/env python
"""File order: how many random mechanisms answer differently when their file's
entries come in another order.

Not a timing benchmark and not a test: it draws random mechanisms from the
property tests' strategy (``tests/strategies.py``, drawn from a fixed seed: the
same models on every run), solves each in its own order and in the two shuffled
orders of ``check_file_order`` (``tests/test_properties.py``), and prints how
many got another verdict (solved, declined, not held, refused) in some order, how
many answers differ by more than that check allows (joint translations,
rotations and contact forces, each to 1e-10 of the largest of its kind, or
1e-15 where a whole kind is round-off), and the worst of them. Exits 0.

It needs the test extras (hypothesis). Run from the repository root:
``python benchmarks/scan_file_order.py`` (``--examples 400``; ``--compliant``:
joints with stiffness in every mechanism).
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the property tests' strategy

import jointplay  # noqa: E402
from test_properties import in_another_order, order_answers, order_limit  # noqa: E402

#: Hypothesis's seed: the same mechanisms on every run, whatever this file says.
SEED = 20140101


def verdict(data: dict[str, Any]) -> tuple[str, jointplay.Result | None]:
    try:
        return "solved", jointplay.solve(jointplay.model_from_dict(data))
    except jointplay.UnboundedMechanismError:
        return "not held", None
    except jointplay.SolverError:
        return "declined", None
    except jointplay.JointplayError:  # not assembled (deviations), say
        return "refused", None


def worst_excess(a: dict[str, dict[str, Any]], b: dict[str, dict[str, Any]]) -> tuple[float, str]:
    """The largest difference over what ``check_file_order`` allows (1: at the limit)."""
    worst, where = 0.0, ""
    for kind, values in a.items():
        allowed = order_limit(values)
        for key, value in values.items():
            excess = float(np.max(np.abs(np.asarray(b[kind][key]) - value))) / allowed
            if excess > worst:
                worst, where = excess, f"{kind} {key}"
    return worst, where


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", type=int, default=400)
    parser.add_argument(
        "--compliant", action="store_true", help="every mechanism with stiff joints drawn"
    )
    args = parser.parse_args(argv)
    warnings.filterwarnings("ignore")
    import clarabel
    import scipy
    from hypothesis import HealthCheck, Phase, given, seed, settings

    from strategies import mechanisms

    print(f"clarabel {clarabel.__version__}, numpy {np.__version__}, scipy {scipy.__version__}")
    count = 0
    verdicts: list[str] = []
    differ: list[tuple[float, str, int, int]] = []

    @settings(
        max_examples=args.examples,
        deadline=None,
        database=None,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @seed(SEED)
    @given(mech=mechanisms(compliant=True if args.compliant else None))
    def scan(mech: Any) -> None:
        nonlocal count
        count += 1
        data = mech.data
        runs = [verdict(data), *(verdict(in_another_order(data, seed)) for seed in (1, 2))]
        kinds = {v for v, _ in runs}
        size = (len(data["bodies"]) - 1, len(data["joints"]))
        if len(kinds) > 1:
            verdicts.append(f"{'/'.join(v for v, _ in runs)} ({size[0]} bodies, {size[1]} joints)")
            return
        if runs[0][1] is None:
            return
        base = order_answers(runs[0][1])
        for _, other in runs[1:]:
            assert other is not None
            excess, where = worst_excess(base, order_answers(other))
            if excess > 1.0:
                differ.append((excess, where, *size))
                return

    start = time.perf_counter()
    scan()
    seconds = time.perf_counter() - start
    print(f"{count} random mechanisms, {seconds:.0f} s")
    print(f"  another verdict in another order: {len(verdicts)}")
    for line in verdicts:
        print(f"    {line}")
    print(f"  answers beyond 1e-10 of the largest of their kind: {len(differ)}")
    for excess, where, bodies, joints in sorted(differ, reverse=True)[:10]:
        print(f"    {excess:.1e} times the limit, at {where} ({bodies} bodies, {joints} joints)")


if __name__ == "__main__":
    main()
