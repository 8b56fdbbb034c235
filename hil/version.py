"""The deltahil version: the version of the source that runs (decision B90).

It lives here, in the source, and pyproject.toml reads it from here (`[tool.setuptools.dynamic]`), so an installed
package's metadata, a wheel and a bare checkout report the same string, and a run does not import
`importlib.metadata` (≈ 12 ms of a `hil run` process) to learn it.
"""

__version__ = "0.1.0"


def version() -> str:
    return __version__
