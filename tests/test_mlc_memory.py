"""Device memory and the App. B signal table: addresses, word order, widths."""

from __future__ import annotations

import pytest

from mlc.memory import DeviceError, DeviceMemory, parse_address
from mlc.signals import resolve, signal_table


def test_pairs_store_low_word_at_the_lower_address():
    mem = DeviceMemory()
    mem.set_u32(31048, 0x0001_0002)
    assert (mem.u16(31048), mem.u16(31049)) == (0x0002, 0x0001)
    swapped = DeviceMemory(word_order="high-first")
    swapped.set_u32(31048, 0x0001_0002)
    assert (swapped.u16(31048), swapped.u16(31049)) == (0x0001, 0x0002)
    assert swapped.u32(31048) == 0x0001_0002


def test_signed_and_float_pairs_round_trip():
    mem = DeviceMemory()
    mem.set_s16(21128, -19)
    assert mem.u16(21128) == 0xFFED and mem.s16(21128) == -19
    mem.set_s32(30272, -123456)
    assert mem.s32(30272) == -123456
    mem.set_f32(31024, 1200.5)
    assert mem.f32(31024) == 1200.5
    mem.set_u32(21014, 4_294_967_295)
    assert mem.u32(21014) == 4_294_967_295


def test_channel_digit_sits_in_the_thousands_place():
    t = signal_table((1, 2))
    assert t["M21000"].name == "CYCLE_START" and t["M22000"].channel == 2
    assert t["M31064"].name == "M_STROBE"
    assert t["M21016"].name == "MST_FINISH"
    assert t["D31048"].name == "M_CODE" and t["D31048"].width == "u32"
    assert t["D31050"].name == "S_CODE" and t["D31052"].name == "T_CODE"
    assert t["M21386"].name == "JOG_FWD_Z"  # axis family: X Y Z …, 16 wide
    assert t["M21402"].name == "JOG_REV_Z"
    assert t["M31336"].name == "HOMING_DONE_X"
    assert t["M21823"].name == "SPINDLE8_ALARM"  # the manual misprints M2x807 (E1)
    assert t["D30370"].name == "VELOCITY_FB_RPM_18"  # printed "D30360 D30371" (E2)
    assert t["D30004"].name == "MPG_PULSES" and t["M20024"].name == "ENABLE_3_MPG"


def test_resolve_by_name_is_channel_relative_and_bad_devices_are_rejected():
    assert resolve("MST_FINISH", 2).address == "M22016"
    assert resolve("m31064").name == "M_STROBE"
    assert resolve("M1000").text == "ordinary MLC device"
    for bad in ("X1024", "Y99999", "Z12", "M100000", "NOT_A_SIGNAL"):
        with pytest.raises(DeviceError):
            resolve(bad)
    with pytest.raises(DeviceError):
        parse_address("D")


@pytest.mark.parametrize("order", ["low-first", "high-first"])
def test_floats_written_in_place_equal_the_word_pair_route(order):
    """set_f32/f32 pack the float's bytes straight into the D words (issue 17): the words, and the value
    read back, are those of the u32 route (struct of the float, split into a low and a high word)."""
    import math
    import struct

    mem = DeviceMemory(word_order=order)
    for k, value in enumerate((1200.5, -0.0, 1e-40, 3.4e38, -7.25e-3, math.inf, 16_777_217.0)):
        n = 30272 + 2 * k
        mem.set_f32(n, value)
        raw = struct.unpack("<I", struct.pack("<f", value))[0]
        lo, hi = raw & 0xFFFF, raw >> 16
        assert (int(mem.d[n]), int(mem.d[n + 1])) == ((lo, hi) if order == "low-first" else (hi, lo))
        assert mem.u32(n) == raw
        assert struct.pack("<f", mem.f32(n)) == struct.pack("<f", value)
    mem.set_f32(0, 2.5)  # the first and the last pair of the range take the same route
    mem.set_f32(len(mem.d) - 2, -2.5)
    assert (mem.f32(0), mem.f32(len(mem.d) - 2)) == (2.5, -2.5)
    assert mem.words[30272] == int(mem.d[30272])  # the word view is the array itself
