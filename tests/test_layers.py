"""The package's layers: a module imports only from its own layer or below.

Core words (errors, settings, units, geometry) at the bottom; the model; model
files; numerics; the assembled cone program; results; the solver; studies;
presentation; the command line and the public API at the top. An import from
a higher layer, even lazy or for type checking only, is a circle in the making.
"""

from __future__ import annotations

import ast
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
