#!/usr/bin/env python3
"""EtherNet/IP explicit messaging through cpppo's client (cpppo.server.enip.client.connector).

    python cpppo_client.py [HOST:PORT] [--host H] [--port P] [--timeout S] [--dint] [--unsigned]
                           OP...   (get C I A | set C I A V | identity | identity-object)

Same CLI and JSON lines as pycomm3_client.py (see README.md). Exit code 0 when every operation ran
(CIP errors included), 1 with --strict if any operation was not ok, 2 for usage errors, 3 if cpppo
is not installed (run .ci/interop-setup and use its venv's python).

cpppo notes (cpppo 5.2.5):
- connector(host, port, timeout) = TCP connect + RegisterSession; no Forward_Open.
- Requests are built with cpppo's own '@class/instance/attribute' syntax through
  get_attribute.attribute_operations ('@C/I/A' -> Get_Attribute_Single, '@C/I/A=(INT)v' ->
  Set_Attribute_Single, '@C/I' -> Get_Attributes_All).
- cpppo defaults to a *Logix route (Unconnected_Send 0x52 to @6/1 with route path 1/0). A NORD
  adapter is the target itself, so every operation passes route_path=False, send_path='' (plain
  SendRRData with the request directly in the UCMM item, same bytes as pycomm3 sends).
"""

import os
import sys

sys.dont_write_bytecode = True  # keep tests/interop free of __pycache__
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import interop_common as ic  # noqa: E402

cpppo, CLIENT = ic.import_peer("cpppo", "server.enip.client", "server.enip.get_attribute")
from cpppo.server.enip import client as enip_client  # noqa: E402
from cpppo.server.enip.get_attribute import attribute_operations  # noqa: E402

SERVICE_FOR = {"get": 0x0E, "set": 0x10, "identity-object": 0x01}


def make_session(cfg: ic.Config):
    def open_session():
        return enip_client.connector(host=cfg.host, port=cfg.port, timeout=cfg.timeout)

    def close_session(conn):
        conn.close()  # cpppo sends no UnRegisterSession; it just closes the TCP connection

    return open_session, close_session


def signed(v: int, width: int) -> int:
    """cpppo's INT/DINT producers pack signed; send values above the signed range as their
    two's-complement equivalent (same bytes on the wire)."""
    bits = 8 * width
    return v - (1 << bits) if v >= 1 << (bits - 1) else v


def cpppo_tag(cfg: ic.Config, op: ic.Op) -> str:
    if op.kind == "identity-object":
        return f"@{op.cls}/{op.instance}"
    path = f"@{op.cls}/{op.instance}/{op.attribute}"
    if op.kind == "get":
        return path
    typ = "DINT" if cfg.dint else "INT"
    return f"{path}=({typ}){signed(op.value, cfg.width)}"


def do_op(cfg: ic.Config, conn, op: ic.Op, res) -> bool:
    if op.kind == "identity":
        return do_list_identity(cfg, conn, res)

    tag = cpppo_tag(cfg, op)
    res["cpppo_request"] = tag
    ops = list(attribute_operations([tag], route_path=False, send_path=""))
    try:
        with conn:  # cpppo requires exclusive access to the connector while parsing replies
            results = list(conn.synchronous(operations=ops, timeout=cfg.timeout))
    except enip_client.ENIPStatusError as e:
        # Non-zero encapsulation status (cpppo raises before any CIP reply is parsed).
        res["encap_status"] = e.status
        res["error"] = f"encapsulation status 0x{e.status:04x} ({e})"
        return False
    if not results:
        res["error"] = (f"no reply: connection closed by the peer or nothing within "
                        f"{cfg.timeout:g}s")
        return False

    _idx, _descr, _req, rpy, sts, val = results[0]
    res["encap_status"] = 0
    res["reply_service"] = rpy.get("service")
    res["status"] = rpy.get("status")
    ext = []
    if "status_ext" in rpy and rpy.status_ext.size:
        ext = list(rpy.status_ext.data)
    res["ext_status"] = ext
    res["ok"] = res["status"] == 0
    if not res["ok"]:
        res["error"] = f"general status 0x{res['status']:02x}" + (f" ext {ext}" if ext else "")
        return True  # the session is still usable after a CIP error reply

    if op.kind == "set":
        res["raw"] = ""
        return True
    data = bytes(bytearray(val)) if isinstance(val, (list, tuple, bytes, bytearray)) else b""
    res["raw"] = data.hex()
    if op.kind == "get":
        res["value"] = ic.decode_value(data, cfg.width, cfg.unsigned)
    else:  # identity-object
        try:
            res["identity"] = ic.decode_identity_attributes_all(data)
        except Exception as e:
            res["ok"] = False
            res["error"] = f"cannot decode Identity attributes: {ic.describe_exc(e)}"
    return True


def do_list_identity(cfg: ic.Config, conn, res) -> bool:
    with conn:
        conn.list_identity(timeout=cfg.timeout)
        rsp, _elapsed = enip_client.await_response(conn, timeout=cfg.timeout)
    if rsp is None or not rsp:
        res["error"] = (f"no ListIdentity reply: connection closed by the peer or nothing within "
                        f"{cfg.timeout:g}s")
        return False
    res["encap_status"] = rsp.enip.status
    if rsp.enip.status != 0:
        res["error"] = f"encapsulation status 0x{rsp.enip.status:04x}"
        return False
    try:
        res["raw"] = bytes(rsp.enip.input).hex()
    except Exception:
        pass
    try:
        items = rsp.enip.CIP.list_identity.CPF.item
        item = items[0]
        io = item.identity_object
        rev = int(io.product_revision)  # cpppo keeps the revision as one UINT: major | minor << 8
        res["identity"] = ic.identity_dict(
            io.vendor_id, io.device_type, io.product_code, rev & 0xFF, rev >> 8, io.status_word,
            io.serial_number, io.product_name, state=io.get("state"),
            encap_protocol_version=io.get("version"), item_type=item.get("type_id"),
            item_count=len(items), sin_family=io.get("sin_family"), sin_port=io.get("sin_port"),
            sin_addr=io.get("sin_addr"))
    except Exception as e:
        res["identity"] = None
        res["error"] = f"cannot read cpppo's parsed ListIdentity reply: {ic.describe_exc(e)}"
        return True
    res["ok"] = True
    return True


def main(argv=None) -> int:
    cfg = ic.parse_args("EtherNet/IP explicit messages via cpppo's client (unconnected).", argv)
    ic.setup_logging(cfg.verbose)
    open_session, close_session = make_session(cfg)
    return ic.run_all(cfg, CLIENT, open_session, close_session,
                      lambda conn, op, res: do_op(cfg, conn, op, res))


if __name__ == "__main__":
    sys.exit(main())
