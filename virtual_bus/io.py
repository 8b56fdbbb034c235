"""A simulated remote I/O module (EtherCAT EIO / CANopen CiA 401 style): digital inputs and
outputs as bit masks plus four analog words each way, as App. B maps remote modules
(D20200+4k outputs, D30200+4k inputs).

It is a SimLink slave (`exchange(outputs, dt) -> inputs`) and also answers the MLC's direct
`exchange_io` call. Tests and scripts drive the inputs (`set_input`, `analog_in`) and read what
the MLC switched (`output(point)`); `wiring` loops outputs back to inputs after a delay, the way a
coolant pump's pressure switch or a clamp's confirmation switch answers.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class IoImage:
    digital: int = 0
    analog: list[int] = field(default_factory=lambda: [0, 0, 0, 0])


@dataclass
class IoModule:
    name: str = "EIO-501"
    kind: str = "io"
    node: int = 501
    inputs: int = 0  # digital input bits
    outputs: int = 0  # digital output bits, as last written by the master
    analog_in: list[int] = field(default_factory=lambda: [0, 0, 0, 0])
    analog_out: list[int] = field(default_factory=lambda: [0, 0, 0, 0])
    wiring: dict[int, tuple[int, float]] = field(default_factory=dict)  # out point → (in point, delay s)
    time: float = 0.0
    history: list[tuple[float, int]] = field(default_factory=list)  # (time, outputs) at each change
    connected: bool = True  # False: the module is off the line (its inputs read 0 in the MLC)
    _since: dict[int, float] = field(default_factory=dict)

    def set_input(self, point: int, on: bool) -> None:
        self.inputs = (self.inputs | 1 << point) if on else (self.inputs & ~(1 << point))

    def output(self, point: int) -> bool:
        return bool(self.outputs >> point & 1)

    # The MLC's side (mlc.remote_io.IoPort): inputs at the start of a scan, outputs after it.

    def read_inputs(self, dt: float) -> tuple[int, list[int]]:
        self.time += dt
        self._wire()
        return self.inputs, list(self.analog_in)

    def write_outputs(self, digital: int, analog: list[int]) -> None:
        if digital != self.outputs:
            self.history.append((self.time, digital))
        self.outputs = digital
        self.analog_out = list(analog[:4])

    def exchange_io(self, outputs: int, analog_out: list[int], dt: float) -> tuple[int, list[int]]:
        self.write_outputs(outputs, analog_out)
        return self.read_inputs(dt)

    def _wire(self) -> None:
        for out_pt, (in_pt, delay) in self.wiring.items():
            if self.output(out_pt):
                start = self._since.setdefault(out_pt, self.time)
                self.set_input(in_pt, self.time - start >= delay - 1e-12)
            else:
                self._since.pop(out_pt, None)
                self.set_input(in_pt, False)

    def exchange(self, rx: IoImage, dt: float) -> IoImage:
        di, ai = self.exchange_io(rx.digital, rx.analog, dt)
        return IoImage(di, ai)
