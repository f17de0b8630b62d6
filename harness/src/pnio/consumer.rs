//! The controller as consumer of the input CR: which input frames carry new data, and when
//! the data hold time has run out on frames that carry none.
//!
//! IEC 61158-6-10 (the consumer protocol machine, CPM): a received RT frame is taken only if
//! its cycle counter moved on from the last one taken — (new − last) mod 2¹⁶ in 1…61440 (p-net's
//! `pf_cpm_check_cycle` checks the same window); one that did not is not new and does not
//! reload the data hold timer. When DataHoldFactor cycles pass without a new frame the timer
//! expires: the consumer's time-out, which ends the AR. A provider whose cycle counter stands
//! still is therefore a provider that stopped, however many frames it still sends.
//!
//! Only frames' arrival times are compared (kernel receive stamps, on the link's clock), and
//! only a frame that came without a new counter after the hold time can expire it: a
//! controller held back by its host reads the frames that waited meanwhile, each stamped when
//! it came, so its own delay blames no device; a device that sent nothing for a while is the
//! data hold time's other half, the cycle's own wait ([`super::controller`]'s
//! `exchange_cycle`).

use std::time::Duration;

/// The widest step of the cycle counter that is still new (IEC 61158-6-10, the CPM's cycle
/// counter check): 61440 of 65536, so that a frame left behind on the way is old.
const NEWEST_STEP: u16 = 61440;

/// The input CR's consumer check.
#[derive(Debug, Clone)]
pub(crate) struct Consumer {
    /// The input CR's frame id, for the verdict.
    frame_id: u16,
    /// DataHoldFactor × the cycle.
    data_hold: Duration,
    /// The cycle counter of the last frame taken as new and when it arrived.
    last: Option<(u16, Duration)>,
    /// Frames since then that were not new.
    old: u32,
}

/// The data hold time expired on frames whose cycle counter did not move.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "input CR {frame_id:04X}h: cycle counter stood at {counter} for {frames} frames over {} \
     (data hold time {} expired)",
    crate::timing::ms(*over),
    crate::timing::ms(*data_hold)
)]
pub(crate) struct StoodStill {
    pub(crate) frame_id: u16,
    /// The counter of the last new frame.
    pub(crate) counter: u16,
    /// The frames that came after it with no new counter.
    pub(crate) frames: u32,
    /// From the last new frame to the one that found the time passed.
    pub(crate) over: Duration,
    pub(crate) data_hold: Duration,
}

impl Consumer {
    /// The consumer of input CR `frame_id` with data hold time `data_hold`, before its first
    /// frame.
    pub(crate) fn new(frame_id: u16, data_hold: Duration) -> Consumer {
        Consumer {
            frame_id,
            data_hold,
            last: None,
            old: 0,
        }
    }

    /// Takes a frame with cycle counter `counter` that arrived at `at`: whether it is new
    /// (its data is taken), or the data hold time expired.
    pub(crate) fn take(&mut self, counter: u16, at: Duration) -> Result<bool, StoodStill> {
        let Some((last, since)) = self.last else {
            self.last = Some((counter, at));
            return Ok(true);
        };
        if (1..=NEWEST_STEP).contains(&counter.wrapping_sub(last)) {
            self.last = Some((counter, at));
            self.old = 0;
            return Ok(true);
        }
        self.old += 1;
        let over = at.saturating_sub(since);
        if over > self.data_hold {
            return Err(StoodStill {
                frame_id: self.frame_id,
                counter: last,
                frames: self.old,
                over,
                data_hold: self.data_hold,
            });
        }
        Ok(false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HOLD: Duration = Duration::from_millis(100);

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn a_moving_counter_is_new_every_frame_even_across_the_wrap() {
        let mut c = Consumer::new(0x8000, HOLD);
        // 1 ms cycles: the counter steps 32 (31.25 µs units) and wraps at 65536.
        for (i, counter) in [65472u16, 65504, 0, 32, 64].into_iter().enumerate() {
            assert_eq!(c.take(counter, ms(i as u64)), Ok(true), "{counter}");
        }
    }

    #[test]
    fn a_repeated_or_older_counter_is_not_new() {
        let mut c = Consumer::new(0x8000, HOLD);
        assert_eq!(c.take(320, ms(0)), Ok(true));
        // The same frame again (a duplicate), then one left behind (a reorder).
        assert_eq!(c.take(320, ms(1)), Ok(false));
        assert_eq!(c.take(288, ms(2)), Ok(false));
        // 61440 ahead is still new; 61441 ahead is taken for 4095 behind.
        assert_eq!(c.take(320u16.wrapping_add(61441), ms(3)), Ok(false));
        assert_eq!(c.take(320u16.wrapping_add(61440), ms(4)), Ok(true));
    }

    #[test]
    fn a_counter_standing_still_past_the_data_hold_time_expires_it() {
        let mut c = Consumer::new(0x8001, HOLD);
        assert_eq!(c.take(0, ms(10)), Ok(true));
        for t in 11..=110 {
            assert_eq!(c.take(0, ms(t)), Ok(false), "{t} ms: within the hold time");
        }
        let e = c.take(0, ms(111)).unwrap_err();
        assert_eq!(
            e,
            StoodStill {
                frame_id: 0x8001,
                counter: 0,
                frames: 101,
                over: ms(101),
                data_hold: HOLD,
            }
        );
        assert_eq!(
            e.to_string(),
            "input CR 8001h: cycle counter stood at 0 for 101 frames over 101 ms \
             (data hold time 100 ms expired)"
        );
    }

    #[test]
    fn frames_that_came_late_but_new_never_expire_it() {
        // A host that held the controller (or the device) back: a gap of 500 ms, then new
        // frames. Only arrival times count, and a new counter reloads the timer.
        let mut c = Consumer::new(0x8000, HOLD);
        assert_eq!(c.take(0, ms(0)), Ok(true));
        assert_eq!(c.take(32, ms(500)), Ok(true));
        assert_eq!(c.take(32, ms(501)), Ok(false));
        assert_eq!(c.take(64, ms(502)), Ok(true));
    }
}
