"""python-can, imported without its MF4 log format's asammdf (decisions B50).

`import can` imports `can.io`, whose MF4 reader/writer tries `import asammdf` at once; where asammdf is installed
(the `mdf` extra, for `hil trace --out run.mf4`) that pulls in polars and numexpr: ≈ 0.84 s of imports in every
CANopen `hil run` / `hil sim`, for a log format the bus never writes (captures are .asc/.blf/.log). python-can is
imported here with asammdf hidden, so its MF4 support reads as not installed; asammdf itself stays importable
(hil/trace_summary.py imports it for MDF4 traces)."""

from __future__ import annotations

import sys
from types import ModuleType


def load() -> ModuleType:
    """The `can` module, imported without asammdf the first time (a no-op once python-can is loaded)."""
    loaded = sys.modules.get("can")
    if loaded is not None:
        return loaded
    hide = "asammdf" not in sys.modules
    if hide:
        sys.modules["asammdf"] = None  # type: ignore[assignment]  # can.io.mf4's try-import fails at once
    try:
        import can
    finally:
        if hide and sys.modules.get("asammdf", 0) is None:
            del sys.modules["asammdf"]
    return can
