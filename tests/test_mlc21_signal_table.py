"""docs/mlc_signals.md (the App. B.2 audit table) cannot drift: every row of mlc/signals.py has a status line in
mlc/signal_status.py and none more, the files it names exist, every device on the page resolves to the same
address through the device map an MLC uses (`mlc.signals.resolve`), the decisions it cites are recorded, and the
page is what docs/build_mlc_signals.py renders now."""

from __future__ import annotations

import re
import runpy

from mlc.signal_status import STATUS, STATUSES, TESTS, key
from mlc.signals import ROWS, resolve, signal_table
from tests.conftest import ROOT


def test_every_app_b_row_has_one_status_line_and_no_line_is_left_over():
    keys = {key(r) for r in ROWS}
    assert keys == set(STATUS), (sorted(keys - set(STATUS)), sorted(set(STATUS) - keys))
    assert {s.status for s in STATUS.values()} <= set(STATUSES)


def test_the_files_named_as_where_exist_and_only_absent_or_hardware_rows_name_none():
    for s in STATUS.values():
        if s.status in ("absent", "hardware"):
            assert s.where == "-", s
        else:
            assert (ROOT / s.where).is_file(), s


def test_every_row_resolves_by_name_to_its_channel_1_address():
    table = signal_table((1,))
    for row in ROWS:
        x = 0 if row.general else 1
        address = f"{row.kind}{row.direction * 10000 + 1000 * x + row.index}"
        assert address in table
        sig = resolve(table[address].name, 1)
        assert sig.address == address, (row.name, sig.address, address)


def _words(text: str) -> set[str]:
    """A file's words and each word's heads before an underscore (``JOG_FWD_X`` gives ``JOG_FWD`` too)."""
    out = set()
    for w in set(re.findall(r"\w+", text)):
        out.add(w)
        i = w.find("_", 1)
        while i > 0:
            out.add(w[:i])
            i = w.find("_", i + 1)
    return out


def test_every_cited_test_file_still_names_its_device():
    first = {}
    for row in ROWS:
        first.setdefault(key(row), row)
    assert set(TESTS) <= set(first)
    for k, stems in TESTS.items():
        row = first[k]
        x = 0 if row.general else 1
        forms = {f"{row.kind}{row.direction * 10000 + 1000 * x + row.index}",
                 f"{row.kind}{row.direction}{'0' if row.general else 'x'}{row.index:03d}", row.name}
        for stem in stems:
            path = ROOT / "tests" / f"test_{stem}.py"
            assert path.is_file() and forms & _words(path.read_text()), (k, stem)


def test_the_decisions_the_table_cites_are_recorded():
    text = (ROOT / "docs" / "decisions" / "mlc.md").read_text()
    cited = {m for s in STATUS.values() for m in re.findall(r"M2[12]-\d+", s.note)}
    assert cited
    for d in cited:
        assert f"**{d}" in text, d


def test_the_page_is_current():
    page = (ROOT / "docs" / "mlc_signals.md").read_text()
    assert page == runpy.run_path(str(ROOT / "docs" / "build_mlc_signals.py"))["render"](), "docs/mlc_signals.md is stale: run python docs/build_mlc_signals.py"
