"""The package version (one place: the API, reports and files read it)."""

__version__ = "0.1.0"
