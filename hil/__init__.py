"""The bench: configuration, the cyclic loop and its clocks, traces, checks, reports, the `hil` CLI.
Wires nc, mlc, fieldbus and virtual_bus together; holds no G-code or bus logic of its own.

As a library: `hil.run(program, bench=…)`, `hil.path(program)`, `hil.load_trace(file)` (hil/api.py).
They are imported on first use, so `import hil` stays light.
"""

from typing import Any

__all__ = ["run", "path", "load_trace", "Result"]


def __getattr__(name: str) -> Any:
    if name in __all__:
        from hil import api

        return getattr(api, name)
    raise AttributeError(f"module 'hil' has no attribute {name!r}")
