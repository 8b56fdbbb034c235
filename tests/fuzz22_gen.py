"""Seeded faults from every side of `hil run` / `hil check` / `hil campaign`, as a user meets them (session 21, fuzz22).

`case(seed, kind, d)` writes the files of one case under `d` and returns the command line; `judge` runs it in a
subprocess and checks what a user would (README "Exit codes"): a documented exit code, no Python traceback, a
message naming what was wrong, a summary for every run that started, and a trace either complete (Parquet that
reads, with its end record) or absent — never a truncated file or a temporary left beside it.
"""
from __future__ import annotations

import os
import random
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MILL = ROOT / "benches" / "mill-3axis.toml"
PROGRAM = "G00 X10. Y10.\nG01 Z-1. F3000.\nX20. Y-5.\nG02 X0. Y-5. R10.\nG00 Z30.\nM30\n"
EXIT_CODES = {0, 1, 2, 3, 130, 143}
# root with unshare: a tiny or read-only tmpfs in a private mount namespace (nothing to clean up afterwards)
MOUNTS = os.geteuid() == 0 and shutil.which("unshare") is not None
GOOD: list[Path] = []  # a complete trace of PROGRAM on the mill, made once by `prepare`
KINDS = ("bench", "program", "at", "trace", "check", "campaign")


@dataclass
class Case:
    kind: str
    argv: list[str]
    trace: Path | None = None
    note: str = ""
    signal_after: float | None = None  # seconds after start; SIGINT or SIGTERM
    signum: int = signal.SIGINT
    files: list[Path] = field(default_factory=list)
    rc: int | None = None  # set by `judge`
    output: str = ""


def _hil(*args: str) -> list[str]:
    return [sys.executable, "-m", "hil.cli", *args]


# ---- bench files: one mutation of the shipped mill, written as TOML text (no writer library needed)
_BENCH_EDITS = [
    ("wrong type", 'lead = 10.0', 'lead = "ten"'),
    ("wrong type", 'cycle_ms = 1.0', 'cycle_ms = "1"'),
    ("wrong type", 'soft_limits = [-300.0, 300.0]', 'soft_limits = "wide"'),
    ("wrong type", 'limits = { velocity = 500.0,', 'limits = { velocity = [500.0],'),
    ("negative limit", 'velocity = 500.0', 'velocity = -500.0'),
    ("negative limit", 'acceleration = 3000.0', 'acceleration = -1.0'),
    ("zero limit", 'jerk = 250000.0', 'jerk = 0.0'),
    ("nan", 'velocity = 300.0', 'velocity = nan'),
    ("inf", 'lead = 10.0', 'lead = inf'),
    ("reversed soft limits", 'soft_limits = [-200.0, 200.0]', 'soft_limits = [200.0, -200.0]'),
    ("short soft limits", 'soft_limits = [-150.0, 150.0]', 'soft_limits = [-150.0]'),
    ("unknown key", 'name = "mill-3axis"', 'name = "mill-3axis"\nfeedrate_magic = 3'),
    ("unknown axis key", 'start = 100.0', 'start = 100.0\nstrat = 1.0'),
    ("unknown section", '[checks]', '[chekcs]\nx = 1\n[checks]'),
    ("duplicate axis", 'name = "Y"', 'name = "X"'),
    ("missing axis name", 'name = "Z"\n', ''),
    ("unknown axis name", 'name = "Y"', 'name = "Q"'),
    ("no axes", '[[axes]]', '[[axez]]'),
    ("bad profile", 'profile = "nc5-mill"', 'profile = "nc5-drill"'),
    ("bad bus", 'bus = "sim"', 'bus = "simulated"'),
    ("bad mlc", 'mlc = "basic"', 'mlc = "no_such_mlc_module"'),
    ("zero cycle", 'cycle_ms = 1.0', 'cycle_ms = 0.0'),
    ("huge cycle", 'cycle_ms = 1.0', 'cycle_ms = 1e300'),
    ("bad ratio", 'ratio = [2, 1]', 'ratio = [2, 0]'),
    ("negative counts", 'counts_per_rev = 1280000', 'counts_per_rev = -5'),
    ("bad drive model", 'model = "asda-a3"', 'model = "asda-z9"'),
    ("negative check", 'max_following_error = 0.1', 'max_following_error = -0.1'),
    ("negative rpm", 'max_rpm = 12000.0', 'max_rpm = -1.0'),
    ("duplicate key", 'lead = 10.0', 'lead = 10.0\nlead = 5.0'),
    ("bad toml", '[checks]', '[checks'),
    ("start outside soft limits", 'start = 100.0', 'start = 400.0'),
]


def bench_case(r: random.Random, d: Path) -> Case:
    text = MILL.read_text()
    edits = r.sample(_BENCH_EDITS, r.choice((1, 1, 2)))
    notes = []
    for note, old, new in edits:
        if old in text:
            text = text.replace(old, new, 1)
            notes.append(note)
    bench = d / "bench.toml"
    bench.write_text(text)
    prog = d / "p.nc"
    prog.write_text(PROGRAM)
    trace = d / "t.parquet"
    cmd = r.choice(("run", "run", "check"))
    if cmd == "check":  # a good trace judged against the broken bench
        return Case("bench", _hil("check", str(GOOD[0]), "--bench", str(bench)),
                    None, "; ".join(notes))
    return Case("bench", _hil("run", str(prog), "--bench", str(bench), "--trace", str(trace)), trace, "; ".join(notes))


# ---- program files that are not text a user meant to write
def program_case(r: random.Random, d: Path) -> Case:
    prog = d / r.choice(("p.nc", "p", "p.NC"))
    kind = r.choice(("binary", "empty", "huge line", "latin-1", "utf-16", "nul", "cr only", "many lines", "bom",
                     "no newline", "directory", "missing", "unreadable"))
    if kind == "binary":
        prog.write_bytes(bytes(r.randrange(256) for _ in range(r.choice((16, 300, 5000)))))
    elif kind == "empty":
        prog.write_bytes(b"")
    elif kind == "huge line":
        prog.write_text("G00 X1." + " " * r.choice((10_000, 1_000_000)) + "Y2.\nG01 X" + "1" * 200_000 + ". F100.\nM30\n")
    elif kind == "latin-1":
        prog.write_bytes("(Stückzahl \xb5m)\nG00 X1.\nM30\n".encode("latin-1"))
    elif kind == "utf-16":
        prog.write_bytes(PROGRAM.encode("utf-16"))
    elif kind == "nul":
        prog.write_bytes(b"G00 X1.\x00 Y2.\nM30\n")
    elif kind == "cr only":
        prog.write_bytes(PROGRAM.replace("\n", "\r").encode())
    elif kind == "many lines":
        prog.write_text("G00 X1.\n" * 200_000 + "M30\n")
    elif kind == "bom":
        prog.write_bytes(b"\xef\xbb\xbf" + PROGRAM.encode())
    elif kind == "no newline":
        prog.write_text(PROGRAM.rstrip("\n"))
    elif kind == "directory":
        prog.mkdir()
    elif kind == "unreadable":
        prog.write_text(PROGRAM)
        prog.chmod(0)
    trace = d / "t.parquet"
    return Case("program", _hil("run", str(prog), "--bench", str(MILL), "--trace", str(trace), "--max-time", "20"),
                trace, kind)


# ---- --at event strings
_AT_GOOD = ["t=0.5:feed-hold", "line=3:set D21002=50", "Z<-0.5:pulse M21019", "t=0.2:reset", "t=0.3:estop"]
_AT_BAD = ["", ":", "t=:feed-hold", "t=abc:feed-hold", "t=-1:feed-hold", "t=nan:feed-hold", "t=inf:reset",
           "t=1e400:reset", "line=:reset", "line=1.5:reset", "line=-3:reset", "Q<5:reset", "Z<<5:reset",
           "Z<abc:reset", "t=1:", "t=1:explode", "t=1:set", "t=1:set D21002", "t=1:set D21002=", "t=1:set D21002=x",
           "t=1:set M99999999=1", "t=1:set D-1=5", "t=1:pulse", "t=1:pulse M", "t=1:set X=1", "t=1:set D21002=1e400",
           "t=1:feed-hold extra", "t=1:set D21002=50:more", "t=\u0661:reset", "t=1:set D21002=\u0665",
           "t=0.1:feed-hold;t=0.2:reset", "line=99999999999999999999:reset", "t=1 :reset", "T=1:reset"]


def at_case(r: random.Random, d: Path) -> Case:
    prog = d / "p.nc"
    prog.write_text(PROGRAM)
    trace = d / "t.parquet"
    args = []
    for _ in range(r.choice((1, 1, 2))):
        at = r.choice(_AT_BAD) if r.random() < 0.8 else r.choice(_AT_GOOD)
        args += ["--at", at]
    return Case("at", _hil("run", str(prog), "--bench", str(MILL), "--trace", str(trace), *args), trace,
                " ".join(args))


# ---- trace paths that cannot be written, and signals in the middle of a run
def trace_case(r: random.Random, d: Path) -> Case:
    prog = d / "p.nc"
    prog.write_text(PROGRAM)
    kinds = ["read-only dir", "missing dir", "is a directory", "file as parent", "csv", "signal", "signal", "signal",
             "existing trace", "dev-null"]
    if MOUNTS:
        kinds += ["disk full", "disk full", "read-only fs"]
    kind = r.choice(kinds)
    trace = d / "t.parquet"
    c = Case("trace", [], trace, kind)
    if kind == "read-only dir":
        ro = d / "ro"
        ro.mkdir()
        ro.chmod(0o555)
        trace = ro / "t.parquet"
    elif kind == "missing dir":
        trace = d / "no" / "such" / "t.parquet"
    elif kind == "is a directory":
        trace.mkdir()
    elif kind == "file as parent":
        (d / "f").write_text("x")
        trace = d / "f" / "t.parquet"
    elif kind == "csv":
        trace = d / "t.csv"
    elif kind == "existing trace":
        trace.write_bytes(b"PAR1 not really")
    elif kind == "dev-null":
        trace = Path("/dev/null")
    elif kind == "signal":
        c.signal_after = r.uniform(0.3, 3.0)
        c.signum = r.choice((signal.SIGINT, signal.SIGTERM))
        # ≈ 1,100 s simulated: still running when the signal comes at ≤ 3 s at any speed the cycle reaches (its
        # one pass, 170 s, ended after 1.8 s once the planner was compiled, B115: the signal then hit the exit)
        prog.write_text("G00 X10. Y10.\nG01 Z-1. F300.\n" + "X200. Y-50.\nX-200.\nY100.\n" * 6 + "G00 Z30.\nM30\n")
        c.note = f"{signal.Signals(c.signum).name} after {c.signal_after:.2f} s"
    c.argv = _hil("run", str(prog), "--bench", str(MILL), "--trace", str(trace))
    c.trace = None if kind == "dev-null" else trace
    if kind in ("disk full", "read-only fs"):  # a tmpfs in a private mount namespace: gone when the run ends
        mnt = d / "mnt"
        mnt.mkdir()
        opts = f"size={r.choice((8, 64, 200))}k" if kind == "disk full" else "ro"
        c.trace = mnt / "t.parquet"
        run = " ".join(shlex.quote(a) for a in _hil("run", str(prog), "--bench", str(MILL), "--trace", str(c.trace)))
        c.argv = ["unshare", "-m", "sh", "-c", f"mount -t tmpfs -o {opts} fuzz22 {shlex.quote(str(mnt))} && "
                  f"{{ {run}; rc=$?; cp {shlex.quote(str(c.trace))} {shlex.quote(str(d / 'copy.parquet'))} 2>/dev/null; "
                  f"echo LEFT:$(ls -A {shlex.quote(str(mnt))} | grep -vx t.parquet); exit $rc; }}"]
        c.trace = d / "copy.parquet"  # what was on the small disk when the run ended: judged whole or absent
        c.note = f"{kind} ({opts})"
    return c


# ---- hil check on damaged traces
def check_case(r: random.Random, d: Path) -> Case:
    good = GOOD[0].read_bytes()
    kind = r.choice(("cut", "flip", "empty", "text", "csv junk", "good with bad bench arg", "missing"))
    t = d / ("t.parquet" if kind in ("cut", "flip", "good with bad bench arg") else r.choice(("t.csv", "t.pq")))
    if kind == "cut":
        t.write_bytes(good[: r.randrange(len(good))])
    elif kind == "flip":
        b = bytearray(good)
        for _ in range(r.choice((1, 10))):
            b[r.randrange(len(b))] ^= 1 << r.randrange(8)
        t.write_bytes(bytes(b))
    elif kind == "empty":
        t.write_bytes(b"")
    elif kind == "text":
        t.write_text("t,line,X_cmd\n0,1,abc\n")
    elif kind == "csv junk":
        t.write_bytes(bytes(r.randrange(256) for _ in range(400)))
    elif kind == "good with bad bench arg":
        t.write_bytes(good)
        return Case("check", _hil("check", str(t), "--bench", str(d / "nope.toml")), None, kind)
    args = ["--max-ferr", r.choice(("0.1", "-1", "nan", "abc"))] if r.random() < 0.5 else ["--bench", str(MILL)]
    return Case("check", _hil("check", str(t), *args), None, kind)


# ---- campaign files
_CAMPAIGNS = [
    "",
    "not toml [",
    '[campaign]\nname = "c"\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\n',
    '[campaign]\nprograms = []\nbenches = ["{bench}"]\n',
    '[campaign]\nprograms = ["{d}/missing*.nc"]\nbenches = ["{bench}"]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = 5\n',
    '[campaign]\nprograms = "{prog}"\nbenches = ["{bench}"]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{d}/bad.toml"]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\noverrides = [-10, "x"]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\noverrides = [0]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\nmax_time = -1\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\nmax_time = 0.05\ntrace = true\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\nretries = -1\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\nbuses = ["nonsense"]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\nfaults = ["nosuch"]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\nfaults = ["f"]\n[faults]\nf = ["{at}"]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\nfaults = ["f"]\ntrace = true\n[faults]\nf = ["{good_at}"]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\n[params]\n"N1.053" = ["x", -1e300]\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\n[checks]\nmax_following_error = -1\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\n[[case]]\nprogram = "{d}/nope.nc"\n',
    '[campaign]\nprograms = ["{prog}"]\nbenches = ["{bench}"]\nmystery = 1\n',
]


def campaign_case(r: random.Random, d: Path) -> Case:
    prog = d / "p.nc"
    prog.write_text(PROGRAM)
    (d / "bad.toml").write_text(MILL.read_text().replace("lead = 10.0", "lead = -1.0", 1))
    text = r.choice(_CAMPAIGNS).format(bench=MILL, prog=prog, d=d, at=r.choice(_AT_BAD), good_at=r.choice(_AT_GOOD))
    f = d / "c.toml"
    f.write_text(text)
    out = d / "out"
    return Case("campaign", _hil("campaign", str(f), "--out", str(out), "--workers", "0", "--quiet",
                                 "--no-reports"), None, text.replace("\n", " | ")[-90:])


_MAKERS = {"bench": bench_case, "program": program_case, "at": at_case, "trace": trace_case, "check": check_case,
           "campaign": campaign_case}


def prepare(d: Path) -> Path:
    """Run PROGRAM once for the trace `hil check` cases damage."""
    d.mkdir(parents=True, exist_ok=True)
    prog, t = d / "good.nc", d / "good.parquet"
    prog.write_text(PROGRAM)
    subprocess.run(_hil("run", str(prog), "--bench", str(MILL), "--trace", str(t)), check=True, cwd=ROOT,
                   env=dict(os.environ, PYTHONPATH=str(ROOT)), stdout=subprocess.DEVNULL)
    GOOD[:] = [t]
    return t


def case(seed: int, kind: str, d: Path) -> Case:
    return _MAKERS[kind](random.Random(f"{kind}-{seed}"), d)


def judge(c: Case, timeout: float = 120.0) -> list[str]:
    """Run the case; return what a user would call wrong (empty: it ended as documented)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONHASHSEED="0")
    p = subprocess.Popen(c.argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=ROOT,
                         start_new_session=True)
    if c.signal_after is not None:
        time.sleep(c.signal_after)
        if p.poll() is None:
            p.send_signal(c.signum)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        out, err = p.communicate()
        return [f"hung for {timeout} s"]
    text = out.decode(errors="replace") + err.decode(errors="replace")
    c.rc, c.output = p.returncode, text
    bad = []
    if "Traceback (most recent call last)" in text:
        bad.append("traceback: " + text[text.index("Traceback"):][-600:])
    if "0x0000" in text:  # App. A has no 0x0000: deltahil's "NC internal error" is a bug as a traceback is
        bad.append("internal error: " + text[text.index("0x0000"):][:300])
    if p.returncode not in EXIT_CODES:
        bad.append(f"exit code {p.returncode}")
    if p.returncode != 0 and not err.strip() and "result" not in out.decode(errors="replace"):
        bad.append("non-zero exit with no message")
    left = re.search(r"^LEFT:(.*)$", out.decode(errors="replace"), re.M)
    if left and left.group(1).strip():  # beside the trace on a full/read-only disk: nothing
        bad.append(f"left on the small filesystem: {left.group(1).strip()}")
    if "run" in c.argv[:4] and p.returncode in (0, 1, 3, 130, 143) and "program" in out.decode(errors="replace")[:200]:
        if not re.search(r"^result ", out.decode(errors="replace"), re.M):
            bad.append("a started run printed no result line")
    if c.trace is not None and c.trace.suffix == ".parquet" and not c.trace.is_dir():
        bad += _trace_state(c.trace)
    if c.kind == "campaign":  # every trace a campaign kept reads whole
        out_dir = Path(c.argv[c.argv.index("--out") + 1])
        for t in sorted(out_dir.rglob("*.parquet")) if out_dir.is_dir() else []:
            bad += _trace_state(t)
    if c.trace is not None and c.trace.parent.is_dir():
        left = [q.name for q in c.trace.parent.iterdir() if q.name.startswith(".") or q.name.endswith((".tmp", ".part"))]
        if left:
            bad.append(f"temporary files left: {left}")
    return bad


def _trace_state(t: Path) -> list[str]:
    if not t.exists():
        return []
    import pyarrow.parquet as pq
    try:
        tab = pq.read_table(t)
    except Exception as e:  # noqa: BLE001 - any failure to read is what we look for
        if t.read_bytes()[:4] == b"PAR1" and t.stat().st_size > 20:
            return [f"trace {t.name} does not read: {e}"]
        return []  # a file the case put there itself (not Parquet) and hil refused to overwrite or left alone
    if tab.num_rows == 0:
        return ["trace has no rows"]
    return []
