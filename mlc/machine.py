"""The MLC as the bench runs it: device memory, the NC side of the special M/D interface for the
channel, remote I/O, and a user scan program, scanned once per bench cycle.

    mlc = Mlc.load("examples/mlc/my_lathe.py", axes=("X", "Z"))   # or Mlc() for the default lathe MLC
    runner = BenchRunner(bench, link, trace, mlc)

Per cycle (`scan(channel)`, called by the runner before the channel step):
  1. the NC reads the relays/registers the MLC wrote in its previous scan and acts on them;
  2. the NC publishes its status for this cycle (modes, strobes + code data, drive status …);
  3. the user program's `scan(ctx)` runs;
  4. the spindle command the drives get is taken from the spindle relays.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from mlc.memory import DeviceMemory
from mlc.nc_link import ChannelLink, DriveStatus
from mlc.on_change import ScanGate, wants_gate
from mlc.program import ScanContext
from mlc.spindle_axis import MODE_CSP, MODE_CSV, SpindleAxisSwitch
from mlc.signals import d2, m2, m3
from nc.alarms import Alarm, NcAlarm
from nc.channel import Channel
from nc.manual import ManualMotion
from nc.motion.limits import MotionConfig


class MlcLoadError(ValueError):
    """The MLC module cannot be loaded or has no scan function."""


@dataclass
class SpindleOutput:
    """What the spindle drive is told (the runner reads `signed_rpm`; the planner reads `rpm`)."""

    rpm: float = 0.0
    direction: int = 0

    @property
    def signed_rpm(self) -> float:
        return self.rpm * self.direction


def load_program(spec: str | None) -> Any:
    """An MLC program by file path (``examples/mlc/x.py``) or module name (``mlc.lathe``)."""
    if spec is None:
        import mlc.lathe as default

        return default
    path = Path(spec)
    try:
        if path.suffix == ".py" or path.exists():
            if not path.is_file():
                raise MlcLoadError(f"MLC module {spec} does not exist")
            name = f"mlc_user_{path.stem}"
            mod_spec = importlib.util.spec_from_file_location(name, path)
            if mod_spec is None or mod_spec.loader is None:
                raise MlcLoadError(f"MLC module {spec} cannot be loaded")
            module: ModuleType = importlib.util.module_from_spec(mod_spec)
            sys.modules[name] = module
            mod_spec.loader.exec_module(module)
        else:
            module = importlib.import_module(spec)
    except MlcLoadError:
        raise
    except Exception as exc:  # a syntax error in the user's file is a usage error, not a crash
        raise MlcLoadError(f"MLC module {spec} failed to load: {type(exc).__name__}: {exc}") from None
    if not callable(getattr(module, "scan", None)):
        raise MlcLoadError(f"MLC module {spec} has no scan(mlc) function")
    return module


class Mlc:
    def __init__(self, program: Any = None, axes: tuple[str, ...] = ("X", "Z"), cycle: float = 0.001,
                 motion: MotionConfig | None = None, max_rpm: float = 6000.0, channel: int = 1,
                 word_order: str = "low-first", start: dict[str, float] | None = None) -> None:
        self.program = program if program is not None else load_program(None)
        self.mem = DeviceMemory(word_order=word_order)  # type: ignore[arg-type]
        self.cycle = cycle
        self.axes = tuple(axes)
        cfg = motion or MotionConfig(cycle=cycle, axes=self.axes)
        pos = np.array([(start or {}).get(a, 0.0) for a in self.axes])
        self.manual = ManualMotion(cfg, pos)
        self.link = ChannelLink(self.mem, channel, self.axes, self.manual, spindle_max_rpm=max_rpm)
        self.ctx = ScanContext(self.mem, channel, cycle, params={"max_rpm": max_rpm})
        self.spindle = SpindleOutput()
        self.drives: list[DriveStatus] | None = None
        self.io_modules: list[Any] = []  # virtual_bus.io modules (or real ones) exchanged every scan
        self.bus: Any = None  # fieldbus.link.LinkStatus of this cycle, when the bench's link reports one
        self.time = 0.0
        self.caxis = SpindleAxisSwitch(self.mem, channel, cycle)  # spindle ↔ C axis, M19 (issue 8 item 5)
        self.caxis_alarmed = False
        self._power_on_image(channel)
        # SCAN_ON_CHANGE programs (the default lathe MLC): the scan runs when what it read changed
        self.gate = ScanGate(self.ctx) if wants_gate(self.program) else None
        setup = getattr(self.program, "setup", None)
        if callable(setup):
            setup(self.ctx)

    @classmethod
    def load(cls, spec: str | None, **kw: Any) -> "Mlc":
        return cls(load_program(spec), **kw)

    def _power_on_image(self, x: int) -> None:
        """Override switches at 100 %, MPG ratio ×1, INC step 1 unit (a panel's usual power-on state)."""
        for i in (2, 4, 6, 26):
            self.mem.set_u16(d2(x, i), 100)
        self.mem.set_u16(d2(x, 9), 1)
        self.mem.set_u32(d2(x, 14), 1)
        self.mem.set_bit(m2(x, 12), True)  # servo ON request
        self.mem.set_bit(29035, True)  # "remaining ON"

    # ---- wiring from the bench -------------------------------------------------------------------
    def attach_variables(self, variables: Any) -> None:
        """Share the interpreter's # variable store (#25000–#25511, #20020)."""
        self.link.variables = variables

    def attach_interpreter(self, interp: Any) -> None:
        """The variable store, and the block skip switch M2x010 (App. B.2.1.1), which the MLC drives from here on:
        a profile that presets the switch ON (parameter ``M2x010``, `hil path --block-skip`) sets the relay at
        power-on, as a panel's switch left ON would (decision M21-1)."""
        self.attach_variables(interp.vars)
        self.link.interp = interp
        # M3x512…: ON for the channel's axes the lathe programs in diameter (N2.001 Bit10; decision M21-3)
        dia = getattr(getattr(interp, "profile", None), "diameter_axes", ())
        for i, a in enumerate(self.link.axes[:16]):
            self.mem.set_bit(m3(self.link.x, 512 + i), a in dia)
        if interp.block_skip:
            self.mem.set_bit(m2(self.link.x, 10), True)
        elif self.mem.bit(m2(self.link.x, 10)):  # set by the MLC's setup: the first block is read before a scan
            interp.block_skip = True

    def bus_feedback(self, drives: list[DriveStatus]) -> None:
        self.drives = drives
        self.link.drives = drives  # the manual modes hold an axis its limit switch stopped (App. A 0x0A06)

    def bus_status(self, status: Any) -> None:
        """The link's state this cycle (`fieldbus.link.LinkStatus`): drives M30000 and the EIO relays."""
        self.bus = status

    # ---- the scan ---------------------------------------------------------------------------------
    def scan(self, channel: Channel) -> None:
        self.time += self.cycle
        self._clocks()
        self._read_io()
        self.link.nc_inputs(channel)
        self.link.nc_outputs(channel, self.drives)
        self._bus_relays()
        ctx = self.ctx
        ctx.time, ctx.scan_count = self.time, ctx.scan_count + 1
        if not getattr(self, "program_failed", False):
            try:
                gate = self.gate
                if gate is None:
                    self.program.scan(ctx)
                elif not gate.quiet():
                    gate.run(self.program.scan)
            except NcAlarm:
                raise
            except Exception as exc:  # the user's MLC code, not the NC: its own alarm, file, line, traceback
                from mlc.user_error import mlc_program_alarm

                # like a PLC whose program faulted: it goes to STOP, the NC stops the channel under control
                self.program_failed = True
                alarm = mlc_program_alarm(exc, getattr(self.program, "__file__", None))
                raise NcAlarm(alarm.code, alarm.message) from None
        self._write_io()
        rpm = self.link.commanded_rpm(0)
        self.spindle.rpm, self.spindle.direction = abs(rpm), (1 if rpm > 0 else -1 if rpm < 0 else 0)
        if self.link._estop:
            self.spindle.direction = 0

    def spindle_drive(self, runner: Any) -> tuple[int, float | None, float | None]:
        """The first spindle drive's (mode, position setpoint deg, speed override rpm) this cycle:
        CSV as a spindle, CSP while positioning (M29/M19) or while it is the channel's C axis, CSP following the
        channel's G84.48 / M2x707 retraction of an interrupted tap (nc.tap_interrupt, decision M26-4)."""
        ch = runner.channel
        rt = ch.tap_retraction if ch is not None else None
        if rt is not None:
            return MODE_CSP, rt.spindle_setpoint(runner.spindle_actual_angle()), None
        if self.caxis.idle():  # the usual cycle: a spindle that stays one, its feedback not read
            if not self.caxis.failed or self.caxis_alarmed:  # _caxis_checked would only pass it on
                return MODE_CSV, None, None
            return self._caxis_checked(runner, (MODE_CSV, None, None))
        n = len(runner.axes)
        tx = runner.tx[n]
        index = runner.spindle_index_angle() if tx.touch_probe_status & 0x0002 else None
        c_cmd = float(runner._commands[runner.axes.index("C")]) if "C" in runner.axes else None
        if c_cmd is None and self.caxis._want_c():  # App. A 0x0C04: no C axis in the channel to switch to
            if not self.caxis_alarmed:
                self.caxis_alarmed = True
                runner._alarm(Alarm(0x0C04, "incorrect switching of the spindle and C-axis: the MLC asks for C-axis "
                                            "mode (M2x708 / M1126) but the channel has no C axis",
                                    line=runner.line or None, axis=runner.bench.spindles[0].name))
            return MODE_CSV, None, None  # the spindle stays a spindle; the alarm stops the channel
        out = self.caxis.drive(runner.spindle_actual_angle(), runner.spindle_actual_rpm(), index, c_cmd)
        return self._caxis_checked(runner, out)

    def _caxis_checked(self, runner: Any, out: tuple[int, float | None, float | None]) -> tuple[int, float | None, float | None]:
        """App. A 0x0C01 once when the positioning outlasted its check time; `out` passed on."""
        if self.caxis.failed and not self.caxis_alarmed:
            self.caxis_alarmed = True
            runner._alarm(Alarm(0x0C01, f"spindle positioning failed: not {'in C-axis mode' if self.caxis.purpose == 'C' else 'oriented'} "
                                        f"({self.caxis.state}) within the check time N0.1025 = "
                                        f"{self.caxis.check_time * 1000:g} ms", line=runner.line or None,
                                axis=runner.bench.spindles[0].name))
        return out

    def _clocks(self) -> None:
        t, m = self.time, self.mem.m
        m[29032] = 1 if int(t / 0.5) % 2 == 1 else 0
        m[29033] = 1 if int(t / 0.05) % 2 == 1 else 0

    def attach_io(self, ports: list[Any], maps: list[Any]) -> None:
        """Remote I/O stations (issue 8): `ports[k]` (a `mlc.remote_io.IoPort`) is station k, `maps[k]`
        its X/Y range (`mlc.remote_io.IoMap`)."""
        self.io_modules = list(ports)
        assert self.ctx.io is not None
        self.ctx.io.maps = list(maps)

    def _read_io(self) -> None:
        """Inputs of every station into its X range (or the module image) before the NC and the user
        scan; a station that is not connected reads 0 (safe state, docs/decisions/mlc.md)."""
        io = self.ctx.io
        assert io is not None
        while len(io.inputs) < len(self.io_modules):
            io.inputs.append(0)
        for k, port in enumerate(self.io_modules):
            di, analog_in = port.read_inputs(self.cycle)
            if not getattr(port, "connected", True):
                di, analog_in = 0, [0, 0, 0, 0]
            io.inputs[k] = di
            m = io.maps[k] if k < len(io.maps) else None
            if m is not None:
                self.mem.set_bits("X", m.x, m.inputs, di)
            for w, v in enumerate(analog_in[:4]):
                self.mem.set_u16(30200 + 4 * k + w, v)

    def _write_io(self) -> None:
        """The Y range (or the module image) of every station to its module, right after the user scan."""
        io = self.ctx.io
        assert io is not None
        for k, port in enumerate(self.io_modules):
            m = io.maps[k] if k < len(io.maps) else None
            outs = self.mem.bits("Y", m.y, m.outputs) if m is not None else (io.outputs[k] if k < len(io.outputs) else 0)
            port.write_outputs(outs, [self.mem.u16(20200 + 4 * k + w) for w in range(4)])

    def _bus_relays(self) -> None:
        """M30000 (EtherCAT communication status: every slave in OP, not servo on) and M30032+k (EIO
        node 501+k connected): the k-th I/O slave on the bus in connection order; an in-process module
        with no bus behind it counts as connected while it answers (its `connected`, default True)."""
        bus, m, modules = self.bus, self.mem.m, self.io_modules
        bus_io = bus.io if bus is not None else ()
        if bus is not None:
            m[30000] = 1 if bus.connected else 0
        n_bus = len(bus_io)
        for k in range(min(20, max(n_bus, len(modules)))):
            on = bus_io[k] if k < n_bus else getattr(modules[k], "connected", True)
            m[30032 + k] = 1 if on else 0  # EIO node 501+k connected

    # ---- convenience for scripts and tests ---------------------------------------------------------
    def get(self, address: str) -> int:
        return self.mem.get(address)

    def put(self, address: str, value: int) -> None:
        self.mem.put(address, value)
