"""`hil run --json`, `--junit FILE`, distinct exit codes for an alarm (1) and failed checks (3),
and `--at` events that never fire failing the run unless `--allow-unfired` (issue 22)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from hil.cli import main

ROOT = Path(__file__).resolve().parents[1]
LATHE = ROOT / "benches" / "lathe-2axis.toml"
TURN = ROOT / "tests" / "data" / "campaign" / "short_turn.nc"


def run(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(["run", *map(str, argv), "--no-progress"])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return rc, out, err


def test_json_is_one_strict_object_with_what_the_run_did(capsys, tmp_path):
    rc, out, err = run(capsys, TURN, "--bench", LATHE, "--json", "--trace", tmp_path / "t.parquet",
                       "--at", "t=0.2:set FEED_OVERRIDE=80")
    assert rc == 0
    d = json.loads(out)  # stdout holds the JSON object only; the text summary went to stderr
    assert d["result"] == "completed" and d["exit_code"] == 0 and d["alarms"] == []
    assert d["bench"]["name"] == "lathe-2axis" and d["cycles"] > 0 and d["program_time_s"] > 0.3
    assert set(d["max_following_error"]) == {"X", "Z"} and d["final_position"]["X"] == pytest.approx(30.0)  # X60. is a diameter: radius 30
    assert [c["check"] for c in d["checks"]][:2] == ["following error X", "following error Z"]
    assert d["events"]["applied"][0]["spec"] == "t=0.2:set FEED_OVERRIDE=80" and d["events"]["never_fired"] == []
    assert d["trace"].endswith("t.parquet") and "program time" in err
    json.loads(out, parse_constant=lambda c: pytest.fail(f"{c} is not JSON"))


def test_alarm_exits_1_and_json_names_it(capsys, tmp_path):
    bad = tmp_path / "bad.nc"
    bad.write_text("G98\nG00 X58. Z98.\nG07.7 X1.\nM30\n")
    rc, out, _ = run(capsys, bad, "--bench", LATHE, "--json")
    d = json.loads(out)
    assert rc == 1 and d["result"] == "alarm" and d["exit_code"] == 1
    assert (d["alarms"][0]["code"], d["alarms"][0]["line"]) == ("0x021D", 3)


def test_failed_check_exits_3_and_junit_has_a_failure_per_failed_check(capsys, tmp_path):
    bench = tmp_path / "tight.toml"
    bench.write_text(LATHE.read_text().replace("max_following_error = { X = 0.1, Z = 0.1 }",
                                               "max_following_error = { X = 0.001, Z = 0.1 }"))
    junit = tmp_path / "r.xml"
    rc, out, _ = run(capsys, TURN, "--bench", bench, "--junit", junit)
    assert rc == 3 and "FAIL  following error X" in out
    suite = ET.parse(junit).getroot()
    cases = {tc.get("name"): tc for tc in suite.iter("testcase")}
    assert suite.get("tests") == str(len(cases)) and suite.get("failures") == "1"
    assert cases["run"].find("failure") is None
    assert cases["following error X"].find("failure") is not None
    assert cases["following error Z"].find("failure") is None
    assert not list(tmp_path.glob(".*tmp"))  # written atomically, no temporary left
    junitparser = pytest.importorskip("junitparser")  # as CI servers read it
    xml = junitparser.JUnitXml.fromfile(str(junit))
    suites = list(xml) if isinstance(xml, junitparser.JUnitXml) else [xml]
    results = {case.name: [type(r).__name__ for r in case.result] for s in suites for case in s}
    assert results["following error X"] == ["Failure"] and results["run"] == []


def test_an_event_that_never_fires_fails_the_run_unless_allowed(capsys):
    argv = (TURN, "--bench", LATHE, "--at", "t=99:feed-hold", "--json")
    rc, out, err = run(capsys, *argv)
    d = json.loads(out)
    assert rc == 3 and d["result"] == "checks_failed" and d["events"]["never_fired"] == ["t=99:feed-hold"]
    assert "never fired" in err
    rc, out, _ = run(capsys, *argv, "--allow-unfired")
    assert rc == 0 and json.loads(out)["result"] == "completed"
