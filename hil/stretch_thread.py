"""A spindle-locked thread chain's cycles as a stretch (decision bench B104, issue 17).

A thread's setpoints follow the spindle's measured angle each cycle (nc.motion.threading), so its cycles were all
stepped. But in lock-step on the in-process bus the spindle drive runs at a speed the MLC commands, whatever the
axes do: its feedback over a stretch is known before the axes' setpoints are (`csv_stretch`). The sampler steps
the planner itself (`Planner.step`, the thread's own step) once per cycle with that cycle's spindle feedback in
the runner's TxPdo, where the runner's spindle callbacks read it, and hands out the setpoints as a stretch's
samples; the axes' drives are then stepped over them as for any stretch.

A stretch stays inside one block of the chain: it ends before the cycle whose step finishes a block (the queue
changes, which the channel's feed reads the next cycle) or stops the chain. The thread's state (`ThreadState`,
changed in place by each step) is stepped on a copy, so that the planner saved before the stretch still holds
the state it had (a cut restores it and samples again), and the spindle settle count is left as it was: the
stretch replays it from the cycles' speeds (`settle_stretch`), as for any stretch.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import numpy as np

from fieldbus.pdo import TxPdo
from hil.stretch_state import _restore_planner, _save_planner
from nc.motion.planner import Planner
from nc.motion.stretch import Samples
from virtual_bus.drive_stretch import Stretch


def thread_running(pl: Planner) -> bool:
    """A chain locked to the spindle, on its way through a thread block, nothing stopping it."""
    st = pl._thread
    return (st is not None and not st.stopping and not st.halted and not pl._stopping and not pl.held
            and bool(pl.blocks) and pl.blocks[0].kind == "thread")


def _clone(st: Any) -> Any:
    c = copy.copy(st)
    c.corners = list(st.corners)
    return c


def thread_sampler(r: Any, spindle: Stretch, n_axes: int) -> Callable[[Planner, int], Samples | None]:
    """The sampler of a thread stretch whose spindle drive's feedback is `spindle` (cycle by cycle)."""
    last = spindle.last
    assert last is not None
    probe = (last.error_code, last.mode_display, last.touch_probe_status, last.touch_probe_pos1, last.digital_inputs)
    feedback = [TxPdo(sw, pos, vel, tq, fe, *probe) for sw, pos, vel, tq, fe in
                zip(spindle.statusword, spindle.position_actual, spindle.velocity_actual, spindle.torque_actual,
                    spindle.following_error)]

    def steps(pl: Planner, n: int) -> tuple[int, list, list, list, list, list]:
        st = pl._thread
        pl._thread = _clone(st)
        blocks, first = len(pl.blocks), pl.blocks[0]
        settle = pl._settle.cycles
        tx = r.tx
        r.tx = mine = list(tx)
        positions: list = []
        raw: list = []
        lines: list[int] = []
        vel: list[float] = []
        moves: list = []
        try:
            for c in range(n):
                mine[n_axes] = feedback[c]
                sp = pl.step()
                if len(pl.blocks) != blocks or not thread_running(pl) or pl.blocks[0] is not first:
                    return c, positions, raw, lines, vel, moves  # this step is not the stretch's: undone
                positions.append(sp.positions)
                raw.append(pl.position)
                lines.append(sp.line)
                vel.append(sp.path_velocity)
                moves.append(sp.move)
        finally:
            r.tx = tx
            pl._settle.cycles = settle
        return n, positions, raw, lines, vel, moves

    def sampler(pl: Planner, n: int) -> Samples | None:
        if not thread_running(pl) or n > len(feedback):
            return None
        saved = _save_planner(pl)
        saved["blocks"] = list(pl.blocks)  # (a step that finishes a block pops it)
        m, *rows = steps(pl, n)
        if m < n:  # the last step left the block or the chain: the planner as after the m before it
            _restore_planner(pl, saved)
            if m < 1:
                return None
            m, *rows = steps(pl, m)
        positions, raw, lines, vel, moves = rows
        return Samples(np.array(positions, dtype=float), lines, np.array(vel, dtype=float), moves[0], moves,
                       np.array(raw, dtype=float))

    return sampler
