//! The slave as an [`Endpoint`]: an ESC processes a frame in place, on the fly, and the slave
//! is the last (and only) one on its segment, so what goes back out of its port 0 is the frame
//! it processed (ETG.1000.4 §5, "processing and forwarding"); a frame it destroys goes
//! nowhere.

use std::time::Duration;

use super::Slave;
use crate::endpoint::{Endpoint, Input, Output, Raised};

impl Endpoint for Slave {
    fn input(&mut self, input: Input<'_>, now: Duration) -> Vec<Output> {
        let Input::Frame(frame) = input else {
            return Vec::new();
        };
        let mut frame = frame.to_vec();
        if self.process(&mut frame, now).send_back() {
            vec![Output::Frame(frame)]
        } else {
            Vec::new()
        }
    }

    fn poll(&mut self, now: Duration) -> Vec<Output> {
        self.next_poll = Slave::poll(self, now);
        Vec::new()
    }

    fn next_deadline(&self) -> Option<Duration> {
        self.next_poll
    }

    /// A CoE emergency in the send mailbox ([`Slave::raise_spurious_emergency`]): the master
    /// fetches it, so nothing leaves now.
    fn raise_alarm(&mut self, now: Duration) -> Option<Raised> {
        let _ = now;
        self.raise_spurious_emergency().map(|what| Raised {
            what,
            outputs: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::{Device, DeviceConfig};
    use proto::nord::Product;

    fn slave() -> Slave {
        Slave::new(Device::new(DeviceConfig::new(Product::Sk550p))).unwrap()
    }

    /// A BRD of the AL status register (0130h, 2 bytes) in an EtherCAT frame from SOEM's
    /// source address.
    fn brd() -> Vec<u8> {
        let mut f = vec![0xFF; 6]; // destination: broadcast
        f.extend_from_slice(&[0x01; 6]); // source
        f.extend_from_slice(&super::super::ETHERTYPE.to_be_bytes());
        // EtherCAT header: length 14 (12 + 2 data), type 1 (ETG.1000.4 table 12).
        f.extend_from_slice(&(0x1000u16 | 14).to_le_bytes());
        // BRD (7), index 0, ADP 0, ADO 0130h, length 2, IRQ 0, data, WKC 0.
        f.extend_from_slice(&[7, 0, 0, 0, 0x30, 0x01, 2, 0, 0, 0, 0, 0, 0, 0]);
        f.resize(60, 0);
        f
    }

    #[test]
    fn what_goes_back_is_the_frame_processed_in_place() {
        let mut by_trait = slave();
        let out = by_trait.input(Input::Frame(&brd()), Duration::ZERO);
        let mut in_place = brd();
        assert!(slave().process(&mut in_place, Duration::ZERO).send_back());
        assert_eq!(out, vec![Output::Frame(in_place)]);
    }

    #[test]
    fn a_destroyed_frame_and_other_inputs_give_nothing() {
        let mut s = slave();
        let mut truncated = brd();
        truncated.truncate(20);
        assert!(s.input(Input::Frame(&truncated), Duration::ZERO).is_empty());
        assert!(s.input(Input::Closed(1), Duration::ZERO).is_empty());
    }

    #[test]
    fn the_deadline_is_what_the_last_poll_said() {
        let mut s = slave();
        assert_eq!(s.next_deadline(), None);
        let now = Duration::from_millis(5);
        assert!(Endpoint::poll(&mut s, now).is_empty());
        assert_eq!(s.next_deadline(), slave().poll(now));
    }
}
