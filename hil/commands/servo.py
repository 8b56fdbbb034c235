"""`hil servo get|set AXIS PARAM [VALUE]`: Delta ASDA servo parameters Pn-xx of one drive.

Over the bench's bus by SDO (object 0x2000 + n*0x100 + xx; SimLink's simulated drives and
EtherCAT), or with ``--servo-modbus DEVICE`` over the drive's RS-485 port (Modbus RTU, pyserial).
A `set` reads the value back and prints both.  Exit 1 when the drive refuses (SDO abort code or
Modbus exception), 2 for usage errors.
"""

from __future__ import annotations

import argparse
import struct
import sys


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("servo", help="read / write a Delta servo parameter (Pn-xx) over SDO or Modbus RTU")
    p.add_argument("action", choices=("get", "set"))
    p.add_argument("axis", help="axis or spindle name on the bench, e.g. X or S1")
    p.add_argument("param", help="servo parameter, e.g. P2-00")
    p.add_argument("value", nargs="?", type=int, help="value to write (set)")
    p.add_argument("--bench", help="bench file (TOML); default: the built-in 2-axis lathe")
    p.add_argument("--bus", help="sim | ethercat:IFACE (overrides the bench)")
    p.add_argument("--servo-modbus", dest="modbus", metavar="DEVICE",
                   help="serial device of the drive's RS-485 port (Modbus RTU); the same flag as hil run's")
    p.add_argument("--modbus", dest="modbus", help=argparse.SUPPRESS)  # old spelling
    p.add_argument("--unit", type=lambda s: int(s, 0), default=0x7F, help="Modbus station address (P3-00), default 0x7F")
    p.add_argument("--servo-baud", dest="baud", type=int, default=38400, help="RS-485 baud rate (default 38400)")
    p.add_argument("--baud", dest="baud", type=int, help=argparse.SUPPRESS)  # old spelling
    p.set_defaults(func=cmd_servo)


def cmd_servo(args: argparse.Namespace) -> int:
    from hil.session import InputError, load_bench
    from virtual_bus.servo_params import coe_index, modbus_address, parse_param

    try:
        group, number = parse_param(args.param)
    except ValueError as exc:
        print(f"hil servo: {exc}", file=sys.stderr)
        return 2
    if args.action == "set" and args.value is None:
        print("hil servo: set needs a VALUE", file=sys.stderr)
        return 2
    label = f"P{group}-{number:02d}"
    if args.modbus:
        return _over_modbus(args, group, number, label, modbus_address(group, number))
    try:
        bench = load_bench(args.bench, None, args.bus)
    except InputError as exc:
        print(f"hil servo: {exc}", file=sys.stderr)
        return 2
    names = list(bench.axis_names) + [s.name for s in bench.spindles]
    if args.axis not in names:
        print(f"hil servo: axis {args.axis!r} is not on bench {bench.name} ({', '.join(names)})", file=sys.stderr)
        return 2
    return _over_sdo(args, bench, names.index(args.axis), group, number, label, coe_index(group, number))


def _over_sdo(args, bench, position: int, group: int, number: int, label: str, index: int) -> int:
    from fieldbus.link import BusError
    from hil.session import InputError, make_link

    try:
        link = make_link(bench)
    except InputError as exc:
        print(f"hil servo: {exc}", file=sys.stderr)
        return 2
    if not hasattr(link, "sdo_read"):
        print(f"hil servo: bus {bench.bus} has no SDO access here; use --servo-modbus DEVICE", file=sys.stderr)
        return 2
    where = f"{args.axis} (slave {position}) object 0x{index:04X}:0 over SDO ({bench.bus})"
    try:
        link.open()
        if args.action == "set":
            link.sdo_write(position, index, 0, struct.pack("<i", args.value))
        value = struct.unpack("<i", link.sdo_read(position, index, 0, 4)[:4])[0]
    except BusError as exc:
        print(f"hil servo: {exc.alarm.code_text} {exc.alarm.message}", file=sys.stderr)
        return 1
    except Exception as exc:  # SDO abort from the drive (simulated or EtherCAT)
        code = getattr(exc, "code", None)
        if code is None:
            raise
        # the drive's own text where the table has none (the exception's text repeats the code: once is enough)
        from hil.servo_link import SDO_TEXT
        print(f"hil servo: {label} on {where}: SDO abort 0x{code:08X} ({SDO_TEXT.get(code, _reason(exc))})",
              file=sys.stderr)
        return 1
    finally:
        link.close()
    _report(args, label, where, value)
    return 0


def _reason(exc: Exception) -> str:
    """An SDO abort's own reason: pysoem's text ends in ": reason", canopen's in ", reason" after the code."""
    text = str(exc)
    if text.startswith(("SDO abort 0x", "Code 0x")):
        return text.rsplit(": " if text.startswith("SDO") else ", ", 1)[-1]
    return text


def _over_modbus(args, group: int, number: int, label: str, address: int) -> int:
    import serial

    from fieldbus.modbus import ModbusError, ModbusRtuMaster

    try:
        master = ModbusRtuMaster.open(args.modbus, args.unit, args.baud)
    except (serial.SerialException, OSError) as exc:
        print(f"hil servo: cannot open {args.modbus}: {exc}", file=sys.stderr)
        return 2
    where = f"{args.axis} station {args.unit} register 0x{address:04X} over Modbus RTU ({args.modbus})"
    try:
        if args.action == "set":
            master.write_param(group, number, args.value)
        value = master.read_param(group, number)
    except ModbusError as exc:
        print(f"hil servo: {label} on {where}: {exc}", file=sys.stderr)
        return 1
    finally:
        master.close()
    _report(args, label, where, value)
    return 0


def _report(args, label: str, where: str, value: int) -> None:
    verb = f"set {args.value} →" if args.action == "set" else "="
    print(f"{label} {verb} {value} (0x{value & 0xFFFFFFFF:08X})  on {where}")
