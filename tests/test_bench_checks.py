"""Each check fails on a crafted trace and names the offending cycle and line; CLI exit codes."""

from pathlib import Path

import numpy as np
import pytest

from hil.bench import ChecksConfig, default_lathe
from hil.checks import run_checks
from hil.cli import main
from hil.trace import CsvTrace, trace_columns
from hil.trace_read import TraceFile
from nc.moves import Move

N = 400


def base(n=N):
    t = np.arange(1, n + 1) * 0.001
    d = {"t": t, "line": np.full(n, 2), "cycle": np.arange(1, n + 1), "period": np.full(n, 0.001),
         "late": np.zeros(n), "alarm": [""] * n}
    for a in ("X", "Z"):
        for k in ("cmd", "act", "vel", "torque", "ferr"):
            d[f"{a}_{k}"] = np.zeros(n)
        d[f"{a}_sw"] = np.full(n, 0x1637)
    for k in ("rpm_cmd", "rpm_act", "angle", "torque"):
        d[f"S1_{k}"] = np.zeros(n)
    d["S1_sw"] = np.full(n, 0x1637)
    return d


def write(tmp_path, d, name="t.csv"):
    cols = trace_columns(["X", "Z"], ["S1"])
    w = CsvTrace(tmp_path / name, cols)
    for i in range(len(d["t"])):
        w.write([d[c][i].item() if hasattr(d[c][i], "item") else d[c][i] for c in cols])
    w.close()
    return TraceFile(tmp_path / name)


def only(results, name):
    (r,) = [r for r in results if r.name == name]
    return r


def test_following_error_names_cycle_and_line(tmp_path):
    d = base()
    d["line"][200:] = 7
    d["Z_ferr"][250] = -0.2
    d["Z_ferr"][251] = 0.08
    res = run_checks(write(tmp_path, d), ChecksConfig(max_following_error={"X": 0.1, "Z": 0.1}))
    assert only(res, "following error X").ok
    z = only(res, "following error Z")
    assert not z.ok and z.cycle == 251 and z.line == 7 and z.value == pytest.approx(0.2)
    assert "cycle 251" in str(z) and "line 7" in str(z)


def line_moves():
    return [Move("line", 3, "G01 Z-20.", {"X": 10.0, "Z": 0.0}, {"X": 10.0, "Z": -20.0}, {"X": 20.0, "Z": -20.0},
                 feed=300.0),
            Move("arc", 4, "G02 X30. Z-25. R5.", {"X": 10.0, "Z": -20.0}, {"X": 15.0, "Z": -25.0},
                 {"X": 30.0, "Z": -25.0}, center={"X": 15.0, "Z": -20.0}, dir="cw", plane=("Z", "X"), feed=300.0)]


def contour_trace():
    d = base()
    s = np.linspace(0, 1, N)
    d["line"][:] = np.where(s < 0.5, 3, 4)
    z = np.where(s < 0.5, -40 * s, 0)
    x = np.full(N, 10.0)
    arc = s >= 0.5
    ang = (s[arc] - 0.5) * 2 * (np.pi / 2)  # quarter circle, centre (Z-20, X15), r=5
    z[arc] = -20 - 5 * np.sin(ang)
    x[arc] = 15 - 5 * np.cos(ang)
    d["Z_act"], d["X_act"] = z.copy(), x.copy()
    d["Z_cmd"], d["X_cmd"] = z.copy(), x.copy()
    return d


def test_contour_error_on_arc(tmp_path):
    d = contour_trace()
    res = run_checks(write(tmp_path, d, "ok.csv"), ChecksConfig(contour_error=0.005), moves=line_moves())
    assert only(res, "contour error").ok and only(res, "contour error").value < 1e-3
    rz, rx = d["Z_act"][330] + 20.0, d["X_act"][330] - 15.0  # push 30 µm radially off the arc
    d["Z_act"][330] += 0.03 * rz / 5.0
    d["X_act"][330] += 0.03 * rx / 5.0
    r = only(run_checks(write(tmp_path, d), ChecksConfig(contour_error=0.005), moves=line_moves()), "contour error")
    assert not r.ok and r.cycle == 331 and r.line == 4 and r.value == pytest.approx(0.03, abs=2e-3)


def test_contour_needs_program_is_skipped_not_passed_silently(tmp_path):
    r = only(run_checks(write(tmp_path, base()), ChecksConfig(contour_error=0.01)), "contour error")
    assert r.skipped and "--program" in str(r)


@pytest.mark.parametrize("kind, order", [("velocity", 1), ("acceleration", 2), ("jerk", 3)])
def test_limit_checks(tmp_path, kind, order):
    bench = default_lathe()  # Z: 400 mm/s, 4000 mm/s², 200000 mm/s³
    d = base()
    d["line"][300:] = 9
    lim = {1: 400.0, 2: 4000.0, 3: 200_000.0}[order]
    # A single step in the order-th derivative of 1.5 × the limit at cycle 311 (row 310).
    bump = np.zeros(N)
    bump[310] = 1.5 * lim * 0.001 ** order
    z = bump
    for _ in range(order):
        z = np.cumsum(z)
    d["Z_cmd"] = z
    res = run_checks(write(tmp_path, d), ChecksConfig(limits=True), bench)
    r = only(res, f"{kind} Z")
    assert not r.ok and r.cycle == 311 and r.line == 9 and r.value == pytest.approx(1.5 * lim, rel=1e-6)
    for other in ("velocity X", "acceleration X", "jerk X"):
        assert only(res, other).ok


def thread_moves():
    return [Move("thread", 5, "G32 Z-20. F2.", {"X": r, "Z": 0.0}, {"X": r, "Z": -20.0}, {"X": 2 * r, "Z": -20.0},
                 feed=2.0, per_rev=True, lead=2.0) for r in (10.0, 9.8, 9.6)]


def thread_trace(phases):
    """Three passes at 600 rpm (10 rev/s, 20 mm/s), spindle at `phase` when each pass starts."""
    per = 1200
    d = base(per * len(phases))
    d["line"][:] = 5
    z_all, a_all, x_all = [], [], []
    for ph, m in zip(phases, thread_moves()):
        k = np.arange(per)
        z = np.where(k < 100, 0.0, -0.02 * (k - 100))  # standing until cycle 100, then 20 mm/s
        z = np.maximum(z, -20.0)
        z[-100:] = 0.0  # rapid return
        ang = (ph + 3.6 * (k - 100)) % 360.0  # 10 rev/s = 3.6° per ms
        z_all.append(z)
        a_all.append(ang)
        x_all.append(np.full(per, m.start["X"]))
    d["Z_act"], d["S1_angle"], d["X_act"] = np.concatenate(z_all), np.concatenate(a_all), np.concatenate(x_all)
    return d


def test_thread_phase_each_pass(tmp_path):
    good = run_checks(write(tmp_path, thread_trace([30.0, 30.0, 30.0]), "g.csv"), ChecksConfig(thread_phase=2.0),
                      moves=thread_moves())
    assert only(good, "thread phase").ok and only(good, "thread phase").value < 0.01
    bad = run_checks(write(tmp_path, thread_trace([30.0, 30.0, 70.0])), ChecksConfig(thread_phase=2.0),
                     moves=thread_moves())
    r = only(bad, "thread phase")
    assert not r.ok and "pass 3" in r.detail and r.line == 5
    assert 2400 < r.cycle <= 3600 and r.value > 30


def test_jitter_percentiles(tmp_path):
    d = base()
    d["period"][::50] = 0.00105  # 50 µs late every 50th cycle: 2 %
    d["period"][123] = 0.0014
    res = run_checks(write(tmp_path, d), ChecksConfig(jitter_p99=20e-6, jitter_max=300e-6), default_lathe())
    p99, mx = only(res, "jitter p99"), only(res, "jitter max")
    assert not p99.ok and p99.value == pytest.approx(50e-6, abs=1e-9) and p99.cycle == 1
    assert not mx.ok and mx.cycle == 124 and mx.value == pytest.approx(400e-6)


def test_hil_check_cli_exit_codes(tmp_path, capsys):
    d = base()
    d["X_ferr"][99] = 0.5
    write(tmp_path, d)
    path = str(tmp_path / "t.csv")
    assert main(["check", path, "--max-ferr", "1.0"]) == 0
    assert main(["check", path, "--max-ferr", "0.1"]) == 1
    out = capsys.readouterr().out
    assert "FAIL  following error X" in out and "cycle 100" in out
    assert main(["check", path]) == 2  # nothing to check
    assert main(["check", str(tmp_path / "none.csv"), "--max-ferr", "1"]) == 2


def test_rotary_following_error_is_reported_in_degrees(tmp_path, capsys):
    """The C axis of benches/lathe-c-axis.toml is in degrees: its check says deg, X's says mm."""
    d = base()
    for k in ("cmd", "act", "vel", "torque", "ferr"):
        d[f"C_{k}"] = np.zeros(N)
    d["C_sw"] = np.full(N, 0x1637)
    d["C_ferr"][120] = 0.3
    cols = trace_columns(["X", "Z", "C"], ["S1"])
    w = CsvTrace(tmp_path / "c.csv", cols)
    for i in range(N):
        w.write([d[c][i].item() if hasattr(d[c][i], "item") else d[c][i] for c in cols])
    w.close()
    bench = str(Path(__file__).resolve().parent.parent / "benches" / "lathe-c-axis.toml")
    assert main(["check", str(tmp_path / "c.csv"), "--bench", bench]) == 1
    out = capsys.readouterr().out
    assert "FAIL  following error C: 0.3 deg > 0.2 deg at cycle 121" in out
    assert "ok    following error X: 0 mm <= 0.1 mm" in out


def test_contour_error_of_a_filtered_cam_program_is_measured_against_the_right_blocks(tmp_path, capsys):
    """On 0.02-0.06 mm CAM blocks at F3000 the position filter (16+16 ms on the mill bench) puts the
    drives ~15 blocks behind the interpolator's line; the contour check must look that far back
    (it reported 0.8 mm, the distance to the wrong blocks), and then finds the real contour error:
    the filter's rounding (N1.053 = 0.02 mm) plus the drives' following error."""
    rng = np.random.default_rng(7)
    x, text = 0.0, ["G90 G17 G94 G01 F3000"]
    for _ in range(400):
        x += float(rng.uniform(0.02, 0.06))
        text.append(f"X{x:.4f} Y{3.0 * np.sin(x / 2.0):.4f}")
    prog = tmp_path / "cam.nc"
    prog.write_text("\n".join(text + ["M30"]) + "\n")
    bench = str(Path(__file__).resolve().parent.parent / "benches" / "mill-3axis.toml")
    assert main(["run", str(prog), "--bench", bench]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if "contour error" in ln)
    assert line.strip().startswith("ok")
    value = float(line.split("contour error:")[1].split("mm")[0])
    assert 0.0005 < value < 0.03


def test_nan_in_a_checked_column_fails_and_a_skipped_check_is_no_pass(tmp_path, capsys):
    """issue 15 item 6 / issue 20: `hil check` passed a following-error column of NaN ("ok … nan mm")
    and counted a SKIP as a pass."""
    from hil.cli import main

    cols = trace_columns(["X", "Z"], [])
    w = CsvTrace(tmp_path / "n.csv", cols)
    for k in range(50):
        row = {c: 0.0 for c in cols}
        row.update(t=(k + 1) * 0.001, line=1, cycle=k + 1, alarm="", X_sw=0x1237, Z_sw=0x1237,
                   X_ferr=float("nan") if k >= 20 else 0.001)
        w.write([row[c] for c in cols])
    w.close()
    assert main(["check", str(tmp_path / "n.csv"), "--max-ferr", "0.1"]) == 1
    out = capsys.readouterr().out
    assert "FAIL  trace data X_ferr" in out and "first at cycle 21" in out
    assert main(["check", str(tmp_path / "n.csv"), "--max-ferr", "0.1", "--contour", "0.05"]) == 1
    out = capsys.readouterr()
    assert "skipped" in out.out and "nothing was judged" in out.err


def cycle_moves():
    """One canned-cycle line (like a G76 pass): thread in, rapid out in X, rapid back in Z."""
    kw = dict(plane=("Z", "X"))
    return [Move("thread", 5, "G76 ...", {"X": 10.0, "Z": 0.0}, {"X": 10.0, "Z": -20.0}, {}, feed=2.0, **kw),
            Move("rapid", 5, "G76 ...", {"X": 10.0, "Z": -20.0}, {"X": 14.0, "Z": -20.0}, {}, **kw),
            Move("rapid", 5, "G76 ...", {"X": 14.0, "Z": -20.0}, {"X": 14.0, "Z": 0.0}, {}, **kw),
            Move("rapid", 5, "G76 ...", {"X": 14.0, "Z": 0.0}, {"X": 10.0, "Z": 0.0}, {}, **kw),
            Move("rapid", 6, "G00 X20. Z10.", {"X": 10.0, "Z": 0.0}, {"X": 20.0, "Z": 10.0}, {}, **kw)]


def cycle_trace(dogleg: bool):
    """The actual path along cycle_moves(); with `dogleg`, the last rapid runs X then Z."""
    pts = [(10.0, 0.0), (10.0, -20.0), (14.0, -20.0), (14.0, 0.0), (10.0, 0.0)]
    pts += [(20.0, 0.0), (20.0, 10.0)] if dogleg else [(20.0, 10.0)]
    seg = np.array(pts)
    k = np.linspace(0, len(seg) - 1, N)
    i = np.minimum(k.astype(int), len(seg) - 2)
    p = seg[i] + (seg[i + 1] - seg[i]) * (k - i)[:, None]
    d = base()
    d["X_act"], d["Z_act"] = p[:, 0].copy(), p[:, 1].copy()
    d["X_cmd"], d["Z_cmd"] = p[:, 0].copy(), p[:, 1].copy()
    d["line"][:] = np.where(k < 4, 5, 6)
    return d


def test_contour_of_a_canned_cycle_includes_its_own_rapids(tmp_path):
    """A G71/G76 line holds feeds and rapids; its rapid return is programmed path too (the
    example lathe part reported a 2.4 mm contour error on the G76 return)."""
    r = only(run_checks(write(tmp_path, cycle_trace(False)), ChecksConfig(contour_error=0.01), moves=cycle_moves()),
             "contour error")
    assert r.ok and r.value < 1e-9, r


def test_contour_of_independent_rapids_is_judged_against_their_box(tmp_path):
    """N1.20 bit 18 (independent rapids): each axis runs on its own, so a rapid on a judged line
    may leave the straight line but not the box its start and end span."""
    from hil.checks import _Cols, check_contour

    d = cycle_trace(True)
    d["line"][:] = 5  # the dogleg rapid is part of the cycle's own line
    tf = write(tmp_path, d)
    moves = cycle_moves()
    moves[4] = Move("rapid", 5, "G76 ...", {"X": 10.0, "Z": 0.0}, {"X": 20.0, "Z": 10.0}, {}, plane=("Z", "X"))
    linear = check_contour(_Cols(tf), ["X", "Z"], moves, 0.01, independent_rapids=False)
    boxed = check_contour(_Cols(tf), ["X", "Z"], moves, 0.01, independent_rapids=True)
    assert not linear.ok and linear.value > 5.0  # the dogleg corner (X20 Z0) is far off the straight line
    assert boxed.ok and boxed.value < 1e-9
