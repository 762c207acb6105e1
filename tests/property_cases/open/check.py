"""Rerun the property checks on the open cases (README.md): one line each,
``fixed`` or what still fails. Run from the repository root:
``python tests/property_cases/open/check.py``. Exits 0 whatever it finds."""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))  # tests/: the property checks and the reference

import test_properties as checks  # noqa: E402


def main() -> None:
    for path in sorted(HERE.glob("*.yaml")):
        try:
            checks.test_regression_case(path)
        except Exception as exc:  # what still fails, in one line
            words = " ".join(str(exc).split())
            print(f"{path.stem}: open: {type(exc).__name__}: {words[:240]}")
        else:
            print(f"{path.stem}: fixed: move it to tests/property_cases/")


if __name__ == "__main__":
    main()
