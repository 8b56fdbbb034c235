"""A throw-away network namespace with a veth pair: the master's end stays in the caller's
namespace, the slaves' end goes into the namespace. Needs CAP_NET_ADMIN (root)."""

from __future__ import annotations

import os
import secrets
import subprocess
from dataclasses import dataclass


def _ip(*args: str) -> None:
    subprocess.run(["ip", *args], check=True, capture_output=True, text=True)


@dataclass
class VethPair:
    netns: str
    master_if: str
    slave_if: str

    @classmethod
    def create(cls, tag: str = "") -> "VethPair":
        uid = (tag + secrets.token_hex(3))[:8]
        pair = cls(f"dhil-{uid}", f"ecm{uid}", f"ecs{uid}")
        _ip("netns", "add", pair.netns)
        try:
            _ip("link", "add", pair.master_if, "type", "veth", "peer", "name", pair.slave_if)
            _ip("link", "set", pair.slave_if, "netns", pair.netns)
            _ip("link", "set", pair.master_if, "up")
            _ip("netns", "exec", pair.netns, "ip", "link", "set", pair.slave_if, "up")
            _ip("netns", "exec", pair.netns, "ip", "link", "set", "lo", "up")
        except subprocess.CalledProcessError:
            pair.delete()
            raise
        return pair

    def exec_prefix(self) -> list[str]:
        return ["ip", "netns", "exec", self.netns]

    def delete(self) -> None:
        subprocess.run(["ip", "link", "del", self.master_if], capture_output=True)
        subprocess.run(["ip", "netns", "del", self.netns], capture_output=True)


def can_create() -> str | None:
    """None if veth pairs can be made here, else the reason they cannot."""
    if os.geteuid() != 0:
        return "needs root (CAP_NET_ADMIN) to create a network namespace and a veth pair"
    try:
        VethPair.create("probe").delete()
    except (OSError, subprocess.CalledProcessError) as exc:
        return f"cannot create a veth pair here: {getattr(exc, 'stderr', '') or exc}"
    return None


class SimProcess:
    """`hil sim ethercat` running in the namespace end of a veth pair, as a context manager:
    creates the pair, starts the slaves, waits until they listen, and cleans everything up."""

    def __init__(self, *sim_args: str, tag: str = "") -> None:
        self.sim_args = list(sim_args)
        self.tag = tag
        self.pair: VethPair | None = None
        self.proc: subprocess.Popen | None = None
        self.log = ""

    @property
    def iface(self) -> str:
        assert self.pair is not None
        return self.pair.master_if

    def __enter__(self) -> "SimProcess":
        import sys

        self.pair = VethPair.create(self.tag)
        try:
            cmd = self.pair.exec_prefix() + [sys.executable, "-m", "hil.cli", "sim", "ethercat",
                                             "--iface", self.pair.slave_if, "--verbose", *self.sim_args]
            self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            line = self.proc.stdout.readline() if self.proc.stdout else ""
            if "slaves on" not in line:
                self.proc.wait(5)
                raise RuntimeError(f"hil sim ethercat did not start: {line}{self.proc.stderr.read() if self.proc.stderr else ''}")
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                _, self.log = self.proc.communicate(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        if self.pair is not None:
            self.pair.delete()
