#!/usr/bin/env python
"""Start-up: how long a command takes, against the bare import of what it needs.

Each command runs as a new process, as a user starts it; the commands take
turns (A B C ... A B C ...) so that drift of the machine's speed hits all of
them alike. The yardstick is a process that only imports the solver's
dependencies: ``import numpy, scipy.sparse, clarabel, pydantic, yaml, pint``.
The target: ``jointplay solve`` on the paper's case, and
``jointplay --help``, within 0.3 s of it (medians).

Run from the repository root with jointplay installed:
``python benchmarks/bench_startup.py [--runs 15]``. It exits 0 whatever the
numbers.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 0.3
BARE = "import numpy, scipy.sparse, clarabel, pydantic, yaml, pint"


def _commands() -> dict[str, list[str]]:
    jointplay = shutil.which("jointplay") or ""
    cli = [jointplay] if jointplay else [sys.executable, "-m", "jointplay.cli"]
    paper = ROOT / "examples" / "paper"
    return {
        "bare import of the solver's dependencies": [sys.executable, "-c", BARE],
        "jointplay --help": [*cli, "--help"],
        "jointplay solve 6.1.6.1.yaml": [*cli, "solve", str(paper / "6.1.6.1.yaml")],
        "jointplay solve 6.3.2.yaml (units: pint)": [*cli, "solve", str(paper / "6.3.2.yaml")],
        "jointplay solve 6.1.6.1.yaml --json": [
            *cli,
            "solve",
            str(paper / "6.1.6.1.yaml"),
            "--json",
        ],
    }


def _time(command: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=15)
    args = parser.parse_args(argv)
    commands = _commands()
    for command in commands.values():  # warm the file cache and pint's registry cache
        _time(command)
    times: dict[str, list[float]] = {name: [] for name in commands}
    for _ in range(args.runs):
        for name, command in commands.items():
            times[name].append(_time(command))
    bare_name = next(iter(commands))
    bare = statistics.median(times[bare_name])
    print(f"Start-up: wall time of one process, {args.runs} runs each, taking turns")
    print(f"  Python {sys.version.split()[0]}; yardstick: python -c '{BARE}'")
    print()
    print(f"{'command':46s} {'median s':>9s} {'min s':>7s} {'max s':>7s} {'- bare s':>9s}")
    print("-" * 82)
    verdicts = []
    for name, runs in times.items():
        median = statistics.median(runs)
        extra = median - bare
        print(f"{name:46s} {median:9.3f} {min(runs):7.3f} {max(runs):7.3f} {extra:+9.3f}")
        if name in ("jointplay --help", "jointplay solve 6.1.6.1.yaml"):
            verdicts.append((name, extra))
    print()
    for name, extra in verdicts:
        met = "MET" if extra <= TARGET_S else "NOT MET"
        print(f"Target: {name} within {TARGET_S} s of the bare import: {extra:+.3f} s -> {met}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
