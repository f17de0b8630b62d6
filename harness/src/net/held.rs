//! What a device served late on purpose (`harness serve <bus> --misbehave late=…`) holds back:
//! each answer leaves when its delay is over, in the order made (a jittered delay never lets a
//! later answer overtake an earlier one), while the device goes on serving (a served device
//! late on purpose, to test that the harness fails it and does not blame its own host).

use std::collections::VecDeque;
use std::time::Instant;

/// Answers held back by a delay.
#[derive(Debug)]
pub(crate) struct Held<T> {
    queue: VecDeque<(Instant, T)>,
}

impl<T> Held<T> {
    /// Nothing held yet.
    pub(crate) fn new() -> Held<T> {
        Held {
            queue: VecDeque::new(),
        }
    }

    /// Holds `answer` until `at`, or until the answer held before it leaves if that is later.
    pub(crate) fn hold(&mut self, at: Instant, answer: T) {
        let at = self.queue.back().map_or(at, |(last, _)| at.max(*last));
        self.queue.push_back((at, answer));
    }

    /// The next answer whose time has come.
    pub(crate) fn due(&mut self) -> Option<T> {
        let (at, _) = self.queue.front()?;
        if *at > Instant::now() {
            return None;
        }
        self.queue.pop_front().map(|(_, a)| a)
    }

    /// When the next answer leaves, if one is held.
    pub(crate) fn next(&self) -> Option<Instant> {
        self.queue.front().map(|(at, _)| *at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn answers_leave_their_delay_late_in_order() {
        let delay = Duration::from_millis(200);
        let mut h = Held::new();
        let start = Instant::now();
        h.hold(Instant::now() + delay, 1);
        h.hold(Instant::now() + delay, 2);
        let held = Instant::now();
        // Nothing leaves before its delay — unless a loaded host held this thread back for
        // most of it, when the check says nothing.
        if held.elapsed() < delay / 2 {
            assert_eq!(h.due(), None);
        }
        // Both are due once the later one's delay has passed (a host that paused this thread
        // between the two holds leaves them further apart than the first one's time).
        std::thread::sleep((held + delay).saturating_duration_since(Instant::now()));
        assert_eq!((h.due(), h.due(), h.due()), (Some(1), Some(2), None));
        assert!(start.elapsed() >= delay);
    }

    #[test]
    fn without_a_delay_an_answer_leaves_at_once() {
        let mut h = Held::new();
        h.hold(Instant::now(), "a");
        assert_eq!(h.due(), Some("a"));
    }

    #[test]
    fn a_shorter_delay_does_not_overtake_a_longer_one_held_before() {
        let mut h = Held::new();
        let now = Instant::now();
        h.hold(now + Duration::from_secs(60), 1);
        h.hold(now, 2);
        assert_eq!(h.due(), None);
        assert_eq!(h.queue[1].0, now + Duration::from_secs(60));
    }
}
