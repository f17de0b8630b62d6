//! The link a bus's tester side (POWERLINK's managing node, PROFINET's IO controller) talks to
//! one device over: the bus's Ethernet frames and UDP datagrams to the device's port, with a
//! clock.
//!
//! [`EmbeddedLink`] carries them to a simulated device in-process on a virtual clock: a frame
//! is handled the moment it is sent, the answers queue for `recv`, and waiting runs the
//! device's timers (and takes what it sends on its own) — instant and deterministic.
//! [`NetLink`] is a raw Ethernet link on a network interface and a UDP socket, on the real
//! clock. [`Tapped`] copies either's traffic into the run's `--pcap` capture.

use std::collections::VecDeque;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use sim::clock::{Clock, VirtualClock};

use crate::net::{LinkError, RawLink};
use crate::pcap::{SharedTap, Stamper};

/// What a device sends: an Ethernet frame or a UDP datagram from its port.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Sent {
    Frame(Vec<u8>),
    Datagram(Vec<u8>),
}

/// A simulated device that can sit behind an [`EmbeddedLink`].
pub(crate) trait SimDevice {
    /// How often it wants [`SimDevice::poll`].
    const POLL_PERIOD: Duration;
    /// Handles one Ethernet frame.
    fn frame(&mut self, frame: &[u8], now: Duration) -> Vec<Sent>;
    /// Handles one datagram to its UDP port from `from`.
    fn datagram(&mut self, from: SocketAddr, datagram: &[u8], now: Duration) -> Vec<Sent>;
    /// Runs its timers; what it sends on its own.
    fn poll(&mut self, now: Duration) -> Vec<Sent>;
    /// Its UDP address.
    fn udp_addr(&self) -> SocketAddr;
}

/// The link as the tester sees it.
pub(crate) trait Link {
    /// The simulated device, when it is in-process.
    type Device;
    /// Time since the link was opened.
    fn now(&self) -> Duration;
    /// Sends one Ethernet frame as it is.
    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError>;
    /// The next frame of the bus's EtherType that arrived, waiting until `deadline` at most,
    /// with its kernel receive stamp where the link has one.
    fn recv(
        &mut self,
        deadline: Duration,
    ) -> Result<Option<(Vec<u8>, Option<Duration>)>, LinkError>;
    /// Sends a UDP datagram to the device's port.
    fn send_udp(&mut self, datagram: &[u8]) -> Result<(), LinkError>;
    /// Sends a UDP datagram back to where the device's last one came from: the answer to a
    /// call the device made as client, maybe from a port of its own (p-net's ApplicationReady
    /// comes from another port than its RPC server's).
    fn send_udp_reply(&mut self, datagram: &[u8]) -> Result<(), LinkError> {
        self.send_udp(datagram)
    }
    /// The next datagram from the device, waiting until `deadline` at most.
    fn recv_udp(&mut self, deadline: Duration) -> Result<Option<Vec<u8>>, LinkError>;
    /// Lets time pass until `until` (the embedded link runs the device's timers).
    fn wait_until(&mut self, until: Duration);
    /// The device's UDP address and the tester's, for captures.
    fn udp_ends(&mut self) -> (SocketAddr, SocketAddr);
    /// Sends the datagrams to `peer` from now on (a device whose address the tester learnt on
    /// the link, as PROFINET's controller does by DCP). The embedded link has one device.
    fn set_udp_peer(&mut self, _peer: SocketAddr) -> Result<(), LinkError> {
        Ok(())
    }
    /// The simulated device and the time, when it is in-process.
    fn device(&mut self) -> Option<(&mut Self::Device, Duration)>;
}

/// Virtual time a frame takes to the device and back.
const EMBEDDED_HOP: Duration = Duration::from_micros(5);

/// A simulated device on a virtual clock.
#[derive(Debug)]
pub(crate) struct EmbeddedLink<D> {
    device: D,
    /// The address the device sees the tester's datagrams come from.
    tester: SocketAddr,
    clock: VirtualClock,
    frames: VecDeque<Vec<u8>>,
    datagrams: VecDeque<Vec<u8>>,
    /// When the device's timers last ran.
    polled: Duration,
}

impl<D: SimDevice> EmbeddedLink<D> {
    /// `device`, reached from `tester`.
    pub(crate) fn new(device: D, tester: SocketAddr) -> EmbeddedLink<D> {
        EmbeddedLink {
            device,
            tester,
            clock: VirtualClock::new(),
            frames: VecDeque::new(),
            datagrams: VecDeque::new(),
            polled: Duration::ZERO,
        }
    }

    fn take(&mut self, sent: Vec<Sent>) {
        for s in sent {
            match s {
                Sent::Frame(f) => self.frames.push_back(f),
                Sent::Datagram(d) => self.datagrams.push_back(d),
            }
        }
    }

    fn advance_to(&mut self, t: Duration) {
        loop {
            let next = self.polled + D::POLL_PERIOD;
            if next > t {
                break;
            }
            let now = self.clock.now();
            if next > now {
                self.clock.advance(next - now);
            }
            let sent = self.device.poll(next);
            self.take(sent);
            self.polled = next;
        }
        let now = self.clock.now();
        if t > now {
            self.clock.advance(t - now);
        }
    }

    /// What `take` finds, polling the device up to `deadline` for it: what the device sends
    /// on its own comes out at the poll that sent it.
    fn next(
        &mut self,
        deadline: Duration,
        take: impl Fn(&mut Self) -> Option<Vec<u8>>,
    ) -> Option<Vec<u8>> {
        loop {
            if let Some(x) = take(self) {
                return Some(x);
            }
            let next = self.polled + D::POLL_PERIOD;
            if next > deadline {
                self.advance_to(deadline);
                return None;
            }
            self.advance_to(next);
        }
    }
}

impl<D: SimDevice> Link for EmbeddedLink<D> {
    type Device = D;

    fn now(&self) -> Duration {
        self.clock.now()
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        let t = self.clock.now() + EMBEDDED_HOP;
        self.advance_to(t);
        let out = self.device.frame(frame, t);
        self.take(out);
        Ok(())
    }

    fn recv(
        &mut self,
        deadline: Duration,
    ) -> Result<Option<(Vec<u8>, Option<Duration>)>, LinkError> {
        Ok(self
            .next(deadline, |l| l.frames.pop_front())
            .map(|f| (f, None)))
    }

    fn send_udp(&mut self, datagram: &[u8]) -> Result<(), LinkError> {
        let t = self.clock.now() + EMBEDDED_HOP;
        self.advance_to(t);
        let out = self.device.datagram(self.tester, datagram, t);
        self.take(out);
        Ok(())
    }

    fn recv_udp(&mut self, deadline: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        Ok(self.next(deadline, |l| l.datagrams.pop_front()))
    }

    fn wait_until(&mut self, until: Duration) {
        self.advance_to(until);
    }

    fn udp_ends(&mut self) -> (SocketAddr, SocketAddr) {
        (self.device.udp_addr(), self.tester)
    }

    fn device(&mut self) -> Option<(&mut D, Duration)> {
        let now = self.clock.now();
        Some((&mut self.device, now))
    }
}

/// The shortest wait [`NetLink::recv_udp`] blocks for; shorter ones only look.
const MIN_UDP_WAIT: Duration = Duration::from_millis(5);

/// A device behind a network interface: raw frames of one EtherType and UDP to `peer`.
pub(crate) struct NetLink<D> {
    raw: RawLink,
    /// Not connected: the device may send from any of its ports.
    udp: UdpSocket,
    peer: SocketAddr,
    /// The host's address toward the peer (for captures).
    local_ip: std::net::IpAddr,
    /// Where the device's last datagram came from.
    last_from: Option<SocketAddr>,
    /// The UDP port the socket is bound to (0: any).
    local_port: u16,
    start: Instant,
    buf: Vec<u8>,
    device: std::marker::PhantomData<fn() -> D>,
}

impl<D> std::fmt::Debug for NetLink<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NetLink")
            .field("raw", &self.raw)
            .field("peer", &self.peer)
            .finish()
    }
}

/// The host's own address on the route to `peer`: what a socket connected to it would send
/// from (a throwaway socket; connecting a UDP socket sends nothing).
fn local_toward(peer: SocketAddr) -> Result<std::net::IpAddr, LinkError> {
    let what = peer.to_string();
    let io = |e| LinkError::io("find the route to the device", &what, e);
    let probe = UdpSocket::bind(("0.0.0.0", 0)).map_err(io)?;
    probe.connect(peer).map_err(io)?;
    Ok(probe.local_addr().map_err(io)?.ip())
}

impl<D> NetLink<D> {
    /// Takes frames of `ethertype` too, besides the one the link was opened for.
    pub(crate) fn also_take(&mut self, ethertype: u16) {
        self.raw.also_take(ethertype);
    }

    /// Opens `iface` for frames of `ethertype` and a UDP socket on `local_port` (0: any) to
    /// `peer`, the device's UDP address.
    pub(crate) fn open(
        iface: &str,
        ethertype: u16,
        peer: SocketAddr,
        local_port: u16,
    ) -> Result<NetLink<D>, LinkError> {
        let mut raw = RawLink::open(iface, Some(ethertype))?;
        raw.set_spin(Duration::from_micros(200));
        let udp = UdpSocket::bind(("0.0.0.0", local_port))
            .map_err(|e| LinkError::io("bind a UDP socket", iface, e))?;
        Ok(NetLink {
            raw,
            udp,
            local_ip: local_toward(peer)?,
            last_from: None,
            peer,
            local_port,
            start: Instant::now(),
            buf: vec![0; crate::net::MAX_FRAME],
            device: std::marker::PhantomData,
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

impl<D> Link for NetLink<D> {
    type Device = D;

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
        let peer = self.peer.to_string();
        loop {
            let left = deadline.saturating_sub(self.now());
            // A receive time-out is counted in the kernel's ticks (4 ms at HZ=250): a wait
            // shorter than a tick is a look at what is queued, without waiting.
            let glance = left < MIN_UDP_WAIT;
            self.udp
                .set_nonblocking(glance)
                .map_err(|e| LinkError::io("set a UDP socket's mode", &peer, e))?;
            if !glance {
                self.udp
                    .set_read_timeout(Some(left))
                    .map_err(|e| LinkError::io("set a UDP timeout", &peer, e))?;
            }
            match self.udp.recv_from(&mut buf) {
                // The device's datagrams, from whichever of its ports.
                Ok((n, from)) if from.ip() == self.peer.ip() => {
                    self.last_from = Some(from);
                    return Ok(Some(buf[..n].to_vec()));
                }
                // A signal (a stopped and continued process, a debugger) is no link error.
                Ok(_) => continue,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) if crate::net::timed_out(&e) => return Ok(None),
                Err(e) => return Err(LinkError::io("receive a UDP datagram", &peer, e)),
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
        let port = self.udp.local_addr().map_or(self.local_port, |a| a.port());
        (self.peer, SocketAddr::new(self.local_ip, port))
    }

    fn send_udp_reply(&mut self, datagram: &[u8]) -> Result<(), LinkError> {
        let to = self.last_from.unwrap_or(self.peer);
        self.udp
            .send_to(datagram, to)
            .map(|_| ())
            .map_err(|e| LinkError::io("send a UDP datagram", &to.to_string(), e))
    }

    fn set_udp_peer(&mut self, peer: SocketAddr) -> Result<(), LinkError> {
        self.local_ip = local_toward(peer)?;
        self.peer = peer;
        self.last_from = None;
        Ok(())
    }

    fn device(&mut self) -> Option<(&mut D, Duration)> {
        None
    }
}

/// A link whose frames also go to the run's capture, both ways, and whose datagrams go there
/// in synthesized IPv4/UDP frames, stamped on the run's time line.
#[derive(Debug)]
pub(crate) struct Tapped<L> {
    inner: L,
    stamper: Stamper,
    /// What the capture's interface description names as the source.
    source: &'static str,
}

impl<L: Link> Tapped<L> {
    /// `inner`, recorded into `tap` from now on under `source`.
    pub(crate) fn new(inner: L, tap: SharedTap, source: &'static str) -> Tapped<L> {
        let stamper = Stamper::new(tap, source, inner.now());
        Tapped {
            inner,
            stamper,
            source,
        }
    }

    fn record(&self, frame: &[u8]) {
        self.stamper
            .record(self.inner.now(), |c, at| c.frame(frame, at));
    }

    /// A datagram from the tester to the device (`to_device`) or back.
    fn record_udp(&mut self, datagram: &[u8], to_device: bool) {
        let (device, tester) = self.inner.udp_ends();
        let (SocketAddr::V4(device), SocketAddr::V4(tester)) = (device, tester) else {
            return;
        };
        let (from, to) = if to_device {
            (tester, device)
        } else {
            (device, tester)
        };
        let source = self.source;
        self.stamper.record(self.inner.now(), |c, at| {
            c.udp_of(source, from, to, datagram, at)
        });
    }
}

impl<L: Link> Link for Tapped<L> {
    type Device = L::Device;

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

    fn send_udp_reply(&mut self, datagram: &[u8]) -> Result<(), LinkError> {
        self.record_udp(datagram, true);
        self.inner.send_udp_reply(datagram)
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

    fn set_udp_peer(&mut self, peer: SocketAddr) -> Result<(), LinkError> {
        self.inner.set_udp_peer(peer)
    }

    fn wait_until(&mut self, until: Duration) {
        self.inner.wait_until(until)
    }

    fn device(&mut self) -> Option<(&mut L::Device, Duration)> {
        self.inner.device()
    }
}
