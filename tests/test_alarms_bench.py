"""NC5 start-up (kernel) alarms of App. A.2 that a bench file's configuration error corresponds to: `hil run`
refuses the bench before any cycle (exit 2, bad input, as the project's exit-code table says) and the message
names the field and the NC5 alarm the controller would show for the same setting (decisions bench.md B17).
"""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from hil.cli import main
from tests.conftest import ROOT

BASE = (ROOT / "benches" / "lathe-2axis.toml").read_text()
SPINDLE = '[[spindles]]\nname = "S1"'


@dataclass(frozen=True)
class BenchCase:
    code: str
    edit: tuple[str, str]  # (text of benches/lathe-2axis.toml, its replacement)
    field: str
    cite: str


BENCH_ALARM_CASES = [
    BenchCase("0x1419", (SPINDLE, '[[axes]]\nname = "Z"\nlead = 10.0\n\n' + SPINDLE), "axes[2].name",
              "App. A 0x1419 'NC axis number setting error': two axes configured as Z"),
    BenchCase("0x141A", (SPINDLE, SPINDLE + '\n\n[[spindles]]\nname = "S1"'), "spindles[1].name",
              "App. A 0x141A 'Spindle number setting error': two spindles numbered S1"),
    BenchCase("0x0C05", (SPINDLE, '[[axes]]\nname = "C"\nunits = "mm"\nlead = 360.0\n\n' + SPINDLE), "axes[2].units",
              "App. A 0x0C05 'The spindle C-axis is not set as rotational axis. Check the C axis setting of N2.001 "
              "bits 2 to 4 for the rotational axis feed mode': a C axis configured linear (mm)"),
    BenchCase("0x141C", (SPINDLE, '[[axes]]\nname = "A"\nlead = 360.0\n\n' + SPINDLE), "axes[2].units",
              "App. A 0x141C 'Setting error of the axis type': an A axis (rotary on the NC, N2.001 bits 2-4) "
              "configured linear (units default mm)"),
    BenchCase("0x1417", (SPINDLE, SPINDLE + '\n\n[[io]]\nname = "panel"\ncanopen_node = 2'), "io[0].canopen_node",
              "App. A 0x1417 'The slave address is duplicated': a remote I/O station on the CANopen node of the "
              "Z drive (drives are nodes 1-3)"),
]


@pytest.mark.parametrize("case", BENCH_ALARM_CASES, ids=[c.code for c in BENCH_ALARM_CASES])
def test_bench_setting_error_names_its_nc5_alarm(tmp_path, capsys, case: BenchCase):
    old, new = case.edit
    assert old in BASE
    bench = tmp_path / "b.toml"
    bench.write_text(BASE.replace(old, new, 1))
    prog = tmp_path / "p.nc"
    prog.write_text("G00 X10.\nM30\n")
    capsys.readouterr()
    assert main(["run", str(prog), "--bench", str(bench)]) == 2, case.cite
    err = capsys.readouterr().err
    line = next((ln for ln in err.splitlines() if f"{case.field}:" in ln), "")
    assert f"NC5 alarm {case.code}:" in line, (case.cite, err)
