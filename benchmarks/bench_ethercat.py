"""EtherCAT over a veth pair: pysoem master + virtual slaves (3 ASDA-class drives).

Prints (asserts nothing):
  * cycles/s reached back to back (lock-step slaves, one LRW per cycle), with both processes SCHED_FIFO 50 on
    one CPU as a user places them (hil/placement.py: `hil sim ethercat --cpu N --priority 50`, and the master
    as `[realtime] lockstep = "fifo"` places `hil run`; decisions E21; what was refused is printed),
  * p50 / p99 / p99.9 cycle-period jitter with the master paced at the bench cycle (real-time
    mode: slaves advance by wall-clock time).
Needs root (veth pair). Usage: python benchmarks/bench_ethercat.py [--cycles N] [--period-ms P]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from fieldbus.cia402 import Cia402Master, Target
from fieldbus.ethercat.link import EthercatLink
from fieldbus.pdo import RxPdo
from hil.bench import default_lathe
from hil.placement import Placed, placement_cpu
from virtual_bus.ethercat.veth import SimProcess


def drive_loop(link: EthercatLink, n: int, period: float | None) -> np.ndarray:
    rx = [RxPdo(mode=8), RxPdo(mode=8), RxPdo(mode=9)]
    masters = [Cia402Master(target=Target.ENABLED) for _ in rx]
    stamps = np.empty(n)
    next_t = time.perf_counter()
    for k in range(n):
        if period:
            next_t += period
            while True:  # sleep most of the way, then spin: the usual Python pacer
                left = next_t - time.perf_counter()
                if left <= 0:
                    break
                if left > 0.0003:
                    time.sleep(left - 0.0002)
        stamps[k] = time.perf_counter()
        tx = link.exchange(rx)
        for m, r, t in zip(masters, rx, tx):
            r.controlword = m.step(t.statusword)
            r.target_position = t.position_actual
    return stamps


def pysoem_alone(link: EthercatLink, n: int) -> float:
    """The master's CPU seconds a cycle in pysoem alone (send + receive of the images already set)."""
    m = link.master
    assert m is not None
    c0 = time.thread_time()
    for _ in range(n):
        m.send_processdata()
        m.receive_processdata(link.receive_timeout_us)
    return (time.thread_time() - c0) / n


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cycles", type=int, default=5000)
    ap.add_argument("--period-ms", type=float, default=1.0)
    args = ap.parse_args()
    bench = default_lathe()  # X, Z and the spindle: 3 drives
    cpu_n, prio = placement_cpu(bench.realtime), 50
    placed_sim = ("--cpu", str(cpu_n), "--priority", str(prio))
    for mode, sim_args in (("lock-step, back to back", placed_sim), ("real-time, paced", ("--realtime",))):
        with SimProcess(*sim_args, tag="ecat9") as sim:
            link = EthercatLink.for_bench(bench, sim.iface)
            link.open()
            try:
                if sim_args is placed_sim:
                    master = Placed()
                    try:
                        placed = f"master {master.apply(prio, cpu_n).what}, slaves {sim.banner.partition('; ')[2]}"
                        c0 = time.thread_time()
                        s = drive_loop(link, args.cycles, None)
                        cpu = time.thread_time() - c0
                        raw = pysoem_alone(link, args.cycles)
                    finally:
                        master.restore()
                    total = s[-1] - s[0]
                    print(f"{mode}: {args.cycles / total:,.0f} cycles/s "
                          f"({total / args.cycles * 1e6:.1f} µs per LRW round trip, 3 drives; {placed}); master CPU "
                          f"{cpu / args.cycles * 1e6:.1f} µs a cycle, pysoem's send + receive alone {raw * 1e6:.1f} µs")
                else:
                    s = drive_loop(link, args.cycles, args.period_ms / 1000.0)
                    jitter = np.abs(np.diff(s) - args.period_ms / 1000.0) * 1e6
                    p50, p99, p999 = np.percentile(jitter, [50, 99, 99.9])
                    print(f"{mode} at {args.period_ms:g} ms: jitter p50 {p50:.1f} µs  p99 {p99:.1f} µs  "
                          f"p99.9 {p999:.1f} µs  max {jitter.max():.1f} µs  bad cycles {link.stats.bad_cycles}")
            finally:
                link.close()


if __name__ == "__main__":
    main()
