//! How the scanner reaches an EtherNet/IP target: the embedded adapter over an in-memory link
//! (same bytes, virtual clock) or a device on the network (TCP 44818, UDP 2222).

use std::collections::BTreeMap;
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
    /// Sends one encapsulation message on the TCP connection of `client` (1 = the scanner's
    /// own; others are opened on first use); returns the reply, or `None` if none came in
    /// time. A connection the target closed stays closed: every later request is an error.
    fn request(&mut self, client: u8, msg: &[u8]) -> Result<Option<Vec<u8>>, String>;
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
    /// Per client, its framer; `None` once the adapter closed the connection.
    clients: BTreeMap<u8, Option<Framer>>,
    recorder: Option<Recorder>,
}

impl Embedded {
    pub(crate) fn new(adapter: Adapter, server: SocketAddrV4, tap: Option<SharedTap>) -> Embedded {
        let clock = VirtualClock::new();
        let recorder = tap.map(|t| Recorder::new(t, server, clock.now()));
        Embedded {
            adapter,
            clock,
            clients: BTreeMap::new(),
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

    fn request(&mut self, client: u8, msg: &[u8]) -> Result<Option<Vec<u8>>, String> {
        let now = self.clock.now();
        // Only the scanner's own connection is captured.
        let recorder = self.recorder.as_ref().filter(|_| client == 1);
        if let Some(r) = recorder {
            r.tcp(true, msg, now);
        }
        let slot = self
            .clients
            .entry(client)
            .or_insert_with(|| Some(Framer::new()));
        let Some(framer) = slot else {
            return Err("the target closed the TCP connection".into());
        };
        // The served adapter drops a client whose message exceeds the framer's limit.
        let (messages, mut close) = match framer.push(msg) {
            Ok(m) => (m, false),
            Err(_) => (Vec::new(), true),
        };
        let id = u64::from(client);
        let peer = SocketAddr::V4(SocketAddrV4::new(
            *SCANNER_V4.ip(),
            SCANNER_V4.port() + u16::from(client),
        ));
        let mut reply = None;
        for m in messages {
            let r = self.adapter.handle_tcp(id, peer, &m, now);
            if r.reply.is_some() {
                reply = r.reply;
            }
            if r.close {
                close = true;
                break;
            }
        }
        if let (Some(r), Some(b)) = (recorder, &reply) {
            r.tcp(false, b, now);
        }
        if close {
            *slot = None;
            self.adapter.client_closed(id);
            if reply.is_none() {
                return Err("the target closed the TCP connection".into());
            }
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
    tcp: Stream,
    /// Connections of other clients, opened on first use.
    others: BTreeMap<u8, Stream>,
    udp: UdpSocket,
    timeout: Duration,
}

/// One TCP connection and the bytes received beyond the last reply.
struct Stream {
    tcp: Option<TcpStream>,
    buf: Vec<u8>,
}

impl Stream {
    fn connect(target: SocketAddr, timeout: Duration) -> Result<Stream, String> {
        let tcp = TcpStream::connect_timeout(&target, timeout)
            .map_err(|e| format!("cannot connect to {target}: {e}"))?;
        tcp.set_nodelay(true).map_err(|e| e.to_string())?;
        Ok(Stream {
            tcp: Some(tcp),
            buf: Vec::new(),
        })
    }

    /// Sends `msg`, waits up to `timeout` for one whole reply.
    fn request(&mut self, msg: &[u8], timeout: Duration) -> Result<Option<Vec<u8>>, String> {
        let tcp = self
            .tcp
            .as_mut()
            .ok_or("the target closed the TCP connection")?;
        tcp.write_all(msg)
            .map_err(|e| format!("TCP send failed: {e}"))?;
        let deadline = Instant::now() + timeout;
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
            tcp.set_read_timeout(Some(left))
                .map_err(|e| e.to_string())?;
            match tcp.read(&mut chunk) {
                Ok(0) => {
                    self.tcp = None;
                    return Err(format!(
                        "the target closed the TCP connection ({} bytes of a reply pending)",
                        self.buf.len()
                    ));
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
                Err(e) => {
                    self.tcp = None;
                    return Err(format!("TCP receive failed: {e}"));
                }
            }
        }
    }
}

impl Network {
    /// Connects to `target` (TCP) and binds UDP 2222 on the local address used for it, where
    /// the target sends T→O data.
    pub(crate) fn connect(target: SocketAddr, timeout: Duration) -> Result<Network, String> {
        let tcp = Stream::connect(target, timeout)?;
        let local = tcp
            .tcp
            .as_ref()
            .and_then(|t| t.local_addr().ok())
            .ok_or("no local address for the TCP connection")?;
        let udp = UdpSocket::bind(SocketAddr::new(local.ip(), IO_PORT))
            .map_err(|e| format!("cannot bind UDP {}:{IO_PORT} for T→O data: {e}", local.ip()))?;
        Ok(Network {
            target,
            tcp,
            others: BTreeMap::new(),
            udp,
            timeout,
        })
    }
}

impl EnipLink for Network {
    fn describe(&self) -> String {
        format!("EtherNet/IP target at {}", self.target)
    }

    fn request(&mut self, client: u8, msg: &[u8]) -> Result<Option<Vec<u8>>, String> {
        let stream = if client == 1 {
            &mut self.tcp
        } else {
            match self.others.entry(client) {
                std::collections::btree_map::Entry::Occupied(e) => e.into_mut(),
                std::collections::btree_map::Entry::Vacant(e) => {
                    e.insert(Stream::connect(self.target, self.timeout)?)
                }
            }
        };
        stream.request(msg, self.timeout)
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
