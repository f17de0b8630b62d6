//! The floor under every SDO figure: what one request and its answer cost over socketcand on
//! TCP loopback with nothing behind them. A trivial server (a thread of the bench) answers
//! each message with one canned frame, and a minimal client writes one fixed request and reads
//! until the answer's `>`. Nothing is parsed, formatted or allocated on the way; what is left
//! is two writes, two reads and two wake-ups of threads in the kernel: the same TCP round
//! trip every client pays to any server on this machine.
//!
//! Both ends are also used on their own: the minimal client against the served segment times
//! the server above the floor, and the SDO clients (the harness's, python-canopen) against the
//! trivial server time each client above it.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::thread;
use std::time::{Duration, Instant};

use harness::can_bench::Reads;
use harness::stats::Rate;

/// The upload request of P102 set 1 of FI 3 (node 36, 2066h:01h) as the harness writes it.
pub(crate) const REQUEST: &[u8] = b"< send 624 8 40 66 20 1 0 0 0 0 >";

/// The node's answer: expedited, 2 bytes, 200 (P102's factory value), as a served segment
/// writes it (the timestamp fixed).
pub(crate) const ANSWER: &[u8] = b"< frame 5A4 0.000000 4B662001C8000000 >";

/// Reads made before the timed ones.
const WARM_UP: u32 = 100;

/// A trivial socketcand server on loopback: `< hi >`, `< ok >` to each of the first two
/// messages (open and rawmode), then [`ANSWER`] to every message; a thread per client, each
/// read answered by one write. It serves until the bench exits.
pub(crate) fn trivial_server() -> std::io::Result<SocketAddr> {
    let listener = TcpListener::bind("127.0.0.1:0")?;
    let addr = listener.local_addr()?;
    thread::spawn(move || {
        for stream in listener.incoming().map_while(Result::ok) {
            thread::spawn(move || serve(stream));
        }
    });
    Ok(addr)
}

fn serve(mut stream: TcpStream) -> std::io::Result<()> {
    stream.set_nodelay(true)?;
    stream.write_all(b"< hi >")?;
    let mut seen = 0u64;
    let mut chunk = [0u8; 1024];
    let mut out = Vec::with_capacity(1024);
    loop {
        let n = stream.read(&mut chunk)?;
        if n == 0 {
            return Ok(());
        }
        out.clear();
        for _ in chunk[..n].iter().filter(|&&b| b == b'>') {
            seen += 1;
            out.extend_from_slice(if seen <= 2 { b"< ok >" } else { ANSWER });
        }
        if !out.is_empty() {
            stream.write_all(&out)?;
        }
    }
}

/// `count` round trips of the minimal client to the socketcand server at `addr` (channel
/// `can0`): [`REQUEST`] written, then read until the answer of node 36 (`< frame 5A4 … >`)
/// is in, each after the last.
pub(crate) fn minimal_client(addr: SocketAddr, count: u32) -> Result<Reads, String> {
    let e = |e: std::io::Error| format!("minimal client to {addr}: {e}");
    let mut s = TcpStream::connect_timeout(&addr, Duration::from_secs(2)).map_err(e)?;
    s.set_nodelay(true).map_err(e)?;
    s.set_read_timeout(Some(Duration::from_secs(2)))
        .map_err(e)?;
    let mut buf = Vec::with_capacity(4096);
    let mut until = |s: &mut TcpStream, want: &[u8]| -> Result<(), String> {
        loop {
            if let Some(end) = buf.iter().position(|&b| b == b'>') {
                let found = buf[..end].windows(want.len()).any(|w| w == want);
                buf.drain(..=end);
                if found {
                    return Ok(());
                }
                continue;
            }
            let mut chunk = [0u8; 1024];
            match s.read(&mut chunk).map_err(e)? {
                0 => return Err(format!("{addr} closed the connection")),
                n => buf.extend_from_slice(&chunk[..n]),
            }
        }
    };
    until(&mut s, b"hi")?;
    s.write_all(b"< open can0 >").map_err(e)?;
    until(&mut s, b"ok")?;
    s.write_all(b"< rawmode >").map_err(e)?;
    until(&mut s, b"ok")?;
    let mut one = |s: &mut TcpStream| -> Result<(), String> {
        s.write_all(REQUEST).map_err(e)?;
        until(s, b"frame 5A4 ")
    };
    for _ in 0..WARM_UP {
        one(&mut s)?;
    }
    let mut each_us = Vec::with_capacity(count as usize);
    let start = Instant::now();
    for _ in 0..count {
        let t = Instant::now();
        one(&mut s)?;
        each_us.push(t.elapsed().as_secs_f64() * 1e6);
    }
    Ok(Reads {
        rate: Rate {
            count: u64::from(count),
            secs: start.elapsed().as_secs_f64(),
        },
        each_us,
    })
}
