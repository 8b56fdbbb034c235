"""A python-canopen `Network` for lock-step simulation on python-can's in-process `virtual` bus.

No Notifier thread: frames are handed to the library when the owner `pump()`s, and a network
with `auto_deliver` pumps its in-process peers and then itself after every frame it sends, so an
SDO request has its answer queued before the client starts waiting. Periodic messages
(heartbeats) run on simulated time, advanced by `advance(dt)` once per SYNC. Together this makes
a CANopen run deterministic and free of sleeps.
"""

from __future__ import annotations

import queue
import time
from collections.abc import Callable

import can
import canopen
from can.interfaces.virtual import VirtualBus


class SharedFrameBus(VirtualBus):
    """python-can's in-process `virtual` bus, handing every receiver the one `Message` a send built.

    `VirtualBus.send` deep-copies the message for each receiver: about 40 % of a lock-step CANopen
    exchange's CPU (issue 17; 15 frames a cycle on the lathe, three receivers each). A lock-step network
    builds a fresh message per frame and never changes it after sending, and with its own messages not
    received every copy got the same timestamp, channel and `is_rx`, so one object serves them all.
    Receivers on the channel that are plain `VirtualBus`es (clients a test attaches) are unaffected."""

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if self.receive_own_messages:  # the copies would differ in is_rx: python-can's own way
            super().send(msg, timeout)
            return
        self._check_if_open()
        if not self.preserve_timestamps:
            msg.timestamp = time.time()
        msg.channel, msg.is_rx = self.channel_id, True
        full = False
        for bus_queue in self.channel:
            if bus_queue is not self.queue:
                try:
                    bus_queue.put(msg, block=True, timeout=timeout)
                except queue.Full:
                    full = True
        if full:
            raise can.CanOperationError("Could not send message to one or more recipients")


class SimPeriodicTask:
    """Stands in for `canopen.network.PeriodicMessageTask` on simulated time."""

    def __init__(self, network: "LockstepNetwork", can_id: int, data: bytes, period: float, remote: bool) -> None:
        self.network, self.can_id, self.data, self.period, self.remote = network, can_id, bytes(data), period, remote
        self.next_time = network.time + period
        self.running = True

    def update(self, data: bytes) -> None:
        self.data = bytes(data)

    def stop(self) -> None:
        self.running = False

    def due(self, now: float) -> None:
        # A small tolerance so that accumulated float cycles don't skip a period.
        while self.running and now + 1e-9 >= self.next_time:
            self.network.send_message(self.can_id, self.data, self.remote)
            self.next_time += self.period


class LockstepNetwork(canopen.Network):
    def __init__(self, channel: str, auto_deliver: bool = False) -> None:
        super().__init__(SharedFrameBus(channel=channel, receive_own_messages=False))
        self.auto_deliver = auto_deliver
        self.peers: list[Callable[[], None]] = []
        self.time = 0.0
        self._tasks: list[SimPeriodicTask] = []

    def send_message(self, can_id: int, data: bytes, remote: bool = False) -> None:
        self.bus.send(can.Message(is_extended_id=can_id > 0x7FF, arbitration_id=can_id, data=data,
                                  is_remote_frame=remote))
        if self.auto_deliver:
            self.deliver()

    def send_raw(self, can_id: int, data: bytes) -> None:
        """Queue a frame without delivering (RPDOs before the SYNC that releases them)."""
        self.bus.send(can.Message(is_extended_id=False, arbitration_id=can_id, data=data))

    def deliver(self) -> None:
        for peer in self.peers:
            peer()
        self.pump()

    def pump(self) -> None:
        bus = self.bus
        while (msg := bus.recv(0)) is not None:
            if not (msg.is_error_frame or msg.is_remote_frame):
                self.notify(msg.arbitration_id, msg.data, self.time)

    def send_periodic(self, can_id: int, data: bytes, period: float, remote: bool = False) -> SimPeriodicTask:
        task = SimPeriodicTask(self, can_id, data, period, remote)
        self._tasks = [t for t in self._tasks if t.running] + [task]
        return task

    def advance(self, dt: float) -> None:
        self.time += dt
        for task in self._tasks:
            task.due(self.time)

    def disconnect(self) -> None:
        for task in self._tasks:
            task.stop()
        if self.bus is not None:
            self.bus.shutdown()
            self.bus = None
