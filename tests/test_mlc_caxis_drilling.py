"""Face drilling and tapping with C positioning on benches/lathe-c-axis.toml, through `hil run` with
the bench's default MLC (the Delta lathe MLC) and its own checks (no --no-check):

- G83 X_ C_ Z_ R_ Q_ F_ with the spindle switched to the C axis (M66 … M77, NC5 §3.14.1): the spindle
  drive is in CSP (M3x709 follows its 0x6061 mode display) while it is C and spins again in CSV after
  M77; C and the spindle stand at every programmed angle within 0.01° while Z is in the hole; the pecks
  stop at R − kQ and at the bottom.
- The NC5 manual's worked example E-N55 (§3.14.2, lathe face tapping with C indexing): its path, and its
  first two holes on the bench (the spindle reverses at every peck before Z comes out).
"""

from __future__ import annotations

import json

import numpy as np

from hil.trace_read import TraceFile
from tests.conftest import ROOT

BENCH = ROOT / "benches" / "lathe-c-axis.toml"
SIGNALS = "M31709,M2239,M31064,M21016,D31048"
TOL_DEG = 0.01

G83_PROGRAM = (ROOT / "examples" / "lathe_face_drilling_c.nc").read_text()

E_N55 = """N01 (TAPPING)
N02G00 X50.000
N03G00 Z5.000
N04T0101
N05G50 S2000
N06G97 S600
N07M3
N08M8
N09G40
N10G00 X30.000
N11G00 C0.000
N12G99 G84 Z-20.000 P500 Q3 R2.000 L1 F1.500
N13C45.
N14C90.
N15C135.
N16C180.
N17C225.
N18C270.
N19C315.
N20G80
N21G00 Z20.000
N22G00 X50.000
N23M09
N24M05
N25M30
"""


def _bench_integer_mm(tmp_path):
    """The C-axis bench with the decimal-point rule off (N8.018 Bit10 = 1): E-N55 writes Q3 for a 3 mm
    peck, as the manual's examples do (decisions A4: manual examples run with the rule off)."""
    b = tmp_path / "lathe-c-axis-int.toml"
    b.write_text(BENCH.read_text() + '\n[params]\n"N8.018 Bit10" = 1\n')
    return b


def _run(hil, tmp_path, text: str, bench=BENCH) -> dict[str, np.ndarray]:
    prog, trace = tmp_path / "p.nc", tmp_path / "t.parquet"
    prog.write_text(text)
    r = hil("run", prog, "--bench", bench, "--trace", trace, "--trace-signals", SIGNALS)
    assert r.code == 0, r.out + r.err
    assert "checks" in r.out and "FAIL" not in r.out  # the bench's own checks ran and passed
    return TraceFile(trace).arrays()


def _angle_error(angle: np.ndarray, want: np.ndarray) -> np.ndarray:
    return np.abs((angle - want + 180.0) % 360.0 - 180.0)


def _rises(col: np.ndarray) -> np.ndarray:
    return np.flatnonzero((col[1:] != 0) & (col[:-1] == 0)) + 1


def _strobed_m_codes(t: dict[str, np.ndarray]) -> list[int]:
    return [int(t["D31048"][i]) for i in _rises(t["M31064"])]


def _bottoms(z: np.ndarray, rows: np.ndarray) -> list[float]:
    """Depths (to 1 µm) where the Z command inside the hole rows stops going down."""
    dz = np.diff(z[rows])
    moving = np.flatnonzero(np.abs(dz) > 1e-9)
    out = [round(float(z[rows][b]), 3) for a, b in zip(moving[:-1], moving[1:]) if dz[a] < 0 < dz[b]]
    if dz[moving[-1]] < 0:
        out.append(round(float(z[rows][moving[-1] + 1]), 3))
    return out


# ---- G83 with the spindle as the C axis ---------------------------------------------------------------
def test_g83_face_drilling_at_c_angles_with_the_spindle_as_c_axis(hil, tmp_path):
    t = _run(hil, tmp_path, G83_PROGRAM)
    r_level = 10.0 - 2.0  # R: 2 mm from the initial point Z10 toward the hole (decisions A50)
    in_hole = np.flatnonzero(t["Z_cmd"] < r_level - 1e-3)

    # Spindle → C → spindle, over the M/S/T handshake: M66 strobe, C mode done (M2239), finish; M77 back.
    assert [c for c in _strobed_m_codes(t) if c in (66, 77)] == [66, 77]
    strobe66, strobe77 = [i for i in _rises(t["M31064"]) if t["D31048"][i] in (66, 77)]
    done_on, done_off = _rises(t["M2239"])[0], np.flatnonzero(np.diff(t["M2239"]) < 0)[0] + 1
    fin66, fin77 = ([i for i in _rises(t["M21016"]) if i > s][0] for s in (strobe66, strobe77))
    assert strobe66 < done_on <= fin66 < in_hole[0] and in_hole[-1] < strobe77 <= done_off <= fin77

    # The spindle drive: CSV (9) → CSP (8) once, for the whole drilling, then CSV again and spinning.
    csp = t["M31709"]
    edges = np.flatnonzero(np.diff(csp)) + 1
    assert [int(csp[i]) for i in edges] == [1, 0]
    assert strobe66 < edges[0] < in_hole[0] and in_hole[-1] < edges[1]
    assert np.all(csp[in_hole] == 1)
    assert np.max(t["S1_rpm_act"][edges[1]:]) > 299.0  # M03 S300 after M77: turning in CSV
    assert np.all(np.abs(t["S1_rpm_act"][in_hole]) < 0.5)

    # C (its drive and the spindle in C mode) at the programmed angle while Z is in the hole.
    c_cmd = t["C_cmd"][in_hole]
    assert sorted(set(np.round(c_cmd, 9))) == [0.0, 90.0, 180.0, 270.0]
    assert np.all(np.diff(c_cmd) >= 0)  # holes in program order
    assert np.max(np.abs(t["C_act"][in_hole] - c_cmd)) <= TOL_DEG
    assert np.max(_angle_error(t["S1_angle"][in_hole], c_cmd)) <= TOL_DEG
    assert np.max(np.abs(t["X_act"][in_hole] - 15.0)) <= 0.005  # X30. is a diameter

    # Deep-peck (L1): Q4 pecks from R to -10, back to R after each peck; the drive reaches each depth.
    for angle in (0.0, 90.0, 180.0, 270.0):
        rows = in_hole[np.abs(t["C_cmd"][in_hole] - angle) < 1e-9]
        bottoms = _bottoms(t["Z_cmd"], rows)
        assert bottoms == [4.0, 0.0, -4.0, -8.0, -10.0], (angle, bottoms)
        retracts = np.flatnonzero(np.diff(rows) > 1)  # the rows leave the hole (Z back at R) between pecks
        assert len(retracts) == 4
        for depth in bottoms:
            near = rows[np.abs(t["Z_cmd"][rows] - depth) < 1e-4]
            assert abs(np.min(t["Z_act"][near[0]:near[-1] + 50]) - depth) <= 0.01


# ---- E-N55: face tapping with C indexing (NC5 §3.14.2) -------------------------------------------------
def test_e_n55_path_taps_eight_holes_at_c_45_degree_steps(hil, tmp_path):
    prog = tmp_path / "e_n55.nc"
    prog.write_text(E_N55)
    r = hil("path", prog, "--json", "--bench", BENCH, "--param", "N8.018 Bit10=1")
    assert r.code == 0, r.err
    moves = [m for m in r.json_lines() if m.get("kind") in ("rapid", "line", "dwell")]
    taps = [m for m in moves if "tap" in m.get("tags", [])]
    holes: dict[float, list[float]] = {}
    for m in taps:
        assert m["end"]["X"] == 15.0 and m["start"]["C"] == m["end"]["C"]  # X30 diameter, C still
        assert m["per_rev"] and m["feed"] == 1.5  # G99: 1.5 mm/rev, the thread pitch
        holes.setdefault(m["end"]["C"], []).append(m["end"]["Z"])
    assert list(holes) == [45.0 * k for k in range(8)]
    for bottoms in holes.values():  # Q3 pecks from R (Z5 − 2 = 3) to the bottom Z-20
        assert bottoms == [0.0, -3.0, -6.0, -9.0, -12.0, -15.0, -18.0, -20.0]
    outs = [m for m in moves if "tap_out" in m.get("tags", [])]
    assert len(outs) == 64 and {m["end"]["Z"] for m in outs} == {3.0}
    dwells = [m for m in moves if "dwell" in m.get("tags", [])]
    assert [(m["duration"], m["end"]["Z"]) for m in dwells] == [(0.5, -20.0)] * 8  # P500: 0.5 s at the bottom
    assert {m["end"]["Z"] for m in moves if "return" in m.get("tags", [])} == {5.0}  # type A: initial level


def test_e_n55_first_two_holes_on_the_bench(hil, tmp_path):
    """N01–N13 (holes at C0 and C45) and the program's end N20–N25, on the bench: C holds the angle,
    the tap goes in only while the spindle turns forward and out only in reverse, at 1.5 mm/rev."""
    lines = E_N55.splitlines()
    text = "\n".join(lines[:13] + lines[19:]) + "\n"
    t = _run(hil, tmp_path, text, _bench_integer_mm(tmp_path))
    r_level = 5.0 - 2.0
    in_hole = np.flatnonzero(t["Z_cmd"] < r_level - 1e-3)
    c_cmd = t["C_cmd"][in_hole]
    assert sorted(set(np.round(c_cmd, 9))) == [0.0, 45.0]
    assert np.max(np.abs(t["C_act"][in_hole] - c_cmd)) <= TOL_DEG

    # The M codes handed to the MLC: M3 M8, per hole M04 at each bottom and M03 before the next peck
    # (and back to M03 after the hole), then M09 M05.
    hole = [4] + [3, 4] * 7 + [3]
    assert _strobed_m_codes(t) == [3, 8] + hole + hole + [9, 5]

    dz = np.gradient(t["Z_cmd"], t["t"])
    rpm = t["S1_rpm_act"]
    going_in, coming_out = in_hole[dz[in_hole] < -1e-6], in_hole[dz[in_hole] > 1e-6]
    assert np.all(rpm[going_in] > 0) and np.all(rpm[coming_out] < 0)  # reversed before Z comes out
    assert abs(np.min(dz[going_in]) + 1.5 * 600.0 / 60.0) <= 0.15  # cruise: 1.5 mm/rev at 600 rpm
    assert abs(np.max(dz[coming_out]) - 1.5 * 600.0 / 60.0) <= 0.15
    for angle in (0.0, 45.0):
        rows = in_hole[np.abs(t["C_cmd"][in_hole] - angle) < 1e-9]
        bottoms = _bottoms(t["Z_cmd"], rows)
        assert bottoms == [0.0, -3.0, -6.0, -9.0, -12.0, -15.0, -18.0, -20.0]
        at_bottom = rows[np.abs(t["Z_cmd"][rows] + 20.0) < 1e-5]
        assert 0.5 <= len(at_bottom) * 0.001 < 1.0  # P500 dwell, then the M04 handshake
        assert abs(np.min(t["Z_act"][rows]) + 20.0) <= 0.01
