//! `harness serve enip`: the simulator as a real EtherNet/IP adapter on the network.
//!
//! TCP and UDP on the listen address (44818 by default) carry encapsulation messages, UDP 2222
//! on the same IP carries class-1 I/O. One thread per TCP client, one for UDP 44818 and two for
//! class-1 I/O (receiving O→T, producing T→O on the adapter's schedule) share the sans-IO
//! [`Adapter`] behind a mutex; time is the real clock since start. A client whose
//! message stays incomplete for [`STALL`] is disconnected, so a hung peer holds nothing.

use std::net::{IpAddr, SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::thread::{self, Thread};
use std::time::{Duration, Instant};

use proto::enip::io::IO_PORT;
use sim::device::{Device, DeviceConfig};
use sim::enip::{Adapter, Framer};

use crate::poll::PollingStream;

/// How long a partial message may wait for its rest.
pub(crate) const STALL: Duration = Duration::from_secs(10);

/// How long a client's thread polls for its next request before it sleeps: a client that
/// sends request after request is served without a thread wake-up (see [`PollingStream`]).
const REQUEST_POLL: Duration = Duration::from_micros(50);

/// How long before a T→O frame is due the I/O producer stops sleeping and watches the clock.
/// A sleeping thread wakes up late when its processor was idle, by a few hundred µs on a
/// virtual machine here (one wake-up in ten came more than 150 µs late with 100 µs); with
/// 300 µs the T→O frames of a 1 ms RPI leave within tens of µs of their time, for a third of
/// one core while I/O runs.
const IO_SPIN: Duration = Duration::from_micros(300);

/// The longest the I/O producer sleeps when nothing is due.
const IO_IDLE: Duration = Duration::from_millis(50);

/// A running adapter.
struct Shared {
    adapter: Mutex<Adapter>,
    start: Instant,
    /// The I/O producer thread, to wake when something becomes due earlier.
    producer: OnceLock<Thread>,
}

impl Shared {
    fn now(&self) -> Duration {
        self.start.elapsed()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Adapter> {
        self.adapter.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// The addresses of an adapter that [`start_enip`] put on the network.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Served {
    /// Encapsulation messages, TCP and UDP.
    pub(crate) listen: SocketAddr,
    /// Class-1 I/O (UDP 2222 on the same IP).
    pub(crate) io: SocketAddr,
}

/// Binds the sockets and starts the adapter's threads, then returns; they serve until the
/// process ends.
pub(crate) fn start_enip(listen: SocketAddr, config: DeviceConfig) -> Result<Served, String> {
    let SocketAddr::V4(v4) = listen else {
        return Err("EtherNet/IP needs an IPv4 listen address".into());
    };
    let tcp =
        TcpListener::bind(listen).map_err(|e| format!("cannot listen on TCP {listen}: {e}"))?;
    let udp = UdpSocket::bind(listen).map_err(|e| format!("cannot bind UDP {listen}: {e}"))?;
    let io_addr = SocketAddr::new(listen.ip(), IO_PORT);
    let io = UdpSocket::bind(io_addr).map_err(|e| format!("cannot bind UDP {io_addr}: {e}"))?;
    let shared = Arc::new(Shared {
        adapter: Mutex::new(Adapter::new(Device::new(config), v4)),
        start: Instant::now(),
        producer: OnceLock::new(),
    });
    let io_tx = io.try_clone().map_err(|e| format!("UDP {io_addr}: {e}"))?;
    {
        let s = shared.clone();
        let producer = thread::spawn(move || io_produce(io_tx, s));
        let _ = shared.producer.set(producer.thread().clone());
    }
    {
        let s = shared.clone();
        thread::spawn(move || io_receive(io, s));
    }
    {
        let s = shared.clone();
        thread::spawn(move || accept(tcp, s));
    }
    {
        let s = shared.clone();
        thread::spawn(move || discovery(udp, s));
    }
    Ok(Served {
        listen,
        io: io_addr,
    })
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
}

/// `harness serve enip ARGS…`; returns the exit code.
pub(super) fn command(args: &[String]) -> Result<i32, String> {
    let a = match crate::cli::parse_args::<ServeArgs>("harness serve enip", args) {
        Ok(a) => a,
        Err(code) => return Ok(code),
    };
    let product = crate::profile::Profile::by_name(&a.profile)?.nord()?;
    if proto::nord::eip::identity(product).is_none() {
        return Err(format!("{} has no EtherNet/IP interface", product.name()));
    }
    let config = DeviceConfig {
        inverters: a
            .inverters
            .unwrap_or(product.max_inverters())
            .min(product.max_inverters()),
        ..DeviceConfig::new(product)
    };
    serve_enip(
        parse_addr(&a.listen)?,
        config,
        a.seconds.map(Duration::from_secs),
    )?;
    Ok(crate::cli::EXIT_PASS)
}

/// Serves until `duration` has passed (forever when `None`).
pub(crate) fn serve_enip(
    listen: SocketAddr,
    config: DeviceConfig,
    duration: Option<Duration>,
) -> Result<(), String> {
    let product = config.product;
    let inverters = config.inverters;
    let served = start_enip(listen, config)?;
    outln!(
        "serving EtherNet/IP adapter ({}, {inverters} inverters) on {} (TCP, UDP) and {} (class-1 I/O)",
        product.name(),
        served.listen,
        served.io
    );
    match duration {
        Some(d) => thread::sleep(d),
        None => loop {
            thread::sleep(Duration::from_secs(3600));
        },
    }
    Ok(())
}

fn accept(listener: TcpListener, shared: Arc<Shared>) {
    let ids = AtomicU64::new(1);
    for stream in listener.incoming().flatten() {
        let id = ids.fetch_add(1, Ordering::Relaxed);
        let s = shared.clone();
        thread::spawn(move || client(stream, id, s));
    }
}

fn client(stream: TcpStream, id: u64, shared: Arc<Shared>) {
    let Ok(peer) = stream.peer_addr() else { return };
    let _ = stream.set_nodelay(true);
    let Ok(mut stream) = PollingStream::new(stream, REQUEST_POLL) else {
        return;
    };
    let mut framer = Framer::new();
    let mut buf = [0u8; 8192];
    let mut pending_since: Option<Instant> = None;
    loop {
        let wait = if pending_since.is_some() {
            Duration::from_millis(500)
        } else {
            Duration::from_secs(60)
        };
        let n = match stream.read(&mut buf, wait) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {
                if pending_since.is_some_and(|t| t.elapsed() > STALL) {
                    break;
                }
                continue;
            }
            Err(_) => break,
        };
        let messages = match framer.push(&buf[..n]) {
            Ok(m) => m,
            Err(_) => break,
        };
        let mut close = false;
        for m in messages {
            let (r, sooner) = {
                let mut a = shared.lock();
                let before = a.next_due();
                let r = a.handle_tcp(id, peer, &m, shared.now());
                let after = a.next_due();
                (r, after.is_some_and(|t| before.is_none_or(|b| t < b)))
            };
            if sooner {
                if let Some(p) = shared.producer.get() {
                    p.unpark();
                }
            }
            if let Some(reply) = r.reply {
                if stream.write_all(&reply, STALL).is_err() {
                    close = true;
                }
            }
            close |= r.close;
            if close {
                break;
            }
        }
        if close {
            break;
        }
        pending_since = match (framer.pending(), pending_since) {
            (0, _) => None,
            (_, Some(t)) => Some(t),
            (_, None) => Some(Instant::now()),
        };
    }
    shared.lock().client_closed(id);
}

fn discovery(udp: UdpSocket, shared: Arc<Shared>) {
    let mut buf = [0u8; 2048];
    loop {
        let Ok((n, from)) = udp.recv_from(&mut buf) else {
            continue;
        };
        let reply = shared.lock().handle_udp(&buf[..n]);
        if let Some(r) = reply {
            let _ = udp.send_to(&r, from);
        }
    }
}

/// Receives O→T datagrams. Production runs apart, so it keeps its own schedule.
fn io_receive(io: UdpSocket, shared: Arc<Shared>) {
    let mut buf = [0u8; 2048];
    loop {
        if let Ok((n, from)) = io.recv_from(&mut buf) {
            let _ = shared.lock().handle_io(from, &buf[..n], shared.now());
        }
    }
}

/// Sends T→O frames when due and runs the watchdogs. It parks until [`IO_SPIN`] before the
/// adapter's next due time (at most [`IO_IDLE`]) and watches the clock for the rest (a socket
/// receive timeout would round up to the kernel's tick, milliseconds). A client whose message
/// makes something due earlier (a Forward_Open) unparks it.
fn io_produce(io: UdpSocket, shared: Arc<Shared>) {
    loop {
        let (frames, due) = {
            let mut a = shared.lock();
            let frames = a.poll(shared.now());
            (frames, a.next_due())
        };
        for (to, frame) in frames {
            let _ = io.send_to(&frame, to);
        }
        let wait = due.map_or(IO_IDLE, |d| d.saturating_sub(shared.now()).min(IO_IDLE));
        if wait > IO_SPIN {
            thread::park_timeout(wait - IO_SPIN);
        } else if let Some(due) = due {
            while shared.now() < due {
                std::hint::spin_loop();
            }
        }
    }
}

/// The listen address of `--listen`: `HOST[:PORT]`, port 44818 by default.
pub(crate) fn parse_addr(text: &str) -> Result<SocketAddr, String> {
    if let Ok(a) = text.parse::<SocketAddr>() {
        return Ok(a);
    }
    text.parse::<IpAddr>()
        .map(|ip| SocketAddr::new(ip, proto::enip::io::ENCAP_PORT))
        .map_err(|_| format!("`{text}` is not an address like 127.0.0.2 or 127.0.0.2:44818"))
}
