"""The docs say what the code does now: no lab-notebook history, no broken links.

History (what was tried, when, at which commit) lives in the git log. The
documents below carry no "session", no commit hash and no "not adopted",
and every relative link in README.md and docs/*.md points to a file.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from conftest import ROOT


def _documents() -> list[Path]:
    found = [
        ROOT / "README.md",
        ROOT / "benchmarks" / "README.md",
        *sorted((ROOT / "docs").rglob("*.md")),
        *sorted((ROOT / "tests" / "property_cases").rglob("README.md")),
    ]
    return [path for path in found if path.is_file()]


#: A commit hash: 7 to 40 hex digits with both a digit and a letter, as a
#: whole word (not the mantissa of a number such as 8.89297292e-02).
HASH = re.compile(
    r"(?<![\w.])(?=[0-9a-f]*[0-9])(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}(?![\w.])(?![-+]\d)",
    re.IGNORECASE,
)
HISTORY = re.compile(r"\bsessions?\b|\bnot adopted\b", re.IGNORECASE)
#: ``[text](target)``, the target up to a space, ``)`` or ``#``.
LINK = re.compile(r"\]\(([^)\s#]*)(#[^)\s]*)?\)")


def _name(path: Path) -> str:
    return str(path.relative_to(ROOT))


@pytest.mark.parametrize("path", _documents(), ids=_name)
def test_no_history_in_the_docs(path: Path) -> None:
    found = []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        found += [f"{number}: {m.group(0)!r}" for m in HISTORY.finditer(line)]
        found += [f"{number}: {m.group(0)!r} (a commit hash?)" for m in HASH.finditer(line)]
    assert found == [], f"{_name(path)}: history belongs in the git log"


def test_the_hash_pattern_tells_hashes_from_numbers() -> None:
    assert HASH.search("at `34a15a1` (clean clone)")
    assert HASH.search("commit 849ad88: a tie")
    assert not HASH.search("u1 = 8.89297292e-02 mm")
    assert not HASH.search("1,000,000 samples; 1234567 rows")
    assert not HASH.search("deadbeefs and abcdefg")


@pytest.mark.parametrize(
    "path", [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))], ids=_name
)
def test_relative_links_point_to_files(path: Path) -> None:
    missing = []
    for target, _anchor in LINK.findall(path.read_text(encoding="utf-8")):
        if not target or re.match(r"[a-z][a-z0-9+.-]*:", target, re.IGNORECASE):
            continue  # an anchor in the same page, or a URL
        if not (path.parent / target).exists():
            missing.append(target)
    assert missing == [], f"{_name(path)}: links to files that do not exist"
