"""The stepped cycle's per-drive work, lean (issue 17, decision B40): the CiA 402 masters, the rest counters,
the servo / overspeed / limit alarms and the actual positions in one pass over the drives, and the trace row,
on plain ints and floats with each drive's unit factors read once per run.

Bit for bit what `BenchRunner._cycle` and `_row` computed before: the same divisions in the same order
(`AxisScaling.to_units` is counts / counts_per_unit, `drive_to_velocity` raw / raw_per_cps / counts_per_unit,
`torque_percent` raw × the unit's percent), never a reciprocal multiplied in its place.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from fieldbus.cia402 import CW_ENABLE_OPERATION, STATES_BY_BITS, SW_INTERNAL_LIMIT, State, Target
from nc.alarms import SERVO_ALARM, Alarm

OVERSPEED = 1.2  # App. A 0x0602: measured axis speed above this multiple of its limit (the virtual drive's own AL007 margin)
_FAULT, _REACTION, _ENABLED = State.FAULT, State.FAULT_REACTION_ACTIVE, State.OPERATION_ENABLED
_KEEP_ENABLED = Target.ENABLED


@dataclass(frozen=True, slots=True)
class Factors:
    """One drive's unit factors, as `fieldbus.units.AxisScaling` divides by them."""

    cpu: float  # counts per user unit (AxisScaling.counts_per_unit)
    raw_per_cps: float  # drive velocity units per count/s
    torque: float  # % of rated torque per drive torque unit
    lead: float


def factors(scales: list[Any]) -> list[Factors]:
    return [Factors(sc.counts_per_unit, sc.units.raw_per_count_per_s(sc.counts_per_rev), sc.units.torque_percent,
                    sc.lead) for sc in scales]


# Cycles a drive's fault reset at power-up may take before a fault it still shows is its alarm (decision B72): the
# master's two-cycle reset edge, the drive's answer a frame or two later on a field bus, and room for a slow drive;
# also how early in the power-up a fault counts as one the drive brought with it.
RESET_CYCLES = 20


def power_up_reset(r: Any, i: int, m: Any, st: Any, code: int) -> bool:
    """A fault a drive shows at power-up (latched before this run: a master that died, a drive powered on in
    fault) is reset once, as the operator's RESET before cycle start, and noted in the result; True while that
    reset is under way. A fault that stays, comes back or arises while powering is the servo alarm (B72)."""
    resets = r._power_up_reset
    if resets is None:
        return False
    if i not in resets:
        if st is not _FAULT or r.cycle > RESET_CYCLES:  # braking (reacting to a fault now), or late: an alarm
            return False
        resets[i] = r.cycle
        r.result.power_up_resets.append((r._name(i), code))
        m.fault_reset()
        return True
    return r.cycle - resets[i] <= RESET_CYCLES


def feedback(r: Any, txs: list[Any], n_axes: int) -> None:
    """The drives' feedback of this cycle: each master stepped (its controlword into the RxPdo), the rest
    counters, servo alarm (fault), App. A 0x0602 overspeed and 0x0402 hardware limit, then `r.actual`."""
    rest, last, rxs, alarmed, at_limit = r._rest, r._last_position, r.rx, r._alarmed_drives, r._at_limit
    overspeed, facs = r._overspeed, r._factors
    acts: list[float] = []
    origin = r.origin.tolist()
    for i, (m, tx) in enumerate(zip(r.masters, txs)):
        sw = tx.statusword
        if m.state is _ENABLED and m.target is _KEEP_ENABLED and STATES_BY_BITS[sw & 0x7F] is _ENABLED:
            # Cia402Master.step's usual cycle, spelt out: enabled, asked to stay so, still enabled
            m.cycles_in_state += 1
            m._reset_phase = 0
            rxs[i].controlword = CW_ENABLE_OPERATION
        else:
            rxs[i].controlword = m.step(sw)
        p, v = tx.position_actual, tx.velocity_actual
        rest[i] = rest[i] + 1 if p == last[i] and v == 0 else 0
        last[i] = p
        st = m.state
        if (st is _FAULT or st is _REACTION) and i not in alarmed and not power_up_reset(r, i, m, st, tx.error_code):
            alarmed.add(i)
            r._alarm(Alarm(SERVO_ALARM, f"servo alarm on {r._name(i)}: drive error code 0x{tx.error_code:04X}",
                           line=r.line or None, axis=r._name(i), info=tx.error_code))
        if i >= n_axes:
            continue
        if abs(v) > overspeed[i] and i not in alarmed:
            alarmed.add(i)
            vel = r.scales[i].drive_to_velocity(v)
            r._alarm(Alarm(0x0602, f"overspeed protection: axis {r._name(i)} at {abs(vel):.1f}/s, beyond "
                                   f"{OVERSPEED:g} x its maximum velocity {r.bench.axes[i].limits.max_velocity:g}/s",
                           line=r.line or None, axis=r._name(i)))
        if sw & SW_INTERNAL_LIMIT:
            if i not in at_limit:
                at_limit[i] = p
                if i not in alarmed:
                    r._alarm(Alarm(0x0402, f"hardware limit reached on axis {r._name(i)}",
                                   line=r.line or None, axis=r._name(i)))
        elif at_limit and i in at_limit and abs(p - at_limit[i]) > r._limit_hysteresis[i]:
            del at_limit[i]  # left the switch (hil script, App. A 0x0A06): the next hit raises again
        acts.append(p / facs[i].cpu + origin[i])
    r.actual[:] = acts


def row(r: Any, n_axes: int) -> list:
    """One trace row (full-precision floats: the trace feeds checks that differentiate positions three times)."""
    timing, txs, facs = r.timing, r.tx, r._factors
    ch = r.channel
    alarms = r._new_alarms() if r.result.alarms or (ch is not None and ch.alarms) else ""  # the usual row: none
    out: list = [round(r.time, 9), r.line, r.cycle, timing.period, timing.late, alarms]
    for i, (cmd, act) in enumerate(zip(r._commands.tolist(), r.actual.tolist())):
        tx, f = txs[i], facs[i]
        cpu = f.cpu
        out += [cmd, act, tx.velocity_actual / f.raw_per_cps / cpu, tx.torque_actual * f.torque,
                tx.following_error / cpu, tx.statusword]
    rxs = r.rx
    for k in range(n_axes, len(facs)):
        tx, f = txs[k], facs[k]
        cpu, rpc, lead = f.cpu, f.raw_per_cps, f.lead
        out += [rxs[k].target_velocity / rpc / cpu / lead * 60.0, tx.velocity_actual / rpc / cpu / lead * 60.0,
                tx.position_actual / cpu % 360.0, tx.torque_actual * f.torque, tx.statusword]
    for src in r.trace_sources:
        out += list(src.values(r))
    return out


def setpoints(r: Any, following: bool, n_axes: int) -> None:
    """The axes' position setpoints (AxisScaling.to_counts spelt out: int(round(units × counts_per_unit)))
    and the run's largest |following error| per axis."""
    cmds, origin, max_ferr, names = r._commands.tolist(), r.origin.tolist(), r.result.max_ferr, r.axes
    rxs, txs, facs, masters, braking = r.rx, r.tx, r._factors, r.masters, r._braking
    for i in range(n_axes):
        rx, tx, cpu = rxs[i], txs[i], facs[i].cpu
        if following and masters[i].state is _ENABLED:
            rx.target_position = int(round((cmds[i] - origin[i]) * cpu))
        elif braking and tx.statusword & 0x6F == 0x27:
            # Until the drive takes its quick stop, the setpoint goes on at the speed it had:
            # a setpoint that stopped dead would brake harder than the drive's own ramp.
            rx.target_position += r._coast[i]
            r._commands[i] = r.scales[i].to_units(rx.target_position) + r.origin[i]
        else:
            # Not enabled: follow the actual position so enabling never jumps.
            rx.target_position = tx.position_actual
            r._commands[i] = r.actual[i]
        ferr = abs(tx.following_error / cpu)
        name = names[i]
        if ferr > max_ferr[name]:
            max_ferr[name] = ferr


WARM_AHEAD_NS = 60_000  # the warm-up starts this long before the clock's own spin (busy_wait, 200 µs by default)
WARM_MIN_NS = 120_000  # and only with this much left: it costs 20-60 µs


def warm(r: Any, n_axes: int) -> None:
    """Reads, in the slack before a stepped cycle's tick, what that cycle will read first (decision B43).

    After a stretch the caches hold the paced loop, not the full cycle: a block end costs ≈ 110 µs warm in lock-step
    and 260-400 µs after the caches were swept. Only reads: the trace row (thrown away), the spindle speeds, the MLC
    memory blocks the link and the drive status use. Nothing here writes state, so every result is unchanged."""
    ch = r.channel
    if not r.trace_sources and not (r.result.alarms or (ch is not None and ch.alarms)):
        row(r, n_axes)  # _new_alarms (which marks alarms seen) is not reached without alarms
    link = getattr(r.mlc, "link", None)
    mem = getattr(link, "mem", None)
    if ch is not None and r.bench.spindles:
        r.spindle_command_rpm()
    if mem is None:
        return
    link.commanded_rpm(0)
    mem.no_alarms()
    b2, b3 = 20000 + 1000 * link.x, 30000 + 1000 * link.x
    bytes(mem.m[b2:b2 + 1000]), bytes(mem.m[b3:b3 + 1000])  # M2x…, M3x…
    mem.word_bytes(b2, 1000), mem.word_bytes(b3, 1000), mem.word_bytes(30000, 1000)  # D2x…, D3x…, drive words
