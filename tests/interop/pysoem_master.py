#!/usr/bin/env python3
"""An independent EtherCAT master: pysoem (SOEM's Python binding) on a network interface.

    python pysoem_master.py IFACE [--timeout S] [--deadline S] [--slave N] [--inverter N]
                            [--cycle-ms MS] [--pdo-cycles N] [--strict] OP...

Opens IFACE (raw Ethernet: root or CAP_NET_RAW), finds the slaves (SOEM's config_init: station
addresses, SII, mailbox; the slaves are asked for PRE-OP), then runs the operations in order and
prints one JSON line per operation on stdout:

  scan                         the slaves found: position, name, vendor, product, revision, state
  read INDEX SUB [TYPE]        SDO upload; TYPE u8 u16 u32 u64 i8 i16 i32 i64 str hex (default:
                               unsigned little-endian by the length of the data)
  write INDEX SUB TYPE VALUE   SDO download of VALUE as TYPE (hex: VALUE is the bytes in hex)
  state NAME                   init, preop, safeop, op or boot the way a master gets there: the PDO
                               map is configured before SAFE-OP, process data flows before OP
  request NAME                 only writes the AL control register (no preparation) and reports
                               the AL status and AL status code: for refused transitions
  ack                          acknowledges an error indication (AL control = state + 10h)
  pdo CONTROL SETPOINT [PAT]   cyclic process data of inverter --inverter (12 bytes each: control
                               word + 5 setpoints out, status word + 5 actual values in, BU 0620
                               §2.2.6.1) with CONTROL and setpoint 1 = SETPOINT, until the status
                               word matches PAT (manual notation, e.g. xx31h) or --pdo-cycles ran
  speed N INDEX SUB            N SDO uploads one after the other, as fast as SOEM goes: uploads/s

Numbers are decimal, 0x-hex or h-suffixed hex (3066h). Every line has "op" and "ok"; a refused
SDO carries "abort_code" (integer) and "abort" (e.g. "06020000h"); a mailbox or working-counter
failure carries "error_kind" and "error". Emergencies the slave sends come out as their own
lines ("op": "emergency").

Exit codes: 0 every operation ran and printed its line (refusals included); 1 --strict and an
operation was not ok; 2 usage error; 3 pysoem is not importable (use the interop venv:
.ci/interop-setup); 4 the interface could not be opened or no slave answered (printed as an
"open" or "scan" line with "ok": false). --deadline (default 120 s) ends the process however
far it got, should SOEM ever block: a test never hangs on it.
"""

import argparse
import json
import os
import re
import signal
import struct
import sys
import time

sys.dont_write_bytecode = True  # keep tests/interop free of __pycache__

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interop_common as ic  # noqa: E402

pysoem, MASTER = ic.import_peer("pysoem")

STATES = {
    "init": pysoem.INIT_STATE,
    "preop": pysoem.PREOP_STATE,
    "boot": pysoem.BOOT_STATE,
    "safeop": pysoem.SAFEOP_STATE,
    "op": pysoem.OP_STATE,
}
STATE_NAMES = {v: k for k, v in STATES.items()}
ERROR_BIT = 0x10  # AL status: error indication (ETG.1000.6 AL status register 0130h, bit 4)

TYPES = {
    "u8": "<B", "u16": "<H", "u32": "<I", "u64": "<Q",
    "i8": "<b", "i16": "<h", "i32": "<i", "i64": "<q",
}

PDO_BYTES = 12  # per inverter, BU 0620 §2.2.6.1
ARITY = {"scan": 0, "read": (2, 3), "write": 4, "state": 1, "request": 1, "ack": 0,
         "pdo": (2, 3), "speed": 3}


class UsageError(Exception):
    pass


def number(text):
    t = text.strip()
    try:
        if t.lower().endswith("h"):
            return int(t[:-1], 16)
        return int(t, 0)
    except ValueError:
        raise UsageError(f"not a number: {text!r}") from None


def pattern(text):
    """A manual-notation word pattern (xx31h, 0B31h, x=any nibble) -> (mask, value)."""
    t = text.strip().lower()
    if t.endswith("h"):
        t = t[:-1]
    if t.startswith("0x"):
        t = t[2:]
    if not re.fullmatch(r"[0-9a-fx]{1,4}", t):
        raise UsageError(f"not a word pattern like xx31h: {text!r}")
    t = t.rjust(4, "0")
    mask = value = 0
    for ch in t:
        mask, value = mask << 4, value << 4
        if ch != "x":
            mask |= 0xF
            value |= int(ch, 16)
    return mask, value


def state_name(state):
    base = STATE_NAMES.get(state & 0x0F, f"{state & 0x0F:#x}")
    return base + ("+error" if state & ERROR_BIT else "")


def hexcode(code):
    return f"{code:08X}h"


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
        ops.append((name, args))
        i += 1 + len(args)
    return ops


def emit(line):
    line.setdefault("master", MASTER)
    sys.stdout.write(json.dumps(line) + "\n")
    sys.stdout.flush()
    return line


def failure(line, exc):
    """Fills `line` from a pysoem exception: an SDO abort is the device's answer, the rest are
    mailbox, packet or working-counter trouble."""
    line["ok"] = False
    if isinstance(exc, pysoem.SdoError):
        line.update(error_kind="sdo_abort", abort_code=exc.abort_code,
                    abort=hexcode(exc.abort_code), error=exc.desc)
    elif isinstance(exc, pysoem.MailboxError):
        line.update(error_kind="mailbox", mailbox_error=exc.error_code, error=exc.desc)
    elif isinstance(exc, pysoem.PacketError):
        line.update(error_kind="packet", packet_error=exc.error_code,
                    error=pysoem.PacketError._code_desc.get(exc.error_code, "packet error"))
    elif isinstance(exc, pysoem.WkcError):
        line.update(error_kind="wkc", wkc=exc.wkc,
                    error=f"no answer (working counter {exc.wkc})")
    else:
        line.update(error_kind=type(exc).__name__, error=str(exc))
    return line


class Master:
    def __init__(self, args):
        self.args = args
        self.m = pysoem.Master()
        self.m.sdo_read_timeout = int(args.timeout * 1e6)
        self.m.sdo_write_timeout = int(args.timeout * 1e6)
        self.mapped = False
        self.outputs = None  # this master's view of the process image of the slave's outputs
        self.emergencies = []

    # --- setup ---------------------------------------------------------------------------
    def open(self):
        if not os.path.exists(f"/sys/class/net/{self.args.iface}"):
            emit({"op": "open", "iface": self.args.iface, "ok": False,
                  "error": f"no network interface named {self.args.iface}"})
            return False
        try:
            self.m.open(self.args.iface)
        except Exception as e:
            emit({"op": "open", "iface": self.args.iface, "ok": False,
                  "error": f"{e} (raw Ethernet needs root or CAP_NET_RAW)"})
            return False
        found = self.m.config_init()
        if found <= 0:
            emit({"op": "scan", "iface": self.args.iface, "ok": False, "slaves": [],
                  "error": f"no slave found on {self.args.iface}"})
            return False
        for s in self.m.slaves:
            s.add_emergency_callback(self._emergency)
        if not 1 <= self.args.slave <= len(self.m.slaves):
            emit({"op": "scan", "ok": False, "error": f"no slave at position {self.args.slave} "
                  f"({len(self.m.slaves)} found)"})
            return False
        # config_init asked every slave for PRE-OP; wait until they are there (or say so).
        self.m.state_check(pysoem.PREOP_STATE, 3_000_000)
        return True

    def _emergency(self, e):
        self.emergencies.append(e)

    def flush_emergencies(self):
        for e in self.emergencies:
            emit({"op": "emergency", "ok": True, "slave": e.slave_pos,
                  "error_code": e.error_code, "error_register": e.error_reg,
                  "data": bytes([e.b1]).hex() + e.w1.to_bytes(2, "little").hex()
                  + e.w2.to_bytes(2, "little").hex()})
        self.emergencies.clear()

    @property
    def slave(self):
        return self.m.slaves[self.args.slave - 1]

    # --- operations ----------------------------------------------------------------------
    def scan(self):
        self.m.read_state()
        slaves = [{
            "position": i + 1, "name": s.name, "vendor": s.man, "product": s.id,
            "revision": s.rev, "vendor_hex": f"{s.man:08X}h", "product_hex": f"{s.id:08X}h",
            "revision_hex": f"{s.rev:08X}h", "state": state_name(s.state),
            "al_status_code": s.al_status,
        } for i, s in enumerate(self.m.slaves)]
        return {"ok": True, "slaves": slaves}

    def read(self, index, sub, typ=None):
        line = {"index": number(index), "subindex": number(sub)}
        line["index_hex"] = f"{line['index']:04X}h"
        try:
            data = self.slave.sdo_read(line["index"], line["subindex"])
        except Exception as e:
            return failure(line, e)
        line.update(ok=True, data=data.hex(), length=len(data))
        line.update(decode(data, typ))
        return line

    def write(self, index, sub, typ, value):
        line = {"index": number(index), "subindex": number(sub), "type": typ}
        line["index_hex"] = f"{line['index']:04X}h"
        data = encode(typ, value)
        line.update(data=data.hex(), value=value if typ in ("hex", "str") else number(value))
        try:
            self.slave.sdo_write(line["index"], line["subindex"], data)
        except Exception as e:
            return failure(line, e)
        line["ok"] = True
        return line

    def _al(self, line, want=None):
        self.m.read_state()
        s = self.slave
        line.update(state=state_name(s.state), al_status=s.state, al_status_code=s.al_status,
                    al_status_code_hex=f"{s.al_status:04X}h",
                    al_status_text=pysoem.al_status_code_to_string(s.al_status))
        if want is not None:
            line["ok"] = (s.state & 0x0F) == want and not s.state & ERROR_BIT
        return line

    def state(self, name):
        want = STATES.get(name.lower())
        if want is None:
            raise UsageError(f"unknown state {name!r} (init, preop, safeop, op, boot)")
        line = {"want": name.lower()}
        t = int(self.args.timeout * 1e6)
        if want in (pysoem.SAFEOP_STATE, pysoem.OP_STATE) and not self.mapped:
            # Configures SM2/SM3 and the FMMUs from the slave's PDO assignment (CoE 1C12h/1C13h
            # or the SII) and asks for SAFE-OP.
            try:
                line["io_map_bytes"] = self.m.config_map()
            except Exception as e:
                failure(line, e)
                return self._al(line)
            self.mapped = True
            self.outputs = bytearray(len(self.slave.output))
            self.m.state_check(pysoem.SAFEOP_STATE, t)
        if want == pysoem.OP_STATE:
            # A slave goes to OP only when it receives valid outputs (ETG.1000.6 SAFE-OP->OP).
            self._exchange()
            self.slave.state = pysoem.OP_STATE
            self.slave.write_state()
            end = time.monotonic() + self.args.timeout
            while time.monotonic() < end:
                self._exchange()
                if self.slave.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
                    break
                time.sleep(self.args.cycle_ms / 1000)
        elif want != pysoem.SAFEOP_STATE or self.slave.state != pysoem.SAFEOP_STATE:
            self.slave.state = want
            self.slave.write_state()
            self.slave.state_check(want, t)
        if want in (pysoem.INIT_STATE, pysoem.PREOP_STATE, pysoem.BOOT_STATE):
            self.mapped = False  # leaving SAFE-OP drops the process data configuration
        return self._al(line, want)

    def request(self, name, ack=False):
        want = STATES.get(name.lower())
        if want is None:
            raise UsageError(f"unknown state {name!r} (init, preop, safeop, op, boot)")
        line = {"want": name.lower(), "al_control": want | (ERROR_BIT if ack else 0)}
        self.slave.state = line["al_control"]
        line["wkc"] = self.slave.write_state()
        # Wait for the slave to get there or to refuse (error indication), at most --timeout.
        end = time.monotonic() + self.args.timeout
        while True:
            self.m.read_state()
            st = self.slave.state
            if (st & 0x0F) == want or st & ERROR_BIT or time.monotonic() >= end:
                break
            time.sleep(0.002)
        return self._al(line, want)

    def ack(self):
        self.m.read_state()
        current = self.slave.state & 0x0F
        line = self.request(STATE_NAMES.get(current, "init"), ack=True)
        line["op"] = "ack"
        return line

    def _exchange(self):
        if self.outputs is not None:
            self.slave.output = bytes(self.outputs)
        self.m.send_processdata()
        return self.m.receive_processdata(2000)

    def pdo(self, control, setpoint, pat=None):
        line = {"control": number(control) & 0xFFFF, "setpoint1": number(setpoint) & 0xFFFF,
                "inverter": self.args.inverter}
        line["control_hex"] = f"{line['control']:04X}h"
        if not self.mapped or self.outputs is None:
            line.update(ok=False, error="no process data: bring the slave to op first")
            return line
        at = PDO_BYTES * (self.args.inverter - 1)
        if at + PDO_BYTES > len(self.outputs):
            line.update(ok=False, error=f"the slave's outputs have {len(self.outputs)} bytes: "
                        f"no inverter {self.args.inverter}")
            return line
        words = [line["control"], line["setpoint1"], 0, 0, 0, 0]
        self.outputs[at:at + PDO_BYTES] = struct.pack("<6H", *words)
        mask, value = pattern(pat) if pat else (0, 0)
        wkc, inputs, cycles, matched = None, b"", 0, False
        for cycles in range(1, self.args.pdo_cycles + 1):
            wkc = self._exchange()
            inputs = self.slave.input
            if len(inputs) >= at + 2:
                status = struct.unpack_from("<H", inputs, at)[0]
                if pat and wkc == self.m.expected_wkc and status & mask == value:
                    matched = True
                    break
            time.sleep(self.args.cycle_ms / 1000)
        line.update(wkc=wkc, expected_wkc=self.m.expected_wkc, cycles=cycles,
                    inputs=bytes(inputs).hex(), outputs=bytes(self.outputs).hex())
        if len(inputs) >= at + PDO_BYTES:
            sw, *actual = struct.unpack_from("<6H", inputs, at)
            line.update(status=sw, status_hex=f"{sw:04X}h", actual=actual)
        else:
            line.update(status=None, error=f"the slave's inputs have {len(inputs)} bytes")
        if pat:
            line.update(pattern=pat, ok=matched)
        else:
            line["ok"] = wkc == self.m.expected_wkc and line.get("status") is not None
        return line

    def speed(self, n, index, sub):
        count, idx, si = number(n), number(index), number(sub)
        errors, first_error = 0, None
        start = time.perf_counter()
        for _ in range(count):
            try:
                self.slave.sdo_read(idx, si)
            except Exception as e:
                errors += 1
                if first_error is None:
                    first_error = failure({}, e)
        seconds = time.perf_counter() - start
        line = {"uploads": count, "index": idx, "subindex": si, "errors": errors,
                "seconds": round(seconds, 6),
                "uploads_per_s": round(count / seconds, 1) if seconds > 0 else None,
                "ok": errors == 0}
        if first_error:
            line["first_error"] = first_error
        return line


def decode(data, typ):
    if typ is None:
        if 1 <= len(data) <= 8:
            return {"value": int.from_bytes(data, "little")}
        return {}
    if typ == "hex":
        return {"value": data.hex()}
    if typ == "str":
        return {"value": data.rstrip(b"\0").decode("latin-1")}
    fmt = TYPES.get(typ)
    if fmt is None:
        raise UsageError(f"unknown type {typ!r} ({', '.join([*TYPES, 'str', 'hex'])})")
    if len(data) != struct.calcsize(fmt):
        return {"value": None, "decode_error": f"{len(data)} bytes for {typ}"}
    return {"value": struct.unpack(fmt, data)[0]}


def encode(typ, value):
    if typ == "hex":
        try:
            return bytes.fromhex(value)
        except ValueError:
            raise UsageError(f"not hex bytes: {value!r}") from None
    if typ == "str":
        return value.encode("latin-1")
    fmt = TYPES.get(typ)
    if fmt is None:
        raise UsageError(f"unknown type {typ!r} ({', '.join([*TYPES, 'str', 'hex'])})")
    try:
        return struct.pack(fmt, number(value))
    except struct.error as e:
        raise UsageError(f"{value} does not fit {typ}: {e}") from None


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 2)[2])
    p.add_argument("iface")
    p.add_argument("ops", nargs="*")
    p.add_argument("--timeout", type=float, default=2.0,
                   help="SDO and state-change timeout in seconds (default 2)")
    p.add_argument("--deadline", type=float, default=120.0,
                   help="end the whole run after this many seconds (default 120)")
    p.add_argument("--slave", type=int, default=1, help="slave position (default 1)")
    p.add_argument("--inverter", type=int, default=1, help="inverter of the pdo op (default 1)")
    p.add_argument("--cycle-ms", type=float, default=1.0, help="process data cycle (default 1)")
    p.add_argument("--pdo-cycles", type=int, default=1000,
                   help="most cycles of one pdo op (default 1000)")
    p.add_argument("--strict", action="store_true", help="exit 1 when an operation is not ok")
    args = p.parse_intermixed_args(argv)
    try:
        ops = parse_ops(args.ops)
    except UsageError as e:
        p.print_usage(sys.stderr)
        sys.stderr.write(f"pysoem_master.py: {e}\n")
        return 2
    # The default action of SIGALRM ends the process, also inside a C call of SOEM.
    signal.signal(signal.SIGALRM, signal.SIG_DFL)
    signal.setitimer(signal.ITIMER_REAL, args.deadline)

    master = Master(args)
    if not master.open():
        return 4
    all_ok = True
    try:
        for name, op_args in ops:
            start = time.perf_counter()
            try:
                line = getattr(master, name)(*op_args)
            except UsageError as e:
                sys.stderr.write(f"pysoem_master.py: {name}: {e}\n")
                return 2
            line = {"op": name, **line}
            line["elapsed_ms"] = round((time.perf_counter() - start) * 1000, 3)
            emit(line)
            master.flush_emergencies()
            all_ok &= bool(line.get("ok"))
    finally:
        try:
            master.m.close()
        except Exception:
            pass
    return 1 if args.strict and not all_ok else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
