//! How the scanner reaches an EtherNet/IP target: the embedded adapter over an in-memory link
//! (same bytes, virtual clock) or a device on the network (TCP 44818, UDP 2222).

use std::collections::BTreeMap;
use std::net::{IpAddr, SocketAddr, SocketAddrV4, TcpStream, UdpSocket};
use std::rc::Rc;
use std::time::{Duration, Instant};

use socket2::{Domain, Protocol, SockAddr, Socket, Type};

use proto::enip::encap::{frame_len, HEADER_LEN};
use proto::enip::io::IO_PORT;
use sim::clock::{Clock, RealClock, VirtualClock};
use sim::enip::{Adapter, Framer};

use super::step::Split;
use crate::binding::StepError;
use crate::pcap::SharedTap;
use crate::poll::{PollingStream, REPLY_POLL};
use crate::timing::Deadline;

/// Why a link to an EtherNet/IP target failed: the link or the host, never the protocol (a
/// reply that breaks the protocol is the scanner's to judge). Every variant is an error
/// verdict for the step that met it.
#[derive(Debug, thiserror::Error)]
pub(crate) enum LinkError {
    /// The target closed the TCP connection, now or before: a connection it closed stays
    /// closed.
    #[error("the target closed the TCP connection{}", pending_text(.pending))]
    Closed {
        /// Bytes of an unfinished reply that had arrived when it closed.
        pending: Option<usize>,
    },
    /// The request's time ran out within a reply: its encapsulation header's length is
    /// past the bytes that followed. The length is a TCP stream's only framing (CIP Vol 2
    /// §2-3), so the scanner cannot tell where the next reply would begin: it closes the
    /// connection rather than read the next reply from the middle of this one.
    #[error(
        "the reply's encapsulation header says length {length} but {followed} bytes followed \
         within {}: the scanner closed the connection, a TCP stream having no other framing to \
         find the next reply by",
        crate::timing::ms(*limit)
    )]
    Incomplete {
        /// The header's length field.
        length: usize,
        /// Data bytes that followed the header.
        followed: usize,
        /// How long the scanner waited for the rest (the device's limit).
        limit: Duration,
    },
    /// A request on a connection the scanner closed after a reply it could not frame.
    #[error("the scanner closed the TCP connection after a reply whose length it could not frame")]
    Abandoned,
    /// A socket operation failed (connect, send, receive, bind).
    #[error("{what}: {source}")]
    Io {
        /// The operation, in words ("TCP send failed", "cannot connect to 10.0.0.2:44818").
        what: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The link cannot be recorded as asked (`--pcap`).
    #[error("{0}")]
    Record(String),
    /// The link cannot send a message as the step asks (in two segments).
    #[error("{0}")]
    Unsupported(String),
}

fn pending_text(pending: &Option<usize>) -> String {
    pending.map_or(String::new(), |n| {
        format!(" ({n} bytes of a reply pending)")
    })
}

/// A link error is an error verdict for the step ([`StepError::Link`]); a connection the
/// target closed or reset is the target's departure ([`StepError::Closed`]).
impl From<LinkError> for StepError {
    fn from(e: LinkError) -> StepError {
        let reset = |s: &std::io::Error| {
            matches!(
                s.kind(),
                std::io::ErrorKind::ConnectionReset
                    | std::io::ErrorKind::ConnectionAborted
                    | std::io::ErrorKind::BrokenPipe
            )
        };
        match &e {
            LinkError::Closed { .. } => StepError::Closed(e.into()),
            // The device's reply broke the stream's framing: the device's fault.
            LinkError::Incomplete { .. } => StepError::Protocol(e.into()),
            LinkError::Io { source, .. } if reset(source) => StepError::Closed(e.into()),
            _ => StepError::Link(e.into()),
        }
    }
}

impl LinkError {
    /// A closed connection, no reply pending.
    const CLOSED: LinkError = LinkError::Closed { pending: None };

    /// Wraps an I/O error of the operation `what`.
    fn io(what: impl Into<String>) -> impl FnOnce(std::io::Error) -> LinkError {
        let what = what.into();
        move |source| LinkError::Io { what, source }
    }
}

/// A way to an EtherNet/IP target.
pub(crate) trait EnipLink {
    /// What is reached.
    fn describe(&self) -> String;
    /// Sends one encapsulation message on the TCP connection of `client` (1 = the scanner's
    /// own; others are opened on first use); returns the reply, or `None` if none came by
    /// the end of `wait` (made as the message leaves; the embedded adapter answers at once or
    /// not at all). A connection the target closed stays closed: every later request is an
    /// error.
    fn request(
        &mut self,
        client: u8,
        msg: &[u8],
        wait: &Deadline,
    ) -> Result<Option<Vec<u8>>, LinkError>;
    /// The next message [`EnipLink::request`] sends (of any client) leaves in two TCP
    /// segments: its first `split.at` bytes, then, `split.gap` later, the rest — on the
    /// network two writes with TCP_NODELAY set, so each goes out as a segment of its own; the
    /// embedded adapter gets the two parts in that order. A message of `split.at` bytes or
    /// fewer goes whole.
    fn split_next(&mut self, split: Split) -> Result<(), LinkError> {
        let _ = split;
        Err(LinkError::Unsupported(format!(
            "{} cannot send a message in two segments",
            self.describe()
        )))
    }
    /// Sends one O→T datagram (if any), lets `rpi` pass, and returns the T→O datagrams that
    /// arrived meanwhile.
    fn io_cycle(
        &mut self,
        datagram: Option<&[u8]>,
        rpi: Duration,
    ) -> Result<Vec<Vec<u8>>, LinkError>;
    /// Gets ready to receive T→O data (before a Forward_Open), so none arrives at a closed port.
    fn prepare_io(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
    /// How long a request waits for its reply on a network link (`--timeout`); `None` for
    /// the embedded adapter, which answers at once or not at all.
    fn timeout(&self) -> Option<Duration> {
        None
    }
    /// The embedded adapter, for fault injection and observation.
    fn adapter(&mut self) -> Option<(&mut Adapter, Duration)>;
    /// Records the link's traffic into `tap` from now on, stamped with `clock` (the run's real
    /// time): a network link, with the addresses its sockets really use. The embedded link
    /// takes its tap when made and records on its virtual clock, so it refuses.
    fn record(&mut self, tap: SharedTap, clock: Rc<RealClock>) -> Result<(), LinkError> {
        let _ = (tap, clock);
        Err(LinkError::Record(format!(
            "{} records from its creation only",
            self.describe()
        )))
    }
}

/// How often a network I/O cycle looks for T→O datagrams.
const IO_POLL: Duration = Duration::from_micros(250);

/// `msg` as it leaves: whole, or in the two parts of `split` when it has bytes on both sides.
fn parts(msg: &[u8], split: Option<Split>) -> (Vec<&[u8]>, Duration) {
    match split {
        Some(s) if s.at > 0 && s.at < msg.len() => {
            let (a, b) = msg.split_at(s.at);
            (vec![a, b], s.gap)
        }
        _ => (vec![msg], Duration::ZERO),
    }
}

/// The peer address the embedded adapter sees (the scanner's).
const SCANNER_V4: SocketAddrV4 =
    SocketAddrV4::new(std::net::Ipv4Addr::new(192, 168, 1, 10), 50_000);
const SCANNER: SocketAddr = SocketAddr::V4(SCANNER_V4);

/// A link's place in the run's capture: the tap, and the clock its packets are stamped with
/// (plus `base`): an embedded case's virtual clock, placed after the run's last packet, or
/// the run's real one.
#[derive(Clone)]
struct Recorder {
    tap: SharedTap,
    clock: Rc<dyn Clock>,
    base: Duration,
}

impl Recorder {
    /// An embedded case's recorder: its virtual time starts 1 ms after the run's last packet.
    fn embedded(tap: SharedTap, clock: Rc<VirtualClock>) -> Recorder {
        let base = tap.borrow().last + Duration::from_millis(1);
        Recorder { tap, clock, base }
    }

    /// A network link's recorder: packets at the time since the run started.
    fn network(tap: SharedTap, clock: Rc<RealClock>) -> Recorder {
        Recorder {
            tap,
            clock,
            base: Duration::ZERO,
        }
    }

    /// Now on the capture's time line; the tap's latest time follows.
    fn now(&self) -> Duration {
        let t = self.base + self.clock.now();
        let mut tap = self.tap.borrow_mut();
        tap.last = tap.last.max(t);
        t
    }

    /// The scanner's address on the embedded link's next connection: a port of its own.
    fn embedded_client(&self) -> SocketAddrV4 {
        let connections = self.tap.borrow_mut().capture.tcp_connections();
        let port = 50_000u16.wrapping_add(connections.wrapping_add(1) % 10_000);
        SocketAddrV4::new(*SCANNER_V4.ip(), port)
    }

    /// A TCP connection from `client` to `server` opened: its handshake, now.
    fn connect(&self, client: SocketAddrV4, server: SocketAddrV4) -> Connection {
        let t = self.now();
        self.tap.borrow_mut().capture.tcp_connect(client, server, t);
        Connection {
            recorder: self.clone(),
            client,
            server,
            open: true,
        }
    }

    /// A UDP datagram, now.
    fn udp(&self, from: SocketAddrV4, to: SocketAddrV4, bytes: &[u8]) {
        let t = self.now();
        self.tap.borrow_mut().capture.udp(from, to, bytes, t);
    }
}

/// One recorded TCP connection.
struct Connection {
    recorder: Recorder,
    client: SocketAddrV4,
    server: SocketAddrV4,
    /// Whether it is still open in the capture; nothing is recorded on it once closed.
    open: bool,
}

impl Connection {
    /// Stream bytes, client to server or back, now.
    fn tcp(&self, to_server: bool, bytes: &[u8]) {
        if !self.open {
            return;
        }
        let t = self.recorder.now();
        let (from, to) = if to_server {
            (self.client, self.server)
        } else {
            (self.server, self.client)
        };
        self.recorder
            .tap
            .borrow_mut()
            .capture
            .tcp_data(from, to, bytes, t);
    }

    /// The connection closed now, by the server or by the client: the FIN exchange.
    fn close(&mut self, by_server: bool) {
        if !std::mem::replace(&mut self.open, false) {
            return;
        }
        let t = self.recorder.now();
        let (from, to) = if by_server {
            (self.server, self.client)
        } else {
            (self.client, self.server)
        };
        self.recorder
            .tap
            .borrow_mut()
            .capture
            .tcp_close(from, to, t);
    }
}

/// The embedded adapter behind an in-memory link.
pub(crate) struct Embedded {
    adapter: Adapter,
    /// The adapter's address.
    server: SocketAddrV4,
    clock: Rc<VirtualClock>,
    /// Per client, its framer; `None` once the adapter closed the connection.
    clients: BTreeMap<u8, Option<Framer>>,
    recorder: Option<Recorder>,
    /// Per client, its recorded connection (the scanner's own from the start, the others
    /// from their first message).
    recorded: BTreeMap<u8, Connection>,
    /// How the next message leaves ([`EnipLink::split_next`]).
    split: Option<Split>,
}

impl Embedded {
    pub(crate) fn new(adapter: Adapter, server: SocketAddrV4, tap: Option<SharedTap>) -> Embedded {
        let clock = Rc::new(VirtualClock::new());
        let recorder = tap.map(|t| Recorder::embedded(t, clock.clone()));
        let recorded = recorder
            .iter()
            .map(|r| (1, r.connect(r.embedded_client(), server)))
            .collect();
        Embedded {
            adapter,
            server,
            clock,
            clients: BTreeMap::new(),
            recorder,
            recorded,
            split: None,
        }
    }

    /// The UDP I/O addresses (2222 on both hosts), O→T or T→O.
    fn io_addrs(&self, to_server: bool) -> (SocketAddrV4, SocketAddrV4) {
        let c = SocketAddrV4::new(*SCANNER_V4.ip(), IO_PORT);
        let s = SocketAddrV4::new(*self.server.ip(), IO_PORT);
        if to_server {
            (c, s)
        } else {
            (s, c)
        }
    }
}

impl Drop for Embedded {
    fn drop(&mut self) {
        for c in self.recorded.values_mut() {
            c.close(false);
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

    fn request(
        &mut self,
        client: u8,
        msg: &[u8],
        _wait: &Deadline,
    ) -> Result<Option<Vec<u8>>, LinkError> {
        let (parts, gap) = parts(msg, self.split.take());
        let id = u64::from(client);
        let peer = SocketAddr::V4(SocketAddrV4::new(
            *SCANNER_V4.ip(),
            SCANNER_V4.port() + u16::from(client),
        ));
        let mut reply = None;
        let mut close = false;
        for (i, part) in parts.iter().enumerate() {
            if i > 0 {
                // The second segment, `gap` after the first, on the virtual clock.
                self.clock.advance(gap);
            }
            let now = self.clock.now();
            if let Some(r) = &self.recorder {
                let server = self.server;
                self.recorded
                    .entry(client)
                    .or_insert_with(|| r.connect(r.embedded_client(), server))
                    .tcp(true, part);
            }
            let slot = self
                .clients
                .entry(client)
                .or_insert_with(|| Some(Framer::new()));
            let Some(framer) = slot else {
                return Err(LinkError::CLOSED);
            };
            // The served adapter drops a client whose message exceeds the framer's limit.
            let messages = match framer.push(part) {
                Ok(m) => m,
                Err(_) => {
                    close = true;
                    Vec::new()
                }
            };
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
            if close {
                break;
            }
        }
        if let (Some(c), Some(b)) = (self.recorded.get(&client), &reply) {
            c.tcp(false, b);
        }
        if close {
            if let Some(c) = self.recorded.get_mut(&client) {
                c.close(true);
            }
            self.clients.insert(client, None);
            self.adapter.client_closed(id);
            if reply.is_none() {
                return Err(LinkError::CLOSED);
            }
        }
        Ok(reply)
    }

    fn split_next(&mut self, split: Split) -> Result<(), LinkError> {
        self.split = Some(split);
        Ok(())
    }

    fn io_cycle(
        &mut self,
        datagram: Option<&[u8]>,
        rpi: Duration,
    ) -> Result<Vec<Vec<u8>>, LinkError> {
        if let Some(d) = datagram {
            if let Some(r) = &self.recorder {
                let (from, to) = self.io_addrs(true);
                r.udp(from, to, d);
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
            let (from, to) = self.io_addrs(false);
            for b in &out {
                r.udp(from, to, b);
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
    /// The local address of the scanner's TCP connection, where T→O data is expected.
    local: IpAddr,
    /// UDP 2222 on `local`, bound when I/O starts: a run without I/O (the `cip` profile)
    /// does not hold the port, so other scanners on the machine can.
    udp: Option<UdpSocket>,
    timeout: Duration,
    /// Where the traffic is recorded, once [`EnipLink::record`] was called.
    recorder: Option<Recorder>,
    /// How the next message leaves ([`EnipLink::split_next`]).
    split: Option<Split>,
}

/// One TCP connection and the bytes received beyond the last reply.
struct Stream {
    tcp: Option<PollingStream>,
    buf: Vec<u8>,
    /// The sender contexts of requests whose reply did not come in time, latest last (at
    /// most [`STALE`]): a reply that comes after all carries its request's context (CIP Vol 2
    /// §2-3.2), and is dropped rather than taken for the reply to a later request.
    stale: Vec<[u8; 8]>,
    /// Its record: bytes as they were sent and as they arrived, with the real addresses.
    recorded: Option<Connection>,
    /// The scanner closed it, its framing lost ([`LinkError::Incomplete`]).
    abandoned: bool,
}

impl Stream {
    fn connect(
        target: SocketAddr,
        local: Option<IpAddr>,
        timeout: Duration,
        recorder: Option<&Recorder>,
    ) -> Result<Stream, LinkError> {
        let tcp = connect_from(target, local, timeout)
            .map_err(LinkError::io(format!("cannot connect to {target}")))?;
        tcp.set_nodelay(true)
            .map_err(LinkError::io(format!("TCP_NODELAY to {target}")))?;
        let tcp = PollingStream::new(tcp, REPLY_POLL)
            .map_err(LinkError::io(format!("TCP to {target}")))?;
        let mut stream = Stream {
            tcp: Some(tcp),
            buf: Vec::new(),
            stale: Vec::new(),
            recorded: None,
            abandoned: false,
        };
        if let Some(r) = recorder {
            stream.record(r)?;
        }
        Ok(stream)
    }

    /// Records the connection from now on: its handshake first.
    fn record(&mut self, recorder: &Recorder) -> Result<(), LinkError> {
        let Some(tcp) = &self.tcp else {
            return Ok(());
        };
        let local = tcp
            .get()
            .local_addr()
            .map_err(LinkError::io("the TCP connection's local address"))?;
        let peer = tcp
            .get()
            .peer_addr()
            .map_err(LinkError::io("the TCP connection's peer address"))?;
        let (SocketAddr::V4(client), SocketAddr::V4(server)) = (local, peer) else {
            return Err(LinkError::Record(format!(
                "{local} → {peer}: a pcap records IPv4 only"
            )));
        };
        self.recorded = Some(recorder.connect(client, server));
        Ok(())
    }

    /// Sends `msg` (in the two segments of `split`, if given), waits until the end of `wait`
    /// for one whole reply (a late reply to an earlier request dropped).
    fn request(
        &mut self,
        msg: &[u8],
        split: Option<Split>,
        wait: &Deadline,
    ) -> Result<Option<Vec<u8>>, LinkError> {
        let (parts, gap) = parts(msg, split);
        for (i, part) in parts.iter().enumerate() {
            if i > 0 {
                // TCP_NODELAY is set (`connect`): the first part left as a segment of its own
                // and the second leaves as another.
                std::thread::sleep(gap);
            }
            let tcp = self.open()?;
            tcp.write_all(part, wait.remaining())
                .map_err(LinkError::io("TCP send failed"))?;
            if let Some(c) = &self.recorded {
                c.tcp(true, part);
            }
        }
        let context = sender_context(msg);
        let mut chunk = [0u8; 4096];
        loop {
            if let Some(n) = frame_len(&self.buf).filter(|n| self.buf.len() >= *n) {
                let frame: Vec<u8> = self.buf.drain(..n).collect();
                let late = sender_context(&frame)
                    .filter(|c| Some(*c) != context)
                    .and_then(|c| self.stale.iter().position(|s| *s == c));
                match late {
                    Some(i) => {
                        self.stale.remove(i);
                        continue;
                    }
                    None => return Ok(Some(frame)),
                }
            }
            let left = wait.remaining();
            if left.is_zero() {
                if let Some(n) = frame_len(&self.buf) {
                    let followed = self.buf.len() - HEADER_LEN;
                    self.abandon();
                    return Err(LinkError::Incomplete {
                        length: n - HEADER_LEN,
                        followed,
                        limit: wait.limit(),
                    });
                }
                if let Some(c) = context {
                    if self.stale.len() == STALE {
                        self.stale.remove(0);
                    }
                    self.stale.push(c);
                }
                return Ok(None);
            }
            match self.open()?.read(&mut chunk, left) {
                Ok(0) => {
                    self.tcp = None;
                    if let Some(c) = &mut self.recorded {
                        c.close(true);
                    }
                    return Err(LinkError::Closed {
                        pending: Some(self.buf.len()),
                    });
                }
                Ok(n) => {
                    // As it arrived: a reply that came in pieces stays in pieces.
                    if let Some(c) = &self.recorded {
                        c.tcp(false, &chunk[..n]);
                    }
                    self.buf.extend_from_slice(&chunk[..n]);
                }
                // The wait may have moved meanwhile (the host was late): looked at again.
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(e) => {
                    // A reset, most likely: the capture has no way to show it and stops here.
                    self.tcp = None;
                    self.recorded = None;
                    return Err(LinkError::io("TCP receive failed")(e));
                }
            }
        }
    }
}

impl Stream {
    /// The connection, unless it was closed.
    fn open(&mut self) -> Result<&mut PollingStream, LinkError> {
        match &mut self.tcp {
            Some(tcp) => Ok(tcp),
            None if self.abandoned => Err(LinkError::Abandoned),
            None => Err(LinkError::CLOSED),
        }
    }

    /// Closes the connection from the scanner's side, its framing lost.
    fn abandon(&mut self) {
        if let Some(tcp) = self.tcp.take() {
            let _ = tcp.get().shutdown(std::net::Shutdown::Both);
        }
        if let Some(c) = &mut self.recorded {
            c.close(false);
        }
        self.buf.clear();
        self.abandoned = true;
    }
}

/// Requests without a reply in time whose replies a stream still recognises as late.
const STALE: usize = 16;

/// The sender context of an encapsulation message (bytes 12..20 of its header), if it has a
/// whole header.
fn sender_context(msg: &[u8]) -> Option<[u8; 8]> {
    msg.get(12..20)?.try_into().ok()
}

/// A TCP connection to `target`, from `local` (any port) when given, else from the address
/// the routing table picks.
fn connect_from(
    target: SocketAddr,
    local: Option<IpAddr>,
    timeout: Duration,
) -> std::io::Result<TcpStream> {
    let Some(local) = local else {
        return TcpStream::connect_timeout(&target, timeout);
    };
    let socket = Socket::new(
        Domain::for_address(target),
        Type::STREAM,
        Some(Protocol::TCP),
    )?;
    socket.bind(&SockAddr::from(SocketAddr::new(local, 0)))?;
    socket.connect_timeout(&SockAddr::from(target), timeout)?;
    Ok(socket.into())
}

impl Drop for Stream {
    fn drop(&mut self) {
        if let Some(c) = &mut self.recorded {
            c.close(false);
        }
    }
}

impl Network {
    /// Connects to `target` (TCP), from `local` when given: T→O data is then expected on
    /// `local`'s UDP 2222.
    pub(crate) fn connect(
        target: SocketAddr,
        local: Option<IpAddr>,
        timeout: Duration,
    ) -> Result<Network, LinkError> {
        let tcp = Stream::connect(target, local, timeout, None)?;
        let local = match &tcp.tcp {
            Some(t) => t
                .get()
                .local_addr()
                .map_err(LinkError::io("the TCP connection's local address"))?,
            None => return Err(LinkError::CLOSED),
        };
        Ok(Network {
            target,
            tcp,
            others: BTreeMap::new(),
            local: local.ip(),
            udp: None,
            timeout,
            recorder: None,
            split: None,
        })
    }
}

/// UDP 2222 on `local`, where the target sends T→O data; bound on first use.
fn io_socket(slot: &mut Option<UdpSocket>, local: IpAddr) -> Result<&UdpSocket, LinkError> {
    if let Some(udp) = slot {
        return Ok(udp);
    }
    let at = SocketAddr::new(local, IO_PORT);
    let udp =
        UdpSocket::bind(at).map_err(LinkError::io(format!("cannot bind UDP {at} for T→O data")))?;
    // Read without blocking: `io_cycle` keeps its own time.
    udp.set_nonblocking(true)
        .map_err(LinkError::io(format!("UDP {at}")))?;
    Ok(slot.insert(udp))
}

impl EnipLink for Network {
    fn describe(&self) -> String {
        format!("EtherNet/IP target at {}", self.target)
    }

    fn timeout(&self) -> Option<Duration> {
        Some(self.timeout)
    }

    fn request(
        &mut self,
        client: u8,
        msg: &[u8],
        wait: &Deadline,
    ) -> Result<Option<Vec<u8>>, LinkError> {
        let split = self.split.take();
        let stream = if client == 1 {
            &mut self.tcp
        } else {
            match self.others.entry(client) {
                std::collections::btree_map::Entry::Occupied(e) => e.into_mut(),
                std::collections::btree_map::Entry::Vacant(e) => e.insert(Stream::connect(
                    self.target,
                    Some(self.local),
                    self.timeout,
                    self.recorder.as_ref(),
                )?),
            }
        };
        stream.request(msg, split, wait)
    }

    fn split_next(&mut self, split: Split) -> Result<(), LinkError> {
        self.split = Some(split);
        Ok(())
    }

    fn io_cycle(
        &mut self,
        datagram: Option<&[u8]>,
        rpi: Duration,
    ) -> Result<Vec<Vec<u8>>, LinkError> {
        let target = self.target.ip();
        let udp = io_socket(&mut self.udp, self.local)?;
        // The socket's own address (it is bound there), if IPv4: the only kind recorded.
        let local = match self.local {
            IpAddr::V4(ip) => Some(SocketAddrV4::new(ip, IO_PORT)),
            IpAddr::V6(_) => None,
        };
        if let Some(d) = datagram {
            let to = SocketAddr::new(target, IO_PORT);
            udp.send_to(d, to)
                .map_err(LinkError::io("UDP send failed"))?;
            if let (Some(r), Some(from), SocketAddr::V4(to)) = (&self.recorder, local, to) {
                r.udp(from, to, d);
            }
        }
        let deadline = Instant::now() + rpi;
        let mut out = Vec::new();
        let mut buf = [0u8; 1500];
        loop {
            loop {
                match udp.recv_from(&mut buf) {
                    Ok((n, from)) => {
                        if let (Some(r), SocketAddr::V4(from), Some(to)) =
                            (&self.recorder, from, local)
                        {
                            r.udp(from, to, &buf[..n]);
                        }
                        out.push(buf[..n].to_vec());
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => return Err(LinkError::io("UDP receive failed")(e)),
                }
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(out);
            }
            // A sleep is precise to tens of µs, where a socket timeout rounds up to the
            // kernel's tick (4 ms here, a whole RPI).
            std::thread::sleep(left.min(IO_POLL));
        }
    }

    fn prepare_io(&mut self) -> Result<(), LinkError> {
        io_socket(&mut self.udp, self.local).map(|_| ())
    }

    fn adapter(&mut self) -> Option<(&mut Adapter, Duration)> {
        None
    }

    fn record(&mut self, tap: SharedTap, clock: Rc<RealClock>) -> Result<(), LinkError> {
        if self.recorder.is_some() {
            return Err(LinkError::Record("the link is recorded already".into()));
        }
        let recorder = Recorder::network(tap, clock);
        self.tcp.record(&recorder)?;
        for stream in self.others.values_mut() {
            stream.record(&recorder)?;
        }
        self.recorder = Some(recorder);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};
    use std::net::{Ipv4Addr, TcpListener};

    /// ListIdentity, sender context "SPLIT-ME": 24 bytes, a header alone.
    const LIST_IDENTITY: [u8; 24] = [
        0x63, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, b'S', b'P', b'L', b'I', b'T', b'-', b'M', b'E', 0,
        0, 0, 0,
    ];

    #[test]
    fn the_embedded_adapter_gets_a_split_message_in_order() {
        use sim::device::{Device, DeviceConfig};
        let server = SocketAddrV4::new(Ipv4Addr::new(192, 168, 1, 20), 44818);
        let adapter = Adapter::new(
            Device::new(DeviceConfig::new(proto::nord::Product::Sk550p)),
            server,
        );
        let mut link = Embedded::new(adapter, server, None);
        let wait = Deadline::after(Duration::ZERO);
        link.split_next(Split {
            at: 10,
            gap: Duration::from_millis(50),
        })
        .unwrap();
        let reply = link.request(1, &LIST_IDENTITY, &wait).unwrap().unwrap();
        assert_eq!(&reply[..2], &[0x63, 0]);
        assert_eq!(&reply[12..20], &LIST_IDENTITY[12..20]);
        // The second part came 50 ms after the first, on the virtual clock; the split was
        // for that message only.
        assert_eq!(link.clock.now(), Duration::from_millis(50));
        assert!(link.split.is_none());
        assert!(link.request(1, &LIST_IDENTITY, &wait).unwrap().is_some());
    }

    #[test]
    fn a_network_link_sends_a_split_message_as_two_segments() {
        let listener = TcpListener::bind("127.0.0.14:0").unwrap();
        let target = listener.local_addr().unwrap();
        let gap = Duration::from_millis(50);
        let server = std::thread::spawn(move || {
            let (mut tcp, _) = listener.accept().unwrap();
            let mut buf = [0u8; 64];
            // Loopback and TCP_NODELAY: the first write arrives alone.
            let first = tcp.read(&mut buf).unwrap();
            let start = Instant::now();
            let mut got = buf[..first].to_vec();
            while got.len() < LIST_IDENTITY.len() {
                let n = tcp.read(&mut buf).unwrap();
                assert!(n > 0, "closed after {} bytes", got.len());
                got.extend_from_slice(&buf[..n]);
            }
            let apart = start.elapsed();
            // The reply: the request's header back, status 0, no data.
            tcp.write_all(&got).unwrap();
            (first, got, apart)
        });
        let mut link = Network::connect(target, None, Duration::from_secs(2)).unwrap();
        link.split_next(Split { at: 10, gap }).unwrap();
        let reply = link
            .request(1, &LIST_IDENTITY, &Deadline::after(Duration::from_secs(2)))
            .unwrap();
        let (first, got, apart) = server.join().unwrap();
        assert_eq!(first, 10);
        assert_eq!(got, LIST_IDENTITY);
        assert!(apart >= gap - Duration::from_millis(5), "{apart:?} apart");
        assert_eq!(reply.as_deref(), Some(&LIST_IDENTITY[..]));
        assert!(link.split.is_none());
    }

    /// A reply whose header says 4 bytes more than follow: the scanner waits out its limit,
    /// names the length and the bytes, and closes the connection; the next request on it
    /// says so rather than read from the middle of the broken reply.
    #[test]
    fn a_reply_longer_by_its_header_than_its_bytes_ends_the_connection() {
        let listener = TcpListener::bind("127.0.0.14:0").unwrap();
        let target = listener.local_addr().unwrap();
        let server = std::thread::spawn(move || {
            let (mut tcp, _) = listener.accept().unwrap();
            let mut got = [0u8; 24];
            tcp.read_exact(&mut got).unwrap();
            // The request's header back, its length 4 with no data after it.
            got[2] = 4;
            tcp.write_all(&got).unwrap();
            // Until the scanner closes.
            let mut rest = [0u8; 64];
            while tcp.read(&mut rest).is_ok_and(|n| n > 0) {}
        });
        let mut link = Network::connect(target, None, Duration::from_secs(2)).unwrap();
        let wait = Deadline::after(Duration::from_millis(100));
        let e = link.request(1, &LIST_IDENTITY, &wait).unwrap_err();
        assert_eq!(
            e.to_string(),
            "the reply's encapsulation header says length 4 but 0 bytes followed within 100 ms: \
             the scanner closed the connection, a TCP stream having no other framing to find \
             the next reply by"
        );
        assert!(matches!(StepError::from(e), StepError::Protocol(_)));
        server.join().unwrap();
        let again = Deadline::after(Duration::from_millis(100));
        let e = link.request(1, &LIST_IDENTITY, &again).unwrap_err();
        assert!(matches!(e, LinkError::Abandoned), "{e}");
    }

    #[test]
    fn a_split_that_leaves_a_side_empty_sends_the_message_whole() {
        let gap = Duration::from_millis(50);
        let whole = parts(&LIST_IDENTITY, Some(Split { at: 24, gap }));
        assert_eq!(whole, (vec![&LIST_IDENTITY[..]], Duration::ZERO));
        let (two, g) = parts(&LIST_IDENTITY, Some(Split { at: 10, gap }));
        assert_eq!(two, vec![&LIST_IDENTITY[..10], &LIST_IDENTITY[10..]]);
        assert_eq!(g, gap);
    }

    #[test]
    fn a_network_link_connects_from_its_local_address_and_takes_its_io_port() {
        let listener = TcpListener::bind("127.0.0.14:0").unwrap();
        let target = listener.local_addr().unwrap();
        let local = IpAddr::V4(Ipv4Addr::new(127, 0, 0, 15));
        let mut link = Network::connect(target, Some(local), Duration::from_secs(2)).unwrap();
        let (_, peer) = listener.accept().unwrap();
        assert_eq!(peer.ip(), local);
        link.prepare_io().unwrap();
        let taken = UdpSocket::bind(SocketAddr::new(local, IO_PORT)).unwrap_err();
        assert_eq!(taken.kind(), std::io::ErrorKind::AddrInUse);
        // Another scanner on another address has its own UDP 2222.
        let other = IpAddr::V4(Ipv4Addr::new(127, 0, 0, 16));
        let mut second = Network::connect(target, Some(other), Duration::from_secs(2)).unwrap();
        second.prepare_io().unwrap();
    }

    #[test]
    fn a_local_address_that_is_not_ours_is_a_connect_error() {
        let listener = TcpListener::bind("127.0.0.14:0").unwrap();
        let target = listener.local_addr().unwrap();
        let foreign = IpAddr::V4(Ipv4Addr::new(192, 0, 2, 1));
        let e = Network::connect(target, Some(foreign), Duration::from_secs(1))
            .err()
            .unwrap();
        assert!(
            matches!(&e, LinkError::Io { what, .. } if what.starts_with("cannot connect to 127.0.0.14")),
            "{e}"
        );
    }
}
