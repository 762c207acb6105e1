"""A command imports only what it uses (issue 19: start-up).

``jointplay solve`` and ``--help`` must not wait for the studies' and the
pictures' libraries: pandas, matplotlib, plotly, SciPy's statistics, Dask,
SALib.
Python's own import log (``-X importtime``) says what a process imported.
How long that takes is measured in benchmarks/bench_startup.py, not here.
"""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from conftest import PAPER

#: Libraries a solve or the help never needs.
HEAVY = (
    "pandas",
    "matplotlib",
    "plotly",
    "scipy.stats",
    "dask",
    "distributed",
    "scipy.spatial",
    "SALib",
)
#: What a solve needs and the help does not (pydantic is left out: Typer
#: itself imports it to read a command's options).
SOLVER = ("numpy", "scipy", "clarabel", "pint", "yaml", "jointplay.solver", "jointplay.model")


def _imported(*args: str) -> set[str]:
    out = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "jointplay.cli", *args],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert out.returncode == 0, out.stdout + out.stderr
    names = set()
    for line in out.stderr.splitlines():
        if line.startswith("import time:") and "|" in line:
            names.add(line.rsplit("|", 1)[1].strip())
    assert "jointplay.errors" in names and "typer" in names  # the log we think it is
    return names


@pytest.mark.parametrize(
    "args",
    [
        ("solve", str(PAPER / "6.1.6.1.yaml")),
        ("solve", str(PAPER / "6.3.2.yaml"), "--json"),  # units through pint
        ("--help",),
        ("solve", "--help"),
    ],
    ids=["solve", "solve-units-json", "help", "solve-help"],
)
def test_a_command_imports_only_what_it_uses(args: tuple[str, ...]) -> None:
    names = _imported(*args)
    # the help needs none of the solver's libraries either; a solve needs them all
    heavy = (*HEAVY, *SOLVER) if "--help" in args else HEAVY
    loaded = sorted(n for n in names if any(n == h or n.startswith(h + ".") for h in heavy))
    assert loaded == []
    if "--help" not in args:
        assert "jointplay.solver" in names and "clarabel" in names


def test_pints_registry_is_kept_and_read_back(tmp_path: object) -> None:
    """The registry is built once and read from pint's cache after that; a
    cache folder that cannot be written only costs the time."""
    code = (
        "from jointplay.units import to_base; "
        "print(repr(to_base('3 arcmin', 'angle')), repr(to_base('1 N*m', 'torque')))"
    )
    answers = set()
    for cache in (str(tmp_path), str(tmp_path), "/proc/no-such-folder"):
        out = subprocess.run(
            [sys.executable, "-c", code],
            capture_output=True,
            text=True,
            timeout=120,
            check=False,
            env={"XDG_CACHE_HOME": cache, "HOME": cache, "PATH": "/usr/bin:/bin"},
        )
        assert out.returncode == 0 and out.stderr == "", out.stderr
        answers.add(out.stdout)
    assert len(answers) == 1  # the same numbers, cached or not
    angle, torque = (float(v) for v in answers.pop().split())
    assert angle == pytest.approx(math.pi / 3600, rel=1e-15)  # 3 arcmin in rad, to round-off
    assert torque == 1000.0  # N*mm


def test_dask_still_imports_after_pint_was_kept_from_it() -> None:
    """pint is imported with Dask hidden (``units._pint``); a study on a Dask
    cluster in the same process imports Dask afterwards as usual."""
    code = (
        "import sys; from jointplay.units import to_base; to_base('1 N*m', 'torque'); "
        "assert 'dask' not in sys.modules; import dask, distributed; print(dask.__name__)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False
    )
    assert out.returncode == 0 and out.stdout.strip() == "dask", out.stderr
