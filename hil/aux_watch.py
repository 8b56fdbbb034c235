"""A warning when the NC has strobed an M, S or T code (M3x064/M3x065/M3x066) and the MLC has not
answered with M2x016 "M, S and T codes finished" within `timeout_s` of simulated time.

Delta's NC waits for the finish as long as it takes (App. B.2.1.1 documents no time-out; the MLC
programmer owns the handshake), so deltahil does the same and raises no alarm: the run keeps
waiting until the MLC answers, an operator stops it or max_time (0xDE03) ends it. What a controller
engineer needs is to be told, once per code, while it waits: a line on stderr when it happens, the
list in the run's summary, in `--json` ("warnings") and in the trace's end record.

It rides on the runner's per-cycle `progress` hook (after the cycle's trace row), wrapping any
progress bar, so the cyclic path gains one attribute read per cycle."""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import IO, Any

from nc.channel import RunState

# the channel's states after the MLC's finish released the code (an alarm or reset flushes it instead)
ANSWERED = (RunState.RUNNING, RunState.WAIT_AUX, RunState.HOLD, RunState.BLOCK_STOP, RunState.FINISHED)
AUX_TIMEOUT_S = 5.0  # simulated seconds; decision T7 in docs/decisions/bench-tools.md


@dataclass
class AuxWarning:
    code: str  # "M03", "S600", "T0101"
    line: int
    block: str
    t: float  # simulated time of the strobe, s
    waited_s: float  # how long it had waited when the warning was raised
    answered_t: float | None = None  # when the MLC finally answered, if it did

    @property
    def text(self) -> str:
        tail = (f"; answered at t={self.answered_t:.3f} s" if self.answered_t is not None
                else "; never answered")
        return (f"warning: {self.code} (line {self.line}: {self.block.strip()}) strobed at t={self.t:.3f} s, "
                f"no MLC finish (M2x016) after {self.waited_s:g} s{tail}")

    def as_dict(self) -> dict[str, Any]:
        return {"kind": "aux_no_finish", "code": self.code, "line": self.line, "block": self.block.strip(),
                "t": self.t, "waited_s": self.waited_s, "answered_t": self.answered_t, "message": self.text}


def code_text(aux: Any) -> str:
    v = aux.value
    num = f"{int(v):02d}" if aux.kind == "M" and float(v).is_integer() else (f"{v:g}")
    return f"{aux.kind}{num}"


@dataclass
class AuxWatch:
    """The runner's `progress` hook: watches the pending M/S/T, then calls the wrapped progress."""

    timeout_s: float = AUX_TIMEOUT_S
    inner: Any = None
    stream: IO[str] | None = None
    warnings: list[AuxWarning] = field(default_factory=list)
    _aux: Any = None
    _since: float = 0.0
    _warned: AuxWarning | None = None

    def update(self, runner: Any) -> None:
        ch = runner.channel
        aux = ch.pending_aux if ch is not None and ch.state is RunState.WAIT_AUX else None
        if aux is not None and aux.kind == "M" and aux.value in (0, 1):
            aux = None  # M00/M01 are never strobed: they wait for the operator's Cycle Start, not for M2x016
        if aux is not self._aux:
            if self._warned is not None and ch.state in ANSWERED:  # not flushed by an alarm or reset
                self._warned.answered_t = round(runner.time, 9)
            self._aux, self._since, self._warned = aux, runner.time, None
        elif aux is not None and self._warned is None and runner.time - self._since >= self.timeout_s:
            w = AuxWarning(code_text(aux), aux.line, aux.block, round(self._since, 9), self.timeout_s)
            self._warned = w
            self.warnings.append(w)
            runner.warnings = self.warnings  # the trace's end record reads them
            print(w.text.replace("; never answered", ""), file=self.stream or sys.stderr, flush=True)
        if self.inner is not None:
            self.inner.update(runner)

    def close(self) -> None:
        if self.inner is not None:
            self.inner.close()
