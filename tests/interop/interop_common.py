"""Shared CLI, output and decoding helpers for the third-party EtherNet/IP client wrappers, and
the import of every peer library (`import_peer`).

Used by pycomm3_client.py and cpppo_client.py (same CLI, same JSON lines), and by the pysoem
scripts for `import_peer`. Standard library only,
so it imports without the interop venv; the client libraries are imported by the scripts.
"""

from __future__ import annotations

import argparse
import ipaddress
import json
import logging
import signal
import socket
import struct
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 44818
DEFAULT_TIMEOUT = 5.0
WATCHDOG_GRACE = 0.5  # hard limit per operation = --timeout + this

USAGE_OPS = """\
operations (any number, run in order, one JSON line each):
  get CLASS INSTANCE ATTRIBUTE        Get_Attribute_Single (0x0E)
  set CLASS INSTANCE ATTRIBUTE VALUE  Set_Attribute_Single (0x10); VALUE is sent as a 2-byte
                                      little-endian INT (4-byte DINT with --dint)
  identity                            ListIdentity (encapsulation command 0x0063) on the TCP session
  identity-object                     Get_Attributes_All (0x01) on the Identity object, class 1 instance 1
Numbers are decimal or 0x-hex. CLASS/INSTANCE/ATTRIBUTE may be 0 (NORD: instance 0 = parameter set 1).
A leading HOST:PORT token is accepted instead of --host/--port.
"""


def import_peer(name: str, *submodules: str):
    """Imports the third-party peer `name` (and `name.submodule`s) from the interop venv, or
    exits with status 3 saying how to get it; returns the module and "name version" for the
    output. Every peer script imports its library so."""
    import importlib
    try:
        module = importlib.import_module(name)
        for sub in submodules:
            importlib.import_module(f"{name}.{sub}")
    except ImportError as e:  # pragma: no cover
        sys.stderr.write(f"{name} is not importable ({e}); run .ci/interop-setup and use "
                         f"${{INTEROP_VENV:-target/interop-venv}}/bin/python\n")
        sys.exit(3)
    try:
        from importlib.metadata import version
        label = f"{name} {version(name)}"
    except Exception:  # pragma: no cover
        label = name
    return module, label


class UsageError(Exception):
    pass


class ConnectFailed(Exception):
    """The TCP connect or RegisterSession failed (distinct from OSError's ConnectionError)."""


class WatchdogTimeout(BaseException):
    """Raised from SIGALRM when an operation exceeds its hard time limit. A BaseException so that
    the libraries' own `except Exception` handlers (pycomm3 wraps everything in CommError) do not
    swallow it."""


@dataclass
class Op:
    kind: str  # get | set | identity | identity-object
    cls: Optional[int] = None
    instance: Optional[int] = None
    attribute: Optional[int] = None
    value: Optional[int] = None  # for set

    def base_result(self) -> Dict[str, Any]:
        return {
            "op": self.kind,
            "class": self.cls,
            "instance": self.instance,
            "attribute": self.attribute,
            "ok": False,
            "status": None,
            "value": self.value if self.kind == "set" else None,
            "error": None,
        }


@dataclass
class Config:
    host: str
    port: int
    timeout: float
    dint: bool
    unsigned: bool
    strict: bool
    verbose: int
    ops: List[Op] = field(default_factory=list)

    @property
    def width(self) -> int:
        return 4 if self.dint else 2


def _num(tok: str, what: str, lo: int, hi: int) -> int:
    try:
        v = int(tok, 0)
    except ValueError:
        raise UsageError(f"{what}: not a number: {tok!r}")
    if not lo <= v <= hi:
        raise UsageError(f"{what}: {v} out of range {lo}..{hi}")
    return v


def parse_ops(tokens: List[str], dint: bool) -> List[Op]:
    ops: List[Op] = []
    i = 0
    # Class ids are 8 or 16 bit in a logical segment, instances up to 32 bit, attributes up to 16 bit.
    lim_cls, lim_ins, lim_att = 0xFFFF, 0xFFFFFFFF, 0xFFFF
    vlo, vhi = (-(2**31), 2**32 - 1) if dint else (-(2**15), 2**16 - 1)
    while i < len(tokens):
        t = tokens[i].lower()
        if t in ("get", "set"):
            n = 3 if t == "get" else 4
            args = tokens[i + 1 : i + 1 + n]
            if len(args) != n:
                raise UsageError(f"{t}: expected {n} arguments, got {args!r}")
            op = Op(
                t,
                _num(args[0], "class", 0, lim_cls),
                _num(args[1], "instance", 0, lim_ins),
                _num(args[2], "attribute", 0, lim_att),
            )
            if t == "set":
                op.value = _num(args[3], "value", vlo, vhi)
            ops.append(op)
            i += 1 + n
        elif t == "identity":
            ops.append(Op("identity"))
            i += 1
        elif t in ("identity-object", "identity_object"):
            ops.append(Op("identity-object", 1, 1, None))
            i += 1
        else:
            raise UsageError(f"unknown operation {tokens[i]!r}")
    return ops


def parse_args(prog_desc: str, argv: Optional[List[str]] = None) -> Config:
    ap = argparse.ArgumentParser(
        description=prog_desc,
        epilog=USAGE_OPS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument("--host", default=None, help=f"target address (default {DEFAULT_HOST})")
    ap.add_argument("--port", type=int, default=None, help=f"target TCP port (default {DEFAULT_PORT})")
    ap.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT,
                    help="seconds: socket timeout and hard limit per operation (default 5)")
    ap.add_argument("--dint", action="store_true", help="values are 4-byte DINT instead of 2-byte INT")
    ap.add_argument("--unsigned", action="store_true", help="decode read values as UINT/UDINT")
    ap.add_argument("--strict", action="store_true", help="exit 1 if any operation is not ok")
    ap.add_argument("--allow-remote", action="store_true",
                    help="allow a non-loopback target (default: only 127.0.0.0/8 and ::1)")
    ap.add_argument("-v", "--verbose", action="count", default=0, help="library logging to stderr")
    ap.add_argument("ops", nargs="*", metavar="OP", help="operations, see below")
    try:
        a = ap.parse_intermixed_args(argv)
    except SystemExit as e:  # argparse already printed the message
        raise SystemExit(2 if e.code else 0)
    tokens = list(a.ops)
    host, port = a.host, a.port
    if tokens and ":" in tokens[0]:
        h, _, p = tokens.pop(0).rpartition(":")
        host = host or h
        port = port or _num(p, "port", 1, 65535)
    host = host or DEFAULT_HOST
    port = port or DEFAULT_PORT
    if not 1 <= port <= 65535:
        ap.error(f"port {port} out of range")
    if a.timeout <= 0:
        ap.error("--timeout must be > 0")
    if not a.allow_remote and not is_loopback(host):
        ap.error(f"refusing non-loopback target {host!r} (use --allow-remote for a real device)")
    try:
        ops = parse_ops(tokens, a.dint)
    except UsageError as e:
        ap.error(str(e))
    if not ops:
        ap.error("no operation given")
    return Config(host, port, a.timeout, a.dint, a.unsigned, a.strict, a.verbose, ops)


def is_loopback(host: str) -> bool:
    try:
        infos = socket.getaddrinfo(host, None)
    except OSError:
        return False
    return bool(infos) and all(ipaddress.ip_address(i[4][0]).is_loopback for i in infos)


def setup_logging(verbose: int) -> None:
    # stdout carries only JSON lines; library chatter goes to stderr, and only when asked for.
    level = logging.CRITICAL + 1 if verbose == 0 else (logging.INFO if verbose == 1 else logging.DEBUG)
    logging.basicConfig(stream=sys.stderr, level=level,
                        format="%(asctime)s %(name)s %(levelname)s %(message)s")
    logging.getLogger().setLevel(level)


# --- hard time limit per operation ---------------------------------------------------------------

def _on_alarm(signum, frame):
    raise WatchdogTimeout()


def run_bounded(seconds: float, fn: Callable[[], Any]) -> Any:
    """Run fn() with a SIGALRM hard limit (main thread only). Raises WatchdogTimeout."""
    old = signal.signal(signal.SIGALRM, _on_alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        return fn()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


# --- value and identity decoding ------------------------------------------------------------------

def encode_value(v: int, width: int) -> bytes:
    """Little-endian INT/DINT; values above the signed range are sent as their unsigned bytes."""
    return (v & ((1 << (8 * width)) - 1)).to_bytes(width, "little")


def decode_value(data: bytes, width: int, unsigned: bool) -> Optional[int]:
    """The read value when the reply carries exactly `width` bytes, else None (see 'raw')."""
    if data is None or len(data) != width:
        return None
    return int.from_bytes(data, "little", signed=not unsigned)


def revision_fields(major: int, minor: int) -> Dict[str, Any]:
    return {"revision": f"{major}.{minor}", "revision_major": major, "revision_minor": minor}


def identity_dict(vendor_id, device_type, product_code, major, minor, status_word, serial,
                  product_name, **extra) -> Dict[str, Any]:
    d = {
        "vendor_id": vendor_id,
        "device_type": device_type,
        "product_code": product_code,
        **revision_fields(major, minor),
        "status_word": status_word,
        "serial": serial,
        "serial_hex": f"0x{serial:08x}" if isinstance(serial, int) else None,
        "product_name": product_name,
    }
    d.update(extra)
    return d


def decode_identity_attributes_all(data: bytes) -> Dict[str, Any]:
    """Identity object Get_Attributes_All reply data: attributes 1..7 (anything after is ignored)."""
    vendor, dtype, pcode, major, minor, status, serial = struct.unpack_from("<HHHBBHI", data, 0)
    n = data[14]
    name = data[15 : 15 + n]
    if len(name) != n:
        raise ValueError(f"product name truncated: length {n}, {len(name)} bytes present")
    return identity_dict(vendor, dtype, pcode, major, minor, status, serial,
                         name.decode("latin-1"), trailing=data[15 + n :].hex())


def decode_list_identity_cpf(cpf: bytes) -> Dict[str, Any]:
    """ListIdentity reply data (after the 24-byte encapsulation header): item count, then the
    first CIP Identity item (type 0x0C). Socket address fields are big-endian, the rest little."""
    (count,) = struct.unpack_from("<H", cpf, 0)
    if count < 1:
        raise ValueError("ListIdentity reply has no items")
    item_type, item_len, version = struct.unpack_from("<HHH", cpf, 2)
    sin_family, sin_port = struct.unpack_from(">hH", cpf, 8)
    sin_addr = socket.inet_ntoa(cpf[12:16])
    off = 2 + 4 + 2 + 16
    vendor, dtype, pcode, major, minor, status, serial = struct.unpack_from("<HHHBBHI", cpf, off)
    off += 14
    n = cpf[off]
    name = cpf[off + 1 : off + 1 + n]
    if len(name) != n:
        raise ValueError(f"product name truncated: length {n}, {len(name)} bytes present")
    off += 1 + n
    state = cpf[off] if off < len(cpf) else None
    return identity_dict(vendor, dtype, pcode, major, minor, status, serial, name.decode("latin-1"),
                         state=state, encap_protocol_version=version, item_type=item_type,
                         item_count=count, sin_family=sin_family, sin_port=sin_port,
                         sin_addr=sin_addr)


def ext_status_from_cip_reply(reply: bytes) -> List[int]:
    """Additional status words of a CIP reply (service, reserved, general status, size, words...)."""
    if reply is None or len(reply) < 4:
        return []
    n = reply[3]
    return [int.from_bytes(reply[4 + 2 * k : 6 + 2 * k], "little") for k in range(n)
            if 6 + 2 * k <= len(reply)]


# --- driver loop ----------------------------------------------------------------------------------

def emit(result: Dict[str, Any]) -> None:
    sys.stdout.write(json.dumps(result, sort_keys=False) + "\n")
    sys.stdout.flush()


def run_all(cfg: Config, client_name: str, open_session: Callable[[], Any],
            close_session: Callable[[Any], None],
            do_op: Callable[[Any, Op, Dict[str, Any]], bool]) -> int:
    """Run every op; one JSON line each. do_op fills the result and returns True if the session is
    still usable afterwards. Each op (plus the connect it may need) is bounded by cfg.timeout via
    SIGALRM; transport failures close the session and the next op opens a new one. If connecting
    fails, the remaining ops are reported failed without another attempt (bounded total time)."""
    session = None
    connect_error: Optional[str] = None
    all_ok = True
    # The libraries' own socket timeouts are cfg.timeout; the watchdog is the backstop for
    # anything that loops or waits outside them (e.g. pycomm3's receive loop on a half frame).
    hard = cfg.timeout + WATCHDOG_GRACE
    for op in cfg.ops:
        res = op.base_result()
        res["client"] = client_name
        t0 = time.monotonic()
        if connect_error is not None:
            res["error"] = f"not attempted: {connect_error}"
        else:
            try:
                if session is None:
                    try:
                        session = run_bounded(hard, open_session)
                    except WatchdogTimeout:
                        raise ConnectFailed(f"connect/RegisterSession timed out after {hard:g}s")
                    except Exception as e:
                        raise ConnectFailed(f"connect/RegisterSession failed: {describe_exc(e)}")
                keep = run_bounded(hard, lambda: do_op(session, op, res))
                if not keep:
                    close_session(session)
                    session = None
            except ConnectFailed as e:
                connect_error = str(e)
                res["error"] = connect_error
            except WatchdogTimeout:
                res["ok"] = False
                res["error"] = f"timeout: no complete reply within {hard:g}s"
                _safe_close(close_session, session)
                session = None
            except Exception as e:  # anything the library raised: report, reconnect for the next op
                res["ok"] = False
                res["error"] = res.get("error") or describe_exc(e)
                _safe_close(close_session, session)
                session = None
        res["elapsed_ms"] = round((time.monotonic() - t0) * 1000, 1)
        all_ok = all_ok and bool(res["ok"])
        emit(res)
    _safe_close(close_session, session)
    return 1 if (cfg.strict and not all_ok) else 0


def describe_exc(e: BaseException) -> str:
    """'Type: message <- Cause: message ...' (pycomm3 wraps socket errors in CommError twice)."""
    parts, seen = [], set()
    while e is not None and id(e) not in seen and len(parts) < 4:
        seen.add(id(e))
        parts.append(f"{type(e).__name__}: {e}".rstrip(": "))
        e = e.__cause__ or e.__context__
    return " <- ".join(parts)


def _safe_close(close_session, session) -> None:
    if session is None:
        return
    try:
        run_bounded(2.0, lambda: close_session(session))
    except BaseException:
        pass
