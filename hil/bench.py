"""Bench description: the machine profile, axes with their drives and units, spindles, bus and cycle."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

from fieldbus.units import AxisScaling
from nc.motion.limits import AxisLimits, MotionConfig, MoveKindLimits
from hil.drive_homing import DriveHoming
from virtual_bus.drive_params import DriveParams

if TYPE_CHECKING:  # mlc.memory pulls numpy: `hil path` starts without it (issue 16)
    from mlc.remote_io import IoMap


@dataclass
class AxisConfig:
    name: str
    scaling: AxisScaling = field(default_factory=AxisScaling)
    limits: AxisLimits = field(default_factory=AxisLimits)
    drive: DriveParams = field(default_factory=DriveParams)
    start: float = 0.0  # machine position of the simulated axis at power-on, mm
    units: str = "mm"  # "mm" (linear) or "deg" (rotary)
    soft_limits: tuple[float, float] | None = None  # machine-coordinate travel window, units
    drive_model: str = "asda-a3-e"  # fieldbus.devices.MODELS: the identity its virtual EtherCAT slave presents
    drive_esi: str = ""  # a vendor ESI file the virtual EtherCAT slave is built from ("" = the packaged one)
    canopen_eds: str = ""  # the drive's EDS/DCF on a CANopen bus; "" = Bench.canopen_eds or the shipped ASDA-B3
    homing: DriveHoming | None = None  # drive homing (CiA 402 mode 6) before every program (hil/drive_homing.py)
    station_alias: int | None = None  # EtherCAT configured station alias its slave must have (None: not checked)


@dataclass
class SpindleConfig:
    name: str = "S1"
    scaling: AxisScaling = field(default_factory=lambda: AxisScaling(counts_per_rev=1_280_000, lead=360.0))
    max_rpm: float = 4000.0
    drive: DriveParams = field(default_factory=lambda: DriveParams(max_speed_rpm=6000.0, csv_accel=1.0e8))
    canopen_eds: str = ""  # as AxisConfig.canopen_eds
    drive_model: str = "asda-a3-e"  # as AxisConfig.drive_model
    drive_esi: str = ""  # as AxisConfig.drive_esi
    station_alias: int | None = None  # as AxisConfig.station_alias


LOCKSTEP_PLACEMENTS = ("default", "fifo")  # [realtime] lockstep: scheduled as any process / SCHED_FIFO on one CPU
# Axis limit bounds (mm or deg per s, s², s³): a 100 m/s axis or a jerk of 1e10 is no machine tool.
LIMIT_BOUNDS = {"velocity": (1e-3, 1e5), "acceleration": (1e-3, 1e7), "jerk": (1e-3, 1e10)}
LIMIT_FIELDS = {"velocity": "max_velocity", "acceleration": "max_acceleration", "jerk": "max_jerk"}  # bench -> AxisLimits
FILTER_MS = 16.0  # default N1.036 and N1.037 (ms)
PATH_DEVIATION = 0.02  # default N1.053 (mm)


@dataclass
class ParamGroup:
    """A G05 parameter group ([param_groups.N] in a bench file, N§3.8.2 "recipes" 1-20): the values it sets;
    what it leaves out keeps the bench's own (decision language L25-1)."""

    params: dict[str, float] = field(default_factory=dict)  # N1.030-N1.037, N1.053, "N2.020 X" ... (MODELLED)
    limits: dict[str, dict[str, float]] = field(default_factory=dict)  # axis -> {velocity, acceleration, jerk}


@dataclass
class IoStationConfig:
    """A remote I/O station ([[io]] in a bench file): its X/Y mapping and how it sits on each bus.
    EtherCAT: the k-th I/O slave in connection order (EIO node 501+k); CANopen: `canopen_node`;
    sim: an in-process `virtual_bus.io.IoModule`."""

    map: IoMap
    canopen_node: int = 64
    canopen_tpdo: str = "sync"  # "sync": inputs sent on every SYNC; "change": on change of state
    modules: tuple[str, ...] = ()  # EtherCAT R1-EC module list (DI16, DO8, …); () = the default DI16 + DO16
    canopen_eds: str = ""  # the station's EDS/DCF; "" = the shipped CiA 401 DIO


@dataclass
class ChecksConfig:
    """Pass/fail limits a run (or `hil check`) is judged by; None leaves a check out."""

    max_following_error: dict[str, float] = field(default_factory=dict)  # axis → mm
    contour_error: float | None = None  # mm from the programmed path
    limits: bool = False  # setpoint v/a/j within the axes' limits
    limit_tolerance: float = 0.02  # fraction above a limit still accepted (numeric differentiation noise)
    thread_phase: float | None = None  # degrees: max spread of spindle angle at each thread pass start
    jitter_p99: float | None = None  # s of |period - cycle|
    jitter_p999: float | None = None
    jitter_max: float | None = None

    @property
    def any(self) -> bool:
        return bool(self.max_following_error or self.contour_error is not None or self.limits
                    or self.thread_phase is not None or self.jitter_p99 is not None
                    or self.jitter_p999 is not None or self.jitter_max is not None)


@dataclass
class RealtimeConfig:
    """How the real-time pacer asks the system for determinism, and what an overrun does."""

    priority: int = 80  # SCHED_FIFO priority (1..99)
    cpu: int | None = None  # CPU to pin the cycle thread to
    busy_wait: float = 0.0002  # s spun on the clock before each deadline instead of sleeping
    overrun: str = "warn"  # "warn" or "alarm"
    lock_memory: bool = True  # mlockall so page faults don't hit the cycle
    # "fifo": a lock-step run (not only --realtime) takes SCHED_FIFO `priority` on `cpu` too, and `hil sim
    # ethercat --bench` places its slaves the same, so the two take turns on one CPU (decisions E21)
    lockstep: str = "default"


@dataclass
class Bench:
    name: str = "lathe-2axis"
    profile: str = "nc5-lathe-a"
    axes: list[AxisConfig] = field(default_factory=list)
    spindles: list[SpindleConfig] = field(default_factory=list)
    cycle: float = 0.001
    bus: str = "sim"
    params: dict[str, float] = field(default_factory=dict)
    enable_timeout: float = 0.5  # s allowed for every drive to reach operation enabled
    settle_time: float = 0.3  # s the bench keeps cycling after the program to let axes settle
    max_time: float = 3600.0  # s of simulated time before the run is abandoned with an alarm
    lookahead: int | None = None  # look-ahead depth in blocks; None: max(100, v/(2·a·T)) (issue 5)
    mlc: str = ""  # MLC logic: "" (by profile, see mlc_program), "basic", "lathe", "package.module" or a .py path
    checks: ChecksConfig = field(default_factory=ChecksConfig)
    realtime: RealtimeConfig = field(default_factory=RealtimeConfig)
    io: list[IoStationConfig] = field(default_factory=list)  # remote I/O stations, EIO 501, 502, …
    canopen_bitrate: int = 1_000_000  # bit/s of a CANopen bus: the bus budget, and python-can where it sets it
    canopen_eds: str = ""  # EDS/DCF of every CANopen drive without its own (AxisConfig.canopen_eds)
    param_groups: dict[int, ParamGroup] = field(default_factory=dict)  # G05 P1-P20 (decision language L25-1)
    source: str = ""  # the bench file this came from, for messages

    @property
    def axis_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def mlc_program(self) -> str:
        """The MLC `hil run` uses when none is given: the bench's, else by profile — Delta's lathe MLC
        (mlc/lathe.py, the M/S/T handshake) on a lathe, BasicMlc on a mill (no mill MLC is shipped)."""
        return self.mlc or ("basic" if self.profile == "nc5-mill" else "lathe")

    def motion_config(self, group: int = 0) -> MotionConfig:
        """The planner's settings: the bench's own (`group` 0), or with G05 parameter group `group`'s values
        over them (KeyError: no such group)."""
        # N1.036 / N1.037 look-ahead filter and S-curve times (ms), N1.053 path smoothing
        # deviation (mm; 0 = no limit but the filter's own budget): see docs/decisions/motion.md.
        p, limits = self.params, {a.name: a.limits for a in self.axes}
        if group:
            g = self.param_groups[group]
            p = {**p, **g.params}
            limits = {a: replace(lim, **{LIMIT_FIELDS[k]: v for k, v in g.limits.get(a, {}).items()})
                      for a, lim in limits.items()}
        filt = p.get("N1.036", FILTER_MS) / 1000.0
        scurve = p.get("N1.037", FILTER_MS) / 1000.0
        dev = p.get("N1.053", PATH_DEVIATION)
        cap = p.get("N1.033", 0.0)  # mm/min; 0 = none
        cfg = MotionConfig(cycle=self.cycle, axes=self.axis_names, limits=limits,
                           filter_time=filt, filter_scurve=scurve, path_tolerance=dev if dev > 0.0 else None,
                           lookahead=self.lookahead, max_feed=cap if cap > 0.0 else None,
                           rapid=_kind_limits(p, "N1.030", "N1.031", "N1.032"),
                           cutting=_kind_limits(p, "N1.033", "N1.034", "N1.035"),
                           axis_rapid={a: k for a in self.axis_names
                                       if (k := _kind_limits(p, *(f"N2.02{i} {a}" for i in range(3)))).set})
        if cfg.filtered:
            # The filter spreads what several blocks in one cycle do; a block need not last a cycle.
            cfg.min_segment_cycles = 0.25
        return cfg

    def motion_configs(self) -> dict[int, MotionConfig]:
        """G05 P0 (the bench's own settings) and every parameter group's, for the channel (nc.channel)."""
        return {n: self.motion_config(n) for n in (0, *sorted(self.param_groups))}


def _kind_limits(p: dict[str, float], speed: str, acc: str, scurve: str) -> MoveKindLimits:
    """A kind of move's NC5 limits from [params] (mm/min and ms) in the planner's units (mm/s, s); an absent key
    stays None (the planner's own limits, unchanged), 0 a speed of none (decisions language L26-1, motion 90)."""
    v = p.get(speed)
    return MoveKindLimits(speed=v / 60.0 if v else None,
                          acc_time=None if acc not in p else p[acc] / 1000.0,
                          scurve_time=None if scurve not in p else p[scurve] / 1000.0)


def default_lathe() -> Bench:
    """X (radius, 5 mm lead) and Z (10 mm lead) on ASDA-class drives, one spindle."""
    x = AxisConfig("X", AxisScaling(lead=5.0), AxisLimits(300.0, 3000.0, 150_000.0), start=60.0)
    z = AxisConfig("Z", AxisScaling(lead=10.0), AxisLimits(400.0, 4000.0, 200_000.0), start=100.0)
    return Bench(axes=[x, z], spindles=[SpindleConfig()])
