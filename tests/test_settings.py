"""Every tolerance of the solve is named once, in ``jointplay.settings``."""

from __future__ import annotations

import ast
from dataclasses import fields
from pathlib import Path

import jointplay
from conftest import PAPER
from jointplay.settings import DEFAULT, SolverSettings

SRC = Path(jointplay.__file__).parent
#: The numeric core: the algorithms from the assembled model to a certified answer.
CORE = sorted(
    [SRC / "assembly.py", SRC / "result.py", *SRC.glob("numerics/*.py"), *SRC.glob("solver/*.py")]
)


def _float_literals(path: Path) -> list[tuple[int, float]]:
    tree = ast.parse(path.read_text())
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and isinstance(node.value, float)
        and id(node) not in docstrings
        and node.value not in (0.0, 1.0)
    ]


def test_no_tolerance_literal_inside_the_algorithms() -> None:
    """0 and 1 are not tolerances; any other float in the core is, and
    belongs in ``SolverSettings`` with its reason."""
    assert len(CORE) > 10
    found = {
        f"{path.relative_to(SRC)}:{line}": value
        for path in CORE
        for line, value in _float_literals(path)
    }
    assert found == {}


def test_one_value_per_concept() -> None:
    """The solver and the batch once called a force "positive" above 1e-8 and
    1e-9 of the largest; the certificate's and the result's tolerances were
    written out twice. Now each is one field, and a result reads the
    settings it was solved with: a finer balance is checked as such."""
    model = jointplay.load(PAPER / "6.1.6.1.yaml")
    loose = jointplay.solve(model)
    fine = jointplay.solve(model, SolverSettings(equilibrium_tolerance=1e-9))
    assert loose.equilibrium_tolerance == DEFAULT.equilibrium_tolerance
    assert fine.equilibrium_tolerance == 1e-9
    names = [f.name for f in fields(SolverSettings)]
    assert len(names) == len(set(names))
    assert jointplay.SolverSettings is SolverSettings
