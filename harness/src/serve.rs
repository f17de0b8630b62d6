//! `harness serve enip`: the simulator as a real EtherNet/IP adapter on the network.
//!
//! TCP and UDP on the listen address (44818 by default) carry encapsulation messages, UDP 2222
//! on the same IP carries class-1 I/O. One thread per TCP client and one per UDP socket share
//! the sans-IO [`Adapter`] behind a mutex; time is the real clock since start. A client whose
//! message stays incomplete for [`STALL`] is disconnected, so a hung peer holds nothing.

use std::io::{Read, Write};
use std::net::{IpAddr, SocketAddr, TcpListener, TcpStream, UdpSocket};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};

use proto::enip::io::IO_PORT;
use sim::device::{Device, DeviceConfig};
use sim::enip::{Adapter, Framer};

/// How long a partial message may wait for its rest.
pub(crate) const STALL: Duration = Duration::from_secs(10);

/// A running adapter.
struct Shared {
    adapter: Mutex<Adapter>,
    start: Instant,
}

impl Shared {
    fn now(&self) -> Duration {
        self.start.elapsed()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Adapter> {
        self.adapter.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// Serves until `duration` has passed (forever when `None`).
pub(crate) fn serve_enip(
    listen: SocketAddr,
    config: DeviceConfig,
    duration: Option<Duration>,
) -> Result<(), String> {
    let SocketAddr::V4(v4) = listen else {
        return Err("EtherNet/IP needs an IPv4 listen address".into());
    };
    let tcp =
        TcpListener::bind(listen).map_err(|e| format!("cannot listen on TCP {listen}: {e}"))?;
    let udp = UdpSocket::bind(listen).map_err(|e| format!("cannot bind UDP {listen}: {e}"))?;
    let io_addr = SocketAddr::new(listen.ip(), IO_PORT);
    let io = UdpSocket::bind(io_addr).map_err(|e| format!("cannot bind UDP {io_addr}: {e}"))?;
    let product = config.product;
    let inverters = config.inverters;
    let shared = Arc::new(Shared {
        adapter: Mutex::new(Adapter::new(Device::new(config), v4)),
        start: Instant::now(),
    });
    println!(
        "serving EtherNet/IP adapter ({}, {inverters} inverters) on {listen} (TCP, UDP) and {io_addr} (class-1 I/O)",
        product.name()
    );
    {
        let s = shared.clone();
        thread::spawn(move || accept(tcp, s));
    }
    {
        let s = shared.clone();
        thread::spawn(move || discovery(udp, s));
    }
    {
        let s = shared.clone();
        thread::spawn(move || io_loop(io, s));
    }
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

fn client(mut stream: TcpStream, id: u64, shared: Arc<Shared>) {
    let Ok(peer) = stream.peer_addr() else { return };
    let _ = stream.set_nodelay(true);
    let mut framer = Framer::new();
    let mut buf = [0u8; 8192];
    let mut pending_since: Option<Instant> = None;
    loop {
        let wait = if pending_since.is_some() {
            Duration::from_millis(500)
        } else {
            Duration::from_secs(60)
        };
        let _ = stream.set_read_timeout(Some(wait));
        let n = match stream.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
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
            let r = shared.lock().handle_tcp(id, peer, &m, shared.now());
            if let Some(reply) = r.reply {
                if stream.write_all(&reply).is_err() {
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

fn io_loop(io: UdpSocket, shared: Arc<Shared>) {
    let mut buf = [0u8; 2048];
    loop {
        let now = shared.now();
        let due = shared.lock().next_due();
        let wait = due
            .map(|d| d.saturating_sub(now))
            .unwrap_or(Duration::from_millis(50))
            .clamp(Duration::from_micros(100), Duration::from_millis(50));
        let _ = io.set_read_timeout(Some(wait));
        if let Ok((n, from)) = io.recv_from(&mut buf) {
            let _ = shared.lock().handle_io(from, &buf[..n], shared.now());
        }
        let frames = shared.lock().poll(shared.now());
        for (to, frame) in frames {
            let _ = io.send_to(&frame, to);
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
