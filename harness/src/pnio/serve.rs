//! `harness serve pnio`: the simulated PROFINET IO device on a network interface.
//!
//! The device (`sim::pnio::IoDevice`, sans-IO) is reached the two ways a PROFINET device is:
//! - raw Ethernet frames of EtherType 8892h ([`crate::net::RawLink`], which opens the
//!   interface promiscuous): DCP (to the device's MAC address — the product's, with the
//!   maker's id the manual shows, not the interface's — or to the Identify multicast
//!   01-0E-CF-00-00-00), the RT frames of its IO CRs and the alarm frames;
//! - UDP port 34964 on the interface's IPv4 address for the context-management RPC calls
//!   (Connect, Control, Release, Read, Write). The device takes the interface's address and
//!   prefix as its IP suite, so what DCP reports is where it answers; an address set later by
//!   DCP changes what the device reports, not the interface (serve it anew on the new
//!   address). Without an IPv4 address only DCP and RT are served, and a line on stderr says
//!   so.
//!
//! One thread owns the raw link: each frame goes to [`IoDevice::frame`], and
//! [`IoDevice::poll`] runs every [`POLL_PERIOD`] (the input CR's frames, the watchdog, alarms,
//! the drive model); what they send goes out at once (the device's own RPC calls on a clone
//! of the UDP socket). A second thread owns the UDP socket and answers each call at once with
//! [`IoDevice::call`], which leaves the timers to the first: the raw link cannot be waited on
//! together with another socket, and a record read must not wait for the next poll. The
//! device is shared under a mutex, and the time handed to it is read with the lock held, so
//! it never goes backwards.
//!
//! With a reply delay (`--reply-delay MS`) the device's RPC answers and DCP responses leave
//! that much later than the device made them (the UDP thread waits before it answers; the raw
//! thread holds DCP responses back while the cyclic frames go on).

use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use proto::eth::{MacAddr, ETHERTYPE_PROFINET};
use proto::nord::pnio::IpSuite;
use proto::nord::Protocol;
use proto::pnio::RPC_PORT;
use sim::pnio::{IoConfig, IoDevice, Out, POLL_PERIOD};

use crate::net::held::Held;
use crate::net::serve_args::RawServeArgs;
use crate::net::udp::{ipv4_of, transient};
use crate::net::workers::{serve_for, Workers};
use crate::net::{LinkError, RawLink, MAX_FRAME};

/// How long the raw thread polls the socket after a frame before it sleeps.
const FRAME_POLL: Duration = Duration::from_micros(50);
/// The longest the UDP thread waits without looking at its stop flag.
const STOP_CHECK: Duration = Duration::from_millis(20);

/// What `harness serve pnio` serves.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServeOptions {
    /// The network interface (`--iface`), e.g. one end of a veth pair.
    pub iface: String,
    /// The product profile (`--profile`, default `sk550p`).
    pub profile: String,
    /// The name of station at power-on (`--name`; none: the factory state, no name).
    pub name: String,
    /// Inverters behind the interface (`--inverters`; default the product's maximum).
    pub inverters: Option<u8>,
    /// How much later than made RPC answers and DCP responses leave (`--reply-delay`; none by
    /// default).
    pub reply_delay: Duration,
}

impl ServeOptions {
    /// `iface` with the defaults: SK 550P without a name, the product's maximum of inverters,
    /// answers at once.
    pub fn new(iface: &str) -> ServeOptions {
        ServeOptions {
            iface: iface.into(),
            profile: "sk550p".into(),
            name: String::new(),
            inverters: None,
            reply_delay: Duration::ZERO,
        }
    }
}

/// Why the device cannot be served, or stopped serving.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The profile is unknown, its product has no PROFINET, or the name is not valid.
    #[error("{0}")]
    Profile(String),
    /// The raw Ethernet link failed (no such interface, no root, I/O).
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The UDP socket of the RPC endpoint could not be bound or failed.
    #[error("UDP {addr} (PNIO-CM RPC): {source}")]
    Udp {
        /// The address it was bound (or to be bound) to.
        addr: SocketAddr,
        /// What the system said.
        source: std::io::Error,
    },
    /// A serving thread panicked (a bug).
    #[error("the PROFINET device's thread panicked: {0}")]
    Panicked(String),
}

/// What a served device did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// PROFINET frames received.
    pub frames_in: u64,
    /// Frames the device sent.
    pub frames_out: u64,
    /// RPC datagrams received.
    pub datagrams_in: u64,
    /// Datagrams the device sent.
    pub datagrams_out: u64,
}

#[derive(Debug, Default)]
struct Counters {
    frames_in: AtomicU64,
    frames_out: AtomicU64,
    datagrams_in: AtomicU64,
    datagrams_out: AtomicU64,
}

fn bump(c: &AtomicU64) {
    c.fetch_add(1, Ordering::Relaxed);
}

/// A device served in threads by [`start`]; dropping it stops them.
#[derive(Debug)]
pub struct Served {
    mac: MacAddr,
    udp: Option<SocketAddr>,
    counters: Arc<Counters>,
    workers: Workers<ServeError>,
}

impl Served {
    /// The device's MAC address: the product's (the interface is promiscuous), not the
    /// interface's.
    pub fn mac(&self) -> MacAddr {
        self.mac
    }

    /// Where the RPC endpoint is served (`None`: the interface had no IPv4 address).
    pub fn rpc_addr(&self) -> Option<SocketAddr> {
        self.udp
    }

    /// What the threads counted so far.
    pub fn stats(&self) -> Stats {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        let c = &self.counters;
        Stats {
            frames_in: get(&c.frames_in),
            frames_out: get(&c.frames_out),
            datagrams_in: get(&c.datagrams_in),
            datagrams_out: get(&c.datagrams_out),
        }
    }

    /// Whether the threads still serve.
    pub fn is_running(&self) -> bool {
        self.workers.is_running()
    }

    /// Stops the threads and returns what they counted, or why they had stopped before.
    pub fn stop(mut self) -> Result<Stats, ServeError> {
        self.join()
    }

    fn join(&mut self) -> Result<Stats, ServeError> {
        self.workers.join(ServeError::Panicked)?;
        Ok(self.stats())
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.join();
    }
}

/// The device of `opts`, its IP suite the interface's when it has one.
fn device(opts: &ServeOptions, ip: Option<(Ipv4Addr, u8)>) -> Result<IoDevice, ServeError> {
    let config = crate::net::serve_args::device_config(
        &opts.profile,
        opts.inverters,
        Protocol::Profinet,
        "PROFINET IO",
    )
    .map_err(ServeError::Profile)?;
    let product = config.product;
    let ip = ip.map(|(ip, prefix)| IpSuite {
        ip,
        mask: Ipv4Addr::from(u32::MAX.checked_shl(32 - u32::from(prefix)).unwrap_or(0)),
        gateway: Ipv4Addr::UNSPECIFIED,
    });
    let io = IoConfig {
        name: opts.name.clone(),
        ip,
        ..IoConfig::new(product)
    };
    IoDevice::new(sim::device::Device::new(config), io)
        .map_err(|e| ServeError::Profile(e.to_string()))
}

/// Opens `opts.iface` and serves the device there in threads of this process, until the
/// returned handle is stopped or dropped.
pub fn start(opts: &ServeOptions) -> Result<Served, ServeError> {
    let mut link = RawLink::open(&opts.iface, Some(ETHERTYPE_PROFINET))?;
    link.set_spin(FRAME_POLL);
    let ip = ipv4_of(&opts.iface);
    let io = device(opts, ip)?;
    let mac = io.mac();
    let socket = match ip {
        Some((ip, _)) => {
            let addr = SocketAddr::from((ip, RPC_PORT));
            let udp = |source| ServeError::Udp { addr, source };
            let socket = UdpSocket::bind(addr).map_err(udp)?;
            socket.set_read_timeout(Some(STOP_CHECK)).map_err(udp)?;
            Some((addr, socket))
        }
        None => None,
    };
    let counters = Arc::new(Counters::default());
    let mut served = Served {
        mac,
        udp: socket.as_ref().map(|(a, _)| *a),
        counters: counters.clone(),
        workers: Workers::new(),
    };
    let stop = served.workers.stop_flag();
    let thread = |e: std::io::Error| ServeError::Panicked(format!("cannot start a thread: {e}"));
    let (reply, recv) = match socket {
        Some((addr, socket)) => {
            let reply = socket
                .try_clone()
                .map_err(|source| ServeError::Udp { addr, source })?;
            (Some((addr, reply)), Some((addr, socket)))
        }
        None => (None, None),
    };
    let device = Shared {
        io: Arc::new(Mutex::new(io)),
        start: Instant::now(),
    };
    let raw = Raw {
        link,
        device: device.clone(),
        reply,
        counters: counters.clone(),
        stop: stop.clone(),
        dcp: Held::new(opts.reply_delay),
    };
    let delay = opts.reply_delay;
    served
        .workers
        .spawn(format!("pnio-device-{}", opts.iface), move || raw.run())
        .map_err(thread)?;
    if let Some((addr, socket)) = recv {
        served
            .workers
            .spawn(format!("pnio-rpc-{}", opts.iface), move || {
                run_udp(socket, addr, &device, &counters, &stop, delay)
            })
            .map_err(thread)?;
    }
    Ok(served)
}

/// The device and its clock, shared by both threads.
#[derive(Clone)]
struct Shared {
    io: Arc<Mutex<IoDevice>>,
    start: Instant,
}

impl Shared {
    /// The device and the time to hand it (read with the lock held: never backwards).
    fn lock(&self) -> Result<(MutexGuard<'_, IoDevice>, Duration), ServeError> {
        let guard = self
            .io
            .lock()
            .map_err(|_| ServeError::Panicked("the other serving thread panicked".into()))?;
        Ok((guard, self.start.elapsed()))
    }
}

/// The raw thread: the link, and the socket the device's own calls go out on.
struct Raw {
    link: RawLink,
    device: Shared,
    reply: Option<(SocketAddr, UdpSocket)>,
    counters: Arc<Counters>,
    stop: Arc<AtomicBool>,
    /// DCP responses held back by the reply delay.
    dcp: Held<Vec<u8>>,
}

impl Raw {
    fn run(mut self) -> Result<(), ServeError> {
        let mut buf = vec![0u8; MAX_FRAME];
        let mut next_poll = Duration::ZERO;
        while !self.stop.load(Ordering::Relaxed) {
            while let Some(f) = self.dcp.due() {
                self.frame(&f)?;
            }
            if self.device.start.elapsed() >= next_poll {
                let (out, now) = {
                    let (mut io, now) = self.device.lock()?;
                    (io.poll(now), now)
                };
                self.send(out)?;
                // On the poll grid: a late wake-up does not shift the next one.
                next_poll = if now - next_poll > POLL_PERIOD {
                    now + POLL_PERIOD
                } else {
                    next_poll + POLL_PERIOD
                };
            }
            let mut until = self.device.start + next_poll;
            if let Some(next) = self.dcp.next() {
                until = until.min(next);
            }
            let received = match self.link.recv(&mut buf, until) {
                Ok(r) => r,
                Err(e) if e.is_link_down() => {
                    thread::sleep(POLL_PERIOD);
                    continue;
                }
                Err(e) => return Err(e.into()),
            };
            let Some(r) = received else { continue };
            bump(&self.counters.frames_in);
            let out = {
                let (mut io, now) = self.device.lock()?;
                io.frame(&buf[..r.len], now)
            };
            self.send(out)?;
        }
        Ok(())
    }

    fn send(&mut self, out: Vec<Out>) -> Result<(), ServeError> {
        for o in out {
            match o {
                Out::Frame(f) if is_dcp(&f) => self.dcp.hold(f),
                Out::Frame(f) => self.frame(&f)?,
                Out::Datagram { to, bytes } => {
                    let Some((addr, socket)) = &self.reply else {
                        continue;
                    };
                    match socket.send_to(&bytes, to) {
                        Ok(_) => bump(&self.counters.datagrams_out),
                        Err(e) if transient(&e) => {}
                        Err(source) => {
                            return Err(ServeError::Udp {
                                addr: *addr,
                                source,
                            })
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// One frame out on the link.
    fn frame(&mut self, f: &[u8]) -> Result<(), ServeError> {
        match self.link.send(f) {
            Ok(()) => bump(&self.counters.frames_out),
            Err(e) if e.is_link_down() => {}
            Err(e) => return Err(e.into()),
        }
        Ok(())
    }
}

/// Whether an Ethernet frame of the device is DCP (its responses).
fn is_dcp(frame: &[u8]) -> bool {
    proto::eth::EthernetFrame::new_checked(frame).is_ok_and(|eth| {
        let p = eth.inner_payload();
        p.len() >= 2
            && matches!(
                proto::pnio::FrameId(u16::from_be_bytes([p[0], p[1]])).kind(),
                proto::pnio::FrameKind::Dcp
            )
    })
}

/// The UDP thread: RPC calls in, the device's answers back to their sender `delay` later.
fn run_udp(
    socket: UdpSocket,
    addr: SocketAddr,
    device: &Shared,
    counters: &Counters,
    stop: &AtomicBool,
    delay: Duration,
) -> Result<(), ServeError> {
    let mut buf = [0u8; 2048];
    while !stop.load(Ordering::Relaxed) {
        let (len, from) = match socket.recv_from(&mut buf) {
            Ok(r) => r,
            Err(e) if transient(&e) => continue,
            Err(source) => return Err(ServeError::Udp { addr, source }),
        };
        bump(&counters.datagrams_in);
        let out = {
            let (mut io, now) = device.lock()?;
            io.call(from, &buf[..len], now)
        };
        if !out.is_empty() {
            thread::sleep(delay);
        }
        for o in out {
            let Out::Datagram { to, bytes } = o else {
                continue;
            };
            match socket.send_to(&bytes, to) {
                Ok(_) => bump(&counters.datagrams_out),
                Err(e) if transient(&e) => {}
                Err(source) => return Err(ServeError::Udp { addr, source }),
            }
        }
    }
    Ok(())
}

/// Serves until `duration` has passed (forever when `None`), after a line on stdout that says
/// what is served where.
fn serve(opts: &ServeOptions, duration: Option<Duration>) -> Result<(), ServeError> {
    let served = start(opts)?;
    let rpc = match served.rpc_addr() {
        Some(a) => format!(", RPC on {a}"),
        None => String::new(),
    };
    let name = if opts.name.is_empty() {
        "no name of station".to_string()
    } else {
        format!("name of station {:?}", opts.name)
    };
    outln!(
        "serving PROFINET IO device {} ({name}) on {} (MAC {}){rpc}",
        opts.profile,
        opts.iface,
        served.mac()
    );
    if served.rpc_addr().is_none() {
        eprintln!(
            "note: {} has no IPv4 address: serving DCP and RT only; give it an address (the \
             SK 550P's factory one is 192.168.20.200/24) for Connect and the data records",
            opts.iface
        );
    }
    serve_for(duration, STOP_CHECK * 10, || served.is_running());
    served.stop().map(|_| ())
}

/// `harness serve pnio` arguments.
#[derive(clap::Parser, Debug)]
#[command(
    name = "harness serve pnio",
    about = "Serve the simulator as a PROFINET IO device on a network interface (raw Ethernet: root or CAP_NET_RAW; RPC on UDP 34964 at the interface's IPv4 address)"
)]
struct ServeArgs {
    #[command(flatten)]
    common: RawServeArgs,
    /// The name of station at power-on (default: none, as delivered).
    #[arg(long, default_value = "")]
    name: String,
}

/// `harness serve pnio ARGS…`; returns the exit code.
pub(crate) fn command(args: &[String]) -> Result<i32, String> {
    let a = match crate::args::parse_args::<ServeArgs>("harness serve pnio", args) {
        Ok(a) => a,
        Err(code) => return Ok(code),
    };
    let opts = ServeOptions {
        iface: a.common.iface,
        profile: a.common.profile,
        name: a.name,
        inverters: a.common.inverters,
        reply_delay: Duration::from_millis(a.common.reply_delay),
    };
    serve(&opts, a.common.seconds.map(Duration::from_secs)).map_err(|e| e.to_string())?;
    Ok(crate::exit::EXIT_PASS)
}
