"""Delta servo parameters: Modbus RTU over a pseudo-terminal (pyserial) and SDO on the simulated bus."""

from __future__ import annotations

import struct

import pytest

from fieldbus.link import SimLink
from fieldbus.modbus import ILLEGAL_ADDRESS, ILLEGAL_VALUE, ModbusError, ModbusRtuMaster, crc16, frame
from virtual_bus.drive import Cia402Drive
from virtual_bus.modbus_drive import PtyModbusDrive
from virtual_bus.servo_params import ABORT_RANGE, ServoParamError, coe_index, modbus_address


@pytest.fixture
def drive_on_pty():
    drive = Cia402Drive(name="X")
    srv = PtyModbusDrive(drive.servo_params).start()
    master = ModbusRtuMaster.open(srv.device, timeout=1.0)
    yield drive, srv, master
    master.close()
    srv.stop()


def _sdo_int(link: SimLink, index: int) -> int:
    return struct.unpack("<i", link.sdo_read(0, index))[0]


def test_crc16_and_addressing_follow_modbus_and_delta():
    assert crc16(bytes.fromhex("01030000000A")) == 0xCDC5  # the Modbus specification's example
    assert frame(bytes.fromhex("7F0302000002"))[-2:] == struct.pack("<H", crc16(bytes.fromhex("7F0302000002")))
    assert modbus_address(2, 0) == 0x0200 and modbus_address(1, 44) == 0x0158 and modbus_address(0, 1) == 0x0002
    assert coe_index(2, 0) == 0x2200 and coe_index(1, 44) == 0x212C


def test_a_parameter_written_over_modbus_rtu_reads_back_the_same_over_sdo(drive_on_pty):
    drive, _srv, master = drive_on_pty
    master.write_param(2, 0, 150)  # P2-00 KPP, function 0x10
    master.write_param(1, 44, 123456789)  # P1-44 gear N1: needs both 16-bit words
    master.write_param(5, 9, -1000)  # P5-09 reverse software limit: negative 32-bit
    master.write_register(modbus_address(2, 4), 700)  # P2-04 KVP, function 0x06 (low word)
    link = SimLink([drive])
    link.open()
    assert _sdo_int(link, 0x2200) == 150
    assert _sdo_int(link, 0x212C) == 123456789
    assert _sdo_int(link, 0x2509) == -1000
    assert _sdo_int(link, 0x2204) == 700
    # and the other way: SDO write, Modbus read (low word first on the wire)
    link.sdo_write(0, 0x2202, 0, struct.pack("<i", 80))
    assert master.read_param(2, 2) == 80
    assert master.read_registers(modbus_address(1, 44), 2) == [123456789 & 0xFFFF, 123456789 >> 16]


def test_the_drive_refuses_bad_parameters_with_delta_answers(drive_on_pty):
    drive, _srv, master = drive_on_pty
    with pytest.raises(ModbusError) as e:
        master.write_param(2, 0, 99999)  # above P2-00's range
    assert e.value.code == ILLEGAL_VALUE
    with pytest.raises(ModbusError) as e:
        master.read_param(6, 50)
    assert e.value.code == ILLEGAL_ADDRESS
    with pytest.raises(ServoParamError) as e2:
        SimLink([drive]).sdo_write(0, 0x2200, 0, struct.pack("<i", -1))
    assert e2.value.code == ABORT_RANGE
    assert drive.servo_params.read("P2-00") == 35  # unchanged by the refused writes


def test_hil_servo_set_over_modbus_then_get_over_sdo_of_the_same_drive(hil, drive_on_pty):
    drive, srv, master = drive_on_pty
    master.close()  # hil servo opens its own serial port on the pty
    r = hil("servo", "set", "X", "P2-00", "220", "--servo-modbus", srv.device)
    assert r.code == 0, r.err
    assert "P2-00 set 220 → 220" in r.out and "register 0x0200" in r.out
    assert struct.unpack("<i", SimLink([drive]).sdo_read(0, 0x2200))[0] == 220


def test_hil_servo_over_the_bench_bus_by_sdo(hil):
    r = hil("servo", "get", "Z", "P1-44")
    assert r.code == 0, r.err
    assert "P1-44 = 16777216" in r.out and "object 0x212C:0 over SDO (sim)" in r.out
    r = hil("servo", "set", "X", "P2-00", "99999")
    assert r.code == 1 and "SDO abort 0x06090030 (value out of range)" in r.err
    assert r.err.count("0x06090030") == 1, r.err  # the code once, with its meaning
    r = hil("servo", "get", "Q", "P2-00")
    assert r.code == 2 and "axis 'Q'" in r.err
