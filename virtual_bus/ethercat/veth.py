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
