"""A remote I/O station on CANopen as the MLC sees it (`mlc.remote_io.IoPort`): CiA 401 station k
of the link, inputs from its last TPDO, outputs in its RPDO of the next cycle. While the station is
not OPERATIONAL (heartbeat lost, left OPERATIONAL) its inputs read 0 (the safe state)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class CanopenIoPort:
    link: object  # fieldbus.canopen.link.CanopenLink
    index: int  # k: the k-th I/O station the link configured
    name: str

    @property
    def connected(self) -> bool:
        return self.link.io_ok(self.index)

    def read_inputs(self, dt: float) -> tuple[int, list[int]]:
        return self.link.io_inputs(self.index), []

    def write_outputs(self, digital: int, analog: list[int]) -> None:
        self.link.set_io_outputs(self.index, digital)
