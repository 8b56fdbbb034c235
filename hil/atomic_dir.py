"""Write a directory of outputs all or nothing: build every file in a hidden temporary folder beside
the target, then move them in (os.replace, one file at a time, in the order given), so a failed or
interrupted writer leaves an earlier report untouched and no temporary folder behind. The target's
other files are never touched: `--out .` must not wipe the current directory (decisions inputs.md I6)."""
from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_dir(target: str | Path, last: str = "index.html") -> Iterator[Path]:
    """Yields the temporary folder; on a clean exit its files replace the target's, `last` last."""
    target = Path(target)
    target.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.resolve().name or 'out'}.", suffix=".tmp", dir=target))
    try:
        yield tmp
        for p in sorted(tmp.iterdir(), key=lambda p: p.name == last):  # the page that links them goes last
            os.replace(p, target / p.name)
    finally:  # BaseException too: Ctrl-C mid-report leaves nothing behind
        shutil.rmtree(tmp, ignore_errors=True)
