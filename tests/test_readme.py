"""The README's Python example runs as written."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from conftest import ROOT


def test_readme_python_example_runs() -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "the README has a Python example"
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        namespace: dict[str, object] = {}
        exec(compile(blocks[0], "README.md", "exec"), namespace)
    finally:
        os.chdir(cwd)
    batch = namespace["batch"]
    assert len(batch) == 2  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("alt", "figure", "model", "out"),
    [
        (
            "The paper's 6.1.6.1 shaft drawn by jointplay",
            "paper-6.1.6.1.png",
            "examples/paper/6.1.6.1.yaml",
            "shaft.png",
        ),
        (
            "A lathe slide of four bodies drawn by jointplay",
            "lathe-slide.png",
            "examples/gallery/lathe_slide.yaml",
            "slide.png",
        ),
    ],
    ids=["paper", "multi-body"],
)
def test_readme_figure_is_drawn_by_jointplay(
    alt: str, figure: str, model: str, out: str, tmp_path: Path
) -> None:
    """Each README figure exists and is what its command draws (same size, within
    font metrics; matplotlib's name in the PNG's metadata)."""
    from PIL import Image
    from typer.testing import CliRunner

    from jointplay.cli import app

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert f"![{alt}](docs/figures/{figure})" in text
    assert f"jointplay plot {model} -o {out}" in text
    committed = Image.open(ROOT / "docs" / "figures" / figure)
    assert "Matplotlib" in committed.info.get("Software", "")
    drawn_path = tmp_path / out
    run = CliRunner().invoke(app, ["plot", str(ROOT / model), "-o", str(drawn_path)])
    assert run.exit_code == 0, run.output
    drawn = Image.open(drawn_path)
    # the same figure; a few pixels of slack for font metrics of other versions
    assert abs(drawn.width - committed.width) <= 0.02 * committed.width
    assert abs(drawn.height - committed.height) <= 0.02 * committed.height


def test_readme_pictures_example_runs(tmp_path: Path) -> None:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    pictures = next(b for b in blocks if "mechanism_figure" in b)
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        exec(compile(pictures, "README.md", "exec"), {})
    finally:
        os.chdir(cwd)
    assert (tmp_path / "shaft.svg").read_text().count("<svg") == 1
    assert (tmp_path / "joints.png").read_bytes().startswith(b"\x89PNG")
    assert "jp-view-0" in (tmp_path / "shaft.html").read_text(encoding="utf-8")


#: A printed output in the README follows a line `<!-- output of: jointplay ... -->`.
OUTPUT = re.compile(r"<!-- output of: (jointplay [^>]*?) -->\n```[a-z]*\n(.*?)```", re.S)


def _words(line: str) -> list[str]:
    return line.split()


@pytest.mark.parametrize(
    ("command", "block"),
    OUTPUT.findall((ROOT / "README.md").read_text(encoding="utf-8")),
    ids=lambda v: v if v.startswith("jointplay") else "",
)
def test_readme_outputs_are_what_jointplay_prints(command: str, block: str) -> None:
    """Every line the README shows of a command's output is a line of what
    the command prints now, in the same order (spacing aside; a line '...'
    stands for lines left out)."""
    import shlex
    import subprocess
    import sys

    args = shlex.split(command)[1:]
    proc = subprocess.run(
        [sys.executable, "-m", "jointplay.cli", *args],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert proc.returncode in (0, 4), proc.stderr
    printed = [_words(line) for line in proc.stdout.splitlines()]
    at = 0
    for line in block.splitlines():
        if line.strip() in ("", "...", "…"):
            continue
        wanted = _words(line)
        try:
            at = printed.index(wanted, at) + 1
        except ValueError:
            pytest.fail(f"README line not printed (in this order) by '{command}': {line!r}")


def test_the_readme_shows_outputs() -> None:
    assert len(OUTPUT.findall((ROOT / "README.md").read_text(encoding="utf-8"))) >= 4


def test_the_readme_says_which_example_gives_which_study() -> None:
    """The README's table of examples and studies is what each model allows:
    an envelope needs a point, Monte Carlo something that varies, tolerances
    a requirement too."""
    import jointplay
    from jointplay.assembly import assemble
    from jointplay.studies.variation import deviation_map, load_map, play_map

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `([a-z]+/[\w*.]+)` \| (\w+) \| (\w+) \| (\w+) \| (\w+) \|$", text, re.M)
    listed = set()
    for pattern, *cells in rows:
        for path in sorted((ROOT / "examples").glob(pattern)):
            listed.add(path)
            model = jointplay.load(path)
            asm = assemble(model)
            varies = bool(
                play_map(asm, str(path)).variables
                or deviation_map(asm).variables
                or any(load_map(asm, c).variables for c in model.case_names or (None,))
            )
            points = bool(model.points)
            expected = [
                True,
                points,
                points and varies,
                points and varies and bool(model.requirements),
            ]
            assert [c == "yes" for c in cells] == expected, path.name
    assert listed == set((ROOT / "examples").glob("*/*.yaml"))
