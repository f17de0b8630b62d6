//! The serve driver's fault injector ([`super::driver::run`]): what a [`Misbehaviour`] does to
//! each output of the device before it leaves, the same for every bus — silence, drops, a
//! corrupted field (the bus's own function, which knows the frame), reordering, duplicates and
//! late answers. Each touched output is one line on stderr (time since the start, the mode, a
//! short summary of the frame) and one count in [`Touched`].

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use sim::endpoint::Output;

use super::misbehave::{Field, Misbehaviour, Pick, Touched};

/// A bus's corruptor: sets `field` wrong in `out` if `out` carries it (through the bus's codec:
/// parse, change, emit), saying what it changed; `None` leaves `out` as it was.
pub(crate) type Corrupt = fn(Field, &mut Output) -> Option<String>;

/// The modes, as counted and logged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    Late,
    Drop,
    Dup,
    Reorder,
    Silent,
    Corrupt,
    Close,
    Alarm,
}

impl Mode {
    fn name(self) -> &'static str {
        match self {
            Mode::Late => "late",
            Mode::Drop => "drop",
            Mode::Dup => "dup",
            Mode::Reorder => "reorder",
            Mode::Silent => "silent",
            Mode::Corrupt => "corrupt",
            Mode::Close => "close",
            Mode::Alarm => "alarm",
        }
    }
}

/// The touched outputs counted by every thread serving one device.
#[derive(Debug, Default)]
pub(crate) struct Tally([AtomicU64; 8]);

impl Tally {
    fn bump(&self, mode: Mode) {
        self.0[mode as usize].fetch_add(1, Ordering::Relaxed);
    }

    /// A session closed on purpose (`close`, which only a bus with sessions does).
    pub(crate) fn closed(&self) {
        self.bump(Mode::Close);
    }

    /// The counts now.
    pub(crate) fn snapshot(&self) -> Touched {
        let get = |m: Mode| self.0[m as usize].load(Ordering::Relaxed);
        Touched {
            late: get(Mode::Late),
            dropped: get(Mode::Drop),
            duplicated: get(Mode::Dup),
            reordered: get(Mode::Reorder),
            silenced: get(Mode::Silent),
            corrupted: get(Mode::Corrupt),
            closed: get(Mode::Close),
            alarms: get(Mode::Alarm),
        }
    }
}

/// One serving thread's injector: the spec, its random numbers and where each mode stands.
#[derive(Debug)]
pub(crate) struct Injector {
    spec: Misbehaviour,
    corrupt: Corrupt,
    rng: fastrand::Rng,
    /// Outputs seen by `drop`, `dup`, `reorder` (for `every:N`).
    seen: [u64; 3],
    start: Instant,
    /// When the silence starts, once known.
    silent_from: Option<Instant>,
    /// An output held back by `reorder` until the next one has left, and when it was due.
    reordered: Option<(Option<Instant>, Output)>,
    /// When the next spurious alarm is due, once the first exchange has set it (`alarm=`).
    alarm_at: Option<Instant>,
}

impl Injector {
    /// `spec` for a device whose clock started at `start`; `corrupt` is its bus's corruptor.
    pub(crate) fn new(spec: Misbehaviour, corrupt: Corrupt, start: Instant) -> Injector {
        Injector {
            silent_from: spec.silent.and_then(|s| s.at).map(|at| start + at),
            rng: fastrand::Rng::with_seed(spec.seed),
            spec,
            corrupt,
            seen: [0; 3],
            start,
            reordered: None,
            alarm_at: None,
        }
    }

    /// Whether anything is to be done at all (a device served as it is skips the rest).
    pub(crate) fn is_active(&self) -> bool {
        !self.spec.is_none()
    }

    /// The device was handed an input now: a silence without a start time starts.
    pub(crate) fn heard(&mut self, now: Instant) {
        if self.spec.silent.is_some() && self.silent_from.is_none() {
            self.silent_from = Some(now);
        }
        if let (Some(a), None) = (self.spec.alarm, self.alarm_at) {
            self.alarm_at = Some(now + a.after);
        }
    }

    /// When the next spurious alarm is due (`None`: none is, or none yet).
    pub(crate) fn next_alarm(&self) -> Option<Instant> {
        self.alarm_at
    }

    /// Whether a spurious alarm is due at `now` (the driver then asks the device to raise one
    /// and tells [`Injector::raised`] what it did).
    pub(crate) fn alarm_due(&self, now: Instant) -> bool {
        self.alarm_at.is_some_and(|at| now >= at)
    }

    /// What the device raised when an alarm was due at `now` (`None`: it had nowhere to raise
    /// one yet, and is asked again a period later): logged and counted; the next one is set
    /// when they repeat.
    pub(crate) fn raised(&mut self, what: Option<&str>, now: Instant, tally: &Tally) {
        let Some(a) = self.spec.alarm else {
            return;
        };
        let Some(what) = what else {
            self.alarm_at = Some(now + a.after);
            return;
        };
        self.alarm_at = a.repeat.then(|| now + a.after);
        tally.bump(Mode::Alarm);
        let t = now.saturating_duration_since(self.start).as_secs_f64();
        eprintln!("misbehave {t:9.3}s {:<7} {what}", Mode::Alarm.name());
    }

    /// What leaves of `out`, made now, each with the time it is due (`None`: at once).
    /// `answer`: the bus holds it back when late.
    pub(crate) fn outgoing(
        &mut self,
        mut out: Output,
        answer: bool,
        now: Instant,
        tally: &Tally,
    ) -> Vec<(Option<Instant>, Output)> {
        if !self.is_active() {
            return vec![(None, out)];
        }
        let start = self.start;
        let touched = |mode: Mode, out: &Output, detail: String| {
            tally.bump(mode);
            let t = now.saturating_duration_since(start).as_secs_f64();
            eprintln!(
                "misbehave {t:9.3}s {:<7} {}{detail}",
                mode.name(),
                summary(out)
            );
        };
        if let (Some(s), Some(from)) = (self.spec.silent, self.silent_from) {
            if now >= from && now < from + s.length {
                touched(Mode::Silent, &out, String::new());
                return Vec::new();
            }
        }
        if let Some(p) = self.spec.drop {
            if self.picks(0, p) {
                touched(Mode::Drop, &out, String::new());
                return Vec::new();
            }
        }
        if let Some(f) = self.spec.corrupt {
            if let Some(what) = (self.corrupt)(f, &mut out) {
                touched(Mode::Corrupt, &out, format!(": {what}"));
            }
        }
        let due = match self.spec.late {
            Some(l) if answer => {
                let spread = (l.max - l.min).as_micros() as u64;
                let delay = l.min + Duration::from_micros(self.rng.u64(0..=spread));
                touched(Mode::Late, &out, format!(" by {} ms", delay.as_millis()));
                Some(now + delay)
            }
            _ => None,
        };
        let mut leave = Vec::with_capacity(3);
        if let Some(p) = self.spec.dup {
            if self.picks(1, p) {
                touched(Mode::Dup, &out, String::new());
                leave.push((due, out.clone()));
            }
        }
        leave.push((due, out));
        if let Some(p) = self.spec.reorder {
            match self.reordered.take() {
                Some(before) => leave.push(before),
                None if self.picks(2, p) => {
                    let (due, out) = leave.pop().expect("one pushed");
                    touched(Mode::Reorder, &out, " after the next".into());
                    self.reordered = Some((due, out));
                }
                None => {}
            }
        }
        leave
    }

    /// Whether the `slot`-th mode, picking `p`, takes the output now before it.
    fn picks(&mut self, slot: usize, p: Pick) -> bool {
        self.seen[slot] += 1;
        match p {
            Pick::All => true,
            Pick::Percent(pc) => self.rng.u8(0..100) < pc,
            Pick::Every(n) => self.seen[slot].is_multiple_of(u64::from(n.get())),
        }
    }
}

/// For a bus's corruptor: hands `change` the payload of `out`, an Ethernet frame, after its
/// header (and VLAN tag); `change` parses it with the bus's codec and returns it emitted anew
/// with a field changed, and what it changed. The new payload replaces the old from its start
/// (the frame's padding stays); one longer than the old leaves `out` as it was.
pub(crate) fn rewrite_payload(
    out: &mut Output,
    change: impl FnOnce(&[u8]) -> Option<(Vec<u8>, String)>,
) -> Option<String> {
    let Output::Frame(bytes) = out else {
        return None;
    };
    let mut eth = proto::eth::EthernetFrame::new_checked(bytes.as_mut_slice()).ok()?;
    let (new, what) = change(eth.inner_payload())?;
    let old = eth.inner_payload_mut();
    old.get_mut(..new.len())?.copy_from_slice(&new);
    Some(what)
}

/// A short summary of an output for the log: its kind, length, and for a frame its EtherType
/// and destination.
fn summary(out: &Output) -> String {
    match out {
        Output::Frame(f) => match proto::eth::EthernetFrame::new_checked(f.as_slice()) {
            Ok(eth) => format!(
                "frame {:04X}h {} B to {}",
                eth.inner_ethertype(),
                f.len(),
                eth.dst()
            ),
            Err(_) => format!("frame {} B", f.len()),
        },
        Output::Datagram { to, bytes, .. } => format!("datagram {} B to {to}", bytes.len()),
        Output::Message { client, bytes } => format!("message {} B to {client:?}", bytes.len()),
        Output::Close(client) => format!("close {client:?}"),
        Output::Can(c) => format!("CAN {c:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(n: u8) -> Vec<Output> {
        (1..=n).map(|i| Output::Frame(vec![i])).collect()
    }

    fn run(
        spec: &str,
        outs: Vec<Output>,
        answer: bool,
    ) -> (Vec<(Option<Instant>, Output)>, Touched) {
        let spec: Misbehaviour = spec.parse().unwrap();
        let tally = Tally::default();
        let start = Instant::now();
        let mut inj = Injector::new(spec, |_, _| None, start);
        inj.heard(start);
        let left = outs
            .into_iter()
            .flat_map(|o| inj.outgoing(o, answer, start, &tally))
            .collect();
        (left, tally.snapshot())
    }

    fn bytes(left: &[(Option<Instant>, Output)]) -> Vec<u8> {
        left.iter()
            .map(|(_, o)| match o {
                Output::Frame(f) => f[0],
                _ => 0,
            })
            .collect()
    }

    #[test]
    fn drop_every_n_drops_the_nth_and_counts_it() {
        let (left, t) = run("drop=every:3", frames(7), false);
        assert_eq!(bytes(&left), [1, 2, 4, 5, 7]);
        assert_eq!(t.dropped, 2);
    }

    #[test]
    fn a_percentage_is_drawn_from_the_seed_and_repeats_with_it() {
        let (a, t) = run("drop=50%", frames(100), false);
        let (b, _) = run("drop=50%", frames(100), false);
        assert_eq!(bytes(&a), bytes(&b));
        assert!((20..=80).contains(&t.dropped), "{t:?}");
    }

    #[test]
    fn dup_and_reorder_change_what_leaves() {
        assert_eq!(
            bytes(&run("dup=every:2", frames(4), false).0),
            [1, 2, 2, 3, 4, 4]
        );
        // Each picked frame waits for the next one.
        assert_eq!(bytes(&run("reorder", frames(4), false).0), [2, 1, 4, 3]);
    }

    #[test]
    fn only_answers_are_late_within_the_range() {
        let spec: Misbehaviour = "late=100ms..300ms".parse().unwrap();
        let tally = Tally::default();
        let start = Instant::now();
        let mut inj = Injector::new(spec, |_, _| None, start);
        let dues: Vec<Duration> = frames(20)
            .into_iter()
            .flat_map(|o| inj.outgoing(o, true, start, &tally))
            .map(|(due, _)| due.expect("held") - start)
            .collect();
        assert_eq!(dues.len(), 20);
        let (lo, hi) = (Duration::from_millis(100), Duration::from_millis(300));
        assert!(dues.iter().all(|d| (lo..=hi).contains(d)), "{dues:?}");
        assert!(dues.iter().any(|d| *d != dues[0]), "jittered: {dues:?}");
        assert_eq!(tally.snapshot().late, 20);
        let (left, t) = run("late=100ms", frames(3), false);
        assert!(left.iter().all(|(d, _)| d.is_none()) && t.late == 0);
    }

    #[test]
    fn silence_starts_at_the_first_input_and_ends_after_its_length() {
        let spec: Misbehaviour = "silent=200ms".parse().unwrap();
        let tally = Tally::default();
        let start = Instant::now();
        let mut inj = Injector::new(spec, |_, _| None, start);
        // Before anything was heard, outputs leave.
        assert_eq!(
            inj.outgoing(Output::Frame(vec![1]), false, start, &tally)
                .len(),
            1
        );
        inj.heard(start + Duration::from_secs(1));
        let at = |ms: u64| start + Duration::from_millis(1000 + ms);
        assert!(inj
            .outgoing(Output::Frame(vec![2]), false, at(0), &tally)
            .is_empty());
        assert!(inj
            .outgoing(Output::Frame(vec![3]), false, at(199), &tally)
            .is_empty());
        assert_eq!(
            inj.outgoing(Output::Frame(vec![4]), false, at(200), &tally)
                .len(),
            1
        );
        assert_eq!(tally.snapshot().silenced, 2);
    }

    #[test]
    fn alarms_fall_due_after_the_first_input_and_repeat_only_with_every() {
        let tally = Tally::default();
        let start = Instant::now();
        let at = |ms: u64| start + Duration::from_millis(ms);
        let mut once = Injector::new("alarm=2s".parse().unwrap(), |_, _| None, start);
        assert!(!once.alarm_due(at(5000)), "nothing heard yet");
        once.heard(at(1000));
        once.heard(at(1500));
        assert_eq!(once.next_alarm(), Some(at(3000)), "from the first input");
        assert!(!once.alarm_due(at(2999)) && once.alarm_due(at(3000)));
        // A device with nowhere to raise it is asked again a period later.
        once.raised(None, at(3000), &tally);
        assert_eq!(once.next_alarm(), Some(at(5000)));
        once.raised(Some("process alarm"), at(5000), &tally);
        assert_eq!(once.next_alarm(), None);
        assert!(!once.alarm_due(at(60_000)));
        let mut every = Injector::new("alarm=every:2s".parse().unwrap(), |_, _| None, start);
        every.heard(at(0));
        every.raised(Some("emergency"), at(2100), &tally);
        assert_eq!(every.next_alarm(), Some(at(4100)));
        assert_eq!(tally.snapshot().alarms, 2);
    }

    #[test]
    fn the_buses_corruptor_changes_what_it_knows_and_is_counted() {
        let spec: Misbehaviour = "corrupt=wkc".parse().unwrap();
        let tally = Tally::default();
        let start = Instant::now();
        let corrupt: Corrupt = |_, o| match o {
            Output::Frame(f) if f[0] == 1 => {
                f[0] = 9;
                Some("first byte 9".into())
            }
            _ => None,
        };
        let mut inj = Injector::new(spec, corrupt, start);
        let left: Vec<_> = frames(2)
            .into_iter()
            .flat_map(|o| inj.outgoing(o, false, start, &tally))
            .collect();
        assert_eq!(bytes(&left), [9, 2]);
        assert_eq!(tally.snapshot().corrupted, 1);
    }
}
