"""Bad input through every `hil` subcommand: an NC alarm code (App. A) or a usage message, exit 1 or 2,
never a traceback or the internal error (0x0000 "NC internal error"), and no half-written output file.

Decisions: docs/decisions/bench.md "bad input end to end" (an alarmed run's trace is a complete, closed
file; a run refused before it starts writes none; exports and traces are renamed from *.part on success).
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hil.cli import main
from hil.trace_read import TraceFile

ROOT = Path(__file__).resolve().parents[1]
LATHE = str(ROOT / "benches" / "lathe-2axis.toml")

OK_NC = "G98\nG00 X10. Z10.\nG01 X12. F1000.\nM30\n"  # feed per minute: runs without a spindle

FILES: dict[str, str | bytes] = {
    "ok.nc": OK_NC,
    "empty.nc": "",
    "garbage.nc": bytes(range(256)) * 8,
    "unknown_g.nc": "G00 X10. Z10.\nG177 X5.\nM30\n",
    "arc_r.nc": "G98\nG00 X0 Z0\nG02 X100. Z0 R1. F100.\nM30\n",
    "m98.nc": "G00 X10. Z10.\nM98 P4711\nM30\n",
    "while.nc": "#1=0\nWHILE[#1 LT 3]DO1\n#1=#1+1\nM30\n",
    "end.nc": "#1=0\nEND1\nM30\n",
    "ifthen.nc": "IF[#1 EQ 0]THEN\nG00 X1.\nM30\n",
    "nested.nc": "#1=" + "[" * 100 + "1" + "]" * 100 + "\nM30\n",
    "chain.nc": "#1=" + "1+" * 2000 + "1\nM30\n",
    "signs.nc": "#1=" + "-" * 5000 + "1\nM30\n",
    "bad.toml": "name = [\n",
    "types.toml": 'name = 5\ncycle_ms = "fast"\n[[axes]]\nname = "X"\n',
    "unknown.toml": 'name = "u"\nfrobnicate = 1\n[[axes]]\nname = "X"\n',
    "garbage.toml": bytes(range(256)),
    "slow.toml": 'name = "slow"\ncycle_ms = 4.0\n[[axes]]\nname = "X"\nlead = 5.0\n[[axes]]\nname = "Z"\nlead = 10.0\n',
    "raise.py": "def main(machine):\n    raise RuntimeError('boom')\n",
    "syntax.py": "def main(machine:\n",
    "not_t.csv": "a,b\n1,2\n",
    "empty.csv": "",
    "garbage.csv": bytes(range(256)) * 4,
    "garbage.parquet": b"PAR1" + bytes(range(256)) * 4,
}


@pytest.fixture(scope="module")
def d(tmp_path_factory) -> Path:
    """The bad files, plus a good trace of ok.nc and damaged copies of it."""
    root = tmp_path_factory.mktemp("bad")
    for name, body in FILES.items():
        (root / name).write_bytes(body if isinstance(body, bytes) else body.encode())
    (root / "long.nc").write_text("G00 X1. Z1.\nX" + "1" * 10_000_000 + "\nM30\n")
    (root / "adir").mkdir()
    assert main(["run", str(root / "ok.nc"), "--trace", str(root / "ok.csv"), "--no-progress"]) == 0
    assert main(["trace", str(root / "ok.csv"), "--out", str(root / "ok.parquet")]) == 0
    lines = (root / "ok.csv").read_text().splitlines()
    (root / "trunc.csv").write_text("\n".join(lines[:5]) + "\n" + lines[5][: len(lines[5]) // 2])
    header = lines[0].split(",")
    keep = [i for i, c in enumerate(header) if not c.startswith("Z_")]
    (root / "missing.csv").write_text("\n".join(",".join(r.split(",")[i] for i in keep) for r in lines) + "\n")
    (root / "textrows.csv").write_text(lines[0] + "\n" + ",".join(["abc"] * len(header)) + "\n")
    pq = (root / "ok.parquet").read_bytes()
    (root / "trunc.parquet").write_bytes(pq[: len(pq) // 2])
    return root


def hil(argv: list[str], capsys) -> tuple[int, str]:
    rc = main(argv)
    out, err = capsys.readouterr()
    text = out + err
    assert "Traceback" not in text
    assert "NC internal error" not in text, f"internal error (a bug) for {argv}: {text[-400:]}"
    return rc, text


# (id, argv with {d} for the folder, exit code, what the message must name)
CASES: list[tuple[str, str, int, tuple[str, ...]]] = [
    # programs: `hil path`
    ("path-missing", "path {d}/nope.nc", 1, ("0x0002", "nope.nc")),
    ("path-folder", "path {d}/adir", 1, ("0x0002", "Is a directory")),
    ("path-garbage", "path {d}/garbage.nc", 1, ("0x0206", "line 1")),
    ("path-unknown-g", "path {d}/unknown_g.nc", 1, ("0x021D", "line 2", "G177")),
    ("path-arc-r", "path {d}/arc_r.nc", 1, ("0x0259", "line 3", "R1.")),
    ("path-m98", "path {d}/m98.nc", 1, ("0x0263", "line 2", "O4711")),
    ("path-while", "path {d}/while.nc", 1, ("0x022C", "line 2")),
    ("path-end", "path {d}/end.nc", 1, ("0x022B", "line 2")),
    ("path-ifthen", "path {d}/ifthen.nc", 1, ("0x023D", "line 1")),
    ("path-nested", "path {d}/nested.nc", 1, ("0x0209", "line 1", "nested")),
    ("path-chain", "path {d}/chain.nc", 1, ("0x0206", "line 1", "operators")),
    ("path-signs", "path {d}/signs.nc", 1, ("0x0209", "line 1")),
    ("path-10MB-line", "path {d}/long.nc --json", 1, ("0x0223", '"line": 2', "10000001 characters")),
    ("path-bench-folder", "path {d}/ok.nc --bench {d}/adir", 2, ("adir",)),
    ("path-bench-toml", "path {d}/ok.nc --bench {d}/bad.toml", 2, ("not valid TOML",)),
    ("path-interrupt-junk", "path {d}/ok.nc --interrupt junk", 2, ("--interrupt",)),
    ("path-interrupt-frac", "path {d}/ok.nc --interrupt 2@7", 2, ("--interrupt",)),
    ("path-param", "path {d}/ok.nc --param N1.040=abc", 2, ("abc",)),
    ("path-vars", "path {d}/ok.nc --vars 9-1", 2, ("--vars",)),
    ("path-lib-missing", "path {d}/ok.nc --lib {d}/nope", 2, ("--lib",)),
    ("path-lib-garbage", "path {d}/ok.nc --lib {d}/garbage.nc", 1, ("0x0206",)),
    ("path-plot-nowhere", "path {d}/ok.nc --plot /proc/nope/x.png", 2, ("cannot write",)),
    # programs, benches and buses: `hil run`
    ("run-missing", "run {d}/nope.nc", 1, ("0x0002",)),
    ("run-garbage", "run {d}/garbage.nc", 1, ("0x0206", "line 1")),
    ("run-unknown-g", "run {d}/unknown_g.nc", 1, ("0x021D", "line 2", "STOPPED")),
    ("run-arc-r", "run {d}/arc_r.nc", 1, ("0x0259", "line 3")),
    ("run-m98", "run {d}/m98.nc", 1, ("0x0263", "line 2")),
    ("run-while", "run {d}/while.nc", 1, ("0x022C", "line 2")),
    ("run-bench-folder", "run {d}/ok.nc --bench {d}/adir", 2, ("Is a directory",)),
    ("run-bench-toml", "run {d}/ok.nc --bench {d}/bad.toml", 2, ("not valid TOML",)),
    ("run-bench-types", "run {d}/ok.nc --bench {d}/types.toml", 2, ("name", "cycle_ms")),
    ("run-bench-unknown", "run {d}/ok.nc --bench {d}/unknown.toml", 2, ("frobnicate: unknown key",)),
    ("run-bench-binary", "run {d}/ok.nc --bench {d}/garbage.toml", 2, ("UTF-8",)),
    ("run-bench-missing", "run {d}/ok.nc --bench {d}/nope.toml", 2, ("nope.toml",)),
    ("run-ethercat-nope0", "run {d}/ok.nc --bus ethercat:nope0", 1, ("0x1429", "nope0", "STOPPED")),
    ("run-canopen-nosuch", "run {d}/ok.nc --bench {d}/slow.toml --bus canopen:nosuchiface", 1,
     ("0x1420", "nosuchiface", "STOPPED")),
    ("run-bus-junk", "run {d}/ok.nc --bus frob:1", 2, ("unknown bus",)),
    ("run-profile", "run {d}/ok.nc --profile zz", 2, ("unknown profile",)),
    ("run-mlc-raises", "run {d}/ok.nc --mlc {d}/syntax.py", 2, ("syntax.py",)),
    ("run-m00-negative", "run {d}/ok.nc --m00-resume -1", 2, ("--m00-resume",)),
    ("run-trace-folder", "run {d}/ok.nc --trace {d}/adir", 2, ("Is a directory",)),
    ("run-feed-override", "run {d}/ok.nc --feed-override 151", 2, ("feed override",)),
    ("run-spindle-override", "run {d}/ok.nc --spindle-override 20", 2, ("spindle override",)),
    ("examples-file", "examples {d}/ok.nc", 2, ("is not a folder",)),
    ("campaign-missing", "campaign {d}/nope.toml --out {d}/co", 2, ("nope.toml", "cannot be read")),
    ("campaign-toml", "campaign {d}/bad.toml --out {d}/co", 2, ("not valid TOML",)),
    ("campaign-binary", "campaign {d}/garbage.toml --out {d}/co", 2, ("UTF-8",)),
    ("campaign-unknown", "campaign {d}/unknown.toml --out {d}/co", 2, ("frobnicate: unknown key",)),
    ("campaign-no-out", "campaign {d}/unknown.toml", 2, ("--out",)),
    ("campaign-workers", "campaign {d}/unknown.toml --out {d}/co --workers -1", 2, ("--workers",)),
    ("campaign-scheduler", "campaign {d}/unknown.toml --out {d}/co --scheduler localhost", 2, ("tcp://",)),
    ("campaign-diff-args", "campaign diff {d}/ok.parquet", 2, ("BASE and NEW",)),
    ("campaign-diff-missing", "campaign diff {d}/nope.parquet {d}/ok.parquet", 2, ("nope.parquet",)),
    ("campaign-diff-garbage", "campaign diff {d}/garbage.parquet {d}/ok.parquet", 2, ("not a campaign result",)),
    ("campaign-diff-trace", "campaign diff {d}/ok.parquet {d}/ok.parquet", 2, ("not a campaign result",)),
    ("run-at-junk", "run {d}/ok.nc --at junk", 2, ("--at", "TRIGGER:ACTION")),
    ("run-at-negative", "run {d}/ok.nc --at t=-1:M31064=1", 2, ("--at", "≥ 0")),
    ("run-events-binary", "run {d}/ok.nc --events {d}/garbage.nc", 2, ("events file",)),
    ("run-events-folder", "run {d}/ok.nc --events {d}/adir", 2, ("events file",)),
    ("run-modbus-missing", "run {d}/ok.nc --servo-modbus /dev/nope-tty", 2, ("/dev/nope-tty",)),
    # traces: `hil trace`, `hil check`, `hil report`
    ("trace-missing", "trace {d}/nope.csv", 2, ("no such trace file",)),
    ("trace-empty", "trace {d}/empty.csv", 2, ("not a bench trace",)),
    ("trace-binary", "trace {d}/garbage.csv", 2, ("not a readable trace",)),
    ("trace-truncated", "trace {d}/trunc.csv", 2, ("damaged trace",)),
    ("trace-text-rows", "trace {d}/textrows.csv", 2, ("damaged trace",)),
    ("trace-not-trace", "trace {d}/not_t.csv", 2, ("'t' and 'line'",)),
    ("trace-parquet-garbage", "trace {d}/garbage.parquet", 2, ("not a readable trace",)),
    ("trace-parquet-truncated", "trace {d}/trunc.parquet", 2, ("not a readable trace",)),
    ("trace-bound-junk", "trace {d}/ok.csv --from junk", 2, ("bad bound",)),
    ("trace-bound-negative", "trace {d}/ok.csv --from -5", 2, ("bad bound",)),
    ("trace-line-negative", "trace {d}/ok.csv --to L-3", 2, ("bad bound",)),
    ("trace-out-folder", "trace {d}/ok.csv --out {d}/adir", 2, ("Is a directory",)),
    ("trace-columns", "trace {d}/ok.csv --columns nope --out {d}/o.csv", 2, ("no column nope",)),
    ("check-missing", "check {d}/nope.csv --max-ferr 1", 2, ("no such trace file",)),
    ("check-truncated", "check {d}/trunc.csv --max-ferr 1", 2, ("damaged trace",)),
    ("check-text-rows", "check {d}/textrows.csv --max-ferr 1", 2, ("damaged trace",)),
    ("check-missing-cols", "check {d}/missing.csv --bench " + LATHE, 2, ("no columns for axis Z",)),
    ("check-negative", "check {d}/ok.csv --max-ferr -1", 2, ("--max-ferr",)),
    ("check-jitter-negative", "check {d}/ok.csv --jitter-p99 -5", 2, ("--jitter-p99",)),
    ("check-program-arc", "check {d}/ok.csv --program {d}/arc_r.nc --contour 0.1", 1, ("0x0259", "line 3")),
    ("check-bench-toml", "check {d}/ok.csv --bench {d}/bad.toml", 2, ("not valid TOML",)),
    ("check-bench-folder", "check {d}/ok.csv --bench {d}/adir", 2, ("adir",)),
    ("report-truncated", "report {d}/trunc.csv --out {d}/rep1", 2, ("damaged trace",)),
    ("report-text-rows", "report {d}/textrows.csv --out {d}/rep2", 2, ("damaged trace",)),
    ("report-parquet", "report {d}/garbage.parquet --out {d}/rep3", 2, ("not a readable trace",)),
    ("report-out-file", "report {d}/ok.csv --out {d}/ok.nc", 2, ("cannot write",)),
    # scripts and the machine commands
    ("script-missing", "script {d}/nope.py", 2, ("does not exist",)),
    ("script-raises", "script {d}/raise.py", 1, ("raise.py raised at line 2", "RuntimeError: boom")),
    ("script-syntax", "script {d}/syntax.py", 2, ("not a Python script",)),
    ("script-binary", "script {d}/garbage.nc", 2, ("not a Python script",)),
    ("script-bench-toml", "script {d}/raise.py --bench {d}/bad.toml", 2, ("not valid TOML",)),
    ("script-ethercat-nope0", "script {d}/raise.py --bus ethercat:nope0", 1, ("0x1429", "nope0")),
    ("script-canopen-nosuch", "script {d}/raise.py --bench {d}/slow.toml --bus canopen:nosuchiface", 1,
     ("0x1420", "nosuchiface")),
    ("mpg-axis", "mpg Q 10", 2, ("'Q'",)),
    ("mpg-rate-zero", "mpg X 10 --rate 0", 2, ("rate",)),
    ("mpg-rate-negative", "mpg X 10 --rate -5", 2, ("rate",)),
    ("mpg-ratio", "mpg X 10 --ratio -1", 2, ("ratio",)),
    ("mpg-ethercat-nope0", "mpg X 10 --bus ethercat:nope0", 1, ("0x1429",)),
    ("spindle-negative-time", "spindle 500 --seconds -1", 2, ("--seconds",)),
    ("spindle-negative-rpm", "spindle -500", 2, ("RPM",)),
    ("spindle-override", "spindle 500 --override -5", 2, ("--override",)),
    ("spindle-ethercat-nope0", "spindle 500 --bus ethercat:nope0", 1, ("0x1429",)),
    ("servo-param", "servo get X junk", 2, ("junk",)),
    ("servo-axis", "servo get Q P2-00", 2, ("'Q'",)),
    ("servo-set-no-value", "servo set X P2-00", 2, ("VALUE",)),
    ("servo-ethercat-nope0", "servo get X P2-00 --bus ethercat:nope0", 1, ("0x1429",)),
    ("servo-canopen-nosuch", "servo get X P2-00 --bench {d}/slow.toml --bus canopen:nosuchiface", 1, ("0x1420",)),
    ("servo-modbus-missing", "servo get X P2-00 --servo-modbus /dev/nope-tty", 2, ("/dev/nope-tty",)),
    ("scan-ethercat-nope0", "scan --bus ethercat:nope0", 1, ("0x1429",)),
    ("scan-sim", "scan --bus sim", 2, ("nothing to scan",)),
    ("scan-junk", "scan --bus junk", 2, ("unknown bus",)),
    ("sim-ethercat-nope0", "sim ethercat --iface nope0 --duration 0.1", 2, ("nope0",)),
    ("sim-ethercat-fault", "sim ethercat --iface nope0 --fault junk", 2, ("fault spec",)),
    ("sim-ethercat-bench", "sim ethercat --iface nope0 --bench {d}/bad.toml", 2, ("not valid TOML",)),
    ("sim-canopen-nosuch", "sim canopen --interface nosuchiface --channel x --bench {d}/slow.toml --duration 0.1",
     2, ("nosuchiface",)),
]


@pytest.mark.parametrize("argv, code, names", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input(d, capsys, argv, code, names):
    rc, text = hil([a.format(d=d) for a in argv.split()] + (["--no-progress"] if argv.startswith("run") else []),
                   capsys)
    assert rc == code, text[-600:]
    for name in names:
        assert name in text, f"{name!r} not in {text[-600:]!r}"


def test_every_subcommand_is_swept():
    """A new hil/commands/<name>.py must bring its bad-input cases here."""
    commands = {p.stem for p in (ROOT / "hil" / "commands").glob("*.py") if p.stem != "__init__"}
    assert commands == {c[1].split()[0] for c in CASES}


def test_alarmed_run_leaves_a_whole_trace(d, capsys):
    """A run stopped by an alarm writes a complete, closed trace that `hil trace` reads; its alarm
    column names the code."""
    out = d / "alarmed.csv"
    rc, _ = hil(["run", str(d / "unknown_g.nc"), "--trace", str(out), "--no-progress"], capsys)
    assert rc == 1 and out.is_file() and not (d / "alarmed.csv.part").exists()
    alarms = [a for a in TraceFile(out).arrays(["alarm"])["alarm"] if a]
    assert alarms and "0x021D" in alarms[0]
    assert hil(["trace", str(out)], capsys)[0] == 0


def test_bus_that_never_opened_leaves_an_empty_trace(d, capsys):
    """No cycle ran: the trace is the header alone, the run names one alarm (no follow-on
    'link used before open'), and `hil check`/`report` refuse to judge it rather than pass it."""
    out = d / "nobus.parquet"
    rc, text = hil(["run", str(d / "ok.nc"), "--bus", "ethercat:nope0", "--trace", str(out), "--no-progress"], capsys)
    assert rc == 1 and "alarms         1" in text
    assert TraceFile(out).num_rows == 0
    for cmd in (["check", str(out), "--max-ferr", "1"], ["report", str(out), "--out", str(d / "rep-nobus")]):
        rc, text = hil(cmd, capsys)
        assert rc == 2 and "has no rows" in text


@pytest.mark.parametrize("bench", ["bad.toml", "adir", "types.toml"])
def test_refused_run_writes_no_trace(d, capsys, bench):
    out = d / f"refused-{bench}.csv"
    rc, _ = hil(["run", str(d / "ok.nc"), "--bench", str(d / bench), "--trace", str(out)], capsys)
    assert rc == 2 and not out.exists() and not Path(str(out) + ".part").exists()


@pytest.mark.parametrize("src", ["trunc.csv", "textrows.csv"])
def test_failed_export_leaves_nothing(d, capsys, src):
    out = d / f"export-{src}.parquet"
    rc, _ = hil(["trace", str(d / src), "--out", str(out)], capsys)
    assert rc == 2 and not out.exists() and not Path(str(out) + ".part").exists()


TOKENS = ["G00", "G01", "G02", "G03", "G04", "G71", "G76", "G65", "M98", "M99", "M30", "X10.", "Z-5.", "U1",
          "R2.", "I3.", "K-4.", "F100.", "P1000", "Q5", "#1=", "#[#2]", "[", "]", "+", "*", "/", "SIN[",
          "WHILE[", "DO1", "END1", "IF[", "THEN", "GOTO", "N10", "O1234", "(", ")", ";", "%", "\n", " "]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.one_of(st.binary(max_size=300), st.lists(st.sampled_from(TOKENS), max_size=60).map("".join)))
def test_random_programs_never_crash(tmp_path, capsys, program):
    """Byte soup or token soup as a program: `hil path --json` and a short `hil run` end with
    exit 0, 1 or 2 and never a traceback or an internal error."""
    prog = tmp_path / "soup.nc"
    prog.write_bytes(program if isinstance(program, bytes) else program.encode())
    bench = tmp_path / "short.toml"
    if not bench.exists():
        bench.write_text(Path(LATHE).read_text().replace('cycle_ms = 1.0', 'cycle_ms = 1.0\nmax_time = 0.5')
                         .split("[checks]")[0])
    assert hil(["path", str(prog), "--json"], capsys)[0] in (0, 1, 2)
    assert hil(["run", str(prog), "--bench", str(bench), "--no-progress"], capsys)[0] in (0, 1, 2)


def test_real_process_exit_codes(d):
    """The installed entry point as a user runs it: exit codes and stderr, argparse's usage error included."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, PYTHONPATH=str(ROOT))
    for argv, code, name in ((["path", str(d / "arc_r.nc")], 1, "0x0259"),
                             (["run", str(d / "ok.nc"), "--bench", str(d / "bad.toml")], 2, "not valid TOML"),
                             (["run", str(d / "ok.nc"), "--m00-resume", "soon"], 2, "invalid float value")):
        p = subprocess.run([sys.executable, "-m", "hil.cli", *argv], capture_output=True, text=True, env=env,
                           timeout=60)
        assert p.returncode == code and name in p.stderr and "Traceback" not in p.stderr + p.stdout, p.stderr
