"""A campaign case whose fault never fired is `not_triggered`, not `completed` (decision B88): the case was there to
test that fault, and `hil run` exits 3 for the same never-triggered event."""

from __future__ import annotations

from pathlib import Path

from hil.campaign.inputs import CaseInputs
from hil.campaign.matrix_html import COLOURS
from hil.campaign.results import STATUSES
from hil.campaign.worker import run_case
from tests.conftest import ROOT

BENCH = ROOT / "benches" / "mill-3axis.toml"


def _case(tmp_path: Path, events: tuple[str, ...]) -> dict:
    prog = tmp_path / "p.nc"
    prog.write_text("G01 X10. F600\nG01 X0.\nM30\n")
    case = CaseInputs(key={"program": "p.nc", "bench": "mill-3axis.toml", "fault": "f"},
                      files=((str(prog), prog.read_bytes()), (str(BENCH), BENCH.read_bytes())),
                      program=str(prog), bench=str(BENCH), events=events)
    return run_case(case)


def test_a_fault_that_never_fired_is_not_triggered(tmp_path):
    row = _case(tmp_path, ("line=99:feed-hold",))
    assert row["status"] == "not_triggered"
    assert row["message"] == "never triggered: line=99:feed-hold"
    assert not row.get("alarm")


def test_a_fault_that_fired_leaves_the_case_completed(tmp_path):
    row = _case(tmp_path, ("line=2:feed-hold", "t=1.5:cycle-start"))
    assert row["status"] == "completed" and not row.get("message")


def test_the_status_is_known_to_the_results_and_the_matrix():
    assert "not_triggered" in STATUSES and "not_triggered" in COLOURS
