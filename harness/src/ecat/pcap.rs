//! `--pcap` for EtherCAT: the frames of a run as they went over the segment, both ways.
//!
//! The master's frames are whole Ethernet frames (EtherType 88A4h), so the capture holds them
//! as they are, the slave's answers with the locally administered source address it sets; a
//! capture of the embedded slave looks like one taken on the wire.

use std::time::Duration;

use super::binding::DutSegment;
use super::master::{Arrival, Segment, SegmentError};
use crate::pcap::{SharedTap, Stamper};
use sim::ecat::Slave;

/// What the interface description names as the source of these frames.
const SOURCE: &str = "EtherCAT frames of a harness run (master and slave, as on the wire)";

/// A segment whose traffic also goes to the run's capture, stamped on the run's time line.
#[derive(Debug)]
pub(crate) struct Tapped<S> {
    inner: S,
    stamper: Stamper,
}

impl<S: Segment> Tapped<S> {
    /// `inner`, recorded into `tap` from now on.
    pub(crate) fn new(inner: S, tap: SharedTap) -> Tapped<S> {
        let stamper = Stamper::new(tap, SOURCE, inner.now());
        Tapped { inner, stamper }
    }

    fn record(&self, frame: &[u8]) {
        self.stamper
            .record(self.inner.now(), |c, at| c.frame(frame, at));
    }
}

impl<S: Segment> Segment for Tapped<S> {
    fn now(&self) -> Duration {
        self.inner.now()
    }

    fn real_time(&self) -> bool {
        self.inner.real_time()
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), SegmentError> {
        self.record(frame);
        self.inner.send(frame)
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        deadline: Duration,
    ) -> Result<Option<Arrival>, SegmentError> {
        let r = self.inner.recv(buf, deadline)?;
        if let Some(a) = &r {
            self.record(&buf[..a.len]);
        }
        Ok(r)
    }

    fn wait_until(&mut self, until: Duration) {
        self.inner.wait_until(until)
    }
}

impl<S: DutSegment> DutSegment for Tapped<S> {
    fn simulated(&mut self) -> Option<(&mut Slave, Duration)> {
        self.inner.simulated()
    }
}

#[cfg(test)]
mod tests {
    use super::super::binding::EcatBinding;
    use super::super::master::EmbeddedSegment;
    use super::*;
    use crate::binding::Binding;
    use crate::pcap::testing::{description, read_pcapng};
    use crate::pcap::Tap;
    use crate::suite::Action;
    use proto::ecat::EcatFrameRepr;
    use proto::nord::{Inverter, Product};
    use sim::device::{Device, DeviceConfig};
    use std::cell::RefCell;
    use std::rc::Rc;

    #[test]
    fn a_run_captures_both_directions_labelled_on_one_time_line() {
        let tap: SharedTap = Rc::new(RefCell::new(Tap::default()));
        for case in ["case 1", "case 2"] {
            tap.borrow_mut().label(case);
            let device = Device::new(DeviceConfig::new(Product::Sk550p));
            let segment = Tapped::new(
                EmbeddedSegment::new(Slave::new(device).unwrap()),
                tap.clone(),
            );
            let mut b = EcatBinding::open(
                segment,
                Some(Product::Sk550p),
                "t".into(),
                false,
                crate::ecat::master::MasterConfig::default().cycle,
            )
            .unwrap();
            let process = Action::Process {
                inverter: Inverter::new(1).unwrap(),
                control: 0x047E,
                setpoints: vec![],
                run: crate::suite::Run::Cycles(2),
            };
            b.perform(&process).unwrap();
        }
        let bytes = tap.borrow().capture.write_to(Vec::new()).unwrap();
        let (_, interfaces, packets) = read_pcapng(&bytes);
        assert_eq!(description(&interfaces[0]).as_deref(), Some(SOURCE));
        // Every frame is an EtherCAT frame that parses; the master's and the slave's
        // (locally administered source address) alternate.
        let mut from_slave = 0;
        for (_, frame, _) in &packets {
            assert_eq!(frame[12..14], [0x88, 0xA4]);
            EcatFrameRepr::parse_bytes(&frame[14..]).unwrap();
            from_slave += usize::from(frame[6] & 0x02 != 0);
        }
        assert_eq!(from_slave * 2, packets.len());
        // Both cases, labelled, the second after the first.
        let first_of = |label: &str| packets.iter().position(|p| p.2 == [label]).unwrap();
        assert!(first_of("case 1") < first_of("case 2"));
        assert!(
            packets.windows(2).all(|w| w[0].0 <= w[1].0),
            "one time line"
        );
    }
}
