#!/usr/bin/env python3
"""Round trips per second of pycomm3's explicit messages, for harness/benches/enip.rs.

    python pycomm3_bench.py [--host H] [--port P] [--count N] [--seconds S] [--timeout S]
                            [--class C] [--instance I] [--attribute A]

Opens one CIPDriver session (TCP connect + RegisterSession), sends 50 warm-up requests, then
Get_Attribute_Single requests until N have been answered or S seconds have passed, each a
SendRRData/UCMM message exactly as pycomm3_client.py sends it (connected=False,
unconnected_send=False, route_path=False). Default: P102 of FI 1 (class 101, instance 0 = set 1,
attribute 102). Prints one JSON line:

    {"client": "pycomm3 1.2.16", "count": N, "seconds": T, "error": null}

"error" names the first failed request (the count stops there). Exit code 0 when the line was
printed, 2 for usage errors, 3 if pycomm3 is not installed (run .ci/interop-setup and use its
venv's python). Loopback targets only.
"""

import argparse
import json
import os
import sys
import time

sys.dont_write_bytecode = True  # keep tests/interop free of __pycache__
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interop_common as ic  # noqa: E402

try:
    import pycomm3
    from pycomm3 import CIPDriver
except ImportError as _e:  # pragma: no cover
    sys.stderr.write(f"pycomm3 is not importable ({_e}); run .ci/interop-setup and use "
                     f"${{INTEROP_VENV:-target/interop-venv}}/bin/python\n")
    sys.exit(3)

SVC_GET_ATTRIBUTE_SINGLE = 0x0E
WARM_UP = 50


def parse_args(argv):
    ap = argparse.ArgumentParser(description="pycomm3 Get_Attribute_Single round trips per second.")
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=ic.DEFAULT_PORT)
    ap.add_argument("--count", type=int, default=5000, help="requests at most (default 5000)")
    ap.add_argument("--seconds", type=float, default=2.0, help="time limit (default 2)")
    ap.add_argument("--timeout", type=float, default=2.0, help="socket timeout per request")
    ap.add_argument("--class", dest="cls", type=lambda s: int(s, 0), default=101)
    ap.add_argument("--instance", type=lambda s: int(s, 0), default=0)
    ap.add_argument("--attribute", type=lambda s: int(s, 0), default=102)
    a = ap.parse_args(argv)
    if not ic.is_loopback(a.host):
        ap.error(f"refusing non-loopback target {a.host!r}")
    if a.count < 1 or a.seconds <= 0 or a.attribute < 1:
        ap.error("--count, --seconds and --attribute must be positive")
    return a


def get(drv, a):
    """One Get_Attribute_Single; None when answered with success, else what went wrong."""
    tag = drv.generic_message(
        service=SVC_GET_ATTRIBUTE_SINGLE,
        class_code=a.cls,
        instance=a.instance,
        attribute=a.attribute,
        connected=False,          # UCMM: no Forward_Open
        unconnected_send=False,   # no 0x52 Unconnected_Send wrapper (the adapter is the target)
        route_path=False,         # no route path appended
        name="get",
    )
    return None if tag.error is None else str(tag.error)


def main(argv=None) -> int:
    a = parse_args(argv)
    out = {"client": f"pycomm3 {pycomm3.__version__}", "count": 0, "seconds": 0.0, "error": None}
    drv = CIPDriver(f"{a.host}:{a.port}")
    drv.socket_timeout = a.timeout
    try:
        if not drv.open():
            out["error"] = "RegisterSession failed"
        else:
            for _ in range(WARM_UP):
                out["error"] = get(drv, a)
                if out["error"]:
                    break
            if not out["error"]:
                n = 0
                start = time.perf_counter()
                deadline = start + a.seconds
                while n < a.count and time.perf_counter() < deadline:
                    out["error"] = get(drv, a)
                    if out["error"]:
                        break
                    n += 1
                out["seconds"] = time.perf_counter() - start
                out["count"] = n
    except Exception as e:  # connection refused, reset, timeout: report, don't trace back
        out["error"] = ic.describe_exc(e)
    finally:
        try:
            drv.close()
        except Exception:
            pass
    print(json.dumps(out), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
