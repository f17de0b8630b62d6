"""python-canopen as the master of the served NORD system bus, over socketcand (python-can's
`socketcand` interface): reads and writes P102 of inverter 3 at its NORD object (node 36,
object 2000h + 102 = 2066h, sub-index 1 = parameter set 1), and checks that bad requests get
CiA 301 abort codes while the node goes on serving. Then it starts the node and runs process
data the CiA 301 way: RPDO1 (200h + 36) with control word 047Eh, SYNC, and the node's TPDO1
(180h + 36) with its status word. Prints one JSON line of what it saw; the Rust test judges it.

With an EDS (`harness describe eds --bus can --profile sk550p --inverter 3`), python-canopen
imports it as the node's object dictionary and also reads P102 by its name there.

Usage: canopen_master.py HOST PORT CHANNEL [EDS]
"""

import json
import struct
import sys
import time

import canopen

host, port, channel = sys.argv[1], int(sys.argv[2]), sys.argv[3]
network = canopen.Network()
network.connect(interface="socketcand", host=host, port=port, channel=channel)
seen = {}
try:
    node = canopen.RemoteNode(36, canopen.ObjectDictionary())
    network.add_node(node)
    sdo = node.sdo
    seen["p102_before"] = struct.unpack("<H", sdo.upload(0x2066, 1))[0]
    sdo.download(0x2066, 1, struct.pack("<H", 250))
    seen["p102_after"] = struct.unpack("<H", sdo.upload(0x2066, 1))[0]
    seen["device_name"] = sdo.upload(0x1008, 0).decode("ascii")
    aborts = {}
    for name, call in [
        ("absent_object", lambda: sdo.upload(0x3000, 0)),
        ("absent_subindex", lambda: sdo.upload(0x1017, 9)),
        ("read_only", lambda: sdo.download(0x1018, 1, b"\x00\x00\x00\x00")),
        ("too_high", lambda: sdo.download(0x2066, 1, struct.pack("<h", 32767))),
    ]:
        try:
            call()
            aborts[name] = None
        except canopen.SdoAbortedError as e:
            aborts[name] = e.code
    seen["aborts"] = aborts
    # Still serving after the refusals.
    seen["p102_last"] = struct.unpack("<H", sdo.upload(0x2066, 1))[0]
    # Process data: node 36 to OPERATIONAL, then RPDO1 "Shut down" (047Eh) and SYNC, a few
    # cycles; the node answers each SYNC with its TPDO1.
    tpdo = []
    network.subscribe(0x1A4, lambda cob_id, data, ts: tpdo.append(bytes(data)))
    node.nmt.state = "OPERATIONAL"
    time.sleep(0.05)
    for _ in range(5):
        network.send_message(0x224, struct.pack("<4H", 0x047E, 0, 0, 0))
        network.sync.transmit()
        time.sleep(0.02)
    time.sleep(0.1)
    seen["tpdo_count"] = len(tpdo)
    seen["tpdo_status"] = struct.unpack("<H", tpdo[-1][:2])[0] if tpdo else None
    seen["tpdo_len"] = len(tpdo[-1]) if tpdo else None
    if len(sys.argv) > 4:
        described = network.add_node(36, sys.argv[4])
        od = described.object_dictionary
        seen["eds_objects"] = len(od)
        seen["eds_p102_by_name"] = described.sdo["P102 Acceleration time"]["Set 1"].raw
        seen["eds_p102_type"] = od[0x2066][1].data_type
        # The node's heartbeat consumer (P120 watches FI 1, node 32) as the node and the EDS
        # give it.
        seen["consumer_read"] = described.sdo[0x1016][1].raw
        seen["consumer_eds"] = od[0x1016][1].default
finally:
    network.disconnect()
print(json.dumps(seen))
