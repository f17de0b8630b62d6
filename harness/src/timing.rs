//! Time on a shared host: the device's limits, and how late the harness itself ran.
//!
//! A verdict about a device must not move with the host's load. Every wait for an answer is
//! the device's limit (the manual's or the standard's) plus the harness's own scheduling
//! delay, measured as it happens: the [watch](start_watch) is a thread that asks to wake every
//! millisecond and records how late it woke, which is what any thread of the harness suffers
//! at that moment (a request that should leave, an answer waiting to be read). A [`Deadline`]
//! moves by the time the host lost meanwhile. A step that still timed out while the host lost
//! a large part of the device's limit ([`excuses`]) says nothing about the device: the runner
//! discards that attempt and runs the case again, and when no attempt runs on time the verdict
//! is inconclusive, "host late by N ms" (see `crate::runner`). A state the device reached
//! through the bus's cycles is excused the same way when the host stalled for
//! [`STALL_EXCUSE`] at once at any time since the case's first step: the harness's cycles
//! stopped meanwhile, and the state shows it only in a later step. A device that answers late
//! while the host was on time fails, with both times.
//!
//! Against the embedded simulator (a virtual clock) the watch never runs and nothing here
//! changes a verdict.

use std::collections::VecDeque;
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// How often the watch asks to wake.
const TICK: Duration = Duration::from_millis(1);
/// Lateness of a wake-up that is the timer's own (slack, the wake-up path), not the host's
/// load: not counted.
const FLOOR: Duration = Duration::from_micros(500);
/// How long the watch remembers: longer than any one step's wait.
const MEMORY: Duration = Duration::from_secs(120);
/// The least host lateness that excuses a timed-out step, whatever its limit: below it, the
/// wait's own extension covers the host (see [`Deadline`]).
const EXCUSE_MIN: Duration = Duration::from_millis(5);
/// The least a wait moves for the host's lost time, however short its limit (a PRes's 500 µs).
const MIN_ROOM: Duration = Duration::from_millis(50);
/// A stall of the host at least this long, anywhere in an attempt, excuses a device state that
/// came from the bus's cycles meanwhile: the harness sent no cycle for twenty of the fastest
/// (1 ms), longer than the tolerances a case's steps leave (a ramp's ±60 ms) and enough for a
/// watchdog that counts lost cycles. A busy host that only slows the harness down stalls it
/// for a few milliseconds at a time (the scheduler's slices).
pub(crate) const STALL_EXCUSE: Duration = Duration::from_millis(20);
/// Of a limit, the share the host must have lost to excuse a time-out: a device given at least
/// three quarters of its time with the host on time and still silent is late.
const EXCUSE_SHARE: u32 = 4;

/// A late wake-up of the watch: when it woke and how much later than asked, past [`FLOOR`].
#[derive(Debug, Clone, Copy)]
struct Late {
    woke: Instant,
    by: Duration,
}

/// The late wake-ups of the last [`MEMORY`], oldest first.
static WATCH: OnceLock<Mutex<VecDeque<Late>>> = OnceLock::new();

/// Starts the watch (once per process; later calls do nothing). Runs against a DUT on the
/// network start it; the embedded simulator's virtual clock needs none.
pub(crate) fn start_watch() {
    let mut started = false;
    WATCH.get_or_init(|| {
        started = true;
        Mutex::new(VecDeque::new())
    });
    if !started {
        return;
    }
    let spawned = std::thread::Builder::new()
        .name("host-watch".into())
        .spawn(|| {
            let mut asked = Instant::now() + TICK;
            loop {
                std::thread::sleep(asked.saturating_duration_since(Instant::now()));
                let woke = Instant::now();
                let by = woke.saturating_duration_since(asked);
                if by > FLOOR {
                    record(Late {
                        woke,
                        by: by - FLOOR,
                    });
                }
                asked = woke + TICK;
            }
        });
    // Without the thread the host counts as on time: verdicts as without the watch.
    if let Err(e) = spawned {
        eprintln!("warning: host watch not started ({e}): a late host will not be recognised");
    }
}

fn record(late: Late) {
    let Some(w) = WATCH.get() else { return };
    let mut w = w.lock().unwrap_or_else(|e| e.into_inner());
    while w
        .front()
        .is_some_and(|l| late.woke.duration_since(l.woke) > MEMORY)
    {
        w.pop_front();
    }
    w.push_back(late);
}

/// Virtual duration as bus cycles (at least one).
pub(crate) fn cycles_for(d: Duration, cycle: Duration) -> u32 {
    let n = d.as_nanos().div_ceil(cycle.as_nanos().max(1));
    u32::try_from(n).unwrap_or(u32::MAX).max(1)
}

/// Held by the tests that make the host late or need it on time: the watch is one per process.
#[cfg(test)]
pub(crate) static TESTS: Mutex<()> = Mutex::new(());

/// Records that the host held the harness back by `by` just now, as the watch would have seen
/// it: for tests of what the runner makes of a late host, which cannot load the machine on cue.
#[cfg(test)]
pub(crate) fn pretend_host_late(by: Duration) {
    start_watch();
    record(Late {
        woke: Instant::now(),
        by,
    });
}

/// The time the host lost between `from` and `to`: the watch's lateness past its floor, added
/// up over the wake-ups it delayed in that span (zero when the watch does not run).
pub(crate) fn host_lost(from: Instant, to: Instant) -> Duration {
    lates(from, to).into_iter().sum()
}

/// The longest the host held the harness back at once between `from` and `to`: a stall that
/// stopped the bus's cycles for that long (zero when the watch does not run).
pub(crate) fn host_stall(from: Instant, to: Instant) -> Duration {
    lates(from, to).into_iter().max().unwrap_or_default()
}

/// The watch's late wake-ups held back during the span from `from` to `to`.
fn lates(from: Instant, to: Instant) -> Vec<Duration> {
    let Some(w) = WATCH.get() else {
        return Vec::new();
    };
    let w = w.lock().unwrap_or_else(|e| e.into_inner());
    w.iter()
        .rev()
        .take_while(|l| l.woke > from)
        // A wake-up just after `to` was held back during the span.
        .filter(|l| l.woke.checked_sub(l.by).is_some_and(|s| s < to))
        .map(|l| l.by)
        .collect()
}

/// Whether `lost`, the time the host lost while a step waited on a device's `limit`, excuses
/// the device for not answering: the host lost at least a quarter of the limit, and at least
/// [`EXCUSE_MIN`].
pub(crate) fn excuses(lost: Duration, limit: Duration) -> bool {
    lost >= EXCUSE_MIN.max(limit / EXCUSE_SHARE)
}

/// Milliseconds, for messages: `37 ms`, `0.4 ms`.
pub(crate) fn ms(d: Duration) -> String {
    let ms = d.as_secs_f64() * 1000.0;
    if ms >= 10.0 {
        format!("{ms:.0} ms")
    } else {
        format!("{ms:.1} ms")
    }
}

/// One wait for a device: its limit from when the request left, moved by the time the host
/// lost meanwhile (the harness's own scheduling delay, measured as it happens).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Deadline {
    start: Instant,
    limit: Duration,
}

impl Deadline {
    /// A wait of `limit` from now: call it as the request leaves.
    pub(crate) fn after(limit: Duration) -> Deadline {
        Deadline {
            start: Instant::now(),
            limit,
        }
    }

    /// The device's limit.
    pub(crate) fn limit(&self) -> Duration {
        self.limit
    }

    /// Time since the request left.
    pub(crate) fn waited(&self) -> Duration {
        self.start.elapsed()
    }

    /// When the wait ends, as far as is known now: the limit plus the host's lost time so far,
    /// that by the limit again at most (and [`MIN_ROOM`]). A host that loses more is late
    /// whatever the harness waits, and a wait that chased it would stretch without end on a
    /// starved host; the time-out that follows is the host's, and the runner, which measures
    /// it too, runs the case again.
    pub(crate) fn end(&self) -> Instant {
        let room = self.limit.max(MIN_ROOM);
        self.start + self.limit + host_lost(self.start, Instant::now()).min(room)
    }

    /// What is left of the wait (zero once it is over).
    pub(crate) fn remaining(&self) -> Duration {
        self.end().saturating_duration_since(Instant::now())
    }

    /// Whether the wait is over.
    pub(crate) fn passed(&self) -> bool {
        self.remaining().is_zero()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_lateness_excuses_nothing_a_large_share_of_the_limit_does() {
        let ms = Duration::from_millis;
        assert!(!excuses(ms(4), ms(8)), "below the floor");
        assert!(excuses(ms(5), ms(8)));
        assert!(!excuses(ms(100), ms(2000)), "a device given 1.9 s of 2 s");
        assert!(excuses(ms(500), ms(2000)));
    }

    #[test]
    fn a_stalled_host_is_measured_and_moves_the_deadline() {
        let _one = TESTS.lock().unwrap_or_else(|e| e.into_inner());
        start_watch();
        // Let the watch run on time for a while.
        std::thread::sleep(Duration::from_millis(20));
        let d = Deadline::after(Duration::from_millis(20));
        let before = d.end();
        // No thread of this process runs while it is stopped, the watch neither: stop it for
        // 50 ms the way a loaded host holds it back (SIGSTOP, then SIGCONT from a child).
        let pid = std::process::id().to_string();
        let mut stopper = std::process::Command::new("sh")
            .args([
                "-c",
                &format!("kill -STOP {pid}; sleep 0.05; kill -CONT {pid}"),
            ])
            .spawn()
            .expect("sh starts");
        stopper.wait().expect("the child ends");
        // Let the watch record its late wake-up.
        std::thread::sleep(Duration::from_millis(5));
        let lost = host_lost(d.start, Instant::now());
        assert!(lost >= Duration::from_millis(30), "lost {lost:?}");
        assert!(d.end() >= before + Duration::from_millis(30));
        assert!(excuses(lost, d.limit()));
        assert!(
            host_stall(d.start, Instant::now()) >= STALL_EXCUSE,
            "one stall"
        );
        // By no more than the limit again, and 50 ms however short the limit.
        assert!(d.end() <= d.start + d.limit + MIN_ROOM);
    }

    #[test]
    fn lost_time_counts_only_in_its_span() {
        start_watch();
        let later = Instant::now() + Duration::from_secs(3600);
        assert_eq!(host_lost(later, later + TICK), Duration::ZERO);
    }

    #[test]
    fn milliseconds_read_as_people_write_them() {
        assert_eq!(ms(Duration::from_micros(400)), "0.4 ms");
        assert_eq!(ms(Duration::from_millis(37)), "37 ms");
    }
}
