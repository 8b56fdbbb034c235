"""A lathe cycle's moves handed on as one MoveList event (`hil path`'s bulk mode, issue 16) are the
same moves, in the same order, as block by block: points, feeds, tags, and a ,C corner held before
the cycle joined to its first move."""

from __future__ import annotations

from pathlib import Path

from nc.interp import Interpreter
from nc.moves import Move, MoveBatch, MoveList
from nc.profiles import make_profile
from nc.store import ProgramStore

PART = """O1002
G10 L10 P1 R0.8 Q3
G21 G99
T0101
G96 S180 M03
G00 X45. Z5.
G71 U1.5 R0.5
G71 P10 Q20 U0.4 W0.1 F0.25
N10 G00 X18.
G01 Z0. F0.12
X24. Z-3.
Z-25.
X28.
X32. Z-35.
G02 X38. Z-38. R3.
G01 Z-50.
N20 X44.
G00 X60. Z50.
G42 G00 X45. Z2.
G70 P10 Q20
G40 G00 X60. Z50.
G00 X28. Z5.
G76 P011060 Q50 R0.05
G76 X21.4 Z-22. P1300 Q400 F2.
G01 X50. ,C1.
G00 X60. Z50.
M30
"""


def _moves(tmp_path: Path, text: str, bulk: bool) -> tuple[list[tuple], int]:
    path = tmp_path / "part.nc"
    path.write_text(text)
    store = ProgramStore()
    ip = Interpreter(make_profile("nc5-lathe-a", None, {}, ()), store=store)
    ip.bulk = bulk
    out, lists = [], 0
    for ev in ip.run(store.load_main(str(path))):
        if type(ev) is MoveList:
            lists += 1
        items = ev.moves() if type(ev) in (MoveList, MoveBatch) else [ev] if isinstance(ev, Move) else []
        out += [(m.kind, m.line, m.start, m.end, m.work, m.center, m.feed, m.tags, m.comp) for m in items]
    return out, lists


def test_cycle_moves_as_one_event_are_the_moves_block_by_block(tmp_path: Path) -> None:
    one_by_one, none = _moves(tmp_path, PART, bulk=False)
    listed, lists = _moves(tmp_path, PART, bulk=True)
    assert none == 0 and lists == 2  # G71 roughing and G76; the compensated G70 goes move by move
    assert listed == one_by_one
    assert any("G71" in m[7] for m in listed) and any(m[8] == "G42" for m in listed)


def test_corner_held_before_a_cycle_joins_its_first_move(tmp_path: Path) -> None:
    text = PART.replace("G00 X45. Z5.\nG71 U1.5", "G00 X60. Z50.\nG01 X45. Z5. ,C0.05 F0.2\nG71 U1.5")
    one_by_one, _ = _moves(tmp_path, text, bulk=False)
    listed, _ = _moves(tmp_path, text, bulk=True)
    assert listed == one_by_one
