from __future__ import annotations

from pathlib import Path

import pytest

import jointplay

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "examples" / "paper"

#: Tight tolerances of the project: positions in mm, rotations in rad.
MM = 1e-6
RAD = 1e-8


def solve_file(name: str) -> jointplay.Result:
    result = jointplay.solve(jointplay.load(PAPER / name))
    result.check()
    return result


def spherical_shaft(**over: object) -> dict[str, object]:
    """The paper's 6.1.6.1 shaft as a dict, for variations in tests."""
    data: dict[str, object] = {
        "bodies": [{"name": "S0", "ground": True}, {"name": "S1"}],
        "joints": [
            {
                "name": "l1",
                "type": "spherical",
                "between": ["S0", "S1"],
                "at": [0, 0, 0],
                "clearance": 0.2,
            },
            {
                "name": "l2",
                "type": "cylindrical",
                "between": ["S0", "S1"],
                "at": [200, 0, 0],
                "axis": [1, 0, 0],
                "length": 40,
                "clearance": 0.2,
            },
        ],
        "loads": [{"body": "S1", "at": [300, 0, 0], "force": [1, 1, 1]}],
    }
    data.update(over)
    return data


@pytest.fixture
def shaft_dict() -> dict[str, object]:
    return spherical_shaft()
