//! The link under the master: a [`Segment`] sends one Ethernet frame and hands back the frames
//! that return, by a deadline on the segment's own clock.
//!
//! Two segments exist: [`EmbeddedSegment`], the simulated slave (`sim::ecat::Slave`) processing
//! each frame in place on a virtual clock (instant, deterministic: a timeout costs no wall
//! time), and [`NetSegment`], a raw Ethernet link on a network interface (EtherType 88A4h,
//! ETG.1000.4 §5.3; BU 0620 §2.2.3's figure prints 88ABh, an erratum) on the real clock.
//! [`Faulty`] wraps either and makes it silent, looping (every frame comes back unprocessed)
//! or garbage-returning, so the master's handling of a broken segment can be tested.
//!
//! Time is always the segment's: [`Segment::now`] since it was opened. The master never reads
//! another clock, so the same master code runs on both.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use sim::clock::{Clock, VirtualClock};
use sim::ecat::Slave;

use crate::net::{LinkError, RawLink};

/// EtherType of EtherCAT (ETG.1000.4 §5.3; BU 0620 §2.2.3 figure 3 prints 88ABh, an erratum).
const ETHERTYPE: u16 = 0x88A4;

/// A frame that came back into the caller's buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Arrival {
    /// Its length in the buffer (Ethernet header included).
    pub(crate) len: usize,
    /// When the kernel received it (real-time clock since the Unix epoch, for jitter figures:
    /// compare stamps with each other only); `None` on the embedded segment or without a stamp.
    pub(crate) stamp: Option<Duration>,
}

/// The segment itself failed: the link could not send or receive. Never a statement about the
/// slaves.
#[derive(Debug, thiserror::Error)]
pub(crate) enum SegmentError {
    /// The raw Ethernet link failed.
    #[error(transparent)]
    Link(#[from] LinkError),
}

/// An EtherCAT segment as the master sees it: frames out, frames back, a clock.
pub(crate) trait Segment {
    /// Time since the segment was opened (virtual on the embedded segment).
    fn now(&self) -> Duration;

    /// Whether [`Segment::now`] is the real clock, on which the host's own delays move a wait
    /// for the slave (`crate::net::wait`); the virtual clock has none.
    fn real_time(&self) -> bool;

    /// Sends one Ethernet II frame (header first, no frame check sequence) as it is.
    fn send(&mut self, frame: &[u8]) -> Result<(), SegmentError>;

    /// Receives the next frame that came back into `buf`, waiting until `deadline` (on
    /// [`Segment::now`]'s clock) at most; `Ok(None)` when none came by then. A frame already
    /// there is returned even after the deadline. Frames longer than `buf` are skipped.
    fn recv(&mut self, buf: &mut [u8], deadline: Duration)
        -> Result<Option<Arrival>, SegmentError>;

    /// Lets time pass until `until` without traffic (the embedded segment runs the slave's
    /// timers; the network segment sleeps).
    fn wait_until(&mut self, until: Duration);
}

impl<S: Segment + ?Sized> Segment for Box<S> {
    fn now(&self) -> Duration {
        (**self).now()
    }
    fn real_time(&self) -> bool {
        (**self).real_time()
    }
    fn send(&mut self, frame: &[u8]) -> Result<(), SegmentError> {
        (**self).send(frame)
    }
    fn recv(
        &mut self,
        buf: &mut [u8],
        deadline: Duration,
    ) -> Result<Option<Arrival>, SegmentError> {
        (**self).recv(buf, deadline)
    }
    fn wait_until(&mut self, until: Duration) {
        (**self).wait_until(until)
    }
}

/// Virtual time one frame takes through the embedded segment (wire, slave, wire): roughly what
/// a short frame takes through one ESC on 100 Mbit/s and back.
pub(crate) const EMBEDDED_ROUND_TRIP: Duration = Duration::from_micros(10);

/// The simulated slave as a segment of its own, on a virtual clock: each frame is processed in
/// place by [`Slave::process`] at the moment it is sent and comes back at once; waiting moves
/// the clock and runs the slave's timers ([`Slave::poll`]) when they are due.
#[derive(Debug)]
pub(crate) struct EmbeddedSegment {
    slave: Slave,
    clock: VirtualClock,
    /// Frames the slave sent back, not yet received.
    returned: VecDeque<Vec<u8>>,
    /// When the slave wants its timers run next.
    wake: Option<Duration>,
}

impl EmbeddedSegment {
    /// A segment with `slave` alone on it, the clock at zero.
    pub(crate) fn new(mut slave: Slave) -> EmbeddedSegment {
        let clock = VirtualClock::new();
        let wake = slave.poll(clock.now());
        EmbeddedSegment {
            slave,
            clock,
            returned: VecDeque::new(),
            wake,
        }
    }

    /// The slave, for observation.
    #[cfg(test)]
    pub(crate) fn slave(&self) -> &Slave {
        &self.slave
    }

    /// The slave, for fault injection (its device) and observation.
    pub(crate) fn slave_mut(&mut self) -> &mut Slave {
        &mut self.slave
    }

    /// Moves the clock to `t` (never back), running the slave's timers on the way.
    fn advance_to(&mut self, t: Duration) {
        while let Some(w) = self.wake.filter(|w| *w <= t) {
            let now = self.clock.now();
            if w > now {
                self.clock.advance(w - now);
            }
            self.run_timers();
        }
        let now = self.clock.now();
        if t > now {
            self.clock.advance(t - now);
        }
    }

    /// Runs the slave's timers now and notes when it wants them run next. A timer that asks to
    /// run again at once is run again a microsecond later, so waiting always ends.
    fn run_timers(&mut self) {
        let now = self.clock.now();
        self.wake = self
            .slave
            .poll(now)
            .map(|n| n.max(now + Duration::from_micros(1)));
    }
}

/// The first frame of `queue` that fits `buf`, copied into it (longer ones are skipped, as
/// [`Segment::recv`] says).
fn take_queued(queue: &mut VecDeque<Vec<u8>>, buf: &mut [u8]) -> Option<Arrival> {
    while let Some(f) = queue.pop_front() {
        if f.len() <= buf.len() {
            buf[..f.len()].copy_from_slice(&f);
            return Some(Arrival {
                len: f.len(),
                stamp: None,
            });
        }
    }
    None
}

impl Segment for EmbeddedSegment {
    fn now(&self) -> Duration {
        self.clock.now()
    }

    fn real_time(&self) -> bool {
        false
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), SegmentError> {
        let t = self.clock.now() + EMBEDDED_ROUND_TRIP / 2;
        self.advance_to(t);
        let mut f = frame.to_vec();
        if self.slave.process(&mut f, self.clock.now()).send_back() {
            self.returned.push_back(f);
        }
        // Processing may have started timers (a state change, the SM watchdog).
        self.run_timers();
        self.advance_to(t + EMBEDDED_ROUND_TRIP / 2);
        Ok(())
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        deadline: Duration,
    ) -> Result<Option<Arrival>, SegmentError> {
        if let Some(a) = take_queued(&mut self.returned, buf) {
            return Ok(Some(a));
        }
        self.advance_to(deadline);
        Ok(None)
    }

    fn wait_until(&mut self, until: Duration) {
        self.advance_to(until);
    }
}

/// A real segment behind a network interface, through the raw Ethernet link of
/// [`crate::net`] (EtherType 88A4h only), on the real clock.
#[derive(Debug)]
pub(crate) struct NetSegment {
    link: RawLink,
    start: Instant,
}

impl NetSegment {
    /// Opens interface `iface` for EtherCAT frames (needs root or `CAP_NET_RAW`).
    pub(crate) fn open(iface: &str) -> Result<NetSegment, SegmentError> {
        let mut link = RawLink::open(iface, Some(ETHERTYPE))?;
        link.set_spin(REPLY_POLL);
        Ok(NetSegment::over(link))
    }

    /// A segment over a link already open (it should filter EtherType 88A4h).
    pub(crate) fn over(link: RawLink) -> NetSegment {
        NetSegment {
            link,
            start: Instant::now(),
        }
    }
}

impl Segment for NetSegment {
    fn now(&self) -> Duration {
        self.start.elapsed()
    }

    fn real_time(&self) -> bool {
        true
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), SegmentError> {
        Ok(self.link.send(frame)?)
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        deadline: Duration,
    ) -> Result<Option<Arrival>, SegmentError> {
        let got = self.link.recv(buf, self.start + deadline)?;
        Ok(got.map(|r| Arrival {
            len: r.len,
            stamp: r.stamp,
        }))
    }

    /// Sleeps until shortly before `until`, then watches the clock for the rest: a thread's
    /// wake-up comes tens of microseconds late, which would move every process data cycle.
    /// It watches without yielding the processor: a thread that yields to a busy process on
    /// its core (a compiler, say) gets it back only after that process's time slice, a tick
    /// of up to 4 ms later, and the cycle is sent that late (seen in the EtherCAT bench under
    /// load: p99 of the send delay 4 ms with `yield_now`).
    fn wait_until(&mut self, until: Duration) {
        let now = self.now();
        if until > now + SPIN {
            std::thread::sleep(until - now - SPIN);
        }
        while self.now() < until {
            std::hint::spin_loop();
        }
    }
}

/// How long [`NetSegment::open`]'s link polls for a returning frame before it sleeps: a slave
/// segment returns a frame within tens of microseconds, so the reply is seen without a thread
/// wake-up (see `crate::poll`), at the cost of the processor while it polls.
const REPLY_POLL: Duration = crate::poll::REPLY_POLL;

/// How long before a deadline [`NetSegment::wait_until`] stops sleeping and watches the clock.
const SPIN: Duration = Duration::from_micros(300);

/// What a [`Faulty`] segment does to the frames sent.
#[cfg(test)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Fault {
    /// Nothing: frames go to the segment underneath.
    #[default]
    None,
    /// Frames vanish; nothing ever comes back (a cut cable, a dead slave).
    Silent,
    /// Every frame comes back as it was sent, unprocessed (a looped cable, a segment without
    /// slaves whose last port is closed on itself).
    Loop,
    /// Frames come back as garbage: EtherCAT frames whose header lies about their length and
    /// whose datagram bytes are scrambled.
    Garbage,
}

/// A segment with a fault injected between the master and the segment underneath.
#[cfg(test)]
#[derive(Debug)]
pub(crate) struct Faulty<S> {
    inner: S,
    fault: Fault,
    back: VecDeque<Vec<u8>>,
}

#[cfg(test)]
impl<S: Segment> Faulty<S> {
    /// `inner` without a fault yet.
    pub(crate) fn new(inner: S) -> Faulty<S> {
        Faulty {
            inner,
            fault: Fault::None,
            back: VecDeque::new(),
        }
    }

    /// Injects `fault` from the next frame on.
    pub(crate) fn set_fault(&mut self, fault: Fault) {
        self.fault = fault;
    }

    /// Makes `frame` arrive before anything else, as if the segment had returned it (a stale
    /// duplicate, another master's frame).
    pub(crate) fn inject(&mut self, frame: Vec<u8>) {
        self.back.push_back(frame);
    }

    /// The segment underneath.
    pub(crate) fn inner(&self) -> &S {
        &self.inner
    }

    /// The segment underneath, mutable.
    pub(crate) fn inner_mut(&mut self) -> &mut S {
        &mut self.inner
    }
}

/// `frame` broken as [`Fault::Garbage`] breaks it: the EtherCAT length field claims 7FFh bytes
/// and every byte after the EtherCAT header is scrambled.
#[cfg(test)]
fn garbage(frame: &[u8]) -> Vec<u8> {
    let mut f = frame.to_vec();
    if f.len() >= 16 {
        f[12..14].copy_from_slice(&ETHERTYPE.to_be_bytes());
        f[14] = 0xFF;
        f[15] = 0x17;
        for (i, b) in f[16..].iter_mut().enumerate() {
            *b ^= 0xA5 ^ (i as u8);
        }
    }
    f
}

#[cfg(test)]
impl<S: Segment> Segment for Faulty<S> {
    fn now(&self) -> Duration {
        self.inner.now()
    }

    fn real_time(&self) -> bool {
        self.inner.real_time()
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), SegmentError> {
        match self.fault {
            Fault::None => self.inner.send(frame),
            Fault::Silent => Ok(()),
            Fault::Loop => {
                self.back.push_back(frame.to_vec());
                Ok(())
            }
            Fault::Garbage => {
                self.back.push_back(garbage(frame));
                Ok(())
            }
        }
    }

    fn recv(
        &mut self,
        buf: &mut [u8],
        deadline: Duration,
    ) -> Result<Option<Arrival>, SegmentError> {
        match take_queued(&mut self.back, buf) {
            Some(a) => Ok(Some(a)),
            None => self.inner.recv(buf, deadline),
        }
    }

    fn wait_until(&mut self, until: Duration) {
        self.inner.wait_until(until)
    }
}
