//! What `harness serve ecat --misbehave` can do on EtherCAT ([`crate::net::misbehave`]): no
//! session to close (raw Ethernet), and two fields to send wrong, set through the frame's
//! checked views ([`proto::ecat::EcatFrame`], [`proto::ecat::Datagram`]) as negative tests break
//! frames: `wkc` (every datagram's working counter 0: as if no slave had processed it),
//! `length` (the EtherCAT header's length 2047, past the frame's end) and `sequence` (the
//! mailbox header's counter of every message the master reads from the send mailbox stands at
//! 1, so that from the second on each has the counter of the one before: a repeat,
//! ETG.1000.6 §5.6 "Cnt"). `alarm=` puts a CoE
//! emergency for an error the inverter does not have into the slave's send mailbox
//! (`sim::ecat::Slave::raise_spurious_emergency`).

use proto::ecat::mailbox::Mailbox;
use proto::ecat::{Command, EcatFrame};
use proto::eth::EthernetFrame;
use proto::nord::ecat::SM_MAILBOX_IN;
use sim::endpoint::Output;

use crate::net::misbehave::{BusFaults, Field};

/// What EtherCAT can do of a spec.
pub(crate) const FAULTS: BusFaults = BusFaults {
    bus: "EtherCAT",
    fields: &[Field::Wkc, Field::Length, Field::Sequence],
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
        Field::Sequence => {
            let mut changed = Vec::new();
            for d in &mut frame.datagrams_mut().ok()? {
                let reads_sm1 = matches!(d.command(), Command::FPRD | Command::APRD)
                    && d.ado() == SM_MAILBOX_IN.start
                    && d.wkc() > 0;
                if !reads_sm1 {
                    continue;
                }
                let Ok(mut m) = Mailbox::new_checked(d.data_mut()) else {
                    continue;
                };
                let was = m.counter();
                if was > 1 {
                    m.set_counter(STANDING);
                    changed.push(was);
                }
            }
            let was: Vec<String> = changed.iter().map(u8::to_string).collect();
            (!was.is_empty()).then(|| format!("mailbox counter {} → {STANDING}", was.join("/")))
        }
        _ => None,
    }
}

/// Where `corrupt=sequence` holds the send mailbox's counter (the first a slave's mailbox
/// gives, so the first answer is new and every later one a repeat).
const STANDING: u8 = 1;

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

    /// An FPRD of the send mailbox (1080h, 128 bytes) as the slave sends it back: a CoE
    /// message with counter `counter`; beside it an FPRD of the AL status with the same bytes.
    fn mailbox_read(counter: u8) -> Vec<u8> {
        use proto::ecat::mailbox::{MailboxRepr, MailboxType};
        let mut data = MailboxRepr::new(MailboxType::COE, counter, vec![0, 0x30, 0x43])
            .emit()
            .unwrap();
        data.resize(128, 0);
        let d = |ado, data: Vec<u8>| DatagramRepr {
            wkc: 1,
            ..DatagramRepr::physical(Command::FPRD, 0, 0x1001, ado, data)
        };
        EcatFrameRepr::new(vec![d(0x1080, data.clone()), d(0x0130, data)])
            .emit_ethernet(MacAddr([0xFF; 6]), MacAddr([3, 1, 1, 1, 1, 1]))
            .unwrap()
    }

    #[test]
    fn sequence_holds_the_send_mailboxs_counter_at_1() {
        let mut out = Output::Frame(mailbox_read(3));
        assert_eq!(
            corrupt(Field::Sequence, &mut out).as_deref(),
            Some("mailbox counter 3 → 1")
        );
        let after = parsed(&out).unwrap();
        let counter = |d: &DatagramRepr| d.data[5] >> 4 & 0x07;
        assert_eq!(counter(&after.datagrams[0]), 1);
        // Only the mailbox header's counter changed; the read of another register is left.
        let before = parsed(&Output::Frame(mailbox_read(3))).unwrap();
        assert_eq!(after.datagrams[0].data[..5], before.datagrams[0].data[..5]);
        assert_eq!(after.datagrams[0].data[6..], before.datagrams[0].data[6..]);
        assert_eq!(after.datagrams[1], before.datagrams[1]);
        // A counter at 1 already, or an empty mailbox (working counter 0): nothing to do.
        assert_eq!(
            corrupt(Field::Sequence, &mut Output::Frame(mailbox_read(1))),
            None
        );
        let mut empty = Output::Frame(frame());
        assert_eq!(corrupt(Field::Sequence, &mut empty), None);
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
