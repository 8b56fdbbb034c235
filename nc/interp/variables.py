"""Macro variable store. None is the vacant value (#0, NC5 App. B.3.1.1).

One `Variables` object per channel holds the user classes of the profile (nc5: local #1–#99,
public #100–#999, retentive #2000–#3999, extend #4000–#11999; lathe-2018: local #1–#50, global
#51–#250, maintain #1601–#1800, extension #10001–#10450), a stack of local frames, the MLC
exchange (`MlcExchange`) and read/write hooks for the system variables the interpreter provides.

The MLC (issue 8) shares ``interpreter.vars.mlc``: it writes the MLC→NC half with
``mlc.set_input(var, value)`` (or ``mlc.inputs[var] = value``) and reads the NC→MLC half from
``mlc.outputs`` (var -> value); ``mlc.on_write`` (if set) is called as ``on_write(var, value)``
whenever the program writes an output variable, and ``vars.on_macro_alarm`` fires for #20020/#6000.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from nc.alarms import NcAlarm

Value = float | None


@dataclass
class MlcExchange:
    """The # variables the MLC and the NC program share.

    nc5 (N§3.2.2): #25000–#25127 ← M2x128–M2x255 (read), #25128–#25255 ← D2x128–D2x255 (read),
    #25256–#25383 → M3x128–M3x255 (read/write), #25384–#25511 → D3x128–D3x255 (read/write).
    lathe-2018 (L§4.1.3): #1801–#1832 ← M1024–M1055, #1833–#1848 ← D1024–D1039 (read),
    #1864–#1895 → M2080–M2111, #1896–#1911 → D1336–D1351 (write).
    """

    legacy: bool = False
    inputs: dict[int, float] = field(default_factory=dict)  # MLC -> NC
    outputs: dict[int, float] = field(default_factory=dict)  # NC -> MLC
    on_write: Callable[[int, float], None] | None = None

    @property
    def input_ranges(self) -> list[tuple[int, int, bool]]:  # (first, last, is_bit)
        if self.legacy:
            return [(1801, 1832, True), (1833, 1848, False)]
        return [(25000, 25127, True), (25128, 25255, False)]

    @property
    def output_ranges(self) -> list[tuple[int, int, bool]]:
        if self.legacy:
            return [(1864, 1895, True), (1896, 1911, False)]
        return [(25256, 25383, True), (25384, 25511, False)]

    def kind(self, number: int) -> tuple[str, bool] | None:
        for lo, hi, bit in self.input_ranges:
            if lo <= number <= hi:
                return "in", bit
        for lo, hi, bit in self.output_ranges:
            if lo <= number <= hi:
                return "out", bit
        return None

    def device(self, number: int, path: int = 1) -> str:
        """The MLC device a variable mirrors, e.g. #25256 -> 'M31128' (path 1)."""
        if self.legacy:
            table = [(1801, "M", 1024), (1833, "D", 1024), (1864, "M", 2080), (1896, "D", 1336)]
            for lo, dev, base in reversed(table):
                if number >= lo:
                    return f"{dev}{base + number - lo}"
        table5 = [(25000, "M", 2), (25128, "D", 2), (25256, "M", 3), (25384, "D", 3)]
        for lo, dev, grp in reversed(table5):
            if number >= lo:
                return f"{dev}{grp}{path}{128 + number - lo:03d}"
        raise KeyError(number)

    def set_input(self, number: int, value: float) -> None:
        k = self.kind(number)
        if k is None or k[0] != "in":
            raise KeyError(f"#{number} is not an MLC->NC variable")
        self.inputs[number] = float(bool(value)) if k[1] else float(value)

    def read(self, number: int) -> float:
        k = self.kind(number)
        if k and k[0] == "in":
            return self.inputs.get(number, 0.0)
        return self.outputs.get(number, 0.0)

    def write(self, number: int, value: float) -> None:
        k = self.kind(number)
        if k is None or k[0] != "out":
            raise NcAlarm(0x0254, f"#{number} is read-only (MLC -> NC exchange)")
        v = float(value)
        if k[1]:
            v = 0.0 if v == 0 else 1.0  # bit variables are only 0/1 (L§4.1.3)
        self.outputs[number] = v
        if self.on_write is not None:
            self.on_write(number, v)


SystemRead = Callable[[int], "Value | type[NotImplemented]"]
SystemWrite = Callable[[int, Value], bool]


@dataclass
class Variables:
    """User variables plus hooks; ``system_read(n)`` / ``system_write(n, v)`` return NotImplemented /
    False for numbers they do not own."""

    legacy: bool = False  # lathe-2018 map
    values: dict[int, float] = field(default_factory=dict)  # public / retentive / extend
    frames: list[dict[int, float]] = field(default_factory=lambda: [{}])  # local levels
    mlc: MlcExchange = field(default_factory=MlcExchange)
    system_read: Callable[[int], object] | None = None
    system_write: Callable[[int, Value], bool] | None = None
    on_macro_alarm: Callable[[int], None] | None = None

    def __post_init__(self) -> None:
        self.mlc.legacy = self.legacy
        self._lmax = self.local_max  # `get`/`set` test it on every read and write (macro hot path)

    @property
    def local_max(self) -> int:
        return 50 if self.legacy else 99

    def is_user(self, n: int) -> bool:
        if self.legacy:
            return 51 <= n <= 250 or 1601 <= n <= 1800 or 10001 <= n <= 10450
        return 100 <= n <= 999 or 2000 <= n <= 11999

    def is_retentive(self, n: int) -> bool:
        """Kept through power-off: nc5 retentive #2000-#3999 and extend #4000-#11999 (N§3.11.1 table); lathe-2018
        maintain #1601-#1800 and extension #10001-#10450 ("non-volatile", L§ macro variables)."""
        if self.legacy:
            return 1601 <= n <= 1800 or 10001 <= n <= 10450
        return 2000 <= n <= 11999

    # ---- local frames (G65/G66/G-M-T call push one; M98 shares the caller's, decisions A19)
    def push_locals(self, args: dict[int, float]) -> None:
        self.frames.append(dict(args))

    def pop_locals(self) -> None:
        if len(self.frames) > 1:
            self.frames.pop()

    @property
    def local_depth(self) -> int:
        return len(self.frames) - 1

    def get(self, number: int) -> Value:
        n = number
        if 0 < n <= self._lmax:  # locals first: most reads of a macro
            return self.frames[-1].get(n)
        if n == 0:
            return None
        if self.is_user(n):
            return self.values.get(n)
        if self.mlc.kind(n):
            return self.mlc.read(n)
        if self.system_read is not None:
            v = self.system_read(n)
            if v is not NotImplemented:
                return v  # type: ignore[return-value]
        raise NcAlarm(0x0235, f"#{n} is not a variable of this controller")

    def set(self, number: int, value: Value) -> None:
        n = number
        if 0 < n <= self._lmax:
            if value is None:
                self.frames[-1].pop(n, None)
            else:
                self.frames[-1][n] = float(value)
            return
        if n == 0:
            raise NcAlarm(0x0254, "#0 is read-only (vacant)")
        if self.is_user(n):
            if value is None:
                self.values.pop(n, None)
            else:
                self.values[n] = float(value)
            return
        if self.mlc.kind(n):
            self.mlc.write(n, 0.0 if value is None else value)
            return
        if n == (6000 if self.legacy else 20020):
            v = 0.0 if value is None else value
            hi = 1000 if self.legacy else 32767
            if not 0 <= v <= hi or v != int(v):
                raise NcAlarm(0x0244, f"#{n} = {v:g} is outside 0..{hi}")
            if v and self.on_macro_alarm is not None:
                self.on_macro_alarm(int(v))
            if v:
                raise NcAlarm(f"MR{int(v)}", f"macro alarm MR{int(v)} (#{n} = {int(v)})")
            return
        if self.system_write is not None and self.system_write(n, value):
            return
        if self.system_read is not None and self.system_read(n) is not NotImplemented:
            raise NcAlarm(0x0254, f"#{n} is read-only")
        raise NcAlarm(0x0235, f"#{n} is not a variable of this controller")
