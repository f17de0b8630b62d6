//! The link under the IO controller ([`crate::net::peer`]): PROFINET frames (EtherType 8892h:
//! DCP, RT, alarms) and RPC datagrams to UDP port 34964, with the simulated IO device
//! (`sim::pnio::IoDevice`) behind the embedded one.

use std::net::SocketAddr;
use std::time::Duration;

use sim::pnio::{IoDevice, Out};

use crate::net::peer::{self, Sent, SimDevice};

/// The link as the controller sees it: any peer link to an IO device.
pub(crate) trait Link: peer::Link<Device = IoDevice> {}
impl<T: peer::Link<Device = IoDevice>> Link for T {}

/// The simulated device on a virtual clock.
pub(crate) type EmbeddedLink = peer::EmbeddedLink<IoDevice>;

/// A device behind a network interface.
pub(crate) type NetLink = peer::NetLink<IoDevice>;

/// What the capture's interface description names as the source of a run's frames.
pub(crate) const SOURCE: &str =
    "PROFINET IO frames of a harness run (IO controller and IO device, as on the wire)";

/// The UDP address the embedded device sees the controller's calls come from: the
/// controller on the device's factory subnet (192.168.20.1), its RPC port.
pub(crate) const EMBEDDED_PEER: SocketAddr = SocketAddr::V4(std::net::SocketAddrV4::new(
    std::net::Ipv4Addr::new(192, 168, 20, 1),
    proto::pnio::RPC_PORT,
));

fn sent(out: Vec<Out>) -> Vec<Sent> {
    out.into_iter()
        .map(|o| match o {
            Out::Frame(f) => Sent::Frame(f),
            Out::Datagram { bytes, .. } => Sent::Datagram(bytes),
        })
        .collect()
}

impl SimDevice for IoDevice {
    const POLL_PERIOD: Duration = sim::pnio::POLL_PERIOD;

    fn frame(&mut self, frame: &[u8], now: Duration) -> Vec<Sent> {
        sent(IoDevice::frame(self, frame, now))
    }

    fn datagram(&mut self, from: SocketAddr, datagram: &[u8], now: Duration) -> Vec<Sent> {
        sent(IoDevice::datagram(self, from, datagram, now))
    }

    fn poll(&mut self, now: Duration) -> Vec<Sent> {
        sent(IoDevice::poll(self, now))
    }

    fn udp_addr(&self) -> SocketAddr {
        self.rpc_addr()
    }
}
