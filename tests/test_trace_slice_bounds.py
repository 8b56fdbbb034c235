"""`hil trace --from/--to` that select nothing: exit 2 naming what the trace holds, no file written
(decisions B53; before, `wrote 0 rows` / `rows 0` with exit 0 and a header-only export)."""

from pathlib import Path

import pytest

from hil.cli import main

BENCHES = Path(__file__).resolve().parent.parent / "benches"
PROGRAM = "G98\nM03 S600\nG00 X24. Z2.\nG01 Z-3. F600.\nG02 X30. Z-6. R3.\nM30\n"


@pytest.fixture(scope="module")
def trace(tmp_path_factory):
    d = tmp_path_factory.mktemp("slice")
    prog = d / "p.nc"
    prog.write_text(PROGRAM)
    out = d / "run.csv"
    assert main(["run", str(prog), "--bench", str(BENCHES / "lathe-2axis.toml"), "--trace", str(out), "--no-check"]) == 0
    return out


@pytest.mark.parametrize("bounds, says", [
    (["--from", "60"], "--from 60 s selects no rows (the trace holds t 0.001 … "),
    (["--from", "L9"], "--from L9 selects no rows (the trace holds t 0.001 … "),
    (["--from", "0.5", "--to", "0.2"], "--from 0.5 s lies after --to 0.2 s: the slice is empty"),
    (["--from", "L5", "--to", "L4"], "--from L5 lies after --to L4: the slice is empty"),
])
@pytest.mark.parametrize("suffix", [None, ".csv", ".parquet"])
def test_a_slice_outside_the_trace_exits_2_and_writes_nothing(trace, tmp_path, capsys, bounds, says, suffix):
    out = tmp_path / f"slice{suffix}" if suffix else None
    args = ["trace", str(trace), *bounds] + (["--out", str(out)] if out else [])
    assert main(args) == 2
    cap = capsys.readouterr()
    assert says in cap.err and "Traceback" not in cap.err + cap.out
    if "selects no rows" in says:
        # the program's lines the user can slice by: the moves, M03 S600 while the spindle runs up and M30 while
        # the drives settle (an M/S/T block is the current line while the NC waits on it, decision B79)
        assert ", lines 2 … 6)" in cap.err
    assert "wrote" not in cap.out and "rows           0" not in cap.out
    if out is not None:
        assert sorted(p.name for p in tmp_path.iterdir()) == []  # neither the file nor its .part


def test_a_slice_inside_the_trace_still_exports(trace, tmp_path, capsys):
    out = tmp_path / "s.csv"
    assert main(["trace", str(trace), "--from", "L4", "--to", "L4", "--out", str(out)]) == 0
    rows = out.read_text().splitlines()[1:]
    assert rows and {r.split(",")[1] for r in rows} == {"4"}
