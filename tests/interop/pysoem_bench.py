#!/usr/bin/env python3
"""CoE SDO uploads per second of pysoem (SOEM), for harness/benches/ecat.

    python pysoem_bench.py IFACE [--count N] [--seconds S] [--index I] [--sub S]
                           [--timeout S] [--deadline S]

Opens IFACE (raw Ethernet: root or CAP_NET_RAW), finds the slaves with SOEM's config_init
(station addresses, SII, mailbox, PRE-OP), waits for PRE-OP, makes 50 warm-up uploads of the
first slave's INDEX:SUB (default 1018h:01h, the vendor id), then uploads it one after the
other, as fast as SOEM goes, until N have been answered or S seconds have passed. Prints one
JSON line:

    {"client": "pysoem 1.1.13", "count": N, "seconds": T, "error": null}

"error" names the first failed upload (the count stops there) or why nothing was measured.
Exit code 0 when the line was printed, 2 for usage errors, 3 if pysoem is not installed (run
.ci/interop-setup and use its venv's python). --deadline (default 60 s) ends the process
however far it got, should SOEM ever block.
"""

import argparse
import json
import os
import signal
import sys
import time

sys.dont_write_bytecode = True  # keep tests/interop free of __pycache__

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interop_common as ic  # noqa: E402

pysoem, CLIENT = ic.import_peer("pysoem")

WARM_UP = 50


def number(text):
    """Decimal, 0x-hex or h-suffixed hex (1018h)."""
    t = text.strip()
    if t.lower().endswith("h"):
        return int(t[:-1], 16)
    return int(t, 0)


def parse_args(argv):
    ap = argparse.ArgumentParser(description="pysoem SDO uploads per second.")
    ap.add_argument("iface")
    ap.add_argument("--count", type=int, default=1000, help="uploads at most (default 1000)")
    ap.add_argument("--seconds", type=float, default=2.0, help="time limit (default 2)")
    ap.add_argument("--index", type=number, default=0x1018, help="object (default 1018h)")
    ap.add_argument("--sub", type=number, default=1, help="sub-index (default 1)")
    ap.add_argument("--timeout", type=float, default=1.0, help="SDO timeout in seconds")
    ap.add_argument("--deadline", type=float, default=60.0, help="end the process after S s")
    a = ap.parse_args(argv)
    if a.count < 1 or a.seconds <= 0 or a.timeout <= 0 or a.deadline <= 0:
        ap.error("--count, --seconds, --timeout and --deadline must be positive")
    if not (0 <= a.index <= 0xFFFF and 0 <= a.sub <= 0xFF):
        ap.error("--index is 16 bits, --sub 8 bits")
    return a


def main(argv=None) -> int:
    a = parse_args(argv)
    # The default action of SIGALRM ends the process, also inside a C call of SOEM.
    signal.signal(signal.SIGALRM, signal.SIG_DFL)
    signal.setitimer(signal.ITIMER_REAL, a.deadline)
    out = {"client": CLIENT, "index": a.index, "subindex": a.sub, "count": 0, "seconds": 0.0,
           "error": None}
    if not os.path.exists(f"/sys/class/net/{a.iface}"):
        out["error"] = f"no network interface named {a.iface}"
        print(json.dumps(out), flush=True)
        return 0
    m = pysoem.Master()
    m.sdo_read_timeout = int(a.timeout * 1e6)
    try:
        m.open(a.iface)
    except Exception as e:
        out["error"] = f"open {a.iface}: {e} (raw Ethernet needs root or CAP_NET_RAW)"
        print(json.dumps(out), flush=True)
        return 0
    try:
        if m.config_init() <= 0:
            out["error"] = f"no slave found on {a.iface}"
        else:
            m.state_check(pysoem.PREOP_STATE, 3_000_000)
            slave = m.slaves[0]
            n, start = 0, None
            try:
                for _ in range(WARM_UP):
                    slave.sdo_read(a.index, a.sub)
                start = time.perf_counter()
                while n < a.count and time.perf_counter() - start < a.seconds:
                    slave.sdo_read(a.index, a.sub)
                    n += 1
            except Exception as e:
                out["error"] = f"upload {a.index:04X}h:{a.sub:02X}h: {type(e).__name__}: {e}"
            if start is not None:
                out["seconds"] = round(time.perf_counter() - start, 6)
            out["count"] = n
    finally:
        try:
            m.close()
        except Exception:
            pass
    print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
