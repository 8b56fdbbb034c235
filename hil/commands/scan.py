"""`hil scan --bus ethercat:IFACE | canopen:INTERFACE:CHANNEL`: list the slaves on a line or the nodes
on a CAN bus (position or node ID, vendor, product, name, state)."""

from __future__ import annotations

import argparse
import sys

from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("scan", help="list the slaves on a bus (vendor, product, name, AL or NMT state; a drive's "
                                    "CiA 402 state, and its error code in fault)")
    p.add_argument("--bus", required=True, help="ethercat:IFACE, or canopen:INTERFACE:CHANNEL (canopen:virtual: "
                                                "the bench's simulated nodes in this process)")
    p.add_argument("--bench", help="with canopen:virtual: whose drives to simulate (default: the built-in lathe)")
    p.add_argument("--json", action="store_true", help="one JSON object per slave")
    p.set_defaults(func=cmd_scan)


def cmd_scan(args: argparse.Namespace) -> int:
    from fieldbus.factory import parse_bus
    from fieldbus.link import BusError
    from hil import strict_json
    from hil.session import InputError, print_alarm

    try:
        spec = parse_bus(args.bus)
    except ValueError as exc:
        print(f"hil scan: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if spec.kind not in ("ethercat", "canopen"):
        print(f"hil scan: the {spec.kind} bus has nothing to scan; use ethercat:IFACE or canopen:INTERFACE:CHANNEL",
              file=sys.stderr)
        return EXIT_USAGE
    try:
        slaves = _scan_ethercat(spec) if spec.kind == "ethercat" else _scan_canopen(spec, args.bench)
    except InputError as exc:
        print(f"hil scan: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BusError as exc:
        print_alarm(exc.alarm, args.json)
        return EXIT_ALARM
    from fieldbus.devices import model_by_identity

    for s in slaves:
        # A drive hil knows by its identity: the model's default resolution and units (decisions E17), what a
        # bench naming that model without counts_per_rev converts with.
        m = model_by_identity(s.vendor_id, s.product_code) if s.kind == "drive" else None
        if args.json:
            print(strict_json.dumps({"position": s.position, "vendor": f"0x{s.vendor_id:08X}",
                              "product": f"0x{s.product_code:08X}", "name": s.name, "kind": s.kind,
                              "state": s.state} | ({"modules": s.layout} if s.kind == "io" and s.layout else {})
                                    | ({"drive_state": s.drive} if s.drive else {})
                                    | ({"model": m.key, "counts_per_rev": m.counts_per_rev,
                                        "velocity_unit": m.units.velocity,
                                        "torque_unit_percent": m.units.torque_percent} if m else {})))
        else:
            model = (f"  [{m.key}: {m.counts_per_rev} counts/rev, velocity {m.units.velocity}, "
                     f"torque {m.units.torque_percent:g} %]") if m else ""
            print(f"{s.position:3d}  vendor 0x{s.vendor_id:08X}  product 0x{s.product_code:08X}  "
                  f"{s.state:8s} {s.kind:5s}  {s.name}" + (f"  [{s.layout}]" if s.kind == "io" and s.layout else "")
                  + (f"  CiA 402 {s.drive}" if s.drive else "") + model)
    return EXIT_OK


def _scan_ethercat(spec) -> list:
    from fieldbus.ethercat.link import EthercatLink

    return EthercatLink(spec.interface).scan()


def _scan_canopen(spec, bench_path: str | None) -> list:
    """A CAN bus by node ID; `canopen:virtual` has no nodes of its own, so the bench's simulated drives
    (as `hil run --bus canopen:virtual` builds them) answer on a private virtual channel."""
    import uuid

    from fieldbus.canopen.budget import DEFAULT_BITRATE
    from fieldbus.canopen.netns import check_multicast_allowed
    from fieldbus.canopen.scan import scan
    from hil.session import InputError, load_bench, sim_slaves

    try:
        check_multicast_allowed(spec.interface)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    bench = load_bench(bench_path)
    bitrate = int(getattr(bench, "canopen_bitrate", None) or DEFAULT_BITRATE)
    if spec.interface != "virtual":
        return scan(spec.interface, spec.channel, bitrate)
    from virtual_bus.canopen.nodes import serve

    channel = f"scan-{uuid.uuid4().hex[:8]}"
    nodes = serve(sim_slaves(bench), "virtual", channel,
                  eds=[c.canopen_eds or bench.canopen_eds for c in [*bench.axes, *bench.spindles]])
    try:
        return scan("virtual", channel, bitrate)
    finally:
        nodes.close()
