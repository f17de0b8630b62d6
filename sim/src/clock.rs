//! Time for the device: virtual in tests, real when served.
//!
//! The device never reads a clock itself (sans-IO); its driver reads one of these and passes
//! `now` in. A virtual clock makes the embedded run deterministic and instant: a 2 s ramp
//! takes no wall time, and a silent DUT turns into a timeout verdict without waiting.

use std::cell::Cell;
use std::time::{Duration, Instant};

/// A source of "now", as time since the clock started.
pub trait Clock {
    /// Time since the clock started.
    fn now(&self) -> Duration;
}

/// A clock that only moves when told to.
#[derive(Debug, Default)]
pub struct VirtualClock {
    now: Cell<Duration>,
}

impl VirtualClock {
    /// A clock at zero.
    pub fn new() -> Self {
        Self::default()
    }

    /// Moves the clock forward.
    pub fn advance(&self, by: Duration) {
        self.now.set(self.now.get().saturating_add(by));
    }
}

impl Clock for VirtualClock {
    fn now(&self) -> Duration {
        self.now.get()
    }
}

/// The wall clock, for a device served on a network.
#[derive(Debug)]
pub struct RealClock {
    start: Instant,
}

impl RealClock {
    /// A clock starting now.
    pub fn new() -> Self {
        RealClock {
            start: Instant::now(),
        }
    }
}

impl Default for RealClock {
    fn default() -> Self {
        Self::new()
    }
}

impl Clock for RealClock {
    fn now(&self) -> Duration {
        self.start.elapsed()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn virtual_clock_moves_only_when_advanced() {
        let c = VirtualClock::new();
        assert_eq!(c.now(), Duration::ZERO);
        c.advance(Duration::from_millis(4));
        c.advance(Duration::from_millis(4));
        assert_eq!(c.now(), Duration::from_millis(8));
    }

    #[test]
    fn real_clock_is_monotonic() {
        let c = RealClock::new();
        let a = c.now();
        assert!(c.now() >= a);
    }
}
