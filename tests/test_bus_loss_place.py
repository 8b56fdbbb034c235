"""A bus that stops answering mid-program names where the program stood (issue 17, decision ethercat.md E35): as a
drive's own alarm (0xF002 `at line 7`) and an NC internal error (B100) do, the bus alarm 0x0601 carries the line,
block and file of the block being executed. It used to print `ALARM 0x0601 axis X -- EtherCAT communication lost …`
with no place at all, and the trace's end record had `alarm_line` null. Lock-step: the sim link's exchange raises
the link's own BusError from cycle 1500 on (its first exchange after that: Z at 100 mm/s in a stroke)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LATHE = ROOT / "benches" / "lathe-2axis.toml"
LONG = "G98\nG00 X58. Z98.\nG01 Z-300. F6000\n" + "G01 Z98.\nG01 Z-300.\n" * 63 + "M30\n"


def test_a_lost_bus_names_the_line_block_and_file_where_the_program_stood(tmp_path):
    from fieldbus.link import BusError
    from hil.runner import BenchRunner
    from hil.session import load_bench, make_link
    from hil.trace import open_trace
    from hil.trace_read import TraceFile
    from nc.alarms import Alarm
    from nc.program import parse_program

    bench = load_bench(str(LATHE))
    bench.mlc = "basic"
    link = make_link(bench)
    answer = link.exchange
    runner = BenchRunner(bench, link, None)

    def exchange(rx):
        if runner.cycle >= 1500:
            raise BusError(Alarm(0x0601, "EtherCAT communication lost for 4 cycles (no frame returned)", axis="X"))
        return answer(rx)

    link.exchange = exchange
    runner.trace = open_trace(tmp_path / "t.parquet", runner.trace_columns())
    result = runner.run_program(parse_program(LONG, name="long.nc"))
    alarm = result.alarms[0]
    assert alarm.code == 0x0601 and alarm.axis == "X"
    tf = TraceFile(tmp_path / "t.parquet")
    c = tf.arrays(["line", "Z_vel"])
    moving_in = int(c["line"][-1])  # the program line of the last cycle before the loss (no row after it)
    assert abs(c["Z_vel"][-1]) > 1  # mid-move
    assert alarm.line == moving_in and alarm.block == LONG.splitlines()[moving_in - 1] and alarm.program == "long.nc"
    assert f"line {moving_in}" in str(alarm)
    assert len(result.alarms) > 1 and all(a.line == moving_in for a in result.alarms)  # the stop's own losses too
    assert tf.meta["end"]["alarm_line"] == moving_in
