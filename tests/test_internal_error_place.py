"""A bug in the NC still names where the program stood (the guide: an internal error gives a Delta alarm code, the
file, line and block, and a clear message; decision B100). Before, `hil run` printed `ALARM 0x0000 -- NC internal
error: ...` with no place at all, for a bug in the interpreter and for one in the planner."""

from __future__ import annotations

import nc.interp.lean as lean
import nc.motion.planner as planner
from hil.cli import main
from tests.conftest import ROOT

MILL = str(ROOT / "benches" / "mill-3axis.toml")
PROGRAM = "G90 G54 G17 G21 G94\nG01 X10. F3000\nG01 X20.\nG01 Y5.\nM30\n"


def _failing_on_call(monkeypatch, cls, name: str, n: int, text: str) -> None:
    orig, calls = getattr(cls, name), [0]

    def bug(self, *args, **kwargs):
        calls[0] += 1
        if calls[0] == n:
            raise RuntimeError(text)
        return orig(self, *args, **kwargs)

    monkeypatch.setattr(cls, name, bug)


def _run(tmp_path, capsys) -> tuple[int, str]:
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    code = main(["run", str(prog), "--bench", MILL, "--no-check"])
    return code, capsys.readouterr().out


def test_a_bug_in_the_interpreter_names_the_file_line_and_block(tmp_path, capsys, monkeypatch):
    _failing_on_call(monkeypatch, lean.LeanLane, "take", 3, "boom in the interpreter")
    code, out = _run(tmp_path, capsys)
    assert code == 1 and "result         STOPPED" in out
    alarm = next(ln for ln in out.splitlines() if "ALARM 0x0000" in ln)
    assert "in p.nc at line " in alarm and "G01 X" in alarm and "boom in the interpreter" in alarm, alarm


def test_a_bug_in_the_planner_names_the_block_being_executed(tmp_path, capsys, monkeypatch):
    _failing_on_call(monkeypatch, planner.Planner, "_plan_path", 5, "boom in the planner")
    code, out = _run(tmp_path, capsys)
    assert code == 1 and "result         STOPPED" in out
    alarm = next(ln for ln in out.splitlines() if "ALARM 0x0000" in ln)
    assert "in p.nc at line 4: G01 Y5." in alarm and "boom in the planner" in alarm, alarm
