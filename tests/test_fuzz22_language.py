"""The language's open items of session 20, decided in session 21 (fuzz22): G52 given incrementally and
address letters no NC5 function reads. Each alarm names its code, line and block as `hil check` prints it."""

from __future__ import annotations

from pathlib import Path

import pytest

import hil as hil_api
from nc.alarms import NcAlarm

ROOT = Path(__file__).resolve().parent.parent
MILL = ROOT / "benches" / "mill-3axis.toml"
LATHE = ROOT / "benches" / "lathe-2axis.toml"


def _path(tmp_path: Path, text: str, bench: Path = MILL):
    prog = tmp_path / "p.nc"
    prog.write_text(text)
    return hil_api.path(prog, bench=bench)


def _alarm(tmp_path: Path, text: str, bench: Path = MILL) -> NcAlarm:
    with pytest.raises(NcAlarm) as e:
        _path(tmp_path, text, bench)
    return e.value.alarm


def _ends(moves) -> list[dict[str, float]]:
    return [dict(m.end) for m in moves if hasattr(m, "end")]


def test_g52_in_g91_is_0x0207_at_its_line(tmp_path):
    """N§3.6.2: the local system "is only valid in G90 absolute mode and cannot be used in G91". It was taken
    as absolute, so `G91 G52 X10.` shifted the origin by 10 whatever the local system was before."""
    a = _alarm(tmp_path, "G90 G54 G00 X0. Y0.\nG91 G52 X10.\nG00 X5.\nM30\n")
    assert a.code == 0x0207 and a.line == 2 and "G52" in a.message
    # G91 modal from an earlier block counts the same
    a = _alarm(tmp_path, "G91 G00 X1.\nG52 Y10.\nM30\n")
    assert a.code == 0x0207 and a.line == 2


def test_g52_in_g90_still_shifts_and_a_g90_in_the_same_block_counts(tmp_path):
    moves = _path(tmp_path, "G90 G54 G00 X0. Y0.\nG91\nG90 G52 X40. Y40.\nG00 X20. Y20.\nM30\n")
    assert _ends(moves)[-1]["X"] == pytest.approx(60.0) and _ends(moves)[-1]["Y"] == pytest.approx(60.0)
    # a G52 without axis words in G91 sets nothing and is not refused
    assert _path(tmp_path, "G91 G52\nM30\n") is not None


def test_g52_with_the_lathe_incremental_u_is_0x0207(tmp_path):
    """L§G52: "valid only when it is set with absolute values": `G52 U10.` (lathe A-type incremental X)."""
    a = _alarm(tmp_path, "G00 X20. Z5.\nG52 U10.\nM30\n", LATHE)
    assert a.code == 0x0207 and a.line == 2
    moves = _path(tmp_path, "G00 X20. Z5.\nG52 X10. Z20.\nG00 X20. Z20.\nM30\n", LATHE)
    assert _ends(moves)[-1]["Z"] == pytest.approx(40.0)


@pytest.mark.parametrize("word", ["E5", "V5.", "U1.", "W-2."])
def test_a_letter_no_mill_function_reads_is_0x0201(tmp_path, word):
    """`G01 X10. E5 F100.` ran as `G01 X10. F100.`: E is read by no NC5 function, U/V/W only as a lathe's
    incremental axes; App. A 0x0201 "Undefined operator" (its example: `G01O100.`)."""
    a = _alarm(tmp_path, f"G00 X0. Y0.\nG01 X10. {word} F100.\nM30\n")
    assert a.code == 0x0201 and a.line == 2 and word in a.block


def test_macro_call_arguments_and_lathe_incrementals_keep_their_letters(tmp_path):
    (tmp_path / "O9010.nc").write_text("O9010\n#100=#5+#22\nM99\n")
    prog = tmp_path / "p.nc"
    prog.write_text("G65 P9010 E5. V2.\nG00 X#100\nM30\n")
    moves = hil_api.path(prog, bench=MILL)
    assert _ends(moves)[-1]["X"] == pytest.approx(7.0)
    moves = _path(tmp_path, "G00 X20. Z5.\nG01 U-4. W-3. F0.2\nM30\n", LATHE)
    assert _ends(moves)[-1]["X"] == pytest.approx(8.0) and _ends(moves)[-1]["Z"] == pytest.approx(2.0)


def test_e_on_the_lathe_is_0x0201_and_v_without_a_y_axis_too(tmp_path):
    for word in ("E1.", "V1."):
        a = _alarm(tmp_path, f"G00 X20. Z5.\nG01 Z0. {word} F0.2\nM30\n", LATHE)
        assert a.code == 0x0201 and a.line == 2
