//! The segment as an [`Endpoint`]: a frame on the bus to [`Segment::receive`], what the nodes
//! send on their own (boot-up, heartbeats, EMCY) from [`Segment::poll`] when due.

use std::time::Duration;

use super::Segment;
use crate::endpoint::{Endpoint, Input, Output, Raised};

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

    fn raise_alarm(&mut self, now: Duration) -> Option<Raised> {
        let (what, frames) = self.spurious_emergency(now)?;
        Some(Raised {
            what,
            outputs: frames.into_iter().map(Output::Can).collect(),
        })
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

    #[test]
    fn a_raised_alarm_is_an_emcy_of_an_error_the_inverter_does_not_have() {
        let mut segment = Segment::new(DeviceConfig::new(Product::Sk550p)).unwrap();
        // In Initialisation no node may send EMCY.
        assert_eq!(segment.raise_alarm(Duration::ZERO), None);
        let now = Duration::from_secs(1);
        segment.poll(now);
        let raised = segment
            .raise_alarm(now)
            .expect("pre-operational nodes send EMCY");
        assert_eq!(
            raised.outputs,
            vec![Output::Can(
                CanFrame::new(0x0A0, &[0x80, 0x75, 0x11, 100, 0, 1, 0, 0]).unwrap()
            )]
        );
        assert!(
            raised.what.starts_with("EMCY 7580h from node 32"),
            "{}",
            raised.what
        );
        // The node's error register says so: 1001h reads 11h.
        let read = CanFrame::new(0x620, &[0x40, 0x01, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        let answer = segment.receive(&read, now);
        assert_eq!(answer[0].data()[..5], [0x4F, 0x01, 0x10, 0x00, 0x11]);
    }
}
