"""Bench tools a user meets on the first day: a closed stdout ends quietly, one spelling per flag
(old spellings still work, hidden from --help), bus captures read back by the tools that read them.

Decisions: docs/decisions/bench-tools.md.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from hil.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
LATHE = str(ROOT / "benches" / "lathe-2axis.toml")
PART = str(ROOT / "examples" / "lathe_part_g71_g70_g76.nc")


def _hil(*args: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "hil.cli", *args], capture_output=True, text=True, timeout=120, **kw)


@pytest.mark.parametrize("what", ["path", "path --json", "trace"])
def test_closed_stdout_ends_quietly(what, tmp_path):
    """`hil path … | head -1`: the first line arrives, exit 0 (README), nothing on stderr."""
    args: tuple[str, ...] = (*what.split(), PART)
    if what == "trace":
        prog = tmp_path / "short.nc"
        prog.write_text(SHORT)
        assert _hil("run", str(prog), "--trace", str(tmp_path / "t.csv")).returncode == 0
        args = ("trace", str(tmp_path / "t.csv"))
    cmd = f"{sys.executable} -m hil.cli {' '.join(args)} | head -1; exit ${{PIPESTATUS[0]}}"
    r = subprocess.run(["bash", "-c", cmd], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""
    first = {"path": "# work coordinates", "path --json": '"kind"', "trace": "trace"}[what]  # path's header line
    assert r.stdout.count("\n") == 1 and first in r.stdout, r.stdout


SHORT = "G98\nG00 X10. Z10.\nG01 X12. Z8. F1000.\nM30\n"  # feed per minute: no spindle needed


def _help(*path: str) -> str:
    parser = build_parser()
    sub = parser._subparsers._group_actions[0].choices[path[0]]
    for name in path[1:]:
        sub = sub._subparsers._group_actions[0].choices[name]
    return sub.format_help()


def test_one_spelling_per_flag_old_ones_hidden():
    """The servo's RS-485 port is --servo-modbus/--servo-baud in hil run and hil servo alike; the old
    --modbus/--baud still parse but are not offered in --help."""
    parser = build_parser()
    for cmd in (["servo", "get", "X", "P2-00"], ["run", "x.nc"]):
        a = parser.parse_args([*cmd, "--servo-modbus", "/dev/ttyUSB0", "--servo-baud", "9600"])
        assert (getattr(a, "modbus", None) or a.servo_modbus) == "/dev/ttyUSB0"
        assert (getattr(a, "baud", None) or a.servo_baud) == 9600
    old = parser.parse_args(["servo", "get", "X", "P2-00", "--modbus", "/dev/ttyS1", "--baud", "19200"])
    assert (old.modbus, old.baud) == ("/dev/ttyS1", 19200)
    assert parser.parse_args(["servo", "get", "X", "P2-00"]).baud == 38400
    text = _help("servo")
    assert "--servo-modbus" in text and "--servo-baud" in text
    assert "--modbus" not in text.replace("--servo-modbus", "") and "--baud" not in text.replace("--servo-baud", "")
    assert parser.parse_args(["sim", "ethercat", "--interface", "veth0"]).iface == "veth0"
    assert "--interface" not in _help("sim", "ethercat")


def test_sim_ethercat_without_bus_is_usage():
    r = _hil("sim", "ethercat")
    assert r.returncode == 2 and "--bus ethercat:IFACE" in r.stderr and "Traceback" not in r.stderr


def _cycles(stdout: str) -> int:
    return int(next(l for l in stdout.splitlines() if l.startswith("cycles")).split()[1])


@pytest.mark.parametrize("suffix", [".asc", ".blf", ".log"])
def test_can_capture_reads_back_with_python_can(tmp_path, suffix):
    """Every CANopen frame of a run, read back by python-can's reader for the suffix: one SYNC per
    cycle, the master's frames (Tx) and the drives' (Rx), in simulated time."""
    import can

    prog = tmp_path / "short.nc"
    prog.write_text(SHORT)
    cap = tmp_path / f"bus{suffix}"
    r = _hil("run", str(prog), "--bench", LATHE, "--bus", "canopen:virtual", "--capture", str(cap))
    assert r.returncode == 0, r.stdout + r.stderr
    msgs = list(can.LogReader(str(cap)))
    syncs = [m for m in msgs if m.arbitration_id == 0x080]
    cycles = _cycles(r.stdout)
    assert abs(len(syncs) - cycles) <= 2
    rpdo1 = {m.arbitration_id for m in msgs if not m.is_rx and 0x201 <= m.arbitration_id <= 0x27F}
    tpdo1 = {m.arbitration_id for m in msgs if m.is_rx and 0x181 <= m.arbitration_id <= 0x1FF}
    assert rpdo1 == {0x201, 0x202, 0x203} and tpdo1 == {0x181, 0x182, 0x183}  # X, Z, spindle S1
    span = syncs[-1].timestamp - syncs[0].timestamp
    assert span == pytest.approx((len(syncs) - 1) * 0.001, abs=2e-3)  # lock-step: 1 ms apart, simulated


@pytest.mark.parametrize("args,words", [
    (("--capture", "x.asc"), "the sim bus has no frames"),
    (("--bus", "canopen:virtual", "--capture", "x.pcapng"), ".asc, .blf, .log"),
    (("--bus", "ethercat:nope0", "--capture", "x.blf"), ".pcapng"),
])
def test_capture_refuses_what_it_cannot_write(tmp_path, args, words):
    prog = tmp_path / "short.nc"
    prog.write_text(SHORT)
    r = _hil("run", str(prog), *args, cwd=tmp_path)
    assert r.returncode == 2 and words in r.stderr and "Traceback" not in r.stderr
    assert not list(tmp_path.glob("x.*"))


def test_ethercat_capture_decodes_in_tshark(tmp_path):
    """`--capture run.pcapng` on the master's NIC: tshark decodes the EtherCAT datagrams; every
    cycle's process-data frame (LRW) is there going out and coming back; nothing but EtherCAT is (the
    kernel's IPv6 router solicitation on a fresh link was frame 1, ahead of the bus's first BWR)."""
    import shutil

    from virtual_bus.ethercat.veth import SimProcess, can_create

    if (why := can_create()) is not None:
        pytest.skip(why)
    if shutil.which("tshark") is None:
        pytest.skip("tshark is not installed (apt-get install tshark)")
    prog = tmp_path / "short.nc"
    prog.write_text(SHORT)
    cap = tmp_path / "run.pcapng"
    with SimProcess(tag="cap") as sim:
        r = _hil("run", str(prog), "--bus", f"ethercat:{sim.iface}", "--capture", str(cap))
        iface = sim.iface
    assert r.returncode == 0, r.stdout + r.stderr
    t = subprocess.run(["tshark", "-r", str(cap), "-Y", "ecat.cmd == 0x0c", "-T", "fields",
                        "-e", "eth.type", "-e", "eth.src", "-e", "frame.interface_name"],
                       capture_output=True, text=True, timeout=120)
    assert t.returncode == 0, t.stderr
    rows = [l.split("\t") for l in t.stdout.splitlines()]
    assert {r_[0] for r_ in rows} == {"0x88a4"} and {r_[2] for r_ in rows} == {iface}
    by_src: dict[str, int] = {}
    for r_ in rows:
        by_src[r_[1]] = by_src.get(r_[1], 0) + 1
    cycles = _cycles(r.stdout)
    every = subprocess.run(["tshark", "-r", str(cap), "-T", "fields", "-e", "eth.type"], capture_output=True,
                           text=True, timeout=120)
    assert set(every.stdout.split()) == {"0x88a4"}
    assert len(by_src) == 2 and all(abs(n - cycles) <= 5 for n in by_src.values()), (by_src, cycles)


def test_user_mlc_error_names_file_line_and_traceback(tmp_path):
    """A bug in the user's MLC: alarm 0xDE02 (not 0x0000) with the file, the line and the user's
    frames; the run stops under control with its summary, exit 1."""
    mlc = tmp_path / "bad_mlc.py"
    mlc.write_text('def helper(mlc):\n    return 1 / mlc.state.get("zero", 0)\n\n\n'
                   'def scan(mlc):\n    mlc.state["n"] = mlc.state.get("n", 0) + 1\n'
                   '    if mlc.state["n"] > 50:\n        helper(mlc)\n')
    prog = tmp_path / "short.nc"
    prog.write_text(SHORT)
    r = _hil("run", str(prog), "--mlc", str(mlc))
    assert r.returncode == 1, r.stdout + r.stderr
    assert f"ALARM 0xDE02 -- MLC program error in {mlc} line 2: ZeroDivisionError" in r.stdout
    assert f'File "{mlc}", line 8, in scan' in r.stdout and f'File "{mlc}", line 2, in helper' in r.stdout
    assert "0x0000" not in r.stdout + r.stderr and "machine.py" not in r.stdout
    assert "result         STOPPED" in r.stdout


def test_mst_code_the_mlc_never_answers_is_a_warning(tmp_path):
    """M08 answered after 1.2 s, M09 never (an MLC that ignores it): with --aux-timeout 1 each gets a
    warning once, on stderr while it waits, in the summary, in --json and in the trace's end record;
    the NC keeps waiting as Delta's does, until max_time (0xDE03) ends the run, exit 1."""
    import json

    from hil.trace_read import TraceFile

    mlc = tmp_path / "slow_mlc.py"
    mlc.write_text('def scan(mlc):\n    if not mlc.m("M_STROBE"):\n        mlc.set("MST_FINISH", False)\n'
                   '        return\n    if int(mlc.d("M_CODE")) == 8 and mlc.timer("fin", 1.2, True):\n'
                   '        mlc.set("MST_FINISH")\n')
    bench = tmp_path / "b.toml"
    bench.write_text(Path(LATHE).read_text().replace('cycle_ms = 1.0', 'cycle_ms = 1.0\nmax_time = 3'))
    prog = tmp_path / "p.nc"
    prog.write_text("G98\nM08\nM09\nM30\n")
    r = _hil("run", str(prog), "--bench", str(bench), "--mlc", str(mlc), "--aux-timeout", "1", "--json",
             "--trace", str(tmp_path / "t.parquet"))
    assert r.returncode == 1, r.stderr
    out = json.loads(r.stdout)
    assert out["alarms"][0]["code"] == "0xDE03"
    w = out["warnings"]
    assert [(x["code"], x["line"], x["waited_s"]) for x in w] == [("M08", 2, 1.0), ("M09", 3, 1.0)]
    assert w[0]["answered_t"] == pytest.approx(w[0]["t"] + 1.2, abs=0.01) and w[1]["answered_t"] is None
    assert "warning: M09 (line 3: M09) strobed at" in r.stderr and "never answered" in r.stderr
    end = TraceFile(tmp_path / "t.parquet").meta["end"]
    assert [x["code"] for x in end["warnings"]] == ["M08", "M09"]


@pytest.mark.parametrize("args, message", [
    ("sim canopen --bus canopen:virtual", "the virtual interface only reaches this process"),
    ("sim canopen --interface virtual --channel x", "the virtual interface only reaches this process"),  # old
    ("sim canopen --bus canopen:socketcan", "the channel is missing"),
    ("sim canopen --bus sim", "serves a CANopen bus"),
    ("sim canopen", "--bus canopen:INTERFACE:CHANNEL is required"),
    ("sim ethercat --bus ethercat:nosuch0", "cannot open nosuch0"),
    ("sim ethercat --iface nosuch0", "cannot open nosuch0"),  # old spelling
    ("sim ethercat --bus canopen:x", "serves an EtherCAT bus"),
])
def test_sim_takes_the_bus_as_hil_run_spells_it(args, message):
    """`hil sim` names its bus with --bus as hil run/script/scan/servo do; the old --iface,
    --interface/--channel still work but are hidden from --help."""
    r = _hil(*args.split())
    assert r.returncode == 2 and message in r.stderr, r.stderr


def test_sim_help_shows_one_spelling():
    for bus in ("canopen", "ethercat"):
        h = _hil("sim", bus, "--help").stdout
        assert "--bus" in h and "--interface" not in h and "--iface" not in h and "--channel" not in h
