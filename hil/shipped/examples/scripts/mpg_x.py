"""Exercise the handwheel: X and Z at ratios 1, 10 and 100, forwards and back.

    hil script examples/scripts/mpg_x.py
"""


def main(machine):
    for axis in ("X", "Z"):
        for ratio in (1, 10, 100):
            start = machine.command(axis)
            machine.mpg(axis, 50, ratio=ratio)
            there = machine.command(axis)
            machine.mpg(axis, -50, ratio=ratio)
            print(f"MPG {axis} ×{ratio:<3} 50 pulses → {there - start:+.3f} mm, back to {machine.command(axis) - start:+.4f}")
    machine.jog("Z", -1, 0.5)
    machine.inc("X", 2, units=500)
    print(f"home Z took {machine.home('Z'):.3f} s")
