#!/usr/bin/env python3
"""An independent PROFINET IO controller client built from scapy's PROFINET layers.

    python scapy_pnio_peer.py [--ip DEVICE_IP] [--port 34964] [--cm-port 34964] [--iface IFACE]
                              [--vendor-id N] [--device-id N] [--instance N]
                              [--submodule SLOT,SUBSLOT,MODULE_IDENT,SUBMODULE_IDENT,IN,OUT]...
                              [--timeout S] [--deadline S] [--dry-run] [--strict] [-v] OP...

Requests are built with scapy.contrib.pnio_rpc (ARBlockReq, IOCRBlockReq, AlarmCRBlockReq,
ExpectedSubmoduleBlockReq, IODWriteReq, IODReadReq, IODControlReq) on scapy.layers.dcerpc's
DceRpc4 (connectionless DCE/RPC, little-endian NDR), sent over UDP to DEVICE_IP:34964 from an
ordinary UDP socket (no privileges), and the replies are parsed with the same layers. The DCP
operations use scapy.contrib.pnio_dcp on a raw AF_PACKET socket on --iface (root or
CAP_NET_RAW).

Operations, run in order, one JSON line each on stdout:

  connect                       Connect (opnum 0): ARBlockReq, IOCRBlockReq input + output,
                                AlarmCRBlockReq, ExpectedSubmoduleBlockReq per slot, from the
                                --submodule list; parses ARBlockRes, IOCRBlockRes, AlarmCRBlockRes,
                                ModuleDiffBlock, ARServerBlock
  device-access                 Connect (opnum 0) of a DeviceAccess AR, as engineering tools
                                read records without I/O: the ARBlockReq alone, ARType 0006h
                                (IOSAR) with ARProperties_DeviceAccess 1; expects the ARBlockRes
                                alone. read/write/release then go in it
  prm-end                       Control (opnum 4) with IODControlReq PrmEnd
  appl-ready                    waits for the device's own ApplicationReady call (Control,
                                opnum 4, to this controller's UDP --cm-port, bound from the
                                start of the run when this operation is given), parses it with
                                scapy (IODControlReq) and answers it with the IODControlRes
                                scapy derives from it (get_response(), Done set). Without it a
                                device retries ApplicationReady and then gives the AR up. With
                                --iface, the device's input CR frames are then watched (scapy's
                                PNIORealTimeCyclicPDU) until one says DataStatus "run":
                                "input_run", "input_data_status", "input_frames"
  write INDEX SLOT SUBSLOT HEX  Write (opnum 3): IODWriteReq + the record data HEX
  read INDEX SLOT SUBSLOT [MAX] Read (opnum 2): IODReadReq asking for at most MAX bytes
                                (default --read-max)
  read-implicit INDEX SLOT SUBSLOT [MAX]
                                ReadImplicit (opnum 5): the same with a nil AR UUID (no AR)
  release                       Release (opnum 1) with the ReleaseBlockReq
  bench-read N INDEX SLOT SUBSLOT [HEX]
                                writes HEX to the record once (when given), then N reads back
                                to back, each request built and each reply parsed by scapy:
                                reads per second
  bench-access N INDEX SLOT SUBSLOT HEX
                                N parameter accesses: each writes the PKW order HEX to the
                                record, then reads the record until the answer carries the
                                order's value (PNIO status 0 with 8 bytes of the order's PNU
                                and IND, response label 1, 2, 4 or 5), a "Read Response (-)"
                                (DE80B500) read again: accesses per second, reads per access
  dcp-identify [NAME]           DCP Identify All (or by NameOfStation) on --iface, answers
                                collected for --timeout seconds
  dcp-set-name MAC NAME         DCP Set NameOfStation, sent as given (no name check: for the
                                device's refusals)
  dcp-set-ip MAC IP MASK GW     DCP Set IP parameter, sent as given

Numbers are decimal, 0x-hex or h-suffixed hex (0B02Fh). The operations after a successful
connect use its AR UUID and session key; write/read before any connect use --ar-uuid (default:
a random one the device does not know).

Every line has "op", "ok" and "elapsed_ms"; when "ok" is false, "error" says why: "timeout"
(no reply within --timeout), "deadline", "parse: …" (scapy could not place every byte of the
reply, or a length in it disagrees), "PNIO status …" (the device refused), "DCE/RPC reject …".
RPC lines carry "pnio_status" (8 hex digits ErrorCode ErrorDecode ErrorCode1 ErrorCode2, from
the NDR header) with "error_code", "error_decode", "error_code1", "error_code2" and
"status_text"; and "blocks" (each reply block: "type" hex, "name", and its fields). write:
"record_status" (the IODWriteResHeader's PNIO status); read: "data" (hex), "record_length".
See /work/brief/pnio-peers.md for every field.

--dry-run sends nothing: each RPC or DCP operation builds its request, writes scapy's hexdump of
it to stderr, parses it back with scapy and prints a line with "dry_run": true, "request_hex",
"request_len", "parsed_back" (the layers and blocks scapy found) and "roundtrip" (whether
rebuilding the parsed request gives the same bytes).

Exit codes: 0 every operation ran and printed its line (refusals, timeouts and parse errors
included); 1 --strict and an operation was not ok; 2 usage error (nothing is sent); 3 scapy is
not importable (use the interop venv: .ci/interop-setup). --deadline (default 60 s) bounds the
whole run: operations not finished by then are reported with "error": "deadline".
"""

import argparse
import ipaddress
import json
import logging
import os
import random
import signal
import socket
import struct
import sys
import time
import uuid

sys.dont_write_bytecode = True  # keep tests/interop free of __pycache__

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interop_common as ic  # noqa: E402

# scapy logs on import (routes, interfaces) and on every DCE/RPC payload it cannot place:
# stdout carries only JSON lines, and stderr only what -v asks for.
logging.getLogger("scapy").setLevel(logging.ERROR)
scapy, LIBRARY = ic.import_peer("scapy", "contrib.pnio", "contrib.pnio_dcp", "contrib.pnio_rpc")
from scapy.contrib import pnio_dcp as D  # noqa: E402
from scapy.contrib import pnio_rpc as R  # noqa: E402
from scapy.contrib.pnio import PNIORealTimeCyclicPDU, ProfinetIO  # noqa: E402
from scapy.layers.dcerpc import DceRpc4  # noqa: E402
from scapy.layers.l2 import Ether  # noqa: E402
from scapy.packet import Padding, Raw  # noqa: E402
from scapy.utils import hexdump  # noqa: E402

RPC_PORT = 34964  # 8894h, the PNIO-CM endpoint
OPNUM = {"connect": 0, "release": 1, "read": 2, "write": 3, "control": 4, "read-implicit": 5}
DEVICE_INTERFACE = uuid.UUID("dea00001-6c97-11d1-8271-00a02442df7d")
CONTROLLER_INTERFACE = uuid.UUID("dea00002-6c97-11d1-8271-00a02442df7d")
# The controller's own object UUID (CMInitiatorObjectUUID): the PNIO form
# DEA00000-6C97-11D1-8271-<instance><device id><vendor id>, here instance 1, ids 0.
INITIATOR_OBJECT = uuid.UUID("dea00000-6c97-11d1-8271-000100000000")
PTYPE = {0: "request", 1: "ping", 2: "response", 3: "fault", 4: "working", 5: "nocall",
         6: "reject", 7: "ack", 8: "cl_cancel", 9: "fack", 10: "cancel_ack"}
FLAG_FRAG = 0x04
FLAG_IDEMPOTENT = 0x20
ETHER_TYPE = 0x8892
DCP_MULTICAST = "01:0e:cf:00:00:00"

# IEC 61158-6-10 PNIO status: ErrorDecode 80h PNIORW / 81h PNIO; ErrorCode1 of PNIORW.
ERROR_DECODE = {0x80: "PNIORW", 0x81: "PNIO", 0x82: "manufacturer specific"}
PNIORW_CODE1 = {
    0xA0: "application: read error", 0xA1: "application: write error",
    0xA2: "application: module failure", 0xA7: "application: busy",
    0xA8: "application: version conflict", 0xA9: "application: feature not supported",
    0xB0: "access: invalid index", 0xB1: "access: write length error",
    0xB2: "access: invalid slot/subslot", 0xB3: "access: type conflict",
    0xB4: "access: invalid area/API", 0xB5: "access: state conflict",
    0xB6: "access: access denied", 0xB7: "access: invalid range",
    0xB8: "access: invalid parameter", 0xB9: "access: invalid type",
    0xBA: "access: backup", 0xC0: "resource: read constrain conflict",
    0xC1: "resource: write constrain conflict", 0xC2: "resource: resource busy",
    0xC3: "resource: resource unavailable",
}
ERROR_CODE = {0xDB: "Connect", 0xDC: "Release", 0xDD: "Control", 0xDE: "Read", 0xDF: "Write",
              0xCF: "RTA error", 0xDA: "AlarmAck"}


class UsageError(Exception):
    pass


class Deadline(BaseException):
    """Raised from SIGALRM when --deadline is reached (a BaseException: no library's
    `except Exception` swallows it)."""


class Timeout(Exception):
    pass


def _on_alarm(signum, frame):
    raise Deadline()


def emit(line):
    line.setdefault("peer", LIBRARY)
    sys.stdout.write(json.dumps(line, default=str) + "\n")
    sys.stdout.flush()
    return line


def number(text, what="number", lo=0, hi=0xFFFFFFFF):
    t = str(text).strip()
    try:
        v = int(t[:-1], 16) if t.lower().endswith("h") else int(t, 0)
    except ValueError:
        raise UsageError(f"{what}: not a number: {text!r}") from None
    if not lo <= v <= hi:
        raise UsageError(f"{what}: {v} out of range {lo}..{hi}")
    return v


def hex_bytes(text, what="data"):
    t = text.strip().replace(" ", "").replace(":", "")
    if t in ("", "-"):
        return b""
    try:
        return bytes.fromhex(t)
    except ValueError:
        raise UsageError(f"{what}: not hex bytes: {text!r}") from None


def mac_arg(text):
    t = text.strip().lower().replace("-", ":")
    parts = t.split(":")
    if len(parts) != 6 or not all(len(p) == 2 for p in parts):
        raise UsageError(f"not a MAC address like 02:00:00:00:00:01: {text!r}")
    hex_bytes("".join(parts), "MAC")
    return t


def status_fields(code):
    """The four bytes of a PNIO status (as a u32, ErrorCode in the high byte)."""
    ec, dec, c1, c2 = (code >> 24) & 0xFF, (code >> 16) & 0xFF, (code >> 8) & 0xFF, code & 0xFF
    if code == 0:
        text = "OK"
    else:
        parts = [ERROR_CODE.get(ec, f"ErrorCode {ec:02X}h"),
                 ERROR_DECODE.get(dec, f"ErrorDecode {dec:02X}h")]
        if dec == 0x80:
            parts.append(PNIORW_CODE1.get(c1, f"ErrorCode1 {c1:02X}h"))
        else:
            parts.append(f"ErrorCode1 {c1:02X}h")
        parts.append(f"ErrorCode2 {c2:02X}h")
        text = ", ".join(parts)
    return {"pnio_status": f"{code:08X}", "error_code": ec, "error_decode": dec,
            "error_code1": c1, "error_code2": c2, "status_text": text}


# --- the submodule layout ---------------------------------------------------------------------

class Submodule:
    def __init__(self, spec):
        parts = [p for p in spec.replace(";", ",").split(",")]
        if len(parts) != 6:
            raise UsageError(f"--submodule {spec!r}: want SLOT,SUBSLOT,MODULE_IDENT,"
                             "SUBMODULE_IDENT,IN,OUT")
        self.slot = number(parts[0], "slot", 0, 0x7FFF)
        self.subslot = number(parts[1], "subslot", 0, 0xFFFF)
        self.module_ident = number(parts[2], "module ident number")
        self.ident = number(parts[3], "submodule ident number")
        self.inp = number(parts[4], "input bytes", 0, 1440)
        self.out = number(parts[5], "output bytes", 0, 1440)

    @property
    def kind(self):
        """SubmoduleProperties.Type: 0 NO_IO, 1 INPUT, 2 OUTPUT, 3 INPUT_OUTPUT."""
        return (1 if self.inp else 0) | (2 if self.out else 0)

    def in_input_cr(self):
        """Carries data (and its IOPS) in the input CR: inputs, and a NO_IO submodule, which
        IEC 61158-6-10 places there with 0 bytes."""
        return self.kind in (0, 1, 3)


def iocr_layout(subs, input_cr):
    """IODataObjects and IOCS entries of one IOCR, frame offsets assigned in order (each data
    object: its bytes + 1 IOPS; each IOCS: 1 byte), and the C_SDU length (at least 40)."""
    data, iocs, off = [], [], 0
    for s in subs:
        has_data = s.in_input_cr() if input_cr else bool(s.out)
        if has_data:
            data.append((s, off))
            off += (s.inp if input_cr else s.out) + 1
    for s in subs:
        consumer = bool(s.out) if input_cr else s.in_input_cr()
        if consumer:
            iocs.append((s, off))
            off += 1
    return data, iocs, max(40, off)


# --- describing what scapy parsed -------------------------------------------------------------

def fields_of(pkt, names):
    out = {}
    for n in names:
        v = pkt.getfieldval(n)
        if isinstance(v, uuid.UUID):
            v = str(v)
        elif isinstance(v, bytes):
            v = v.hex()
        out[n] = v
    return out


def decode_module_diff(body):
    """ModuleDiffBlock body (after the version bytes), which scapy 2.8.0 has no class for
    (it parses it as a generic Block with a raw load)."""
    apis, off = [], 0

    def take(fmt):
        nonlocal off
        vals = struct.unpack_from(">" + fmt, body, off)
        off += struct.calcsize(">" + fmt)
        return vals

    (n_api,) = take("H")
    for _ in range(n_api):
        api, n_mod = take("IH")
        mods = []
        for _ in range(n_mod):
            slot, mident, mstate, n_sub = take("HIHH")
            subs = []
            for _ in range(n_sub):
                subslot, sident, sstate = take("HIH")
                subs.append({"subslot": subslot, "submodule_ident": sident,
                             "submodule_state": sstate,
                             "ident_info": (sstate >> 11) & 0xF, "ar_info": (sstate >> 7) & 0xF})
            mods.append({"slot": slot, "module_ident": mident, "module_state": mstate,
                         "submodules": subs})
        apis.append({"api": api, "modules": mods})
    if off != len(body):
        raise ValueError(f"ModuleDiffBlock: {len(body) - off} bytes after its last field")
    return apis


def decode_ar_server(body):
    """ARServerBlock body (scapy has no class): StationNameLength, name, padding."""
    (n,) = struct.unpack_from(">H", body, 0)
    name = body[2:2 + n]
    if len(name) != n:
        raise ValueError("ARServerBlock: station name runs past the block")
    return name.decode("latin-1")


BLOCK_FIELDS = {
    R.ARBlockRes: ["ARType", "ARUUID", "SessionKey", "CMResponderMacAdd",
                   "CMResponderUDPRTPort"],
    R.IOCRBlockRes: ["IOCRType", "IOCRReference", "FrameID"],
    R.AlarmCRBlockRes: ["AlarmCRType", "LocalAlarmReference", "MaxAlarmDataLength"],
    R.IODControlRes: ["ARUUID", "SessionKey", "AlarmSequenceNumber",
                      "ControlCommand_PrmBegin", "ControlCommand_Done",
                      "ControlCommand_Release", "ControlCommand_ApplicationReady",
                      "ControlCommand_PrmEnd", "ControlBlockProperties"],
    R.IODWriteRes: ["seqNum", "ARUUID", "API", "slotNumber", "subslotNumber", "index",
                    "recordDataLength", "additionalValue1", "additionalValue2", "status"],
    R.IODReadRes: ["seqNum", "ARUUID", "API", "slotNumber", "subslotNumber", "index",
                   "recordDataLength", "additionalValue1", "additionalValue2"],
}


def describe_block(b, issues):
    """One parsed block as a dict; what does not add up goes to `issues`."""
    if isinstance(b, (Raw, Padding)):
        issues.append(f"{len(bytes(b))} bytes scapy could not take as a block")
        return {"type": None, "name": "raw", "data": bytes(b).hex()}
    btype = b.getfieldval("block_type")
    d = {"type": f"{btype:04X}" if isinstance(btype, int) else btype,
         "name": R.BLOCK_TYPES_ENUM.get(btype, "unknown"),
         "class": type(b).__name__, "length": b.getfieldval("block_length"),
         "version": [b.getfieldval("block_version_high"), b.getfieldval("block_version_low")]}
    if d["version"] != [1, 0]:
        issues.append(f"block {d['type']}: version {d['version'][0]}.{d['version'][1]}")
    names = BLOCK_FIELDS.get(type(b))
    if names:
        d["fields"] = fields_of(b, names)
        if "status" in d["fields"]:  # a PNIO status inside a block: big-endian, as hex
            d["fields"]["status"] = f"{d['fields']['status']:08X}"
    elif type(b) is R.Block:
        body = bytes(b.getfieldval("load") or b"")
        if len(body) + 2 != (b.getfieldval("block_length") or 0):
            issues.append(f"block {d['type']}: BlockLength {b.block_length} runs past the data")
        try:
            if btype == 0x8104:
                d["module_diff"] = decode_module_diff(body)
            elif btype == 0x8106:
                d["station_name"] = decode_ar_server(body)
            else:
                d["data"] = body.hex()
        except (ValueError, struct.error) as e:
            issues.append(f"block {d['type']}: {e}")
    # (An IODReadResHeader parsed on its own has the record data after it: read_reply checks
    # its length.)
    if b.payload and bytes(b.payload) and not isinstance(b, R.IODReadRes):
        issues.append(f"block {d['type']}: {len(bytes(b.payload))} bytes after it inside its "
                      "own parse")
    return d


# --- the controller ---------------------------------------------------------------------------

class Controller:
    def __init__(self, a):
        self.a = a
        self.object = uuid.UUID(
            f"dea00000-6c97-11d1-8271-{a.instance:04x}{a.device_id:04x}{a.vendor_id:04x}")
        self.activity = uuid.uuid4()
        self.seq = 0
        self.boot = 0
        self.ar_uuid = uuid.UUID(a.ar_uuid) if a.ar_uuid else uuid.uuid4()
        self.session_key = a.session_key
        self.record_seq = 0
        self.sock = None
        self.mac = a.mac
        self.dcp_sock = None
        self.dcp_mac = None
        self.connected = False
        self.cm_sock = None
        self.input_frame_id = None

    # -- transport ------------------------------------------------------------------------------
    def udp(self):
        if self.sock is None:
            self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self.sock.bind(("", 0))
        return self.sock

    def local_mac(self):
        """CMInitiatorMacAdd: --mac, else the MAC of the interface the device's address is
        routed through (00:00:00:00:00:00 on loopback)."""
        if self.mac:
            return self.mac
        iface = self.a.iface
        if not iface and self.a.ip:
            try:
                from scapy.config import conf
                iface = conf.route.route(self.a.ip)[0]
                iface = getattr(iface, "name", iface)
            except Exception:
                iface = None
        mac = "00:00:00:00:00:00"
        if iface:
            try:
                with open(f"/sys/class/net/{iface}/address") as f:
                    mac = f.read().strip() or mac
            except OSError:
                pass
        self.mac = mac
        return mac

    def rpc_packet(self, opnum, blocks):
        args_max = self.a.args_max
        pdu = R.PNIOServiceReqPDU(args_max=args_max, max_count=args_max, blocks=blocks)
        return DceRpc4(ptype=0, flags1=FLAG_IDEMPOTENT, object=self.object, if_id=DEVICE_INTERFACE,
                       act_id=self.activity, server_boot=self.boot, if_vers=1, seqnum=self.seq,
                       opnum=opnum) / pdu

    def call(self, opnum, blocks, line):
        """Sends one request and returns the raw reply of this activity and sequence number
        (a 'working' answer is waited past); raises Timeout."""
        pkt = self.rpc_packet(opnum, blocks)
        data = bytes(pkt)
        seq = self.seq
        self.seq += 1
        line["request_len"] = len(data)
        if self.a.dry_run:
            return self.dry(pkt, data, line)
        s = self.udp()
        s.sendto(data, (self.a.ip, self.a.port))
        end = time.monotonic() + self.a.timeout
        ignored = 0
        while True:
            left = end - time.monotonic()
            if left <= 0:
                if ignored:
                    line["ignored_datagrams"] = ignored
                raise Timeout()
            s.settimeout(left)
            try:
                raw, _src = s.recvfrom(65535)
            except socket.timeout:
                continue
            except ConnectionRefusedError:
                # ICMP port unreachable (reported on some stacks): wait out the timeout all
                # the same (a device may still be starting).
                time.sleep(min(0.05, max(0.0, end - time.monotonic())))
                continue
            # The answer of this call: same activity, same sequence number (scapy parses the
            # header; a datagram it cannot read as DCE/RPC is skipped).
            try:
                hdr = DceRpc4(raw)
                mine = hdr.act_id == self.activity and hdr.seqnum == seq
            except Exception:
                mine = False
            if not mine or hdr.ptype == 4:  # another call's, or "working"
                ignored += 1
                continue
            if ignored:
                line["ignored_datagrams"] = ignored
            return raw

    def dry(self, pkt, data, line):
        sys.stderr.write(f"--- {line['op']}: {len(data)} bytes to UDP {RPC_PORT}\n")
        sys.stderr.write(hexdump(data, dump=True) + "\n")
        back = DceRpc4(data)
        pdu = back.getlayer(R.PNIOServiceReqPDU)
        line.update(dry_run=True, request_hex=data.hex(), roundtrip=bytes(back) == data)
        parsed = {"layers": [l.__name__ for l in back.layers()]}
        if pdu is not None:
            parsed["args_length"] = pdu.args_length
            parsed["blocks"] = [{"type": f"{b.block_type:04X}",
                                 "name": R.BLOCK_TYPES_ENUM.get(b.block_type, "unknown"),
                                 "class": type(b).__name__, "length": b.block_length}
                                for b in pdu.blocks if hasattr(b, "block_type")]
        line["parsed_back"] = parsed
        line["ok"] = pdu is not None and line["roundtrip"]
        if not line["ok"]:
            line["error"] = "scapy does not parse its own request back to the same bytes"
        return None

    # -- reply analysis -------------------------------------------------------------------------
    def reply(self, raw, line):
        """Parses a reply with scapy; fills `line`; returns (PNIOServiceResPDU, NDR args bytes)
        or None when the line is already final."""
        line["reply_len"] = len(raw)
        try:
            pkt = DceRpc4(raw)
        except Exception as e:
            line.update(ok=False, error=f"parse: scapy: {type(e).__name__}: {e}",
                        reply_hex=raw.hex())
            return None
        line["rpc_ptype"] = PTYPE.get(pkt.ptype, pkt.ptype)
        if self.boot == 0 and pkt.server_boot:
            self.boot = pkt.server_boot
        body = bytes(pkt.payload)
        if pkt.ptype in (3, 6):  # fault, reject: one u32 status in the drep's order
            fmt = "<I" if pkt.endian == 1 else ">I"
            st = struct.unpack_from(fmt, body, 0)[0] if len(body) >= 4 else None
            line.update(ok=False, nca_status=None if st is None else f"{st:08X}",
                        error=f"DCE/RPC {PTYPE[pkt.ptype]}"
                        + ("" if st is None else f" {st:08X}"))
            return None
        if pkt.ptype != 2:
            line.update(ok=False, error=f"DCE/RPC {PTYPE.get(pkt.ptype, pkt.ptype)}, not a response")
            return None
        issues = []
        if pkt.flags1 & FLAG_FRAG:
            issues.append("fragmented reply (this client takes single-fragment replies only)")
        if pkt.len != len(body):
            issues.append(f"DCE/RPC length {pkt.len} but {len(body)} bytes follow the header")
        if pkt.object != self.object:
            issues.append(f"object UUID {pkt.object} is not the request's {self.object}")
        res = pkt.getlayer(R.PNIOServiceResPDU)
        if res is None:
            line.update(ok=False, error="parse: scapy found no PNIO response PDU in the reply "
                        f"(its object UUID must start dea00000-6c97-11d1-8271-): {body.hex()}")
            return None
        line.update(status_fields(res.status))
        n = res.args_length
        args = body[20:]
        if len(body) < 20:
            issues.append(f"NDR header cut: {len(body)} bytes")
        if len(args) != n:
            issues.append(f"ArgsLength {n} but {len(args)} bytes of NDR data follow")
        if res.actual_count != n or res.offset != 0:
            issues.append(f"NDR ActualCount {res.actual_count} / Offset {res.offset} vs "
                          f"ArgsLength {n}")
        if res.max_count < n:
            issues.append(f"NDR MaximumCount {res.max_count} < ArgsLength {n}")
        if n > self.a.args_max:
            issues.append(f"ArgsLength {n} exceeds the request's ArgsMaximum {self.a.args_max}")
        line["_issues"] = issues
        return res, args[:n]

    def finish(self, line, extra_ok=True):
        issues = line.pop("_issues", [])
        if issues:
            line["parse_issues"] = issues
        status_ok = line.get("pnio_status") == "00000000"
        line["ok"] = bool(status_ok and not issues and extra_ok)
        if not line["ok"] and "error" not in line:
            if issues:
                line["error"] = "parse: " + "; ".join(issues)
            elif not status_ok:
                line["error"] = f"PNIO status {line.get('pnio_status')} ({line.get('status_text')})"
            else:
                line["error"] = line.pop("_why", "unexpected reply")
        line.pop("_why", None)
        return line

    def answer_blocks(self, opnum, blocks, line):
        """Sends the call and parses the answer's blocks; None when there was none to parse
        (the line then says why)."""
        raw = self.call(opnum, blocks, line)
        if raw is None:
            return None
        r = self.reply(raw, line)
        if r is None:
            return None
        res, _args = r
        return self.blocks_of(res, line)

    def blocks_of(self, res, line):
        issues = line["_issues"]
        out = [describe_block(b, issues) for b in res.blocks]
        line["blocks"] = out
        return out

    # -- operations -----------------------------------------------------------------------------
    def connect(self, line):
        subs = self.a.submodules
        a = self.a
        apis = lambda data, iocs: [R.IOCRAPI(  # noqa: E731
            API=0,
            IODataObjects=[R.IOCRAPIObject(SlotNumber=s.slot, SubslotNumber=s.subslot,
                                           FrameOffset=o) for s, o in data],
            IOCSs=[R.IOCRAPIObject(SlotNumber=s.slot, SubslotNumber=s.subslot, FrameOffset=o)
                   for s, o in iocs])]
        in_data, in_iocs, in_len = iocr_layout(subs, True)
        out_data, out_iocs, out_len = iocr_layout(subs, False)
        common = dict(LT=ETHER_TYPE, IOCRProperties_RTClass=1,
                      SendClockFactor=a.send_clock_factor, ReductionRatio=a.reduction_ratio,
                      Phase=1, Sequence=0, FrameSendOffset=0xFFFFFFFF,
                      WatchdogFactor=a.watchdog_factor, DataHoldFactor=a.data_hold_factor,
                      IOCRTagHeader_IOUserPriority=6, IOCRMulticastMACAdd="00:00:00:00:00:00")
        blocks = [
            R.ARBlockReq(ARType=1, ARUUID=self.ar_uuid, SessionKey=self.session_key,
                         CMInitiatorMacAdd=self.local_mac(),
                         CMInitiatorObjectUUID=INITIATOR_OBJECT,
                         ARProperties_State=1, ARProperties_ParametrizationServer=1,
                         ARProperties_StartupMode=1 if a.startup == "advanced" else 0,
                         CMInitiatorActivityTimeoutFactor=a.activity_timeout,
                         CMInitiatorUDPRTPort=ETHER_TYPE,
                         CMInitiatorStationName=a.controller_name.encode("latin-1")),
            R.IOCRBlockReq(IOCRType=1, IOCRReference=1, DataLength=in_len,
                           FrameID=a.input_frame_id, APIs=apis(in_data, in_iocs), **common),
            R.IOCRBlockReq(IOCRType=2, IOCRReference=2, DataLength=out_len,
                           FrameID=a.output_frame_id, APIs=apis(out_data, out_iocs), **common),
            R.AlarmCRBlockReq(AlarmCRType=1, LT=ETHER_TYPE, RTATimeoutFactor=1, RTARetries=3,
                              LocalAlarmReference=1, MaxAlarmDataLength=200),
        ]
        slots = []
        for s in subs:
            if s.slot not in slots:
                slots.append(s.slot)
        for slot in slots:
            mine = [s for s in subs if s.slot == slot]
            expected = []
            for s in mine:
                dd = []
                if s.kind in (0, 1, 3):
                    dd.append(R.ExpectedSubmoduleDataDescription(
                        DataDescription=1, SubmoduleDataLength=s.inp, LengthIOCS=1, LengthIOPS=1))
                if s.kind in (2, 3):
                    dd.append(R.ExpectedSubmoduleDataDescription(
                        DataDescription=2, SubmoduleDataLength=s.out, LengthIOCS=1, LengthIOPS=1))
                expected.append(R.ExpectedSubmodule(SubslotNumber=s.subslot,
                                                    SubmoduleIdentNumber=s.ident,
                                                    SubmoduleProperties_Type=s.kind,
                                                    DataDescription=dd))
            blocks.append(R.ExpectedSubmoduleBlockReq(APIs=[R.ExpectedSubmoduleAPI(
                API=0, SlotNumber=slot, ModuleIdentNumber=mine[0].module_ident,
                ModuleProperties=0, Submodules=expected)]))
        line.update(ar_uuid=str(self.ar_uuid), session_key=self.session_key,
                    object_uuid=str(self.object), initiator_mac=self.local_mac(),
                    input_length=in_len, output_length=out_len)
        got = self.answer_blocks(OPNUM["connect"], blocks, line)
        if got is None:
            return line
        issues = line["_issues"]
        by = {}
        for b in got:
            by.setdefault(b["type"], []).append(b)
        line["module_diff"] = [m for b in by.get("8104", []) for m in b.get("module_diff", [])]
        if line.get("pnio_status") == "00000000":
            ar = by.get("8101")
            if not ar:
                issues.append("no ARBlockRes in the reply")
            else:
                f = ar[0]["fields"]
                line["responder_mac"] = f["CMResponderMacAdd"]
                line["responder_udp_rt_port"] = f["CMResponderUDPRTPort"]
                if f["ARUUID"] != str(self.ar_uuid) or f["SessionKey"] != self.session_key:
                    issues.append("ARBlockRes names another AR UUID or session key")
            iocrs = by.get("8102", [])
            line["frame_ids"] = {("input" if b["fields"]["IOCRType"] == 1 else "output"):
                                 b["fields"]["FrameID"] for b in iocrs}
            if sorted(b["fields"]["IOCRType"] for b in iocrs) != [1, 2]:
                issues.append(f"IOCRBlockRes for {len(iocrs)} IOCRs, not input + output")
            if not by.get("8103"):
                issues.append("no AlarmCRBlockRes in the reply")
        self.finish(line)
        if line["ok"]:
            self.connected = True
            self.input_frame_id = line["frame_ids"].get("input")
        return line

    def device_access(self, line):
        a = self.a
        block = R.ARBlockReq(ARType=6, ARUUID=self.ar_uuid, SessionKey=self.session_key,
                             CMInitiatorMacAdd=self.local_mac(),
                             CMInitiatorObjectUUID=INITIATOR_OBJECT,
                             ARProperties_State=1, ARProperties_DeviceAccess=1,
                             CMInitiatorActivityTimeoutFactor=a.activity_timeout,
                             CMInitiatorUDPRTPort=ETHER_TYPE,
                             CMInitiatorStationName=a.controller_name.encode("latin-1"))
        line.update(ar_uuid=str(self.ar_uuid), session_key=self.session_key)
        got = self.answer_blocks(OPNUM["connect"], [block], line)
        if got is None:
            return line
        line["block_types"] = [b["type"] for b in got]
        if line.get("pnio_status") == "00000000":
            if line["block_types"] != ["8101"]:
                line["_issues"].append(f"blocks {line['block_types']}, not the ARBlockRes alone")
            elif got[0]["fields"]["ARType"] != 6:
                line["_issues"].append("the ARBlockRes names another ARType")
        self.finish(line)
        if line["ok"]:
            self.connected = True
        return line

    def record_header(self, cls, index, slot, subslot, length, ar=None):
        self.record_seq += 1
        return cls(seqNum=self.record_seq - 1, ARUUID=self.ar_uuid if ar is None else ar, API=0,
                   slotNumber=slot, subslotNumber=subslot, index=index,
                   recordDataLength=length)

    def write(self, line, index, slot, subslot, data):
        line.update(index=index, slot=slot, subslot=subslot, length=len(data))
        req = self.record_header(R.IODWriteReq, index, slot, subslot, len(data)) / Raw(data)
        got = self.answer_blocks(OPNUM["write"], [req], line)
        if got is None:
            return line
        hdr = [b for b in got if b["type"] == "8008"]
        ok = True
        if hdr:
            st = hdr[0]["fields"]["status"]
            line["record_status"] = st
            ok = st == "00000000"
            if not ok and line.get("pnio_status") == "00000000":
                line["_why"] = f"IODWriteResHeader status {st}"
        elif line.get("pnio_status") == "00000000":
            line["_issues"].append("no IODWriteResHeader in the reply")
        return self.finish(line, ok)

    def read(self, line, index, slot, subslot, maxlen, implicit=False):
        line.update(index=index, slot=slot, subslot=subslot, max_length=maxlen)
        nil = uuid.UUID(int=0)
        req = self.record_header(R.IODReadReq, index, slot, subslot, maxlen,
                                 ar=nil if implicit else None)
        raw = self.call(OPNUM["read-implicit" if implicit else "read"], [req], line)
        if raw is None:
            return line
        return self.read_reply(raw, line)

    def read_reply(self, raw, line):
        r = self.reply(raw, line)
        if r is None:
            return line
        _res, args = r
        issues = line["_issues"]
        # scapy 2.8.0's IODReadRes leaves the record data outside the block, and inside the
        # NDR block list it takes those bytes for a further block: the header is parsed on its
        # own here, and the record data is what follows it.
        if len(args) >= 64:
            try:
                hdr = R.IODReadRes(args)
            except Exception as e:
                issues.append(f"IODReadRes: scapy: {type(e).__name__}: {e}")
                return self.finish(line)
            d = describe_block(hdr, issues)
            line["blocks"] = [d]
            n = hdr.recordDataLength
            data = args[4 + hdr.block_length:]
            line["record_length"] = n
            if hdr.block_type != 0x8009:
                issues.append(f"first block {hdr.block_type:04X} is not IODReadResHeader")
            if len(data) != n:
                issues.append(f"RecordDataLength {n} but {len(data)} bytes follow the header")
            line["data"] = data[:n].hex()
        elif args:
            issues.append(f"{len(args)} bytes of NDR data, too short for an IODReadResHeader")
        elif line.get("pnio_status") == "00000000":
            issues.append("no IODReadResHeader in the reply")
        return self.finish(line)

    def control(self, line, release=False):
        req = R.IODControlReq(ARUUID=self.ar_uuid, SessionKey=self.session_key,
                              ControlCommand_PrmEnd=0 if release else 1,
                              ControlCommand_Release=1 if release else 0)
        line.update(ar_uuid=str(self.ar_uuid))
        got = self.answer_blocks(OPNUM["release" if release else "control"], [req], line)
        if got is None:
            return line
        want = "8114" if release else "8110"
        ok = True
        if line.get("pnio_status") == "00000000":
            if not any(b["type"] == want for b in got):
                line["_issues"].append(f"no {want} block in the reply")
            else:
                f = [b for b in got if b["type"] == want][0]["fields"]
                ok = f["ControlCommand_Done"] == 1
                if not ok:
                    line["_why"] = "ControlCommand Done not set"
        self.finish(line, ok)
        if release and line["ok"]:
            self.connected = False
        return line

    # -- the device's own call: ApplicationReady -------------------------------------------------
    def cm_open(self):
        """The controller's RPC endpoint (UDP --cm-port), where the device calls
        ApplicationReady."""
        if self.cm_sock is None and not self.a.dry_run:
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            s.bind(("", self.a.cm_port))
            self.cm_sock = s
        return self.cm_sock

    def appl_ready(self, line):
        """Waits for the device's ApplicationReady request, parses it with scapy and answers it
        with IODControlReq.get_response() (ControlCommand Done) in a DCE/RPC response of the
        same activity and sequence number."""
        line.update(ar_uuid=str(self.ar_uuid), cm_port=self.a.cm_port)
        if self.a.dry_run:
            req = R.IODControlReq(ARUUID=self.ar_uuid, SessionKey=self.session_key,
                                  ControlCommand_ApplicationReady=1)
            res = req.__class__(bytes(req)).get_response()
            line.update(dry_run=True, request_block=bytes(req)[:2].hex(),
                        response_hex=bytes(res).hex(), ok=True)
            return line
        s = self.cm_open()
        end = time.monotonic() + self.a.timeout
        ignored = []
        while True:
            left = end - time.monotonic()
            if left <= 0:
                if ignored:
                    line["ignored_datagrams"] = ignored
                raise Timeout()
            s.settimeout(left)
            try:
                raw, src = s.recvfrom(65535)
            except socket.timeout:
                continue
            try:
                pkt = DceRpc4(raw)
            except Exception as e:
                ignored.append(f"not DCE/RPC ({type(e).__name__}: {e}): {raw.hex()}")
                continue
            req = pkt.getlayer(R.PNIOServiceReqPDU)
            if pkt.ptype != 0 or req is None:
                ignored.append(f"ptype {pkt.ptype}, no PNIO request PDU: {raw.hex()}")
                continue
            break
        if ignored:
            line["ignored_datagrams"] = ignored
        issues = []
        line.update(request_from=f"{src[0]}:{src[1]}", request_len=len(raw),
                    rpc_opnum=pkt.opnum, rpc_object=str(pkt.object), rpc_if_id=str(pkt.if_id),
                    rpc_endian=pkt.endian)
        if pkt.len != len(bytes(pkt.payload)):
            issues.append(f"DCE/RPC length {pkt.len} but {len(bytes(pkt.payload))} bytes follow")
        if req.args_length != len(bytes(pkt.payload)) - 20:
            issues.append(f"ArgsLength {req.args_length} but "
                          f"{len(bytes(pkt.payload)) - 20} bytes of NDR data follow")
        got = [describe_block(b, issues) for b in req.blocks]
        line["blocks"] = got
        ctrl = [b for b in req.blocks if isinstance(b, R.IODControlReq)]
        if not ctrl:
            issues.append("no IODControlReq in the request")
            line.update(ok=False, error="parse: " + "; ".join(issues), request_hex=raw.hex())
            return line
        c = ctrl[0]
        line.update(block_type=f"{c.block_type:04X}",
                    request_ar_uuid=str(c.ARUUID), request_session_key=c.SessionKey,
                    control_command_application_ready=c.ControlCommand_ApplicationReady)
        if pkt.opnum != OPNUM["control"]:
            issues.append(f"opnum {pkt.opnum}, not Control (4)")
        if pkt.if_id != CONTROLLER_INTERFACE:
            issues.append(f"interface {pkt.if_id} is not the controller interface")
        if c.block_type != 0x0112 or c.ControlCommand_ApplicationReady != 1:
            issues.append(f"block {c.block_type:04X} is no ApplicationReady request")
        if c.ARUUID != self.ar_uuid or c.SessionKey != self.session_key:
            issues.append("the request names another AR UUID or session key")
        res = c.get_response()
        res.ControlCommand_Done = 1
        pdu = R.PNIOServiceResPDU(status=0, max_count=req.args_max, blocks=[res])
        reply = DceRpc4(ptype=2, flags1=0, endian=pkt.endian, object=pkt.object,
                        if_id=pkt.if_id, act_id=pkt.act_id, server_boot=pkt.server_boot,
                        if_vers=pkt.if_vers, seqnum=pkt.seqnum, opnum=pkt.opnum) / pdu
        data = bytes(reply)
        rt = self.dcp_open() if self.a.iface and self.input_frame_id is not None else None
        s.sendto(data, src)
        line.update(response_len=len(data), response_block=f"{res.block_type:04X}")
        if rt is not None:
            line.update(self.watch_input(rt))
        if issues:
            line.update(parse_issues=issues, ok=False, error="parse: " + "; ".join(issues))
        else:
            line["ok"] = True
        return line

    def watch_input(self, rt):
        """The device's input CR frames on --iface after ApplicationReady was answered, parsed
        by scapy (PNIORealTimeCyclicPDU): until one has DataStatus.ProviderState "run" (the
        device took the answer and exchanges data), --timeout at most."""
        out = {"input_frame_id": self.input_frame_id, "input_frames": 0,
               "input_data_status": None, "input_run": False}
        end = time.monotonic() + self.a.timeout
        while not out["input_run"]:
            left = end - time.monotonic()
            if left <= 0:
                break
            rt.settimeout(left)
            try:
                raw = rt.recv(65535)
            except socket.timeout:
                break
            if len(raw) < 16 or struct.unpack_from(">H", raw, 14)[0] != self.input_frame_id:
                continue
            pdu = Ether(raw).getlayer(PNIORealTimeCyclicPDU)
            if pdu is None:
                out["input_parse_error"] = f"scapy found no RT PDU: {raw.hex()}"
                continue
            out["input_frames"] += 1
            out["input_data_status"] = f"{int(pdu.dataStatus):02X}"
            out["input_run"] = bool(int(pdu.dataStatus) & 0x10)
        return out

    def bench_read(self, line, n, index, slot, subslot, data):
        line.update(index=index, slot=slot, subslot=subslot, reads=n)
        if data is not None:
            w = self.write({"op": "write"}, index, slot, subslot, data)
            line["write"] = {k: w.get(k) for k in ("ok", "pnio_status", "record_status",
                                                   "error")}
        if self.a.dry_run:
            return self.read(line, index, slot, subslot, self.a.read_max)
        statuses, answered, issues_seen, first = {}, 0, 0, {}
        start = time.perf_counter()
        stopped = None
        for _ in range(n):
            sub = {"op": "read"}
            try:
                self.read(sub, index, slot, subslot, self.a.read_max)
            except Timeout:
                stopped = "timeout"
                break
            answered += 1
            st = sub.get("pnio_status", "none")
            statuses[st] = statuses.get(st, 0) + 1
            if sub.get("parse_issues") or "pnio_status" not in sub:
                issues_seen += 1
                first.setdefault("first_error", sub.get("error"))
            if st == "00000000":
                first.setdefault("first_data", sub.get("data"))
        secs = time.perf_counter() - start
        line.update(answered=answered, statuses=statuses, parse_errors=issues_seen,
                    seconds=round(secs, 6),
                    reads_per_s=round(answered / secs, 1) if secs > 0 else None, **first)
        line["ok"] = answered == n and issues_seen == 0
        if stopped:
            line["error"] = f"read {answered + 1} of {n}: timeout"
        elif issues_seen:
            line["error"] = f"{issues_seen} replies did not parse: {first.get('first_error')}"
        return line

    def bench_access(self, line, n, index, slot, subslot, order, max_reads=1000):
        """N complete parameter accesses, each as the harness's bench makes them: the order
        written (IODWrite), then IODRead until the answer with the value."""
        line.update(index=index, slot=slot, subslot=subslot, accesses=n)
        want = order[:2], order[2:4]

        def pnu_of(b):
            return int.from_bytes(b, "big") & 0x07FF

        done, reads, busy, times, answer, error = 0, 0, 0, [], None, None
        start = time.perf_counter()
        for i in range(n):
            t = time.perf_counter()
            w = self.write({"op": "write"}, index, slot, subslot, order)
            if not w.get("ok"):
                error = f"access {i + 1}: write: {w.get('error')}"
                break
            got = None
            for _ in range(max_reads):
                sub = {"op": "read"}
                self.read(sub, index, slot, subslot, self.a.read_max)
                reads += 1
                st = sub.get("pnio_status")
                if st == "DE80B500":
                    busy += 1
                    continue
                if st != "00000000" or sub.get("parse_issues"):
                    error = f"access {i + 1}: read: {sub.get('error') or st}"
                    break
                got = bytes.fromhex(sub.get("data", ""))
                break
            if error:
                break
            if got is None:
                error = f"access {i + 1}: no answer with the value after {max_reads} reads"
                break
            ak = got[0] >> 4 if got else None
            if (len(got) != 8 or ak not in (1, 2, 4, 5) or pnu_of(got[:2]) != pnu_of(want[0])
                    or got[2:4] != want[1]):
                error = f"access {i + 1}: answer {got.hex()} is not the value of order {order.hex()}"
                break
            answer = answer or got.hex()
            times.append(time.perf_counter() - t)
            done += 1
        secs = time.perf_counter() - start
        times.sort()
        line.update(done=done, reads=reads, busy=busy, seconds=round(secs, 6),
                    accesses_per_s=round(done / secs, 1) if secs > 0 else None,
                    p50_us=round(times[len(times) // 2] * 1e6) if times else None,
                    p99_us=round(times[min(len(times) - 1, len(times) * 99 // 100)] * 1e6)
                    if times else None,
                    answer=answer)
        line["ok"] = error is None and done == n
        if error:
            line["error"] = error
        return line

    # -- DCP through scapy's pnio_dcp on a raw socket -------------------------------------------
    def dcp_open(self):
        if self.dcp_sock is None:
            if not self.a.iface:
                raise UsageError("DCP operations need --iface")
            iface = self.a.iface
            try:
                with open(f"/sys/class/net/{iface}/address") as f:
                    self.dcp_mac = f.read().strip()
            except OSError:
                if self.a.dry_run:
                    self.dcp_mac = "00:00:00:00:00:00"
                    return None
                raise OSError(f"no network interface named {iface}")
            if self.a.dry_run:
                return None
            s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETHER_TYPE))
            s.bind((iface, 0))
            self.dcp_sock = s
        return self.dcp_sock

    def dcp_exchange(self, frame, line, xid, collect):
        """Sends a DCP frame; returns the replies (scapy Ether packets) to our MAC with this xid:
        all within --timeout when `collect`, else the first."""
        data = bytes(frame)
        line["request_len"] = len(data)
        if self.a.dry_run:
            sys.stderr.write(f"--- {line['op']}: {len(data)} bytes on {self.a.iface}\n")
            sys.stderr.write(hexdump(data, dump=True) + "\n")
            back = Ether(data)
            line.update(dry_run=True, request_hex=data.hex(), roundtrip=bytes(back) == data,
                        parsed_back={"layers": [l.__name__ for l in back.layers()]})
            dcp = back.getlayer(D.ProfinetDCP)
            line["ok"] = dcp is not None and line["roundtrip"]
            if dcp is not None:
                line["parsed_back"].update(fields_of(dcp, ["service_id", "service_type", "xid",
                                                           "dcp_data_length"]))
            if not line["ok"]:
                line["error"] = "scapy does not parse its own request back to the same bytes"
            return None
        s = self.dcp_sock
        s.send(data)
        out = []
        end = time.monotonic() + self.a.timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                break
            s.settimeout(left)
            try:
                raw = s.recv(65535)
            except socket.timeout:
                break
            if len(raw) < 24 or raw[0:6] != bytes.fromhex(self.dcp_mac.replace(":", "")):
                continue
            if struct.unpack_from(">I", raw, 18)[0] != xid or raw[17] & 0x01 == 0:
                continue  # not an answer (ServiceType bit 0) of this transaction
            out.append(raw)
            if not collect:
                break
        return out

    def dcp_header(self, dst, frame_id, service_id, xid, delay=0):
        return (Ether(dst=dst, src=self.dcp_mac, type=ETHER_TYPE)
                / ProfinetIO(frameID=frame_id)
                / D.ProfinetDCP(service_id=service_id, service_type=0, xid=xid, reserved=delay))

    def dcp_identify(self, line, name=None):
        self.dcp_open()
        xid = random.getrandbits(32)
        base = dict(service_id=5, service_type=0, xid=xid, reserved=self.a.response_delay)
        if name is None:
            dcp = D.ProfinetDCP(option=0xFF, sub_option=0xFF, dcp_block_length=0,
                                dcp_data_length=4, **base)
        else:
            nb = name.encode("latin-1")
            line["name"] = name
            dcp = D.ProfinetDCP(option=2, sub_option=2, dcp_block_length=len(nb),
                                name_of_station=nb,
                                dcp_data_length=4 + len(nb) + (len(nb) & 1), **base)
            dcp = odd_pad(dcp, 4 + len(nb))
        frame = Ether(dst=DCP_MULTICAST, src=self.dcp_mac, type=ETHER_TYPE) \
            / ProfinetIO(frameID=0xFEFE) / dcp
        replies = self.dcp_exchange(frame, line, xid, collect=True)
        if replies is None:
            return line
        devices, errors = [], []
        for raw in replies:
            try:
                devices.append(self.dcp_device(raw))
            except Exception as e:
                errors.append(f"{type(e).__name__}: {e}")
        line.update(devices=devices, count=len(devices))
        line["ok"] = bool(devices) and not errors
        if errors:
            line.update(error="parse: " + "; ".join(errors), replies_hex=[r.hex() for r in replies])
        elif not devices:
            line["error"] = "no device answered"
        return line

    def dcp_device(self, raw):
        pkt = Ether(raw)
        dcp = pkt.getlayer(D.ProfinetDCP)
        if dcp is None:
            raise ValueError(f"scapy found no DCP layer: {raw.hex()}")
        d = {"mac": pkt.src, "frame_id": pkt[ProfinetIO].frameID,
             "service_type": dcp.service_type, "blocks": []}
        if dcp.service_type != 1:
            d["error"] = f"ServiceType {dcp.service_type}"
            return d
        total = 0
        for b in dcp.dcp_blocks:
            blen = b.getfieldval("dcp_block_length") or 0
            total += 4 + blen + (blen & 1)
            entry = {"option": b.option, "suboption": b.sub_option, "class": type(b).__name__}
            d["blocks"].append(entry)
            if isinstance(b, D.DCPNameOfStationBlock):
                d["name"] = b.name_of_station.decode("latin-1")
            elif isinstance(b, D.DCPIPBlock):
                d.update(ip=b.ip, netmask=b.netmask, gateway=b.gateway, ip_block_info=b.block_info)
            elif isinstance(b, D.DCPDeviceIDBlock):
                d.update(vendor_id=b.vendor_id, device_id=b.device_id)
            elif isinstance(b, D.DCPDeviceRoleBlock):
                d["device_role"] = b.device_role_details
            elif isinstance(b, D.DCPDeviceOptionsBlock):
                d["device_options"] = [[o.option, o.sub_option] for o in b.device_options]
            elif isinstance(b, D.DCPManufacturerSpecificBlock):
                d["family"] = b.device_vendor_value.decode("latin-1")
            elif isinstance(b, D.DCPAliasNameBlock):
                d["alias_name"] = b.alias_name.decode("latin-1")
            elif isinstance(b, D.DCPDeviceInstanceBlock):
                d["device_instance"] = [b.device_instance_high, b.device_instance_low]
            elif isinstance(b, D.DCPOEMIDBlock):
                d.update(oem_vendor_id=b.vendor_id, oem_device_id=b.device_id)
            elif isinstance(b, D.DCPMACBlock):
                d["mac_block"] = b.mac
            else:
                entry["data"] = bytes(b.getfieldval("data") or b"").hex()
        if total != dcp.dcp_data_length:
            raise ValueError(f"DCPDataLength {dcp.dcp_data_length} but the blocks scapy found "
                             f"take {total} bytes")
        return d

    def dcp_set(self, line, mac, option, sub, value):
        """Set request of one block: NameOfStation (2/2, `value` the name's bytes, sent as
        given) or IP parameter (1/2, `value` = (ip, netmask, gateway))."""
        self.dcp_open()
        xid = random.getrandbits(32)
        fields = dict(service_id=4, service_type=0, xid=xid, reserved=0, option=option,
                      sub_option=sub, block_qualifier=0 if self.a.temporary else 1)
        if (option, sub) == (2, 2):
            blen = 2 + len(value)
            fields["name_of_station"] = value
        else:
            blen = 14
            fields.update(ip=value[0], netmask=value[1], gateway=value[2])
        dcp = D.ProfinetDCP(dcp_block_length=blen, dcp_data_length=4 + blen + (blen & 1),
                            **fields)
        dcp = odd_pad(dcp, 4 + blen)
        frame = Ether(dst=mac, src=self.dcp_mac, type=ETHER_TYPE) / ProfinetIO(frameID=0xFEFD) \
            / dcp
        replies = self.dcp_exchange(frame, line, xid, collect=False)
        if replies is None:
            return line
        if not replies:
            line.update(ok=False, error="timeout")
            return line
        pkt = Ether(replies[0])
        dcp = pkt.getlayer(D.ProfinetDCP)
        ctrl = [b for b in (dcp.dcp_blocks if dcp is not None else [])
                if isinstance(b, D.DCPControlBlock)]
        if dcp is None or not ctrl:
            line.update(ok=False, error="parse: no Control response block in the answer",
                        reply_hex=replies[0].hex())
            return line
        c = ctrl[0]
        line.update(code=c.block_error, message=D.BLOCK_ERRORS.get(c.block_error, "unknown"),
                    response_option=[c.response, c.response_sub_option],
                    service_type=dcp.service_type)
        line["ok"] = c.block_error == 0 and dcp.service_type == 1
        if not line["ok"]:
            line["error"] = f"BlockError {c.block_error} ({line['message']})"
        return line


def odd_pad(dcp, block_bytes):
    """A DCP block of odd length is followed by a padding byte, counted in DCPDataLength.
    scapy fills a DCP PDU shorter than 44 bytes with zeros itself (the minimum frame), which
    then holds that byte; a longer one gets it here."""
    if block_bytes & 1 and 10 + block_bytes >= D.MIN_PACKET_LENGTH:
        return dcp / Padding(b"\x00")
    return dcp


# --- command line -----------------------------------------------------------------------------

ARITY = {"connect": 0, "device-access": 0, "prm-end": 0, "appl-ready": 0, "write": 4, "read": (3, 4), "read-implicit": (3, 4),
         "release": 0, "bench-read": (4, 5), "bench-access": 5, "dcp-identify": (0, 1),
         "dcp-set-name": 2,
         "dcp-set-ip": 4}


def parse_ops(tokens, read_max):
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
        i += 1 + len(args)
        if name in ("write", "read", "read-implicit"):
            v = [number(args[0], "index", 0, 0xFFFF), number(args[1], "slot", 0, 0xFFFF),
                 number(args[2], "subslot", 0, 0xFFFF)]
            if name == "write":
                v.append(hex_bytes(args[3]))
            else:
                v.append(number(args[3], "max length", 0, 0xFFFF) if len(args) > 3 else read_max)
            args = v
        elif name == "bench-read":
            args = [number(args[0], "N", 1, 10_000_000), number(args[1], "index", 0, 0xFFFF),
                    number(args[2], "slot", 0, 0xFFFF), number(args[3], "subslot", 0, 0xFFFF),
                    hex_bytes(args[4]) if len(args) > 4 else None]
        elif name == "bench-access":
            args = [number(args[0], "N", 1, 10_000_000), number(args[1], "index", 0, 0xFFFF),
                    number(args[2], "slot", 0, 0xFFFF), number(args[3], "subslot", 0, 0xFFFF),
                    hex_bytes(args[4])]
            if len(args[4]) != 8:
                raise UsageError(f"bench-access: a PKW order is 8 bytes, got {len(args[4])}")
        elif name == "dcp-set-name":
            args = [mac_arg(args[0]), args[1]]
        elif name == "dcp-set-ip":
            for a in args[1:]:
                try:
                    ipaddress.IPv4Address(a)
                except ValueError:
                    raise UsageError(f"dcp-set-ip: not an IPv4 address: {a!r}") from None
            args = [mac_arg(args[0])] + args[1:]
        ops.append((name, args))
    return ops


def run_op(c, name, args):
    line = {"op": name}
    try:
        if name == "connect":
            return c.connect(line)
        if name == "device-access":
            return c.device_access(line)
        if name == "prm-end":
            return c.control(line)
        if name == "appl-ready":
            return c.appl_ready(line)
        if name == "release":
            return c.control(line, release=True)
        if name == "write":
            return c.write(line, *args)
        if name == "read":
            return c.read(line, *args)
        if name == "read-implicit":
            return c.read(line, *args, implicit=True)
        if name == "bench-read":
            return c.bench_read(line, *args)
        if name == "bench-access":
            return c.bench_access(line, *args)
        if name == "dcp-identify":
            return c.dcp_identify(line, *args)
        if name == "dcp-set-name":
            line.update(mac=args[0], name=args[1])
            return c.dcp_set(line, args[0], 2, 2, args[1].encode("latin-1"))
        if name == "dcp-set-ip":
            line.update(mac=args[0], ip=args[1], netmask=args[2], gateway=args[3])
            return c.dcp_set(line, args[0], 1, 2, args[1:4])
    except Timeout:
        line.pop("_issues", None)
        line.update(ok=False, error="timeout")
    except PermissionError as e:
        line.update(ok=False, error=f"{e} (raw Ethernet needs root or CAP_NET_RAW)")
    except OSError as e:
        line.update(ok=False, error=f"{type(e).__name__}: {e}")
    line.pop("_issues", None)
    return line


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 2)[2])
    p.add_argument("ops", nargs="*", metavar="OP")
    p.add_argument("--ip", help="the device's IPv4 address (RPC operations)")
    p.add_argument("--port", type=int, default=RPC_PORT, help="RPC port (default 34964)")
    p.add_argument("--cm-port", type=int, default=RPC_PORT,
                   help="UDP port of this controller's own RPC endpoint, where the device calls "
                   "ApplicationReady (appl-ready; default 34964)")
    p.add_argument("--iface", help="network interface for DCP (and for the controller's MAC)")
    p.add_argument("--mac", help="CMInitiatorMacAdd (default: the MAC of the interface towards "
                   "--ip)")
    p.add_argument("--vendor-id", default="0", help="the device's vendor id (object UUID)")
    p.add_argument("--device-id", default="0", help="the device's device id (object UUID)")
    p.add_argument("--instance", default="1", help="the device's instance (object UUID, "
                   "default 1)")
    p.add_argument("--submodule", action="append", default=[],
                   metavar="SLOT,SUBSLOT,MODULE_IDENT,SUBMODULE_IDENT,IN,OUT",
                   help="an expected submodule with its input/output data bytes; repeat for "
                   "each (DAP and its interface/port submodules included)")
    p.add_argument("--controller-name", default="scapy-controller",
                   help="CMInitiatorStationName (default scapy-controller)")
    p.add_argument("--ar-uuid", help="AR UUID (default: a random one)")
    p.add_argument("--session-key", default="1", help="session key (default 1)")
    p.add_argument("--startup", choices=["legacy", "advanced"], default="legacy",
                   help="ARProperties StartupMode (default legacy)")
    p.add_argument("--activity-timeout", default="1000",
                   help="CMInitiatorActivityTimeoutFactor, 100 ms units (default 1000)")
    # RT_CLASS_1 (its IOCRProperties) takes frame ids C000h-F7FFh (IEC 61158-6-10 FrameID table).
    p.add_argument("--input-frame-id", default="0xC000", help="input CR FrameID (default C000h)")
    p.add_argument("--output-frame-id", default="0xC001",
                   help="output CR FrameID (default C001h)")
    p.add_argument("--send-clock-factor", default="32", help="SendClockFactor (default 32 = 1 ms)")
    p.add_argument("--reduction-ratio", default="32", help="ReductionRatio (default 32)")
    p.add_argument("--watchdog-factor", default="10", help="WatchdogFactor (default 10)")
    p.add_argument("--data-hold-factor", default="10",
                   help="DataHoldFactor (default 10: 320 ms with the defaults; this client "
                   "sends no RT frames)")
    p.add_argument("--args-max", default="16384",
                   help="ArgsMaximum / MaximumCount of the requests (default 16384)")
    p.add_argument("--read-max", default="4096",
                   help="RecordDataLength of a read request (default 4096)")
    p.add_argument("--response-delay", default="1",
                   help="DCP Identify ResponseDelayFactor (default 1: answer at once)")
    p.add_argument("--temporary", action="store_true",
                   help="DCP sets store temporarily (BlockQualifier 0), not permanently")
    p.add_argument("--timeout", type=float, default=2.0,
                   help="seconds to wait for a reply, per request (default 2)")
    p.add_argument("--deadline", type=float, default=60.0,
                   help="end the whole run after this many seconds (default 60)")
    p.add_argument("--dry-run", action="store_true",
                   help="send nothing: build, hexdump to stderr, parse back")
    p.add_argument("--strict", action="store_true", help="exit 1 when an operation is not ok")
    p.add_argument("-v", "--verbose", action="count", default=0, help="scapy's logging on stderr")
    a = p.parse_intermixed_args(argv)
    try:
        a.vendor_id = number(a.vendor_id, "--vendor-id", 0, 0xFFFF)
        a.device_id = number(a.device_id, "--device-id", 0, 0xFFFF)
        a.instance = number(a.instance, "--instance", 0, 0xFFFF)
        a.session_key = number(a.session_key, "--session-key", 0, 0xFFFF)
        a.activity_timeout = number(a.activity_timeout, "--activity-timeout", 1, 0xFFFF)
        a.input_frame_id = number(a.input_frame_id, "--input-frame-id", 0, 0xFFFF)
        a.output_frame_id = number(a.output_frame_id, "--output-frame-id", 0, 0xFFFF)
        a.send_clock_factor = number(a.send_clock_factor, "--send-clock-factor", 1, 0xFFFF)
        a.reduction_ratio = number(a.reduction_ratio, "--reduction-ratio", 1, 0xFFFF)
        a.watchdog_factor = number(a.watchdog_factor, "--watchdog-factor", 1, 0xFFFF)
        a.data_hold_factor = number(a.data_hold_factor, "--data-hold-factor", 1, 0xFFFF)
        a.args_max = number(a.args_max, "--args-max", 0, 0xFFFFFFFF)
        a.read_max = number(a.read_max, "--read-max", 0, 0xFFFFFFFF)
        a.response_delay = number(a.response_delay, "--response-delay", 0, 0xFFFF)
        a.submodules = [Submodule(s) for s in a.submodule]
        if a.mac:
            a.mac = mac_arg(a.mac)
        if a.ar_uuid:
            try:
                uuid.UUID(a.ar_uuid)
            except ValueError:
                raise UsageError(f"--ar-uuid: not a UUID: {a.ar_uuid!r}") from None
        ops = parse_ops(a.ops, a.read_max)
        if not ops:
            raise UsageError("no operation given")
        names = {n for n, _ in ops}
        if "connect" in names and not a.submodules:
            raise UsageError("connect needs the layout: --submodule … for every submodule")
        rpc = names - {"dcp-identify", "dcp-set-name", "dcp-set-ip"}
        if rpc and not a.ip:
            if not a.dry_run:
                raise UsageError(f"{', '.join(sorted(rpc))} need --ip")
            a.ip = "127.0.0.1"
        if a.ip:
            try:
                ipaddress.IPv4Address(a.ip)
            except ValueError:
                raise UsageError(f"--ip: not an IPv4 address: {a.ip!r}") from None
        if names & {"dcp-identify", "dcp-set-name", "dcp-set-ip"} and not a.iface:
            raise UsageError("DCP operations need --iface")
        if a.timeout <= 0 or a.deadline <= 0:
            raise UsageError("--timeout and --deadline must be > 0")
    except UsageError as e:
        p.print_usage(sys.stderr)
        sys.stderr.write(f"scapy_pnio_peer.py: {e}\n")
        return 2
    if a.verbose:
        logging.basicConfig(stream=sys.stderr, level=logging.DEBUG)
        logging.getLogger("scapy").setLevel(logging.DEBUG if a.verbose > 1 else logging.INFO)

    signal.signal(signal.SIGALRM, _on_alarm)
    signal.setitimer(signal.ITIMER_REAL, a.deadline)
    c = Controller(a)
    all_ok = True
    expired = False
    if "appl-ready" in names:
        # Bound before anything is sent: the device calls ApplicationReady right after it
        # answers PrmEnd.
        try:
            c.cm_open()
        except OSError as e:
            sys.stderr.write(f"scapy_pnio_peer.py: UDP {a.cm_port}: {e}\n")
    try:
        for name, op_args in ops:
            start = time.perf_counter()
            if expired:
                line = {"op": name, "ok": False, "error": "deadline"}
            else:
                try:
                    line = run_op(c, name, op_args)
                except Deadline:
                    expired = True
                    line = {"op": name, "ok": False, "error": "deadline"}
                except Exception as e:  # a reply scapy choked on: reported, the run goes on
                    line = {"op": name, "ok": False,
                            "error": f"parse: {type(e).__name__}: {e}"}
            line.pop("_issues", None)
            line.pop("_why", None)
            if name not in ("dcp-identify", "dcp-set-name", "dcp-set-ip"):
                line.setdefault("ip", a.ip)
            line.setdefault("ok", False)
            line["elapsed_ms"] = round((time.perf_counter() - start) * 1000, 3)
            emit(line)
            all_ok &= bool(line.get("ok"))
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        for s in (c.sock, c.dcp_sock, c.cm_sock):
            if s is not None:
                s.close()
    return 1 if a.strict and not all_ok else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
