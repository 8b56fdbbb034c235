"""What the subcommands share: loading programs and benches, making links, printing alarms."""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

from hil import strict_json
from nc.alarms import Alarm, NcAlarm
from nc.profiles import PROFILE_NAMES
from nc.program import Program, parse_program

if TYPE_CHECKING:  # the bus side loads where a link or a drive is made, not for `hil path` (issue 16)
    from hil.bench import Bench
    from fieldbus.link import BusLink
    from virtual_bus.drive import Cia402Drive


class InputError(Exception):
    """A program, bench or bus that cannot be used; carries a Delta alarm where one applies."""

    def __init__(self, message: str, alarm: Alarm | None = None) -> None:
        self.alarm = alarm
        super().__init__(message)


def load_program(path: str, libs: Sequence[str] = ()) -> Program:
    """The file's main program.  Every O program of the file and of ``libs`` (``--lib DIR|FILE``)
    goes to the program store the program carries, so M98/G65 calls resolve (issue 3)."""
    from nc.store import ProgramStore

    store = ProgramStore()
    try:
        store.add_libs(libs)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    return store.load_main(path)


def load_bench(path: str | None, profile: str | None = None, bus: str | None = None) -> Bench:
    if path:
        from hil.bench_file import load_bench_file  # TOML loader

        bench = load_bench_file(path)
    else:
        from hil.bench import default_lathe  # with the drive and fieldbus configs it holds

        bench = default_lathe()
    return override_bench(bench, profile, bus)


def checked_profile(name: str) -> str:
    """A `--profile` name, or the InputError listing the names."""
    if name not in PROFILE_NAMES:
        raise InputError(f"unknown profile {name!r}; choose one of {', '.join(PROFILE_NAMES)}")
    return name


def override_bench(bench: Bench, profile: str | None = None, bus: str | None = None) -> Bench:
    """`--profile` and `--bus` over what the bench says."""
    if profile:
        bench.profile = checked_profile(profile)
    if bus:
        bench.bus = bus
    return bench


def sim_slaves(bench: Bench) -> list[Cia402Drive]:
    """Virtual drives for every axis and spindle, at the bench's power-on positions."""
    from fieldbus.pdo import RxPdo
    from virtual_bus.drive import Cia402Drive

    drives = []
    for a in bench.axes:
        d = Cia402Drive(params=replace(a.drive, counts_per_rev=a.scaling.counts_per_rev, units=a.scaling.units), name=a.name)
        d.position = float(a.scaling.to_counts(a.start))
        d.command = d.position
        drives.append(d)
    for s in bench.spindles:
        d = Cia402Drive(params=replace(s.drive, counts_per_rev=s.scaling.counts_per_rev, units=s.scaling.units), name=s.name, mode=9)
        d.apply(RxPdo(mode=9))
        drives.append(d)
    return drives


def sim_io_stations(bench: Bench) -> list:
    """Virtual CiA 401 nodes for the bench's remote I/O stations, each with its own EDS."""
    from fieldbus.canopen.objects import DIO_EDS
    from virtual_bus.canopen.dio import Cia401Slave

    return [Cia401Slave(st.canopen_node, st.map.inputs, st.map.outputs, st.map.name, st.canopen_eds or DIO_EDS)
            for st in bench.io]


def make_link(bench: Bench) -> BusLink:
    from fieldbus.factory import parse_bus
    from fieldbus.link import SimLink

    try:
        spec = parse_bus(bench.bus)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    if spec.kind == "sim":
        return SimLink(sim_slaves(bench), bench.cycle)
    if spec.kind == "ethercat":
        from fieldbus.ethercat.link import EthercatLink

        return EthercatLink.for_bench(bench, spec.interface)
    from fieldbus.canopen.link import CanopenLink

    try:
        link = CanopenLink.for_bench(bench, spec.interface, spec.channel)
    except ValueError as exc:  # bus budget above 100 %, missing multicast group, unusable cycle
        raise InputError(f"bus {spec}: {exc}") from None
    if spec.interface == "virtual":
        # In-process simulated CANopen drives on the same virtual channel, pumped in lock-step.
        from virtual_bus.canopen import attach_lockstep

        attach_lockstep(link, sim_slaves(bench))
        if bench.io:  # the bench's remote I/O stations as simulated CiA 401 nodes (hil/remote_io.py)
            from virtual_bus.canopen.dio import attach_lockstep_io

            link.io_devices = sim_io_stations(bench)
            attach_lockstep_io(link, link.io_devices)
    return link


def print_alarm(alarm: Alarm, as_json: bool = False, stream=None) -> None:
    stream = stream or (sys.stdout if as_json else sys.stderr)
    if as_json:
        print(strict_json.dumps(alarm.as_dict()), file=stream)
    else:
        print(str(alarm), file=stream)
