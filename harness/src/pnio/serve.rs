//! `harness serve pnio`: the simulated PROFINET IO device on a network interface.
//!
//! The device (`sim::pnio::IoDevice`, sans-IO) is reached the two ways a PROFINET device is:
//! - raw Ethernet frames of EtherType 8892h ([`crate::net::RawLink`], which opens the
//!   interface promiscuous): DCP (to the device's MAC address — the product's, with the
//!   maker's id the manual shows, not the interface's — or to the Identify multicast
//!   01-0E-CF-00-00-00), the RT frames of its IO CRs and the alarm frames;
//! - UDP port 34964 on the interface's IPv4 address for the context-management RPC calls
//!   (Connect, Control, Release, Read, Write). The device takes the interface's address and
//!   prefix as its IP suite, so what DCP reports is where it answers; an address set later by
//!   DCP changes what the device reports, not the interface (serve it anew on the new
//!   address). Without an IPv4 address only DCP and RT are served, and a line on stderr says
//!   so.
//!
//! One thread of the serve driver ([`crate::net::driver`]) waits on both, frames first
//! ([`RawPort`]): each frame goes to [`IoDevice::frame`], each call to [`IoDevice::call`]
//! (answered at once: a record read does not wait for the next poll), and [`IoDevice::poll`]
//! runs on the grid of [`sim::pnio::POLL_PERIOD`] (the input CR's frames, the watchdog,
//! alarms, the drive model); what they send goes out at once, the device's own RPC calls from
//! its RPC port.
//!
//! Misbehaving on purpose (`--misbehave`, [`crate::net::misbehave`]), `late=` holds the
//! device's RPC answers and DCP responses back while the cyclic frames go on, and `corrupt=`
//! knows the cyclic frames' cycle counter and data status ([`super::faults`]).

use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::sync::Arc;
use std::time::Duration;

use proto::eth::{MacAddr, ETHERTYPE_PROFINET};
use proto::nord::pnio::IpSuite;
use proto::nord::Protocol;
use proto::pnio::RPC_PORT;
use sim::endpoint::{Input, Output};
use sim::pnio::{IoConfig, IoDevice};

use super::faults;
use crate::net::driver::{Options, Serving, Shared};
use crate::net::misbehave::Misbehaviour;
use crate::net::raw_port::RawPort;
use crate::net::serve_args::{RawServeArgs, SystemBusArg};
use crate::net::udp::ipv4_of;
use crate::net::workers::serve_for;
use crate::net::{LinkError, RawLink};

/// How long the raw thread polls the socket after a frame before it sleeps.
const FRAME_POLL: Duration = Duration::from_micros(50);
/// The longest the thread waits without looking at its stop flag.
const STOP_CHECK: Duration = Duration::from_millis(20);

/// What `harness serve pnio` serves.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServeOptions {
    /// The network interface (`--iface`), e.g. one end of a veth pair.
    pub iface: String,
    /// The product profile (`--profile`, default `sk550p`).
    pub profile: String,
    /// The name of station at power-on (`--name`; none: the factory state, no name).
    pub name: String,
    /// Inverters behind the interface (`--inverters`; default the product's maximum).
    pub inverters: Option<u8>,
    /// What the device does wrong on purpose (`--misbehave`; nothing by default): `late=`
    /// holds its RPC answers and DCP responses back.
    pub misbehave: Misbehaviour,
}

impl ServeOptions {
    /// `iface` with the defaults: SK 550P without a name, the product's maximum of inverters,
    /// answers at once.
    pub fn new(iface: &str) -> ServeOptions {
        ServeOptions {
            iface: iface.into(),
            profile: "sk550p".into(),
            name: String::new(),
            inverters: None,
            misbehave: Misbehaviour::default(),
        }
    }
}

/// Why the device cannot be served, or stopped serving.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The profile is unknown, its product has no PROFINET, or the name is not valid.
    #[error("{0}")]
    Profile(String),
    /// The raw Ethernet link failed (no such interface, no root, I/O).
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The UDP socket of the RPC endpoint could not be bound or failed.
    #[error("UDP {addr} (PNIO-CM RPC): {source}")]
    Udp {
        /// The address it was bound (or to be bound) to.
        addr: SocketAddr,
        /// What the system said.
        source: std::io::Error,
    },
    /// A serving thread panicked (a bug).
    #[error("the PROFINET device's thread panicked: {0}")]
    Panicked(String),
    /// The system bus could not be published (`--system-bus`).
    #[error("--system-bus: {0}")]
    SystemBus(crate::net::serve_error::ServeError),
}

pub use crate::net::driver::Counts as Stats;

/// A device served in a thread by [`start`]; dropping it stops it.
#[derive(Debug)]
pub struct Served {
    mac: MacAddr,
    udp: Option<SocketAddr>,
    /// The device, for `--system-bus`.
    device: Arc<Shared<IoDevice>>,
    serving: Serving<ServeError>,
}

impl Served {
    /// The device's MAC address: the product's (the interface is promiscuous), not the
    /// interface's.
    pub fn mac(&self) -> MacAddr {
        self.mac
    }

    /// Where the RPC endpoint is served (`None`: the interface had no IPv4 address).
    pub fn rpc_addr(&self) -> Option<SocketAddr> {
        self.udp
    }

    /// What the thread counted so far.
    pub fn stats(&self) -> Stats {
        self.serving.counts()
    }

    /// Whether the thread still serves.
    pub fn is_running(&self) -> bool {
        self.serving.is_running()
    }

    /// Stops the thread and returns what it counted, or why it had stopped before.
    pub fn stop(mut self) -> Result<Stats, ServeError> {
        self.join()
    }

    fn join(&mut self) -> Result<Stats, ServeError> {
        self.serving.stop(ServeError::Panicked)
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.join();
    }
}

/// The device of `opts`, its IP suite the interface's when it has one.
fn device(opts: &ServeOptions, ip: Option<(Ipv4Addr, u8)>) -> Result<IoDevice, ServeError> {
    let config = crate::net::serve_args::device_config(
        &opts.profile,
        opts.inverters,
        Protocol::Profinet,
        "PROFINET IO",
    )
    .map_err(ServeError::Profile)?;
    let product = config.product;
    let ip = ip.map(|(ip, prefix)| IpSuite {
        ip,
        mask: Ipv4Addr::from(u32::MAX.checked_shl(32 - u32::from(prefix)).unwrap_or(0)),
        gateway: Ipv4Addr::UNSPECIFIED,
    });
    let io = IoConfig {
        name: opts.name.clone(),
        ip,
        ..IoConfig::new(product)
    };
    IoDevice::new(sim::device::Device::new(config), io)
        .map_err(|e| ServeError::Profile(e.to_string()))
}

/// Opens `opts.iface` and serves the device there in a thread of this process, until the
/// returned handle is stopped or dropped.
pub fn start(opts: &ServeOptions) -> Result<Served, ServeError> {
    let mut link = RawLink::open(&opts.iface, Some(ETHERTYPE_PROFINET))?;
    link.set_spin(FRAME_POLL);
    let ip = ipv4_of(&opts.iface);
    let io = device(opts, ip)?;
    let mac = io.mac();
    let mut port = RawPort::new(link);
    let mut udp = None;
    if let Some((ip, _)) = ip {
        let addr = SocketAddr::from((ip, RPC_PORT));
        let socket = UdpSocket::bind(addr).map_err(|source| ServeError::Udp { addr, source })?;
        port = port.with_udp(socket, addr)?;
        udp = Some(addr);
    }
    let mut serving = Serving::new();
    let device = Shared::new(io);
    serving
        .spawn(
            format!("pnio-device-{}", opts.iface),
            device.clone(),
            port,
            Options::new(STOP_CHECK).misbehaving(opts.misbehave, late, faults::corrupt),
        )
        .map_err(|e| ServeError::Panicked(format!("cannot start a thread: {e}")))?;
    Ok(Served {
        mac,
        udp,
        device,
        serving,
    })
}

/// What `late=` holds back: DCP responses and the answers to RPC calls (not the
/// device's own calls, ApplicationReady).
fn late(input: &Input<'_>, out: &Output) -> bool {
    match out {
        Output::Frame(f) => is_dcp(f),
        Output::Datagram { .. } => matches!(input, Input::Datagram { .. }),
        _ => false,
    }
}

/// Whether an Ethernet frame of the device is DCP (its responses).
fn is_dcp(frame: &[u8]) -> bool {
    proto::eth::EthernetFrame::new_checked(frame).is_ok_and(|eth| {
        let p = eth.inner_payload();
        p.len() >= 2
            && matches!(
                proto::pnio::FrameId(u16::from_be_bytes([p[0], p[1]])).kind(),
                proto::pnio::FrameKind::Dcp
            )
    })
}

/// Serves until `duration` has passed (forever when `None`), after a line on stdout that says
/// what is served where.
fn serve(
    opts: &ServeOptions,
    duration: Option<Duration>,
    system_bus: Option<&str>,
) -> Result<(), ServeError> {
    let served = start(opts)?;
    let relay = system_bus
        .map(|addr| crate::can::relay_served(addr, served.device.clone(), IoDevice::device_mut))
        .transpose()
        .map_err(ServeError::SystemBus)?;
    let rpc = match served.rpc_addr() {
        Some(a) => format!(", RPC on {a}"),
        None => String::new(),
    };
    let name = if opts.name.is_empty() {
        "no name of station".to_string()
    } else {
        format!("name of station {:?}", opts.name)
    };
    outln!(
        "serving PROFINET IO device {} ({name}) on {} (MAC {}){rpc}",
        opts.profile,
        opts.iface,
        served.mac()
    );
    crate::can::announce_relay(relay.as_ref());
    crate::net::misbehave::announce(&opts.misbehave);
    if served.rpc_addr().is_none() {
        eprintln!(
            "note: {} has no IPv4 address: serving DCP and RT only; give it an address (the \
             SK 550P's factory one is 192.168.20.200/24) for Connect and the data records",
            opts.iface
        );
    }
    serve_for(duration, STOP_CHECK * 10, || served.is_running());
    let stats = served.stop()?;
    crate::net::misbehave::summarize(&opts.misbehave, stats.misbehaved);
    Ok(())
}

/// `harness serve pnio` arguments.
#[derive(clap::Parser, Debug)]
#[command(
    name = "harness serve pnio",
    about = "Serve the simulator as a PROFINET IO device on a network interface (raw Ethernet: root or CAP_NET_RAW; RPC on UDP 34964 at the interface's IPv4 address)"
)]
struct ServeArgs {
    #[command(flatten)]
    common: RawServeArgs,
    #[command(flatten)]
    system_bus: SystemBusArg,
    /// The name of station at power-on (default: none, as delivered).
    #[arg(long, default_value = "")]
    name: String,
}

/// `harness serve pnio ARGS…`; returns the exit code.
pub(crate) fn command(args: &[String]) -> Result<i32, crate::net::serve_error::ServeError> {
    let a = match crate::args::parse_args::<ServeArgs>("harness serve pnio", args) {
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
        name: a.name,
        inverters: a.common.inverters,
        misbehave,
    };
    let seconds = a.common.seconds.map(Duration::from_secs);
    serve(&opts, seconds, a.system_bus.system_bus.as_deref())
        .map_err(crate::net::serve_error::ServeError::bus)?;
    Ok(crate::exit::EXIT_PASS)
}
