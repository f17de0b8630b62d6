//! The link under the managing node: POWERLINK Ethernet frames (EtherType 88ABh) and SDO
//! datagrams to UDP port 3819, with a clock.
//!
//! [`EmbeddedLink`] carries the frames to the simulated controlled node (`sim::epl::Node`) on a
//! virtual clock: a frame is handled the moment it is sent, its answers queue for `recv`, and
//! waiting runs the node's timers — instant and deterministic. [`NetLink`] is a raw Ethernet
//! link on a network interface and a UDP socket, on the real clock.

use std::collections::VecDeque;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use proto::eth::ETHERTYPE_POWERLINK;
use sim::clock::{Clock, VirtualClock};
use sim::epl::{Node, POLL_PERIOD};

use crate::net::{LinkError, RawLink};

/// The link as the managing node sees it.
pub(crate) trait Link {
    /// Time since the link was opened.
    fn now(&self) -> Duration;
    /// Sends one Ethernet frame as it is.
    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError>;
    /// The next POWERLINK frame that arrived, waiting until `deadline` at most, with its
    /// kernel receive stamp where the link has one.
    fn recv(
        &mut self,
        deadline: Duration,
    ) -> Result<Option<(Vec<u8>, Option<Duration>)>, LinkError>;
    /// Sends a UDP datagram to the node's SDO port.
    fn send_udp(&mut self, datagram: &[u8]) -> Result<(), LinkError>;
    /// The next datagram from the node's SDO port, waiting until `deadline` at most.
    fn recv_udp(&mut self, deadline: Duration) -> Result<Option<Vec<u8>>, LinkError>;
    /// Lets time pass until `until` (the embedded link runs the node's timers).
    fn wait_until(&mut self, until: Duration);
    /// The node's SDO address (UDP port 3819) and the MN's, for captures.
    fn udp_ends(&mut self) -> (SocketAddr, SocketAddr);
    /// The simulated node, when it is in-process.
    fn node(&mut self) -> Option<(&mut Node, Duration)>;
}

/// Virtual time a frame takes to the node and back.
const EMBEDDED_HOP: Duration = Duration::from_micros(5);

/// The simulated node on a virtual clock.
#[derive(Debug)]
pub(crate) struct EmbeddedLink {
    node: Node,
    clock: VirtualClock,
    frames: VecDeque<Vec<u8>>,
    datagrams: VecDeque<Vec<u8>>,
    /// When the node's timers last ran.
    polled: Duration,
}

/// The UDP address the embedded node sees the harness's datagrams come from (the MN's
/// address on the POWERLINK subnet, 192.168.100.240).
const EMBEDDED_PEER: SocketAddr = SocketAddr::V4(std::net::SocketAddrV4::new(
    std::net::Ipv4Addr::new(192, 168, 100, 240),
    proto::epl::SDO_UDP_PORT,
));

impl EmbeddedLink {
    pub(crate) fn new(node: Node) -> EmbeddedLink {
        EmbeddedLink {
            node,
            clock: VirtualClock::new(),
            frames: VecDeque::new(),
            datagrams: VecDeque::new(),
            polled: Duration::ZERO,
        }
    }

    fn advance_to(&mut self, t: Duration) {
        loop {
            let next = self.polled + POLL_PERIOD;
            if next > t {
                break;
            }
            let now = self.clock.now();
            if next > now {
                self.clock.advance(next - now);
            }
            self.node.poll(next);
            self.polled = next;
        }
        let now = self.clock.now();
        if t > now {
            self.clock.advance(t - now);
        }
    }
}

impl Link for EmbeddedLink {
    fn now(&self) -> Duration {
        self.clock.now()
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let t = self.clock.now() + EMBEDDED_HOP;
        self.advance_to(t);
        let out = self.node.receive(frame, t);
        self.frames.extend(out);
        Ok(())
    }

    fn recv(
        &mut self,
        deadline: Duration,
    ) -> Result<Option<(Vec<u8>, Option<Duration>)>, LinkError> {
        if let Some(f) = self.frames.pop_front() {
            return Ok(Some((f, None)));
        }
        self.advance_to(deadline);
        Ok(None)
    }

    fn send_udp(&mut self, datagram: &[u8]) -> Result<(), LinkError> {
        let t = self.clock.now() + EMBEDDED_HOP;
        self.advance_to(t);
        let out = self.node.udp(EMBEDDED_PEER, datagram, t);
        self.datagrams.extend(out);
        Ok(())
    }

    fn recv_udp(&mut self, deadline: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        if let Some(d) = self.datagrams.pop_front() {
            return Ok(Some(d));
        }
        self.advance_to(deadline);
        Ok(None)
    }

    fn wait_until(&mut self, until: Duration) {
        self.advance_to(until);
    }

    fn udp_ends(&mut self) -> (SocketAddr, SocketAddr) {
        let node = proto::nord::epl::ip_address(self.node.node_id());
        (
            SocketAddr::from((node, proto::epl::SDO_UDP_PORT)),
            EMBEDDED_PEER,
        )
    }

    fn node(&mut self) -> Option<(&mut Node, Duration)> {
        let now = self.clock.now();
        Some((&mut self.node, now))
    }
}

/// A node behind a network interface: raw POWERLINK frames and UDP to `peer`.
pub(crate) struct NetLink {
    raw: RawLink,
    udp: UdpSocket,
    peer: SocketAddr,
    start: Instant,
    buf: Vec<u8>,
}

impl std::fmt::Debug for NetLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NetLink")
            .field("raw", &self.raw)
            .field("peer", &self.peer)
            .finish()
    }
}

impl NetLink {
    /// Opens `iface` for POWERLINK frames and a UDP socket for SDO to `peer` (the node's
    /// address, 192.168.100.N).
    pub(crate) fn open(iface: &str, peer: SocketAddr) -> Result<NetLink, LinkError> {
        let mut raw = RawLink::open(iface, Some(ETHERTYPE_POWERLINK))?;
        raw.set_spin(Duration::from_micros(200));
        let udp = UdpSocket::bind(("0.0.0.0", 0))
            .map_err(|e| LinkError::io("bind a UDP socket", iface, e))?;
        // Connected, the socket knows its own address (for captures) and takes datagrams of
        // the node only.
        udp.connect(peer)
            .map_err(|e| LinkError::io("reach the node over UDP", iface, e))?;
        Ok(NetLink {
            raw,
            udp,
            peer,
            start: Instant::now(),
            buf: vec![0; crate::net::MAX_FRAME],
        })
    }

    /// The interface's Ethernet address.
    pub(crate) fn mac(&self) -> [u8; 6] {
        self.raw.mac().0
    }

    fn instant(&self, at: Duration) -> Instant {
        self.start + at
    }
}

impl Link for NetLink {
    fn now(&self) -> Duration {
        self.start.elapsed()
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        self.raw.send(frame)
    }

    fn recv(
        &mut self,
        deadline: Duration,
    ) -> Result<Option<(Vec<u8>, Option<Duration>)>, LinkError> {
        let until = self.instant(deadline);
        Ok(self
            .raw
            .recv(&mut self.buf, until)?
            .map(|r| (self.buf[..r.len].to_vec(), r.stamp)))
    }

    fn send_udp(&mut self, datagram: &[u8]) -> Result<(), LinkError> {
        self.udp
            .send_to(datagram, self.peer)
            .map(|_| ())
            .map_err(|e| LinkError::io("send a UDP datagram", &self.peer.to_string(), e))
    }

    fn recv_udp(&mut self, deadline: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        let mut buf = [0u8; 1500];
        loop {
            let left = deadline.saturating_sub(self.now());
            if left.is_zero() {
                return Ok(None);
            }
            self.udp
                .set_read_timeout(Some(left))
                .map_err(|e| LinkError::io("set a UDP timeout", &self.peer.to_string(), e))?;
            match self.udp.recv_from(&mut buf) {
                Ok((n, from)) if from == self.peer => return Ok(Some(buf[..n].to_vec())),
                Ok(_) => continue,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    return Ok(None)
                }
                Err(e) => {
                    return Err(LinkError::io(
                        "receive a UDP datagram",
                        &self.peer.to_string(),
                        e,
                    ))
                }
            }
        }
    }

    fn wait_until(&mut self, until: Duration) {
        let now = self.now();
        if until > now {
            std::thread::sleep(until - now);
        }
    }

    fn udp_ends(&mut self) -> (SocketAddr, SocketAddr) {
        let local = self.udp.local_addr().unwrap_or(EMBEDDED_PEER);
        (self.peer, local)
    }

    fn node(&mut self) -> Option<(&mut Node, Duration)> {
        None
    }
}
