//! What a device served late on purpose (`harness serve <bus> --reply-delay MS`) holds back:
//! each answer leaves its delay after the device made it, in order, while the device goes on
//! serving (a served device late on purpose, to test that the harness fails it and does not
//! blame its own host).

use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// Answers held back by a delay.
#[derive(Debug)]
pub(crate) struct Held<T> {
    delay: Duration,
    queue: VecDeque<(Instant, T)>,
}

impl<T> Held<T> {
    /// Holds each answer back by `delay` (none: each leaves at once).
    pub(crate) fn new(delay: Duration) -> Held<T> {
        Held {
            delay,
            queue: VecDeque::new(),
        }
    }

    /// Holds `answer`, made now.
    pub(crate) fn hold(&mut self, answer: T) {
        self.queue.push_back((Instant::now() + self.delay, answer));
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

    #[test]
    fn answers_leave_their_delay_late_in_order() {
        let delay = Duration::from_millis(200);
        let mut h = Held::new(delay);
        let start = Instant::now();
        h.hold(1);
        h.hold(2);
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
        let mut h = Held::new(Duration::ZERO);
        h.hold("a");
        assert_eq!(h.due(), Some("a"));
    }
}
