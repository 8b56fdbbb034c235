"""Retentive # variables from run to run (`hil run --retain FILE`, hil/retentive.py): N§3.11.1 marks #2000-#3999
(retentive) and #4000-#11999 (extend) as kept through power-off, public #100-#999 not. A file that cannot be that
memory is App. A 0x140B 'Retentive # variable error'."""

from __future__ import annotations

import json

import pytest

import hil as hil_api

COUNTER = "#2000=#2000+1\n#4001=#2000*10\n#100=7\nG00 W-[#2000]\nM30\n"  # lathe A: Z moves back by the count


def test_a_part_counter_in_2000_counts_across_runs_and_public_variables_do_not(hil, program, tmp_path):
    store = tmp_path / "retain.json"
    prog = program(COUNTER)
    for _ in range(3):
        r = hil("run", prog, "--retain", store)
        assert r.code == 0, r.out + r.err
    assert json.loads(store.read_text()) == {"2000": 3.0, "4001": 30.0}  # #100 (public) is not kept


def test_the_retained_value_drives_the_next_run(tmp_path):
    store = tmp_path / "retain.json"
    store.write_text('{"2000": 4}')
    prog = tmp_path / "p.nc"
    prog.write_text(COUNTER)
    r = hil_api.run(prog, retain=store, check=False)
    assert r.alarms == [] and r.run.final["Z"] == pytest.approx(r.bench.axes[1].start - 5.0, abs=1e-3)
    assert json.loads(store.read_text())["2000"] == 5.0


@pytest.mark.parametrize("text, why", [("{\"2000\": 1", "cannot be read"), ("[1, 2]", "not a table"),
                                       ("{\"100\": 1}", "#100 is not a retentive variable"),
                                       ("{\"2000\": \"x\"}", "is not a number")],
                         ids=["truncated", "list", "public", "text"])
def test_0x140b_a_corrupt_retentive_store_stops_the_run_before_it_starts(hil, program, tmp_path, text, why):
    """App. A 0x140B 'Retentive # variable error. Controller malfunction': the run does not start (exit 1, no
    motion, no trace row) and the file is left as it was."""
    store = tmp_path / "retain.json"
    store.write_text(text)
    trace = tmp_path / "t.csv"
    r = hil("run", program(COUNTER), "--retain", store, "--trace", trace)
    assert r.code == 1 and "ALARM 0x140B" in r.out + r.err and why in r.out + r.err
    assert store.read_text() == text
    assert not trace.exists() or len(trace.read_text().splitlines()) <= 1


@pytest.mark.parametrize("where, why", [("missing/retain.json", "its folder does not exist"),
                                        ("a_dir", "is a folder, not a file")], ids=["no-folder", "folder"])
def test_a_retain_file_that_cannot_be_written_is_refused_before_the_run(hil, program, tmp_path, where, why):
    """A --retain FILE whose folder is missing ran the whole program and only then failed to save (0x140B after the
    axes had moved, the count lost): it is a bad option, refused before the drives are enabled (exit 2)."""
    (tmp_path / "a_dir").mkdir()
    trace = tmp_path / "t.csv"
    store = tmp_path / where
    r = hil("run", program(COUNTER), "--retain", store, "--trace", trace)
    assert r.code == 2 and f"--retain {store}: {why}" in r.err and "Traceback" not in r.err, r.out + r.err
    assert not trace.exists() and not (tmp_path / "missing").exists()
