"""The package's layers: a module imports only from its own layer or below.

Core words (errors, settings, units, geometry) at the bottom; the model; model
files; numerics; the assembled cone program; results; the solver; studies;
presentation; the command line and the public API at the top. An import from
a higher layer, even lazy or for type checking only, is a circle in the making.
Inside a layer, modules form no import circle either (issue 54): the solver's
records, workspace, algorithms and public entry points stack, and so do the
model's modules and the studies'.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import jointplay

PACKAGE = Path(jointplay.__file__).parent

LAYERS = [
    {"errors", "settings", "units", "geometry", "version", "proven"},
    {"model"},
    {"io"},
    {"numerics"},
    {"assembly", "finite"},
    {"result", "indeterminacy"},
    {"solver"},
    {"studies"},
    {"present"},
    {"cli", "", "__main__"},  # "" is the package's own __init__: the public API
]


def _layer(module: str) -> int:
    top = module.split(".")[0]
    for level, names in enumerate(LAYERS):
        if top in names:
            return level
    raise AssertionError(f"jointplay.{module} belongs to no layer: add it to LAYERS")


def _modules() -> list[tuple[str, Path]]:
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        name = ".".join(p for p in parts if p != "__init__")
        out.append((name, path))
    return out


def _imports(path: Path) -> set[str]:
    """Every jointplay module that ``path`` names in an import, at any depth."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            assert node.level == 0, f"{path.name}: relative import; write jointplay.<layer>..."
            targets = [node.module or ""]
        elif isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        else:
            continue
        for target in targets:
            if target == "jointplay":
                found.add("")
            elif target.startswith("jointplay."):
                found.add(target.removeprefix("jointplay."))
    return found


@pytest.mark.parametrize(("module", "path"), _modules(), ids=lambda v: str(v))
def test_a_module_imports_only_its_layer_or_below(module: str, path: Path) -> None:
    mine = _layer(module)
    above = sorted(t for t in _imports(path) if _layer(t) > mine)
    assert not above, f"jointplay.{module} (layer {mine}) imports from above: {above}"


def test_every_layer_has_its_package() -> None:
    for names in LAYERS:
        for name in names - {""}:
            assert (PACKAGE / name).is_dir() or (PACKAGE / f"{name}.py").is_file(), name


def _names(path: Path, modules: set[str]) -> set[str]:
    """The modules ``path`` imports, at any depth (in functions, under
    ``TYPE_CHECKING``): ``from jointplay.solver import conic`` names the
    module ``solver.conic``; a name that is no module names its package's
    ``__init__`` (``from jointplay import Workspace``: "")."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "jointplay":
            package = (node.module or "").removeprefix("jointplay").removeprefix(".")
            for alias in node.names:
                sub = f"{package}.{alias.name}".lstrip(".")
                found.add(sub if sub in modules else package)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "jointplay":
                    found.add(alias.name.removeprefix("jointplay").removeprefix("."))
    return found


def _circle(within: str) -> list[str] | None:
    """An import circle among the modules of ``within`` (a package; "": all),
    as the modules around it, or None."""
    every = dict(_modules())
    inside = {m for m in every if within == "" or m == within or m.startswith(f"{within}.")}
    edges = {m: sorted(_names(every[m], set(every)) & inside - {m}) for m in inside}
    state: dict[str, str] = {}  # "open" while its imports are followed, then "done"
    path: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = "open"
        path.append(m)
        for n in edges[m]:
            if state.get(n) == "open":
                return [*path[path.index(n) :], n]
            if n not in state and (found := visit(n)) is not None:
                return found
        state[m] = "done"
        path.pop()
        return None

    for m in sorted(inside):
        if m not in state and (found := visit(m)) is not None:
            return found
    return None


@pytest.mark.parametrize("package", ["solver", "model", "studies", ""])
def test_no_import_circle(package: str) -> None:
    circle = _circle(package)
    assert circle is None, "import circle: " + " -> ".join(f"jointplay.{m}" for m in circle or [])


def test_a_lower_solver_layer_loads_no_higher_one() -> None:
    """The solver's ``__init__`` imports none of its modules: importing the
    workspace runs the records and the workspace, not the algorithms."""
    code = "import sys, jointplay.solver.workspace; print(*sorted(sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    loaded = {m for m in out.stdout.split() if m.startswith("jointplay.solver")}
    assert loaded == {"jointplay.solver", "jointplay.solver.records", "jointplay.solver.workspace"}
