"""Machine-readable results of a run: the `hil run --json` object and JUnit XML (`--junit FILE`),
both built from the library's `hil.api.Result`, so the CLI, the pytest plugin and scripts agree.

Exit codes (README): 0 completed and every check passed; 1 ended by an alarm; 3 completed but a
check failed (an `--at` event that never fired counts as a failed check unless allowed);
128 + n when signal n stopped the run under control (130 SIGINT, 143 SIGTERM, 129 SIGHUP, 131 SIGQUIT).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from hil.strict_json import finite

EXIT_OK, EXIT_ALARM, EXIT_CHECKS = 0, 1, 3


def verdict(result: Any, allow_unfired: bool = False) -> tuple[str, int]:
    """("completed" | "alarm" | "checks_failed" | "stopped", exit code)."""
    stopped_by = getattr(result.run, "stopped_by", None)
    if stopped_by:  # a signal's controlled stop: 128 + the signal's number (130 SIGINT, 143 SIGTERM)
        from hil.stop_signals import exit_code

        return "stopped", exit_code(stopped_by)
    if not result.completed:
        return "alarm", EXIT_ALARM
    if not result.checks_ok or (result.unfired and not allow_unfired):
        return "checks_failed", EXIT_CHECKS
    return "completed", EXIT_OK


def as_dict(result: Any, allow_unfired: bool = False) -> dict[str, Any]:
    status, code = verdict(result, allow_unfired)
    bench = result.bench
    applied = sorted((e for e in result.events if e.fired_cycle is not None), key=lambda e: e.fired_cycle)
    return finite({
        "result": status, "exit_code": code, "stopped_by": getattr(result.run, "stopped_by", None),
        "program": result.program,
        "bench": {"name": bench.name, "source": bench.source, "profile": bench.profile, "bus": bench.bus,
                  "cycle_s": bench.cycle},
        "alarms": [a.as_dict() for a in result.alarms],
        "warnings": [w.as_dict() for w in getattr(result, "warnings", ())],
        "checks": [c.as_dict() for c in result.checks],
        "events": {"applied": [{"spec": e.spec, "t": e.fired_time, "cycle": e.fired_cycle, "line": e.fired_line,
                                "action": str(e.action)} for e in applied],
                   "never_fired": [e.spec for e in result.unfired]},
        "power_up_fault_resets": [{"drive": a, "error_code": c}
                                  for a, c in getattr(result.run, "power_up_resets", ())],
        "fitted_windows": _fits(getattr(result.run, "fits_ahead", None)),
        "param_groups": [{"line": line, "group": n} for line, n in getattr(result.run, "param_groups", ())],
        "program_time_s": result.program_time, "sim_time_s": result.sim_time, "cycles": result.cycles,
        "max_following_error": result.max_following_error, "final_position": result.final_position,
        "trace": str(result.trace.path) if result.trace is not None else None,
    })


def _fits(fits: tuple[int, int] | None) -> dict[str, int] | None:
    """B86: a real-time run's fitted windows, by where they were worked out (None: no second process)."""
    return None if fits is None else {"ahead": fits[0], "in_cycle": fits[1]}


def to_json(result: Any, allow_unfired: bool = False) -> str:
    return json.dumps(as_dict(result, allow_unfired), allow_nan=False)


def junit_xml(result: Any, allow_unfired: bool = False) -> bytes:
    """One test suite per run: a test case "run" (fails on an alarm), one per check (skipped checks
    are <skipped/>), and one "events" case when the run had --at events."""
    import xml.etree.ElementTree as ET  # (--junit's alone: ≈ 3 ms of every run's start otherwise, bench B91)

    name = f"hil run {Path(result.program).name}"
    suite = ET.Element("testsuite", name=name, time=f"{result.sim_time:.6f}")
    cases = []
    run = ET.Element("testcase", classname=name, name="run", time=f"{result.program_time:.6f}")
    if result.alarms:
        a = result.alarms[0]
        f = ET.SubElement(run, "failure", type=a.code_text, message=a.message)
        f.text = "\n".join(str(x) for x in result.alarms)
    cases.append(run)
    for c in result.checks:
        tc = ET.Element("testcase", classname=name, name=c.name, time="0")
        if c.skipped:
            ET.SubElement(tc, "skipped", message=c.detail)
        elif not c.ok:
            ET.SubElement(tc, "failure", type="check", message=str(c))
        cases.append(tc)
    if result.events:
        tc = ET.Element("testcase", classname=name, name="events", time="0")
        if result.unfired and not allow_unfired:
            ET.SubElement(tc, "failure", type="never fired",
                          message="; ".join(e.spec for e in result.unfired))
        cases.append(tc)
    suite.extend(cases)
    suite.set("tests", str(len(cases)))
    suite.set("failures", str(sum(tc.find("failure") is not None for tc in cases)))
    suite.set("skipped", str(sum(tc.find("skipped") is not None for tc in cases)))
    suite.set("errors", "0")
    return ET.tostring(ET.ElementTree(suite).getroot(), encoding="utf-8", xml_declaration=True)


def write_atomic(path: str | Path, data: bytes) -> None:
    """The previous complete file or the new one, never half of one; no temporary file left."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)
