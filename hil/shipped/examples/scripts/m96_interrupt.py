"""M96 program interruption from the MLC (NC5 §3.11.4.6) on the 3-axis mill:

    hil script examples/scripts/m96_interrupt.py --bench benches/mill-3axis.toml

The program cuts X0→X100; half way the MLC raises M21019. The cut stops on its path, O0050 lifts
Z by 10 and lowers it again with M31031 ON, and its M99 goes on in a straight line to X100.
"""

PROGRAM = """G90 G54 G17 G21 G94
M96 P50
G01 X100. F3000
Y50.
X0
M97
M30
O0050
G91 G01 Z10. F2000
Z-10.
M99
"""


def main(machine):
    ch = machine.start_program(PROGRAM, "m96")
    machine.wait_until(lambda: machine.position("X") > 50.0, 5.0, "X past 50")
    machine.set("M21019", 1)  # the trigger: a rising edge
    machine.wait_until(lambda: machine.get("M31031") == 1, 1.0, "M31031 ON")
    print(f"t={machine.time:.3f} s  M21019 taken: X stopped at {machine.command('X'):.4f} (line 3 ends at X100)")
    machine.wait_until(lambda: machine.get("M31031") == 0, 5.0, "M31031 OFF")
    print(f"t={machine.time:.3f} s  O0050 done (M31031 OFF): X {machine.command('X'):.4f} Z {machine.command('Z'):.4f}")
    machine.set("M21019", 0)
    machine.wait_until(lambda: not ch.busy, 10.0, "program end")
    print(f"t={machine.time:.3f} s  end: X {machine.command('X'):.4f} Y {machine.command('Y'):.4f} "
          f"Z {machine.command('Z'):.4f}")
