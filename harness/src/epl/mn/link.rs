//! The link under the managing node ([`crate::net::peer`]): POWERLINK Ethernet frames
//! (EtherType 88ABh) and SDO datagrams to UDP port 3819, with the simulated controlled node
//! (`sim::epl::Node`) behind the embedded one.

use std::net::SocketAddr;
use std::time::Duration;

use sim::epl::Node;

use crate::net::peer::{self, Sent, SimDevice};

/// The link as the managing node sees it: any peer link to a controlled node.
pub(crate) trait Link: peer::Link<Device = Node> {}
impl<T: peer::Link<Device = Node>> Link for T {}

/// The simulated node on a virtual clock.
pub(crate) type EmbeddedLink = peer::EmbeddedLink<Node>;
/// A node behind a network interface.
pub(crate) type NetLink = peer::NetLink<Node>;

/// What the capture's interface description names as the source of a run's frames.
pub(crate) const SOURCE: &str =
    "POWERLINK frames of a harness run (managing and controlled node, as on the wire)";

/// The UDP address the embedded node sees the harness's datagrams come from (the MN's
/// address on the POWERLINK subnet, 192.168.100.240).
pub(crate) const EMBEDDED_PEER: SocketAddr = SocketAddr::V4(std::net::SocketAddrV4::new(
    std::net::Ipv4Addr::new(192, 168, 100, 240),
    proto::epl::SDO_UDP_PORT,
));

impl SimDevice for Node {
    const POLL_PERIOD: Duration = sim::epl::POLL_PERIOD;

    fn frame(&mut self, frame: &[u8], now: Duration) -> Vec<Sent> {
        self.receive(frame, now)
            .into_iter()
            .map(Sent::Frame)
            .collect()
    }

    fn datagram(&mut self, from: SocketAddr, datagram: &[u8], now: Duration) -> Vec<Sent> {
        self.udp(from, datagram, now)
            .into_iter()
            .map(Sent::Datagram)
            .collect()
    }

    fn poll(&mut self, now: Duration) -> Vec<Sent> {
        Node::poll(self, now);
        Vec::new()
    }

    fn udp_addr(&self) -> SocketAddr {
        let node = proto::nord::epl::ip_address(self.node_id());
        SocketAddr::from((node, proto::epl::SDO_UDP_PORT))
    }
}
