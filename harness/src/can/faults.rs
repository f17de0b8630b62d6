//! What `harness serve can --misbehave` can do on the system bus ([`crate::net::misbehave`]):
//! every mode the serve driver has on the nodes' frames; `alarm=`, an EMCY of an error no
//! inverter has (`sim::can::Segment::spurious_emergency`); and two fields of the SDO server's
//! segmented uploads (CiA 301 §7.2.4.3.4–5), parsed and emitted anew with
//! [`proto::canopen::SdoResponse`]: `sequence`, each upload segment's toggle bit not
//! alternated; `length`, the size an initiate-upload answer announces 100 bytes more than
//! the segments carry. No session to close: the socketcand connection is the bus's cable, not
//! the device's.

use proto::can::CanFrame;
use proto::canopen::sdo::InitiateData;
use proto::canopen::SdoResponse;
use sim::endpoint::Output;

use crate::net::misbehave::{BusFaults, Field};

/// What the system bus can do of a spec.
pub(crate) const FAULTS: BusFaults = BusFaults {
    bus: "the system bus",
    fields: &[Field::Sequence, Field::Length],
    no_close: Some(
        "has no session to close (CAN frames; a socketcand connection is the bus's cable): use silent= or drop=",
    ),
    no_alarm: None,
};

/// What the announced size of a segmented upload grows by under `corrupt=length`.
const MORE: u32 = 100;

/// Sets `field` wrong in `out` if it is an SDO answer that carries it; what it changed.
pub(crate) fn corrupt(field: Field, out: &mut Output) -> Option<String> {
    let Output::Can(frame) = out else {
        return None;
    };
    if !(0x581..=0x5FF).contains(&frame.id()) || frame.is_remote() {
        return None;
    }
    let response = SdoResponse::parse(frame.data()).ok()?;
    let (changed, what) = match (field, response) {
        (Field::Sequence, SdoResponse::UploadSegment { toggle, last, data }) => (
            SdoResponse::UploadSegment {
                toggle: !toggle,
                last,
                data,
            },
            format!(
                "upload segment toggle bit {} → {}",
                u8::from(toggle),
                u8::from(!toggle)
            ),
        ),
        (
            Field::Length,
            SdoResponse::InitiateUpload {
                index,
                sub,
                data: InitiateData::Segmented { size: Some(n) },
            },
        ) => (
            SdoResponse::InitiateUpload {
                index,
                sub,
                data: InitiateData::Segmented {
                    size: Some(n.saturating_add(MORE)),
                },
            },
            format!(
                "{index:04X}h:{sub:02X}h upload size {n} → {}",
                n.saturating_add(MORE)
            ),
        ),
        _ => return None,
    };
    *frame = CanFrame::new(frame.id(), &changed.emit()).ok()?;
    Some(what)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::canopen::sdo::SegmentData;

    fn answer(r: SdoResponse) -> Output {
        Output::Can(CanFrame::new(0x5A0, &r.emit()).unwrap())
    }

    #[test]
    fn the_toggle_bit_and_the_announced_size_are_sent_wrong() {
        let segment = |toggle| SdoResponse::UploadSegment {
            toggle,
            last: false,
            data: SegmentData::new(b"SK 550P").unwrap(),
        };
        let mut out = answer(segment(false));
        assert_eq!(
            corrupt(Field::Sequence, &mut out).as_deref(),
            Some("upload segment toggle bit 0 → 1")
        );
        assert_eq!(out, answer(segment(true)));
        let initiate = |n| SdoResponse::InitiateUpload {
            index: 0x1008,
            sub: 0,
            data: InitiateData::Segmented { size: Some(n) },
        };
        let mut out = answer(initiate(7));
        assert_eq!(
            corrupt(Field::Length, &mut out).as_deref(),
            Some("1008h:00h upload size 7 → 107")
        );
        assert_eq!(out, answer(initiate(107)));
    }

    #[test]
    fn what_does_not_carry_the_field_is_left_as_it_was() {
        // An expedited answer has no announced size to lie about; a segment, no size.
        let expedited = SdoResponse::parse(&[0x4F, 0x01, 0x10, 0x00, 0x11, 0, 0, 0]).unwrap();
        let mut out = answer(expedited);
        let before = out.clone();
        assert_eq!(corrupt(Field::Length, &mut out), None);
        assert_eq!(corrupt(Field::Sequence, &mut out), None);
        assert_eq!(corrupt(Field::Wkc, &mut out), None);
        assert_eq!(out, before);
        // Not an SDO answer: a heartbeat of node 32.
        let mut heartbeat = Output::Can(CanFrame::new(0x720, &[0x7F]).unwrap());
        assert_eq!(corrupt(Field::Sequence, &mut heartbeat), None);
    }
}
