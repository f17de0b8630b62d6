//! One wait for a device on a link's own clock: the embedded simulator's virtual clock, or the
//! real clock of a device on the network.
//!
//! The EtherCAT master and the PROFINET IO controller read no clock but their link's, so the
//! same code runs instantly on the virtual clock and in real time on a network. On the real
//! clock a wait is a [`Deadline`]: the device's limit, moved by the time the host lost
//! meanwhile (`crate::timing`). The virtual clock loses none: there the wait is the limit.

use std::time::{Duration, Instant};

use crate::timing::Deadline;

/// Attempts at a bring-up that timed out while the host was late, as the runner repeats a
/// case (`crate::runner`).
const BRING_UP_ATTEMPTS: usize = 3;

/// How many times its limits a device is given to show that it answers at all, after it let
/// one pass with the host on time: a late device is reached, one silent for all that time is
/// not (the EtherNet/IP connection check's ListIdentity, the second look of [`bring_up`]).
pub(crate) const REACH: u32 = 5;

/// Why a bring-up failed.
#[derive(Debug)]
pub(crate) enum BringUpError<E> {
    /// It failed, and not by answering late.
    Failed(E),
    /// A wait passed its limit with the host on time, and given [`REACH`] times its limits the
    /// device came up: it answers, late. The error is that of the wait that passed.
    Late(E),
}

/// A wait of a device's limit, from when the request left, on a link's clock.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Wait {
    /// When the request left (link clock).
    from: Duration,
    limit: Duration,
    /// The same wait on the real clock, for a link that runs on it.
    real: Option<Deadline>,
}

impl Wait {
    /// A wait of `limit` from `now` (the link's clock: call it as the request leaves); on the
    /// real clock (`real_time`) it moves by the host's lost time.
    pub(crate) fn new(now: Duration, limit: Duration, real_time: bool) -> Wait {
        Wait {
            from: now,
            limit,
            real: real_time.then(|| Deadline::after(limit)),
        }
    }

    /// The device's limit.
    pub(crate) fn limit(&self) -> Duration {
        self.limit
    }

    /// When the wait ends on the link's clock, as far as is known at `now`.
    pub(crate) fn end(&self, now: Duration) -> Duration {
        match self.real {
            // The link's real clock and the deadline's run alike.
            Some(d) => now + d.remaining(),
            None => self.from + self.limit,
        }
    }

    /// Whether the wait is over at `now`.
    pub(crate) fn passed(&self, now: Duration) -> bool {
        now >= self.end(now)
    }

    /// How long the wait has lasted at `now`.
    pub(crate) fn waited(&self, now: Duration) -> Duration {
        now.saturating_sub(self.from)
    }
}

/// Runs `attempt`, a bring-up (opening a device: many waits, none of them a case's step),
/// again while it fails by a wait that passed as the host lost a large part of the device's
/// limit (`crate::timing::excuses`), [`BRING_UP_ATTEMPTS`] times in all; `late` gives such a
/// failure's limit and time waited. `attempt` takes the factor its waits' limits are
/// multiplied by: 1, but [`REACH`] for a second look at a device whose wait passed while the
/// host was on time, which tells a late device ([`BringUpError::Late`]) from an absent one.
pub(crate) fn bring_up<T, E>(
    mut attempt: impl FnMut(u32) -> Result<T, E>,
    late: impl Fn(&E) -> Option<(Duration, Duration)>,
) -> Result<T, BringUpError<E>> {
    let mut last = attempt(1);
    for _ in 1..BRING_UP_ATTEMPTS {
        match &last {
            Err(e) if late(e).is_some_and(|(limit, waited)| host_was_late(limit, waited)) => {
                last = attempt(1);
            }
            _ => break,
        }
    }
    match last {
        Ok(t) => Ok(t),
        Err(e) if late(&e).is_some() => match attempt(REACH) {
            Ok(_) => Err(BringUpError::Late(e)),
            Err(_) => Err(BringUpError::Failed(e)),
        },
        Err(e) => Err(BringUpError::Failed(e)),
    }
}

/// Whether the host lost enough of a wait of `limit` that ended now after `waited` to excuse
/// the device.
fn host_was_late(limit: Duration, waited: Duration) -> bool {
    let now = Instant::now();
    let from = now.checked_sub(waited).unwrap_or(now);
    crate::timing::excuses(crate::timing::host_lost(from, now), limit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_the_virtual_clock_the_wait_is_the_limit() {
        let ms = Duration::from_millis;
        let w = Wait::new(ms(100), ms(50), false);
        assert_eq!(w.end(ms(120)), ms(150));
        assert!(!w.passed(ms(149)));
        assert!(w.passed(ms(150)));
        assert_eq!((w.limit(), w.waited(ms(150))), (ms(50), ms(50)));
    }

    /// A bring-up whose waits pass after `answers_after`, with the host on time.
    fn device(answers_after: Duration) -> impl FnMut(u32) -> Result<u32, (Duration, Duration)> {
        let limit = Duration::from_millis(50);
        let mut tries = 0;
        move |patience| {
            tries += 1;
            if answers_after <= limit * patience {
                Ok(tries)
            } else {
                Err((limit, limit))
            }
        }
    }

    #[test]
    fn a_device_late_with_the_host_on_time_is_told_from_an_absent_one() {
        let ms = Duration::from_millis;
        let late = |e: &(Duration, Duration)| Some(*e);
        // On time: the first attempt.
        assert_eq!(bring_up(device(ms(10)), late).unwrap(), 1);
        // 80 ms against a limit of 50: not again at the same limits (the host was on time),
        // but it comes up given five times them.
        match bring_up(device(ms(80)), late) {
            Err(BringUpError::Late((limit, waited))) => {
                assert_eq!((limit, waited), (ms(50), ms(50)))
            }
            other => panic!("{other:?}"),
        }
        // Silent past five times its limits: absent.
        assert!(matches!(
            bring_up(device(ms(300)), late),
            Err(BringUpError::Failed(_))
        ));
        // A failure that is no wait is not looked at again.
        let mut tries = 0;
        let r: Result<(), _> = bring_up(
            |_| {
                tries += 1;
                Err("refused")
            },
            |_| None,
        );
        assert!(matches!(r, Err(BringUpError::Failed("refused"))));
        assert_eq!(tries, 1);
    }

    #[test]
    fn on_the_real_clock_the_wait_ends_a_limit_after_it_began() {
        let start = std::time::Instant::now();
        let now = || start.elapsed();
        let w = Wait::new(now(), Duration::from_millis(20), true);
        assert!(!w.passed(now()));
        while !w.passed(now()) {
            std::thread::sleep(Duration::from_millis(1));
        }
        assert!(w.waited(now()) >= Duration::from_millis(20));
    }
}
