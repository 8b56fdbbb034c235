"""Move.replaced (issue 16) copies every field as dataclasses.replace does: compensation rewrites the
moves of a compensated contour with it, so a field it forgot would vanish from `hil path`."""

from __future__ import annotations

import dataclasses

from nc.moves import Move


def _distinct_move() -> Move:
    m = Move("arc", 7, "G2 X1", {"X": 1.0}, {"X": 2.0}, {"X": 4.0})
    for i, f in enumerate(dataclasses.fields(Move)):  # a value of its own in every field
        value = getattr(m, f.name)
        if isinstance(value, bool):
            value = not value
        elif isinstance(value, (int, float)) and f.name != "line":
            value = value + i + 0.5
        elif value is None or f.name in ("program", "comp", "dir"):
            value = f"{f.name}-{i}"
        elif isinstance(value, tuple):
            value = (f.name,)
        setattr(m, f.name, value)
    return m


def test_replaced_keeps_every_field_and_changes_the_named_ones() -> None:
    m = _distinct_move()
    assert m.replaced() == dataclasses.replace(m)
    changed = m.replaced(start={"X": 9.0}, tags=("comp",))
    assert changed == dataclasses.replace(m, start={"X": 9.0}, tags=("comp",))
    assert changed.start == {"X": 9.0} and m.start == {"X": 1.0}
