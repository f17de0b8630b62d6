//! What `harness serve enip --misbehave` can do on EtherNet/IP ([`crate::net::misbehave`]):
//! `close` (each TCP connection closed, unanswered, at its first request after
//! RegisterSession: [`super::serve_tcp`]) and one field to send wrong, `status`: the CIP general
//! status of every explicit reply (SendRRData's unconnected, SendUnitData's connected data)
//! becomes 08h "service not supported", parsed and emitted anew with the encapsulation, CPF
//! and message-router codecs; `length`: the encapsulation header's length of the same replies
//! [`PAST`] bytes past the data that follows, set through the checked view
//! ([`proto::enip::encap::EncapFrame::set_length`]). On TCP that length is the only framing,
//! so the scanner waits for bytes that never come; `sequence`: the sequence number of every
//! class-1 T→O frame's sequenced address item stands at 1 (the CIP sequence count in its data
//! goes on), so the scanner, as consumer, discards them as not new.

use proto::enip::cip::{GeneralStatus, MrResponse};
use proto::enip::cpf::{Cpf, Item};
use proto::enip::encap::{Command, EncapFrame, EncapRepr, SendData};
use proto::enip::io::IO_PORT;
use sim::endpoint::Output;

use crate::net::misbehave::{BusFaults, Field};

/// What EtherNet/IP can do of a spec.
pub(crate) const FAULTS: BusFaults = BusFaults {
    bus: "EtherNet/IP",
    fields: &[Field::Status, Field::Length, Field::Sequence],
    no_close: None,
    no_alarm: Some(
        "sends nothing unasked: explicit messaging only answers, and class-1 I/O carries no alarm",
    ),
};

/// How far past the data that follows `corrupt=length` sets the header's length.
const PAST: u16 = 512;

/// Sets `field` wrong in `out` if it is an explicit reply (`status`, `length`) or a class-1
/// T→O frame (`sequence`); what it changed.
pub(crate) fn corrupt(field: Field, out: &mut Output) -> Option<String> {
    let bytes = match (field, out) {
        (Field::Sequence, Output::Datagram { port, bytes, .. }) if *port == IO_PORT => {
            return sequence(bytes);
        }
        (_, Output::Message { bytes, .. }) => bytes,
        _ => return None,
    };
    let explicit = EncapFrame::new_checked(bytes.as_slice())
        .is_ok_and(|f| matches!(f.command(), Command::SEND_RR_DATA | Command::SEND_UNIT_DATA));
    if !explicit {
        return None;
    }
    match field {
        Field::Status => status(bytes),
        Field::Length => {
            let mut frame = EncapFrame::new_checked(bytes.as_mut_slice()).ok()?;
            let was = frame.length();
            let wrong = was.saturating_add(PAST);
            frame.set_length(wrong);
            Some(format!("encapsulation length {was} → {wrong}"))
        }
        _ => None,
    }
}

/// Where `corrupt=sequence` holds the T→O sequence number: the first frame is taken, every
/// later one is no number past it.
const STANDING: u32 = 1;

/// The sequenced address item's sequence number of a class-1 frame [`STANDING`].
fn sequence(bytes: &mut Vec<u8>) -> Option<String> {
    let mut cpf = Cpf::parse(bytes).ok()?;
    let Some(Item::SequencedAddress { sequence, .. }) = cpf.items.first_mut() else {
        return None;
    };
    let was = std::mem::replace(sequence, STANDING);
    if was == STANDING {
        return None;
    }
    *bytes = cpf.emit().ok()?;
    Some(format!("T→O sequence number {was} → {STANDING}"))
}

/// The CIP general status of an explicit reply 08h.
fn status(bytes: &mut Vec<u8>) -> Option<String> {
    let mut encap = EncapRepr::parse(bytes).ok()?;
    let mut send = SendData::parse(&encap.data).ok()?;
    let (data, at) = send.cpf.items.iter_mut().find_map(|i| match i {
        Item::UnconnectedData(d) => Some((d, 0)),
        // Connected data starts with its 2-byte sequence count.
        Item::ConnectedData(d) => Some((d, 2)),
        _ => None,
    })?;
    let mut mr = MrResponse::parse(data.get(at..)?).ok()?;
    let was = mr.general;
    mr.general = GeneralStatus::SERVICE_NOT_SUPPORTED.0;
    data.truncate(at);
    data.extend(mr.emit());
    encap.data = send.emit().ok()?;
    *bytes = encap.emit().ok()?;
    Some(format!("general status {was:02X}h → 08h"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::enip::cpf::Cpf;

    /// A SendRRData reply: a null address item and an unconnected data item holding a
    /// Get_Attribute_Single (0Eh) success reply with data 2Ah 00h.
    fn reply(item: Item) -> Output {
        let send = SendData {
            interface: 0,
            timeout: 0,
            cpf: Cpf::new(vec![Item::Null, item]),
        };
        let encap = EncapRepr {
            command: Command::SEND_RR_DATA.0,
            session: 7,
            data: send.emit().unwrap(),
            ..EncapRepr::default()
        };
        Output::Message {
            client: 1,
            bytes: encap.emit().unwrap(),
        }
    }

    fn mr(out: &Output, at: usize) -> MrResponse {
        let Output::Message { bytes, .. } = out else {
            panic!()
        };
        let send = SendData::parse(&EncapRepr::parse(bytes).unwrap().data).unwrap();
        match &send.cpf.items[1] {
            Item::UnconnectedData(d) | Item::ConnectedData(d) => {
                MrResponse::parse(&d[at..]).unwrap()
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn an_explicit_reply_says_service_not_supported_and_keeps_its_data() {
        let ok = MrResponse::ok(0x0E, vec![0x2A, 0]);
        let mut out = reply(Item::UnconnectedData(ok.emit()));
        assert_eq!(
            corrupt(Field::Status, &mut out).as_deref(),
            Some("general status 00h → 08h")
        );
        assert_eq!(
            mr(&out, 0),
            MrResponse {
                general: 0x08,
                ..ok.clone()
            }
        );
        // Connected: after the sequence count, which stays.
        let mut data = vec![5, 0];
        data.extend(ok.emit());
        let mut out = reply(Item::ConnectedData(data));
        assert!(corrupt(Field::Status, &mut out).is_some());
        assert_eq!(mr(&out, 2).general, 0x08);
    }

    #[test]
    fn length_points_past_the_reply_and_keeps_its_bytes() {
        let before = reply(Item::UnconnectedData(
            MrResponse::ok(0x0E, vec![0x2A, 0]).emit(),
        ));
        let Output::Message { bytes: b, .. } = &before else {
            unreachable!()
        };
        let data = b.len() - 24;
        let mut out = before.clone();
        assert_eq!(
            corrupt(Field::Length, &mut out),
            Some(format!("encapsulation length {data} → {}", data + 512))
        );
        let Output::Message { bytes: a, .. } = &out else {
            unreachable!()
        };
        // Bytes 2–3 only: a reader takes 512 more bytes to belong to it than follow.
        assert_eq!(a.len(), b.len());
        assert_eq!(a[..2], b[..2]);
        assert_eq!(a[4..], b[4..]);
        assert_eq!(proto::enip::encap::frame_len(a), Some(b.len() + 512));
    }

    #[test]
    fn sequence_stands_at_1_in_t_o_frames_only() {
        use proto::enip::io::IoFrame;
        let frame = |sequence| IoFrame {
            connection: 0x1234,
            sequence,
            count: 9,
            run_idle: None,
            data: vec![1, 2, 3, 4],
        };
        let io = |bytes, port| Output::Datagram {
            port,
            to: "127.0.0.1:2222".parse().unwrap(),
            bytes,
        };
        let mut out = io(frame(5).emit().unwrap(), IO_PORT);
        assert_eq!(
            corrupt(Field::Sequence, &mut out).as_deref(),
            Some("T→O sequence number 5 → 1")
        );
        assert_eq!(
            out,
            io(frame(1).emit().unwrap(), IO_PORT),
            "nothing else moved"
        );
        // At 1 already; a datagram from the encapsulation port; an explicit reply.
        assert_eq!(corrupt(Field::Sequence, &mut out), None);
        let mut other = io(frame(5).emit().unwrap(), 44818);
        assert_eq!(corrupt(Field::Sequence, &mut other), None);
        let mut explicit = reply(Item::UnconnectedData(MrResponse::ok(0x0E, vec![]).emit()));
        assert_eq!(corrupt(Field::Sequence, &mut explicit), None);
    }

    #[test]
    fn other_messages_and_fields_are_left_alone() {
        let register = Output::Message {
            client: 1,
            bytes: EncapRepr {
                command: Command::REGISTER_SESSION.0,
                data: vec![1, 0, 0, 0],
                ..EncapRepr::default()
            }
            .emit()
            .unwrap(),
        };
        for field in [Field::Status, Field::Length] {
            let mut out = register.clone();
            assert_eq!(corrupt(field, &mut out), None);
            assert_eq!(out, register);
        }
        let mut out = reply(Item::UnconnectedData(MrResponse::ok(0x0E, vec![]).emit()));
        assert_eq!(corrupt(Field::Wkc, &mut out), None);
    }
}
