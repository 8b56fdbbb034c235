"""`hil check`, `hil trace` and `hil report` say how the traced run ended when it did not reach its program's end
(decision B87): "12 passed" on a run an alarm stopped after 8 cycles judged those 8 cycles, not the program."""

from __future__ import annotations

import html

from hil.cli import main
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")


def _trace(tmp_path, text: str, *extra: str) -> str:
    prog = tmp_path / "p.nc"
    prog.write_text(text)
    trace = str(tmp_path / "t.parquet")
    main(["run", str(prog), "--bench", MILL, "--trace", trace, *extra])
    return trace


def test_check_trace_and_report_name_the_alarm_that_ended_the_run(tmp_path, capsys):
    trace = _trace(tmp_path, "G01 X10. F600\nG04 X-1\nM30\n")  # 0x0223 negative dwell, at line 2
    capsys.readouterr()
    assert main(["check", trace]) == 0  # the checks themselves pass: the exit code stays theirs
    out = capsys.readouterr().out
    note = "run ended by an alarm 0x0223 at line 2 at t=0.008 s (cycle 8), before its program's end"
    assert f"{note}: the checks judge the cycles it ran" in out
    assert out.index(note) < out.index("passed")  # before the verdict, where it is read
    main(["trace", trace])
    assert f"end            {note}" in capsys.readouterr().out
    main(["report", trace, "--out", str(tmp_path / "rep")])
    assert note in capsys.readouterr().out
    assert html.escape(note) in (tmp_path / "rep" / "index.html").read_text()


def test_a_reset_that_aborted_the_program_is_named(tmp_path, capsys):
    trace = _trace(tmp_path, "G01 X50. F600\nG01 X0.\nM30\n", "--at", "t=0.5:reset")
    capsys.readouterr()
    main(["check", trace])
    assert "run ended aborted (a reset flushed the program)" in capsys.readouterr().out


def test_a_completed_run_gets_no_note(tmp_path, capsys):
    trace = _trace(tmp_path, "G01 X10. F600\nM30\n")
    capsys.readouterr()
    assert main(["check", trace]) == 0
    main(["trace", trace])
    assert "run ended" not in capsys.readouterr().out
