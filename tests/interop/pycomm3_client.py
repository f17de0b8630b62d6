#!/usr/bin/env python3
"""EtherNet/IP explicit messaging through pycomm3's CIPDriver (unconnected, UCMM).

    python pycomm3_client.py [HOST:PORT] [--host H] [--port P] [--timeout S] [--dint] [--unsigned]
                             OP...   (get C I A | set C I A V | identity | identity-object)

One JSON line per operation on stdout (see README.md). Exit code 0 when every operation ran (CIP
errors included), 1 with --strict if any operation was not ok, 2 for usage errors, 3 if pycomm3
is not installed (run .ci/interop-setup and use its venv's python).

pycomm3 notes (checked against pycomm3 1.2.16's source and on the wire with tshark):
- CIPDriver.open() = TCP connect + RegisterSession only. It never sends Forward_Open; pycomm3
  only does that for connected=True messages (and LogixDriver's tag services), so every request
  here is a SendRRData/UCMM message with connected=False, unconnected_send=False, route_path=False.
- Instance 0 is encoded correctly (logical segment 24 00). Attribute 0 is NOT: request_path() does
  `if attribute:` and silently drops a falsy attribute from the path, so we pass attribute 0 as
  b"\\x00", which pycomm3 encodes as the 8-bit segment 30 00.
"""

import os
import sys

sys.dont_write_bytecode = True  # keep tests/interop free of __pycache__
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interop_common as ic  # noqa: E402

try:
    import pycomm3
    from pycomm3 import CIPDriver, ModuleIdentityObject
    from pycomm3.packets import ListIdentityRequestPacket
except ImportError as _e:  # pragma: no cover
    sys.stderr.write(f"pycomm3 is not importable ({_e}); run .ci/interop-setup and use "
                     f"${{INTEROP_VENV:-target/interop-venv}}/bin/python\n")
    sys.exit(3)

SVC_GET_ATTRIBUTES_ALL = 0x01
SVC_GET_ATTRIBUTE_SINGLE = 0x0E
SVC_SET_ATTRIBUTE_SINGLE = 0x10

CLIENT = f"pycomm3 {pycomm3.__version__}"


def jsonable(v):
    if isinstance(v, (bytes, bytearray)):
        return v.hex()
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if v is None or isinstance(v, (bool, int, float, str)):
        return v
    return str(v)


def make_session(cfg: ic.Config):
    def open_session():
        drv = CIPDriver(f"{cfg.host}:{cfg.port}")
        drv.socket_timeout = cfg.timeout  # used by open() for the socket it creates
        if not drv.open():
            try:
                drv.close()
            finally:
                raise RuntimeError("RegisterSession failed (no session handle in the reply)")
        return drv

    def close_session(drv):
        drv.close()  # UnRegisterSession (and Forward_Close only if a connection was open: never here)

    return open_session, close_session


def attribute_arg(attribute):
    if attribute is None:
        return b""  # no attribute segment (Get_Attributes_All)
    if attribute == 0:
        return b"\x00"  # pycomm3 drops a falsy attribute; bytes b"\x00" encodes as 30 00
    return attribute


def fill_from_reply(res, resp, service, tag_error):
    """Common fields from a pycomm3 SendRRData response packet. Returns the reply data or None."""
    raw = resp.raw or b""
    res["encap_status"] = resp.command_status
    cip = raw[40:] if len(raw) >= 44 else b""  # pycomm3 assumes the fixed 2-item CPF layout
    res["reply_service"] = cip[0] if cip else None
    res["status"] = resp.service_status
    res["ext_status"] = ic.ext_status_from_cip_reply(cip) if cip else []
    res["ok"] = bool(resp)  # pycomm3's verdict: encapsulation status 0 and general status 0
    if not res["ok"]:
        err = tag_error or resp.error or "unknown error"
        if resp.command_status not in (None, 0):
            err = f"encapsulation status 0x{resp.command_status:04x} (pycomm3: {err})"
        elif resp.service_status not in (None, 0):
            ext = res["ext_status"]
            err = (f"general status 0x{resp.service_status:02x}" + (f" ext {ext}" if ext else "")
                   + f" (pycomm3: {err})")
        res["error"] = err
        return None
    if res["reply_service"] != (service | 0x80):
        # pycomm3 does not check this; we do.
        res["ok"] = False
        res["error"] = f"reply service 0x{res['reply_service']:02x} does not answer 0x{service:02x}"
        return None
    return resp.data or b""


def do_op(cfg: ic.Config, drv, op: ic.Op, res) -> bool:
    if op.kind == "identity":
        return do_list_identity(drv, res)

    if op.kind == "get":
        service, data = SVC_GET_ATTRIBUTE_SINGLE, b""
    elif op.kind == "set":
        service, data = SVC_SET_ATTRIBUTE_SINGLE, ic.encode_value(op.value, cfg.width)
    else:  # identity-object
        service, data = SVC_GET_ATTRIBUTES_ALL, b""

    tag = drv.generic_message(
        service=service,
        class_code=op.cls,
        instance=op.instance,
        attribute=attribute_arg(op.attribute),
        request_data=data,
        connected=False,          # UCMM: no Forward_Open
        unconnected_send=False,   # no 0x52 Unconnected_Send wrapper (the adapter is the target)
        route_path=False,         # no route path appended
        name=op.kind,
        return_response_packet=True,  # Tag.value is the response packet: status, raw bytes
    )
    resp = tag.value
    reply = fill_from_reply(res, resp, service, tag.error)
    keep = resp.command_status == 0 and resp.service_status is not None
    if reply is None:
        return keep
    res["raw"] = reply.hex()
    if op.kind == "get":
        res["value"] = ic.decode_value(reply, cfg.width, cfg.unsigned)
    elif op.kind == "identity-object":
        try:
            res["identity"] = ic.decode_identity_attributes_all(reply)
        except Exception as e:
            res["ok"] = False
            res["error"] = f"cannot decode Identity attributes: {ic.describe_exc(e)}"
        try:
            res["pycomm3_identity"] = jsonable(ModuleIdentityObject.decode(reply))
        except Exception as e:
            res["pycomm3_identity"] = None
            res["pycomm3_error"] = ic.describe_exc(e)
    return keep


def do_list_identity(drv, res) -> bool:
    # CIPDriver.list_identity(path) is a classmethod that opens a second connection with pycomm3's
    # fixed 5 s default timeout and returns only a name-mapped dict; instead we send pycomm3's own
    # ListIdentityRequestPacket on this session through the public CIPDriver.send().
    resp = drv.send(ListIdentityRequestPacket())
    raw = resp.raw or b""
    res["encap_status"] = resp.command_status
    res["raw"] = raw[24:].hex()
    try:
        res["identity"] = ic.decode_list_identity_cpf(raw[24:])
    except Exception as e:
        res["identity"] = None
        res["error"] = f"cannot decode ListIdentity reply: {ic.describe_exc(e)}"
    res["pycomm3_identity"] = jsonable(resp.identity) if resp.identity else None
    res["ok"] = bool(resp) and res["identity"] is not None
    if not bool(resp):
        res["error"] = res["error"] or f"pycomm3: {resp.error}"
    return resp.command_status == 0


def main(argv=None) -> int:
    cfg = ic.parse_args("EtherNet/IP explicit messages via pycomm3 CIPDriver (unconnected).", argv)
    ic.setup_logging(cfg.verbose)
    open_session, close_session = make_session(cfg)
    return ic.run_all(cfg, CLIENT, open_session, close_session,
                      lambda drv, op, res: do_op(cfg, drv, op, res))


if __name__ == "__main__":
    sys.exit(main())
