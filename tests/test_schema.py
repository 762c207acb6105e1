"""``jointplay schema``: the model file's JSON Schema (issue 19).

Every bundled example validates against it, and files that the model
refuses for their shape (an unknown key, a missing field, a wrong type, a
text that is not a quantity) are refused by the schema too, so an editor
flags them as they are typed.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import jsonschema
import pytest
import yaml

import jointplay
from conftest import spherical_shaft
from test_cli import run

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").rglob("*.yaml"))


@pytest.fixture(scope="module")
def validator() -> jsonschema.protocols.Validator:
    proc = run("schema")
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    schema = json.loads(proc.stdout)
    cls = jsonschema.validators.validator_for(schema)
    cls.check_schema(schema)  # a well-formed schema of the dialect it names
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    return cls(schema)


def test_the_examples_are_enough_to_test_with() -> None:
    assert len(EXAMPLES) >= 15


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_every_bundled_example_validates(
    path: Path, validator: jsonschema.protocols.Validator
) -> None:
    data = yaml.safe_load(path.read_text())
    errors = [e.message for e in validator.iter_errors(data)]
    assert errors == []
    jointplay.load(path)  # and the model reads it


def _broken(change: dict[str, Any]) -> dict[str, Any]:
    data = spherical_shaft()
    data.update(change)
    return data


BROKEN = {
    "unknown top-level key": _broken({"gravitation": [0, 0, -9810]}),
    "unknown joint key": _broken(
        {"joints": [{**spherical_shaft()["joints"][0], "clerance": 0.2}]}  # type: ignore[index]
    ),
    "unknown joint type": _broken(
        {"joints": [{**spherical_shaft()["joints"][0], "type": "ball"}]}  # type: ignore[index]
    ),
    "missing bodies": {k: v for k, v in spherical_shaft().items() if k != "bodies"},
    "a length as a list": _broken(
        {"joints": [{**spherical_shaft()["joints"][0], "clearance": [0.2]}]}  # type: ignore[index]
    ),
    "a text that is not a quantity": _broken(
        {"loads": [{"body": "S1", "at": [300, 0, 0], "force": ["one", 1, 1]}]}
    ),
    "a point of two components": _broken(
        {"loads": [{"body": "S1", "at": [300, 0], "force": [1, 1, 1]}]}
    ),
    "schema version 2": _broken({"schema": 2}),
    "a fit without its diameter": _broken(
        {"joints": [{**spherical_shaft()["joints"][0], "clearance": {"fit": "H7/g6"}}]}  # type: ignore[index]
    ),
}


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_the_schema_refuses_what_the_model_refuses(
    name: str, validator: jsonschema.protocols.Validator
) -> None:
    data = BROKEN[name]
    assert list(validator.iter_errors(data)), f"the schema let '{name}' through"
    with pytest.raises(jointplay.ModelError):
        jointplay.model_from_dict(data)


def test_quantities_with_units_pass_the_schema(validator: jsonschema.protocols.Validator) -> None:
    data = _broken(
        {
            "loads": [
                {
                    "body": "S1",
                    "at": ["300 mm", 0, "0.0 m"],
                    "force": ["1 N", {"min": 0, "max": 2}, 1],
                }
            ],
            "gravity": [0, 0, "-9.81 m/s^2"],
        }
    )
    assert [e.message for e in validator.iter_errors(data)] == []
    jointplay.model_from_dict(data)
