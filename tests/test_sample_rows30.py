"""few_rows' and a cruise's buffers as rows of a slab (nc.motion.sample_rows `_Slab`, decision bench B175; a cruise's
`slab_rows`, B176): on a dense CAM program planned offline with a small slab (a new slab every few blocks), the
setpoints are those of another slab size bit for bit, and every buffer handed out is its own rows: float64, C order,
(rows, axes) and (rows,), never overlapping another buffer, and still holding at the end of the run the values it had
when the planner took it; a cruise's speeds all its one speed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import nc.motion.sample_rows as sample_rows
from benchmarks.bench_motion import cam_program
from hil.bench_file import load_bench_file
from nc.interp import Interpreter
from nc.motion.offline import run
from nc.profiles import make_profile
from nc.program.blocks import parse_program

ROOT = Path(__file__).resolve().parents[1]
START = {"X": 0.0, "Y": 0.0, "Z": 100.0}


def _run(on_cycle=None):
    prog = parse_program(cam_program(400), name="cam.nc")
    motion = load_bench_file(ROOT / "benches" / "mill-3axis.toml").motion_config()
    return run(Interpreter(make_profile("nc5-mill", ("X", "Y", "Z"))).run(prog), motion, START, on_cycle=on_cycle)


def _bits(a: np.ndarray) -> bytes:
    return np.ascontiguousarray(a).tobytes()


def test_slab_rows_are_fresh_buffers(monkeypatch):
    want = _run()
    monkeypatch.setattr(sample_rows, "SLAB", 8)
    monkeypatch.setattr(sample_rows, "_slab", sample_rows._Slab(3))
    taken: list[tuple[np.ndarray, np.ndarray, bytes, bytes, bool]] = []
    slabs: list[np.ndarray] = []

    def on_cycle(_n, ch):
        pl = ch.planner
        pos, vel = pl._buf_pos, pl._buf_vel
        if pos is None or (taken and taken[-1][0] is pos):
            return
        sl = sample_rows._slab
        if pos.base is sl.pos:  # a buffer few_rows made
            assert vel.base is sl.vel
            taken.append((pos, vel, _bits(pos), _bits(vel), False))
            if not slabs or slabs[-1] is not sl.pos:
                slabs.append(sl.pos)

    got = _run(on_cycle)
    assert _bits(got.positions) == _bits(want.positions) and _bits(got.lines) == _bits(want.lines)
    assert len(taken) > 100 and len(slabs) > 10, (len(taken), len(slabs))
    assert all(1 <= t[0].shape[0] <= sample_rows.FEW for t in taken)  # few_rows' buffers alone
    _own_rows(taken)


def _own_rows(taken: list[tuple]) -> None:
    """Each buffer (pos, vel, their bits when taken, a cruise's?) is float64, C order, (rows, 3) and (rows,), unchanged
    since it was taken, and shares no row of its slab with another; a cruise's speeds are its one speed."""
    spans: dict[int, list[tuple[int, int]]] = {}
    for pos, vel, pos_bits, vel_bits, cruise in taken:
        assert pos.dtype == np.float64 and vel.dtype == np.float64
        assert pos.flags.c_contiguous and vel.flags.c_contiguous
        assert pos.ndim == 2 and pos.shape[1] == 3 and vel.shape == (pos.shape[0],)
        if cruise:
            assert np.all(vel == vel[0]) and vel[0] > 0.0  # a cruise: one speed
        assert _bits(pos) == pos_bits and _bits(vel) == vel_bits  # nothing wrote into a buffer handed out
        start = (pos.__array_interface__["data"][0] - pos.base.__array_interface__["data"][0]) // (3 * 8)
        spans.setdefault(id(pos.base), []).append((start, start + pos.shape[0]))
    for rows in spans.values():
        rows.sort()
        for (_, end), (nxt, _) in zip(rows, rows[1:]):
            assert end <= nxt  # no two buffers share a row


def test_cruise_buffers_are_slab_rows(monkeypatch):
    monkeypatch.setattr(sample_rows, "SLAB", sample_rows.FEW)  # few_rows' rows only: a cruise of more rows (most)
    # takes np.array and np.full, as before B176
    monkeypatch.setattr(sample_rows, "_slab", sample_rows._Slab(3))
    want = _run()
    monkeypatch.setattr(sample_rows, "SLAB", 64)  # a new slab every few cruises
    monkeypatch.setattr(sample_rows, "_slab", sample_rows._Slab(3))
    taken: list[tuple[np.ndarray, np.ndarray, bytes, bytes, bool]] = []
    cruises: list[np.ndarray] = []

    def on_cycle(_n, ch):
        pl = ch.planner
        pos, vel = pl._buf_pos, pl._buf_vel
        if pos is None or (taken and taken[-1][0] is pos) or (cruises and cruises[-1] is pos):
            return
        cruise = pl._buf_blk is not None  # (only a cruise sets the rows' block offsets)
        if cruise:
            cruises.append(pos)
        sl = sample_rows._slab
        if pos.base is sl.pos:
            assert vel.base is sl.vel
            taken.append((pos, vel, _bits(pos), _bits(vel), cruise))

    got = _run(on_cycle)
    assert _bits(got.positions) == _bits(want.positions) and _bits(got.lines) == _bits(want.lines)
    slab_cruises = [t for t in taken if t[4]]
    assert len(cruises) > 20 and len(slab_cruises) == len(cruises), (len(cruises), len(slab_cruises))
    _own_rows(taken)
