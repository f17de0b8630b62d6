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
//! Threads: one accepting clients, one per client reading its messages, putting its frames on
//! the bus for the others and handing them to the segment's thread, which the serve driver
//! ([`crate::net::driver`]) runs: every frame of the nodes, answers and what they send on their
//! own (boot-up, heartbeats, EMCY), leaves through it, so `--misbehave` touches them all
//! (`docs/misbehave.md`; the fields and alarms in [`super::faults`]). The sans-IO segment sits
//! behind the driver's mutex; its clock is the real time since the start.

use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use proto::can::socketcand::{Framed, Message, Timestamp, MAX_MESSAGE_LEN};
use proto::can::CanFrame;
use proto::nord::Product;
use sim::can::Segment;
use sim::device::DeviceConfig;
use sim::endpoint::{Endpoint, Input, Output};

use super::faults;
use super::link::{CanLink, CanLinkError};
use crate::net::driver::{self, Counters, Options, Port, Serving, Shared};
use crate::net::misbehave::{Misbehaviour, Touched};
use crate::net::serve_args::MisbehaveArgs;
use crate::net::serve_error::ServeError;

/// socketcand's own default port.
pub(crate) const DEFAULT_PORT: u16 = 29536;

/// The longest the segment's timers wait when no node has anything due.
const IDLE: Duration = Duration::from_millis(20);

/// The shortest wait for the next frame or timer (a zero timeout would wait for ever on a
/// socket).
const MIN_WAIT: Duration = Duration::from_micros(200);

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
    #[command(flatten)]
    misbehave: MisbehaveArgs,
}

/// `harness serve can ARGS…`; returns the exit code.
pub(super) fn command(args: &[String]) -> Result<i32, ServeError> {
    let a = match crate::args::parse_args::<ServeArgs>("harness serve can", args) {
        Ok(a) => a,
        Err(code) => return Ok(code),
    };
    let product = crate::profile::product_named(&a.profile).map_err(ServeError::Profile)?;
    let misbehave = match a.misbehave.for_bus(&faults::FAULTS) {
        Ok(m) => m,
        Err(code) => return Ok(code),
    };
    let (Some(socketcand), None) = (&a.socketcand, &a.iface) else {
        let iface = a.iface.as_deref().unwrap_or_default();
        return serve_iface(
            iface,
            config(product, a.inverters),
            a.seconds.map(Duration::from_secs),
            misbehave,
        )
        .map(|()| crate::exit::EXIT_PASS);
    };
    let addr = crate::net::serve_args::socket_addr(socketcand, DEFAULT_PORT)
        .map_err(ServeError::Address)?;
    let listener = TcpListener::bind(addr).map_err(ServeError::socket("listen on", addr))?;
    let served = Served::start(listener, config(product, a.inverters), a.channel, misbehave)?;
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
        proto::nord::can::MIN_CYCLE_US.get() / 1000
    );
    crate::net::misbehave::announce(&misbehave);
    match a.seconds {
        Some(s) => thread::sleep(Duration::from_secs(s)),
        None => loop {
            thread::park();
        },
    }
    let touched = served.stop();
    crate::net::misbehave::summarize(&misbehave, touched);
    Ok(crate::exit::EXIT_PASS)
}

/// Why the segment on a CAN interface stopped serving.
#[derive(Debug, thiserror::Error)]
enum IfaceError {
    /// The interface failed.
    #[error(transparent)]
    Link(#[from] CanLinkError),
    /// The serving thread panicked (a bug).
    #[error("the system bus's thread panicked: {0}")]
    Panicked(String),
}

/// `harness serve can --iface IFACE`: the segment on a CAN interface of this host, served by
/// one thread of the serve driver: each frame read is the nodes' to answer, and what they send
/// on their own goes out when due; until `duration` has passed (forever when `None`).
fn serve_iface(
    iface: &str,
    config: DeviceConfig,
    duration: Option<Duration>,
    misbehave: Misbehaviour,
) -> Result<(), ServeError> {
    let link = super::socketcan::SocketCan::open(iface).map_err(ServeError::bus)?;
    let segment = Segment::new(config).map_err(ServeError::bus)?;
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
    crate::net::misbehave::announce(&misbehave);
    let mut serving = Serving::<IfaceError>::new();
    let port = Channel { link, frame: None };
    serving
        .spawn(
            format!("can-{iface}"),
            Shared::new(segment),
            port,
            options(misbehave),
        )
        .map_err(|source| ServeError::Thread {
            what: "the system bus's thread",
            source,
        })?;
    crate::net::workers::serve_for(duration, IDLE, || serving.is_running());
    let counts = serving
        .stop(IfaceError::Panicked)
        .map_err(ServeError::bus)?;
    crate::net::misbehave::summarize(&misbehave, counts.misbehaved);
    Ok(())
}

/// How the segment's thread serves, misbehaving as `misbehave` says: `late=` holds back the
/// nodes' answers (what they sent for a frame of the bus: SDO answers, boot-up after a reset),
/// not what they send on their own.
fn options(misbehave: Misbehaviour) -> Options {
    Options::new(IDLE).misbehaving(
        misbehave,
        |input, _| matches!(input, Input::Can(_)),
        faults::corrupt,
    )
}

/// A CAN interface of this host as the driver's port: frames in and out.
struct Channel<L> {
    link: L,
    /// The last frame read (the input handed over borrows it).
    frame: Option<CanFrame>,
}

impl<L: CanLink> Port for Channel<L> {
    type Error = CanLinkError;

    fn recv(&mut self, deadline: Instant) -> Result<Option<Input<'_>>, CanLinkError> {
        let wait = deadline.saturating_duration_since(Instant::now());
        self.frame = self.link.recv(wait.max(MIN_WAIT))?;
        Ok(self.frame.as_ref().map(Input::Can))
    }

    fn send(&mut self, out: &Output) -> Result<bool, CanLinkError> {
        let Output::Can(frame) = out else {
            return Ok(false);
        };
        self.link.send(frame).map(|()| true)
    }
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

/// What the threads share: the way to the segment's thread (none on a relay,
/// [`Served::relay`]) and the clients.
struct Hub {
    to_segment: Option<Mutex<Sender<CanFrame>>>,
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

    fn clients(&self) -> MutexGuard<'_, Vec<Client>> {
        self.clients.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// `frames` to every raw-mode client but `except`, stamped now; a client that cannot take
    /// them is dropped. `text` is the caller's buffer for the messages (kept between calls,
    /// so that a frame costs no allocation).
    fn broadcast<'a>(
        &self,
        frames: impl IntoIterator<Item = &'a CanFrame>,
        except: Option<u64>,
        text: &mut String,
    ) {
        let now = self.now();
        self.broadcast_at(frames.into_iter().map(|f| (now, f)), except, text);
    }

    /// [`Hub::broadcast`] with each frame's own time (a relayed bus's, when it was on it): the
    /// frames' messages written one after the other, in one write to each client. Nothing is
    /// written (or formatted) when no client but `except` is in raw mode.
    fn broadcast_at<'a>(
        &self,
        frames: impl IntoIterator<Item = (Duration, &'a CanFrame)>,
        except: Option<u64>,
        text: &mut String,
    ) {
        let mut clients = self.clients();
        if !clients.iter().any(|c| c.raw && Some(c.id) != except) {
            return;
        }
        text.clear();
        for (at, frame) in frames {
            let m = Message::Frame {
                frame: *frame,
                time: Timestamp {
                    secs: at.as_secs(),
                    usecs: at.subsec_micros(),
                },
            };
            // A frame of the segment is a data frame of at most 8 bytes: always writable.
            let _ = m.emit_into(text);
        }
        if text.is_empty() {
            return;
        }
        clients.retain_mut(|c| {
            if !c.raw || Some(c.id) == except {
                return true;
            }
            c.stream.write_all(text.as_bytes()).is_ok()
        });
    }

    /// A client put `frame` on the bus: the others see it, and the nodes take it (their
    /// answers come from the segment's thread).
    fn transmit(&self, from: u64, frame: &CanFrame, text: &mut String) {
        self.broadcast(std::slice::from_ref(frame), Some(from), text);
        if let Some(to) = &self.to_segment {
            // The segment's thread gone (the server stopping): the frame has no one to take it.
            let _ = to.lock().unwrap_or_else(|p| p.into_inner()).send(*frame);
        }
    }
}

/// The socketcand server as the port of the segment's thread: the clients' frames come in
/// from their threads; what the nodes send goes to every client.
struct Clients {
    hub: Arc<Hub>,
    inbox: Receiver<CanFrame>,
    /// The frame being handed over (the input borrows it).
    frame: Option<CanFrame>,
    text: String,
}

impl Port for Clients {
    type Error = std::convert::Infallible;

    fn recv(&mut self, deadline: Instant) -> Result<Option<Input<'_>>, Self::Error> {
        let wait = deadline.saturating_duration_since(Instant::now());
        self.frame = match self.inbox.recv_timeout(wait) {
            Ok(f) => Some(f),
            Err(RecvTimeoutError::Timeout) => None,
            // Every client thread and the hub's sender gone: the server is stopping.
            Err(RecvTimeoutError::Disconnected) => {
                thread::sleep(wait.max(MIN_WAIT));
                None
            }
        };
        Ok(self.frame.as_ref().map(Input::Can))
    }

    fn send(&mut self, out: &Output) -> Result<bool, Self::Error> {
        let Output::Can(frame) = out else {
            return Ok(false);
        };
        self.hub
            .broadcast(std::slice::from_ref(frame), None, &mut self.text);
        Ok(true)
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
    /// What the segment's thread counted (what `--misbehave` touched).
    counters: Arc<Counters>,
}

impl Served {
    /// Serves the segment of `config` to the clients of `listener`, misbehaving as
    /// `misbehave` says.
    pub(crate) fn start(
        listener: TcpListener,
        config: DeviceConfig,
        channel: String,
        misbehave: Misbehaviour,
    ) -> Result<Served, ServeError> {
        let segment = Segment::new(config).map_err(ServeError::bus)?;
        let nodes = segment.nodes();
        let (to, inbox) = mpsc::channel();
        let mut served = Served::hub(listener, Some(to), channel)?;
        served.nodes = nodes;
        let hub = served.hub.clone();
        // The socketcand timestamps and the segment's time run on one clock.
        let segment = Shared::since(segment, hub.start);
        let counters = served.counters.clone();
        thread::spawn(move || {
            let mut port = Clients {
                hub: hub.clone(),
                inbox,
                frame: None,
                text: String::new(),
            };
            let Ok(()) = driver::run(
                &segment,
                &mut port,
                &options(misbehave),
                &counters,
                &hub.stop,
            );
        });
        Ok(served)
    }

    /// A bus with no nodes of its own, to `listener`'s clients: what [`relay_system_bus`] puts
    /// on it (a served bus module's system bus, seen from its gateway) and what the clients
    /// send each other.
    fn relay(listener: TcpListener, channel: String) -> Result<Served, ServeError> {
        Served::hub(listener, None, channel)
    }

    fn hub(
        listener: TcpListener,
        to_segment: Option<Sender<CanFrame>>,
        channel: String,
    ) -> Result<Served, ServeError> {
        let addr = listener
            .local_addr()
            .map_err(ServeError::socket("read the address of", "the listener"))?;
        let start = Instant::now();
        let hub = Arc::new(Hub {
            to_segment: to_segment.map(Mutex::new),
            clients: Mutex::new(Vec::new()),
            start,
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
            nodes: Vec::new(),
            counters: Arc::default(),
        })
    }

    /// Stops serving: the clients are disconnected. What `--misbehave` touched.
    pub(crate) fn stop(&self) -> Touched {
        self.hub.stop.store(true, Ordering::Relaxed);
        for c in self.hub.clients().drain(..) {
            let _ = c.stream.shutdown(Shutdown::Both);
        }
        // Wakes the acceptor, which then sees the stop.
        let _ = TcpStream::connect_timeout(&self.addr, Duration::from_millis(200));
        self.counters.snapshot().misbehaved
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

/// One client from `< hi >` to its disconnect; a stream that is not socketcand's protocol gets
/// `< error … >` and is closed.
fn serve_client(hub: &Hub, mut stream: TcpStream) -> std::io::Result<()> {
    stream.set_nodelay(true)?;
    stream.write_all(b"< hi >")?;
    let id = hub.next_id.fetch_add(1, Ordering::Relaxed);
    let mut opened = false;
    let mut buf = Vec::new();
    let mut chunk = [0u8; 1024];
    // The messages this client's frames make for the others and for it (the nodes' answers).
    let mut text = String::new();
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
                Message::Send { frame } if opened => hub.transmit(id, &frame, &mut text),
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
) -> Result<Served, ServeError> {
    let addr =
        crate::net::serve_args::socket_addr(addr, DEFAULT_PORT).map_err(ServeError::Address)?;
    let listener = TcpListener::bind(addr).map_err(ServeError::socket("listen on", addr))?;
    let served = Served::relay(listener, "can0".into())?;
    // The first look attaches the tap.
    take();
    let hub = served.hub.clone();
    thread::spawn(move || {
        let mut text = String::new();
        while !hub.stop.load(Ordering::Relaxed) {
            let frames = take();
            hub.broadcast_at(frames.iter().map(|(at, f)| (*at, f)), None, &mut text);
            thread::sleep(RELAY_PERIOD);
        }
    });
    Ok(served)
}

/// [`relay_system_bus`] for a device the serve driver runs (`serve epl|pnio --system-bus`):
/// `device` reaches the simulated device inside it.
pub(crate) fn relay_served<S: Endpoint + Send + 'static>(
    addr: &str,
    shared: Arc<driver::Shared<S>>,
    device: fn(&mut S) -> &mut sim::device::Device,
) -> Result<Served, ServeError> {
    relay_system_bus(addr, move || device(&mut shared.lock().0).tap_system_bus())
}

/// Says on stdout where a served device's system bus is relayed (`serve ecat|epl|pnio
/// --system-bus`), after the device's own serving line.
pub(crate) fn announce_relay(relay: Option<&Served>) {
    if let Some(r) = relay {
        outln!(
            "its system bus over socketcand on {}, channel {}",
            r.addr,
            r.channel
        );
    }
}

fn close(hub: &Hub, id: u64, stream: &TcpStream) -> std::io::Result<()> {
    hub.clients().retain(|c| c.id != id);
    stream.shutdown(Shutdown::Both)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The next message of `stream`, skipping the frames of the bus.
    fn next_reply(stream: &mut TcpStream, buf: &mut Vec<u8>) -> Message {
        let mut chunk = [0u8; 256];
        loop {
            if let Ok(Framed::Complete { message, consumed }) = Message::parse(buf) {
                buf.drain(..consumed);
                return message;
            }
            let n = stream.read(&mut chunk).unwrap();
            assert!(n > 0, "the server closed the connection");
            buf.extend_from_slice(&chunk[..n]);
        }
    }

    #[test]
    fn an_error_frame_from_a_client_is_refused_and_the_segment_serves_on() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let served = Served::start(
            listener,
            config(Product::Sk550p, Some(2)),
            "can0".into(),
            Misbehaviour::default(),
        )
        .unwrap();
        let mut s = TcpStream::connect(served.addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let mut buf = Vec::new();
        assert_eq!(next_reply(&mut s, &mut buf), Message::Hi);
        s.write_all(b"< open can0 >< rawmode >").unwrap();
        assert_eq!(next_reply(&mut s, &mut buf), Message::Ok);
        assert_eq!(next_reply(&mut s, &mut buf), Message::Ok);
        // An error frame is no frame a client can put on the bus (socketcand has no command
        // for it): refused, the connection kept.
        s.write_all(b"< error 088 1.000000 >").unwrap();
        let reply = loop {
            match next_reply(&mut s, &mut buf) {
                Message::Frame { .. } => continue,
                other => break other,
            }
        };
        assert_eq!(
            reply,
            Message::Error {
                text: "unknown command".into()
            }
        );
        // Node 32 still answers an SDO upload of 1000h.
        s.write_all(b"< send 620 8 40 0 10 0 0 0 0 0 >").unwrap();
        let answer = loop {
            match next_reply(&mut s, &mut buf) {
                Message::Frame { frame, .. } if frame.id() == 0x5A0 => break frame,
                _ => continue,
            }
        };
        assert_eq!(answer.data()[..4], [0x43, 0x00, 0x10, 0x00]);
        served.stop();
    }
}
