"""System # variables the interpreter provides (NC5 App. B.3; lathe manual §4.1.2).

`SystemVariables.read(n)` returns the value, or NotImplemented for a number it does not own;
`write(n, v)` returns True when it stored the value.  Read-only numbers reject writes with 0x0254
(via `Variables.set`).  ``live(n)`` tells whether touching n stops preview (● in App. B).

Decisions: positions are NC5 #21000+i (machine), #21016+i (absolute), #21032+i (target),
#21048+i / #21064+i (G31 latch), i = the axis' index in the channel (profile axes order); Fanuc
numbers such as #5001 are ordinary extend variables on NC5 and are not positions.
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING

from nc.alarms import NcAlarm

if TYPE_CHECKING:  # pragma: no cover
    from nc.interp.host import InterpHost

CONSTANTS = [math.e, math.log2(math.e), math.log10(math.e), math.log(2), math.log(10), math.pi, math.pi / 2,
             math.pi / 4, 1 / math.pi, 2 / math.pi, 2 / math.sqrt(math.pi), math.sqrt(2), 1 / math.sqrt(2)]
LEGACY_AXES = ("X", "Y", "Z", "A", "B", "C")
NC5_TOOL_BASES = {26000: "length", 42000: "wear", 61000: "tolerance", 77000: "life_target_axis",
                  93000: "life_used_axis"}


class SystemVariables:
    def __init__(self, interp: "InterpHost") -> None:
        self.i = interp
        self.t0 = time.monotonic()

    # ---- helpers
    def _axis(self, idx: int) -> str | None:
        axes = LEGACY_AXES if self.i.profile.legacy else self.i.axes
        return axes[idx] if 0 <= idx < len(axes) else None

    def _wcs_value(self, wcs: int | None, axis: str) -> float:
        fr = self.i.frames
        v = fr.external.get(axis, 0.0) if wcs is None else fr.work_offsets[wcs].get(axis, 0.0)
        return v * 2.0 if axis in self.i.profile.diameter_axes else v

    def _set_wcs(self, wcs: int | None, axis: str, value: float) -> None:
        fr = self.i.frames
        v = value / 2.0 if axis in self.i.profile.diameter_axes else value
        if wcs is None:
            fr.external[axis] = v
        else:
            fr.writable_offsets()[wcs][axis] = v

    def live(self, n: int) -> bool:
        if self.i.profile.legacy:
            return 2100 <= n <= 2217 or n == 6000
        return 20020 <= n <= 20026 or 20404 <= n <= 20411 or 21000 <= n <= 23183 or 24001 <= n <= 24004 \
            or 195000 <= n <= 195999

    # ---- read
    def read(self, n: int) -> object:
        return self._legacy_read(n) if self.i.profile.legacy else self._nc5_read(n)

    def _positions(self, n: int, base: int) -> object:
        i = self.i
        idx = n - base
        kind, k = divmod(idx, 16)
        a = self._axis(k)
        if a is None:
            return None
        if kind == 0:
            return i.position[a]
        if kind == 1:
            return i.work_position()[a]
        if kind == 2:
            return i.last_target.get(a)
        if kind in (3, 4):
            if i.skip_position is None:
                return None
            return i.skip_position[a] if kind == 3 else i.to_work(i.skip_position)[a]
        return 0.0

    def _nc5_read(self, n: int) -> object:
        i, st = self.i, self.i.state
        if 20000 <= n <= 20012:
            return CONSTANTS[n - 20000]
        if n == 20020:
            return 0.0
        if n in (20021, 20022):
            return 0.0
        if n == 20023:  # the value of the last G10 L40/L41/L45/L46 (App. B.3.4.1)
            return i.servo.value
        if n == 20024:  # its execution result, 0 = done
            return i.servo.result
        if n == 20025:
            t = time.localtime()
            return float((t.tm_year % 100) * 10000 + t.tm_mon * 100 + t.tm_mday)
        if n == 20026:
            t = time.localtime()
            return float(t.tm_hour * 10000 + t.tm_min * 100 + t.tm_sec)
        if 20300 <= n <= 20331:
            return float(st.groups.get(n - 20300, 0.0)) if n - 20300 in st.groups else None
        if n == 20400:
            return st.feed
        if n == 20401:
            return float(st.h_number)
        if n == 20402:
            return float(st.d_number)
        if n == 20403:
            return float(st.tool)
        if 20404 <= n <= 20411:
            return st.spindle_speed if n == 20404 else 0.0
        if 21000 <= n <= 21095:
            return self._positions(n, 21000)
        if 22000 <= n <= 23247:
            a_idx, off = divmod(n - 22000, 78)
            a = self._axis(a_idx)
            if a is None:
                return NotImplemented
            if off == 0:
                return self._wcs_value(None, a)
            if 2 <= off <= 7:
                return self._wcs_value(off - 2, a)
            if 8 <= off <= 13:
                return self._wcs_value(off - 8, a)
            if 14 <= off <= 77:
                return self._wcs_value(6 + off - 14, a)
            return None
        if n in (24001, 24002):
            return float(st.tool) if n == 24001 else 0.0
        if n in (24003, 24004):
            return 0.0
        t = self._nc5_tool(n)
        if t is not None:
            table, key = t
            return table.get(key, 0.0)
        return NotImplemented

    def _nc5_tool(self, n: int):
        tools = self.i.tools
        for base, name in NC5_TOOL_BASES.items():
            if base <= n < base + 16000:
                a_idx, t = divmod(n - base, 1000)
                a = self._axis(a_idx)
                if a is None:
                    return None
                table = {"length": tools.lengths, "wear": tools.wears, "tolerance": tools.tolerance}.get(name)
                if table is None:
                    return tools.life, (name + a, t + 1)
                return table, (a, t + 1)
        if 58000 <= n <= 58999:
            return tools.radius, n - 58000 + 1
        if 59000 <= n <= 59999:
            return tools.radius_wear, n - 59000 + 1
        if 60000 <= n <= 60999:
            return tools.life, ("status", n - 60000 + 1)
        if 192000 <= n <= 195999:
            return tools.life, (("target", "used_time", "target_count", "used_count")[(n - 192000) // 1000],
                                (n % 1000) + 1)
        return None

    def _legacy_read(self, n: int) -> object:
        i, st = self.i, self.i.state
        if 2000 <= n <= 2019:
            return float(st.groups[n - 2000]) if n - 2000 in st.groups else 0.0
        if n == 2020:
            return st.feed
        if n == 2023:
            return float(st.tool)
        if n == 2024:
            return st.spindle_speed
        if 2100 <= n <= 2217:
            blk, k = divmod(n - 2100, 16)
            a = self._axis(k)
            if a is None or k > 5 or a not in i.axes:
                return None if k <= 5 else NotImplemented
            if blk == 0:
                return i.position[a]
            if blk in (1, 5):
                return i.work_position()[a]
            if blk == 2:
                return i.last_target.get(a)
            if blk in (3, 4):
                if i.skip_position is None:
                    return None
                return i.skip_position[a] if blk == 3 else i.to_work(i.skip_position)[a]
            return 0.0
        if 2300 <= n <= 2302:
            return i.last_arc_ijk[n - 2300]
        if n == 2303:
            return (time.monotonic() - self.t0) * 1000.0
        if n in (2304, 2305):
            return float(st.tool // 100 if st.tool >= 100 else st.tool) if n == 2304 else 0.0
        if 3000 <= n <= 3646:
            a_idx, off = divmod(n - 3000, 128)
            a = self._axis(a_idx)
            if a is None or off > 6 or a not in i.axes:
                return NotImplemented if (a is None or off > 6) else 0.0
            return self._wcs_value(None if off == 0 else off - 1, a)
        if n == 6000:
            return 0.0
        t = self._legacy_tool(n)
        if t is not None:
            table, key = t
            return table.get(key, 0.0)
        if n == 8600:
            return getattr(self, "timer", 0.0)
        return NotImplemented

    def _legacy_tool(self, n: int):
        tools = self.i.tools
        for base, what in ((6000, ("length", "X")), (6200, ("length", "Y")), (6400, ("length", "Z")),
                           (6600, ("wear", "X")), (6800, ("wear", "Y")), (7000, ("wear", "Z"))):
            if base + 1 <= n <= base + 64:
                table = tools.lengths if what[0] == "length" else tools.wears
                return table, (what[1], n - base)
        for base, table in ((7200, tools.radius), (7400, tools.radius_wear), (7600, tools.tip)):
            if base + 1 <= n <= base + 64:
                return table, n - base
        return None

    # ---- write
    def write(self, n: int, v: float | None) -> bool:
        val = 0.0 if v is None else float(v)
        i = self.i
        i._lean_origin = None  # offsets and tool data: the lean lane's origin is found again (nc.interp.lean)
        if i.profile.legacy:
            if 3000 <= n <= 3646:
                a_idx, off = divmod(n - 3000, 128)
                a = self._axis(a_idx)
                if a is None or off > 6:
                    return False
                if a in i.axes:
                    self._set_wcs(None if off == 0 else off - 1, a, val)
                return True
            t = self._legacy_tool(n)
            if t is not None:
                t[0][t[1]] = val
                i._apply_tool_offset() if i.profile.is_lathe else None
                return True
            if n == 8600:
                self.timer = val
                return True
            if n in (2500, 2501):
                return True
            return False
        if 22000 <= n <= 23247:
            a_idx, off = divmod(n - 22000, 78)
            a = self._axis(a_idx)
            if a is None or off == 1:
                return False
            wcs = None if off == 0 else (off - 2 if off <= 7 else off - 8 if off <= 13 else 6 + off - 14)
            self._set_wcs(wcs, a, val)
            return True
        if n in (24003, 24004):
            return True
        t = self._nc5_tool(n)
        if t is not None:
            t[0][t[1]] = val
            if i.profile.is_lathe:
                i._apply_tool_offset()
            return True
        return False
