"""The planner's spindle-locked thread chains, stepped cycle by cycle (nc.motion.threading). A mixin of `Planner`."""

from __future__ import annotations

from itertools import islice

import numpy as np

from nc.motion import threading as thr
from nc.motion.plan_state import Setpoint, _near
from nc.motion.thread_corners import corner_offset


class ThreadStepping:
    """Methods of `nc.motion.planner.Planner` (its state is the planner's own: see that module's doc)."""

    def _thread_step(self) -> Setpoint:
        """One cycle of a spindle-locked thread chain (see nc.motion.threading)."""
        T = self.cfg.cycle
        b = self.blocks[0]
        self._started = True
        angle = float(self.spindle_angle())
        st = self._thread
        if st is None:
            if self._stopping:
                self._flush()
                return Setpoint(self.position.copy(), self.line, 0.0, None)
            if b.seg is not None and _near(b.seg.start, self.position):
                b.seg.start = self.position.copy()
            self.line = b.move.line
            if self.spindle_command is not None and not self._settle.ready(float(self.spindle_command())):
                self.spindle_wait = True  # the spindle still changes speed: stand still on the thread's line
                self._wait_cycles += 1
                self.v = self.a = 0.0
                return Setpoint(self.position.copy(), self.line, 0.0, b.move)
            self.spindle_wait = False
            self.thread_waits.append((b.move.line, self._wait_cycles))
            self._wait_cycles = 0
            st = self._thread = thr.arm(b, angle, float(self.spindle_rpm()), float(self.spindle_index()),
                                        b.move.line)
            self.thread_log.append((b.move.line, st.sync_angle, st.ramp_start))
            self.solves += 1
        if self._stopping and not st.stopping:
            if st.v <= 1e-9 and not st.locked:
                self._flush()
                return Setpoint(self.position.copy(), self.line, 0.0, None)
            chain = [b]
            for nb in islice(self.blocks, 1, None):  # the thread blocks the stop may run on into
                if nb.kind != "thread":
                    break
                chain.append(nb)
            thr.stop(st, chain)
        while True:
            last = not (len(self.blocks) > 1 and self.blocks[1].kind == "thread")  # a stop runs on too (motion 63)
            if not last:
                thr.add_corner(st, b, self.blocks[1], self.lim.acc, self.lim.jerk)
            s = thr.advance(st, b, angle, T, last)
            if s is not None:
                break
            if last:
                self.position = b.seg.end.copy()
                self._thread = None
                self.s = self.v = self.a = 0.0
                self._finish_block()
                return Setpoint(self.position.copy(), b.move.line, 0.0, b.move)
            self._finish_block(keep_plan=True)
            nb = self.blocks[0]
            thr.next_block(st, b, nb)
            b = nb
        self.position = b.seg.points(np.array([s]))[0]
        if st.corners:  # the chain's corners are rounded within the axes' limits (nc.motion.thread_corners)
            off = corner_offset(st.corners, st.u_block + s / thr.major_factor(b))
            if off is not None:
                self.position = self.position + off
        self.line = b.move.line
        self.s, self.v, self.a = s, st.v, 0.0
        if st.halted:
            self._flush()
            self.v = 0.0
        return Setpoint(self.position.copy(), self.line, st.v, b.move)
