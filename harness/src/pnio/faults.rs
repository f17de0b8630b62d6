//! What `harness serve pnio --misbehave` can do on PROFINET IO ([`crate::net::misbehave`]):
//! no session to close (the AR is the controller's to end, the RPC is connectionless UDP), and
//! two fields of the cyclic frames the device sends ([`proto::pnio::rt::RtRepr`], parsed and
//! emitted anew): `cycle` (the cycle counter stands still at 0: a provider that no longer
//! updates its data) and `data-status` (DataValid cleared: the data is not valid).

use proto::pnio::rt::{DataStatus, RtRepr};
use proto::pnio::{FrameId, FrameKind};
use sim::endpoint::Output;

use crate::net::inject::rewrite_payload;
use crate::net::misbehave::{BusFaults, Field};

/// What PROFINET IO can do of a spec.
pub(crate) const FAULTS: BusFaults = BusFaults {
    bus: "PROFINET IO",
    fields: &[Field::Cycle, Field::DataStatus],
    no_close: Some(
        "has no session to close (cyclic frames on raw Ethernet, RPC over UDP): use silent= or drop=",
    ),
    no_alarm: Some("raises no alarm yet (not built)"),
};

/// Sets `field` wrong in `out` if it is a cyclic (RT) frame; what it changed.
pub(crate) fn corrupt(field: Field, out: &mut Output) -> Option<String> {
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
