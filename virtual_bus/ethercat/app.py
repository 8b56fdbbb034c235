"""What sits behind a virtual slave's process data: a CiA 402 drive or a digital I/O module.

Process data goes through the object dictionary (outputs are written into their objects, inputs
read from theirs), so the PDO mapping a master configures over SDO is the one that is used.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from operator import attrgetter

from fieldbus.pdo import ASDA_CSP_CSV, ASDA_E, RxPdo, TxPdo
from fieldbus.cia402 import State
from virtual_bus.drive import Cia402Drive
from virtual_bus.drive_modes import CST, MODE_OBJECTS, check_value
from virtual_bus.ethercat.coe import ABORT_VALUE_RANGE, ObjectDictionary, SdoAbort
from virtual_bus.ethercat.device import OBJ_VAR, TYPES, OdEntry, OdObject
from virtual_bus.ethercat.esc import SlaveApp
from virtual_bus.ethercat.pdo_image import DriveCodec, Images
from virtual_bus.servo_params import ServoParamError, ServoParams, coe_objects

# (index, subindex) -> RxPdo / TxPdo attribute, from the layouts' entries
RX_ATTR = {(e.index, e.subindex): e.attr for e in ASDA_CSP_CSV.rx + ASDA_E.rx} | {(0x60FE, 1): "digital_outputs"}
TX_ATTR = {(e.index, e.subindex): e.attr for e in ASDA_CSP_CSV.tx + ASDA_E.tx}
COMM_FAULT = 0x7500  # CiA 402 error code class "communication"


@dataclass
class DriveApp(SlaveApp):
    drive: Cia402Drive
    od: ObjectDictionary | None = None
    _last_error: int = 0
    _params: set[int] = field(default_factory=set)  # object indices of the Delta Pn-xx parameters
    # Compiled once at attach (issue 17): the OD entries behind RxPdo / TxPdo fields, so a frame
    # makes no object lookups; entries keep their identity (SDO writes change their values only).
    _rx_pairs: list[tuple[str, OdEntry]] = field(default_factory=list)
    _tx_entries: tuple[OdEntry, ...] = ()
    _tx_values: Callable[[TxPdo], tuple] = field(default=lambda fb: ())
    _images: Images = field(default_factory=Images)
    _codec: DriveCodec | None = None  # the mapping in force in one function per direction, see `_codec_for`
    _codec_maps: tuple[object, object] = (None, None)
    _coast_t: float = 0.0  # time since the drive began its fault reaction with no master (`coast`)
    _coast_v: float = 0.0  # its speed then (counts/s)

    def attach(self, od: ObjectDictionary) -> None:
        self.od = od
        # Delta parameters Pn-xx as objects 0x2000 + n*0x100 + xx (DINT), served from the drive's
        # `ServoParams` so SDO, Modbus and the drive see one table (issue 8).
        dtype, bits, signed = TYPES["DINT"]
        self._params = {index for index, _ in coe_objects()}
        for index, p in coe_objects():
            od.objects[index] = OdObject(index, p.label, OBJ_VAR, {0: OdEntry(
                0, p.label, dtype, bits, signed, "rw" if p.writable else "ro", value=p.default)})
        od.after_write = self._after_write
        od.before_write = self._before_write
        objects = self.drive.modes.objects  # the profile modes' objects start at the ESI's defaults
        for (index, sub), attr in MODE_OBJECTS.items():
            if index in od.objects and sub in od.objects[index].entries:
                setattr(objects, attr, od.value(index, sub))
        self._rx_pairs = [(attr, od.entry(index, sub)) for (index, sub), attr in RX_ATTR.items() if index in od.objects]
        tx = [(od.entry(index, sub), attr) for (index, sub), attr in TX_ATTR.items() if index in od.objects]
        self._tx_entries = tuple(e for e, _ in tx)
        getter = attrgetter(*(a for _, a in tx)) if tx else (lambda fb: ())
        self._tx_values = getter if len(tx) != 1 else (lambda fb: (getter(fb),))
        self._publish()

    def _before_write(self, index: int, sub: int, value) -> None:
        """0x6060 takes only the modes 0x6502 advertises (0: no mode); CiA 402 / Delta: abort 0x06090030."""
        od = self.od
        if index == 0x6060 and od is not None and 0x6502 in od.objects:
            supported = od.value(0x6502)
            if value != 0 and not (1 <= value <= 32 and supported >> (value - 1) & 1):
                raise SdoAbort(ABORT_VALUE_RANGE)
        if (index, sub) in MODE_OBJECTS and not check_value(index, sub, value, self.drive.modes.objects):
            raise SdoAbort(ABORT_VALUE_RANGE)

    def _after_write(self, index: int, sub: int) -> None:
        """A servo parameter written over SDO goes through the drive's checks; a refusal restores
        the old value and aborts the transfer with the drive's code."""
        od, params = self.od, self.drive.servo_params
        if index == 0x6060 and od is not None:  # by SDO too: the drive takes the mode at once, 0x6061 shows it
            if od.value(0x6060) != self.drive.mode:
                self.drive.select_mode(od.value(0x6060))
            self._publish()
            return
        attr = MODE_OBJECTS.get((index, sub))
        if attr is not None and od is not None:  # the drive's copy of a profile-mode object (drive_modes.py)
            setattr(self.drive.modes.objects, attr, od.value(index, sub))
            return
        if od is None or index not in self._params:  # 0x2511 (P5-17, auxiliary encoder) is the device's own
            return
        try:
            params.write(ServoParams.from_index(index, sub), od.value(index, sub))
        except ServoParamError as exc:
            od.set(index, sub, params.read(ServoParams.from_index(index, sub)))
            raise SdoAbort(exc.code) from None

    def _publish(self) -> None:
        self._publish_fb(self.drive.feedback())

    def _publish_fb(self, fb: TxPdo) -> None:
        for e, v in zip(self._tx_entries, self._tx_values(fb)):
            e.value = int(v)

    def refresh(self, index: int) -> None:
        if any(index == i for i, _ in TX_ATTR):
            self._publish()
        elif index in self._params and self.od is not None:
            self.od.set(index, 0, self.drive.servo_params.read(ServoParams.from_index(index, 0)))

    def _codec_for(self, rx_map, tx_map, od: ObjectDictionary) -> DriveCodec | None:
        """The compiled codec of the mapping lists the ESC hands over (new ones on every SAFE-OP entry)."""
        if self._codec_maps[0] is not rx_map or self._codec_maps[1] is not tx_map:
            self._codec = DriveCodec.compile(rx_map, tx_map, od, RX_ATTR, TX_ATTR)
            self._codec_maps = (rx_map, tx_map)
        return self._codec

    def cycle(self, outputs: bytes | memoryview, rx_map, tx_map, step: bool, dt: float = 0.0,
              lost: bool = False) -> bytes:
        od = self.od
        assert od is not None
        codec, maps = self._codec, self._codec_maps
        if maps[0] is not rx_map or maps[1] is not tx_map:
            codec = self._codec_for(rx_map, tx_map, od)
        drive = self.drive
        if step and not lost:
            if codec is not None:  # the usual frame: outputs into their objects and the RxPdo in one call
                rx = codec.read_rx(outputs, drive.mode)
            else:
                self._images.get(rx_map, tx_map, od).unpack(outputs, rx_map, od)
                rx = self._rx_from_od()
            if drive.mode == CST:
                self._torque_limits()
            # apply, step and feedback in one call: the drive's fused path of an enabled CSP / CSV cycle
            # (the one CANopen's SYNC takes), the three calls otherwise (issue 17)
            fb = drive.exchange(rx, dt)
            if codec is not None:
                return codec.write_tx(fb)
        else:
            if step:
                # Out of OP by an error (SM watchdog, sync, AL error): the outputs are not valid any more.
                # The drive takes its communication fault reaction (CiA 402 0x6007 = 2: fault, braking on
                # the quick-stop ramp) and its time runs on, so the master still sees it brake.
                if drive.state in (State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE):
                    drive.fault(COMM_FAULT)  # a drive that was not powering its motor has nothing to stop
                drive.step(dt)
            fb = drive.feedback()
            if codec is not None:
                return codec.write_tx(fb)
        self._publish_fb(fb)
        return self._images.get(rx_map, tx_map, od).pack(tx_map, od)

    def _torque_limits(self) -> None:
        """CST: the torque limits may travel in 0x1603; the drive takes them from their objects."""
        od = self.od
        if od is not None and 0x60E0 in od.objects:
            self.drive.modes.objects.positive_torque_limit = od.value(0x60E0)
            self.drive.modes.objects.negative_torque_limit = od.value(0x60E1)

    @property
    def coasting(self) -> bool:
        return self.drive.state in (State.OPERATION_ENABLED, State.QUICK_STOP_ACTIVE, State.FAULT_REACTION_ACTIVE)

    def coast(self, dt: float) -> str | None:
        """No master: the communication fault reaction (as in `cycle` with `lost`) runs on in the drive's own
        time, so it brakes on the quick-stop ramp to standstill and drops its power stage (FAULT)."""
        d = self.drive
        if self._coast_t == 0.0:  # the first step with no master (the reaction may have begun on a read already)
            self._coast_v = d.velocity
        if d.state is not State.FAULT_REACTION_ACTIVE:
            d.fault(COMM_FAULT)
        d.step(dt)
        self._coast_t += dt
        if d.state is State.FAULT_REACTION_ACTIVE:
            return None
        how = (f"braked from {self._coast_v:.0f} counts/s to standstill in {self._coast_t:.3f} s"
               if abs(self._coast_v) >= 1.0 else "at standstill")
        self._coast_t = 0.0  # (a next loss of its master is logged afresh)
        return (f"drive {how} on its communication fault reaction, at {round(d.position)} counts; "
                f"FAULT 0x{d.error_code:04X}, power stage off")

    def _rx_from_od(self) -> RxPdo:
        rx = RxPdo(mode=self.drive.mode)
        for attr, e in self._rx_pairs:
            v = e.value
            setattr(rx, attr, v if isinstance(v, int) else 0)  # ObjectDictionary.value's rule
        return rx

    def new_error(self) -> int:
        """The drive's error code if it changed to a new non-zero value since the last call."""
        code = self.drive.error_code
        fresh = code if code and code != self._last_error else 0
        self._last_error = code
        return fresh


@dataclass
class DioApp(SlaveApp):
    """An R1-EC station's digital modules (virtual_bus/ethercat/r1ec.py): `inputs` / `outputs` are the
    station's points in module order; input module i is 0x6000+0x10·i:1, output module j 0x7000+0x10·j:1
    (the default station: 16 inputs at 0x6000:1, 16 outputs at 0x7000:1). A test drives `inputs`."""

    inputs: int = 0
    outputs: int = 0
    od: ObjectDictionary | None = None
    history: list[int] = field(default_factory=list)
    in_objs: list[tuple[int, int]] = field(default_factory=list)  # (index, bits) per input module
    out_objs: list[tuple[int, int]] = field(default_factory=list)
    _images: Images = field(default_factory=Images)

    @property
    def coasting(self) -> bool:
        return self.outputs != 0

    def coast(self, dt: float) -> str | None:
        """No master: the outputs go to their safe state, off (an ESC's process-data watchdog: a spindle enable
        or a coolant valve must not stay on with nobody in charge)."""
        was, self.outputs = self.outputs, 0
        return f"outputs off (were 0x{was:X}): their safe state with no master"

    def attach(self, od: ObjectDictionary) -> None:
        self.od = od
        self.in_objs = self._modules(od, 0x6000)
        self.out_objs = self._modules(od, 0x7000)

    @staticmethod
    def _modules(od: ObjectDictionary, base: int) -> list[tuple[int, int]]:
        out, index = [], base
        while index in od.objects:
            out.append((index, od.objects[index].entries[1].bits))
            index += 0x10
        return out

    def _publish(self) -> None:
        od = self.od
        assert od is not None
        shift = 0
        for index, bits in self.in_objs:
            od.set(index, 1, self.inputs >> shift & ((1 << bits) - 1))
            shift += bits

    def refresh(self, index: int) -> None:
        if self.od is not None and any(index == i for i, _ in self.in_objs):
            self._publish()

    def cycle(self, outputs: bytes | memoryview, rx_map, tx_map, step: bool, dt: float = 0.0,
              lost: bool = False) -> bytes:
        od = self.od
        assert od is not None
        images = self._images.get(rx_map, tx_map, od)
        if step and not lost:
            images.unpack(outputs, rx_map, od)
            value, shift = 0, 0
            for index, bits in self.out_objs:
                value |= (od.value(index, 1) & ((1 << bits) - 1)) << shift
                shift += bits
            self.outputs = value
        self._publish()
        return images.pack(tx_map, od)
