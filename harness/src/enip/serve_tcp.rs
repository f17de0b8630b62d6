//! The TCP clients of `harness serve enip`: all of them in one event loop.
//!
//! One thread runs a current-thread tokio runtime and each TCP client is a task on it: an idle
//! client costs its socket and a few hundred bytes, no thread (8,000 idle clients leave the
//! served adapter at its handful of threads; the bench shows it). The tasks share the sans-IO
//! [`sim::enip::Adapter`] with the UDP and I/O threads behind [`Shared`]'s mutex, never held
//! across an await, and hand it each message as an [`Input::Message`].
//!
//! Per client the loop enforces what only the driver can, the adapter deciding the values:
//!
//! - the Encapsulation Inactivity Timeout (TCP/IP Interface attribute 13, default 120 s,
//!   0 disables): a client with no encapsulation traffic for that long is closed unless it
//!   has CIP connections open ([`sim::enip::Adapter::holds_connections`]; then it is checked
//!   again one timeout later). The clock starts at accept, as OpENer's socket timer does. A
//!   Set_Attribute_Single of it reaches every waiting client at once (a watch channel);
//! - [`STALL`]: a message that stays incomplete that long closes its client;
//! - the connection limit: clients beyond it are accepted, their first message answered with
//!   "insufficient memory" ([`sim::enip::no_room_reply`]) and closed — never left in the
//!   backlog, never a crash when the process runs out of file descriptors.
//!
//! A busy client keeps the latency of a thread of its own: after each message its task polls
//! the socket for [`REQUEST_POLL`] before it goes back to waiting on the event loop, so a
//! client that sends request after request is served without a wake-up. Between polls it
//! yields the processor (a client on the same core gets to send its next request: without it
//! the round trips of one client over loopback fell from ~40k/s to ~10k/s on two busy cores)
//! and the event loop (the other clients get their turn).

use std::cell::RefCell;
use std::io::ErrorKind;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use sim::endpoint::{Endpoint, Input, Output};
use sim::enip::{ClientId, Framer};
use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::watch;
use tokio::time::{sleep_until, timeout, Instant};

use super::serve::{Shared, STALL};
use crate::net::serve_error::ServeError;

/// How long a client's task polls for its next request before it waits on the event loop.
const REQUEST_POLL: Duration = Duration::from_micros(50);

/// How long a client beyond the connection limit has to send its first message.
const NO_ROOM_WAIT: Duration = Duration::from_secs(1);

/// Clients beyond the limit being refused at once; more are closed without a reply.
const NO_ROOM_CLIENTS: usize = 64;

/// How long accepting pauses after the process ran out of file descriptors (or the kernel of
/// buffers): a client leaving frees one.
const ACCEPT_BACKOFF: Duration = Duration::from_millis(20);

/// The bytes one read takes at most.
const READ_CHUNK: usize = 8192;

/// Starts the event loop's thread serving `listener`'s clients, at most `max_clients` at
/// once.
pub(super) fn start(
    listener: std::net::TcpListener,
    shared: Arc<Shared>,
    max_clients: usize,
) -> Result<(), ServeError> {
    let at = listener
        .local_addr()
        .map_or_else(|_| "TCP".into(), |a| a.to_string());
    listener
        .set_nonblocking(true)
        .map_err(ServeError::socket("make non-blocking: TCP", at))?;
    let event_loop = |source| ServeError::Thread {
        what: "the TCP event loop",
        source,
    };
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_io()
        .enable_time()
        .build()
        .map_err(event_loop)?;
    std::thread::Builder::new()
        .name("enip-tcp".into())
        .spawn(move || {
            runtime.block_on(async move {
                match TcpListener::from_std(listener) {
                    Ok(l) => accept(l, shared, max_clients).await,
                    Err(e) => eprintln!("serve enip: TCP listener: {e}"),
                }
            })
        })
        .map_err(event_loop)?;
    Ok(())
}

/// What every client task shares.
struct Loop {
    shared: Arc<Shared>,
    /// The adapter's inactivity timeout as last seen; a client that changes it sends it.
    timeout: watch::Sender<Option<Duration>>,
    /// Clients served (not counting those being refused).
    clients: AtomicUsize,
    /// Clients being refused.
    refusing: AtomicUsize,
}

async fn accept(listener: TcpListener, shared: Arc<Shared>, max_clients: usize) {
    let inactivity = shared.lock().inactivity_timeout();
    let l = Arc::new(Loop {
        shared,
        timeout: watch::Sender::new(inactivity),
        clients: AtomicUsize::new(0),
        refusing: AtomicUsize::new(0),
    });
    let mut next_id: ClientId = 1;
    loop {
        let (stream, peer) = match listener.accept().await {
            Ok(c) => c,
            Err(_) => {
                // EMFILE, ENFILE, ENOBUFS, or a client that left before it was accepted:
                // nothing to close, and the backlog keeps the rest.
                tokio::time::sleep(ACCEPT_BACKOFF).await;
                continue;
            }
        };
        if l.clients.load(Ordering::Relaxed) < max_clients {
            let slot = Slot::take(&l, next_id);
            next_id += 1;
            tokio::spawn(client(stream, peer, slot));
        } else if l.refusing.fetch_add(1, Ordering::Relaxed) < NO_ROOM_CLIENTS {
            let l = l.clone();
            tokio::spawn(async move {
                let _ = timeout(NO_ROOM_WAIT, no_room(stream)).await;
                l.refusing.fetch_sub(1, Ordering::Relaxed);
            });
        } else {
            l.refusing.fetch_sub(1, Ordering::Relaxed);
            drop(stream);
        }
    }
}

/// A client's place in the loop; giving it up ends the client's sessions and explicit
/// connections in the adapter, however the task ended.
struct Slot {
    l: Arc<Loop>,
    id: ClientId,
}

impl Slot {
    fn take(l: &Arc<Loop>, id: ClientId) -> Slot {
        l.clients.fetch_add(1, Ordering::Relaxed);
        Slot { l: l.clone(), id }
    }
}

impl Drop for Slot {
    fn drop(&mut self) {
        self.l.shared.adapter.input(Input::Closed(self.id));
        self.l.clients.fetch_sub(1, Ordering::Relaxed);
    }
}

/// A client beyond the limit: its first message answered with "insufficient memory".
async fn no_room(mut stream: TcpStream) {
    let mut framer = Framer::new();
    loop {
        if stream.readable().await.is_err() {
            return;
        }
        match read_now(&stream, &mut framer) {
            Read::Nothing => continue,
            Read::Messages(m) if m.is_empty() => continue,
            Read::Messages(m) => {
                if let Some(reply) = m.first().and_then(|m| sim::enip::no_room_reply(m)) {
                    let _ = stream.write_all(&reply).await;
                }
                return;
            }
            Read::Closed => return,
        }
    }
}

/// What a read without waiting found.
enum Read {
    /// Nothing has arrived.
    Nothing,
    /// Bytes arrived; the whole messages among them (maybe none yet).
    Messages(Vec<Vec<u8>>),
    /// The peer closed, the connection failed, or the stream cannot be framed.
    Closed,
}

thread_local! {
    /// The loop thread's read buffer: one for all clients, so a waiting client holds none and
    /// a poll clears nothing.
    static READ_BUF: RefCell<Vec<u8>> = RefCell::new(vec![0; READ_CHUNK]);
}

/// Reads what has arrived into `framer`.
fn read_now(stream: &TcpStream, framer: &mut Framer) -> Read {
    READ_BUF.with_borrow_mut(|buf| match stream.try_read(buf) {
        Ok(0) => Read::Closed,
        Ok(n) => framer.push(&buf[..n]).map_or(Read::Closed, Read::Messages),
        Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => {
            Read::Nothing
        }
        Err(_) => Read::Closed,
    })
}

/// Serves one client until it closes, misbehaves, or stays inactive too long.
async fn client(mut stream: TcpStream, peer: SocketAddr, slot: Slot) {
    let _ = stream.set_nodelay(true);
    let mut timeouts = slot.l.timeout.subscribe();
    let mut framer = Framer::new();
    let mut last = Instant::now();
    let mut pending_since: Option<Instant> = None;
    let mut inject = slot.l.shared.injector();
    // `close`: the connection ends, unanswered, at its second request (the first after
    // RegisterSession).
    let closes = slot.l.shared.misbehave.close;
    let mut requests = 0u32;
    loop {
        let inactive_at = timeouts.borrow_and_update().map(|t| last + t);
        let stall_at = pending_since.map(|t| t + STALL);
        let wake = match (inactive_at, stall_at) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        tokio::select! {
            r = stream.readable() => if r.is_err() { return },
            _ = sleep_until(wake.unwrap_or_else(Instant::now)), if wake.is_some() => {
                let now = Instant::now();
                if stall_at.is_some_and(|t| now >= t) {
                    return;
                }
                if inactive_at.is_some_and(|t| now >= t) {
                    if !slot.l.shared.lock().holds_connections(slot.id) {
                        return;
                    }
                    last = now;
                }
                continue;
            }
            // A new timeout: the deadline is worked out again.
            r = timeouts.changed() => if r.is_err() { return },
        }
        // Serve what arrived, then poll for the next request for a little while.
        let mut polled = std::time::Instant::now();
        loop {
            match read_now(&stream, &mut framer) {
                Read::Closed => return,
                Read::Nothing if polled.elapsed() >= REQUEST_POLL => break,
                Read::Nothing => {
                    std::thread::yield_now();
                    tokio::task::yield_now().await;
                }
                Read::Messages(messages) => {
                    last = Instant::now();
                    // `--misbehave`: the adapter acts on them all at once; the injector says
                    // what of its replies leaves, and when (`late=`).
                    let mut leave = Vec::new();
                    for m in messages {
                        requests += 1;
                        if closes && requests == 2 {
                            misbehaved_close(&slot, peer);
                            return;
                        }
                        inject.heard(last.into_std());
                        for out in handle(&slot, peer, &m) {
                            let tally = slot.l.shared.counters.misbehaved();
                            leave.extend(inject.outgoing(out, true, last.into_std(), tally));
                        }
                    }
                    for (due, out) in leave {
                        match out {
                            Output::Message { bytes, .. } => {
                                if let Some(due) = due {
                                    sleep_until_due(Instant::from_std(due)).await;
                                }
                                match timeout(STALL, stream.write_all(&bytes)).await {
                                    Ok(Ok(())) => {}
                                    _ => return,
                                }
                            }
                            Output::Close(_) => return,
                            _ => {}
                        }
                    }
                    polled = std::time::Instant::now();
                }
            }
        }
        pending_since = match (framer.pending(), pending_since) {
            (0, _) => None,
            (_, Some(t)) => Some(t),
            (_, None) => Some(Instant::now()),
        };
    }
}

/// `close`: the line on stderr and the count for a connection closed on purpose.
fn misbehaved_close(slot: &Slot, peer: SocketAddr) {
    let shared = &slot.l.shared;
    shared.counters.misbehaved().closed();
    let t = shared.adapter.now().as_secs_f64();
    eprintln!("misbehave {t:9.3}s close   TCP connection of {peer} at its second request");
}

/// Waits until `due`, and not at all when it has passed. Tokio rounds a timer's deadline up
/// to the next whole millisecond of its clock, so a sleep until a time already passed still
/// waits for the timer's next tick: every reply of an adapter not late on purpose left up to
/// 1–2 ms late (found by the soak, `harness/benches/soak/`: a good client's p50 of 1.2 ms).
async fn sleep_until_due(due: Instant) {
    if due > Instant::now() {
        sleep_until(due).await;
    }
}

/// One message through the adapter: its reply, and its close when the adapter ends the
/// connection. Wakes the I/O thread when something became due sooner (a Forward_Open) and
/// tells every client when the inactivity timeout changed.
fn handle(slot: &Slot, peer: SocketAddr, msg: &[u8]) -> Vec<Output> {
    let shared = &slot.l.shared;
    let (r, sooner, timeout) = {
        let (mut a, now) = shared.adapter.lock();
        let before = a.next_due();
        let message = Input::Message {
            client: slot.id,
            peer,
            bytes: msg,
        };
        let r = a.input(message, now);
        let after = a.next_due();
        let sooner = after.is_some_and(|t| before.is_none_or(|b| t < b));
        (r, sooner, a.inactivity_timeout())
    };
    if sooner {
        shared.wake_io();
    }
    slot.l.timeout.send_if_modified(|t| {
        let changed = *t != timeout;
        *t = timeout;
        changed
    });
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(start_paused = true)]
    async fn a_reply_due_now_does_not_wait_for_the_timers_next_tick() {
        // Half-way through a millisecond of the (paused) clock, where the rounding bites: a
        // timer until now would let the idle runtime move the clock on to the next tick.
        tokio::time::advance(Duration::from_micros(500)).await;
        let due = Instant::now();
        sleep_until_due(due).await;
        assert_eq!(Instant::now(), due, "the reply waited for the timer's tick");
        // A reply late on purpose (`--reply-delay`) still waits for its time (and the tick
        // after it).
        let late = due + Duration::from_millis(3);
        sleep_until_due(late).await;
        assert!(Instant::now() >= late);
    }
}
