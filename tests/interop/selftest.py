#!/usr/bin/env python3
"""Self-test of the interop peers: cpppo's server against both client scripts, on loopback.

    "${INTEROP_VENV:-target/interop-venv}"/bin/python tests/interop/selftest.py [--timeout S]

Spawns cpppo_server.sh on a free port, runs pycomm3_client.py and cpppo_client.py against it,
checks their JSON lines, stops the server, and prints "N passed, N failed" (exit 1 on failure).
Bounded: every subprocess has a timeout, the server has a --lifetime.
"""

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
PRODUCT_NAME = "1756-L61/B LOGIX5561"  # cpppo's built-in identity (no config file)

results = []


def check(name, cond, detail=""):
    results.append(bool(cond))
    print(f"{'ok  ' if cond else 'FAIL'} {name}" + ("" if cond else f"  -- {detail}"))


def free_port():
    # Needs TCP and UDP free (cpppo binds both).
    for _ in range(50):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        try:
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as u:
                u.bind(("127.0.0.1", port))
            return port
        except OSError:
            continue
    raise RuntimeError("no free port")


def wait_accepting(proc, port, limit):
    end = time.monotonic() + limit
    while time.monotonic() < end:
        if proc.poll() is not None:
            return False
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.5):
                return True
        except OSError:
            time.sleep(0.1)
    return False


def run_client(name, port, timeout, *ops, extra=()):
    cmd = [sys.executable, os.path.join(HERE, f"{name}_client.py"), "--port", str(port),
           "--timeout", str(timeout), *extra, *ops]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    lines = [json.loads(l) for l in p.stdout.splitlines() if l.strip()]
    return p.returncode, lines, p.stderr


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--timeout", type=float, default=3.0)
    a = ap.parse_args()
    port = free_port()
    server = subprocess.Popen(
        [os.path.join(HERE, "cpppo_server.sh"), "--port", str(port), "--lifetime", "120"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True,
        env={**os.environ, "INTEROP_PYTHON": sys.executable})
    try:
        ready = wait_accepting(server, port, 20)
        check("cpppo server accepts on 127.0.0.1", ready)
        if not ready:
            return 1
        for i, client in enumerate(("pycomm3", "cpppo")):
            v16 = -1234 - i
            ops = ["get", "1", "1", "1",          # Identity vendor id
                   "get", "1", "1", "7",          # product name (SHORT_STRING)
                   "get", "1", "0", "1",          # instance 0: Identity class revision
                   "set", "0x64", "1", "102", str(v16),
                   "get", "0x64", "1", "102",
                   "get", "0x64", "1", "717",     # 16-bit attribute segment
                   "get", "1", "1", "99",         # unknown attribute
                   "get", "0x99", "1", "1",       # unknown class: cpppo drops the session
                   "get", "1", "1", "1",          # works again (reconnected)
                   "identity", "identity-object"]
            rc, out, err = run_client(client, port, a.timeout, *ops)
            check(f"{client}: exit 0 and one line per op", rc == 0 and len(out) == 11,
                  f"rc={rc} lines={len(out)} stderr={err[-300:]}")
            if len(out) != 11:
                continue
            g_vendor, g_name, g_inst0, s, g, g717, g_unk_attr, g_unk_cls, g_again, ident, ido = out
            check(f"{client}: get 1/1/1 vendor == 1", g_vendor["ok"] and g_vendor["value"] == 1, g_vendor)
            check(f"{client}: get 1/1/7 product name",
                  g_name["ok"] and g_name["raw"] == (bytes([len(PRODUCT_NAME)]) + PRODUCT_NAME.encode()).hex(), g_name)
            check(f"{client}: get 1/0/1 (instance 0)", g_inst0["ok"] and g_inst0["status"] == 0, g_inst0)
            check(f"{client}: set INT", s["ok"] and s["status"] == 0 and s["value"] == v16, s)
            check(f"{client}: get reads back the INT", g["ok"] and g["value"] == v16, g)
            check(f"{client}: get 16-bit attribute 717", g717["ok"] and g717["value"] == 0, g717)
            check(f"{client}: unknown attribute -> ok=false, general status 0x08",
                  not g_unk_attr["ok"] and g_unk_attr["status"] == 8 and g_unk_attr["error"], g_unk_attr)
            check(f"{client}: unknown class -> ok=false, no CIP status, encapsulation status 8",
                  not g_unk_cls["ok"] and g_unk_cls["status"] is None and g_unk_cls["encap_status"] == 8,
                  g_unk_cls)
            check(f"{client}: next op after the dropped session works", g_again["ok"], g_again)
            idn = ident.get("identity") or {}
            check(f"{client}: identity (ListIdentity)",
                  ident["ok"] and idn.get("vendor_id") == 1 and idn.get("product_name") == PRODUCT_NAME
                  and idn.get("revision") == "20.11", ident)
            ido_id = ido.get("identity") or {}
            same = all(ido_id.get(k) == idn.get(k) for k in
                       ("vendor_id", "device_type", "product_code", "revision", "serial", "product_name"))
            check(f"{client}: identity-object matches ListIdentity", ido["ok"] and same, ido)

            rc, out, err = run_client(client, port, a.timeout, "set", "0x64", "1", "1000", "-70000",
                                      "get", "0x64", "1", "1000", extra=("--dint",))
            check(f"{client}: --dint set/get", rc == 0 and len(out) == 2 and out[0]["ok"]
                  and out[1]["value"] == -70000, out)

        # Cross-client: what one wrote the other reads.
        run_client("pycomm3", port, a.timeout, "set", "0x65", "1", "102", "4242")
        rc, out, _ = run_client("cpppo", port, a.timeout, "get", "0x65", "1", "102")
        check("cross: pycomm3 writes, cpppo reads", out and out[0]["value"] == 4242, out)
    finally:
        try:
            os.killpg(server.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
        try:
            server.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(server.pid, signal.SIGKILL)
            server.wait(timeout=5)
    # A closed port: reported per op, exit 0, fast.
    t0 = time.monotonic()
    rc, out, _ = run_client("pycomm3", port, a.timeout, "get", "1", "1", "1", "identity")
    check("closed port: pycomm3 reports ok=false, exit 0",
          rc == 0 and len(out) == 2 and not any(o["ok"] for o in out) and time.monotonic() - t0 < 10, out)
    rc, out, _ = run_client("cpppo", port, a.timeout, "get", "1", "1", "1")
    check("closed port: cpppo reports ok=false, exit 0", rc == 0 and len(out) == 1 and not out[0]["ok"], out)

    failed = results.count(False)
    print(f"{len(results) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
