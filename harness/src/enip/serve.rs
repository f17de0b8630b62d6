//! `harness serve enip`: the simulator as a real EtherNet/IP adapter on the network.
//!
//! TCP and UDP on the listen address (44818 by default) carry encapsulation messages, UDP 2222
//! on the same IP carries class-1 I/O. One event-loop thread for all TCP clients
//! ([`super::serve_tcp`]: inactivity timeout, connection limit), one for UDP 44818 and one, the
//! serve driver's ([`crate::net::driver`]), for class-1 I/O share the sans-IO [`Adapter`] behind
//! the driver's mutex; time is the real clock since start. A client whose message stays
//! incomplete for [`STALL`] is disconnected, so a hung peer holds nothing.
//!
//! The one I/O thread both takes the O→T frames and sends the T→O frames when due: it reads
//! each O→T frame as soon as it waits again, so the T→O frames cannot run ahead of O→T frames
//! queued for a receiving thread that a loaded host holds back.

//! `--misbehave` ([`crate::net::misbehave`]) makes the adapter misbehave on purpose, so that a
//! run against it shows how the harness judges it: `late=` acts on each request at once and
//! sends its encapsulation reply (TCP, and UDP ListIdentity) late; `drop`, `dup`, `reorder`,
//! `silent` touch those replies and the class-1 T→O frames alike (the same injector as the
//! serve driver's, [`crate::net::inject`]); `corrupt=status` and `close` are
//! [`super::faults`]'s.

use std::net::{SocketAddr, TcpListener, UdpSocket};
use std::os::fd::AsFd;
use std::os::unix::net::UnixDatagram;
use std::sync::atomic::AtomicBool;
use std::sync::mpsc::Sender;
use std::sync::{Arc, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use nix::errno::Errno;
use nix::poll::{ppoll, PollFd, PollFlags};
use nix::sys::resource::{getrlimit, setrlimit, Resource};
use nix::sys::time::TimeSpec;
use proto::enip::io::IO_PORT;
use sim::device::{Device, DeviceConfig};
use sim::endpoint::{Input, Output};
use sim::enip::{Adapter, MAX_SESSIONS};

use super::faults;
use crate::net::driver::{self, Counters, Options, Port};
use crate::net::inject::Injector;
use crate::net::misbehave::Misbehaviour;
use crate::net::serve_error::ServeError;

/// How long a partial message may wait for its rest.
pub(crate) const STALL: Duration = Duration::from_secs(10);

/// TCP clients served at once unless `--max-connections` says otherwise: far above the
/// session limit, as a connection without a session costs a socket and no thread.
pub(crate) const MAX_CONNECTIONS: usize = 10_000;

/// File descriptors kept free of TCP clients: the listener's, the UDP sockets', those of
/// clients being refused, and the process's own.
const FD_RESERVE: usize = 128;

/// Connections not yet accepted that the kernel queues for the listener (`listen` backlog),
/// so that a burst of clients is not dropped and retried a second later.
const BACKLOG: i32 = 1024;

/// How long before a T→O frame is due the I/O thread stops sleeping and watches the clock.
/// A sleeping thread wakes up late when its processor was idle, by a few hundred µs on a
/// virtual machine here (one wake-up in ten came more than 150 µs late with 100 µs); with
/// 300 µs the T→O frames of a 1 ms RPI leave within tens of µs of their time, for a third of
/// one core while I/O runs.
const IO_SPIN: Duration = Duration::from_micros(300);

/// The longest the I/O thread sleeps when nothing is due and nothing comes.
const IO_IDLE: Duration = Duration::from_millis(50);

/// A running adapter.
pub(super) struct Shared {
    /// The adapter on its clock, the real time since it started.
    pub(super) adapter: Arc<driver::Shared<Adapter>>,
    /// Wakes the I/O thread to look at the adapter's next due time again: one byte to the
    /// other end, which the thread waits on beside the I/O socket.
    wake: UnixDatagram,
    /// What the adapter does wrong on purpose (`--misbehave`).
    pub(super) misbehave: Misbehaviour,
    /// What every thread counted, the misbehaviour's touched outputs among it.
    pub(super) counters: Counters,
}

impl Shared {
    pub(super) fn lock(&self) -> MutexGuard<'_, Adapter> {
        self.adapter.lock().0
    }

    /// A fault injector for one thread or client, on the adapter's clock.
    pub(super) fn injector(&self) -> Injector {
        Injector::new(self.misbehave, faults::corrupt, self.adapter.start())
    }

    /// Wakes the I/O thread to look at the adapter's next due time again (a wake-up already
    /// pending is enough: a full socket drops this one).
    pub(super) fn wake_io(&self) {
        let _ = self.wake.send(&[1]);
    }
}

/// How many clients a served adapter takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Limits {
    /// Encapsulation sessions; RegisterSession beyond is refused ("insufficient memory").
    pub(crate) sessions: usize,
    /// TCP clients; those beyond are answered "insufficient memory" and closed.
    pub(crate) connections: usize,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            sessions: MAX_SESSIONS,
            connections: MAX_CONNECTIONS,
        }
    }
}

/// The addresses of an adapter that [`start_enip`] put on the network.
#[derive(Clone)]
pub(crate) struct Served {
    /// Encapsulation messages, TCP and UDP.
    pub(crate) listen: SocketAddr,
    /// Class-1 I/O (UDP 2222 on the same IP).
    pub(crate) io: SocketAddr,
    /// TCP clients served at once (`--max-connections`, less where the open-files limit
    /// leaves no room for so many).
    pub(crate) connections: usize,
    /// The adapter and its threads' counts.
    shared: Arc<Shared>,
}

/// Binds the sockets and starts the adapter's threads, then returns; they serve until the
/// process ends. The process's soft limit of open files is raised to its hard limit first,
/// and the TCP clients served at once are as many as `limits` says and that limit leaves room
/// for. The adapter misbehaves as `misbehave` says.
pub(crate) fn start_enip(
    listen: SocketAddr,
    config: DeviceConfig,
    limits: Limits,
    misbehave: Misbehaviour,
) -> Result<Served, ServeError> {
    start_enip_tapped(listen, config, limits, misbehave, None)
}

/// [`start_enip`], and with `system_bus` (HOST[:PORT]) a socketcand server carrying what the
/// adapter's gateway exchanges with its inverters (`crate::can::relay_system_bus`).
pub(crate) fn start_enip_tapped(
    listen: SocketAddr,
    config: DeviceConfig,
    limits: Limits,
    misbehave: Misbehaviour,
    system_bus: Option<&str>,
) -> Result<Served, ServeError> {
    let SocketAddr::V4(v4) = listen else {
        return Err(ServeError::Address(format!(
            "EtherNet/IP needs an IPv4 listen address, not {listen}"
        )));
    };
    let connections = limits
        .connections
        .min(open_files_limit().saturating_sub(FD_RESERVE));
    let tcp = listener(listen).map_err(ServeError::socket("listen on TCP", listen))?;
    let udp = UdpSocket::bind(listen).map_err(ServeError::socket("bind UDP", listen))?;
    let io_addr = SocketAddr::new(listen.ip(), IO_PORT);
    let io = UdpSocket::bind(io_addr).map_err(ServeError::socket("bind UDP", io_addr))?;
    io.set_nonblocking(true)
        .map_err(ServeError::socket("make non-blocking: UDP", io_addr))?;
    let adapter = Adapter::new(Device::new(config), v4).with_max_sessions(limits.sessions);
    let wake_up = || -> std::io::Result<(UnixDatagram, UnixDatagram)> {
        let (wake, woken) = UnixDatagram::pair()?;
        wake.set_nonblocking(true)?;
        woken.set_nonblocking(true)?;
        Ok((wake, woken))
    };
    let (wake, woken) = wake_up().map_err(ServeError::socket("open", "the I/O wake-up socket"))?;
    let shared = Arc::new(Shared {
        adapter: driver::Shared::new(adapter),
        wake,
        misbehave,
        counters: Counters::default(),
    });
    {
        let shared = shared.clone();
        thread::spawn(move || {
            // Served until the process ends.
            let serving = AtomicBool::new(false);
            // No T→O frame is an answer: `late=` leaves them be.
            let opts =
                Options::new(IO_IDLE).misbehaving(shared.misbehave, |_, _| false, faults::corrupt);
            let mut port = IoPort {
                io,
                woken,
                buf: [0; 2048],
            };
            if let Err(e) = driver::run(
                &shared.adapter,
                &mut port,
                &opts,
                &shared.counters,
                &serving,
            ) {
                eprintln!("EtherNet/IP class-1 I/O stopped: cannot wait on UDP {io_addr}: {e}");
            }
        });
    }
    super::serve_tcp::start(tcp, shared.clone(), connections)?;
    let late = late_sender(&udp, misbehave.late.is_some())?;
    {
        let s = shared.clone();
        thread::spawn(move || discovery(udp, s, late));
    }
    if let Some(addr) = system_bus {
        let s = shared.clone();
        crate::can::relay_system_bus(addr, move || s.lock().device_mut().tap_system_bus())
            .map_err(|e| ServeError::SystemBus(Box::new(e)))?;
    }
    Ok(Served {
        listen,
        io: io_addr,
        connections,
        shared,
    })
}

/// A TCP listener on `addr` with a [`BACKLOG`] of its own (the standard library's is 128).
fn listener(addr: SocketAddr) -> std::io::Result<TcpListener> {
    let s = socket2::Socket::new(
        socket2::Domain::for_address(addr),
        socket2::Type::STREAM,
        Some(socket2::Protocol::TCP),
    )?;
    s.set_reuse_address(true)?;
    s.bind(&addr.into())?;
    s.listen(BACKLOG)?;
    Ok(s.into())
}

/// The process's soft limit of open files after raising it to the hard limit (as far as the
/// system lets it: a refusal leaves the soft limit as it was).
fn open_files_limit() -> usize {
    let Ok((soft, hard)) = getrlimit(Resource::RLIMIT_NOFILE) else {
        return usize::MAX;
    };
    let now = if hard > soft && setrlimit(Resource::RLIMIT_NOFILE, hard, hard).is_ok() {
        hard
    } else {
        soft
    };
    usize::try_from(now).unwrap_or(usize::MAX)
}

/// `harness serve enip` arguments.
#[derive(clap::Parser, Debug)]
#[command(
    name = "harness serve enip",
    about = "Serve the simulator as an EtherNet/IP adapter"
)]
struct ServeArgs {
    /// Listen address, HOST[:PORT] (UDP 2222 on the same host carries I/O).
    #[arg(long, default_value = "127.0.0.2:44818")]
    listen: String,
    /// Product profile: sk550p, tu3-eip, tu4-eip, cu4-eip.
    #[arg(long, default_value = "tu3-eip")]
    profile: String,
    /// Inverters behind the interface (default: the product's maximum).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    inverters: Option<u8>,
    /// Stop after this many seconds (default: serve until killed).
    #[arg(long)]
    seconds: Option<u64>,
    /// Encapsulation sessions at once; RegisterSession beyond is refused with encapsulation
    /// status 0002h "insufficient memory".
    #[arg(long, default_value_t = MAX_SESSIONS, value_parser = at_least_one)]
    max_sessions: usize,
    /// TCP connections served at once; those beyond are answered 0002h "insufficient
    /// memory" and closed.
    #[arg(long, default_value_t = MAX_CONNECTIONS, value_parser = at_least_one)]
    max_connections: usize,
    #[command(flatten)]
    misbehave: crate::net::serve_args::MisbehaveArgs,
    /// Also serve the adapter's system bus over socketcand on HOST[:PORT] (channel `can0`):
    /// the CANopen frames its gateway exchanges with the inverters, for `harness run --tap
    /// socketcand://HOST:PORT/can0` or any CAN tool.
    #[arg(long, value_name = "ADDR")]
    system_bus: Option<String>,
}

/// A limit of 1 or more.
fn at_least_one(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("must be 1 or more".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(e.to_string()),
    }
}

/// `harness serve enip ARGS…`; returns the exit code.
pub(super) fn command(args: &[String]) -> Result<i32, ServeError> {
    let a = match crate::args::parse_args::<ServeArgs>("harness serve enip", args) {
        Ok(a) => a,
        Err(code) => return Ok(code),
    };
    let product = crate::profile::product_named(&a.profile).map_err(ServeError::Profile)?;
    if proto::nord::eip::identity(product).is_none() {
        return Err(ServeError::Profile(format!(
            "{} has no EtherNet/IP interface",
            product.name()
        )));
    }
    let config = DeviceConfig {
        inverters: a
            .inverters
            .unwrap_or(product.max_inverters())
            .min(product.max_inverters()),
        ..DeviceConfig::new(product)
    };
    let limits = Limits {
        sessions: a.max_sessions,
        connections: a.max_connections,
    };
    let misbehave = match a.misbehave.for_bus(&faults::FAULTS) {
        Ok(m) => m,
        Err(code) => return Ok(code),
    };
    serve_enip(
        parse_addr(&a.listen).map_err(ServeError::Address)?,
        config,
        limits,
        (misbehave, a.system_bus.as_deref()),
        a.seconds.map(Duration::from_secs),
    )?;
    Ok(crate::exit::EXIT_PASS)
}

/// Serves until `duration` has passed (forever when `None`).
pub(crate) fn serve_enip(
    listen: SocketAddr,
    config: DeviceConfig,
    limits: Limits,
    (misbehave, system_bus): (Misbehaviour, Option<&str>),
    duration: Option<Duration>,
) -> Result<(), ServeError> {
    let product = config.product;
    let inverters = config.inverters;
    let served = start_enip_tapped(listen, config, limits, misbehave, system_bus)?;
    let late = match system_bus {
        Some(addr) => format!("; its system bus over socketcand on {addr}, channel can0"),
        None => String::new(),
    };
    outln!(
        "serving EtherNet/IP adapter ({}, {inverters} inverters) on {} (TCP, UDP) and {} (class-1 I/O); at most {} sessions, {} TCP connections{late}",
        product.name(),
        served.listen,
        served.io,
        limits.sessions,
        served.connections
    );
    crate::net::misbehave::announce(&misbehave);
    match duration {
        Some(d) => thread::sleep(d),
        None => loop {
            thread::sleep(Duration::from_secs(3600));
        },
    }
    let touched = served.shared.counters.snapshot().misbehaved;
    crate::net::misbehave::summarize(&misbehave, touched);
    Ok(())
}

fn discovery(udp: UdpSocket, shared: Arc<Shared>, late: Option<Sender<LateReply>>) {
    let mut buf = [0u8; 2048];
    let Ok(port) = udp.local_addr().map(|a| a.port()) else {
        return;
    };
    let mut inject = shared.injector();
    loop {
        let Ok((n, from)) = udp.recv_from(&mut buf) else {
            continue;
        };
        let bytes = &buf[..n];
        inject.heard(Instant::now());
        for out in shared.adapter.input(Input::Datagram { port, from, bytes }) {
            let tally = shared.counters.misbehaved();
            for (due, out) in inject.outgoing(out, true, Instant::now(), tally) {
                let Output::Datagram { to, bytes, .. } = out else {
                    continue;
                };
                match (due, &late) {
                    (Some(due), Some(late)) => {
                        let _ = late.send((due, bytes, to));
                    }
                    _ => {
                        let _ = udp.send_to(&bytes, to);
                    }
                }
            }
        }
    }
}

/// A UDP reply held back: when it leaves, its bytes, where to.
type LateReply = (Instant, Vec<u8>, SocketAddr);

/// With `late=`, a thread that sends each UDP reply handed to it when it is due (in the order
/// handed over, which the injector keeps), so that the discovery thread goes on receiving
/// meanwhile; none without it.
fn late_sender(udp: &UdpSocket, late: bool) -> Result<Option<Sender<LateReply>>, ServeError> {
    if !late {
        return Ok(None);
    }
    let at = udp
        .local_addr()
        .map_or_else(|_| "UDP".into(), |a| a.to_string());
    let udp = udp
        .try_clone()
        .map_err(ServeError::socket("clone UDP", at))?;
    let (tx, rx) = std::sync::mpsc::channel::<LateReply>();
    thread::spawn(move || {
        for (due, reply, to) in rx {
            thread::sleep(due.saturating_duration_since(Instant::now()));
            let _ = udp.send_to(&reply, to);
        }
    });
    Ok(Some(tx))
}

/// The class-1 I/O socket as the serve driver's port: O→T frames in, T→O frames out when due.
/// Between them it sleeps in `ppoll` on the socket and the wake-up socket until [`IO_SPIN`]
/// before the deadline (a socket receive timeout would round up to the kernel's tick,
/// milliseconds), and watches the clock and the socket for the rest. A client whose message
/// makes something due earlier (a Forward_Open) wakes it.
struct IoPort {
    io: UdpSocket,
    woken: UnixDatagram,
    buf: [u8; 2048],
}

impl Port for IoPort {
    type Error = Errno;

    fn recv(&mut self, deadline: Instant) -> Result<Option<Input<'_>>, Errno> {
        loop {
            // An error here ends one datagram, not the socket (an ICMP error of an earlier
            // send, or nothing queued).
            if let Ok((n, from)) = self.io.recv_from(&mut self.buf) {
                let bytes = &self.buf[..n];
                return Ok(Some(Input::Datagram {
                    port: IO_PORT,
                    from,
                    bytes,
                }));
            }
            let wait = deadline.saturating_duration_since(Instant::now());
            if wait.is_zero() {
                return Ok(None);
            }
            if wait <= IO_SPIN {
                std::hint::spin_loop();
                continue;
            }
            let mut fds = [
                PollFd::new(self.io.as_fd(), PollFlags::POLLIN),
                PollFd::new(self.woken.as_fd(), PollFlags::POLLIN),
            ];
            match ppoll(
                &mut fds,
                Some(TimeSpec::from_duration(wait - IO_SPIN)),
                None,
            ) {
                Ok(_) | Err(Errno::EINTR) => {}
                Err(e) => return Err(e),
            }
            if fds[1].revents().is_some_and(|r| !r.is_empty()) {
                while self.woken.recv(&mut [0; 16]).is_ok() {}
                return Ok(None);
            }
        }
    }

    fn send(&mut self, out: &Output) -> Result<bool, Errno> {
        let Output::Datagram { to, bytes, .. } = out else {
            return Ok(false);
        };
        Ok(self.io.send_to(bytes, to).is_ok())
    }
}

/// The listen address of `--listen`: `HOST[:PORT]`, port 44818 by default.
pub(crate) fn parse_addr(text: &str) -> Result<SocketAddr, String> {
    crate::net::serve_args::socket_addr(text, proto::enip::io::ENCAP_PORT)
}
