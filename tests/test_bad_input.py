"""Every bad input gets one clear message naming the file, the entry and the fix,
and exit code 2 from the CLI; never a traceback."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

import jointplay
from conftest import spherical_shaft
from jointplay import ModelError
from test_cli import run


def write(tmp_path: Path, data: Any, name: str = "model.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data, sort_keys=False) if not isinstance(data, str) else data)
    return path


def joint(index: int, **changes: Any) -> dict[str, Any]:
    data = spherical_shaft()
    data["joints"][index].update(changes)
    return data


FACE = {"name": "f", "type": "planar", "between": ["S0", "S1"], "at": [0, 0, 0], "clearance": 0.1}

CASES: list[tuple[str, Any, str]] = [
    (
        "unknown body in a joint",
        joint(1, between=["S0", "S2"]),
        r"joints\[1\] 'l2': between: unknown body 'S2'; bodies are: S0, S1\. Did you mean 'S1'\?",
    ),
    (
        "unknown body in a load",
        spherical_shaft(loads=[{"body": "shaft", "at": [0, 0, 0], "force": [1, 0, 0]}]),
        r"loads\[0\]: body: unknown body 'shaft'",
    ),
    (
        "unknown joint type",
        joint(0, type="sferical"),
        r"joints\[0\] 'l1': unknown joint type 'sferical'\. Did you mean 'spherical'\? "
        r"Known types:",
    ),
    (
        "duplicate body names",
        spherical_shaft(bodies=[{"name": "S0", "ground": True}, {"name": "S1"}, {"name": "S1"}]),
        r"bodies\[2\]: duplicate body name 'S1' \(also bodies\[1\]\)",
    ),
    (
        "duplicate joint names",
        joint(1, name="l1"),
        r"joints\[1\]: duplicate joint name 'l1' \(also joints\[0\]\)",
    ),
    (
        "joint from a body to itself",
        joint(0, between=["S1", "S1"]),
        r"joints\[0\] 'l1': between: the joint goes from body 'S1' to itself",
    ),
    (
        "negative clearance",
        joint(0, clearance=-0.2),
        r"joints\[0\] 'l1': clearance: expected a value >= 0, got -0\.2",
    ),
    ("zero length", joint(1, length=0), r"joints\[1\] 'l2': length: expected a value > 0, got 0"),
    (
        "negative length",
        joint(1, length="-4 cm"),
        r"joints\[1\] 'l2': length: expected a value > 0, got -40",
    ),
    (
        "zero axis",
        joint(1, axis=[0, 0, 0]),
        r"joints\[1\] 'l2': axis: expected a nonzero direction",
    ),
    (
        "NaN",
        joint(0, clearance=float("nan")),
        r"joints\[0\] 'l1': clearance: expected a finite length",
    ),
    (
        "NaN in a vector",
        spherical_shaft(loads=[{"body": "S1", "at": [300, 0, 0], "force": [1, ".nan", 1]}]),
        r"loads\[0\]: force: component y: expected a finite force",
    ),
    (
        "no ground body",
        spherical_shaft(bodies=[{"name": "S0"}, {"name": "S1"}]),
        r"bodies: no ground body; mark the fixed body with 'ground: true'",
    ),
    (
        "a body no joint connects to ground",
        spherical_shaft(bodies=[{"name": "S0", "ground": True}, {"name": "S1"}, {"name": "S2"}]),
        r"bodies: no chain of joints connects 'S2' to a ground body",
    ),
    (
        "wrong units",
        joint(0, clearance="3 kg"),
        r"joints\[0\] 'l1': clearance: expected a length, got '3 kg', which is a mass; write a "
        r"plain number in mm or a string with units",
    ),
    (
        "a force as a length: the dimension named as the model names it",
        joint(0, clearance="15 N"),
        r"joints\[0\] 'l1': clearance: expected a length, got '15 N', which is a force; write a ",
    ),
    (
        "a unit no model entry takes: pint's words",
        joint(0, clearance="3 s"),
        r"joints\[0\] 'l1': clearance: expected a length, got '3 s', which is a \[time\]; write a ",
    ),
    (
        "an angle as a length",
        joint(0, clearance="0.5 deg"),
        r"joints\[0\] 'l1': clearance: expected a length, got '0.5 deg', which is an angle; "
        r"write a plain number in mm",
    ),
    (
        "a clearance on a rigid joint",
        spherical_shaft(
            bodies=[{"name": "S0", "ground": True}, {"name": "S1"}],
            joints=[
                {
                    "name": "w",
                    "type": "rigid",
                    "between": ["S0", "S1"],
                    "at": [0, 0, 0],
                    "clearance": 0.1,
                }
            ],
        ),
        r"joints\[0\] 'w': clearance: a rigid joint has no play, got clearance 0.1",
    ),
    (
        "unknown unit",
        joint(0, clearance="3 furlongs_per_fortnight"),
        r"joints\[0\] 'l1': clearance: unknown unit in '3 furlongs_per_fortnight'",
    ),
    (
        "unknown key with a suggestion",
        joint(1, lenght=40),
        r"joints\[1\] 'l2': lenght: unknown key 'lenght'\. Did you mean 'length'\?",
    ),
    (
        "missing key",
        {
            "bodies": [{"name": "S0", "ground": True}, {"name": "S1"}],
            "joints": [
                {
                    "name": "l1",
                    "type": "cylindrical",
                    "between": ["S0", "S1"],
                    "at": [0, 0, 0],
                    "clearance": 0.2,
                }
            ],
        },
        r"joints\[0\] 'l1': length: the key 'length' is required here; add it",
    ),
    (
        "a force without a point",
        spherical_shaft(loads=[{"body": "S1", "force": [1, 0, 0]}]),
        r"loads\[0\]: a force needs its point of application",
    ),
    (
        "a load on the ground",
        spherical_shaft(loads=[{"body": "S0", "at": [0, 0, 0], "force": [1, 0, 0]}]),
        r"loads\[0\]: body: 'S0' is a ground body",
    ),
    (
        "a vector of two components",
        joint(0, at=[0, 0]),
        r"joints\[0\] 'l1': at: expected a list of 3 components",
    ),
    (
        "up along the axis",
        joint(1, up=[2, 0, 0]),
        r"joints\[1\] 'l2': up \[2\.0, 0\.0, 0\.0\] is parallel to axis",
    ),
    (
        "ground given as text",
        spherical_shaft(bodies=[{"name": "S0", "ground": "yes"}, {"name": "S1"}]),
        r"bodies\[0\] 'S0': ground: expected true or false, got 'yes'",
    ),
    (
        "a joint between two grounds",
        spherical_shaft(bodies=[{"name": "S0", "ground": True}, {"name": "S1", "ground": True}]),
        r"joints\[0\] 'l1': between: both 'S0' and 'S1' are ground bodies",
    ),
    (
        "unknown top-level key",
        spherical_shaft(load=[]),
        r"unknown key 'load'\. Did you mean 'loads'\?",
    ),
    ("not a mapping", [1, 2, 3], r"expected a mapping with 'bodies', 'joints' and 'loads'"),
    ("empty file", "", r"the file is empty"),
    ("not YAML at all", "bodies: [\n  - {name: S0", r"not valid YAML at line"),
    ("duplicate YAML key", "bodies: []\nbodies: []\n", r"duplicate key 'bodies'"),
    ("no joints", spherical_shaft(joints=[]), r"joints: expected at least one entry"),
    (
        "functional point without its position",
        spherical_shaft(points=[{"name": "tip", "body": "S1"}]),
        r"points\[0\] 'tip': at: the key 'at' is required here; add it",
    ),
    (
        "typo in a load case",
        spherical_shaft(load_cases={"a": [{"body": "S1", "torqe": [1, 0, 0]}]}),
        r"load_cases\.a\[0\]: torqe: unknown key 'torqe'\. Did you mean 'torque'\?",
    ),
    (
        "negative mass",
        spherical_shaft(bodies=[{"name": "S0", "ground": True}, {"name": "S1", "mass": -2}]),
        r"bodies\[1\] 'S1': mass: expected a value >= 0, got -2",
    ),
    (
        "load cases that are not a mapping",
        spherical_shaft(load_cases=[1, 2]),
        r"load_cases: expected a mapping \(NAME: \[\.\.\.\], \.\.\.\), got list",
    ),
    (
        "planar face both a rectangle and a disc",
        spherical_shaft(joints=[{**FACE, "diameter": 20, "width": 3, "height": 4}]),
        r"joints\[0\] 'f': a planar joint's face is a rectangle \('width' and 'height'\) "
        r"or a disc \('diameter'\), not both; remove one",
    ),
    (
        "point joint given a clearance",
        spherical_shaft(joints=[{**FACE, "type": "point", "clearance": 0.1}]),
        r"joints\[0\] 'f': clearance: a point joint has a one-sided 'gap' to its plane, "
        r"not a 'clearance'; write gap: 0\.1",
    ),
]


@pytest.mark.parametrize(("label", "data", "message"), CASES, ids=[c[0] for c in CASES])
def test_bad_model_raises_one_clear_model_error(
    tmp_path: Path, label: str, data: Any, message: str
) -> None:
    path = write(tmp_path, data)
    with pytest.raises(ModelError, match=message) as info:
        jointplay.load(path)
    text = str(info.value)
    assert text.startswith(str(path) + ": ")
    first, *others = text.split("\n")  # a file's other problems, listed after the first
    assert re.search(message, first), first
    if others:
        count, *problems = others
        assert count == f"{len(problems)} more problem(s) in this file:", text
        assert all(line.startswith("  ") and "\n" not in line for line in problems), text
    assert "Traceback" not in text


@pytest.mark.parametrize(("label", "data", "message"), CASES[:8], ids=[c[0] for c in CASES[:8]])
def test_cli_exits_2_with_the_message_and_no_traceback(
    tmp_path: Path, label: str, data: Any, message: str
) -> None:
    path = write(tmp_path, data)
    proc = run("solve", str(path))
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert "Traceback" not in proc.stderr
    assert str(path) in proc.stderr
    assert proc.stderr.startswith("jointplay: invalid model: ")


def test_missing_file_is_exit_2(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match="no such file"):
        jointplay.load(tmp_path / "nope.yaml")


_SHAFT_TEXT = yaml.safe_dump(spherical_shaft(), sort_keys=False)
#: 80 kB of comment lines: more than the bytes checked first (HEAD_BYTES).
_FAR = ("# " + "-" * 77 + "\n") * 1000

NOT_TEXT = [
    (
        "a picture",
        b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)) * 1000,
        "this is a binary file (it holds NUL bytes), not a model file",
    ),
    (
        "UTF-16 without its mark",
        (_SHAFT_TEXT + _FAR).encode("utf-16-le"),
        "this is a binary file (it holds NUL bytes), not a model file",
    ),
    (
        "Latin-1",
        ("name: Tr\xe4ger\n" + _SHAFT_TEXT + _FAR).encode("latin-1"),
        "not UTF-8 text: byte 0xe4 at line 1, column 9 is not UTF-8; save the file as UTF-8",
    ),
    (
        "a NUL byte far in",
        (_FAR + _SHAFT_TEXT).encode() + b"name: \x00\n",
        "holds the control character #x0000, which YAML does not allow",
    ),
    (
        "Latin-1 far in",
        (_FAR + "name: Tr\xe4ger\n" + _SHAFT_TEXT).encode("latin-1"),
        "not UTF-8 text: byte 0xe4 at line 1001, column 9",
    ),
]


@pytest.mark.parametrize(("label", "content", "message"), NOT_TEXT, ids=[c[0] for c in NOT_TEXT])
def test_a_file_that_is_not_text_is_refused_with_exit_2(
    tmp_path: Path, label: str, content: bytes, message: str
) -> None:
    """Binary content is refused from the first bytes (HEAD_BYTES), before the
    rest of the file is read; past them, as the text is decoded or parsed.
    Either way one line naming the file, and exit code 2."""
    path = tmp_path / "model.yaml"
    path.write_bytes(content)
    proc = run("solve", str(path))
    assert proc.returncode == 2, proc.stderr
    assert proc.stdout == "" and "Traceback" not in proc.stderr
    assert proc.stderr.startswith(f"jointplay: invalid model: {path}: "), proc.stderr
    assert message in proc.stderr and proc.stderr.count("\n") == 1, proc.stderr


def test_a_character_across_the_first_bytes_checked_still_reads(tmp_path: Path) -> None:
    from jointplay.io.modelfile import HEAD_BYTES

    comment = "# " + "x" * (HEAD_BYTES - 3) + "\u00e4\n"  # its two bytes: either side
    path = tmp_path / "model.yaml"
    path.write_text(comment + _SHAFT_TEXT, encoding="utf-8")
    assert path.read_bytes()[HEAD_BYTES - 1 : HEAD_BYTES + 1] == "\u00e4".encode()
    assert len(jointplay.load(path).bodies) == 2


def test_json_and_toml_read_the_same_keys(tmp_path: Path) -> None:
    data = spherical_shaft()
    data["loads"].append({"body": "S1", "torque": [0, 0, "1 N*m"]})
    as_yaml = jointplay.load(write(tmp_path, data))
    as_json = jointplay.load(write(tmp_path, json.dumps(data), "model.json"))
    toml = """
[[bodies]]
name = "S0"
ground = true
[[bodies]]
name = "S1"
[[joints]]
name = "l1"
type = "spherical"
between = ["S0", "S1"]
at = [0, 0, 0]
clearance = 0.2
[[joints]]
name = "l2"
type = "cylindrical"
between = ["S0", "S1"]
at = [200, 0, 0]
axis = [1, 0, 0]
length = 40
clearance = 0.2
[[loads]]
body = "S1"
at = [300, 0, 0]
force = [1, 1, 1]
[[loads]]
body = "S1"
torque = [0, 0, "1 N*m"]
"""
    as_toml = jointplay.load(write(tmp_path, toml, "model.toml"))
    assert as_yaml == as_json == as_toml
    bad_json = write(tmp_path, '{"bodies": [', "bad.json")
    with pytest.raises(ModelError, match=r"bad.json: not valid JSON"):
        jointplay.load(bad_json)
    bad_toml = write(tmp_path, "bodies = [", "bad.toml")
    with pytest.raises(ModelError, match=r"bad.toml: not valid TOML"):
        jointplay.load(bad_toml)


def test_models_are_immutable() -> None:
    model = jointplay.model_from_dict(spherical_shaft())
    with pytest.raises(Exception, match="frozen"):
        model.joints[0].clearance = 1.0  # type: ignore[misc]


def test_a_generated_model_with_too_many_entries_is_refused_before_validation() -> None:
    """A model given as a dict meets no file limit; 100,001 bodies are refused
    by count, naming the section, before each is validated."""
    data = {
        "bodies": [{"name": "g", "ground": True}] + [{"name": f"b{i}"} for i in range(100_000)],
        "joints": [],
    }
    with pytest.raises(ModelError) as info:
        jointplay.model_from_dict(data)
    message = str(info.value)
    assert "bodies" in message and "100,001 entries" in message


_SHAFT_YAML = """bodies:
  - {{name: S0, ground: true}}
  - {{name: S1}}
joints:
  - {{name: l1, type: spherical, between: [S0, S1], at: [0, 0, 0], clearance: {play}}}
  - {{name: l2, type: cylindrical, between: [S0, S1], at: [200, 0, 0], length: 40, clearance: 0.2}}
loads:
  - {{body: S1, at: [300, 0, 0], force: [1, 1, 1]}}
"""


@pytest.mark.parametrize(
    ("play", "message"),
    [
        ("0x10", "'0x10' is a YAML 1.1 numeral"),  # YAML 1.1: 16
        ("1_0", "'1_0' is a YAML 1.1 numeral"),  # YAML 1.1: 10
        ("017", "'017' is a YAML 1.1 numeral"),  # YAML 1.1: 15 (octal)
        ("1:30", "'1:30' is a YAML 1.1 numeral"),  # YAML 1.1: 90 (sexagesimal)
        ("1_0.5", "'1_0.5' is a YAML 1.1 numeral"),
        ("0o17", "'0o17' is a hexadecimal, octal or binary numeral"),  # YAML 1.2: 15
        ("'0x10'", "'0x10' is a hexadecimal, octal or binary numeral"),  # as text
        ("'0x10 mm'", "'0x10 mm' is a hexadecimal, octal or binary numeral"),  # with a unit
        ("1e-400", "too small for double precision and would read as 0"),
        ("1.0e-400", "too small for double precision and would read as 0"),
        ("'1e-400 mm'", "too small for double precision and would read as 0"),
    ],
)
def test_numbers_that_read_otherwise_are_refused(tmp_path: Path, play: str, message: str) -> None:
    """A number that YAML 1.1 reads otherwise than YAML 1.2 and JSON, or that
    underflows to 0 (which would make the joint ideal), is refused where a
    number is expected, naming the entry, with exit 2."""
    path = tmp_path / "model.yaml"
    path.write_text(_SHAFT_YAML.format(play=play))
    proc = run("solve", str(path))
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.startswith(f"jointplay: invalid model: {path}: ")
    assert message in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize("play", ["0.2", ".2", "2e-1", "0", "-0.0", "'200 um'", "'1e-9 km'"])
def test_plain_decimal_numbers_still_read(tmp_path: Path, play: str) -> None:
    path = tmp_path / "model.yaml"
    path.write_text(_SHAFT_YAML.format(play=play))
    jointplay.load(path)


def test_a_tiny_number_with_a_large_unit_is_read_not_called_an_underflow() -> None:
    # 1e-300 is a double; in km it is 1e-294 mm (as a play, the model refuses it
    # as too small against its size: test_a_play_too_small_to_resolve_...)
    from jointplay.units import to_base

    assert to_base("1e-300 km", "length") == pytest.approx(1e-294, rel=1e-12)


_SHAFT_TOML = """
bodies = [{name = "S0", ground = true}, {name = "S1"}]
joints = [
  {name = "l1", type = "spherical", between = ["S0", "S1"], at = [0, 0, 0], clearance = 1e-400},
  {name = "l2", type = "cylindrical", between = ["S0", "S1"], at = [200, 0, 0], length = 40,
   clearance = 0.2},
]
loads = [{body = "S1", at = [300, 0, 0], force = [1, 1, 1]}]
"""


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_json_and_toml_refuse_an_underflow_too(tmp_path: Path, suffix: str) -> None:
    if suffix == ".json":
        data = yaml.safe_load(_SHAFT_YAML.format(play="0.2"))
        body = json.dumps(data).replace('"clearance": 0.2', '"clearance": 1e-400', 1)
    else:
        body = _SHAFT_TOML
    path = tmp_path / f"model{suffix}"
    path.write_text(body)
    assert "1e-400" in path.read_text()
    with pytest.raises(ModelError, match="too small for double precision"):
        jointplay.load(path)


def test_every_problem_of_a_file_is_listed_at_once(tmp_path: Path) -> None:
    """One run lists them all (issue 19): the first in the message's first line,
    then one line per other problem, each naming its entry. A key missing beside
    a misspelt one, and an empty section whose entries all failed, follow from
    other problems and are not listed again."""
    data = spherical_shaft()
    data["bodies"][1]["mass"] = -2  # type: ignore[index]
    data["joints"][0]["at"] = [0, 0]  # type: ignore[index]
    bore = data["joints"][1]  # type: ignore[index]
    bore["lenght"] = bore.pop("length")
    bore["clearance"] = "2 N"
    with pytest.raises(ModelError) as caught:
        model_from_dict_at(tmp_path, data)
    first, count, *others = str(caught.value).split("\n")
    assert first.endswith("model.yaml: bodies[1] 'S1': mass: expected a value >= 0, got -2")
    assert count == "3 more problem(s) in this file:"
    assert [line.split(":")[0:2] for line in others] == [
        ["  joints[0] 'l1'", " at"],
        ["  joints[1] 'l2'", " clearance"],
        ["  joints[1] 'l2'", " lenght"],
    ]
    assert "Did you mean 'length'?" in others[2]


def test_a_long_list_of_problems_is_cut_saying_how_many(tmp_path: Path) -> None:
    from jointplay.io.modelfile import MOST_PROBLEMS

    data = spherical_shaft()
    ball = data["joints"][0]  # type: ignore[index]
    data["joints"] = [{**ball, "name": f"j{i}", "clearance": "x"} for i in range(MOST_PROBLEMS + 6)]
    with pytest.raises(ModelError) as caught:
        model_from_dict_at(tmp_path, data)
    lines = str(caught.value).split("\n")
    assert lines[1] == f"{MOST_PROBLEMS + 5} more problem(s) in this file:"
    assert len(lines) == 2 + MOST_PROBLEMS + 1 and lines[-1] == "  ... and 5 more"


def model_from_dict_at(tmp_path: Path, data: dict[str, Any]) -> Any:
    return jointplay.load(write(tmp_path, data))


def test_gravity_survives_its_own_round_trip(tmp_path: Path) -> None:
    """A nonzero plain number is refused in gravity, so a model writes its
    gravity back with the unit: sweeps and ``Model.replace`` rebuild models
    from their dump (a sweep on a model with gravity once failed there)."""
    model = jointplay.load(Path(__file__).parents[1] / "examples" / "studies" / "shaft_cases.yaml")
    again = jointplay.model_from_dict(model.model_dump(by_alias=True, exclude_none=True))
    assert again.gravity == model.gravity and model.gravity is not None
    assert model.replace(name="renamed").gravity == model.gravity
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "jointplay.cli",
            "sweep",
            str(Path(__file__).parents[1] / "examples" / "studies" / "shaft_cases.yaml"),
            "--vary",
            "joints[l2].clearance=0.1:0.3:3",
            "--case",
            "cutting",
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr


def test_a_huge_integer_in_gravity_is_a_model_error(tmp_path: Path) -> None:
    data = spherical_shaft(gravity=[0, 0, int("9" * 400)])
    path = tmp_path / "model.json"
    path.write_text(json.dumps(data))
    with pytest.raises(ModelError, match="gravity"):
        jointplay.load(path)


def test_a_long_yaml_1_1_numeral_is_refused_too(tmp_path: Path) -> None:
    path = tmp_path / "model.yaml"
    path.write_text(_SHAFT_YAML.format(play="0x" + "0" * 1000 + "10"))
    with pytest.raises(ModelError, match=r"YAML 1\.1 numeral"):
        jointplay.load(path)


def test_problems_across_entries_are_listed_together(tmp_path: Path) -> None:
    """Names that point nowhere, in joints, loads and requirements, come in one
    run; a connection check that would only repeat them is left out."""
    data = spherical_shaft(
        points=[{"name": "tip", "body": "S1", "at": [300, 0, 0]}],
        requirements=[{"point": "tap", "max_displacement": 0.1}],
    )
    data["joints"][0]["between"] = ["S0", "S2"]  # type: ignore[index]
    data["loads"] = [  # type: ignore[index]
        {"body": "S3", "at": [300, 0, 0], "force": [1, 1, 1]},
        {"body": "S0", "at": [300, 0, 0], "force": [1, 1, 1]},
    ]
    with pytest.raises(ModelError) as caught:
        model_from_dict_at(tmp_path, data)
    first, count, *others = str(caught.value).split("\n")
    assert first.endswith(
        "joints[0] 'l1': between: unknown body 'S2'; bodies are: S0, S1. Did you mean 'S1'?"
    )
    assert count == "3 more problem(s) in this file:"
    assert [line.split(":")[0] for line in others] == [
        "  loads[0]",
        "  loads[1]",
        "  requirements[0]",
    ]
    assert "no chain of joints" not in str(caught.value)


def test_field_problems_and_names_that_point_nowhere_come_in_one_run(tmp_path: Path) -> None:
    """A negative play, a force in kg and a joint to a body that does not
    exist: all three at once (pydantic stops at the fields, before the checks
    across entries; the names are looked up in the file's data as it is)."""
    path = tmp_path / "model.yaml"
    path.write_text(
        """bodies:
  - {name: S0, ground: true}
  - {name: S1}
joints:
  - {name: l1, type: spherical, between: [S0, S1], at: [0, 0, 0], clearance: -0.2}
  - {name: l2, type: cylindrical, between: [S0, S2], at: [200, 0, 0], axis: [1, 0, 0],
     length: 40, clearance: 0.2}
loads:
  - {body: S1, at: [300, 0, 0], force: [1, "3 kg", 1]}
"""
    )
    proc = run("solve", str(path))
    assert proc.returncode == 2 and proc.stdout == ""
    assert "Traceback" not in proc.stderr
    first, count, *others = proc.stderr.rstrip("\n").split("\n")
    assert first == (
        f"jointplay: invalid model: {path}: joints[0] 'l1': clearance: expected a value >= 0, "
        "got -0.2"
    )
    assert count == "2 more problem(s) in this file:"
    assert others[0] == (
        "  joints[1] 'l2': between: unknown body 'S2'; bodies are: S0, S1. Did you mean 'S1'?"
    )
    assert others[1].startswith("  loads[0]: force: component y: expected a force, got '3 kg'")


def _problem_lines(data: dict[str, Any]) -> list[str]:
    with pytest.raises(ModelError) as caught:
        jointplay.model_from_dict(data)
    first, *others = str(caught.value).split("\n")
    return [first.removeprefix("<model>: "), *(line.strip() for line in others[1:])]


def test_a_name_that_points_nowhere_reads_the_same_beside_a_field_problem() -> None:
    """Every kind of name that points nowhere, with and without a field's
    problem beside it: the same lines, so that fixing the field changes
    nothing else."""
    data = spherical_shaft(
        points=[{"name": "tip", "body": "S3", "at": [300, 0, 0]}],
        requirements=[{"point": "tap", "max_displacement": 0.1}],
        load_cases={"push": [{"body": "S4", "at": [300, 0, 0], "force": [1, 0, 0]}]},
        deviations=[
            {"name": "setup", "body": "S5", "at": [0, 0, 0], "position": {"diameter": "10 um"}}
        ],
    )
    data["joints"][0]["between"] = ["S0", "S2"]  # type: ignore[index]
    data["joints"][1]["deviation"] = "setpu"  # type: ignore[index]
    data["loads"][0]["body"] = "S6"  # type: ignore[index]
    names = _problem_lines(data)
    assert len(names) == 7 and all("unknown" in line or "no body" in line for line in names)
    data["joints"][1]["clearance"] = -1  # type: ignore[index]
    both = _problem_lines(data)
    assert both[0] == "joints[1] 'l2': clearance: expected a value >= 0, got -1"
    assert sorted(both[1:]) == sorted(names)
    # in file order: the entries' sections as the model lists them
    assert [line.split(":")[0].split("[")[0] for line in both[1:]] == [
        "joints",
        "joints",
        "loads",
        "load_cases.push",
        "points",
        "requirements",
        "deviations",
    ]


def test_names_are_not_looked_up_where_a_name_does_not_read() -> None:
    """A body whose 'name' key is misspelt: the bodies' names are not known,
    so the joints' are not called unknown (they only follow from it)."""
    data = spherical_shaft(bodies=[{"name": "S0", "ground": True}, {"nmae": "S1"}])
    data["joints"][0]["clearance"] = -1  # type: ignore[index]
    text = "\n".join(_problem_lines(data))
    assert "bodies[1]: nmae: unknown key 'nmae'. Did you mean 'name'?" in text
    assert "joints[0] 'l1': clearance" in text
    assert "unknown body" not in text, text


def test_a_duplicate_name_does_not_hide_the_other_problems(tmp_path: Path) -> None:
    data = spherical_shaft(
        points=[
            {"name": "B", "body": "S1", "at": [0, 0, 0]},
            {"name": "B", "body": "S1", "at": [1, 0, 0]},
        ]
    )
    data["joints"][0]["between"] = ["S0", "S9"]  # type: ignore[index]
    with pytest.raises(ModelError) as caught:
        model_from_dict_at(tmp_path, data)
    text = str(caught.value)
    assert "joints[0] 'l1': between: unknown body 'S9'" in text.split("\n")[0]
    assert "  points[1]: duplicate point name 'B'" in text


def test_an_unconnected_body_is_reported_beside_a_joint_between_grounds(tmp_path: Path) -> None:
    """Only a joint to an unknown body makes the connection check moot."""
    data = spherical_shaft(
        bodies=[
            {"name": "S0", "ground": True},
            {"name": "S1"},
            {"name": "S2"},
            {"name": "G", "ground": True},
        ]
    )
    data["joints"].append(  # type: ignore[union-attr]
        {
            "name": "gg",
            "type": "spherical",
            "between": ["S0", "G"],
            "at": [0, 0, 0],
            "clearance": 0.2,
        }
    )
    with pytest.raises(ModelError) as caught:
        model_from_dict_at(tmp_path, data)
    text = str(caught.value)
    assert "joints[2] 'gg': between: both 'S0' and 'G' are ground bodies" in text
    assert "no chain of joints connects 'S2'" in text


@pytest.mark.parametrize("depth", [65, 1001, 5000])
@pytest.mark.parametrize("style", ["flow", "block"])
def test_deep_nesting_is_one_message_whichever_layer_meets_it(
    tmp_path: Path, depth: int, style: str
) -> None:
    # 65 meets our own check on the nodes; past 1000 levels libyaml (PyYAML >= 6.0.4)
    # stops the scanner first: both must read the same.
    nested = "  " + "[" * depth + "]" * depth if style == "flow" else "  " + "- " * depth + "1"
    path = write(tmp_path, f"bodies: []\nextra:\n{nested}\n")
    with pytest.raises(ModelError, match=r"nests lists or mappings more than \d+ deep"):
        jointplay.load(path)


@pytest.mark.parametrize("play", ["1e-310 mm", "1e-200 mm", "1e-13 mm"])
def test_a_play_too_small_to_resolve_is_refused_for_every_joint(tmp_path: Path, play: str) -> None:
    # against the paper's 300 mm shaft: below 1e-12 of it, a play cannot be
    # told from 0 (and plays of 1e-200 mm overflowed the scaled program)
    data = spherical_shaft()
    for joint in data["joints"]:
        joint["clearance"] = play
    with pytest.raises(ModelError) as info:
        jointplay.load(write(tmp_path, data))
    text = str(info.value)
    for entry in ("joints[0] 'l1': clearance", "joints[1] 'l2': clearance"):
        assert entry in text and "too small to tell from 0" in text, text


def test_a_small_real_play_still_solves(tmp_path: Path) -> None:
    data = spherical_shaft()
    data["joints"][0]["clearance"] = "1 nm"  # 3e-9 of the 300 mm shaft: allowed
    result = jointplay.solve(jointplay.load(write(tmp_path, data)))
    assert result.certificate.certified


def test_a_joint_of_unknown_type_still_has_its_other_problems_listed(tmp_path: Path) -> None:
    # pydantic stops at the unknown type; the keys every type shares are still checked
    data = spherical_shaft()
    data["joints"][0].update(type="sphericle", clearance=-0.2, colour="red")
    with pytest.raises(ModelError) as info:
        jointplay.load(write(tmp_path, data))
    first, count, *others = str(info.value).split("\n")
    assert "joints[0] 'l1': unknown joint type 'sphericle'. Did you mean 'spherical'?" in first
    assert count == "2 more problem(s) in this file:"
    assert others[0].startswith("  joints[0] 'l1': clearance: expected a value >= 0")
    assert others[1].startswith("  joints[0] 'l1': colour: unknown key 'colour'")
    del data["joints"][0]["type"]  # no type at all: the same
    with pytest.raises(ModelError) as info:
        jointplay.load(write(tmp_path, data))
    first, count, *others = str(info.value).split("\n")
    assert "joints[0] 'l1': the joint needs a 'type'" in first
    assert count == "2 more problem(s) in this file:"
    # a key that only some types need is not said to be missing: the type decides
    data = spherical_shaft()
    del data["joints"][1]["clearance"]
    data["joints"][1]["type"] = "prismatc"
    with pytest.raises(ModelError) as info:
        jointplay.load(write(tmp_path, data))
    assert str(info.value).count("\n") == 0, str(info.value)
    assert "unknown joint type 'prismatc'. Did you mean 'prismatic'?" in str(info.value)
    # ... while one that every type needs still is
    del data["joints"][1]["between"]
    with pytest.raises(ModelError) as info:
        jointplay.load(write(tmp_path, data))
    assert "'l2': between: expected the names of two bodies, [a, b]" in str(info.value)


def test_the_package_still_reaches_its_modules_and_lists_its_names() -> None:
    import subprocess
    import sys

    code = (
        "import jointplay; "
        "assert jointplay.settings.DEFAULT is not None; "
        "assert callable(jointplay.units.to_base); "
        "assert '__file__' in dir(jointplay) and 'solve' in dir(jointplay); "
        "assert 'numpy' not in __import__('sys').modules"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr


def test_a_play_range_too_small_to_resolve_is_refused_by_its_largest_value(
    tmp_path: Path,
) -> None:
    data = spherical_shaft()
    for joint in data["joints"]:
        joint["clearance"] = {"min": 0, "max": "2e-200 mm"}
    with pytest.raises(ModelError, match=r"clearance: up to 2e-200 mm is less than 1e-12"):
        jointplay.load(write(tmp_path, data))
    data["joints"][0]["clearance"] = {"min": 0, "max": "0.02 mm"}  # reaches real plays: fine
    data["joints"][1]["clearance"] = 0.2
    jointplay.load(write(tmp_path, data))


def test_every_error_pickles_whole() -> None:
    """An error raised in a study's worker process (multiprocessing, Dask)
    crosses to the caller by pickle: every error type comes back with its
    message, fields and exit code (keyword-only fields used to make pickle
    fail, and the user got a traceback instead of the verdict)."""
    import pickle

    from jointplay.errors import (
        ModelError,
        MotionError,
        OptionError,
        SolverError,
        StudyError,
        UnassembledError,
        UnboundedMechanismError,
    )
    from jointplay.studies.kinematics import ReachError

    errors = [
        ModelError("bad", source="m.yaml", entry="joints[0]"),
        OptionError("bad option", source="m.yaml", entry="--range"),
        StudyError("nothing varies", source="m.yaml"),
        UnassembledError("no position", joints=("l1", "l2"), source="m.yaml"),
        UnboundedMechanismError(
            "S1 turns",
            body="S1",
            motion="rotation about x",
            direction={"S1": ((1, 0, 0), (0, 0, 0))},
        ),
        SolverError("not certified"),
        MotionError("dead point", kind="dead point", step=3, value=1.5, joints=("B",), source="m"),
        ReachError("ends", end=2.0, kind="unreachable", step=4, value=2.5, joints=("C",)),
    ]
    for error in errors:
        back = pickle.loads(pickle.dumps(error))
        assert type(back) is type(error)
        assert str(back) == str(error) and vars(back) == vars(error)
        assert back.exit_code == error.exit_code
