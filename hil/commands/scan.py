"""`hil scan --bus ethercat:IFACE`: list the slaves on a line (position, vendor, product, name, state)."""

from __future__ import annotations

import argparse
import sys

from hil.cli import EXIT_ALARM, EXIT_OK, EXIT_USAGE


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("scan", help="list the slaves on a bus (EtherCAT: vendor, product, name, AL state)")
    p.add_argument("--bus", required=True, help="ethercat:IFACE")
    p.add_argument("--json", action="store_true", help="one JSON object per slave")
    p.set_defaults(func=cmd_scan)


def cmd_scan(args: argparse.Namespace) -> int:
    from fieldbus.factory import parse_bus
    from fieldbus.link import BusError
    from hil import strict_json
    from hil.session import print_alarm

    try:
        spec = parse_bus(args.bus)
    except ValueError as exc:
        print(f"hil scan: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if spec.kind != "ethercat":
        print(f"hil scan: scanning {spec.kind} buses is not supported here; use ethercat:IFACE", file=sys.stderr)
        return EXIT_USAGE
    from fieldbus.ethercat.link import EthercatLink

    try:
        slaves = EthercatLink(spec.interface).scan()
    except BusError as exc:
        print_alarm(exc.alarm, args.json)
        return EXIT_ALARM
    for s in slaves:
        if args.json:
            print(strict_json.dumps({"position": s.position, "vendor": f"0x{s.vendor_id:08X}",
                              "product": f"0x{s.product_code:08X}", "name": s.name, "kind": s.kind,
                              "state": s.state} | ({"modules": s.layout} if s.kind == "io" and s.layout else {})))
        else:
            print(f"{s.position:3d}  vendor 0x{s.vendor_id:08X}  product 0x{s.product_code:08X}  "
                  f"{s.state:8s} {s.kind:5s}  {s.name}" + (f"  [{s.layout}]" if s.kind == "io" and s.layout else ""))
    return EXIT_OK
