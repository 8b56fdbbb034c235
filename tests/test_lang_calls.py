"""Calls and the program store: G65, G66/G67, M98/M99, G/M/T-code macros, M96, nesting (§7.3, E-N38/39,
E-L14, E-L21, E-L44), preview log and the parser fuzz test."""

from __future__ import annotations

import subprocess
import sys

import pytest
from hypothesis import given, settings, strategies as st

from lang_helpers import run_path

SUB = "\nO1010\n#100=#1+#2\n#101=#101+1\nM99\n"


def test_e_n38_g65_arguments_and_repeat(capsys, tmp_path):
    prog = "#101=0\nN10 G65 P1010 A5.0 B3.0 L2\nN20 #102=#1\nM30\n" + SUB
    r = run_path(capsys, tmp_path, prog, "--vars", "100-102")
    assert r.vars == {"100": 8.0, "101": 2.0, "102": None}  # L2 runs twice; locals are the macro's own


def test_e_n39_g66_after_each_motion_block_until_g67(capsys, tmp_path):
    prog = """G90 G00 X0 Y0
G66 P0008 A2.0
G00 X10.
#500=1
X20.
G67
Y20.
M30
O0008
#101=#101+1
#102=#1
#103=#2
G00 Z[#101]
M99
"""
    r = run_path(capsys, tmp_path, prog, "--vars", "101-103")
    assert r.vars == {"101": 2.0, "102": 2.0, "103": None}  # #1 = A2.0, B not given: #2 vacant
    zs = [m["work"]["Z"] for m in r.moves if m["line"] == 13]
    assert zs == [1.0, 2.0]  # once after X10., once after X20., never for Y20. or inside O0008
    assert [m["line"] for m in r.moves].index(13) == 2


def test_e_l14_multi_start_thread_via_g66(capsys, tmp_path):
    prog = """T0101
M03 S1000
G00 X40. Z10.
G66 P3300 A0
X17.45
G67
G66 P3300 A120000
X17.45
G67
M30
O3300
G32 Z-30. F3. Q#1
G00 X45.
G00 Z10.
M99
"""
    r = run_path(capsys, tmp_path, prog, profile="nc5-lathe-a")
    assert r.code == 0, r.alarm
    threads = [m for m in r.moves if m["kind"] == "thread"]
    assert len(threads) == 2 and all(m["work"]["Z"] == -30.0 for m in threads)


def test_m98_m99_nc5_h_q_and_return_label(capsys, tmp_path):
    prog = """#100=0
M98 P2000 H20
#101=1
N30 #102=1
M30
O2000
N10 #100=#100+1
N20 #100=#100+10
M99 P30
"""
    r = run_path(capsys, tmp_path, prog, "--vars", "100-102")
    assert r.vars == {"100": 10.0, "101": None, "102": 1.0}
    assert run_path(capsys, tmp_path, "M98\n").alarm["code"] == "0x0261"
    assert run_path(capsys, tmp_path, "M98 P77\n").alarm["code"] == "0x0263"
    # App. A 0x0251 "Only P_, H(Q)_, L_ can be used": L is legal, a non-integer repeat count is not (A21)
    assert run_path(capsys, tmp_path, "M98 P2000 L2.5\n" + prog[prog.index("O2000"):]).alarm["code"] == "0x0251"


def test_m98_h_wins_over_q(capsys, tmp_path):
    prog = "M98 P2000 H20 Q1\nM30\nO2000\nN10 #100=1\nN20 #101=1\nM99\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "100-101")
    assert r.vars == {"100": None, "101": 1.0}


def test_lathe_2018_m98_p_l_repeats(capsys, tmp_path):
    prog = "#100=0\nM98 P10 L3\nM30\nO0010\n#100=#100+1\nM99\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "100", profile="lathe-2018")
    assert r.vars["100"] == 3.0


def test_m99_in_main_restarts_then_stops(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "#100=#100+1\nM99\n", "--vars", "100", "--param", "M99 main restarts=3")
    assert r.vars["100"] == 4.0


def test_nesting_limits(capsys, tmp_path):
    deep = "G65 P1\nM30\nO0001\nG65 P1\nM99\n"
    assert run_path(capsys, tmp_path, deep).alarm["code"] == "0x0212"
    sub = "M98 P1\nM30\nO0001\nM98 P1\nM99\n"
    assert run_path(capsys, tmp_path, sub).alarm["code"] == "0x022D"
    eight = "#100=0\nG65 P1 A8.\nM30\nO0001\n#100=#100+1\nIF[#1LE1]GOTO9\nG65 P1 A[#1-1]\nN9 M99\n"
    assert run_path(capsys, tmp_path, eight, "--vars", "100").vars["100"] == 8.0  # 8 levels allowed


def test_argument_letters_repeat_map(capsys, tmp_path):
    prog = "G65 P1 A1. A2. A3. T4. T5. T6. T7. T8.\nM30\nO0001\n#100=#1+#27*10+#53*100\n#101=#20+#46+#72+#85+#92\nM99\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "100-101")
    assert r.vars == {"100": 321.0, "101": 30.0}
    assert run_path(capsys, tmp_path, "G65 P1 A1. A2. A3. A4.\nO0001\nM99\n").alarm["code"] == "0x0251"


def test_g_m_t_code_macro_calls(capsys, tmp_path):
    prog = "G100 X5. Q2.\nM150 A1.\nT0303\nM30\nO9100\n#100=#24+#17\nM99\nO9150\n#101=#1\nM99\nO9000\n#102=#20\nT#20\nM99\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "100-102", "--param", "N1.200=100", "--param", "N1.250=150",
                 "--param", "N1.010 Bit22=1", profile="nc5-lathe-a")
    assert r.vars == {"100": 7.0, "101": 1.0, "102": 303.0}
    cont = run_path(capsys, tmp_path, "G120 A3.\nM30\nO8002\n#100=#1\nM99\n", "--vars", "100",
                    "--param", "N1.120=118", "--param", "N1.121=8000", "--param", "N1.122=10")
    assert cont.vars["100"] == 3.0


def test_e_l44_lathe_2018_t_call(capsys, tmp_path):
    prog = "T0303\nM30\nO9000\n#100=#20\nT#20\nM99\n"
    r = run_path(capsys, tmp_path, prog, "--vars", "100", "--param", "O9000=1", profile="lathe-2018")
    assert r.vars["100"] == 303.0


def test_program_store_folder_order(capsys, tmp_path):
    lib = tmp_path / "lib"
    (lib / "PATH_1").mkdir(parents=True)
    (lib / "GLOBAL" / "O_MACRO").mkdir(parents=True)
    (lib / "PATH_1" / "O0005.NC").write_text("#100=1\nM99\n")
    (lib / "GLOBAL" / "O_MACRO" / "O0005").write_text("#100=2\nM99\n")
    (lib / "GLOBAL" / "O_MACRO" / "O0006").write_text("#101=2\nM99\n")
    main = tmp_path / "main"
    main.mkdir()
    (main / "O0006").write_text("#101=1\nM99\n")
    f = main / "p.nc"
    f.write_text("M98 P5\nG65 P6\nM30\n")
    from hil.cli import main as cli
    capsys.readouterr()
    assert cli(["path", str(f), "--json", "--lib", str(lib), "--vars", "100-101"]) == 0
    out = capsys.readouterr().out
    assert '"100": 1.0' in out and '"101": 1.0' in out  # PATH_1 before GLOBAL; main folder first for G65


def test_m96_interrupt(capsys, tmp_path):
    from nc.interp import Interpreter
    from nc.moves import Move, Sync
    from nc.profiles import make_profile
    from nc.store import ProgramStore
    store = ProgramStore()
    progs = store.add_text("M96 P50\nG90 G01 X10. F100\nX20.\nX30.\nM30\nO0050\n#100=7\nM99\n")
    it = Interpreter(make_profile("nc5-mill"), store=store)
    ev = it.run(progs[0], preview=False)
    first = [next(e for e in ev if not isinstance(e, Sync))]  # M96 is a preview stop (Sync) first
    assert isinstance(first[0], Move)
    it.request_interrupt()
    rest = list(ev)
    assert it.variable(100) == 7.0 and [e.work["X"] for e in rest if isinstance(e, Move)] == [20.0, 30.0]


def test_mlc_exchange_shared_object(capsys, tmp_path):
    from nc.interp import Interpreter
    from nc.profiles import make_profile
    from nc.program import parse_program
    it = Interpreter(make_profile("nc5-mill"))
    seen = []
    it.vars.mlc.on_write = lambda n, v: seen.append((n, v))
    it.vars.mlc.set_input(25000, 1)
    it.vars.mlc.set_input(25128, 1234)
    list(it.run(parse_program("#100=#25000+#25128\n#25256=5\n#25384=#100\nM30\n")))
    assert it.variable(100) == 1235.0
    assert seen == [(25256, 1.0), (25384, 1235.0)] and it.vars.mlc.device(25256) == "M31128"
    r = run_path(capsys, tmp_path, "#25000=1\n")
    assert r.alarm["code"] == "0x0254"


def test_preview_log_shows_statements_ahead_of_motion(capsys, tmp_path):
    prog = "G90 G01 X10. F100\nX20.\n#100=1\nX30.\n#101=2\nG10 L2 P1 X0\n#102=3\nX40.\nM30\n"
    r = run_path(capsys, tmp_path, prog, "--preview-log")
    logs = {o["line"]: o for o in r.other if o["kind"] == "preview"}
    assert logs[3]["ahead_of_line"] == 1 and logs[5]["ahead_of_line"] == 1  # ran while line 1 moved
    assert logs[7]["ahead_of_line"] == 4 and logs[7]["blocks_ahead"] == 0  # G10 emptied the window
    r = run_path(capsys, tmp_path, prog, "--preview-log", "--param", "preview depth=0")
    logs = {o["line"]: o for o in r.other if o["kind"] == "preview"}
    assert logs[3]["ahead_of_line"] == 2


def test_halt_m_code_stops_preview(capsys, tmp_path):
    r = run_path(capsys, tmp_path, "G01 X1. F100\nM200\n#100=1\nM30\n", "--preview-log",
                 "--param", "N1.118=200", "--param", "N1.119=2")
    assert any(o["kind"] == "sync" and o["reason"] == "M200" for o in r.other)


def test_cli_subprocess_alarm_exit_code(tmp_path):
    f = tmp_path / "bad.nc"
    f.write_text("G90 G00 X1.\nGOTO 5\n")
    p = subprocess.run([sys.executable, "-m", "hil.cli", "path", str(f)], capture_output=True, text=True)
    assert p.returncode == 1 and "0x022A" in p.stderr and "line 2" in p.stderr and "Traceback" not in p.stderr


TEXT = st.text(alphabet="GXYZMFSTPQRIJKNO#[]=+-*/.,;()0123456789 \nIFGOTOWHILEDOEND", max_size=60)


@settings(max_examples=300, deadline=None)
@given(TEXT)
def test_fuzz_parser_and_interpreter_raise_only_nc_alarms(text):
    from nc.alarms import NcAlarm
    from nc.interp import Interpreter
    from nc.profiles import make_profile
    from nc.program import parse_program
    for prof in ("nc5-mill", "lathe-2018"):
        try:
            prog = parse_program(text)
            p = make_profile(prof)
            p.params["max blocks"] = 2000
            for i, _ in enumerate(Interpreter(p).run(prog)):
                if i > 2000:
                    break
        except NcAlarm:
            pass
