//! The segment as an [`Endpoint`]: a frame on the bus to [`Segment::receive`], what the nodes
//! send on their own (boot-up, heartbeats, EMCY) from [`Segment::poll`] when due.

use std::time::Duration;

use super::Segment;
use crate::endpoint::{Endpoint, Input, Output};

impl Endpoint for Segment {
    fn input(&mut self, input: Input<'_>, now: Duration) -> Vec<Output> {
        let Input::Can(frame) = input else {
            return Vec::new();
        };
        self.receive(frame, now)
            .into_iter()
            .map(Output::Can)
            .collect()
    }

    fn poll(&mut self, now: Duration) -> Vec<Output> {
        Segment::poll(self, now)
            .into_iter()
            .map(Output::Can)
            .collect()
    }

    fn next_deadline(&self) -> Option<Duration> {
        self.next_due()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::DeviceConfig;
    use proto::can::CanFrame;
    use proto::nord::Product;

    #[test]
    fn the_nodes_answer_as_they_answer_a_frame() {
        let config = DeviceConfig::new(Product::Sk550p);
        let mut by_trait = Segment::new(config).unwrap();
        let mut direct = Segment::new(config).unwrap();
        // NMT "start remote node" to all nodes (CiA 301 §7.2.8.3.1.1), then an SDO upload
        // request of 1000h:00h to node 32.
        let frames = [
            CanFrame::new(0x000, &[0x01, 0x00]).unwrap(),
            CanFrame::new(0x620, &[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]).unwrap(),
        ];
        for (i, f) in frames.iter().enumerate() {
            let now = Duration::from_millis(i as u64);
            let want: Vec<Output> = direct
                .receive(f, now)
                .into_iter()
                .map(Output::Can)
                .collect();
            assert_eq!(by_trait.input(Input::Can(f), now), want);
        }
        assert!(by_trait
            .input(Input::Frame(&[0; 60]), Duration::ZERO)
            .is_empty());
    }
}
