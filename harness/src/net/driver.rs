//! The one serve driver: runs any simulated device ([`sim::endpoint::Endpoint`]) with the real
//! clock since it started, on whatever [`Port`] carries its inputs and outputs — a raw
//! interface with a UDP socket beside it ([`super::raw_port::RawPort`]), a CAN channel, or
//! nothing but the clock for a thread that only runs the device's timers while others feed it
//! (EtherNet/IP's TCP clients, socketcand's).
//!
//! One pass of the loop: the answers held back late (`--misbehave late=…`) whose time has come go out;
//! unless inputs are still queued, the device is polled (it runs what is due,
//! [`Endpoint::poll`]) and what that makes goes out; the port is waited on until the device's next deadline, the next held answer or
//! [`Options::idle`], whichever is first; an input is handed to the device with the time, and
//! what it answers goes out at once, or its delay later when it is an answer the delay holds
//! ([`Options::answers`]). Every output passes the fault injector on its way out
//! ([`super::inject`], `--misbehave`): so every bus served here can drop, duplicate, reorder,
//! delay or hold back in silence what its device sends, and corrupt a field its bus knows. Inputs that queued while the process was held back (a loaded host)
//! reach the device before its timers run: a POWERLINK node descheduled for 100 ms must see
//! the SoCs waiting in its socket before it judges the MN lost, or it blames the MN for its
//! own host ([`DRAIN`]). The device sits behind a mutex ([`Shared`]) so that other threads
//! (other ports, a handle asking its state) reach the same device on the same clock.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use sim::endpoint::{Endpoint, Input, Output};

use super::held::Held;
use super::inject::{Corrupt, Injector, Tally};
use super::misbehave::{Misbehaviour, Touched};
use super::workers::Workers;

/// A device and its clock, shared by the threads that serve it.
#[derive(Debug)]
pub(crate) struct Shared<S> {
    station: Mutex<S>,
    start: Instant,
    /// The latest time handed to the device, in nanoseconds of its clock (written with the
    /// lock held): [`Shared::poll_at`] never hands an earlier one.
    handed: AtomicU64,
}

impl<S: Endpoint> Shared<S> {
    /// `station` on a clock that starts now.
    pub(crate) fn new(station: S) -> Arc<Shared<S>> {
        Shared::since(station, Instant::now())
    }

    /// `station` on a clock that started at `start` (a server whose other parts stamp
    /// frames on the same clock).
    pub(crate) fn since(station: S, start: Instant) -> Arc<Shared<S>> {
        Arc::new(Shared {
            station: Mutex::new(station),
            start,
            handed: AtomicU64::new(0),
        })
    }

    /// When the device's clock started.
    pub(crate) fn start(&self) -> Instant {
        self.start
    }

    /// The device's clock: the real time since the start.
    pub(crate) fn now(&self) -> Duration {
        self.start.elapsed()
    }

    /// The device, and the time to hand it: read with the lock held, so that the device
    /// never sees time go backwards whichever thread reaches it. A thread that panicked
    /// holding the lock left the device as it was: the others go on with it (the panic is
    /// reported when the threads are joined).
    pub(crate) fn lock(&self) -> (MutexGuard<'_, S>, Duration) {
        self.lock_at(self.now())
    }

    /// [`Shared::lock`] with the time `at`, or the latest time the device was handed when that
    /// is later.
    fn lock_at(&self, at: Duration) -> (MutexGuard<'_, S>, Duration) {
        let guard = self.station.lock().unwrap_or_else(|p| p.into_inner());
        let latest = Duration::from_nanos(self.handed.load(Ordering::Relaxed));
        let now = at.max(latest);
        let nanos = u64::try_from(now.as_nanos()).unwrap_or(u64::MAX);
        self.handed.store(nanos, Ordering::Relaxed);
        (guard, now)
    }

    /// Hands `input` to the device now; what it sends.
    pub(crate) fn input(&self, input: Input<'_>) -> Vec<Output> {
        let (mut s, now) = self.lock();
        s.input(input, now)
    }

    /// Lets the device run what is due now; what it sends, and when it wants to be polled
    /// next (its clock).
    pub(crate) fn poll(&self) -> (Vec<Output>, Option<Duration>) {
        self.poll_at(self.now())
    }

    /// Asks the device to raise a spurious alarm now ([`Endpoint::raise_alarm`]).
    pub(crate) fn raise_alarm(&self) -> Option<sim::endpoint::Raised> {
        let (mut s, now) = self.lock();
        s.raise_alarm(now)
    }

    /// [`Shared::poll`] at `at`, a time at which every input that had come was handed over:
    /// what came later is judged after the device's timers.
    fn poll_at(&self, at: Duration) -> (Vec<Output>, Option<Duration>) {
        let (mut s, now) = self.lock_at(at);
        let out = s.poll(now);
        (out, s.next_deadline())
    }
}

/// Where a serving thread's inputs come from and its outputs go.
pub(crate) trait Port {
    /// Why the port cannot go on (the thread ends with it).
    type Error;

    /// The next input, waiting until `deadline` at most (`None`: none came by then). An input
    /// already there is returned even when `deadline` has passed.
    fn recv(&mut self, deadline: Instant) -> Result<Option<Input<'_>>, Self::Error>;

    /// Sends `out`: `Ok(false)` when it was lost without the port failing (a link that is
    /// down, a peer gone, an output this port has no way out for).
    fn send(&mut self, out: &Output) -> Result<bool, Self::Error>;

    /// Frames skipped so far because they did not fit a buffer.
    fn oversized(&self) -> u64 {
        0
    }
}

/// How a serving loop waits and what it holds back.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Options {
    /// The longest wait between two passes: how late the stop flag is seen, and how often a
    /// device without a deadline is polled.
    pub(crate) idle: Duration,
    /// `--misbehave`: what the device does wrong on purpose (nothing by default).
    pub(crate) misbehave: Misbehaviour,
    /// Which outputs the device made of an input are answers that `late=` holds back
    /// (the bus says: an EtherCAT frame, a POWERLINK SDO, a PROFINET DCP response or RPC
    /// answer); what it makes on its own time never is.
    pub(crate) answers: fn(&Input<'_>, &Output) -> bool,
    /// `corrupt=`: the bus's corruptor (none by default: nothing to corrupt).
    pub(crate) corrupt: Corrupt,
}

impl Options {
    /// Waits of at most `idle`, nothing held back.
    pub(crate) fn new(idle: Duration) -> Options {
        Options {
            idle,
            misbehave: Misbehaviour::default(),
            answers: |_, _| false,
            corrupt: |_, _| None,
        }
    }

    /// These options, with the device misbehaving as `misbehave` says: `answers` picks the
    /// outputs `late=` holds back, `corrupt` sets a field wrong.
    pub(crate) fn misbehaving(
        self,
        misbehave: Misbehaviour,
        answers: fn(&Input<'_>, &Output) -> bool,
        corrupt: Corrupt,
    ) -> Options {
        Options {
            misbehave,
            answers,
            corrupt,
            ..self
        }
    }
}

/// What serving threads counted, updated as they go.
#[derive(Debug, Default)]
pub(crate) struct Counters {
    frames_in: AtomicU64,
    frames_out: AtomicU64,
    datagrams_in: AtomicU64,
    datagrams_out: AtomicU64,
    unanswered: AtomicU64,
    lost: AtomicU64,
    oversized: AtomicU64,
    misbehaved: Tally,
}

/// What the threads serving a device counted, at one moment (the POWERLINK node's and the
/// PROFINET device's `Stats`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Frames received (Ethernet or CAN).
    pub frames_in: u64,
    /// Frames sent.
    pub frames_out: u64,
    /// Datagrams received.
    pub datagrams_in: u64,
    /// Datagrams sent.
    pub datagrams_out: u64,
    /// Inputs the device made nothing of.
    pub unanswered: u64,
    /// Outputs lost on the way out (a link down, a peer gone).
    pub lost: u64,
    /// Frames skipped because they were longer than a standard Ethernet frame.
    pub oversized: u64,
    /// What `--misbehave` did to the outputs.
    pub misbehaved: Touched,
}

impl Counters {
    /// Where the fault injector counts what it touched (threads outside [`run`]).
    pub(crate) fn misbehaved(&self) -> &Tally {
        &self.misbehaved
    }

    /// The counts now.
    pub(crate) fn snapshot(&self) -> Counts {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        Counts {
            frames_in: get(&self.frames_in),
            frames_out: get(&self.frames_out),
            datagrams_in: get(&self.datagrams_in),
            datagrams_out: get(&self.datagrams_out),
            unanswered: get(&self.unanswered),
            lost: get(&self.lost),
            oversized: get(&self.oversized),
            misbehaved: self.misbehaved.snapshot(),
        }
    }

    fn input(&self, input: &Input<'_>) {
        match input {
            Input::Frame(_) | Input::Can(_) => bump(&self.frames_in),
            Input::Datagram { .. } => bump(&self.datagrams_in),
            Input::Message { .. } | Input::Closed(_) => {}
        }
    }

    fn sent(&self, out: &Output, sent: bool) {
        match (out, sent) {
            (_, false) => bump(&self.lost),
            (Output::Frame(_) | Output::Can(_), true) => bump(&self.frames_out),
            (Output::Datagram { .. }, true) => bump(&self.datagrams_out),
            (Output::Message { .. } | Output::Close(_), true) => {}
        }
    }
}

fn bump(c: &AtomicU64) {
    c.fetch_add(1, Ordering::Relaxed);
}

/// How many inputs in a row a pass hands over before the device is polled again: enough for
/// what queues in a descheduled moment, few enough that a flood cannot starve the timers.
const DRAIN: u32 = 64;

/// Serves `shared`'s device on `port` until `stop` is set or the port fails (see the module's
/// documentation for one pass).
pub(crate) fn run<S: Endpoint, P: Port>(
    shared: &Shared<S>,
    port: &mut P,
    opts: &Options,
    counters: &Counters,
    stop: &AtomicBool,
) -> Result<(), P::Error> {
    let mut held: Held<Output> = Held::new();
    let mut inject = Injector::new(opts.misbehave, opts.corrupt, shared.start);
    // Inputs handed over since the last poll.
    let mut backlog = 0;
    // When the port was last seen with nothing queued: the device's timers run at that time,
    // not later. A thread held back between seeing the port empty and polling (a loaded host)
    // must not have its device judge the inputs that came meanwhile missing (a POWERLINK node
    // its MN's SoCs).
    let mut empty_at = shared.now();
    let send = |port: &mut P, out: &Output| -> Result<(), P::Error> {
        let sent = port.send(out)?;
        counters.sent(out, sent);
        Ok(())
    };
    // An output on its way out through the injector: now, held, or not at all.
    let leave = |port: &mut P,
                 held: &mut Held<Output>,
                 inject: &mut Injector,
                 out: Output,
                 answer: bool|
     -> Result<(), P::Error> {
        if !inject.is_active() {
            return send(port, &out);
        }
        for (due, out) in inject.outgoing(out, answer, Instant::now(), &counters.misbehaved) {
            match due {
                Some(at) => held.hold(at, out),
                None => send(port, &out)?,
            }
        }
        Ok(())
    };
    while !stop.load(Ordering::Relaxed) {
        while let Some(out) = held.due() {
            send(port, &out)?;
        }
        let now = Instant::now();
        if inject.alarm_due(now) {
            let raised = shared.raise_alarm();
            inject.raised(
                raised.as_ref().map(|r| r.what.as_str()),
                now,
                &counters.misbehaved,
            );
            for out in raised.into_iter().flat_map(|r| r.outputs) {
                leave(port, &mut held, &mut inject, out, false)?;
            }
        }
        // After an input, whatever else is already queued goes first (`until` has passed:
        // the port returns it or nothing at once).
        let mut until = Instant::now();
        if backlog == 0 || backlog >= DRAIN {
            let (outs, next) = if backlog == 0 {
                shared.poll_at(empty_at)
            } else {
                shared.poll()
            };
            backlog = 0;
            for out in outs {
                leave(port, &mut held, &mut inject, out, false)?;
            }
            until += opts.idle;
            if let Some(next) = next {
                until = until.min(shared.start + next);
            }
            if let Some(next) = held.next() {
                until = until.min(next);
            }
            if let Some(next) = inject.next_alarm() {
                until = until.min(next);
            }
        }
        let outs: Vec<(bool, Output)> = {
            let looked = Instant::now().max(until);
            let Some(input) = port.recv(until)? else {
                backlog = 0;
                empty_at = looked.min(Instant::now()) - shared.start;
                counters
                    .oversized
                    .store(port.oversized(), Ordering::Relaxed);
                continue;
            };
            backlog += 1;
            counters.input(&input);
            inject.heard(Instant::now());
            let outs = shared.input(input);
            if outs.is_empty() {
                bump(&counters.unanswered);
            }
            outs.into_iter()
                .map(|o| ((opts.answers)(&input, &o), o))
                .collect()
        };
        counters
            .oversized
            .store(port.oversized(), Ordering::Relaxed);
        for (answer, out) in outs {
            leave(port, &mut held, &mut inject, out, answer)?;
        }
    }
    Ok(())
}

/// A device served by [`spawn`]: its threads and what they count.
#[derive(Debug)]
pub(crate) struct Serving<E> {
    workers: Workers<E>,
    counters: Arc<Counters>,
}

impl<E: Send + 'static> Serving<E> {
    /// No threads yet.
    pub(crate) fn new() -> Serving<E> {
        Serving {
            workers: Workers::new(),
            counters: Arc::default(),
        }
    }

    /// Starts a thread called `name` serving `shared`'s device on `port` ([`run`]); when it
    /// ends, the other threads stop too.
    pub(crate) fn spawn<S, P>(
        &mut self,
        name: String,
        shared: Arc<Shared<S>>,
        mut port: P,
        opts: Options,
    ) -> std::io::Result<()>
    where
        S: Endpoint + Send + 'static,
        P: Port + Send + 'static,
        E: From<P::Error>,
    {
        let stop = self.workers.stop_flag();
        let counters = self.counters.clone();
        self.workers.spawn(name, move || {
            run(&shared, &mut port, &opts, &counters, &stop).map_err(E::from)
        })
    }

    /// What the threads counted so far.
    pub(crate) fn counts(&self) -> Counts {
        self.counters.snapshot()
    }

    /// Whether every thread still serves (they end on a port's error).
    pub(crate) fn is_running(&self) -> bool {
        self.workers.is_running()
    }

    /// Stops the threads and waits for them: what they counted, or the first error one
    /// stopped on (a panic made an `E` by `panicked`).
    pub(crate) fn stop(&mut self, panicked: impl Fn(String) -> E) -> Result<Counts, E> {
        self.workers.join(panicked)?;
        Ok(self.counts())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;

    /// A device that answers each frame with its bytes reversed and, on its own, sends one
    /// frame `[n]` every `period` (its deadline; zero: at every poll).
    struct Mirror {
        next: Duration,
        period: Duration,
        n: u8,
    }

    impl Endpoint for Mirror {
        fn input(&mut self, input: Input<'_>, _: Duration) -> Vec<Output> {
            match input {
                Input::Frame(f) => vec![Output::Frame(f.iter().rev().copied().collect())],
                _ => Vec::new(),
            }
        }

        fn poll(&mut self, now: Duration) -> Vec<Output> {
            if now < self.next {
                return Vec::new();
            }
            self.next = now + self.period;
            // Wrapping: a timer due at every poll runs hundreds of times in the test's 30 ms.
            self.n = self.n.wrapping_add(1);
            vec![Output::Frame(vec![self.n])]
        }

        fn next_deadline(&self) -> Option<Duration> {
            Some(self.next)
        }
    }

    /// A port with frames queued in advance, recording what was sent and when; it sets
    /// `stop` once it has nothing more to give and `after` has passed.
    struct Script {
        inputs: VecDeque<Vec<u8>>,
        current: Vec<u8>,
        sent: Vec<(Instant, Vec<u8>)>,
        after: Instant,
        stop: Arc<AtomicBool>,
    }

    impl Port for Script {
        type Error = std::convert::Infallible;

        fn recv(&mut self, deadline: Instant) -> Result<Option<Input<'_>>, Self::Error> {
            if let Some(f) = self.inputs.pop_front() {
                self.current = f;
                return Ok(Some(Input::Frame(&self.current)));
            }
            if Instant::now() >= self.after {
                self.stop.store(true, Ordering::Relaxed);
            }
            std::thread::sleep(deadline.saturating_duration_since(Instant::now()));
            Ok(None)
        }

        fn send(&mut self, out: &Output) -> Result<bool, Self::Error> {
            let Output::Frame(f) = out else {
                return Ok(false);
            };
            self.sent.push((Instant::now(), f.clone()));
            Ok(true)
        }
    }

    fn serve(delay: Duration) -> (Script, Counts) {
        serve_every(Duration::from_millis(5), delay)
    }

    fn serve_every(period: Duration, delay: Duration) -> (Script, Counts) {
        let stop = Arc::new(AtomicBool::new(false));
        let start = Instant::now();
        let mut port = Script {
            inputs: VecDeque::from([vec![1, 2, 3], vec![4, 5]]),
            current: Vec::new(),
            sent: Vec::new(),
            after: start + Duration::from_millis(30),
            stop: stop.clone(),
        };
        let shared = Shared::since(
            Mirror {
                next: Duration::ZERO,
                period,
                n: 0,
            },
            start,
        );
        let counters = Counters::default();
        let misbehave = if delay.is_zero() {
            Misbehaviour::default()
        } else {
            Misbehaviour::late(delay)
        };
        let opts = Options::new(Duration::from_millis(20)).misbehaving(
            misbehave,
            |i, _| matches!(i, Input::Frame(_)),
            |_, _| None,
        );
        run(&shared, &mut port, &opts, &counters, &stop).unwrap();
        (port, counters.snapshot())
    }

    #[test]
    fn inputs_are_answered_at_once_and_timers_run_between_them() {
        let (port, counts) = serve(Duration::ZERO);
        let frames: Vec<&[u8]> = port.sent.iter().map(|(_, f)| f.as_slice()).collect();
        // The first poll, then both answers before any later poll, then the timer every 5 ms.
        assert_eq!(frames[..3], [&[1u8][..], &[3, 2, 1], &[5, 4]]);
        assert!(frames.len() >= 3 + 4, "{frames:?}");
        assert_eq!(
            (counts.frames_in, counts.unanswered, counts.lost),
            (2, 0, 0)
        );
        assert_eq!(counts.frames_out as usize, frames.len());
    }

    /// A device that only records the times it is polled at.
    struct Stamps(Vec<Duration>);

    impl Endpoint for Stamps {
        fn input(&mut self, _: Input<'_>, _: Duration) -> Vec<Output> {
            Vec::new()
        }
        fn poll(&mut self, now: Duration) -> Vec<Output> {
            self.0.push(now);
            Vec::new()
        }
        fn next_deadline(&self) -> Option<Duration> {
            None
        }
    }

    /// A port that finds nothing at its deadline, then is held back 30 ms before it returns
    /// (a loaded host), once; then it stops the loop.
    struct Stalling {
        looked: Option<Instant>,
        stop: Arc<AtomicBool>,
    }

    impl Port for Stalling {
        type Error = std::convert::Infallible;

        fn recv(&mut self, deadline: Instant) -> Result<Option<Input<'_>>, Self::Error> {
            if self.looked.is_some() {
                self.stop.store(true, Ordering::Relaxed);
                return Ok(None);
            }
            std::thread::sleep(deadline.saturating_duration_since(Instant::now()));
            self.looked = Some(Instant::now());
            std::thread::sleep(Duration::from_millis(30));
            Ok(None)
        }

        fn send(&mut self, _: &Output) -> Result<bool, Self::Error> {
            Ok(true)
        }
    }

    #[test]
    fn timers_run_at_the_time_the_port_was_seen_empty_not_after_a_stall() {
        let stop = Arc::new(AtomicBool::new(false));
        let shared = Shared::new(Stamps(Vec::new()));
        let mut port = Stalling {
            looked: None,
            stop: stop.clone(),
        };
        let opts = Options::new(Duration::from_millis(5));
        run(&shared, &mut port, &opts, &Counters::default(), &stop).unwrap();
        let looked = port.looked.expect("looked") - shared.start;
        let polls = shared.lock().0 .0.clone();
        assert_eq!(polls.len(), 2, "{polls:?}");
        // The second poll is at the look, though it ran 30 ms later.
        assert!(
            polls[1] <= looked + Duration::from_millis(1),
            "{polls:?} {looked:?}"
        );
        assert!(shared.now() >= looked + Duration::from_millis(30));
    }

    #[test]
    fn queued_inputs_reach_the_device_before_its_timers_run_again() {
        // A device whose timer is due at every poll: the two frames already queued are both
        // handed over before the second poll, as frames that queued while a loaded host held
        // the process back must be (a node would otherwise judge its MN lost).
        let (port, _) = serve_every(Duration::ZERO, Duration::ZERO);
        let frames: Vec<&[u8]> = port.sent.iter().map(|(_, f)| f.as_slice()).collect();
        assert_eq!(frames[..4], [&[1u8][..], &[3, 2, 1], &[5, 4], &[2]]);
    }

    #[test]
    fn answers_leave_their_delay_late_while_the_timers_go_on() {
        let delay = Duration::from_millis(15);
        let (port, _) = serve(delay);
        let first = port.sent[0].0;
        let answer = port
            .sent
            .iter()
            .position(|(_, f)| f == &[3, 2, 1])
            .expect("answered");
        assert!(
            answer > 1,
            "timer frames went out meanwhile: {:?}",
            port.sent
        );
        assert!(port.sent[answer].0 - first >= delay);
        let second = port.sent.iter().position(|(_, f)| f == &[5, 4]);
        assert!(second > Some(answer), "in order: {:?}", port.sent);
    }
}
