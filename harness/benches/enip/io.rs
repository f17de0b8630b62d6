//! The jitter figure: T→O arrival times of a class-1 connection and how far they stray from
//! the RPI (`harness::stats::jitter`), from the kernel's receive stamps.

use std::io::IoSliceMut;
use std::net::{SocketAddr, UdpSocket};
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread;
use std::time::{Duration, Instant};

use harness::stats::{jitter, Jitter};
use nix::errno::Errno;
use nix::sys::socket::{recvmsg, setsockopt, sockopt, ControlMessageOwned, MsgFlags};
use nix::sys::time::TimeSpec;
use proto::enip::io::{IoFrame, IO_PORT};
use proto::nord::eip::{self, Direction};

use super::common::enip_client::Client;
use super::{Settings, PRODUCT};

/// T→O arrival jitter of an Exclusive Owner connection: O→T every RPI from one thread, T→O
/// arrival times recorded on this one.
pub(super) fn io_jitter(s: &Settings) -> Result<Jitter, String> {
    let mut client = Client::connect(s.listen)?;
    let local = client.local_addr().map_err(|e| e.to_string())?.ip();
    // Bound before Forward_Open: the first T→O frame follows its reply at once.
    let udp = UdpSocket::bind(SocketAddr::new(local, IO_PORT))
        .map_err(|e| format!("cannot bind UDP {local}:{IO_PORT} for T→O data: {e}"))?;
    let out = eip::assemblies(PRODUCT)
        .iter()
        .filter(|a| a.direction == Direction::Output)
        .max_by_key(|a| a.len)
        .ok_or("no output assembly")?;
    let inp = eip::assembly(PRODUCT, out.instance + 1).ok_or("no input assembly")?;
    let run_idle = eip::o_t_run_idle(PRODUCT, out.instance, 0);
    let (o_t_size, t_o_size) = eip::connection_sizes(PRODUCT, out.instance, inp.instance, 0);
    let rpi_us = u32::try_from(s.rpi.as_micros()).map_err(|e| e.to_string())?;
    let conn = client.forward_open(out.instance, inp.instance, o_t_size, t_o_size, rpi_us)?;

    let stop = Arc::new(AtomicBool::new(false));
    let sender = {
        let udp = udp.try_clone().map_err(|e| e.to_string())?;
        let stop = stop.clone();
        let to = SocketAddr::new(s.listen.ip(), IO_PORT);
        let (rpi, len, id) = (s.rpi, usize::from(out.len), conn.o_t_id);
        thread::spawn(move || -> Result<(), String> {
            let mut frame = IoFrame {
                connection: id,
                sequence: 0,
                count: 0,
                run_idle: run_idle.then_some(1),
                data: vec![0; len],
            };
            let mut due = Instant::now();
            while !stop.load(Ordering::Relaxed) {
                frame.sequence = frame.sequence.wrapping_add(1);
                frame.count = frame.count.wrapping_add(1);
                let bytes = frame.emit().map_err(|e| e.to_string())?;
                udp.send_to(&bytes, to)
                    .map_err(|e| format!("O→T send failed: {e}"))?;
                due += rpi;
                thread::sleep(due.saturating_duration_since(Instant::now()));
            }
            Ok(())
        })
    };

    let recorded = record_t_o(&udp, conn.t_o_id, s.record);
    stop.store(true, Ordering::Relaxed);
    let sent = sender
        .join()
        .map_err(|_| "the O→T thread panicked".to_string())?;
    client.forward_close(conn.serial)?;
    sent?;
    let arrivals = recorded?;
    jitter(&arrivals, s.rpi).ok_or_else(|| format!("only {} T→O frames", arrivals.len()))
}

/// (sequence, arrival time) of every T→O frame of connection `t_o_id` for `span` from the
/// first.
fn record_t_o(
    udp: &UdpSocket,
    t_o_id: u32,
    span: Duration,
) -> Result<Vec<(u32, Duration)>, String> {
    udp.set_read_timeout(Some(Duration::from_millis(100)))
        .map_err(|e| e.to_string())?;
    // The kernel stamps each datagram as it arrives (SO_TIMESTAMPNS): the figure is the
    // adapter's and the network's, not how soon this thread was scheduled to read it.
    setsockopt(udp, sockopt::ReceiveTimestampns, &true)
        .map_err(|e| format!("SO_TIMESTAMPNS: {e}"))?;
    let mut buf = [0u8; 1500];
    let mut arrivals = Vec::with_capacity(span.as_millis() as usize + 64);
    let begin = Instant::now();
    let mut first: Option<(Instant, Duration)> = None;
    loop {
        let now = Instant::now();
        match first {
            Some((f, _)) if now >= f + span => break,
            None if now >= begin + Duration::from_secs(1) => {
                return Err("no T→O frame within 1 s of Forward_Open".into())
            }
            _ => {}
        }
        match receive_stamped(udp, &mut buf) {
            Ok((n, stamp)) => {
                let Ok(frame) = IoFrame::parse(&buf[..n], false) else {
                    continue;
                };
                if frame.connection != t_o_id {
                    continue;
                }
                let (_, f) = *first.get_or_insert((Instant::now(), stamp));
                arrivals.push((frame.sequence, stamp.saturating_sub(f)));
            }
            Err(Errno::EAGAIN) => {
                if first.is_some() {
                    return Err(format!(
                        "T→O stopped after {} frames (connection timed out?)",
                        arrivals.len()
                    ));
                }
            }
            Err(e) => return Err(format!("T→O receive failed: {e}")),
        }
    }
    Ok(arrivals)
}

/// One datagram into `buf`: its length and the kernel's arrival stamp (wall clock, as a
/// duration since the Unix epoch; only differences are used).
fn receive_stamped(udp: &UdpSocket, buf: &mut [u8]) -> Result<(usize, Duration), Errno> {
    let mut cmsg = nix::cmsg_space!(TimeSpec);
    let mut iov = [IoSliceMut::new(buf)];
    let msg = recvmsg::<()>(
        udp.as_raw_fd(),
        &mut iov,
        Some(&mut cmsg),
        MsgFlags::empty(),
    )?;
    let stamp = msg.cmsgs()?.find_map(|c| match c {
        ControlMessageOwned::ScmTimestampns(t) => Some(Duration::from(t)),
        _ => None,
    });
    // Without a stamp (the option refused) the datagram is unusable for the figure.
    stamp.map(|t| (msg.bytes, t)).ok_or(Errno::ENOMSG)
}
