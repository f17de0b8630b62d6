//! The node as an [`Endpoint`]: Ethernet frames to [`Node::receive`], datagrams to UDP port
//! 3819 (DS 301 C_SDO_EPL_PORT) to [`Node::udp`], answered from the same port, and
//! [`Node::poll`] a [`POLL_PERIOD`] after the last (the Basic Ethernet timeout, the loss of
//! the SoC, the drive model), however often the driver polls.

use std::time::Duration;

use proto::epl::SDO_UDP_PORT;

use super::{Node, POLL_PERIOD};
use crate::endpoint::{Endpoint, Input, Output, Raised};

impl Endpoint for Node {
    fn input(&mut self, input: Input<'_>, now: Duration) -> Vec<Output> {
        match input {
            Input::Frame(frame) => self
                .receive(frame, now)
                .into_iter()
                .map(Output::Frame)
                .collect(),
            Input::Datagram { port, from, bytes } if port == SDO_UDP_PORT => self
                .udp(from, bytes, now)
                .into_iter()
                .map(|bytes| Output::Datagram {
                    port,
                    to: from,
                    bytes,
                })
                .collect(),
            _ => Vec::new(),
        }
    }

    fn poll(&mut self, now: Duration) -> Vec<Output> {
        if now >= self.next_poll {
            Node::poll(self, now);
            self.next_poll = now + POLL_PERIOD;
        }
        Vec::new()
    }

    fn next_deadline(&self) -> Option<Duration> {
        Some(self.next_poll)
    }

    /// What a CN does when an error occurs (DS 301 §6.5): a new entry in its StatusResponse
    /// and EN toggled in its PRes; nothing leaves now, the MN fetches the entry with a SoA
    /// StatusRequest when it sees EN change.
    fn raise_alarm(&mut self, now: Duration) -> Option<Raised> {
        let e = self.raise_spurious(now)?;
        Some(Raised {
            what: format!(
                "error entry {:04X}h ({}) in the StatusResponse, EN toggled to {}",
                e.code,
                String::from_utf8_lossy(&e.info.to_le_bytes()).trim(),
                u8::from(self.exception_new())
            ),
            outputs: Vec::new(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::{Device, DeviceConfig};
    use crate::epl::NodeConfig;
    use proto::nord::Product;

    fn node() -> Node {
        let device = Device::new(DeviceConfig::new(Product::Sk550p));
        Node::new(device, NodeConfig::new(1)).unwrap()
    }

    #[test]
    fn polled_a_period_after_the_last_however_often_asked() {
        let mut n = node();
        assert_eq!(n.next_deadline(), Some(Duration::ZERO));
        let t = Duration::from_millis(3);
        assert!(Endpoint::poll(&mut n, t).is_empty());
        assert_eq!(n.next_deadline(), Some(t + POLL_PERIOD));
        Endpoint::poll(&mut n, t + POLL_PERIOD / 2);
        assert_eq!(n.next_deadline(), Some(t + POLL_PERIOD));
    }

    #[test]
    fn a_spurious_emergency_is_an_entry_and_en_toggled_once_the_node_cycles() {
        let mut n = node();
        assert_eq!(
            n.raise_alarm(Duration::ZERO),
            None,
            "NOT_ACTIVE: no MN to fetch it"
        );
        n.enter(proto::epl::NmtState::PRE_OPERATIONAL_2, Duration::ZERO);
        let r = n.raise_alarm(Duration::from_millis(5)).unwrap();
        assert_eq!(
            r.what,
            "error entry 9000h (1   12.0) in the StatusResponse, EN toggled to 1"
        );
        assert!(r.outputs.is_empty(), "fetched by the MN");
        let s = n.status();
        assert!(s.flags.en);
        assert_eq!((s.entries[0].code, s.error_register), (0x9000, 1));
        n.raise_alarm(Duration::from_millis(6)).unwrap();
        assert!(!n.status().flags.en, "toggled again");
        assert_eq!(n.status().entries.len(), 2);
    }

    #[test]
    fn datagrams_to_another_port_are_not_the_nodes() {
        let mut n = node();
        let from = "192.168.100.240:3819".parse().unwrap();
        let input = Input::Datagram {
            port: SDO_UDP_PORT + 1,
            from,
            bytes: &[0; 8],
        };
        assert!(n.input(input, Duration::ZERO).is_empty());
        assert_eq!(n.dropped(), 0, "not even looked at");
    }
}
