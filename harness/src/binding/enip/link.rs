//! How the scanner reaches an EtherNet/IP target: the embedded adapter over an in-memory link
//! (same bytes, virtual clock) or a device on the network (TCP 44818, UDP 2222).

use std::io::{Read, Write};
use std::net::{SocketAddr, SocketAddrV4, TcpStream, UdpSocket};

use crate::pcap::SharedTap;
use std::time::{Duration, Instant};

use proto::enip::encap::{frame_len, HEADER_LEN};
use proto::enip::io::IO_PORT;
use sim::clock::{Clock, VirtualClock};
use sim::enip::{Adapter, Framer};

/// A way to an EtherNet/IP target.
pub(crate) trait EnipLink {
    /// What is reached.
    fn describe(&self) -> String;
    /// Sends one encapsulation message; returns the reply, or `None` if none came in time.
    fn request(&mut self, msg: &[u8]) -> Result<Option<Vec<u8>>, String>;
    /// Sends one O→T datagram (if any), lets `rpi` pass, and returns the T→O datagrams that
    /// arrived meanwhile.
    fn io_cycle(&mut self, datagram: Option<&[u8]>, rpi: Duration) -> Result<Vec<Vec<u8>>, String>;
    /// The embedded adapter, for fault injection and observation.
    fn adapter(&mut self) -> Option<(&mut Adapter, Duration)>;
}

/// The peer address the embedded adapter sees (the scanner's).
const SCANNER_V4: SocketAddrV4 =
    SocketAddrV4::new(std::net::Ipv4Addr::new(192, 168, 1, 10), 50_000);
const SCANNER: SocketAddr = SocketAddr::V4(SCANNER_V4);

/// Where captured packets of the embedded link go: the tap, this case's time base and its
/// client address.
struct Recorder {
    tap: SharedTap,
    base: Duration,
    client: SocketAddrV4,
    server: SocketAddrV4,
}

impl Recorder {
    fn new(tap: SharedTap, server: SocketAddrV4, now: Duration) -> Recorder {
        let (base, client) = {
            let mut t = tap.borrow_mut();
            t.connections = t.connections.wrapping_add(1);
            let port = 50_000u16.wrapping_add(t.connections % 10_000);
            (
                t.last + Duration::from_millis(1),
                SocketAddrV4::new(*SCANNER_V4.ip(), port),
            )
        };
        let r = Recorder {
            tap,
            base,
            client,
            server,
        };
        r.tap
            .borrow_mut()
            .capture
            .tcp_open(client, server, base + now);
        r
    }

    fn at(&self, now: Duration) -> Duration {
        let t = self.base + now;
        let mut tap = self.tap.borrow_mut();
        tap.last = tap.last.max(t);
        t
    }

    fn tcp(&self, to_server: bool, bytes: &[u8], now: Duration) {
        let t = self.at(now);
        let (from, to) = if to_server {
            (self.client, self.server)
        } else {
            (self.server, self.client)
        };
        self.tap.borrow_mut().capture.tcp_data(from, to, bytes, t);
    }

    fn udp(&self, to_server: bool, bytes: &[u8], now: Duration) {
        let t = self.at(now);
        let c = SocketAddrV4::new(*self.client.ip(), IO_PORT);
        let s = SocketAddrV4::new(*self.server.ip(), IO_PORT);
        let (from, to) = if to_server { (c, s) } else { (s, c) };
        self.tap.borrow_mut().capture.udp(from, to, bytes, t);
    }
}

/// The embedded adapter behind an in-memory link.
pub(crate) struct Embedded {
    adapter: Adapter,
    clock: VirtualClock,
    framer: Framer,
    recorder: Option<Recorder>,
}

impl Embedded {
    pub(crate) fn new(adapter: Adapter, server: SocketAddrV4, tap: Option<SharedTap>) -> Embedded {
        let clock = VirtualClock::new();
        let recorder = tap.map(|t| Recorder::new(t, server, clock.now()));
        Embedded {
            adapter,
            clock,
            framer: Framer::new(),
            recorder,
        }
    }
}

impl Drop for Embedded {
    fn drop(&mut self) {
        if let Some(r) = &self.recorder {
            let t = r.at(self.clock.now());
            r.tap.borrow_mut().capture.tcp_close(r.client, r.server, t);
        }
    }
}

impl EnipLink for Embedded {
    fn describe(&self) -> String {
        format!(
            "embedded EtherNet/IP adapter ({})",
            self.adapter.product().name()
        )
    }

    fn request(&mut self, msg: &[u8]) -> Result<Option<Vec<u8>>, String> {
        let now = self.clock.now();
        if let Some(r) = &self.recorder {
            r.tcp(true, msg, now);
        }
        let mut reply = None;
        for m in self.framer.push(msg).map_err(|e| e.to_string())? {
            let r = self.adapter.handle_tcp(1, SCANNER, &m, now);
            if r.reply.is_some() {
                reply = r.reply;
            }
        }
        if let (Some(r), Some(b)) = (&self.recorder, &reply) {
            r.tcp(false, b, now);
        }
        Ok(reply)
    }

    fn io_cycle(&mut self, datagram: Option<&[u8]>, rpi: Duration) -> Result<Vec<Vec<u8>>, String> {
        if let Some(d) = datagram {
            if let Some(r) = &self.recorder {
                r.udp(true, d, self.clock.now());
            }
            // A datagram the adapter drops is what a real device would do too.
            let _ = self.adapter.handle_io(SCANNER, d, self.clock.now());
        }
        self.clock.advance(rpi);
        let out: Vec<Vec<u8>> = self
            .adapter
            .poll(self.clock.now())
            .into_iter()
            .map(|(_, b)| b)
            .collect();
        if let Some(r) = &self.recorder {
            for b in &out {
                r.udp(false, b, self.clock.now());
            }
        }
        Ok(out)
    }

    fn adapter(&mut self) -> Option<(&mut Adapter, Duration)> {
        let now = self.clock.now();
        Some((&mut self.adapter, now))
    }
}

/// A target on the network.
pub(crate) struct Network {
    target: SocketAddr,
    tcp: TcpStream,
    udp: UdpSocket,
    timeout: Duration,
    buf: Vec<u8>,
}

impl Network {
    /// Connects to `target` (TCP) and binds UDP 2222 on the local address used for it, where
    /// the target sends T→O data.
    pub(crate) fn connect(target: SocketAddr, timeout: Duration) -> Result<Network, String> {
        let tcp = TcpStream::connect_timeout(&target, timeout)
            .map_err(|e| format!("cannot connect to {target}: {e}"))?;
        tcp.set_nodelay(true).map_err(|e| e.to_string())?;
        let local = tcp.local_addr().map_err(|e| e.to_string())?;
        let udp = UdpSocket::bind(SocketAddr::new(local.ip(), IO_PORT))
            .map_err(|e| format!("cannot bind UDP {}:{IO_PORT} for T→O data: {e}", local.ip()))?;
        Ok(Network {
            target,
            tcp,
            udp,
            timeout,
            buf: Vec::new(),
        })
    }
}

impl EnipLink for Network {
    fn describe(&self) -> String {
        format!("EtherNet/IP target at {}", self.target)
    }

    fn request(&mut self, msg: &[u8]) -> Result<Option<Vec<u8>>, String> {
        self.tcp
            .write_all(msg)
            .map_err(|e| format!("TCP send failed: {e}"))?;
        let deadline = Instant::now() + self.timeout;
        let mut chunk = [0u8; 4096];
        loop {
            if let Some(n) = frame_len(&self.buf) {
                if self.buf.len() >= n {
                    return Ok(Some(self.buf.drain(..n).collect()));
                }
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(None);
            }
            self.tcp
                .set_read_timeout(Some(left))
                .map_err(|e| e.to_string())?;
            match self.tcp.read(&mut chunk) {
                Ok(0) => {
                    return Err(format!(
                        "the target closed the TCP connection ({} bytes of a reply pending)",
                        self.buf.len()
                    ))
                }
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    if self.buf.len() >= HEADER_LEN {
                        return Err(format!(
                            "incomplete reply: the header announces {} bytes, {} arrived",
                            frame_len(&self.buf).unwrap_or(0),
                            self.buf.len()
                        ));
                    }
                    return Ok(None);
                }
                Err(e) => return Err(format!("TCP receive failed: {e}")),
            }
        }
    }

    fn io_cycle(&mut self, datagram: Option<&[u8]>, rpi: Duration) -> Result<Vec<Vec<u8>>, String> {
        if let Some(d) = datagram {
            self.udp
                .send_to(d, SocketAddr::new(self.target.ip(), IO_PORT))
                .map_err(|e| format!("UDP send failed: {e}"))?;
        }
        let deadline = Instant::now() + rpi;
        let mut out = Vec::new();
        let mut buf = [0u8; 1500];
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(out);
            }
            self.udp
                .set_read_timeout(Some(left))
                .map_err(|e| e.to_string())?;
            match self.udp.recv_from(&mut buf) {
                Ok((n, _)) => out.push(buf[..n].to_vec()),
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    return Ok(out)
                }
                Err(e) => return Err(format!("UDP receive failed: {e}")),
            }
        }
    }

    fn adapter(&mut self) -> Option<(&mut Adapter, Duration)> {
        None
    }
}
