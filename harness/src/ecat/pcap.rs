//! `--pcap` for EtherCAT: the frames of a run as they went over the segment, both ways.
//!
//! The master's frames are whole Ethernet frames (EtherType 88A4h), so the capture holds them
//! as they are, the slave's answers with the locally administered source address it sets; a
//! capture of the embedded slave looks like one taken on the wire.

use std::time::Duration;

use super::binding::DutSegment;
use super::master::{Arrival, Segment, SegmentError};
use crate::pcap::SharedTap;
use sim::ecat::Slave;

/// What the interface description names as the source of these frames.
const SOURCE: &str = "EtherCAT frames of a harness run (master and slave, as on the wire)";

/// A segment whose traffic also goes to the run's capture, stamped on the run's time line
/// (the segment's clock, placed after the last packet so far).
#[derive(Debug)]
pub(crate) struct Tapped<S> {
    inner: S,
    tap: SharedTap,
    base: Duration,
}

impl<S: Segment> Tapped<S> {
    /// `inner`, recorded into `tap` from now on.
    pub(crate) fn new(inner: S, tap: SharedTap) -> Tapped<S> {
        let base = {
            let mut t = tap.borrow_mut();
            t.capture.source(SOURCE);
            t.last + Duration::from_millis(1)
        };
        let base = base.saturating_sub(inner.now());
        Tapped { inner, tap, base }
    }

    fn record(&self, frame: &[u8]) {
        let at = self.base + self.inner.now();
        let mut t = self.tap.borrow_mut();
        t.last = t.last.max(at);
        t.capture.frame(frame, at);
    }
}

impl<S: Segment> Segment for Tapped<S> {
    fn now(&self) -> Duration {
        self.inner.now()
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
