"""python-canopen as a CANopen node of any maker: a LocalNode with the object dictionary of an
EDS joins the served system bus over socketcand (python-can's `socketcand` interface) at
NODE, and answers SDO requests with python-canopen's own SDO server until SECONDS have passed.
Prints `ready` once it is on the bus; `harness run --profile any --dut
socketcand://HOST:PORT/CHANNEL/NODE` then tests it.

Usage: canopen_node.py HOST PORT CHANNEL NODE EDS SECONDS
"""

import sys
import time

import canopen

host, port, channel = sys.argv[1], int(sys.argv[2]), sys.argv[3]
node_id, eds, seconds = int(sys.argv[4]), sys.argv[5], float(sys.argv[6])
network = canopen.Network()
network.connect(interface="socketcand", host=host, port=port, channel=channel)
try:
    node = canopen.LocalNode(node_id, eds)
    network.add_node(node)
    print("ready", flush=True)
    time.sleep(seconds)
finally:
    network.disconnect()
