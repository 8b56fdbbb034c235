"""A stretch's cycles after its first, done at once (issue 17, decision B20).

The first cycle of a stretch runs through the runner's own cycle (`BenchRunner._cycle`); it writes every NC
output the stretch's state decides (modes, strobes, running, queue length ...). In the cycles after it
nothing the NC or the MLC reads changes except what the drives feed back, so `bulk_ok` admits a stretch
here when every cycle of it would do exactly this, and `bulk_cycles` does it once for all of them:
- the runner: cycle and time (time summed cycle by cycle, so its rounding is the stepped one), the masters'
  cycle count in their state (step() returns the same controlword), the rest counters, the maximum
  following error, the last feedback, actual and command positions, the program line;
- the MLC: its time and scan counts, the scans its gate skips (the gate's recorded reads are none of the
  devices written here, and it waits for no timer), the drive status words of the last cycle with the peak
  torque held over the stretch, the blink relays and the axis-at-0 relays of the last cycle;
- the trace: one row per cycle from the drives' columns, the same values the row of a stepped cycle has.
"""

from __future__ import annotations

import sys
from struct import error as _struct_error, pack as _pack
import time as _time
from functools import reduce
from itertools import accumulate, repeat
from operator import add
from typing import Any

import numpy as np

from fieldbus.pdo import TxPdo
from hil.clock import CycleTiming
from hil.mlc_bridge import drive_status
from hil.stretch_state import _hooks
from mlc.basic import BasicMlc
from mlc.machine import Mlc
from mlc.nc_link import MANUAL_MODES
from mlc.on_change import AREA_M, AREA_WORDS, TIMER_EPS
from mlc.spindle_axis import SPINDLE
from nc.channel import Channel
from nc.motion.planner import Planner
from nc.motion.stretch import Samples
from virtual_bus.drive_stretch import Stretch


def written_devices(x: int) -> set[tuple[int, int]]:
    """The devices a bulk stretch writes for its last cycle only (a superset of what changes cycle by cycle in
    a quiet stretch): the blink relays, the drive status (ChannelLink._drive_outputs), the axis-at-0 relays."""
    b3 = 30000 + 1000 * x
    m = {29032, 29033, 30000, b3 + 34, b3 + 35, b3 + 36}
    for lo, hi in ((b3 + 96, b3 + 104), (b3 + 256, b3 + 288), (b3 + 352, b3 + 368), (b3 + 464, b3 + 512),
                   (b3 + 704, b3 + 832)):
        m.update(range(lo, hi))
    # the spindle's rpm and angle D3x026-D3x029: d3(x, i) = 30000 + 1000·x + i, the block of the relays above
    # (it read 30000 + 100·x, D3x1026…: a gated scan reading them was not woken in a stretch; decision M21-2)
    words = set(range(30240, 30440)) | set(range(b3 + 26, b3 + 30))
    return {(AREA_M, i) for i in m} | {(AREA_WORDS, i) for i in words}


def bulk_ok(r: Any) -> bool:
    """Every cycle after a stretch's first would take the path `bulk_cycles` takes (module doc)."""
    if r.trace_sources or not (r.on_cycle is None or type(r.on_cycle) is _hooks()[1]):  # OperatorPanel
        return False  # device columns and --at events are read cycle by cycle
    mlc = r.mlc
    if type(mlc) is BasicMlc:
        return True
    if type(mlc) is not Mlc or mlc.io_modules or mlc.caxis.state != SPINDLE or mlc.caxis._started is not None:
        return False
    link = mlc.link
    if link.mode in MANUAL_MODES or link.hard_limits.latched or link.limit_latch.latched or \
            (link.manual is not None and link.manual.clamped):
        return False  # AUTO only: the manual windows and latches are not worked out
    gate = mlc.gate
    return gate is not None and gate.last is not None and not gate.last.dirty


_CACHE: dict[tuple, set] = {}


def first_change(r: Any, ch: Channel, outs: list[Stretch], k0: int, m: int, raw: list[np.ndarray]) -> int:
    """The first of cycles k0 … m-1 whose gated user scan would run (a device it read among those the drive
    status writes changes, or a timer it waits for is due) or whose AuxWatch would warn; m if none. Devices
    it read among the drive status are worked out cycle by cycle (the drive status bridge and
    ChannelLink._drive_outputs over the stretch's feedback, then put back), the rest need nothing."""
    mlc = r.mlc
    watch = r.progress if hasattr(r.progress, "timeout_s") else None  # hil.aux_watch.AuxWatch
    due = (watch._since, watch.timeout_s) if watch is not None and watch._aux is not None and watch._warned is None \
        else None
    if type(mlc) is BasicMlc:
        return m if due is None else _first_due(r.time, r.bench.cycle, k0, m, due)
    rec = mlc.gate.last
    link = mlc.link
    key = ("bulk-written", link.x)
    devices = _CACHE.get(key)
    if devices is None:
        devices = _CACHE[key] = written_devices(link.x)
    watched = [(a, i, v) for (a, i), v in rec.reads.items() if (a, i) in devices]
    if not watched and not rec.timers:
        return m if due is None else _first_due(r.time, r.bench.cycle, k0, m, due)
    mem = mlc.mem
    areas = (mem.m, mem.words)
    saved = (mlc.time, r.tx, bytes(mem.m), mem.d.copy())
    t, rt = mlc.time, r.time
    status = r.link.status() if callable(getattr(r.link, "status", None)) else None
    pl = ch.planner
    here = pl.position
    try:
        for k in range(k0, m):
            t += mlc.cycle
            rt += r.bench.cycle
            if any(t - start >= seconds - TIMER_EPS for start, seconds in rec.timers):
                return k
            if due is not None and rt - due[0] >= due[1]:  # AuxWatch.update's test at the cycle's end
                return k
            if watched:
                r.tx = [TxPdo(o.statusword[k], o.position_actual[k], o.velocity_actual[k], o.torque_actual[k],
                              o.following_error[k], o.last.error_code, o.last.mode_display,
                              o.last.touch_probe_status, o.last.touch_probe_pos1, o.last.digital_inputs)
                        for o in outs]
                mlc.time = t
                mlc._clocks()
                link._drive_outputs(drive_status(r, status), ch)
                if link.manual is not None:
                    pl.position = raw[k]
                    bits, b3 = mem.m, 30000 + 1000 * link.x
                    for i, p in enumerate(raw[k].tolist()):
                        bits[b3 + 352 + i] = 1 if abs(p) < 1e-6 else 0
                if any(areas[a][i] != v for a, i, v in watched):
                    return k
        return m
    finally:  # the scans of these cycles write these devices themselves (stepped or at once)
        mlc.time, r.tx = saved[0], saved[1]
        mem.m[:] = saved[2]
        mem.d[:] = saved[3]
        pl.position = here


def _first_due(time: float, dt: float, k0: int, m: int, due: tuple[float, float]) -> int:
    """The first cycle whose end-of-cycle AuxWatch.update finds the wait past its timeout."""
    for k in range(k0, m):
        time += dt
        if time - due[0] >= due[1]:
            return k
    return m


def outputs_hold(r: Any, ch: Channel, position: np.ndarray) -> bool:
    """The NC outputs of the stretch's state (ChannelLink.nc_outputs without the drive status, the planner at
    `position`, where it stands before the first cycle's step) written now, ahead of the first cycle's scan:
    True when the gated user scan would still skip (every device it read holds what it saw). The last cycle
    writes them again (bulk_cycles); nothing reads them in between (the NC's inputs are the MLC's devices)."""
    mlc = r.mlc
    if type(mlc) is BasicMlc:
        return True
    pl = ch.planner
    here, pl.position = pl.position, position
    try:
        mlc.link.nc_outputs(ch, None)
    finally:
        pl.position = here
    mem = mlc.mem
    areas = (mem.m, mem.words, mem.x, mem.y, mem.a, mlc.ctx.io.inputs)
    return all(areas[area][i] == v for (area, i), v in mlc.gate.last.reads.items())


def bulk_cycles(r: Any, ch: Channel, pl: Planner, smp: Samples, outs: list[Stretch], k0: int, m: int,
                before_last_step: np.ndarray, settle: tuple[list[float], list[float]] | None,
                timings: list[CycleTiming] | None = None, rows_paced: bool = False, counted: int | None = None) -> Any:
    """Cycles k0 … m-1 of the stretch as the runner's cycle would run them one by one (module doc). `timings`:
    real time, the cycles were paced one by one (hil.stretch.Stretcher._pace) with these timings, which the
    trace rows take; the clock has counted them. With one timing fewer than cycles, the last cycle is paced
    after this (in the slack before it): its trace row is left to the returned `last_row(timing)`, the
    runner's own row (its state is that cycle's now). `rows_paced`: the paced cycles' rows were written in
    their own slacks (decision B36), none here; `counted`: with them, cycles k0 … counted-1 were counted in a
    paced slack too (count_cycles)."""
    t_wall = _time.perf_counter_ns()
    cnt = m - k0
    n_axes = len(r.axes)
    first_cycle = r.cycle + 1
    # the times summed cycle by cycle, as stepping sums them (accumulate and reduce add in order, at C speed)
    times = count_cycles(r, outs, k0 if counted is None else counted, m)
    r.tx = tx = [o.last for o in outs]
    scales, org = r.scales, r.origin.tolist()
    r.actual[:] = [scales[i].to_units(tx[i].position_actual) + o for i, o in enumerate(org)]
    positions, lines = smp.positions, smp.lines
    line = r.line
    row_lines = lines[k0:m]
    if all(row_lines):  # every row names its line (a 0 keeps the one before)
        line = row_lines[-1]
    else:
        row_lines = []
        for ln in lines[k0:m]:
            line = ln or line
            row_lines.append(line)
    if settle is not None:  # Planner.step's spindle settle count reads the measured speed of each cycle
        rpms, cmds = settle
        cmd = float(pl.spindle_command())  # type: ignore[misc]
        if len(scales) > n_axes:
            sc = scales[n_axes]
            # AxisScaling.drive_to_rpm over the column: the same divisions and products in the same order (in
            # Python: a real-time stretch's ≈ 16 values cost less than numpy's conversions, B36)
            rpc, cpu, lead = sc._raw_per_cps, sc._cpu, sc.lead
            rpms += [v / rpc / cpu / lead * 60.0 for v in outs[n_axes].velocity_actual[k0:m]]
        else:
            rpms += [abs(r.spindle_command_rpm())] * cnt
        cmds += [cmd] * cnt
    _mlc(r, ch, outs, k0, m, before_last_step)
    cmds_last = positions[m - 1].tolist()
    r._commands[:] = cmds_last
    r.line = line
    for i in range(n_axes):
        r.rx[i].target_position = scales[i].to_counts(cmds_last[i] - org[i])
    deferred = timings is not None and len(timings) == cnt - 1
    if r.trace is not None and rows_paced:
        r._row_cycle = r.cycle
    elif r.trace is not None:
        assert counted is None  # (the rows need every cycle's time)
        if deferred:
            _rows(r, outs, k0, m - 1, times[:-1], first_cycle, row_lines[:-1], positions, timings)
        else:
            _rows(r, outs, k0, m, times, first_cycle, row_lines, positions, timings)
    if r.on_cycle is not None:
        r.on_cycle(r)  # the operator panel, with nothing held: the same call every cycle
    if r.progress is not None:
        r.progress.update(r)
    if timings is not None:
        if not deferred:
            r.timing = timings[-1]
            return None

        def last_row(timing: CycleTiming) -> None:
            r.timing = timing
            if r.trace is not None:  # the stepped cycle's row (one row in numpy cost ≈ 100 µs of the slack, B36)
                r.trace.write(r._row())
                r._row_cycle = r.cycle
            if r.on_cycle is not None:
                r.on_cycle(r)  # the last cycle's own call: a press while it waited is taken as stepping takes it
            if r.progress is not None:
                r.progress.update(r)

        return last_row
    clock = r.clock
    clock._n += cnt
    clock.jitter.add_repeated(0.0, cnt, first_cycle)
    clock.exec.add_repeated((_time.perf_counter_ns() - t_wall) * 1e-9 / cnt, cnt, first_cycle)
    return None


def count_cycles(r: Any, outs: list[Stretch], k0: int, m: int) -> list[float]:
    """The runner's counters over cycles k0 … m-1 of a stretch (bulk_cycles' first part): time and cycle, the
    masters' cycles in their state, the rest counters, the largest following error, the C axis switch's cycles.
    Each adds on in order, so counting a stretch in parts (its paced cycles in a slack, B36) counts as at once.
    Returns the cycles' times."""
    cnt = m - k0
    dt = r.bench.cycle
    times = list(accumulate(repeat(dt, cnt), add, initial=r.time))
    r.time = times[-1]
    del times[0]
    link = r.link
    link.time = reduce(add, repeat(dt, cnt), link.time)
    link.cycles += cnt
    r.cycle += cnt
    for master in r.masters:
        master.cycles_in_state += cnt  # step() in a held state: the same controlword, one more cycle in it
    rest, last = r._rest, r._last_position
    for i, o in enumerate(outs):
        rest[i], last[i] = _rest(rest[i], last[i], o.position_actual[k0:m], o.velocity_actual[k0:m])
    n_axes, scales, max_ferr = len(r.axes), r.scales, r.result.max_ferr
    for i in range(n_axes):
        # |fe / cpu| is |fe| / |cpu| exactly and a division by a constant is monotone: the largest |fe| gives the peak
        ferr = abs(scales[i].to_units(max(map(abs, outs[i].following_error[k0:m])))) if cnt else 0.0
        if ferr > max_ferr[r.axes[i]]:
            max_ferr[r.axes[i]] = ferr
    mlc = r.mlc
    if type(mlc) is Mlc and n_axes < len(r.rx):
        mlc.caxis._cycles += cnt  # Mlc.spindle_drive → SpindleAxisSwitch.drive, a spindle staying one
    return times


def _rest(n_rest: int, p_last: int, pa: list[int], va: list[int]) -> tuple[int, int]:
    """The runner's rest count and last position after these cycles' feedback: a cycle at rest (its position the
    one before, velocity 0) counts on, any other starts again at 0."""
    cnt = len(pa)
    if va.count(0) == cnt and pa.count(p_last) == cnt:  # at rest throughout
        return n_rest + cnt, p_last
    k = cnt - 1  # the cycles at rest at the end
    while k > 0 and va[k] == 0 and pa[k] == pa[k - 1]:
        k -= 1
    return cnt - 1 - k, pa[-1]


def _mlc(r: Any, ch: Channel, outs: list[Stretch], k0: int, m: int, before_last_step: np.ndarray) -> None:
    """The MLC's scans of cycles k0 … m-1: counts and time per scan, the NC's outputs of the last one."""
    mlc = r.mlc
    cnt = m - k0
    if type(mlc) is BasicMlc:
        mlc.cycle += cnt
        return
    t = mlc.time
    for _ in range(cnt):
        t += mlc.cycle
    mlc.time = t
    link = mlc.link
    link.cycle += cnt
    ctx = mlc.ctx
    ctx.time, ctx.scan_count = t, ctx.scan_count + cnt
    mlc.gate.skipped += cnt
    mlc._clocks()
    # the peak torque (D30400+k) is held over every cycle: the cycles before the last one here, the last
    # one by _drive_outputs itself
    words = mlc.mem.words
    for k, o in enumerate(outs[:32]):
        if m - 1 <= k0:
            break
        # |round(torque % × 10)| grows with |0x6077| (a product, rounded half to even: odd-symmetric): the
        # largest raw torque gives the peak
        raw = max(map(abs, o.torque_actual[k0:m - 1]))
        peak = min(abs(int(round(r.scales[k].torque_percent(raw) * 10.0))), 0xFFFF)
        if peak > words[30400 + k]:
            words[30400 + k] = peak
    status = r.link.status() if callable(getattr(r.link, "status", None)) else None
    mlc.bus_feedback(drive_status(r, status))
    if status is not None:
        mlc.bus_status(status)
    pl = ch.planner  # the last cycle's outputs: those of the stretch's state, its drive status, axes at 0
    here, pl.position = pl.position, before_last_step
    try:
        link.nc_outputs(ch, mlc.drives)
    finally:
        pl.position = here


def _round9(times: list[float]) -> list[float]:
    """round(t, 9) of each time (the trace's time column), in numpy where that is the same: t·1e9 within 0.49 of
    the integer n it rounds to and under 2^45 (its product's error under 0.004), so t·10^9 exactly is nearest to n
    as well, no tie; n / 1e9 is then the double nearest to n·10^-9, which round() makes of the digits of n."""
    x = np.array(times) * 1e9
    n = np.rint(x)
    if np.all(np.abs(x - n) < 0.49) and np.all(np.abs(x) < 2.0 ** 45):
        return (n / 1e9).tolist()
    return [round(t, 9) for t in times]


def _floats(counts: list[int]) -> np.ndarray:
    """`np.array(counts, dtype=np.float64)` of a drive's feedback counts: the same doubles (each int to its nearest
    double, as numpy's conversion makes it through a Python float), made through the int64 bytes `struct` packs and
    numpy's cast (issue 17, decision bench B165: numpy's conversion of a list made a float object a value, ≈ 550
    instructions; decision bench B180: `array("q", …)` parsed each int through PyArg_Parse's format, ≈ 280 under
    callgrind, struct's `q` ≈ 140). A value that is not an int within int64 (a float, a huge count) takes numpy's
    way, as before."""
    try:
        return np.frombuffer(_pack(f"{len(counts)}q", *counts), np.int64).astype(np.float64)
    except _struct_error:  # not an integer, or out of int64's range
        return np.array(counts, dtype=np.float64)


def _rows(r: Any, outs: list[Stretch], k0: int, m: int, times: list[float], first_cycle: int, lines: list[int],
          positions: np.ndarray, timings: list[CycleTiming] | None = None) -> None:
    """The trace rows of cycles k0 … m-1, as BenchRunner._row makes them: the unit conversions over the columns
    in numpy, with the same operations in the same order (IEEE division and product, numpy's float remainder
    is Python's %), back as Python floats."""
    n_axes = len(r.axes)
    scales, org = r.scales, r.origin.tolist()
    cnt = m - k0
    trace = r.trace
    # a Parquet trace takes the columns as they are (float64 arrays); rows for the others
    parquet = sys.modules.get("hil.trace_parquet")  # loaded when a Parquet trace is open: a run without one
    as_cols = parquet is not None and type(trace) is parquet.ParquetTrace  # does not import pyarrow (≈ 45 ms)
    done = (lambda a: a) if as_cols else (lambda a: a.tolist())
    cols: list = []
    for i, (sc, out) in enumerate(zip(scales, outs)):
        cpu, rpc = sc._cpu, sc._raw_per_cps
        pa = _floats(out.position_actual[k0:m])
        va = _floats(out.velocity_actual[k0:m])
        tq = done(_floats(out.torque_actual[k0:m]) * sc.units.torque_percent)
        if i < n_axes:  # AxisScaling.to_units, drive_to_velocity, torque_percent
            cols += [done(np.ascontiguousarray(positions[k0:m, i])), done(pa / cpu + org[i]), done(va / rpc / cpu), tq,
                     done(_floats(out.following_error[k0:m]) / cpu), out.statusword[k0:m]]
        else:  # drive_to_rpm of the command and the feedback, the angle mod 360
            cols += [[sc.drive_to_rpm(r.rx[i].target_velocity)] * cnt, done(va / rpc / cpu / sc.lead * 60.0),
                     done(np.remainder(pa / cpu, 360.0)), tq, out.statusword[k0:m]]
    if timings is None:
        periods, lates = [r.timing.period] * cnt, [r.timing.late] * cnt
    else:  # real time: each cycle's own
        periods, lates = [t.period for t in timings], [t.late for t in timings]
    head = [_round9(times), lines, list(range(first_cycle, first_cycle + cnt)), periods, lates,
            [""] * cnt]
    if as_cols:
        trace.write_columns(head + cols, cnt)
    else:
        for row in zip(*head, *cols):
            trace.write(row)
    r._row_cycle = r.cycle
