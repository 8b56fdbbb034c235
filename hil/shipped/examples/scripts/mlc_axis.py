"""An MLC axis (NC5 App. B.2 M2x432+i … M3x448+i; decisions mlc M26-20 … M26-27) on the 3-axis mill:

    hil script examples/scripts/mlc_axis.py --bench benches/mill-3axis.toml

X (axis 0: M21432, D21256/D21288) is switched to the MLC, moved to 30.5 absolute at 6000 mm/min, then 5 incremental,
run in speed mode at 1200 mm/min for 0.5 s and stopped, and handed back to the NC, whose MDI G01 then starts from
where the MLC left X. `machine.set` writes the f32 registers as floats (both words, decision bench B129).
"""

X = 0  # the channel's axis index of X
SWITCH, SPEED, TRIGGER, INCREMENTAL = 21432 + X, 21416 + X, 21448 + X, 21464 + X
SWITCHED, REACHED = f"M{31432 + X}", f"M{31448 + X}"
TARGET, VELOCITY = 21256 + 2 * X, 21288 + 2 * X


def main(machine):
    machine.set(f"M{SWITCH}")
    t = machine.wait_until(lambda: machine.get(SWITCHED) == 1, 1.0, "X switched to the MLC")
    print(f"switched at t {t:.3f} s, X {machine.command('X'):.4f}")
    machine.set(f"D{TARGET}", 30.5)
    machine.set(f"D{VELOCITY}", 6000.0)
    machine.set(f"M{TRIGGER}")
    machine.cycle(2)  # the MLC's scan sees the edge, M3x448 drops
    t = machine.wait_until(lambda: machine.get(REACHED) == 1, 5.0, "X at 30.5")
    print(f"absolute: X {machine.command('X'):.4f} after {t:.3f} s")
    machine.set(f"M{TRIGGER}", False)
    machine.set(f"M{INCREMENTAL}")
    machine.set(f"D{TARGET}", 5.0)
    machine.cycle()
    machine.set(f"M{TRIGGER}")
    machine.cycle(2)  # the MLC's scan sees the edge, M3x448 drops
    t = machine.wait_until(lambda: machine.get(REACHED) == 1, 5.0, "X at 35.5")
    print(f"incremental: X {machine.command('X'):.4f} after {t:.3f} s")
    machine.set(f"M{TRIGGER}", False)
    machine.set(f"M{SPEED}")
    machine.set(f"D{VELOCITY}", -1200.0)
    machine.cycle()
    machine.set(f"M{TRIGGER}")
    machine.cycle(2)  # the MLC's scan sees the edge, M3x448 drops
    machine.wait_until(lambda: machine.get(REACHED) == 1, 5.0, "X at -20 mm/s")
    machine.wait(0.5)
    machine.set(f"M{TRIGGER}", False)
    machine.wait(0.1)
    print(f"speed mode: X {machine.command('X'):.4f} after 0.5 s at -20 mm/s and the stop")
    machine.set(f"M{SWITCH}", False)
    machine.wait_until(lambda: machine.get(SWITCHED) == 0, 1.0, "X back to the NC")
    start = machine.command("X")
    machine.mdi("G90 G01 X0. F3000")
    print(f"NC again: G01 X0. from X {start:.4f} to X {machine.command('X'):.4f}, "
          f"alarms {len(machine.all_alarms())}")
