"""PDO layouts' compiled codecs (issue 17): the bytes on the wire, and the same bytes as wrapping
each value to its entry's width (`_fit`) then packing with the entry's own struct code."""

from __future__ import annotations

import random

import pytest

from fieldbus.pdo import ASDA_CSP, ASDA_E, LAYOUTS, PdoLayout, RxPdo, TxPdo, _fit


def test_asda_e_images_on_the_wire():
    rx = RxPdo(controlword=0x0F, target_position=-2, mode=8, target_velocity=100_000, target_torque=-5,
               touch_probe_function=0x21)
    assert ASDA_E.pack_rx(rx).hex() == "0f00" "feffffff" "a0860100" "fbff" "08" "2100"
    raw = bytes.fromhex("3712" "00e1f505" "f6ffffff" "0a00" "08" "0300" "78563412" "04000000")
    tx = ASDA_E.unpack_tx(raw + b"\xee\xee")  # a longer process image: its first 22 bytes
    assert (tx.statusword, tx.position_actual, tx.velocity_actual, tx.torque_actual, tx.mode_display,
            tx.touch_probe_status, tx.touch_probe_pos1, tx.digital_inputs) == \
        (0x1237, 100_000_000, -10, 10, 8, 3, 0x12345678, 4)
    assert ASDA_E.pack_tx(tx) == raw
    # values past an entry's width wrap as the drive's registers do: 2**31 reads back negative
    assert ASDA_E.unpack_rx(ASDA_E.pack_rx(RxPdo(target_position=1 << 31, mode=-1))).target_position == -(1 << 31)


@pytest.mark.parametrize("layout", list(LAYOUTS.values()), ids=list(LAYOUTS))
def test_compiled_codecs_equal_the_entry_by_entry_route(layout: PdoLayout):
    rng = random.Random(layout.name)

    def value() -> int:
        return rng.choice((rng.getrandbits(40) - (1 << 39), rng.getrandbits(16), -1, 0, 1 << 31))

    for _ in range(500):
        rx, tx = RxPdo(*(value() for _ in range(7))), TxPdo(*(value() for _ in range(10)))
        want_rx = layout.rx_struct.pack(*(_fit(getattr(rx, e.attr), e) for e in layout.rx))
        want_tx = layout.tx_struct.pack(*(_fit(getattr(tx, e.attr), e) for e in layout.tx))
        assert layout.pack_rx(rx) == want_rx and layout.pack_tx(tx) == want_tx
        back = layout.unpack_tx(want_tx, TxPdo())
        assert [getattr(back, e.attr) for e in layout.tx] == [_fit(getattr(tx, e.attr), e) for e in layout.tx]
        back_rx = layout.unpack_rx(want_rx)
        assert [getattr(back_rx, e.attr) for e in layout.rx] == [_fit(getattr(rx, e.attr), e) for e in layout.rx]


def test_carries_names_the_objects_of_both_directions():
    assert ASDA_E.carries(0x60B8) and ASDA_E.carries(0x60FD) and not ASDA_E.carries(0x60F4)
    assert ASDA_CSP.carries(0x60F4) and ASDA_CSP.carries(0x603F) and not ASDA_CSP.carries(0x60FF)


def test_axis_velocity_scaling_equals_the_drive_units_route():
    """AxisScaling.velocity_to_drive with its factors derived once gives DriveUnits.velocity_to_raw's
    value: 1,000 rpm of a 1:1 spindle is 10000 × 0.1 rpm, a 10 mm lead at 5 mm/s is 300 (0.1 rpm)."""
    from fieldbus.units import AxisScaling, DriveUnits

    spindle, screw = AxisScaling(lead=360.0), AxisScaling(counts_per_rev=1 << 24, gear_load=3, direction=-1)
    assert spindle.rpm_to_drive(1000) == 10000 and AxisScaling().velocity_to_drive(5.0) == 300
    rng = random.Random(5)
    for sc in (spindle, screw, AxisScaling(units=DriveUnits("count/s"))):
        for _ in range(500):
            v = rng.uniform(-1e5, 1e5) * rng.choice((1e-6, 1.0, 1e4))
            assert sc.velocity_to_drive(v) == sc.units.velocity_to_raw(v * sc.counts_per_unit, sc.counts_per_rev)
