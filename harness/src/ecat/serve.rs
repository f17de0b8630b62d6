//! `harness serve ecat`: the simulated EtherCAT slave on a network interface.
//!
//! The serve driver ([`crate::net::driver`]) runs the sans-IO slave in one thread on the raw
//! Ethernet link ([`crate::net::RawLink`], EtherType 88A4h, BU 0620 §2.2.3; the manual's
//! figure prints 88ABh, an erratum). Each frame that arrives is processed in place, as an
//! EtherCAT slave controller processes a frame on the fly, and sent back out of the same
//! interface: the slave is the last (and only) one on its segment, so its port 0 returns what
//! it processed (ETG.1000.4 §5, "processing and forwarding"). The slave sets the locally
//! administered bit in the source address of what it sends. Between frames the thread waits
//! at most until the slave's next timer (watchdogs) and lets it run with the real clock since
//! start. Misbehaving on purpose (`--misbehave`, [`crate::net::misbehave`]), `late=` holds
//! every processed frame back, the slave serving on meanwhile, and `corrupt=` knows the
//! working counter and the length ([`super::faults`]).

use std::time::Duration;

use super::faults;
use crate::net::driver::{Counts, Options, Serving, Shared};
use crate::net::misbehave::{Misbehaviour, Touched};
use crate::net::raw_port::RawPort;
use crate::net::serve_args::{RawServeArgs, SystemBusArg};
pub use crate::net::LinkError;
use crate::net::RawLink;
use sim::ecat::Slave;
use sim::endpoint::Endpoint;

/// EtherType of EtherCAT frames, 88A4h (the simulator's constant; BU 0620 §2.2.3 figure 3
/// prints 88ABh, an erratum).
pub use sim::ecat::ETHERTYPE;

/// How long the slave's thread polls the socket after a frame before it sleeps: a master that
/// sends frame after frame (mailbox polling, an SDO burst) is served without a thread wake-up.
const FRAME_POLL: Duration = Duration::from_micros(50);

/// The longest the thread sleeps without looking at its stop flag.
const STOP_CHECK: Duration = Duration::from_millis(20);

/// What `harness serve ecat` serves.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServeOptions {
    /// The network interface (`--iface`), e.g. one end of a veth pair.
    pub iface: String,
    /// The product profile (`--profile`, default `sk550p`).
    pub profile: String,
    /// Inverters behind the interface (`--inverters`; default the product's maximum).
    pub inverters: Option<u8>,
    /// What the slave does wrong on purpose (`--misbehave`; nothing by default).
    pub misbehave: Misbehaviour,
}

impl ServeOptions {
    /// `iface` with the defaults: SK 550P, the product's maximum of inverters, frames back at
    /// once.
    pub fn new(iface: &str) -> ServeOptions {
        ServeOptions {
            iface: iface.into(),
            profile: "sk550p".into(),
            inverters: None,
            misbehave: Misbehaviour::default(),
        }
    }
}

/// Why the slave cannot be served, or stopped serving.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The profile is unknown or its product has no EtherCAT interface.
    #[error("{0}")]
    Profile(String),
    /// The raw Ethernet link failed (no such interface, no root, I/O).
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The serving thread panicked (a bug).
    #[error("the EtherCAT slave's thread panicked: {0}")]
    Panicked(String),
    /// `--system-bus`: the socketcand server for the gateway's frames cannot run.
    #[error("--system-bus: {0}")]
    SystemBus(crate::net::serve_error::ServeError),
}

/// What a served slave did, as counted by its thread.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Frames received and sent back.
    pub frames: u64,
    /// Frames received and not sent back (the slave dropped them, or the link was down).
    pub dropped: u64,
    /// Frames skipped because they were longer than a standard Ethernet frame.
    pub oversized: u64,
    /// What `--misbehave` did.
    pub misbehaved: Touched,
}

impl From<Counts> for Stats {
    fn from(c: Counts) -> Stats {
        Stats {
            frames: c.frames_out,
            dropped: c.unanswered + c.lost,
            oversized: c.oversized,
            misbehaved: c.misbehaved,
        }
    }
}

/// A slave served in a thread by [`start`]; dropping it stops the thread.
#[derive(Debug)]
pub struct Served {
    iface: String,
    mac: [u8; 6],
    serving: Serving<ServeError>,
}

impl Served {
    /// The interface it serves on.
    pub fn iface(&self) -> &str {
        &self.iface
    }

    /// The interface's own Ethernet address (frames the slave sends carry the master's source
    /// address with the locally administered bit set instead).
    pub fn mac(&self) -> [u8; 6] {
        self.mac
    }

    /// Whether the thread still serves (it ends on a link error).
    pub fn is_running(&self) -> bool {
        self.serving.is_running()
    }

    /// Stops the thread (within [`STOP_CHECK`]) and returns what it counted, or why it had
    /// stopped before.
    pub fn stop(mut self) -> Result<Stats, ServeError> {
        self.join()
    }

    fn join(&mut self) -> Result<Stats, ServeError> {
        self.serving.stop(ServeError::Panicked).map(Stats::from)
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.join();
    }
}

/// Opens `opts.iface` and serves the simulated slave of `opts.profile` on it in a thread of
/// this process, until the returned handle is stopped or dropped.
pub fn start(opts: &ServeOptions) -> Result<Served, ServeError> {
    let config = device_config(opts)?;
    start_endpoint(&opts.iface, slave(config)?, opts.misbehave)
}

/// Serves until `duration` has passed (forever when `None`), after a line on stdout that says
/// what is served where. With `system_bus` (HOST[:PORT]) a socketcand server there carries the
/// CANopen frames the slave's gateway exchanges with FI 2…8 (`crate::can::relay_served`).
pub(crate) fn serve(
    opts: &ServeOptions,
    duration: Option<Duration>,
    system_bus: Option<&str>,
) -> Result<(), ServeError> {
    let config = device_config(opts)?;
    let shared = Shared::new(slave(config)?);
    let served = start_shared(&opts.iface, shared.clone(), opts.misbehave)?;
    let relay = system_bus
        .map(|addr| crate::can::relay_served(addr, shared, Slave::device_mut))
        .transpose()
        .map_err(ServeError::SystemBus)?;
    let m = served.mac();
    outln!(
        "serving EtherCAT slave ({}, {} inverters) on {} ({:02x}:{:02x}:{:02x}:{:02x}:{:02x}:{:02x})",
        config.product.name(),
        config.inverters,
        opts.iface,
        m[0],
        m[1],
        m[2],
        m[3],
        m[4],
        m[5]
    );
    crate::can::announce_relay(relay.as_ref());
    crate::net::misbehave::announce(&opts.misbehave);
    crate::net::workers::serve_for(duration, STOP_CHECK * 10, || served.is_running());
    let stats = served.stop()?;
    crate::net::misbehave::summarize(&opts.misbehave, stats.misbehaved);
    Ok(())
}

/// `harness serve ecat` arguments.
#[derive(clap::Parser, Debug)]
#[command(
    name = "harness serve ecat",
    about = "Serve the simulator as an EtherCAT slave on a network interface (raw Ethernet: root or CAP_NET_RAW)"
)]
struct ServeArgs {
    #[command(flatten)]
    common: RawServeArgs,
    #[command(flatten)]
    system_bus: SystemBusArg,
}

/// `harness serve ecat ARGS…`; returns the exit code.
pub(crate) fn command(args: &[String]) -> Result<i32, crate::net::serve_error::ServeError> {
    let a = match crate::args::parse_args::<ServeArgs>("harness serve ecat", args) {
        Ok(a) => a,
        Err(code) => return Ok(code),
    };
    let misbehave = match a.common.misbehave.for_bus(&faults::FAULTS) {
        Ok(m) => m,
        Err(code) => return Ok(code),
    };
    let opts = ServeOptions {
        iface: a.common.iface,
        profile: a.common.profile,
        inverters: a.common.inverters,
        misbehave,
    };
    let seconds = a.common.seconds.map(Duration::from_secs);
    serve(&opts, seconds, a.system_bus.system_bus.as_deref())
        .map_err(crate::net::serve_error::ServeError::bus)?;
    Ok(crate::exit::EXIT_PASS)
}

/// The simulated device of `opts`: a product with an EtherCAT interface.
fn device_config(opts: &ServeOptions) -> Result<sim::device::DeviceConfig, ServeError> {
    crate::net::serve_args::device_config(
        &opts.profile,
        opts.inverters,
        proto::nord::Protocol::Ethercat,
        "EtherCAT",
    )
    .map_err(ServeError::Profile)
}

/// The simulated slave of `config`.
fn slave(config: sim::device::DeviceConfig) -> Result<Slave, ServeError> {
    Slave::new(sim::device::Device::new(config)).map_err(|e| ServeError::Profile(e.to_string()))
}

/// Opens the interface and serves `slave` on it in a thread (the serve driver,
/// [`crate::net::driver`]), misbehaving as `misbehave` says.
pub(crate) fn start_endpoint(
    iface: &str,
    slave: impl Endpoint + Send + 'static,
    misbehave: Misbehaviour,
) -> Result<Served, ServeError> {
    start_shared(iface, Shared::new(slave), misbehave)
}

/// [`start_endpoint`] for a slave already shared (with the `--system-bus` relay).
fn start_shared<S: Endpoint + Send + 'static>(
    iface: &str,
    shared: std::sync::Arc<Shared<S>>,
    misbehave: Misbehaviour,
) -> Result<Served, ServeError> {
    let mut link = RawLink::open(iface, Some(ETHERTYPE))?;
    link.set_spin(FRAME_POLL);
    let mac = link.mac().0;
    let mut serving = Serving::new();
    // Every frame the slave sends back is its answer to one that came.
    let opts = Options::new(STOP_CHECK).misbehaving(misbehave, |_, _| true, faults::corrupt);
    serving
        .spawn(
            format!("ecat-slave-{iface}"),
            shared,
            RawPort::new(link),
            opts,
        )
        .map_err(|e| ServeError::Panicked(format!("cannot start a thread: {e}")))?;
    Ok(Served {
        iface: iface.into(),
        mac,
        serving,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::veth::Veth;
    use crate::net::MAX_FRAME;
    use sim::endpoint::{Input, Output};
    use std::sync::atomic::Ordering;
    use std::sync::Arc;
    use std::time::Instant;

    /// A stand-in for the slave: sets the locally administered bit in the source address and
    /// increments the first payload byte; drops frames whose first payload byte is FFh. Its
    /// timer is due every 5 ms and counts how often it ran.
    struct Echo {
        polls: Arc<std::sync::atomic::AtomicU64>,
        next: Duration,
    }

    impl Endpoint for Echo {
        fn input(&mut self, input: Input<'_>, _: Duration) -> Vec<Output> {
            let Input::Frame(frame) = input else {
                return Vec::new();
            };
            if frame[14] == 0xFF {
                return Vec::new();
            }
            let mut frame = frame.to_vec();
            frame[6] |= 0x02;
            frame[14] += 1;
            vec![Output::Frame(frame)]
        }

        fn poll(&mut self, now: Duration) -> Vec<Output> {
            if now >= self.next {
                self.polls.fetch_add(1, Ordering::Relaxed);
                self.next = now + Duration::from_millis(5);
            }
            Vec::new()
        }

        fn next_deadline(&self) -> Option<Duration> {
            Some(self.next)
        }
    }

    fn frame(tag: u8) -> Vec<u8> {
        let mut f = vec![0xFF; 6]; // destination: broadcast
        f.extend_from_slice(&[0x01, 0x01, 0x01, 0x01, 0x01, 0x01]); // source: SOEM's
        f.extend_from_slice(&ETHERTYPE.to_be_bytes()); // EtherType 88A4h
        f.push(tag);
        f.resize(60, 0);
        f
    }

    #[test]
    fn frames_come_back_processed_and_timers_run_between_them() {
        let Some(v) = Veth::new("e") else { return };
        let polls = Arc::new(std::sync::atomic::AtomicU64::new(0));
        let core = Echo {
            polls: polls.clone(),
            next: Duration::ZERO,
        };
        let served = start_endpoint(&v.0, core, Misbehaviour::default()).expect("serve");
        assert!(served.is_running());
        let mut master = RawLink::open(&v.1, Some(ETHERTYPE)).unwrap();
        let mut buf = [0u8; MAX_FRAME];
        for tag in [1u8, 0xFF, 7] {
            master.send(&frame(tag)).unwrap();
        }
        let mut back = Vec::new();
        while let Some(r) = master
            .recv(&mut buf, Instant::now() + Duration::from_millis(300))
            .unwrap()
        {
            assert_eq!(buf[6], 0x03, "locally administered bit set");
            back.push(buf[14]);
            assert_eq!(r.len, 60);
        }
        assert_eq!(back, [2, 8]);
        std::thread::sleep(Duration::from_millis(50));
        let stats = served.stop().expect("stops cleanly");
        assert_eq!((stats.frames, stats.dropped), (2, 1));
        let polls = polls.load(Ordering::Relaxed);
        assert!(polls >= 5, "timers ran {polls} times in >300 ms");
    }

    #[test]
    fn a_vanished_interface_ends_the_thread_with_an_error() {
        let Some(v) = Veth::new("g") else { return };
        let core = Echo {
            polls: Default::default(),
            next: Duration::ZERO,
        };
        let served = start_endpoint(&v.0, core, Misbehaviour::default()).expect("serve");
        drop(v);
        let t = Instant::now();
        while served.is_running() && t.elapsed() < Duration::from_secs(2) {
            std::thread::sleep(Duration::from_millis(10));
        }
        match served.stop() {
            Err(ServeError::Link(LinkError::Io { .. })) => {}
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn an_unknown_interface_is_refused_before_any_thread() {
        let core = Echo {
            polls: Default::default(),
            next: Duration::ZERO,
        };
        match start_endpoint("no-such-if0", core, Misbehaviour::default()) {
            Err(ServeError::Link(LinkError::NoSuchInterface { .. })) => {}
            other => panic!("{other:?}"),
        }
    }
}
