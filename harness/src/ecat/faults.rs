//! What `harness serve ecat --misbehave` can do on EtherCAT ([`crate::net::misbehave`]): no
//! session to close (raw Ethernet), and two fields to send wrong, set through the frame's
//! checked views ([`proto::ecat::EcatFrame`], [`proto::ecat::Datagram`]) as negative tests break
//! frames: `wkc` (every datagram's working counter 0: as if no slave had processed it) and
//! `length` (the EtherCAT header's length 2047, past the frame's end). `alarm=` puts a CoE
//! emergency for an error the inverter does not have into the slave's send mailbox
//! (`sim::ecat::Slave::raise_spurious_emergency`).

use proto::ecat::EcatFrame;
use proto::eth::EthernetFrame;
use sim::endpoint::Output;

use crate::net::misbehave::{BusFaults, Field};

/// What EtherCAT can do of a spec.
pub(crate) const FAULTS: BusFaults = BusFaults {
    bus: "EtherCAT",
    fields: &[Field::Wkc, Field::Length],
    no_close: Some("has no session to close (raw Ethernet frames): use silent= or drop="),
    no_alarm: None,
};

/// Sets `field` wrong in `out`, an EtherCAT frame; what it changed (`None`: not a frame that
/// parses, or not a field of EtherCAT).
pub(crate) fn corrupt(field: Field, out: &mut Output) -> Option<String> {
    let Output::Frame(bytes) = out else {
        return None;
    };
    let mut eth = EthernetFrame::new_checked(bytes.as_mut_slice()).ok()?;
    let mut frame = EcatFrame::new_checked(eth.inner_payload_mut()).ok()?;
    match field {
        Field::Wkc => {
            let mut datagrams = frame.datagrams_mut().ok()?;
            let was: Vec<String> = datagrams.iter().map(|d| d.wkc().to_string()).collect();
            for d in &mut datagrams {
                d.set_wkc(0);
            }
            Some(format!("working counter {} → 0", was.join("/")))
        }
        Field::Length => {
            let was = frame.len();
            frame.set_len(0x07FF);
            Some(format!("EtherCAT length {was} → 2047"))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::ecat::{Command, DatagramRepr, EcatFrameRepr};
    use proto::eth::MacAddr;

    /// A frame of two datagrams as a slave sends them back: an APRD of the AL status (0130h,
    /// 2 bytes, working counter 1) and a BRD (working counter 1).
    fn frame() -> Vec<u8> {
        let d = |command, ado| DatagramRepr {
            wkc: 1,
            ..DatagramRepr::physical(command, 0, 0, ado, vec![0; 2])
        };
        EcatFrameRepr::new(vec![d(Command::APRD, 0x130), d(Command::BRD, 0)])
            .emit_ethernet(MacAddr([0xFF; 6]), MacAddr([3, 1, 1, 1, 1, 1]))
            .unwrap()
    }

    fn parsed(out: &Output) -> Result<EcatFrameRepr, proto::wire::Error> {
        let Output::Frame(b) = out else { panic!() };
        EcatFrameRepr::parse_bytes(
            EthernetFrame::new_checked(b.as_slice())
                .unwrap()
                .inner_payload(),
        )
    }

    #[test]
    fn wkc_sets_every_working_counter_to_zero_and_keeps_the_rest() {
        let mut out = Output::Frame(frame());
        let before = parsed(&out).unwrap();
        assert_eq!(
            corrupt(Field::Wkc, &mut out).as_deref(),
            Some("working counter 1/1 → 0")
        );
        let after = parsed(&out).unwrap();
        assert!(after.datagrams.iter().all(|d| d.wkc == 0));
        let same = |r: &EcatFrameRepr| -> Vec<_> {
            r.datagrams
                .iter()
                .map(|d| (d.command, d.address, d.data.clone()))
                .collect()
        };
        assert_eq!(same(&after), same(&before));
    }

    #[test]
    fn length_points_past_the_frame_so_it_no_longer_parses() {
        let mut out = Output::Frame(frame());
        assert_eq!(
            corrupt(Field::Length, &mut out).as_deref(),
            Some("EtherCAT length 28 → 2047")
        );
        assert!(
            matches!(parsed(&out), Err(proto::wire::Error::Length { .. })),
            "{:?}",
            parsed(&out)
        );
    }

    #[test]
    fn what_is_not_an_ecat_frame_or_field_is_left_alone() {
        let mut short = Output::Frame(vec![0; 10]);
        assert_eq!(corrupt(Field::Wkc, &mut short), None);
        let mut out = Output::Frame(frame());
        assert_eq!(corrupt(Field::State, &mut out), None);
        assert_eq!(out, Output::Frame(frame()));
    }
}
