#!/usr/bin/env python3
"""An independent PROFINET DCP client: the PyPI package pnio_dcp on a network interface.

    python pnio_dcp_peer.py IFACE_IP [--timeout S] [--deadline S] [--temporary] [--strict] [-v]
                            OP...

IFACE_IP is an IPv4 address of the interface to use (pnio_dcp finds the interface by its
address, through psutil); an interface name is accepted too and stands for its first IPv4
address. The interface needs one: pnio_dcp cannot be opened on an interface without. DCP itself
is raw Ethernet (EtherType 8892h on an AF_PACKET socket): root or CAP_NET_RAW.

Operations, run in order, one JSON line each on stdout:

  identify-all                 Identify All (multicast 01:0e:cf:00:00:00, ResponseDelay 128 as
                               pnio_dcp sends it); collects the answers for --timeout seconds
  identify MAC                 Identify All addressed to one MAC (unicast): the first answer
  get-name MAC                 Get NameOfStation (option 2/2)
  get-ip MAC                   Get IP parameter (option 1/2)
  set-name MAC NAME            Set NameOfStation (pnio_dcp checks NAME against
                               ^[a-z][a-zA-Z0-9.-]*$ and lower-cases it before sending: a name
                               it refuses is reported with "sent": false, nothing goes out)
  set-ip MAC IP MASK GATEWAY   Set IP parameter
  blink MAC                    Control/Signal (flash the LED)
  reset-to-factory MAC [MODE]  Control/ResetToFactory (5/6); MODE application, communication
                               (default), engineering, all, device, restore
  factory-reset MAC            Control/ResetFactorySettings (5/5)

Set operations store permanently (BlockQualifier 1) unless --temporary (0).

Every line has "op", "ok" and "elapsed_ms"; "error" says why when "ok" is false (a timeout
is "timeout"). Lines of identify-all/identify/get-*: "devices": [{name, mac, ip, netmask,
gateway, family} as pnio_dcp parsed them, plus vendor_id, device_id, device_role,
device_options, device_instance, alias_name, ip_block_info and "blocks" (every block: option,
suboption, info, data hex), which this script decodes from the same frame because pnio_dcp
drops them}]. Lines of set-*/blink/reset: "code" (the DCP BlockError of the device's Control
response, 0 = ok) and "message" (pnio_dcp's text for it).

Exit codes: 0 every operation ran and printed its line (refusals, timeouts and an interface
that cannot be opened included: then every line says so); 1 --strict and an operation was not
ok; 2 usage error; 3 pnio_dcp is not importable (use the interop venv: .ci/interop-setup).
--deadline (default 60 s) bounds the whole run: operations not finished by then are reported
with "error": "deadline".
"""

import argparse
import ipaddress
import json
import logging
import os
import signal
import socket
import struct
import sys
import time

sys.dont_write_bytecode = True  # keep tests/interop free of __pycache__

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interop_common as ic  # noqa: E402

pnio_dcp, LIBRARY = ic.import_peer("pnio_dcp")

ARITY = {
    "identify-all": 0, "identify": 1, "get-name": 1, "get-ip": 1, "set-name": 2, "set-ip": 4,
    "blink": 1, "reset-to-factory": (1, 2), "factory-reset": 1,
}
RESET_MODES = {
    "application": pnio_dcp.ResetFactoryModes.RESET_APPLICATION_DATA,
    "communication": pnio_dcp.ResetFactoryModes.RESET_COMMUNICATION,
    "engineering": pnio_dcp.ResetFactoryModes.RESET_ENGENEERING,
    "all": pnio_dcp.ResetFactoryModes.RESET_ALL_DATA,
    "device": pnio_dcp.ResetFactoryModes.RESET_DEVICE,
    "restore": pnio_dcp.ResetFactoryModes.RESET_AND_RESTORE,
}
ETHER_TYPE = 0x8892
IDENTIFY_RESPONSE = 0xFEFF
GET_SET = 0xFEFD
DEVICE_ROLES = {0x01: "io-device", 0x02: "io-controller", 0x04: "io-multidevice",
                0x08: "io-supervisor"}


class UsageError(Exception):
    pass


class Deadline(BaseException):
    """Raised from SIGALRM when --deadline is reached (a BaseException: no library's
    `except Exception` swallows it)."""


def _on_alarm(signum, frame):
    raise Deadline()


def emit(line):
    line.setdefault("peer", LIBRARY)
    sys.stdout.write(json.dumps(line) + "\n")
    sys.stdout.flush()
    return line


def mac_arg(text):
    t = text.strip().lower().replace("-", ":")
    parts = t.split(":")
    if len(parts) != 6 or not all(len(p) == 2 for p in parts):
        raise UsageError(f"not a MAC address like 02:00:00:00:00:01: {text!r}")
    try:
        bytes.fromhex("".join(parts))
    except ValueError:
        raise UsageError(f"not a MAC address: {text!r}") from None
    return t


def parse_ops(tokens):
    ops, i = [], 0
    while i < len(tokens):
        name = tokens[i]
        if name not in ARITY:
            raise UsageError(f"unknown operation {name!r} (known: {', '.join(ARITY)})")
        n = ARITY[name]
        lo, hi = (n, n) if isinstance(n, int) else n
        args = []
        for j in range(hi):
            k = i + 1 + j
            if k >= len(tokens) or (j >= lo and tokens[k] in ARITY):
                break
            args.append(tokens[k])
        if len(args) < lo:
            raise UsageError(f"{name} needs {lo} argument(s), got {len(args)}")
        if name not in ("identify-all",):
            args[0] = mac_arg(args[0])
        if name == "reset-to-factory" and len(args) > 1 and args[1] not in RESET_MODES:
            raise UsageError(f"reset mode {args[1]!r} is not one of {', '.join(RESET_MODES)}")
        if name == "set-ip":
            for a in args[1:]:
                try:
                    ipaddress.IPv4Address(a)
                except ValueError:
                    raise UsageError(f"set-ip: not an IPv4 address: {a!r}") from None
        ops.append((name, args))
        i += 1 + len(args)
    return ops


def iface_ip(text):
    """IFACE_IP as given, or the first IPv4 address of the interface named so (psutil is
    pnio_dcp's own dependency)."""
    try:
        ipaddress.IPv4Address(text)
        return text, None
    except ValueError:
        pass
    import psutil
    for addr in psutil.net_if_addrs().get(text, []):
        if addr.family == socket.AF_INET:
            return addr.address, text
    raise UsageError(f"{text!r} is neither an IPv4 address nor an interface with one")


# --- what pnio_dcp leaves out: the raw frames it received, decoded here -------------------------

class RecordingSocket:
    """Stands in for pnio_dcp's L2 socket: passes everything through and keeps the frames that
    recv() returned, so that the blocks pnio_dcp does not decode (DeviceID, DeviceRole, …) can
    be read from the same frame."""

    def __init__(self, inner):
        self.inner = inner
        self.frames = []

    def recv(self):
        data = self.inner.recv()
        if data is not None:
            self.frames.append(bytes(data))
        return data

    def send(self, data):
        return self.inner.send(data)

    def close(self):
        return self.inner.close()


def dcp_blocks(frame):
    """(frame id, xid, source MAC, [(option, suboption, block bytes after the length)]) of a
    DCP frame, or None when it is not one. Raises ValueError on a block running past the
    frame."""
    if len(frame) < 26 or struct.unpack_from(">H", frame, 12)[0] != ETHER_TYPE:
        return None
    off = 14
    frame_id = struct.unpack_from(">H", frame, off)[0]
    _service, _stype, xid, _delay, length = struct.unpack_from(">BBIHH", frame, off + 2)
    body = frame[off + 12: off + 12 + length]
    if len(body) != length:
        raise ValueError(f"DCPDataLength {length} but {len(body)} bytes follow")
    blocks, i = [], 0
    while i + 4 <= len(body):
        opt, sub, blen = struct.unpack_from(">BBH", body, i)
        data = body[i + 4: i + 4 + blen]
        if len(data) != blen:
            raise ValueError(f"block {opt}/{sub}: DCPBlockLength {blen} runs past the frame")
        blocks.append((opt, sub, data))
        i += 4 + blen + (blen & 1)
    src = ":".join(f"{b:02x}" for b in frame[6:12])
    return frame_id, xid, src, blocks


def decode_blocks(blocks):
    """The fields of a response's blocks (each starts with its 2-byte BlockInfo)."""
    out = {"blocks": []}
    for opt, sub, data in blocks:
        info = struct.unpack_from(">H", data, 0)[0] if len(data) >= 2 else None
        value = data[2:]
        out["blocks"].append({"option": opt, "suboption": sub, "info": info,
                              "data": value.hex()})
        if (opt, sub) == (2, 3) and len(value) >= 4:
            out["vendor_id"], out["device_id"] = struct.unpack_from(">HH", value, 0)
        elif (opt, sub) == (2, 4) and len(value) >= 1:
            out["device_role"] = value[0]
            out["device_role_names"] = [n for bit, n in DEVICE_ROLES.items() if value[0] & bit]
        elif (opt, sub) == (2, 5):
            out["device_options"] = [[value[k], value[k + 1]] for k in range(0, len(value) - 1, 2)]
        elif (opt, sub) == (2, 6):
            out["alias_name"] = value.decode("latin-1")
        elif (opt, sub) == (2, 7) and len(value) >= 2:
            out["device_instance"] = [value[0], value[1]]
        elif (opt, sub) == (2, 8) and len(value) >= 4:
            out["oem_vendor_id"], out["oem_device_id"] = struct.unpack_from(">HH", value, 0)
        elif (opt, sub) == (1, 2):
            out["ip_block_info"] = info
    return out


# --- the operations ---------------------------------------------------------------------------

class Peer:
    def __init__(self, args, ip):
        self.args = args
        self.ip = ip
        self.dcp = None
        self.open_error = None
        self.rec = None

    def open(self):
        try:
            self.dcp = pnio_dcp.DCP(self.ip)
        except ValueError as e:
            self.open_error = f"pnio_dcp: {e} (it needs an IPv4 address of the interface)"
            return
        except PermissionError as e:
            self.open_error = f"pnio_dcp: {e} (raw Ethernet needs root or CAP_NET_RAW)"
            return
        except OSError as e:
            self.open_error = f"pnio_dcp: {e}"
            return
        self.dcp.default_timeout = self.args.timeout
        self.dcp.identify_all_timeout = self.args.timeout
        # pnio_dcp wraps its socket as a name-mangled attribute; wrap it once more to keep the
        # frames, and shorten the 1 s receive timeout of its Linux socket so that an operation
        # ends close to --timeout instead of up to a second after.
        inner = getattr(self.dcp, "_DCP__socket", None)
        if inner is not None:
            try:
                inner.socket.settimeout(0.05)
            except AttributeError:
                pass
            self.rec = RecordingSocket(inner)
            self.dcp._DCP__socket = self.rec

    def xid(self):
        return getattr(self.dcp, "_DCP__xid", None)

    def device(self, dev):
        d = {"name": dev.name_of_station, "mac": dev.MAC, "ip": dev.IP, "netmask": dev.netmask,
             "gateway": dev.gateway, "family": dev.family}
        # The same device's frame, as received (the one of this transaction).
        if self.rec is not None:
            xid = self.xid()
            for frame in self.rec.frames:
                try:
                    parsed = dcp_blocks(frame)
                except (ValueError, struct.error) as e:
                    d["raw_error"] = str(e)
                    continue
                if parsed and parsed[1] == xid and parsed[2] == dev.MAC:
                    d.update(decode_blocks(parsed[3]))
                    d["frame_id"] = parsed[0]
                    break
        return d

    def run(self, name, args):
        if self.rec is not None:
            self.rec.frames.clear()
        line = {"op": name}
        if name == "identify-all":
            devices = [self.device(d) for d in self.dcp.identify_all(timeout=self.args.timeout)]
            line.update(devices=devices, count=len(devices), ok=bool(devices))
            if not devices:
                line["error"] = "no device answered"
            return line
        mac = args[0]
        line["mac"] = mac
        try:
            if name == "identify":
                line.update(devices=[self.device(self.dcp.identify(mac))], ok=True)
            elif name == "get-name":
                line.update(name=self.dcp.get_name_of_station(mac), ok=True)
            elif name == "get-ip":
                line.update(ip=self.dcp.get_ip_address(mac), ok=True)
            else:
                return self.set(name, args, line)
        except pnio_dcp.DcpTimeoutError:
            line.update(ok=False, error="timeout")
        return line

    def set(self, name, args, line):
        mac = args[0]
        permanent = not self.args.temporary
        try:
            if name == "set-name":
                line["name"] = args[1]
                r = self.dcp.set_name_of_station(mac, args[1], store_permanent=permanent)
            elif name == "set-ip":
                line.update(ip=args[1], netmask=args[2], gateway=args[3])
                r = self.dcp.set_ip_address(mac, args[1:4], store_permanent=permanent)
            elif name == "blink":
                r = self.dcp.blink(mac)
            elif name == "reset-to-factory":
                mode = args[1] if len(args) > 1 else "communication"
                line["mode"] = mode
                r = self.dcp.reset_to_factory(mac, RESET_MODES[mode])
            else:
                r = self.dcp.factory_reset(mac)
        except (ValueError, TypeError) as e:
            # pnio_dcp's own checks (name pattern, address octets): nothing was sent.
            line.update(ok=False, sent=False, error=f"refused by pnio_dcp before sending: {e}")
            return line
        except pnio_dcp.DcpTimeoutError:
            line.update(ok=False, error="timeout")
            return line
        if isinstance(r, pnio_dcp.ResponseCode):
            line["code"] = r.code
            try:
                line["message"] = r.get_message()
            except KeyError:
                line["message"] = f"Code {r.code:02d}: (unknown to pnio_dcp)"
            line["ok"] = r.code == 0
            if r.code != 0:
                line["error"] = line["message"]
        else:
            # pnio_dcp takes an answer whose first block is not Control (5) for a device.
            line.update(ok=False, error="the answer's first block is not a Control response",
                        answer=self.device(r) if isinstance(r, pnio_dcp.Device) else repr(r))
        return line


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 2)[2])
    p.add_argument("iface_ip", metavar="IFACE_IP")
    p.add_argument("ops", nargs="*", metavar="OP")
    p.add_argument("--timeout", type=float, default=2.0,
                   help="seconds to wait for answers, per operation (default 2)")
    p.add_argument("--deadline", type=float, default=60.0,
                   help="end the whole run after this many seconds (default 60)")
    p.add_argument("--temporary", action="store_true",
                   help="set-name/set-ip store temporarily (BlockQualifier 0), not permanently")
    p.add_argument("--strict", action="store_true", help="exit 1 when an operation is not ok")
    p.add_argument("-v", "--verbose", action="count", default=0,
                   help="pnio_dcp's logging on stderr")
    args = p.parse_intermixed_args(argv)
    try:
        ops = parse_ops(args.ops)
        if not ops:
            raise UsageError("no operation given")
        if args.timeout <= 0 or args.deadline <= 0:
            raise UsageError("--timeout and --deadline must be > 0")
        ip, iface = iface_ip(args.iface_ip)
    except UsageError as e:
        p.print_usage(sys.stderr)
        sys.stderr.write(f"pnio_dcp_peer.py: {e}\n")
        return 2
    level = logging.CRITICAL + 1 if args.verbose == 0 else logging.DEBUG
    logging.basicConfig(stream=sys.stderr, level=level)
    logging.getLogger("pnio_dcp").setLevel(level)

    signal.signal(signal.SIGALRM, _on_alarm)
    signal.setitimer(signal.ITIMER_REAL, args.deadline)
    peer = Peer(args, ip)
    all_ok = True
    expired = False
    try:
        try:
            peer.open()
        except Deadline:
            expired = True
        for name, op_args in ops:
            start = time.perf_counter()
            if expired:
                line = {"op": name, "ok": False, "error": "deadline"}
            elif peer.dcp is None:
                line = {"op": name, "ok": False, "error": peer.open_error or "deadline"}
            else:
                try:
                    line = peer.run(name, op_args)
                except Deadline:
                    expired = True
                    line = {"op": name, "ok": False, "error": "deadline"}
                except Exception as e:  # whatever pnio_dcp raised on a reply it could not take
                    line = {"op": name, "ok": False, "error": f"{type(e).__name__}: {e}"}
            line["iface_ip"] = ip
            if iface:
                line["iface"] = iface
            line["elapsed_ms"] = round((time.perf_counter() - start) * 1000, 3)
            emit(line)
            all_ok &= bool(line.get("ok"))
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        if peer.dcp is not None and peer.rec is not None:
            try:
                peer.rec.close()
            except Exception:
                pass
    return 1 if args.strict and not all_ok else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
