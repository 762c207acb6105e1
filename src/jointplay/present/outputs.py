"""Output files named on the command line, checked before any work is done
(light: no plotting library is imported here)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from jointplay.errors import OptionError

#: Figure formats by file suffix.
FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}


def check_output_path(path: Path | str, suffixes: Sequence[str], option: str, fix: str) -> Path:
    """``path`` if it names a file of one of ``suffixes`` in a folder that
    exists, else an ``OptionError`` ('{suffix}' in ``fix`` is the name's own)."""
    out = Path(path)
    if not out.suffix:  # the suffix tells the format: say which ones there are
        raise OptionError(
            f"{option} {out}: the name has no suffix, which tells the format; name the "
            f"file {_either(suffixes)}, e.g. {out}{suffixes[0]}"
        )
    if out.suffix.lower() not in suffixes:
        raise OptionError(f"{option} {out}: " + fix.format(suffix=out.suffix))
    return check_file_path(out, option)


def _either(suffixes: Sequence[str]) -> str:
    """'.png, .svg or .pdf'."""
    return ", ".join(suffixes[:-1]) + " or " + suffixes[-1] if len(suffixes) > 1 else suffixes[0]


def check_file_path(path: Path | str, option: str) -> Path:
    """``path`` if a file can be written there: it is not a folder, and its
    folder exists."""
    out = Path(path)
    if out.is_dir():
        raise OptionError(f"{option} {out}: cannot write it (it is a folder); name a file")
    if not out.parent.is_dir():
        raise OptionError(
            f"{option} {out}: the folder '{out.parent}' does not exist; create it or write "
            "elsewhere"
        )
    return out


def check_figure_path(path: Path | str, option: str = "-o") -> str:
    """The figure's format from its file name ('png', 'svg' or 'pdf')."""
    fix = "cannot write a figure as '{suffix}'; name the file .png, .svg or .pdf"
    return FORMATS[check_output_path(path, tuple(FORMATS), option, fix).suffix.lower()]
