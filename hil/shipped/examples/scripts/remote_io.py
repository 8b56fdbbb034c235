"""Force remote inputs and watch the outputs (benches/lathe-io.toml, examples/mlc/remote_io.py).

    hil script examples/scripts/remote_io.py --bench benches/lathe-io.toml --mlc examples/mlc/remote_io.py
"""


def main(machine):
    machine.set_input("X2")                       # foot switch pressed
    machine.cycle(2)
    print(f"X2 {machine.get('X2')} → chuck clamp Y1 {int(machine.get_output('Y1'))}")
    machine.mdi("M08")                            # coolant on through the M/S/T handshake
    print(f"M08 → coolant Y0 {int(machine.get_output('Y0'))}")
    machine.set_input("X0")                       # the pressure switch answers
    machine.wait(0.6)
    print(f"pressure X0 {machine.get('X0')}, alarm A1 {machine.get('A1')}")
    machine.mdi("M09")
    print(f"M09 → coolant Y0 {int(machine.get_output('Y0'))}")
