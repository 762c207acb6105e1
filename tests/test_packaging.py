"""The version ranges we claim are the ones CI tests at both ends."""

from __future__ import annotations

import re
import tomllib

from conftest import ROOT


def test_the_lowest_versions_ci_tests_are_the_pins_lower_bounds() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    lower = {}
    for requirement in project["dependencies"]:
        found = re.fullmatch(r"([A-Za-z0-9_.\-\[\]]+)>=([\d.]+),<[\d.]+", requirement)
        assert found, f"{requirement!r}: every dependency has a lower and an upper bound"
        lower[found[1].lower()] = found[2]
    pinned = {}
    for line in (ROOT / ".ci" / "lowest.txt").read_text(encoding="utf-8").splitlines():
        if line.strip() and not line.startswith("#"):
            name, version = line.split("==")
            pinned[name.lower()] = version
    assert set(pinned) == {"numpy", "scipy", "clarabel", "threadpoolctl", "salib"}
    for name, version in pinned.items():
        assert lower[name] == version or lower[name] + ".0" == version, name
