"""docs/alarms.md is generated from the code and the tests, never stale; every NC5 App. A code is raised
by a test or its absence explained (docs/alarms-unraised.toml); explanations do not outlive the gap."""

from __future__ import annotations

import importlib.util
import sys

from tests.conftest import ROOT


def _builder():
    spec = importlib.util.spec_from_file_location("build_alarms", ROOT / "docs" / "build_alarms.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["build_alarms"] = mod  # its dataclass looks its module up
    spec.loader.exec_module(mod)
    return mod


def test_alarms_page_is_up_to_date():
    assert (ROOT / "docs" / "alarms.md").read_text() == _builder().build(), \
        "docs/alarms.md is stale: run python docs/build_alarms.py"


def test_every_appendix_a_code_is_raised_or_explained():
    b = _builder()
    raised, marks = b.raising_tests(), b.unraised()
    missing = sorted(f"0x{c:04X}" for c in b.ALARM_TABLE if c not in raised and c not in marks)
    assert not missing, f"App. A codes neither raised by a test nor in docs/alarms-unraised.toml: {missing}"
    stale = sorted(f"0x{c:04X}" for c in marks if c in raised)
    assert not stale, f"raised by a test now, drop from docs/alarms-unraised.toml: {stale}"
    unknown = sorted(f"0x{c:04X}" for c in marks if c not in b.ALARM_TABLE)
    assert not unknown, unknown
    assert all(m.status in ("not emulatable", "not modelled") and m.reason for m in marks.values())


def test_the_generator_sees_a_raise_and_ignores_a_negated_code(tmp_path):
    b = _builder()
    (tmp_path / "test_x.py").write_text(
        'def test_a():\n    assert r.alarm["code"] == "0x0203"\n'
        'def test_b():\n    assert r.alarm["code"] != "0x0204"\n    assert sii[0] == 0x0205\n')
    found = b.raising_tests(tmp_path)
    assert 0x0203 in found and 0x0204 not in found and 0x0205 not in found
