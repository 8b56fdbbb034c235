"""A remote I/O station on EtherCAT as the MLC sees it (`mlc.remote_io.IoPort`): the k-th I/O
slave in connection order (EIO node 501+k), its inputs from the last good frame, its outputs on
the next frame. While the slave is not in OP its inputs read 0 (the safe state). A station the bench
builds from `modules` is checked against the module list the slave reports (0xF050): another
composition, even of the same size, is 0x142E (when every ident it reports is one of ours)."""

from __future__ import annotations

from dataclasses import dataclass

from fieldbus.ethercat import alarms as A
from fieldbus.ethercat.r1ec_modules import MODULES
from fieldbus.link import BusError
from nc.alarms import Alarm


@dataclass
class EthercatIoPort:
    link: object  # fieldbus.ethercat.link.EthercatLink
    index: int  # k: the k-th I/O slave on the line
    name: str
    inputs: int  # points the bench declares
    outputs: int
    modules: tuple[str, ...] = ()  # the bench's R1-EC modules in slot order; () = check the sizes only
    _checked: bool = False

    @property
    def connected(self) -> bool:
        return self.link.io_ok(self.index)

    def _check(self) -> None:
        """Once, after bring-up: the slave exists and its image holds the declared points (0x142E)."""
        if self._checked or self.link.master is None:
            return
        self._checked = True
        n_in, n_out = self.link.io_bits(self.index)
        found = len(self.link.io)
        if self.index >= found:  # App. A 0x142F: no I/O slave at the station's port (connection order)
            raise BusError(Alarm(A.EIO_NOT_FOUND, f"remote I/O station {self.name} (EIO node {501 + self.index}) "
                                                  f"not found: only {found} I/O slaves on the line"))
        if n_in < self.inputs or n_out < self.outputs:
            raise BusError(Alarm(A.EIO_MISMATCH, f"remote I/O station {self.name} (EIO node {501 + self.index}) needs "
                                         f"{self.inputs} inputs / {self.outputs} outputs; EtherCAT has "
                                         f"{n_in} inputs / {n_out} outputs"))
        found_mods = self.link.io_modules(self.index) if self.modules else None
        # Idents outside our catalogue (a real R1-EC's own codes) cannot be named: the sizes above decide.
        if found_mods is not None and all(m in MODULES for m in found_mods) and found_mods != list(self.modules):
            raise BusError(Alarm(A.EIO_MISMATCH, f"remote I/O station {self.name} (EIO node {501 + self.index}) is set "
                                                 f"up as {' + '.join(self.modules)}; the slave reports "
                                                 f"{' + '.join(found_mods) or 'no modules'}"))

    def read_inputs(self, dt: float) -> tuple[int, list[int]]:
        self._check()
        return self.link.io_inputs(self.index) & ((1 << self.inputs) - 1), []

    def write_outputs(self, digital: int, analog: list[int]) -> None:
        self.link.set_io_outputs(self.index, digital & ((1 << self.outputs) - 1))

