"""`hil sim BUS ...`: run virtual slaves of a bus as a process, for a master on the other end.

Each bus registers itself in SIMULATORS (name -> function adding its sub-subparser), so adding
one is a function plus one dict entry.
"""

from __future__ import annotations

import argparse
import signal
import sys
from collections.abc import Callable

from hil.cli import EXIT_OK, EXIT_USAGE
from hil.sim_canopen import add_canopen


def _add_ethercat(sims: argparse._SubParsersAction) -> None:
    p = sims.add_parser("ethercat", help="software EtherCAT slaves (CiA 402 drives, DIO) on a raw socket",
                        formatter_class=_FaultHelpFormatter,
                        description="Serve the bench's drives (axes, then spindles) as EtherCAT slaves on IFACE.",
                        epilog=_FAULT_HELP)
    p.add_argument("--bus", metavar="ethercat:IFACE",
                   help="the bus, spelled as hil run's --bus: ethercat:IFACE (e.g. one end of a veth pair); required")
    p.add_argument("--iface", help=argparse.SUPPRESS)  # old spellings, kept working
    p.add_argument("--interface", dest="iface", help=argparse.SUPPRESS)
    p.add_argument("--bench", help="bench file (TOML); default: the built-in 2-axis lathe")
    p.add_argument("--esi", metavar="FILE",
                   help="a vendor ESI file (e.g. Delta's) the drives are built from: each takes the device of its "
                        "model's product code; a bench drive's own `esi` wins")
    p.add_argument("--io", type=int, default=0, metavar="N",
                   help="R1-EC class I/O slaves after the drives: one per [[io]] station of the bench (its `modules`), "
                        "then DI16 + DO16 ones up to N")
    p.add_argument("--realtime", action="store_true",
                   help="advance drive models by wall-clock time between frames instead of one cycle per frame")
    p.add_argument("--cpu", type=int, metavar="N",
                   help="run the slaves on CPU N under SCHED_FIFO (lock-step beside `hil run` on the same CPU; "
                        "default: the bench's [realtime] cpu when its lockstep is \"fifo\")")
    p.add_argument("--priority", type=int, metavar="P",
                   help="SCHED_FIFO priority 1-99 of the slaves (default: the bench's [realtime] priority)")
    p.add_argument("--fault", action="append", default=[], metavar="SPEC", help="inject a scripted fault (repeatable)")
    p.add_argument("--duration", type=float, help="stop after this many seconds")
    p.add_argument("--verbose", action="store_true", help="log faults and AL state changes to stderr")
    p.set_defaults(func=cmd_sim_ethercat)


_FAULT_HELP = "(fault specs)"  # the epilog, written out when the help is shown


def _fault_help() -> str:
    from virtual_bus.ethercat import faults

    return "fault specs:\n" + "\n".join(faults.__doc__.splitlines()[4:])


class _FaultHelpFormatter(argparse.RawDescriptionHelpFormatter):
    """Reads the fault specs for `hil sim ethercat --help` only: importing virtual_bus.ethercat when
    the parser is built cost every `hil` command its start-up time (issue 16)."""

    def _format_text(self, text: str) -> str:
        return super()._format_text(_fault_help() if text == _FAULT_HELP else text)


# name -> registrar; the CANopen simulator adds its own entry here.
SIMULATORS: dict[str, Callable[[argparse._SubParsersAction], None]] = {
    "ethercat": _add_ethercat,
    "canopen": add_canopen,
}


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sim", help="run virtual bus slaves as a process (ethercat, ...)")
    sims = p.add_subparsers(dest="bus", metavar="BUS")
    sims.required = True
    for add in SIMULATORS.values():
        add(sims)


def build_chain(bench, io: int = 0, realtime: bool = False, faults=()):
    """Software ESCs for the bench's drives (each its `drive.model`: ASDA-A3-E, B3-E or A2-E) and R1-EC class I/O stations: one per
    [[io]] station with its `modules`, and up to `io` in all (extra ones DI16 + DO16)."""
    from hil.session import sim_slaves
    from virtual_bus.ethercat.app import DioApp, DriveApp
    from virtual_bus.ethercat.device import load_device
    from virtual_bus.ethercat.esc import Esc
    from virtual_bus.ethercat.network import Chain

    from virtual_bus.ethercat.r1ec import DEFAULT_MODULES, r1ec_device
    from virtual_bus.ethercat.sii import set_alias

    from fieldbus.devices import MODELS

    # each drive presents its model's identity and PDO sets, from the packaged file or the bench's ESI
    models = [(c.drive_model, c.drive_esi) for c in list(bench.axes) + list(bench.spindles)]
    aliases = [c.station_alias for c in list(bench.axes) + list(bench.spindles)]
    devices = {(m, esi): load_device(esi, MODELS[m].product_code) if esi else load_device(m) for m, esi in set(models)}
    slaves = []
    for k, (d, model) in enumerate(zip(sim_slaves(bench), models)):
        # Clocks start apart and run at slightly different rates, so DC has something to do.
        slaves.append(Esc(devices[model], DriveApp(d), name=d.name, drift_ppm=(-1) ** k * 10.0 * k,
                          clock_base_ns=(k + 1) * 1_234_567_890, cycle_time=bench.cycle, lockstep=not realtime))
        if aliases[k] is not None:  # the bench's `drive.alias`: this slave's station alias (App. A 0x1416)
            set_alias(slaves[-1].sii, aliases[k])
            slaves[-1].power_on()
    # the bench's [[io]] stations (each with its R1-EC modules), then extra default 16/16 ones
    stations = [(st.map.name, st.modules or DEFAULT_MODULES) for st in getattr(bench, "io", [])]
    io_devices = {mods: r1ec_device(mods) for _, mods in stations} | {DEFAULT_MODULES: load_device("r1-ec-dio")}
    for k in range(max(io, len(stations))):
        name, mods = stations[k] if k < len(stations) else (f"DIO{k + 1}", DEFAULT_MODULES)
        slaves.append(Esc(io_devices[mods], DioApp(), name=name,
                          clock_base_ns=(len(slaves) + 1) * 987_654_321, cycle_time=bench.cycle,
                          lockstep=not realtime))
    return Chain(slaves, list(faults))


def with_esi(bench, esi: str):
    """The bench with every drive that names no ESI file of its own built from `esi`; ValueError when the
    file cannot be read or lacks a drive's model (its product code)."""
    from dataclasses import replace
    from pathlib import Path

    from fieldbus.devices import MODELS
    from virtual_bus.ethercat.device import parse_device

    path = str(Path(esi).expanduser().resolve())
    for model in {c.drive_model for c in list(bench.axes) + list(bench.spindles) if not c.drive_esi}:
        try:
            parse_device(path, MODELS[model].product_code)
        except (OSError, ValueError, KeyError, SyntaxError) as exc:  # ET.ParseError is a SyntaxError
            raise ValueError(f"--esi {esi}: the {model} drives: {exc}") from None
    return replace(bench, axes=[c if c.drive_esi else replace(c, drive_esi=path) for c in bench.axes],
                   spindles=[c if c.drive_esi else replace(c, drive_esi=path) for c in bench.spindles])


def ethercat_iface(bus: str | None, iface: str | None) -> str:
    """IFACE from --bus ethercat:IFACE, or the old --iface/--interface; ValueError says what to give."""
    from fieldbus.factory import parse_bus

    if bus:
        if iface:
            raise ValueError("give --bus ethercat:IFACE, not --iface as well")
        spec = parse_bus(bus)
        if spec.kind != "ethercat":
            raise ValueError(f"--bus {bus}: hil sim ethercat serves an EtherCAT bus, ethercat:IFACE")
        return spec.interface
    if not iface:  # not argparse's required=: the hidden aliases fill it too
        raise ValueError("give the network interface: --bus ethercat:IFACE")
    return iface


def _place(args: argparse.Namespace, bench) -> tuple[object | None, str]:
    """SCHED_FIFO on one CPU for the slaves (decisions E21) when --cpu/--priority ask for it, or the bench's
    [realtime] lockstep = "fifo" in lock-step; (the placement to restore, "; what was granted" for the banner)."""
    rt = bench.realtime
    if args.cpu is None and args.priority is None and (rt.lockstep != "fifo" or args.realtime):
        return None, ""
    from hil.placement import Placed, placement_cpu

    placed = Placed()
    cpu = args.cpu if args.cpu is not None else placement_cpu(rt)
    granted = placed.apply(args.priority or rt.priority, cpu)
    return placed, "; " + granted.what


def cmd_sim_ethercat(args: argparse.Namespace) -> int:
    from virtual_bus.ethercat.faults import parse_fault
    from virtual_bus.ethercat.network import RawSocketLine
    from hil.session import InputError, load_bench

    try:
        args.iface = ethercat_iface(args.bus, args.iface)
        bench = load_bench(args.bench)
        if args.esi:
            bench = with_esi(bench, args.esi)
        faults = [parse_fault(f) for f in args.fault]
        if args.priority is not None and not 1 <= args.priority <= 99:
            raise ValueError(f"--priority {args.priority}: a SCHED_FIFO priority from 1 to 99")
        if args.cpu is not None and args.cpu < 0:
            raise ValueError(f"--cpu {args.cpu}: a CPU number (0, 1, ...)")
    except (InputError, ValueError) as exc:
        print(f"hil sim ethercat: {exc}", file=sys.stderr)
        return EXIT_USAGE
    chain = build_chain(bench, args.io, args.realtime, faults)
    if args.verbose:
        chain.log = lambda msg: print(f"hil sim ethercat: {msg}", file=sys.stderr, flush=True)
    try:
        line = RawSocketLine(chain, args.iface)
    except OSError as exc:
        print(f"hil sim ethercat: cannot open {args.iface}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE
    signal.signal(signal.SIGTERM, lambda *_: setattr(line, "running", False))
    names = ", ".join(s.name for s in chain.slaves)
    placed, where = _place(args, bench)
    print(f"hil sim ethercat: {len(chain.slaves)} slaves on {args.iface}: {names}{where}", flush=True)
    try:
        line.serve(args.duration)
    except KeyboardInterrupt:
        pass
    finally:
        if placed is not None:
            placed.restore()
        line.close()
        if args.verbose:
            for name, state, code in chain.states():
                print(f"hil sim ethercat: {name} AL state {state} code 0x{code:04X}", file=sys.stderr)
    return EXIT_OK
