//! `--pcap` for POWERLINK: the Ethernet frames of a run as they went over the link, both
//! ways, and the SDO datagrams over UDP in synthesized IPv4/UDP frames, stamped on the run's
//! time line.

use std::net::SocketAddr;
use std::time::Duration;

use super::link::Link;
use crate::net::LinkError;
use crate::pcap::{SharedTap, Stamper};
use sim::epl::Node;

/// What the interface description names as the source of these frames.
const SOURCE: &str =
    "POWERLINK frames of a harness run (managing and controlled node, as on the wire)";

/// A link whose frames also go to the run's capture.
#[derive(Debug)]
pub(crate) struct Tapped<L> {
    inner: L,
    stamper: Stamper,
}

impl<L: Link> Tapped<L> {
    /// `inner`, recorded into `tap` from now on.
    pub(crate) fn new(inner: L, tap: SharedTap) -> Tapped<L> {
        let stamper = Stamper::new(tap, SOURCE, inner.now());
        Tapped { inner, stamper }
    }

    fn record(&self, frame: &[u8]) {
        self.stamper
            .record(self.inner.now(), |c, at| c.frame(frame, at));
    }

    /// A datagram from the MN to the node (`to_node`) or back.
    fn record_udp(&mut self, datagram: &[u8], to_node: bool) {
        let (node, mn) = self.inner.udp_ends();
        let (SocketAddr::V4(node), SocketAddr::V4(mn)) = (node, mn) else {
            return;
        };
        let (from, to) = if to_node { (mn, node) } else { (node, mn) };
        self.stamper.record(self.inner.now(), |c, at| {
            c.udp_of(SOURCE, from, to, datagram, at)
        });
    }
}

impl<L: Link> Link for Tapped<L> {
    fn now(&self) -> Duration {
        self.inner.now()
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        self.record(frame);
        self.inner.send(frame)
    }

    fn recv(
        &mut self,
        deadline: Duration,
    ) -> Result<Option<(Vec<u8>, Option<Duration>)>, LinkError> {
        let r = self.inner.recv(deadline)?;
        if let Some((f, _)) = &r {
            self.record(f);
        }
        Ok(r)
    }

    fn send_udp(&mut self, datagram: &[u8]) -> Result<(), LinkError> {
        self.record_udp(datagram, true);
        self.inner.send_udp(datagram)
    }

    fn recv_udp(&mut self, deadline: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        let r = self.inner.recv_udp(deadline)?;
        if let Some(d) = &r {
            self.record_udp(d, false);
        }
        Ok(r)
    }

    fn udp_ends(&mut self) -> (SocketAddr, SocketAddr) {
        self.inner.udp_ends()
    }

    fn wait_until(&mut self, until: Duration) {
        self.inner.wait_until(until)
    }

    fn node(&mut self) -> Option<(&mut Node, Duration)> {
        self.inner.node()
    }
}
