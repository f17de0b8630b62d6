//! `harness serve can --socketcand ADDR` (or `--iface IFACE`, on a CAN interface of the host
//! through SocketCAN, [`serve_iface`]): the simulated system bus (a CAN segment carrying the
//! inverters as CANopen nodes, `sim::can`) served over socketcand's TCP protocol, the way a CAN
//! bus on another machine is reached (a Raspberry Pi on a test bench running socketcand).
//!
//! As on a real bus, every client sees every other client's frames, and all see the nodes'
//! answers: other implementations (python-can, python-canopen) join the segment as nodes or as
//! its master. A client first gets `< hi >`, opens the channel (`< open can0 >`, another name
//! is refused as socketcand refuses an interface it does not have) and switches to raw mode;
//! then `< send … >` puts a frame on the bus and `< frame … >` brings each frame of the bus.
//!
//! Threads: one accepting clients, one per client reading its messages, one producing what
//! the nodes send on their own schedule (heartbeats). The sans-IO segment sits behind a mutex;
//! its clock is the real time since the start.

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use proto::can::socketcand::{Framed, Message, Timestamp, MAX_MESSAGE_LEN};
use proto::can::CanFrame;
use proto::nord::Product;
use sim::can::Segment;
use sim::device::DeviceConfig;

/// socketcand's own default port.
pub(crate) const DEFAULT_PORT: u16 = 29536;

/// The longest the producer sleeps when no node has anything due.
const IDLE: Duration = Duration::from_millis(20);

/// `harness serve can` arguments.
#[derive(clap::Parser, Debug)]
#[command(
    name = "harness serve can",
    about = "Serve the simulated NORD system bus (CANopen on CAN) over socketcand"
)]
struct ServeArgs {
    /// Listen address of the socketcand server, HOST[:PORT] (port 29536 by default).
    #[arg(
        long,
        value_name = "ADDR",
        required_unless_present = "iface",
        conflicts_with = "iface"
    )]
    socketcand: Option<String>,
    /// Serve on this CAN interface of the host instead (SocketCAN: `can0` on an adapter,
    /// `vcan0`).
    #[arg(long, value_name = "IFACE")]
    iface: Option<String>,
    /// The bus name clients open (`< open NAME >`).
    #[arg(long, default_value = "can0")]
    channel: String,
    /// Product profile: whose inverters are on the bus (sk550p, tu3-eip, …).
    #[arg(long, default_value = "sk550p")]
    profile: String,
    /// Inverters on the bus (default: the product's maximum).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    inverters: Option<u8>,
    /// Stop after this many seconds (default: serve until killed).
    #[arg(long)]
    seconds: Option<u64>,
}

/// `harness serve can ARGS…`; returns the exit code.
pub(super) fn command(args: &[String]) -> Result<i32, String> {
    let a = match crate::args::parse_args::<ServeArgs>("harness serve can", args) {
        Ok(a) => a,
        Err(code) => return Ok(code),
    };
    let product = crate::profile::product_named(&a.profile)?;
    let (Some(socketcand), None) = (&a.socketcand, &a.iface) else {
        let iface = a.iface.as_deref().unwrap_or_default();
        return serve_iface(
            iface,
            config(product, a.inverters),
            a.seconds.map(Duration::from_secs),
        )
        .map(|()| crate::exit::EXIT_PASS);
    };
    let addr = crate::net::serve_args::socket_addr(socketcand, DEFAULT_PORT)?;
    let listener = TcpListener::bind(addr).map_err(|e| format!("cannot listen on {addr}: {e}"))?;
    let served = Served::start(listener, config(product, a.inverters), a.channel)?;
    // On stdout, once the socket is bound: what a test or a script waits for.
    outln!(
        "serving the system bus of {} ({} inverters, nodes {}) over socketcand on {}, channel {}",
        product.name(),
        served.nodes.len(),
        served
            .nodes
            .iter()
            .map(u8::to_string)
            .collect::<Vec<_>>()
            .join(", "),
        served.addr,
        served.channel
    );
    let (inverters, cycle) = (
        served.nodes.len() as u8,
        bus_time(product, served.nodes.len()),
    );
    outln!(
        "a process-data cycle of the {inverters} inverters takes up to {:.2} ms of the bus at 250 kBaud (worst-case bit stuffing; the manuals allow cycles from {} ms)",
        f64::from(cycle) / 1000.0,
        proto::nord::can::MIN_CYCLE_US / 1000
    );
    match a.seconds {
        Some(s) => thread::sleep(Duration::from_secs(s)),
        None => loop {
            thread::park();
        },
    }
    served.stop();
    Ok(crate::exit::EXIT_PASS)
}

/// `harness serve can --iface IFACE`: the segment on a CAN interface of this host, one thread:
/// each frame read is the nodes' to answer, and what they send on their own goes out when due;
/// until `duration` has passed (forever when `None`).
fn serve_iface(
    iface: &str,
    config: DeviceConfig,
    duration: Option<Duration>,
) -> Result<(), String> {
    use super::link::CanLink;
    let mut link = super::socketcan::SocketCan::open(iface).map_err(|e| e.to_string())?;
    let mut segment = Segment::new(config).map_err(|e| e.to_string())?;
    outln!(
        "serving the system bus of {} (nodes {}) on CAN interface {iface}",
        config.product.name(),
        segment
            .nodes()
            .iter()
            .map(u8::to_string)
            .collect::<Vec<_>>()
            .join(", ")
    );
    let start = Instant::now();
    while duration.is_none_or(|d| start.elapsed() < d) {
        let now = start.elapsed();
        for f in segment.poll(now) {
            link.send(&f).map_err(|e| e.to_string())?;
        }
        let wait = segment
            .next_due()
            .map_or(IDLE, |d| d.saturating_sub(now).min(IDLE))
            .max(Duration::from_micros(200));
        if let Some(frame) = link.recv(wait).map_err(|e| e.to_string())? {
            for f in segment.receive(&frame, start.elapsed()) {
                link.send(&f).map_err(|e| e.to_string())?;
            }
        }
    }
    Ok(())
}

/// The product with `inverters` (default and ceiling: its maximum).
fn config(product: Product, inverters: Option<u8>) -> DeviceConfig {
    let max = product.max_inverters();
    DeviceConfig {
        inverters: inverters.unwrap_or(max).clamp(1, max),
        ..DeviceConfig::new(product)
    }
}

/// The bus time of one process-data cycle of `inverters` of `product`'s series with the most
/// process values (`proto::nord::can::cycle_bus_time_us`), µs.
fn bus_time(product: Product, inverters: usize) -> u32 {
    proto::nord::can::inverter_series(product)
        .iter()
        .map(|s| proto::nord::can::cycle_bus_time_us(*s, inverters as u8))
        .max()
        .unwrap_or(0)
}

/// One connected client.
struct Client {
    id: u64,
    stream: TcpStream,
    /// Switched to raw mode: gets every frame of the bus.
    raw: bool,
}

/// What the threads share: the segment (none on a relay, [`Served::relay`]) and the clients.
struct Hub {
    segment: Option<Mutex<Segment>>,
    clients: Mutex<Vec<Client>>,
    start: Instant,
    channel: String,
    stop: AtomicBool,
    next_id: AtomicU64,
}

impl Hub {
    fn now(&self) -> Duration {
        self.start.elapsed()
    }

    fn segment(&self) -> Option<MutexGuard<'_, Segment>> {
        self.segment
            .as_ref()
            .map(|s| s.lock().unwrap_or_else(|p| p.into_inner()))
    }

    fn clients(&self) -> MutexGuard<'_, Vec<Client>> {
        self.clients.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// `frames` to every raw-mode client but `except`; a client that cannot take them is
    /// dropped.
    fn broadcast(&self, frames: &[CanFrame], except: Option<u64>) {
        let now = self.now();
        let stamped: Vec<(Duration, CanFrame)> = frames.iter().map(|f| (now, *f)).collect();
        self.broadcast_at(&stamped, except);
    }

    /// [`Hub::broadcast`] with each frame's own time (a relayed bus's, when it was on it).
    fn broadcast_at(&self, frames: &[(Duration, CanFrame)], except: Option<u64>) {
        if frames.is_empty() {
            return;
        }
        let mut text = String::new();
        for (at, frame) in frames {
            let m = Message::Frame {
                frame: *frame,
                time: Timestamp {
                    secs: at.as_secs(),
                    usecs: at.subsec_micros(),
                },
            };
            // A frame of the segment is a data frame of at most 8 bytes: always writable.
            if let Ok(s) = m.emit() {
                text.push_str(&s);
            }
        }
        self.clients().retain_mut(|c| {
            if !c.raw || Some(c.id) == except {
                return true;
            }
            c.stream.write_all(text.as_bytes()).is_ok()
        });
    }

    /// A client put `frame` on the bus: the others see it, the nodes take it and answer.
    fn transmit(&self, from: u64, frame: &CanFrame) {
        self.broadcast(std::slice::from_ref(frame), Some(from));
        let answers = self
            .segment()
            .map(|mut s| s.receive(frame, self.now()))
            .unwrap_or_default();
        self.broadcast(&answers, None);
    }
}

/// A segment being served.
pub(crate) struct Served {
    hub: Arc<Hub>,
    /// Where it listens.
    pub(crate) addr: SocketAddr,
    /// The bus name clients open.
    pub(crate) channel: String,
    /// The CANopen node ids of the inverters.
    pub(crate) nodes: Vec<u8>,
}

impl Served {
    /// Serves the segment of `config` to the clients of `listener`.
    pub(crate) fn start(
        listener: TcpListener,
        config: DeviceConfig,
        channel: String,
    ) -> Result<Served, String> {
        let segment = Segment::new(config).map_err(|e| e.to_string())?;
        let served = Served::hub(listener, Some(segment), channel)?;
        let h = served.hub.clone();
        thread::spawn(move || produce(&h));
        Ok(served)
    }

    /// A bus with no nodes of its own, to `listener`'s clients: what [`relay_system_bus`] puts
    /// on it (a served bus module's system bus, seen from its gateway) and what the clients
    /// send each other.
    fn relay(listener: TcpListener, channel: String) -> Result<Served, String> {
        Served::hub(listener, None, channel)
    }

    fn hub(
        listener: TcpListener,
        segment: Option<Segment>,
        channel: String,
    ) -> Result<Served, String> {
        let addr = listener.local_addr().map_err(|e| e.to_string())?;
        let nodes = segment.as_ref().map(Segment::nodes).unwrap_or_default();
        let hub = Arc::new(Hub {
            segment: segment.map(Mutex::new),
            clients: Mutex::new(Vec::new()),
            start: Instant::now(),
            channel: channel.clone(),
            stop: AtomicBool::new(false),
            next_id: AtomicU64::new(1),
        });
        let h = hub.clone();
        thread::spawn(move || accept(&h, &listener));
        Ok(Served {
            hub,
            addr,
            channel,
            nodes,
        })
    }

    /// Stops serving: the clients are disconnected.
    pub(crate) fn stop(&self) {
        self.hub.stop.store(true, Ordering::Relaxed);
        for c in self.hub.clients().drain(..) {
            let _ = c.stream.shutdown(Shutdown::Both);
        }
        // Wakes the acceptor, which then sees the stop.
        let _ = TcpStream::connect_timeout(&self.addr, Duration::from_millis(200));
    }
}

fn accept(hub: &Arc<Hub>, listener: &TcpListener) {
    for stream in listener.incoming() {
        if hub.stop.load(Ordering::Relaxed) {
            return;
        }
        let Ok(stream) = stream else { continue };
        let hub = hub.clone();
        thread::spawn(move || {
            let _ = serve_client(&hub, stream);
        });
    }
}

/// The nodes' own frames (heartbeats) when due.
fn produce(hub: &Hub) {
    while !hub.stop.load(Ordering::Relaxed) {
        let now = hub.now();
        let Some((frames, due)) = hub.segment().map(|mut s| (s.poll(now), s.next_due())) else {
            return;
        };
        hub.broadcast(&frames, None);
        let wait = due.map_or(IDLE, |d| d.saturating_sub(hub.now()).min(IDLE));
        thread::sleep(wait.max(Duration::from_micros(200)));
    }
}

/// One client from `< hi >` to its disconnect; a stream that is not socketcand's protocol gets
/// `< error … >` and is closed.
fn serve_client(hub: &Hub, mut stream: TcpStream) -> std::io::Result<()> {
    stream.set_nodelay(true)?;
    stream.write_all(b"< hi >")?;
    let id = hub.next_id.fetch_add(1, Ordering::Relaxed);
    let mut opened = false;
    let mut buf = Vec::new();
    let mut chunk = [0u8; 1024];
    loop {
        let n = stream.read(&mut chunk)?;
        if n == 0 {
            break;
        }
        buf.extend_from_slice(&chunk[..n]);
        loop {
            let (message, consumed) = match Message::parse(&buf) {
                Ok(Framed::Complete { message, consumed }) => (message, consumed),
                Ok(Framed::Incomplete) if buf.len() <= MAX_MESSAGE_LEN => break,
                Ok(Framed::Incomplete) => {
                    stream.write_all(b"< error message too long >")?;
                    return close(hub, id, &stream);
                }
                Err(e) => {
                    stream.write_all(format!("< error {e} >").as_bytes())?;
                    return close(hub, id, &stream);
                }
            };
            buf.drain(..consumed);
            match message {
                Message::Open { channel } if !opened && channel == hub.channel => {
                    opened = true;
                    hub.clients().push(Client {
                        id,
                        stream: stream.try_clone()?,
                        raw: false,
                    });
                    stream.write_all(b"< ok >")?;
                }
                Message::Open { .. } => {
                    stream.write_all(b"< error could not open bus >")?;
                    return close(hub, id, &stream);
                }
                Message::RawMode if opened => {
                    // The reply first, then frames: the client reads `< ok >` before any.
                    let mut clients = hub.clients();
                    if let Some(c) = clients.iter_mut().find(|c| c.id == id) {
                        c.stream.write_all(b"< ok >")?;
                        c.raw = true;
                    }
                }
                Message::Echo => stream.write_all(b"< echo >")?,
                Message::Send { frame } if opened => hub.transmit(id, &frame),
                _ => stream.write_all(b"< error unknown command >")?,
            }
        }
    }
    close(hub, id, &stream)
}

/// How often a served bus module's system-bus frames are handed to the relay.
const RELAY_PERIOD: Duration = Duration::from_millis(2);

/// `serve enip --system-bus ADDR`: a socketcand server on `addr` (HOST[:PORT], channel `can0`)
/// carrying what the served bus module's gateway exchanges with its inverters, which `take`
/// hands over with the time each frame was on the bus (`sim::device::Device::tap_system_bus`),
/// every [`RELAY_PERIOD`]: each frame's socketcand timestamp is its own, not the relay's. A run
/// watches it with `--tap socketcand://ADDR/can0`.
pub(crate) fn relay_system_bus(
    addr: &str,
    mut take: impl FnMut() -> Vec<(Duration, CanFrame)> + Send + 'static,
) -> Result<Served, String> {
    let addr = crate::net::serve_args::socket_addr(addr, DEFAULT_PORT)?;
    let listener = TcpListener::bind(addr).map_err(|e| format!("cannot listen on {addr}: {e}"))?;
    let served = Served::relay(listener, "can0".into())?;
    // The first look attaches the tap.
    take();
    let hub = served.hub.clone();
    thread::spawn(move || {
        while !hub.stop.load(Ordering::Relaxed) {
            hub.broadcast_at(&take(), None);
            thread::sleep(RELAY_PERIOD);
        }
    });
    Ok(served)
}

fn close(hub: &Hub, id: u64, stream: &TcpStream) -> std::io::Result<()> {
    hub.clients().retain(|c| c.id != id);
    stream.shutdown(Shutdown::Both)
}
