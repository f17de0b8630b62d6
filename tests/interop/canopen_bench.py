"""python-canopen's SDO reads per second on the served NORD system bus, over socketcand
(python-can's `socketcand` interface): one operation is one complete SDO read of P102 set 1 of
FI 3 (node 36, 2066h:01h, expedited), the upload request sent and the answer with the value
received, as the harness's own figure counts it. Prints one JSON line: {"reads": N, "secs": S,
"us": [each read's time in µs]} or {"error": ...}; exits 3 when python-canopen cannot be
imported.

Usage: canopen_bench.py HOST PORT CHANNEL COUNT
"""

import json
import sys
import time

try:
    import canopen
except ImportError as e:
    print(e, file=sys.stderr)
    sys.exit(3)

host, port, channel, count = sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
network = canopen.Network()
try:
    network.connect(interface="socketcand", host=host, port=port, channel=channel)
    node = canopen.RemoteNode(36, canopen.ObjectDictionary())
    network.add_node(node)
    for _ in range(50):
        node.sdo.upload(0x2066, 1)
    each = []
    start = time.perf_counter()
    for _ in range(count):
        t = time.perf_counter()
        if len(node.sdo.upload(0x2066, 1)) != 2:
            raise ValueError("P102 is not 2 bytes")
        each.append(round((time.perf_counter() - t) * 1e6, 1))
    secs = time.perf_counter() - start
    print(json.dumps({"reads": count, "secs": secs, "us": each}))
except Exception as e:  # the bench reports any failure as its figure's error
    print(json.dumps({"error": f"{type(e).__name__}: {e}"}))
finally:
    network.disconnect()
