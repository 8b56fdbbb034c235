"""The tapping interrupt (decisions mlc M26-1 … M26-9): what the G84.48 retraction does on benches/mill-3axis.toml
(a G84 at S600 F900, pitch 1.5 mm, to Z-15 from R2, cut off by the E-stop with Z below -5), and what the feature
adds to every lock-step cycle that has no tap in it (a plain G01 active), timed alone. Prints, asserts nothing.

    python benchmarks/tap_interrupt.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # this tree, not an installed one

from benchmarks.cycle_parts import mill_machine as machine, report  # noqa: E402

TAP = "G17 G90 G94 G00 X0. Y0. Z10.\nM03 S600\nG99 G84 X0. Y0. Z-15. R2. F900.\nG80 G00 Z10.\nM30\n"
PITCH = 1.5


def retraction() -> None:
    m = machine()
    m.start_program(TAP)
    m.wait_until(lambda: m.command("Z") < -5, 20)
    m.estop()
    m.wait(0.5)
    m.estop(False)
    m.reset()
    m.wait(0.5)
    n = len(m.runner.axes)
    sc = m.runner.scales[n]
    rows: list[tuple] = []
    m.watchers.append(lambda mm: rows.append((mm.command("Z"), mm.position("Z"), sc.to_units(mm.runner.rx[n].target_position),
                                              mm.runner.spindle_actual_angle(), mm.runner.rx[n].mode)))
    took = m.mdi("G84.48")
    c = np.array(rows)
    k = np.flatnonzero(c[:, 4] == 8)  # the spindle drive in CSP: the retraction's cycles
    z, za, d, da = c[k, 0], c[k, 1], c[k, 2], c[k, 3]
    T = m.bench.cycle
    v = np.diff(z) / T
    a = np.diff(v) / T
    w = np.diff(d) / T
    print(f"G84.48: {len(k)} cycles ({took:.3f} s with the MDI's handshakes), Z {z[0]:.4f} -> {z[-1]:.6f}, "
          f"spindle {(d[-1] - d[0]) / 360:+.4f} turns")
    print(f"  Z command vs spindle setpoint x pitch: max {np.max(np.abs((z - z[0]) + (d - d[0]) / 360 * PITCH)) * 1e6:.2f} nm")
    print(f"  actual thread phase (Z travel vs spindle turns x pitch): max "
          f"{np.max(np.abs((za - za[0]) + (da - da[0]) / 360 * PITCH)) * 1e3:.3f} um")
    print(f"  Z peak {np.max(np.abs(v)):.2f} mm/s, {np.max(np.abs(a)):.1f} mm/s^2; spindle peak "
          f"{np.max(np.abs(w)) / 6:.1f} rpm, {np.max(np.abs(np.diff(w) / T)):.0f} deg/s^2")
    m.close()


def per_cycle_cost() -> None:
    m = machine()
    ch = m.start_program("G90 G01 X100. F60.\nM30\n")
    m.wait_until(lambda: m.command("X") > 0.5, 5.0)
    link, mem, b2 = m.mlc.link, m.mlc.mem.m, 20000 + 1000 * m.x

    report({
        "M3x707 (Channel.rigid_tapping via getattr, nc_outputs)": lambda: 1 if getattr(ch, "rigid_tapping", False) else 0,
        "M2x080/M2x707 levels (nc_inputs)": lambda: mem[b2 + 80] or mem[b2 + 707] or link._tap_levels,
        "Channel.step: retraction test": lambda: ch._retract is not None,
        "Mlc.spindle_drive: retraction test": lambda: ch.tap_retraction if ch is not None else None,
        "spindle_command_rpm: status test": lambda: ch.tap.record is not None,
    }, width=58)
    m.close()


if __name__ == "__main__":
    retraction()
    print("per cycle, a plain G01 active (best of 7 x 200k, a closure's call subtracted):")
    per_cycle_cost()
