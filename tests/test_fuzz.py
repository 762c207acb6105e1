"""Hostile input: every malformed file gets exit code 2 and one short message
naming the file, the entry and the fix; never a traceback, a hang or a wrong
answer. A file that loads either solves with a certificate or exits 2 or 3.

Two parts: the corpus (``tests/fuzz_corpus``, one file per case, indexed by
``expected.yaml``), and a mutation fuzzer that starts from the bundled
examples. A crash the fuzzer finds becomes a corpus file.
"""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from conftest import ROOT
from jointplay.cli import app
from jointplay.io.modelfile import MAX_ENTRIES, MAX_FILE_BYTES, MAX_NODES

CORPUS = Path(__file__).parent / "fuzz_corpus"
EXPECTED: dict[str, dict[str, Any]] = yaml.safe_load((CORPUS / "expected.yaml").read_text())
#: No case may take longer (the loader bounds sizes, aliases and nesting).
SECONDS = 10.0
#: A problem is one paragraph: one line, at most this long.
LONGEST_MESSAGE = 700

runner = CliRunner()


def test_the_index_and_the_corpus_agree() -> None:
    files = {p.name for p in CORPUS.iterdir()} - {"expected.yaml"}
    kept = {name for name, case in EXPECTED.items() if "generate" not in case}
    assert files == kept
    assert len(EXPECTED) >= 40


def _make(name: str, case: dict[str, Any], where: Path) -> Path:
    """The file to solve: the corpus file, or one the case says to generate."""
    kind = case.get("generate")
    if kind is None:
        return CORPUS / name
    path = where / name
    if kind == "directory":
        path.mkdir()
    elif kind == "huge":  # over the size limit, and valid YAML (comments)
        line = "# " + "x" * 98 + "\n"
        path.write_text(line * (MAX_FILE_BYTES // len(line) + 1))
    elif kind == "many_values":  # under the size limit, over the limit of values
        path.write_text("bodies: [" + "1, " * MAX_NODES + "1]\n")
    elif kind == "many_entries":  # under the limit of values, over that of entries
        path.write_text("bodies: [{name: a}]\nloads: [" + "{}, " * MAX_ENTRIES + "{}]\n")
    else:
        assert kind == "missing", kind
    return path


def _run(args: list[str]) -> tuple[int, str, str, float]:
    start = time.perf_counter()
    result = runner.invoke(app, args)
    elapsed = time.perf_counter() - start
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise AssertionError(f"{args}: the CLI raised {result.exception!r}")
    return result.exit_code, result.stdout, result.stderr, elapsed


def _check_one_message(err: str, path: Path, kind: str) -> str:
    """One message: its first line the first problem, naming the file; an
    invalid model may list its other problems after it (issue 19), under a
    count, one indented line each, each naming its entry."""
    assert "Traceback" not in err
    assert err.endswith("\n"), f"not ended: {err!r}"
    first, *others = err[:-1].split("\n")
    assert len(first) <= LONGEST_MESSAGE, f"{len(first)} characters: {first}"
    prefix = f"jointplay: {kind}: "
    assert first.startswith(prefix), err
    if kind == "invalid model":
        assert first.startswith(f"{prefix}{path}: "), err
    if others:
        assert kind == "invalid model", f"not one line: {err!r}"
        count, *problems = others
        assert count.endswith(" more problem(s) in this file:"), err
        total = int(count.split()[0])
        if problems[-1].startswith("  ... and "):  # a long list is cut, saying how much
            assert total == len(problems) - 1 + int(problems[-1].split()[2]), err
        else:
            assert total == len(problems), err
        for line in problems:
            assert line.startswith("  ") and len(line) <= LONGEST_MESSAGE, f"{line!r} in {err!r}"
    return err


def _check_certified(out: str) -> None:
    doc = json.loads(out)
    assert doc["status"] == "optimal"
    for result in doc["cases"].values() if "cases" in doc else [doc]:
        assert result["status"] == "optimal"
        assert result["equilibrium_residual"] <= 1e-8
        if "accuracy" in result:
            assert result["accuracy"]["certified"]


def _cases() -> list[Any]:
    return [pytest.param(name, case, id=name) for name, case in EXPECTED.items()]


@pytest.mark.parametrize(("name", "case"), _cases())
def test_corpus_case(name: str, case: dict[str, Any], tmp_path: Path) -> None:
    path = _make(name, case, tmp_path)
    for mode in ([], ["--json"]):
        code, out, err, elapsed = _run(["solve", str(path), *mode])
        assert elapsed < SECONDS, f"{name}: {elapsed:.1f} s"
        assert "Traceback" not in out + err
        assert code == case["exit"], f"{name}: exit {code}, expected {case['exit']}: {err}"
        if code == 0:
            if mode:
                _check_certified(out)
            else:
                assert "certificate: holds" in out and "FAILED" not in out
            continue
        kind = {1: "error", 2: "invalid model", 3: "not held"}[code]
        message = _check_one_message(err, path, kind)
        for piece in case.get("message", []):
            assert piece in message, f"{name}: {piece!r} not in {message!r}"
        if mode:
            doc = json.loads(out)
            assert doc["status"] == {1: "error", 2: "invalid", 3: "unbounded"}[code]
            assert doc["message"] == message.removeprefix(f"jointplay: {kind}: ").rstrip("\n")


#: A handful through a real process: what a user sees, exit code and stderr.
SUBPROCESS = [
    "006_huge_integer.yaml",
    "016_power_tower_unit.yaml",
    "017_alias_bomb.yaml",
    "021_clearence_typo.yaml",
    "027_binary.yaml",
    "042_markup_name.yaml",
]


@pytest.mark.parametrize("name", SUBPROCESS)
def test_corpus_case_in_a_process(name: str) -> None:
    path = CORPUS / name
    start = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "jointplay.cli", "solve", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert time.perf_counter() - start < SECONDS + 5  # + the interpreter's start
    case = EXPECTED[name]
    assert proc.returncode == case["exit"], proc.stderr
    assert "Traceback" not in proc.stdout + proc.stderr
    if case["exit"] == 0:
        assert "certificate: holds" in proc.stdout and proc.stderr == ""
        return
    assert proc.stdout == ""
    message = _check_one_message(proc.stderr, path, "invalid model")
    for piece in case.get("message", []):
        assert piece in message


# -- the mutation fuzzer ---------------------------------------------------------

SEEDS = {p.name: yaml.safe_load(p.read_text()) for p in sorted(ROOT.glob("examples/**/*.yaml"))}

HOSTILE_NUMBERS = [
    0,
    -0.0,
    -1,
    0.2,
    7,
    1e308,
    -1e308,
    1e400,
    float("nan"),
    float("inf"),
    float("-inf"),
    1e-320,
    10**400,
    2**63,
    1e6,
    -1e6,
    1e9,
    1e-9,
    1e15,
]
HOSTILE_TEXTS = [
    "3 kg",
    "1 N",
    "0.2 mm",
    "400 um",
    "1 N*m",
    "2 percent",
    "0.5 deg",
    "1 furlongs_per_fortnight",
    "mm",
    "1e400 mm",
    "inf",
    ".nan",
    "-0.0",
    "9.81 m/s^2",
    "5 N/mm",
    "",
    " ",
    "10**10**10 mm",
    "1 mm^2",
    "0.2 dimensionless",
    "[/bold]",
    ":smile:",
    "a\nb",
    "x" * 300,
    "2001-13-45",
    "yes",
]
KEYS = [
    "clearence",
    "lenght",
    "axis",
    "up",
    "stiffness",
    "gap",
    "mass",
    "center_of_mass",
    "gravity",
    "ground",
    "type",
    "tpye",
    "name",
    "between",
    "at",
    "force",
    "torque",
    "width",
    "diameter",
    "load_cases",
    "schema",
]
SCALES = [-1, 0, 1e-6, 1e-3, 0.5, 2, 10, 1e3, 1e5]
TYPES = ["spherical", "cylindrical", "revolute", "rigid", "point", "planar", "prismatic", "x"]
INSERTS = [b"&a ", b"*a", b"[", b"{", b"\t", b"!!binary ", b": ", b"- ", b"\xff", b"---\n", b"<<: "]


def _scalars() -> st.SearchStrategy[Any]:
    return st.one_of(
        st.sampled_from(HOSTILE_NUMBERS),
        st.sampled_from(HOSTILE_TEXTS),
        st.none(),
        st.booleans(),
        st.integers(),
        st.floats(),
        st.text(max_size=8),
    )


def _values() -> st.SearchStrategy[Any]:
    return st.recursive(
        _scalars(),
        lambda inner: st.one_of(
            st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=3)
        ),
        max_leaves=6,
    )


def _paths(data: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every place in the data: keys of mappings, indices of lists."""
    if isinstance(data, dict):
        items: Any = data.items()
    elif isinstance(data, list):
        items = enumerate(data)
    else:
        return []
    out = []
    for key, value in items:
        out.append((*prefix, key))
        out.extend(_paths(value, (*prefix, key)))
    return out


def _at(data: Any, path: tuple[Any, ...]) -> Any:
    for key in path:
        data = data[key]
    return data


@st.composite
def mutants(draw: Any) -> tuple[str, str, bytes, bool]:
    """A bundled example, mutated one to three times in its data, then written
    as YAML or JSON, and perhaps cut or garbled as text: (seed, suffix, bytes,
    --json)."""
    seed = draw(st.sampled_from(sorted(SEEDS)))
    data = copy.deepcopy(SEEDS[seed])
    # half the mutants only rescale numbers: most of them load, and must then solve
    numeric = draw(st.booleans())
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(data)
        if numeric:
            paths = [p for p in paths if type(_at(data, p)) in (int, float)]
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = _at(data, path[:-1])
        key = path[-1]
        ops = ["delete", "value", "number", "text", "unknown key", "nest", "repeat", "type"]
        op = "scale" if numeric else draw(st.sampled_from(ops))
        if op == "delete":
            del parent[key]
        elif op == "value":
            parent[key] = draw(_values())
        elif op == "number":
            parent[key] = draw(st.sampled_from(HOSTILE_NUMBERS))
        elif op == "text":
            parent[key] = draw(st.sampled_from(HOSTILE_TEXTS))
        elif op == "unknown key":
            target = parent if isinstance(parent, dict) else data
            target[draw(st.sampled_from(KEYS))] = draw(_scalars())
        elif op == "nest":
            parent[key] = [parent[key]]
        elif op == "repeat" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[key]))
        elif op == "type":
            parent[key] = draw(st.sampled_from(TYPES))
        elif op == "scale":
            # a value that still loads, often: the solver must certify or say why not
            parent[key] = parent[key] * draw(st.sampled_from(SCALES)) + draw(
                st.sampled_from([0, 0, 0.01, 1])
            )
    as_json = draw(st.sampled_from([False, False, True]))
    raw = (json.dumps(data) if as_json else yaml.safe_dump(data, sort_keys=False)).encode()
    garble = draw(st.sampled_from(["", "", "", "cut", "flip", "insert"]))
    if garble == "cut":
        raw = raw[: draw(st.integers(0, len(raw)))]
    elif garble == "flip":
        i = draw(st.integers(0, len(raw) - 1))
        raw = raw[:i] + bytes([draw(st.integers(0, 255))]) + raw[i + 1 :]
    elif garble == "insert":
        i = draw(st.integers(0, len(raw)))
        raw = raw[:i] + draw(st.sampled_from(INSERTS)) + raw[i:]
    return seed, ".json" if as_json else ".yaml", raw, draw(st.booleans())


#: The "long" Hypothesis profile (tests/conftest.py: JOINTPLAY_PROFILE=long or
#: --hypothesis-profile=long): many fresh examples instead of the fixed 150.
_profile_name = getattr(settings, "get_current_profile_name", lambda: "")
_LONG = _profile_name() == "long" or os.environ.get("JOINTPLAY_PROFILE") == "long"


@settings(
    max_examples=5000 if _LONG else 150,
    derandomize=not _LONG,
    database=None,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
@given(case=mutants())
def test_mutated_examples_exit_0_2_or_3_cleanly(
    case: tuple[str, str, bytes, bool], tmp_path_factory: pytest.TempPathFactory
) -> None:
    seed, suffix, raw, as_json = case
    path = tmp_path_factory.getbasetemp() / f"mutant{suffix}"
    path.write_bytes(raw)
    code, out, err, elapsed = _run(["solve", str(path)] + (["--json"] if as_json else []))
    reproduce = (
        f"mutant of {seed}; to keep it, save these bytes in tests/fuzz_corpus/ and index "
        f"them in expected.yaml: {raw!r}"
    )
    assert code in (0, 2, 3), f"exit {code}: {err} ({reproduce})"
    assert "Traceback" not in out + err, reproduce
    assert elapsed < SECONDS, f"{elapsed:.1f} s ({reproduce})"
    if code == 0:
        if as_json:
            _check_certified(out)
        else:
            assert "certificate: holds" in out and "FAILED" not in out, reproduce
        return
    _check_one_message(err, path, {2: "invalid model", 3: "not held"}[code])
