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
        hexid = secrets.token_hex(3)
        uid = (tag + hexid)[:8] if len(tag) <= 3 else tag[:2] + hexid  # (interface names: 15 characters at most)
        pair = cls(f"dhil-{tag}{hexid}", f"ecm{uid}", f"ecs{uid}")  # the namespace: the whole tag
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
        self.banner = ""  # its first line: the slaves it serves, and its placement (decisions E21)

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
            self.banner = line.strip()
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



class ForkedLine:
    """A `Chain` built in this process, served by a forked child on the namespace end of a fresh veth
    pair (pysoem holds the GIL while it waits for a frame, so the slaves cannot be a thread of the
    master's process). The DIO slaves' terminals are shared memory: the parent sets inputs and reads
    outputs while the master runs on `iface`; the child copies them around every frame.
    Context manager; cleans everything up. Needs root, like `VethPair`."""

    def __init__(self, chain, tag: str = "") -> None:
        import multiprocessing as mp

        self.chain = chain
        self.tag = tag
        self.pair: VethPair | None = None
        self.proc = None
        self._dio = [k for k, s in enumerate(chain.slaves) if hasattr(s.app, "inputs")]
        ctx = mp.get_context("fork")
        self._ctx = ctx
        self._in = ctx.Array("Q", max(1, len(self._dio)), lock=False)
        self._out = ctx.Array("Q", max(1, len(self._dio)), lock=False)
        self._frames = ctx.Value("Q", 0, lock=False)

    @property
    def iface(self) -> str:
        assert self.pair is not None
        return self.pair.master_if

    # ---- the parent's view of the I/O slaves (k-th DIO slave on the line) ------------------------
    def set_inputs(self, k: int, value: int) -> None:
        self._in[k] = value

    def outputs(self, k: int) -> int:
        return int(self._out[k])

    @property
    def pd_frames(self) -> int:
        """Process-data frames the line has answered or dropped so far."""
        return int(self._frames.value)

    def __enter__(self) -> "ForkedLine":
        self.pair = VethPair.create(self.tag)
        ready = self._ctx.Event()
        self.proc = self._ctx.Process(target=self._serve, args=(ready,), daemon=True)
        self.proc.start()
        if not ready.wait(5.0):
            self.__exit__(None, None, None)
            raise RuntimeError("the forked EtherCAT line did not start")
        return self

    def _serve(self, ready) -> None:
        import ctypes

        from virtual_bus.ethercat.network import RawSocketLine

        assert self.pair is not None
        libc = ctypes.CDLL(None, use_errno=True)
        with open(f"/var/run/netns/{self.pair.netns}") as ns:
            if libc.setns(ns.fileno(), 0x40000000) != 0:  # CLONE_NEWNET
                raise OSError(ctypes.get_errno(), "setns")
        line = RawSocketLine(self.chain, self.pair.slave_if)
        apps = [self.chain.slaves[k].app for k in self._dio]
        process = self.chain.process

        def shared_process(frame: bytes):
            for k, app in enumerate(apps):
                app.inputs = int(self._in[k])
            answer = process(frame)
            for k, app in enumerate(apps):
                self._out[k] = app.outputs
            self._frames.value = self.chain.pd_frames
            return answer

        self.chain.process = shared_process  # type: ignore[method-assign]
        ready.set()
        line.serve()

    def __exit__(self, *exc) -> None:
        if self.proc is not None and self.proc.is_alive():
            self.proc.terminate()
            self.proc.join(5.0)
        if self.pair is not None:
            self.pair.delete()
