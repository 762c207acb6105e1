"""``python -m jointplay``: the command line, as ``jointplay``."""

from jointplay.cli import main

main()
