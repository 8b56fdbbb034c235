"""The installed deltahil version (package metadata; "unknown" when run from a bare checkout)."""

from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _version


def version() -> str:
    try:
        return _version("deltahil")
    except PackageNotFoundError:
        return "unknown"
