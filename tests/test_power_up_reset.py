"""A drive that is in fault when `hil run` powers the bench up (latched before the run: a master that died
mid-program, decision E33; a drive switched on in fault) gets one fault reset, as the operator's RESET before
cycle start, and the run goes on with the reset named in its summary. A fault the reset does not clear, or one
that arises while powering up or later, stays the servo alarm (decision B72)."""

from __future__ import annotations

import json

from fieldbus.cia402 import State
from fieldbus.link import SimLink
from hil.bench import default_lathe
from hil.commands.run import print_summary
from hil.runner import BenchRunner
from hil.session import sim_slaves
from nc.program import parse_program
from virtual_bus.drive import AL_EMERGENCY

PROGRAM = "G98\nG00 X80. Z-20.\nG01 X100. Z-60. F3000\nM30\n"
COMM = 0x7500  # CiA 402 communication fault, what a drive latches when its master goes silent


def _run(prepare):
    bench = default_lathe()
    drives = sim_slaves(bench)
    prepare(drives)
    runner = BenchRunner(bench, SimLink(drives, bench.cycle))
    return runner.run_program(parse_program(PROGRAM)), drives, bench


def _latched(d, code=COMM):
    d.fault(code)
    d.step(0.001)  # at rest: the fault reaction ends at once in FAULT
    assert d.state is State.FAULT


def test_a_fault_latched_before_the_run_is_reset_once_and_the_program_runs(capsys):
    result, drives, bench = _run(lambda ds: (_latched(ds[0]), _latched(ds[2])))
    assert result.finished and not result.alarms
    assert result.power_up_resets == [("X", COMM), ("S1", COMM)]
    clean, _, _ = _run(lambda ds: None)
    # the same run as without the faults, three cycles later (the reset's edge and the drive's answer)
    assert result.final == clean.final and result.enable_cycles == clean.enable_cycles + 3
    assert abs(result.program_time - clean.program_time) < 1e-9 and result.cycles == clean.cycles + 3
    assert not any(d.state is State.FAULT for d in drives)
    print_summary("p.nc", bench, result)
    out = capsys.readouterr().out
    assert f"drives enabled after {result.enable_cycles} cycles  (fault reset at power-up: X 0x7500, S1 0x7500)" in out


def test_a_fault_the_reset_does_not_clear_is_still_0x0a07():
    """The emergency-stop input of the Z drive (ASDA AL013) stays active: the reset is tried, the fault stays."""
    def prepare(ds):
        ds[1].external_fault = AL_EMERGENCY
    result, drives, _ = _run(prepare)
    codes = [(a.code, a.axis) for a in result.alarms]
    assert (0x0A07, "Z") in codes and (0xF002, "Z") in codes and not result.finished
    assert result.power_up_resets == [("Z", AL_EMERGENCY)]
    assert result.final["X"] == default_lathe().axes[0].start  # nothing moved


def test_no_reset_without_a_fault(capsys):
    result, _, bench = _run(lambda ds: None)
    assert result.finished and result.power_up_resets == []
    print_summary("p.nc", bench, result)
    assert "fault reset" not in capsys.readouterr().out


def test_the_json_summary_lists_the_resets(tmp_path, monkeypatch, capsys):
    from hil import session
    from hil.cli import main

    real = session.sim_slaves

    def latched_x(bench):
        ds = real(bench)
        _latched(ds[0])
        return ds

    monkeypatch.setattr(session, "sim_slaves", latched_x)
    prog = tmp_path / "p.nc"
    prog.write_text(PROGRAM)
    assert main(["run", str(prog), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["power_up_fault_resets"] == [{"drive": "X", "error_code": COMM}] and got["result"] == "completed"
