//! The idle-clients figure: a good client's request latency with thousands of idle TCP
//! connections open to the served adapter, next to the same without them, and the serving
//! process's thread count both ways (the adapter is served in this process, so
//! `/proc/self/task` counts its threads and the bench's).

use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use harness::stats::percentile;
use nix::sys::resource::{getrlimit, setrlimit, Resource};
use proto::enip::encap::{frame_len, Command, EncapRepr};
use proto::enip::epath::EPath;

use super::common::enip_client::Client;
use super::Settings;

/// A good client's latency and rate.
pub(super) struct Latency {
    pub(super) p50: Duration,
    pub(super) p99: Duration,
    pub(super) per_sec: f64,
    pub(super) count: usize,
}

impl Latency {
    pub(super) fn show(&self) -> String {
        format!(
            "p50 {} µs, p99 {} µs, {:.0} requests/s ({} requests)",
            self.p50.as_micros(),
            self.p99.as_micros(),
            self.per_sec,
            self.count
        )
    }
}

/// The figure, both ways.
pub(super) struct Idle {
    pub(super) without: Latency,
    pub(super) with: Latency,
    pub(super) threads_without: usize,
    pub(super) threads_with: usize,
    /// How long opening the idle connections took.
    pub(super) opening: Duration,
}

/// Opens `s.idle` TCP connections (no session: each answered one ListIdentity, so it is known
/// served, then silent) and times a good client's Get_Attribute_Single of `path` without and
/// with them.
pub(super) fn idle_clients(s: &Settings, path: &EPath) -> Result<Idle, String> {
    raise_open_files(s.idle)?;
    let without = good_client(s, path)?;
    let threads_without = threads()?;
    let begin = Instant::now();
    let mut idle = Vec::with_capacity(s.idle);
    for n in 0..s.idle {
        idle.push(served_connection(s.listen).map_err(|e| format!("idle connection {n}: {e}"))?);
    }
    let opening = begin.elapsed();
    let threads_with = threads()?;
    let with = good_client(s, path)?;
    drop(idle);
    Ok(Idle {
        without,
        with,
        threads_without,
        threads_with,
        opening,
    })
}

/// Raises the soft open-files limit to the hard one: both ends of every idle connection are
/// in this process.
fn raise_open_files(idle: usize) -> Result<(), String> {
    let (_, hard) = getrlimit(Resource::RLIMIT_NOFILE).map_err(|e| format!("getrlimit: {e}"))?;
    setrlimit(Resource::RLIMIT_NOFILE, hard, hard).map_err(|e| format!("setrlimit: {e}"))?;
    let need = 2 * idle as u64 + 256;
    if hard < need {
        return Err(format!(
            "{idle} idle connections need {need} open files here, the hard limit is {hard}"
        ));
    }
    Ok(())
}

/// Threads of this process.
fn threads() -> Result<usize, String> {
    std::fs::read_dir("/proc/self/task")
        .map(Iterator::count)
        .map_err(|e| format!("/proc/self/task: {e}"))
}

/// A TCP connection the adapter has answered (ListIdentity), left open.
fn served_connection(at: SocketAddr) -> Result<TcpStream, String> {
    use std::io::{Read, Write};
    let mut tcp = TcpStream::connect_timeout(&at, Duration::from_secs(2))
        .map_err(|e| format!("connect: {e}"))?;
    tcp.set_read_timeout(Some(Duration::from_secs(2)))
        .map_err(|e| e.to_string())?;
    let msg = EncapRepr {
        command: Command::LIST_IDENTITY.0,
        ..EncapRepr::default()
    };
    tcp.write_all(&msg.emit().map_err(|e| e.to_string())?)
        .map_err(|e| format!("send: {e}"))?;
    let mut buf = Vec::new();
    let mut chunk = [0u8; 512];
    while frame_len(&buf).is_none_or(|n| buf.len() < n) {
        match tcp.read(&mut chunk) {
            Ok(0) => return Err("closed by the adapter".into()),
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
            Err(e) => return Err(format!("no ListIdentity reply: {e}")),
        }
    }
    let reply = EncapRepr::parse(&buf).map_err(|e| e.to_string())?;
    if reply.status != 0 {
        return Err(format!("ListIdentity status {:#x}", reply.status));
    }
    Ok(tcp)
}

/// The bench's minimal client timing each of its requests, after a warm-up.
fn good_client(s: &Settings, path: &EPath) -> Result<Latency, String> {
    let mut c = Client::connect(s.listen)?;
    for _ in 0..super::WARM_UP {
        c.get(path)?;
    }
    let mut times = Vec::with_capacity(s.requests as usize);
    let begin = Instant::now();
    while times.len() < s.requests as usize && begin.elapsed() < s.limit {
        let t = Instant::now();
        c.get(path)?;
        times.push(t.elapsed());
    }
    let secs = begin.elapsed().as_secs_f64();
    times.sort_unstable();
    Ok(Latency {
        p50: percentile(&times, 50.0).ok_or("no request timed")?,
        p99: percentile(&times, 99.0).ok_or("no request timed")?,
        per_sec: times.len() as f64 / secs,
        count: times.len(),
    })
}
