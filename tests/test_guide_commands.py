"""Every shell command in docs/guide/*.md runs as the guide says.

Each page runs in its own temp folder holding the shipped benches/ and examples/ (`hil examples .`)
and tests/ (for the campaign data). Its ```sh/```bash blocks run in page order as bash scripts
(`set -e`), with `hil` resolving to this checkout. HTML comments right before a fence steer it,
and are invisible to the reader:

  <!-- guide-test: exit N -->      the block (one command) exits N (default 0)
  <!-- guide-test: output -->      this plain block quotes the previous command's output: each of
                                   its lines (but "..."/"…") must appear in it, spaces squeezed
  <!-- guide-test: file NAME -->   this plain block is a file the reader writes: saved as NAME
  <!-- guide-test: setup CMD -->   run CMD first (a file the prose asks for, e.g. a copy of an example)
  <!-- guide-test: root -->        needs root (netns, veth, raw sockets): skipped otherwise
  <!-- guide-test: skip WHY -->    not run (installs software, opens a browser, needs other machines)
  <!-- guide-test: cleanup CMD -->  run CMD after the page, passed or failed (netns, veth)
  <!-- guide-test: slow -->        the page takes minutes: only with `-m slow` (deselected by default)

All of a page's blocks run in one bash (set -e), as in a reader's terminal.

Decisions: docs/decisions/bench-tools.md T4.
"""

from __future__ import annotations

import os
import re
import select
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
GUIDE = ROOT / "docs" / "guide"
FENCE = re.compile(r"((?:[ \t]*<!-- guide-test:[^\n]*?-->[ \t]*\n)*)[ \t]*```(\w*)[^\n]*\n(.*?)^[ \t]*```", re.S | re.M)
MARK = re.compile(r"<!-- guide-test: (\w+) ?(.*?) -->")


@dataclass
class Block:
    line: int
    lang: str
    text: str
    marks: dict[str, list[str]] = field(default_factory=dict)

    @property
    def runs(self) -> bool:
        return self.lang in ("sh", "bash")


def blocks(page: Path) -> list[Block]:
    text = page.read_text()
    out = []
    for m in FENCE.finditer(text):
        marks: dict[str, list[str]] = {}
        for k, v in MARK.findall(m.group(1)):
            marks.setdefault(k, []).append(v.strip())
        out.append(Block(text[:m.start(2)].count("\n") + 1, m.group(2), textwrap.dedent(m.group(3)), marks))
    return out


def _squeeze(s: str) -> str:
    return " ".join(s.split())


def pages() -> list:
    params = []
    for page in sorted(GUIDE.glob("*.md")):
        bs = blocks(page)
        if not any(b.runs for b in bs):
            continue
        slow = any("slow" in b.marks for b in bs)
        params.append(pytest.param(page.name, id=page.stem, marks=[pytest.mark.slow] if slow else []))
    return params


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    env["MPLBACKEND"] = "Agg"
    env.pop("HIL_PROGRESS", None)
    return env


class Shell:
    """One bash for the whole page, as a reader's terminal: a background job started in one block
    (`hil sim … &`) is still there for `kill %1` in a later one. `set -e`: a failing command ends the
    shell, and the block it was in is reported."""

    def __init__(self, cwd: Path, env: dict[str, str]) -> None:
        self.proc = subprocess.Popen(["bash"], cwd=cwd, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, start_new_session=True)
        self.n = 0
        self.send("set -e; exec 2>&1")

    def send(self, text: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(text.encode() + b"\n")
        self.proc.stdin.flush()

    def run(self, script: str, expect: int, timeout: float = 600.0) -> tuple[int | None, str]:
        """(exit code, output); exit None when the shell died (set -e: a command failed)."""
        self.n += 1
        end = f"__guide_block_{self.n}_rc="
        if expect:
            self.send(f"set +e\n{script}\n__rc=$?; set -e; echo {end}$__rc")
        else:
            self.send(f"{script}\necho {end}0")
        out, deadline = b"", time.monotonic() + timeout
        fd = self.proc.stdout.fileno()  # type: ignore[union-attr]
        while time.monotonic() < deadline:
            if not select.select([fd], [], [], 1.0)[0]:
                if self.proc.poll() is not None:  # the shell died; a background job may hold the pipe
                    return None, out.decode(errors="replace")
                continue
            chunk = os.read(fd, 65536)
            if not chunk:
                return None, out.decode(errors="replace")
            out += chunk
            text = out.decode(errors="replace")
            if (k := text.find(end)) >= 0 and "\n" in text[k:]:
                rc = int(text[k + len(end):].split("\n", 1)[0])
                return rc, text[:k]
        raise TimeoutError(f"block ran past {timeout:.0f} s:\n{out.decode(errors='replace')[-2000:]}")

    def close(self) -> None:
        try:
            os.killpg(self.proc.pid, signal.SIGTERM)  # the shell and the jobs it started, nothing else
        except ProcessLookupError:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()


@pytest.mark.parametrize("name", pages())
def test_guide_page_commands(name, tmp_path):
    work = tmp_path / "w"
    work.mkdir()
    env = _env()
    r = subprocess.run([sys.executable, "-m", "hil.cli", "examples", "."], cwd=work, env=env, capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    shutil.copytree(ROOT / "tests" / "data", work / "tests" / "data")
    page = blocks(GUIDE / name)
    cleanup = [c for b in page for c in b.marks.get("cleanup", [])]
    shell = Shell(work, env)
    last, ran = "", 0
    try:
        for b in page:
            where = f"docs/guide/{name}:{b.line}"
            if "skip" in b.marks or ("root" in b.marks and os.geteuid() != 0):
                continue
            if "file" in b.marks:
                (work / b.marks["file"][0]).write_text(b.text)
                continue
            if "output" in b.marks:
                got = _squeeze(last)
                for want in b.text.splitlines():
                    if want.strip() and want.strip() not in ("...", "…"):
                        assert _squeeze(want) in got, \
                            f"{where}: the guide quotes {want.strip()!r}; the command printed:\n{last}"
                continue
            if not b.runs:
                continue
            want = int(b.marks.get("exit", ["0"])[0])
            rc, last = shell.run("\n".join([*b.marks.get("setup", []), b.text]), want)
            assert rc is not None, f"{where}: a command failed (set -e)\n{last[-3000:]}"
            assert rc == want, f"{where}: exit {rc}, the guide says {want}\n{last[-3000:]}"
            assert "Traceback" not in last, f"{where}:\n{last[-3000:]}"
            ran += 1
    finally:
        shell.close()
        for c in cleanup:
            subprocess.run(["bash", "-c", c], cwd=work, env=env, capture_output=True, timeout=60)
    if not ran:
        pytest.skip(f"{name}: every command needs root or real hardware (see its guide-test marks)")
