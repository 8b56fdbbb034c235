"""Figures for reports and plots without pyplot: a `Figure` with its own canvas, so importing the
report never switches a notebook's matplotlib backend, and a caller gets figures it can show."""

from __future__ import annotations

from typing import Any


def subplots(*args: Any, figsize: tuple[float, float] | None = None, dpi: float | None = None,
             **kw: Any) -> tuple[Any, Any]:
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi)
    return fig, fig.subplots(*args, **kw)
