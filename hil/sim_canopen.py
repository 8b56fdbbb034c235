"""`hil sim canopen`: the bench's drives as CiA 402 CANopen nodes in this process, for a master
(`hil run --bus canopen:INTERFACE:CHANNEL`, or any other CANopen master) on the same bus.

Node IDs are 1, 2, … in axis order, then the spindles. The nodes follow the master's SYNC in
real time: every SYNC applies the RPDOs, advances each drive by its interpolation time period
(0x60C2) and sends the TPDOs. The bench's [[io]] stations join as CiA 401 nodes (`canopen_node`).
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading

from hil.cli import EXIT_OK, EXIT_USAGE


def add_canopen(sims: argparse._SubParsersAction) -> None:
    p = sims.add_parser("canopen", help="simulated CiA 402 CANopen servo nodes (python-canopen LocalNode)",
                        description="Serve the bench's drives as CANopen nodes 1, 2, … (axes, then spindles).")
    p.add_argument("--bus", metavar="canopen:INTERFACE:CHANNEL",
                   help="the bus, spelled as hil run's --bus: canopen:socketcan:vcan0 (can0 on a bench) or "
                        "canopen:udp_multicast:239.74.163.2 (inside a loopback-only network namespace); required")
    p.add_argument("--interface", help=argparse.SUPPRESS)  # old spellings, kept working
    p.add_argument("--channel", help=argparse.SUPPRESS)
    p.add_argument("--bench", help="bench file (TOML); default: the built-in 2-axis lathe")
    p.add_argument("--duration", type=float, help="stop after this many seconds")
    p.add_argument("--verbose", action="store_true",
                   help="log what the drives do on their own to stderr (a master gone silent: AL180, braking)")
    p.set_defaults(func=cmd_sim_canopen)


def cmd_sim_canopen(args: argparse.Namespace) -> int:
    from fieldbus.canopen.pycan import load  # python-can only when the simulator runs, without asammdf (B50)

    can = load()

    from fieldbus.canopen.netns import check_multicast_allowed
    from hil.session import InputError, load_bench, sim_io_stations, sim_slaves
    from virtual_bus.canopen import serve

    try:
        args.interface, args.channel = canopen_endpoint(args.bus, args.interface, args.channel)
        bench = load_bench(args.bench)
        if args.interface == "virtual":
            raise InputError("the virtual interface only reaches this process; use socketcan or udp_multicast "
                             "(hil run --bus canopen:virtual starts its own nodes)")
        check_multicast_allowed(args.interface)
    except (InputError, ValueError) as exc:
        print(f"hil sim canopen: {exc}", file=sys.stderr)
        return EXIT_USAGE
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        eds = [getattr(a, "canopen_eds", "") or bench.canopen_eds for a in [*bench.axes, *bench.spindles]]
        bus = serve(sim_slaves(bench), args.interface, args.channel, eds=eds)
    except (OSError, ValueError, ImportError, can.CanError) as exc:  # CanError: no such python-can interface
        print(f"hil sim canopen: cannot open {args.interface}:{args.channel}: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if args.verbose:
        bus.log = lambda msg: print(f"hil sim canopen: {msg}", file=sys.stderr, flush=True)
    io = sim_io_stations(bench)
    for station in io:  # remote I/O stations on the same bus (mlc/remote_io.py)
        station.attach(bus.network)
    nodes = ", ".join([f"{s.node_id}={s.drive.name}" for s in bus.slaves] + [f"{s.node_id}={s.name}" for s in io])
    print(f"hil sim canopen: nodes {nodes} on {args.interface}:{args.channel}", flush=True)
    try:
        stop.wait(args.duration)
    except KeyboardInterrupt:
        pass
    finally:
        for station in io:
            station.node.nmt.stop_heartbeat()
        bus.close()
        states = ", ".join([f"{s.node_id} {s.nmt_state} {s.drive.state.value}, {s.syncs} SYNC" for s in bus.slaves]
                           + [f"{s.node_id} {s.nmt_state}, {s.syncs} SYNC, outputs changed {len(s.history)} times"
                              for s in io])
        print(f"hil sim canopen: stopped ({states})", file=sys.stderr)
    return EXIT_OK


def canopen_endpoint(bus: str | None, interface: str | None, channel: str | None) -> tuple[str, str]:
    """(python-can interface, channel) from --bus canopen:INTERFACE:CHANNEL, or the old
    --interface/--channel pair; ValueError says what to give."""
    from fieldbus.factory import parse_bus

    if bus:
        if interface or channel:
            raise ValueError("give --bus canopen:INTERFACE:CHANNEL, not --interface/--channel as well")
        spec = parse_bus(bus)
        if spec.kind != "canopen":
            raise ValueError(f"--bus {bus}: hil sim canopen serves a CANopen bus, canopen:INTERFACE:CHANNEL")
        interface, channel = spec.interface, spec.channel
    if not interface:
        raise ValueError("--bus canopen:INTERFACE:CHANNEL is required, e.g. --bus canopen:socketcan:vcan0")
    if not channel and interface != "virtual":
        raise ValueError(f"--bus canopen:{interface}:CHANNEL: the channel is missing (vcan0, can0, 239.x.x.x)")
    return interface, channel or ""
