//! What `harness serve pnio --misbehave` can do on PROFINET IO ([`crate::net::misbehave`]):
//! no session to close (the AR is the controller's to end, the RPC is connectionless UDP),
//! two fields of the cyclic frames the device sends ([`proto::pnio::rt::RtRepr`], parsed and
//! emitted anew): `cycle` (the cycle counter stands still at 0: a provider that no longer
//! updates its data) and `data-status` (DataValid cleared: the data is not valid), and one of
//! its RPC responses ([`proto::pnio::rpc::NdrResponse`]): `status` (the PNIO status of every
//! Connect, Release, Control, Read and Write response an error: its service's ErrorCode, then
//! 81 40 06, "PNIO, CMRPC: state conflict", as a device refuses a call its state does not
//! allow); and `sequence`, the SendSeqNum of every alarm DATA-RTA-PDU one ahead of the
//! alarm CR's (as if a PDU were lost). `alarm=` raises a process alarm on the alarm CR (`sim::pnio::IoDevice`'s
//! `Endpoint::raise_alarm`), which NORD's manuals never have the device send.

use proto::pnio::alarm::{AlarmRepr, RtaPduType};
use proto::pnio::rpc::{NdrResponse, Opnum, PacketType, RpcRepr};
use proto::pnio::rt::{DataStatus, RtRepr};
use proto::pnio::status::cm;
use proto::pnio::{FrameId, FrameKind, PnioStatus, RPC_PORT};
use sim::endpoint::Output;

use crate::net::inject::rewrite_payload;
use crate::net::misbehave::{BusFaults, Field};

/// What PROFINET IO can do of a spec.
pub(crate) const FAULTS: BusFaults = BusFaults {
    bus: "PROFINET IO",
    fields: &[
        Field::Cycle,
        Field::DataStatus,
        Field::Status,
        Field::Sequence,
    ],
    no_close: Some(
        "has no session to close (cyclic frames on raw Ethernet, RPC over UDP): use silent= or drop=",
    ),
    no_alarm: None,
};

/// Sets `field` wrong in `out` if it is a cyclic (RT) frame, or for `status` an RPC
/// response; what it changed.
pub(crate) fn corrupt(field: Field, out: &mut Output) -> Option<String> {
    if field == Field::Status {
        return refuse(out);
    }
    if field == Field::Sequence {
        return skip_sequence(out);
    }
    if !matches!(field, Field::Cycle | Field::DataStatus) {
        return None;
    }
    rewrite_payload(out, |payload| {
        let id = FrameId(u16::from_be_bytes([*payload.first()?, *payload.get(1)?]));
        if id.kind() != FrameKind::Rt {
            return None;
        }
        let mut rt = RtRepr::parse(payload, None).ok()?;
        let what = if field == Field::Cycle {
            let was = rt.cycle_counter;
            rt.cycle_counter = 0;
            format!("cycle counter {was} → 0")
        } else {
            let was = rt.data_status;
            rt.data_status = was.with(DataStatus::DATA_VALID, false);
            format!(
                "data status {:02X}h → {:02X}h (DataValid off)",
                was.0, rt.data_status.0
            )
        };
        Some((rt.emit(), what))
    })
}

/// Moves the SendSeqNum of an alarm DATA PDU one on (mod 8000h); what it changed.
fn skip_sequence(out: &mut Output) -> Option<String> {
    rewrite_payload(out, |payload| {
        let id = FrameId(u16::from_be_bytes([*payload.first()?, *payload.get(1)?]));
        if !matches!(id.kind(), FrameKind::Alarm { .. }) {
            return None;
        }
        let mut pdu = AlarmRepr::parse(payload).ok()?;
        if pdu.pdu_type != RtaPduType::DATA {
            return None;
        }
        let was = pdu.send_seq;
        pdu.send_seq = (was + 1) & 0x7FFF;
        let what = format!("alarm SendSeqNum {was} → {}", pdu.send_seq);
        Some((pdu.emit().ok()?, what))
    })
}

/// The ErrorCode of a refused call (IEC 61158-6-10 "ErrorCode": the response's service).
fn error_code(opnum: Opnum) -> Option<u8> {
    Some(match opnum {
        Opnum::CONNECT => cm::CONNECT,
        Opnum::RELEASE => cm::RELEASE,
        Opnum::CONTROL => cm::CONTROL,
        Opnum::READ | Opnum::READ_IMPLICIT => PnioStatus::CODE_READ,
        Opnum::WRITE => PnioStatus::CODE_WRITE,
        _ => return None,
    })
}

/// Sets the PNIO status of an RPC response from the device's port to "state conflict" of its
/// service; its blocks stay.
fn refuse(out: &mut Output) -> Option<String> {
    let Output::Datagram { port, bytes, .. } = out else {
        return None;
    };
    if *port != RPC_PORT {
        return None;
    }
    let mut rpc = RpcRepr::parse_bytes(bytes).ok()?;
    if rpc.packet_type != PacketType::RESPONSE {
        return None;
    }
    let code = error_code(rpc.opnum)?;
    let mut ndr = NdrResponse::parse(&rpc.body, rpc.drep).ok()?;
    let was = ndr.status;
    ndr.status = PnioStatus::cm(code, cm::CMRPC, cm::CMRPC_STATE_CONFLICT);
    rpc.body = ndr.emit(rpc.drep);
    *bytes = rpc.emit().ok()?;
    Some(format!(
        "{} response PNIO status {} → {}",
        rpc.opnum.name().unwrap_or("RPC"),
        was.meaning(),
        ndr.status.meaning()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::eth::{EthernetRepr, MacAddr, ETHERTYPE_PROFINET};

    /// An input CR's frame: frame id 8001h, a 40-byte C_SDU of 1…40, cycle counter 0140h,
    /// data status 35h (primary, valid, run, ok), transfer status 0.
    fn rt() -> RtRepr {
        RtRepr {
            frame_id: FrameId(0x8001),
            data: (1..=40).collect(),
            cycle_counter: 0x0140,
            data_status: DataStatus::GOOD,
            transfer_status: 0,
        }
    }

    fn frame(payload: &[u8]) -> Output {
        Output::Frame(
            EthernetRepr {
                dst: MacAddr([0x02, 0, 0, 0, 0, 1]),
                src: MacAddr([0x00, 0x09, 0xE5, 0, 0, 1]),
                ethertype: ETHERTYPE_PROFINET,
            }
            .emit(payload),
        )
    }

    fn parsed(out: &Output) -> RtRepr {
        let Output::Frame(b) = out else { panic!() };
        RtRepr::parse(&b[14..], None).unwrap()
    }

    #[test]
    fn cycle_stops_the_counter_and_keeps_the_data() {
        let mut out = frame(&rt().emit());
        assert_eq!(
            corrupt(Field::Cycle, &mut out).as_deref(),
            Some("cycle counter 320 → 0")
        );
        assert_eq!(
            parsed(&out),
            RtRepr {
                cycle_counter: 0,
                ..rt()
            }
        );
    }

    #[test]
    fn data_status_clears_data_valid_only() {
        let mut out = frame(&rt().emit());
        assert_eq!(
            corrupt(Field::DataStatus, &mut out).as_deref(),
            Some("data status 35h → 31h (DataValid off)")
        );
        let after = parsed(&out);
        assert!(!after.data_status.data_valid());
        assert_eq!(
            after,
            RtRepr {
                data_status: DataStatus(0x31),
                ..rt()
            }
        );
    }

    /// The device's answer to a call of `opnum`, with status OK and the blocks `data`, as a
    /// datagram from its RPC port.
    fn response(opnum: Opnum, packet_type: PacketType, data: &[u8]) -> Output {
        use proto::pnio::rpc::{Drep, NdrRequest, Uuid};
        let call = NdrRequest::new(4096, Vec::new()).unwrap();
        let body = NdrResponse::answering(&call, PnioStatus::OK, data.to_vec()).unwrap();
        let req = RpcRepr::request(
            Uuid::default(),
            Uuid::PNIO_DEVICE_INTERFACE,
            Uuid::default(),
            7,
            opnum,
            Vec::new(),
        );
        Output::Datagram {
            port: RPC_PORT,
            to: "192.168.22.200:34964".parse().unwrap(),
            bytes: req
                .reply(packet_type, body.emit(Drep::LITTLE_ENDIAN))
                .emit()
                .unwrap(),
        }
    }

    fn ndr_of(out: &Output) -> NdrResponse {
        let Output::Datagram { bytes, .. } = out else {
            panic!()
        };
        let rpc = RpcRepr::parse_bytes(bytes).unwrap();
        NdrResponse::parse(&rpc.body, rpc.drep).unwrap()
    }

    #[test]
    fn status_refuses_each_call_with_its_services_error_code_and_keeps_the_blocks() {
        for (opnum, code) in [
            (Opnum::CONNECT, 0xDB),
            (Opnum::RELEASE, 0xDC),
            (Opnum::CONTROL, 0xDD),
            (Opnum::READ, 0xDE),
            (Opnum::READ_IMPLICIT, 0xDE),
            (Opnum::WRITE, 0xDF),
        ] {
            let mut out = response(opnum, PacketType::RESPONSE, &[1, 2, 3]);
            let what = corrupt(Field::Status, &mut out).expect("a response is refused");
            let ndr = ndr_of(&out);
            assert_eq!(ndr.status.to_bytes(), [code, 0x81, 0x40, 0x06], "{opnum:?}");
            assert_eq!(ndr.data, [1, 2, 3]);
            assert!(
                what.contains(&format!("OK → {code:02X} 81 40 06: ")),
                "{what}"
            );
        }
        let mut out = response(Opnum::CONNECT, PacketType::RESPONSE, &[]);
        assert_eq!(
            corrupt(Field::Status, &mut out).as_deref(),
            Some(
                "Connect response PNIO status 00 00 00 00: OK → DB 81 40 06: IODConnectRes, \
                 PNIO: CMRPC: state conflict"
            )
        );
    }

    #[test]
    fn status_leaves_rejects_frames_and_other_ports_alone() {
        // A reject carries an NCA status, not a PNIO status.
        let reject = response(Opnum::CONNECT, PacketType::REJECT, &[]);
        let mut out = reject.clone();
        assert_eq!(corrupt(Field::Status, &mut out), None);
        assert_eq!(out, reject);
        let mut out = frame(&rt().emit());
        assert_eq!(corrupt(Field::Status, &mut out), None);
        let Output::Datagram { bytes, to, .. } = response(Opnum::READ, PacketType::RESPONSE, &[])
        else {
            panic!()
        };
        let mut out = Output::Datagram {
            port: 1234,
            to,
            bytes,
        };
        assert_eq!(corrupt(Field::Status, &mut out), None);
    }

    #[test]
    fn sequence_moves_an_alarm_data_pdus_send_seq_num_on_and_leaves_acks() {
        use proto::pnio::alarm::{AlarmNotification, AlarmSpecifier, AlarmType, RtaBody};
        let n = AlarmNotification {
            high: false,
            alarm_type: AlarmType::PROCESS,
            api: 0,
            slot: 3,
            subslot: 1,
            module_ident: 7,
            submodule_ident: 7,
            specifier: AlarmSpecifier(0),
            items: Vec::new(),
        };
        let data = AlarmRepr::data(3, 1, 0x7FFF, 0xFFFE, RtaBody::Notification(n));
        let mut out = frame(&data.emit().unwrap());
        assert_eq!(
            corrupt(Field::Sequence, &mut out).as_deref(),
            Some("alarm SendSeqNum 32767 → 0")
        );
        let Output::Frame(b) = &out else { panic!() };
        assert_eq!(
            AlarmRepr::parse(&b[14..]).unwrap(),
            AlarmRepr {
                send_seq: 0,
                ..data
            }
        );
        let ack = frame(
            &AlarmRepr::ack(FrameId::ALARM_LOW, 3, 1, 0, 0)
                .emit()
                .unwrap(),
        );
        let mut out = ack.clone();
        assert_eq!(corrupt(Field::Sequence, &mut out), None);
        assert_eq!(out, ack);
        let mut out = frame(&rt().emit());
        assert_eq!(corrupt(Field::Sequence, &mut out), None);
    }

    #[test]
    fn dcp_and_other_fields_are_left_alone() {
        // A DCP Identify response's frame id, FEFFh, and a few bytes.
        let dcp = frame(&[0xFE, 0xFF, 0x05, 0x01, 0, 0, 0, 1]);
        let mut out = dcp.clone();
        assert_eq!(corrupt(Field::Cycle, &mut out), None);
        assert_eq!(out, dcp);
        let mut out = frame(&rt().emit());
        assert_eq!(corrupt(Field::Wkc, &mut out), None);
    }
}
