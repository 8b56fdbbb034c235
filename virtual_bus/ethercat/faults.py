"""Scripted faults for the virtual line, keyed to the process-data frame count so that a lock-step
run hits them at the same cycle every time.

Spec grammar (`hil sim ethercat --fault SPEC`, repeatable):
  drop@N[xK]              the K frames from process-data frame N are lost (no answer)
  late@N[xK]:MS           those frames are answered MS milliseconds late
  leave:S@N[+K]           slave S (0-based) leaves the line at frame N (back after K frames)
  wkc:S@N[xK]             slave S stops counting the working counter for K frames
  alerr:S@N[:CODE]        slave S drops to SAFE-OP with AL status code CODE (default 0x001A)
  drivefault:S@N[:CODE]   the drive behind slave S faults with error code CODE (default 0x0009)
  drift:S@N:NS            from frame N on, slave S's local DC clock gains NS ns per frame (a bad
                          oscillator its control loop, trimming at most 5 µs a frame, cannot follow)
  refuse:S@T[:CODE]       slave S refuses every request into AL state T (2 PRE-OP, 4 SAFE-OP, 8 OP) with AL
                          status CODE (default 0x0001, unspecified error): a bring-up that cannot finish
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_RE = re.compile(r"^(?P<kind>drop|late|leave|wkc|alerr|drivefault|drift|refuse)(?::(?P<slave>\d+))?@(?P<at>\d+)"
                 r"(?:x(?P<count>\d+))?(?:\+(?P<back>\d+))?(?::(?P<arg>(?:0x)?[0-9a-fA-F.]+))?$")


@dataclass(frozen=True)
class Fault:
    kind: str
    at: int
    slave: int = 0
    count: int = 1
    back: int = 0  # leave: frames until the slave returns; 0 = never
    arg: float = 0.0

    def active(self, frame: int) -> bool:
        if self.kind == "drift":
            return frame >= self.at
        if self.kind == "leave":
            return frame >= self.at and (not self.back or frame < self.at + self.back)
        return self.at <= frame < self.at + self.count


def parse_fault(spec: str) -> Fault:
    m = _RE.match(spec.strip())
    if not m:
        raise ValueError(f"bad fault spec {spec!r} (see `hil sim ethercat --help`)")
    kind = m["kind"]
    if kind in ("leave", "wkc", "alerr", "drivefault", "drift", "refuse") and m["slave"] is None:
        raise ValueError(f"fault {kind} needs a slave: {kind}:S@N")
    arg = m["arg"]
    value = float(int(arg, 16)) if arg and arg.lower().startswith("0x") else float(arg or 0)
    if kind == "alerr" and not arg:
        value = 0x001A
    if kind == "drivefault" and not arg:
        value = 0x0009
    if kind == "refuse":
        if int(m["at"]) not in (2, 4, 8):
            raise ValueError(f"fault refuse: the state must be 2 (PRE-OP), 4 (SAFE-OP) or 8 (OP), got {m['at']}")
        value = value or 0x0001
    return Fault(kind, int(m["at"]), int(m["slave"] or 0), int(m["count"] or 1), int(m["back"] or 0), value)
