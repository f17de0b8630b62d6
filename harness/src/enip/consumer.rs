//! The scanner as consumer of its connection's class-1 T→O data. Each frame's sequenced
//! address item numbers it (CIP Vol 2, "Sequenced Address Item": a 32-bit sequence number the
//! producer increments per frame); a consumer takes a frame only if its number advanced past
//! the last one taken (modulo 2³²) and discards the others as duplicates or late. A discarded
//! frame is no data, so it does not feed the connection's inactivity watchdog (CIP Vol 1
//! §3-4.4, the connection's timeout: RPI × the timeout multiplier): a producer whose number
//! stands still or goes backwards keeps sending, and the connection times out all the same.
//! The verdict names that: how many frames were discarded and where their number stood.
//!
//! The watchdog runs from the first frame discarded after the last one taken, and moves with
//! the host's lateness ([`Deadline`]): only a device that sends, and sends nothing new, for the
//! connection's timeout is judged; one that sends nothing is the scanner's other time-out.

use std::time::Duration;

use crate::binding::StepError;
use crate::timing::Deadline;

/// What the scanner has taken of a connection's T→O frames.
#[derive(Debug, Default)]
pub(super) struct Consumer {
    /// The sequence number of the last frame taken.
    last: Option<u32>,
    /// Frames discarded since then.
    stale: Option<Stale>,
}

/// Frames discarded since the last one taken.
#[derive(Debug)]
struct Stale {
    /// The connection's timeout, from the first of them.
    since: Deadline,
    /// How many.
    frames: u32,
    /// The last one's sequence number.
    sequence: u32,
}

impl Consumer {
    /// Whether a frame numbered `sequence` is new data, to be taken; otherwise it is counted
    /// as discarded, the connection's `timeout` running.
    pub(super) fn take(&mut self, sequence: u32, timeout: Duration) -> bool {
        // Advanced: ahead by less than half the number space (serial number arithmetic).
        let new = self
            .last
            .is_none_or(|last| (1..1 << 31).contains(&sequence.wrapping_sub(last)));
        if new {
            self.last = Some(sequence);
            self.stale = None;
            return true;
        }
        let stale = self.stale.get_or_insert(Stale {
            since: Deadline::after(timeout),
            frames: 0,
            sequence,
        });
        stale.frames += 1;
        stale.sequence = sequence;
        false
    }

    /// The connection's time-out, once only discarded frames came for its length.
    pub(super) fn check(&self, connection: u32) -> Result<(), StepError> {
        match &self.stale {
            Some(s) if s.since.passed() => Err(StepError::late(
                &s.since,
                format!(
                    "new T→O data of I/O connection {connection:08X}h ({} frames discarded: \
                     their sequence number {} did not advance past {}, CIP Vol 2)",
                    s.frames,
                    s.sequence,
                    self.last.unwrap_or_default()
                ),
            )),
            _ => Ok(()),
        }
    }

    /// How many frames were discarded since the last one taken, for the transcript.
    pub(super) fn discarded(&self) -> u32 {
        self.stale.as_ref().map_or(0, |s| s.frames)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LONG: Duration = Duration::from_secs(60);

    #[test]
    fn numbers_that_advance_are_taken_across_the_wrap() {
        let mut c = Consumer::default();
        for s in [u32::MAX - 1, u32::MAX, 0, 1, 5] {
            assert!(c.take(s, LONG), "{s}");
        }
        assert_eq!(c.discarded(), 0);
        assert!(c.check(1).is_ok());
    }

    #[test]
    fn a_number_standing_or_going_back_is_discarded() {
        let mut c = Consumer::default();
        assert!(c.take(7, LONG));
        assert!(!c.take(7, LONG), "standing");
        assert!(!c.take(6, LONG), "back");
        assert!(
            !c.take(7u32.wrapping_add(1 << 31), LONG),
            "half the space away"
        );
        assert_eq!(c.discarded(), 3);
        assert!(c.check(1).is_ok(), "the timeout has not passed");
        // A new one ends the run of discarded frames.
        assert!(c.take(8, LONG));
        assert_eq!(c.discarded(), 0);
    }

    #[test]
    fn only_discarded_frames_for_the_timeout_is_the_connections_time_out() {
        let mut c = Consumer::default();
        assert!(c.take(1, Duration::ZERO));
        assert!(!c.take(1, Duration::ZERO));
        assert!(!c.take(1, Duration::ZERO));
        let e = c.check(0x1234_5678).unwrap_err();
        assert!(matches!(e, StepError::Late { .. }), "{e}");
        assert!(
            e.to_string().starts_with(
                "new T→O data of I/O connection 12345678h (2 frames discarded: their sequence \
                 number 1 did not advance past 1, CIP Vol 2): no answer within the device's \
                 limit of 0.0 ms"
            ),
            "{e}"
        );
    }
}
