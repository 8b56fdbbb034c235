"""Issue 15, G-code program input: ASCII digits only, strict JSON, no internal error from a program,
the endless-loop guard's own code, program roots (docs/decisions/program-input.md P1-P6)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hil.cli import main


def _strict(line: str) -> dict:
    def refuse(name: str) -> None:
        raise AssertionError(f"non-JSON constant {name} in {line[:120]!r}")

    return json.loads(line, parse_constant=refuse)


def path_json(capsys, program: Path, *args: str) -> tuple[int, list[dict]]:
    """`hil path PROGRAM --json` in-process: exit code and every output object (strict JSON)."""
    capsys.readouterr()
    code = main(["path", str(program), "--json", "--profile", "nc5-mill", *args])
    out = capsys.readouterr().out
    return code, [_strict(s) for s in out.splitlines() if s.strip()]


def alarm_of(objs: list[dict]) -> dict:
    alarms = [o for o in objs if o["kind"] == "alarm"]
    assert len(alarms) == 1, objs
    return alarms[0]


# ---- P1: ASCII digits only --------------------------------------------------------------------------
@pytest.mark.parametrize("block, char", [
    ("G01 X١٠. F100", "ARABIC-INDIC DIGIT ONE"),  # X10 in Arabic-Indic digits
    ("G01 X１０. F100", "FULLWIDTH DIGIT ONE"),
    ("G01 X1٠. F100", "ARABIC-INDIC DIGIT ZERO"),  # mixed: one foreign digit is enough
    ("#1=１２", "FULLWIDTH DIGIT ONE"),  # macro expression
    ("#١=12", "ARABIC-INDIC DIGIT ONE"),  # variable number
    ("N١٠ G01 X1. F100", "ARABIC-INDIC DIGIT ONE"),  # sequence number
    ("G04 X" + "١" * 40 + ".", "ARABIC-INDIC DIGIT ONE"),  # the dwell that was read as "infinite"
    ("G01 X२. F100", "DEVANAGARI DIGIT TWO"),
])
def test_non_ascii_digit_is_a_format_alarm_with_line_and_block(capsys, tmp_path, block, char) -> None:
    prog = tmp_path / "u.nc"
    prog.write_text(f"G90 G00 X0 Y0\n{block}\nM30\n", encoding="utf-8")
    code, objs = path_json(capsys, prog)
    a = alarm_of(objs)
    assert code == 1
    assert (a["code"], a["line"], a["block"], a["program"]) == ("0x020A", 2, block if len(block) <= 200 else a["block"], "u.nc")
    assert char in a["message"]
    assert [o["kind"] for o in objs] == ["alarm"]  # the program is refused before anything moves


def test_o_line_in_foreign_digits_is_an_alarm_not_program_12(capsys, tmp_path) -> None:
    prog = tmp_path / "o.nc"
    prog.write_text("O１２\nG01 X1. F100\n", encoding="utf-8")
    code, objs = path_json(capsys, prog)
    a = alarm_of(objs)
    assert (code, a["code"], a["line"], a["block"]) == (1, "0x020A", 1, "O１２")


def test_foreign_digits_in_a_comment_are_fine(capsys, tmp_path) -> None:
    prog = tmp_path / "c.nc"
    prog.write_text("(قطعة ١٢ / 部品１２)\nG01 X12. F100 ; ١٢\nM30\n", encoding="utf-8")
    code, objs = path_json(capsys, prog)
    assert code == 0
    assert [o["work"]["X"] for o in objs if o["kind"] == "line"] == [12.0]


# ---- P2: strict JSON ----------------------------------------------------------------------------------
def test_strict_json_turns_non_finite_into_null_and_never_prints_nan() -> None:
    from hil.strict_json import dumps
    text = dumps({"a": float("inf"), "b": [float("nan"), 1.5], "c": {"d": -float("inf")}})
    assert json.loads(text) == {"a": None, "b": [None, 1.5], "c": {"d": None}}
    assert "Infinity" not in text and "NaN" not in text


def test_vars_with_a_huge_value_print_as_strict_json(capsys, tmp_path) -> None:
    prog = tmp_path / "v.nc"
    prog.write_text("#1=9999999.*9999999.\n#2=#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1*#1\n")
    code, objs = path_json(capsys, prog, "--vars", "1-2")  # 1e307 is finite: printed as a JSON number
    assert code == 0 and objs[-1]["values"]["2"] > 1e307
    prog.write_text(prog.read_text() + "#3=#2*#2\n")
    code, objs = path_json(capsys, prog, "--vars", "1-3")
    a = alarm_of(objs)  # an assignment of ±inf is an arithmetic alarm where it is written
    assert (code, a["code"], a["line"]) == (1, "0x0257", 3)


# ---- P3: no internal error from a program ---------------------------------------------------------------
def test_o_number_with_5000_digits_is_0x0223_with_file_and_line(capsys, tmp_path) -> None:
    prog = tmp_path / "big.nc"
    prog.write_text("G00 X0\nO" + "7" * 5000 + "\nG01 X1. F100\n")
    code, objs = path_json(capsys, prog)
    a = alarm_of(objs)
    assert (code, a["code"], a["line"], a["program"]) == (1, "0x0223", 2, "big.nc")
    assert "5000 digits" in a["message"] and len(a["block"]) < 300  # named, not echoed


@pytest.mark.parametrize("call", ["M98 P#3", "G65 P#3", "M98 P#4"])
def test_m98_with_a_program_number_too_long_for_a_file_name(capsys, tmp_path, call) -> None:
    prog = tmp_path / "m.nc"
    prog.write_text("#1=10000000000.\n#2=#1*#1*#1*#1*#1*#1*#1*#1*#1*#1\n#3=#2*#2*#2\n"
                    f"#4=-7\n{call}\nM30\n")
    code, objs = path_json(capsys, prog)
    a = alarm_of(objs)
    assert code == 1 and a["code"] != "0x0000"
    assert (a["line"], a["block"], a["program"]) == (5, call, "m.nc")


def test_parse_error_in_a_subprogram_names_its_file_line_and_the_caller(capsys, tmp_path) -> None:
    (tmp_path / "O0007.nc").write_text("G01 X2. F100\nG01 X2 Y3 Q\nM99\n")
    prog = tmp_path / "main.nc"
    prog.write_text("G00 X0\nG00 Y0\nM98 P7\nM30\n")
    code, objs = path_json(capsys, prog)
    a = alarm_of(objs)
    assert (code, a["code"], a["line"], a["block"]) == (1, "0x0222", 2, "G01 X2 Y3 Q")
    assert a["program"] == str(tmp_path / "O0007.nc")
    assert "called from line 3 of main.nc: M98 P7" in a["message"]


def test_binary_subprogram_is_refused_without_echo(capsys, tmp_path) -> None:
    (tmp_path / "O0009").write_bytes(b"\x7fELF\x00\x01secret-bytes\n")
    prog = tmp_path / "main.nc"
    prog.write_text("M98 P9\n")
    code, objs = path_json(capsys, prog)
    a = alarm_of(objs)
    assert (code, a["code"], a["line"], a["block"]) == (1, "0x0263", 1, "M98 P9")
    assert "not a program" in a["message"] and "secret" not in json.dumps(objs)


# ---- P5: endless-loop guard ------------------------------------------------------------------------
def test_endless_loop_guard_has_its_own_code(capsys, tmp_path) -> None:
    from nc.alarms import alarm_name
    prog = tmp_path / "loop.nc"
    prog.write_text("#1=1\nWHILE[#1GT0]DO1\n#2=#2+1\nEND1\nM30\n")
    code, objs = path_json(capsys, prog, "--param", "max blocks=5000")
    a = alarm_of(objs)
    assert (code, a["code"], a["program"]) == (1, "0xDE01", "loop.nc")
    assert a["line"] in (2, 3, 4) and "5000 blocks" in a["message"]  # a line of the loop
    assert "Endless-loop" in alarm_name(0xDE01)


def test_a_straight_program_longer_than_max_blocks_runs_to_its_end(capsys, tmp_path) -> None:
    """The guard counts what loops add beyond the program's own blocks: a CAM file of more lines than
    'max blocks' (1M lines against the default 1,000,000) runs every line once, and a loop in it is
    still caught (decision P5)."""
    prog = tmp_path / "cam.nc"
    prog.write_text("G21 G90\n" + "".join(f"G1 X{i * 0.01:.3f} Y0 F1000\n" for i in range(300)) + "M30\n")
    code, objs = path_json(capsys, prog, "--profile", "nc5-mill", "--param", "max blocks=100")
    assert code == 0 and not [o for o in objs if o["kind"] == "alarm"]
    assert sum(o["kind"] == "line" for o in objs) == 300
    loop = tmp_path / "loop.nc"
    loop.write_text("".join(f"G1 X{i * 0.01:.3f} F1000\n" for i in range(300)) + "#1=1\nWHILE[#1GT0]DO1\n#2=#2+1\nEND1\nM30\n")
    code, objs = path_json(capsys, loop, "--profile", "nc5-mill", "--param", "max blocks=100")
    assert code == 1 and alarm_of(objs)["code"] == "0xDE01"


# ---- P4: program roots --------------------------------------------------------------------------------
def test_symlink_out_of_the_program_folders_is_refused_and_not_echoed(capsys, tmp_path) -> None:
    secret = tmp_path / "outside" / "secret.txt"
    secret.parent.mkdir()
    secret.write_text("root:x:0:0:TOPSECRET\n")
    progs = tmp_path / "progs"
    progs.mkdir()
    os.symlink(secret, progs / "O0008")
    (progs / "main.nc").write_text("G00 X0\nM98 P8\nM30\n")
    code, objs = path_json(capsys, progs / "main.nc")
    a = alarm_of(objs)
    assert (code, a["code"], a["line"], a["block"]) == (1, "0x0263", 2, "M98 P8")
    assert "outside the program folders" in a["message"]
    assert "TOPSECRET" not in json.dumps(objs) and "root:x" not in json.dumps(objs)


def linked_program(tmp_path, folder: str, n: int, link_to) -> Path:
    """O000n in tmp_path/folder, reached from tmp_path/progs through a symlink; returns main.nc."""
    (tmp_path / folder).mkdir()
    (tmp_path / folder / f"O000{n}.nc").write_text(f"G01 X{n}. F100\nM99\n")
    progs = tmp_path / "progs"
    progs.mkdir()
    os.symlink(link_to, progs / f"O000{n}.nc")
    (progs / "main.nc").write_text(f"M98 P{n}\nM30\n")
    return progs / "main.nc"


def test_symlink_to_another_program_root_is_allowed(capsys, tmp_path) -> None:
    main = linked_program(tmp_path, "lib", 5, tmp_path / "lib" / "O0005.nc")
    code, objs = path_json(capsys, main, "--lib", str(tmp_path / "lib"))
    assert code == 0 and [o["work"]["X"] for o in objs if o["kind"] == "line"] == [5.0]


def test_dotdot_folder_symlink_out_of_the_root_is_refused(capsys, tmp_path) -> None:
    main = linked_program(tmp_path, "other", 6, "../other/O0006.nc")
    code, objs = path_json(capsys, main)
    assert (code, alarm_of(objs)["code"]) == (1, "0x0263")


# ---- bounded fuzz of `hil path`'s code path ---------------------------------------------------------------
_DIGITS = "0123456789١٢٣٠۴５０२"
_ATOMS = st.sampled_from(["G01", "G00", "G04", "X", "Y", "Z", "F", "P", "M98", "O", "N", "#1=", "#[", "]",
                          "WHILE[#1LT3]DO1", "END1", "IF[", "GOTO", ".", "-", "E", " ", "\n", "(", ")",
                          "*", "/", ";", "M99", "M30", "G65", "L", "1e308", "9" * 15, "\u3000", "\x00"])
_PROGRAM = st.lists(st.one_of(_ATOMS, st.text(alphabet=_DIGITS, min_size=1, max_size=30),
                              st.text(max_size=6)), max_size=40).map("".join)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=_PROGRAM)
def test_fuzzed_programs_give_no_internal_error_and_strict_json(capsys, tmp_path, text) -> None:
    prog = tmp_path / "fz.nc"
    prog.write_text(text, encoding="utf-8", errors="surrogatepass")
    code, objs = path_json(capsys, prog, "--param", "max blocks=3000")
    assert code in (0, 1)
    for o in objs:
        if o["kind"] == "alarm":
            assert o["code"] != "0x0000", o


def test_campaign_journal_writes_a_nan_figure_as_null(tmp_path) -> None:
    from hil.campaign.results import Journal
    j = Journal(tmp_path)
    j.append({"input_hash": "h1", "status": "completed", "max_ferr_mm": float("nan"), "time_s": 1.5})
    j.close(remove=False)
    rows = j.previous()
    assert rows["h1"]["max_ferr_mm"] is None and rows["h1"]["time_s"] == 1.5
    assert "NaN" not in j.path.read_text()
