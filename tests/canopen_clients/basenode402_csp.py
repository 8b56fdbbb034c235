"""An independent CANopen master: python-canopen's own BaseNode402 client, in its own process.

Usage: python basenode402_csp.py GROUP  (inside a loopback-only network namespace). It finds node 1,
sets a 10 ms interpolation period, reads the PDO configuration the node advertises, runs SYNC and
its RPDOs at 10 ms, switches to CSP and to operation enabled, moves 0.02 motor revolutions and
prints what it saw as one JSON line.
"""
import json, sys, time
import canopen
from canopen.profiles.p402 import BaseNode402
from fieldbus.canopen.objects import ASDA_B3_EDS
group = sys.argv[1]
net = canopen.Network()
net.connect(interface="udp_multicast", channel=group)
node = BaseNode402(1, str(ASDA_B3_EDS))
net.add_node(node)
end = time.monotonic() + 10
while True:
    try:
        device_type = node.sdo[0x1000].raw
        break
    except canopen.SdoCommunicationError:
        if time.monotonic() > end:
            raise
node.nmt.state = "PRE-OPERATIONAL"
node.sdo[0x60C2][1].raw = 10
node.sdo[0x60C2][2].raw = -3
node.setup_402_state_machine()
start = node.sdo[0x6064].raw
node.rpdo[0x607A].raw = start  # CSP: command where the drive stands before enabling
node.nmt.state = "OPERATIONAL"
net.sync.start(0.01)
for m in node.rpdo.values():
    if m.enabled:
        m.start(0.01)
node.op_mode = "CYCLIC SYNCHRONOUS POSITION"
node.state = "OPERATION ENABLED"
result = {"device_type": device_type, "state": node.state, "op_mode": node.op_mode,
          "statusword_sdo": node.sdo[0x6041].raw, "start": start}
target = start + 25_600  # 0.02 motor rev
node.rpdo[0x607A].raw = target
time.sleep(0.5)
result["position"] = node.sdo[0x6064].raw
result["target"] = target
node.state = "SWITCH ON DISABLED"
result["final_state"] = node.state
net.sync.stop()
for m in node.rpdo.values():
    m.stop()
net.disconnect()
print(json.dumps(result), flush=True)
