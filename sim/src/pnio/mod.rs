//! The PROFINET IO device of the SK 550P (BU 0620 §2.5) and the SK TU3-PNT (BU 0590), sans-IO:
//! DCP, the context management over RPC, the cyclic RT data, the data records and the alarms
//! around one [`Device`].
//!
//! - [`station`]: the name of station and IP suite, and the DCP services on them;
//! - [`ar`]: the application relation: Connect (the expected modules against the product's
//!   slots), PrmEnd, ApplicationReady, Release, record read/write; the DeviceAccess AR;
//! - [`cyclic`]: the IO CRs' layout, the RT frames both ways, the watchdog;
//! - [`alarms`]: diagnosis alarms over the alarm CR and their acknowledgement;
//! - [`records`]: the parameter channel in data records 47 and 100…108.
//!
//! The device is driven by what arrives ([`IoDevice::frame`], [`IoDevice::datagram`]) and by
//! time ([`IoDevice::poll`], every [`POLL_PERIOD`]); it answers with [`Out`]s.

mod alarms;
mod ar;
mod cyclic;
mod endpoint;
mod im0;
pub mod records;
mod station;
#[cfg(test)]
mod tests;

use std::net::{SocketAddr, SocketAddrV4};
use std::time::Duration;

use proto::eth::{EthernetFrame, EthernetRepr, MacAddr, ETHERTYPE_PROFINET};
use proto::nord::led::Row;
use proto::nord::pnio::{self as def, IpSuite, LedState};
use proto::nord::{Product, Protocol};
use proto::pnio::{FrameId, FrameKind, RPC_PORT};

use crate::device::Device;
use ar::{Access, Ar};
use records::Records;
use station::Station;

/// How often the device wants [`IoDevice::poll`]: its send clock of 1 ms (SendClockFactor 32,
/// the cycle the issue asks for), the finest an input CR is sent at.
pub const POLL_PERIOD: Duration = Duration::from_millis(1);

/// What the device sends.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Out {
    /// An Ethernet frame, as it goes on the wire.
    Frame(Vec<u8>),
    /// A UDP datagram from the device's RPC port to `to`.
    Datagram {
        /// Where it goes.
        to: SocketAddr,
        /// The RPC PDU.
        bytes: Vec<u8>,
    },
}

/// How the device is set up beyond its [`Device`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IoConfig {
    /// The device's MAC address.
    pub mac: MacAddr,
    /// Its name of station at power-on (empty: none assigned yet).
    pub name: String,
    /// Its IP suite at power-on (`None`: the product's factory suite).
    pub ip: Option<IpSuite>,
}

impl IoConfig {
    /// The factory state of `product`: no name, the factory IP suite, a MAC address with the
    /// maker's id the manual shows — SK 550P F0:5F:5A (BU 0620 §4.4.3 P878), SK TU3-PNT the
    /// example of BU 0590 §5.1.4 P181, 00:0E:CF:03:60:00.
    pub fn new(product: Product) -> IoConfig {
        let mac = match product {
            Product::Sk550p => MacAddr([0xF0, 0x5F, 0x5A, 0x00, 0x05, 0x50]),
            _ => MacAddr([0x00, 0x0E, 0xCF, 0x03, 0x60, 0x00]),
        };
        IoConfig {
            mac,
            name: String::new(),
            ip: None,
        }
    }
}

/// A device that cannot be a PROFINET IO device.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IoError {
    /// The product has no PROFINET interface.
    #[error("{0} has no PROFINET IO interface")]
    NoProfinet(&'static str),
    /// The name given is no valid name of station.
    #[error("name of station {0:?}: {1}")]
    Name(String, String),
}

/// A PROFINET IO device (sans-IO).
#[derive(Debug)]
pub struct IoDevice {
    device: Device,
    product: Product,
    mac: MacAddr,
    station: Station,
    ar: Option<Ar>,
    /// The DeviceAccess AR of an engineering tool, beside the IO AR.
    access: Option<Access>,
    records: Records,
    /// The last AR ended by its watchdog (the controller was lost) and none came since.
    lost: bool,
    /// DCP Signal: the LED flashes until then.
    signal_until: Option<Duration>,
    /// The P700 values last seen, for the alarms.
    faults: [i32; 8],
    /// The alarm number of each inverter's incoming alarm not yet outgoing (0: none).
    raised: [u16; 8],
    /// Inverters lost from the system bus ([`IoDevice::lose_inverter`]).
    lost_fis: [bool; 8],
    /// The alarm number the SK TU3-PNT's test alarm P163 [-04] raised (0: none).
    test_alarm: u16,
    /// Frames and datagrams the device could not parse or that were not for it.
    dropped: u64,
    /// The activity of the device's own RPC calls (ApplicationReady).
    calls: u32,
    /// When the next LLDP frame goes out.
    next_lldp: Duration,
    /// When the device wants [`IoDevice::poll`] next as an endpoint: on a grid of
    /// [`POLL_PERIOD`].
    next_poll: Duration,
}

/// LLDP: a frame every 5 s (IEC 61158-6-10 for PROFINET devices), valid for 4 intervals.
const LLDP_INTERVAL: Duration = Duration::from_secs(5);
const LLDP_TTL_S: u16 = 20;

impl IoDevice {
    /// The IO device of `device`, powered on at time zero.
    pub fn new(device: Device, config: IoConfig) -> Result<IoDevice, IoError> {
        let product = device.config().product;
        if !product.protocols().contains(&Protocol::Profinet) {
            return Err(IoError::NoProfinet(product.name()));
        }
        let factory = config.ip.is_none();
        let ip = match config.ip {
            Some(ip) => ip,
            None => def::factory_ip(product).ok_or(IoError::NoProfinet(product.name()))?,
        };
        if !config.name.is_empty() {
            def::check_station_name(&config.name)
                .map_err(|e| IoError::Name(config.name.clone(), e.to_string()))?;
        }
        let mut io = IoDevice {
            device,
            product,
            mac: config.mac,
            station: Station::new(config.name, ip),
            ar: None,
            access: None,
            records: Records::default(),
            lost: false,
            signal_until: None,
            faults: [0; 8],
            raised: [0; 8],
            lost_fis: [false; 8],
            test_alarm: 0,
            dropped: 0,
            calls: 0,
            next_lldp: LLDP_INTERVAL,
            next_poll: Duration::ZERO,
        };
        if factory {
            // The IP parameters hold the factory suite DCP reports (BU 0620 §4.2.4, BU 0590
            // §5.1.2).
            io.station.keep(&mut io.device, product);
        }
        io.station.show(&mut io.device, product);
        io.show_identity();
        io.device.tick(Duration::ZERO);
        Ok(io)
    }

    /// The device's MAC address.
    pub fn mac(&self) -> MacAddr {
        self.mac
    }

    /// Its name of station.
    pub fn name(&self) -> &str {
        &self.station.name
    }

    /// Its IP suite in use.
    pub fn ip(&self) -> IpSuite {
        self.station.ip
    }

    /// Its RPC endpoint (UDP 34964 on its IP address).
    pub fn rpc_addr(&self) -> SocketAddr {
        SocketAddr::V4(SocketAddrV4::new(self.station.ip.ip, RPC_PORT))
    }

    /// Whether an application relation is up (ApplicationReady confirmed).
    pub fn in_data_exchange(&self) -> bool {
        self.ar.as_ref().is_some_and(Ar::running)
    }

    /// Frames and datagrams dropped.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// The simulated device.
    pub fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// The two PROFINET LEDs at `now` (SK 550P "BF" and "RUN", SK TU3-PNT "RUN" and "ERR",
    /// [`def::status_leds`]); a DCP Signal makes RUN flash.
    pub fn leds(&self, now: Duration) -> [(&'static str, Row); 2] {
        let state = match &self.ar {
            Some(ar) if ar.running() => LedState::ArEstablished,
            _ => LedState::WaitingForAr,
        };
        let alarm = self.raised.iter().any(|a| *a != 0) || self.lost_fis.iter().any(|l| *l);
        let mut leds = def::status_leds(self.product, state, alarm, self.lost)
            .unwrap_or([("run", proto::nord::led::PROFINET_RUN[0]); 2]);
        if self.signal_until.is_some_and(|t| now < t) {
            if let Some(run) = leds.iter_mut().find(|(n, _)| *n == "run") {
                run.1 = proto::nord::led::PROFINET_RUN[1];
            }
        }
        leds
    }

    /// Handles one whole Ethernet frame received at `now`; returns what to send.
    pub fn frame(&mut self, frame: &[u8], now: Duration) -> Vec<Out> {
        let mut out = self.timers(now);
        let Ok(eth) = EthernetFrame::new_checked(frame) else {
            self.dropped += 1;
            return out;
        };
        if eth.inner_ethertype() != ETHERTYPE_PROFINET {
            return out;
        }
        let dst = eth.dst();
        if dst != self.mac && !dst.is_multicast() {
            return out;
        }
        let src = eth.src();
        let payload = eth.inner_payload();
        let Some(id) = payload
            .get(..2)
            .map(|b| FrameId(u16::from_be_bytes([b[0], b[1]])))
        else {
            self.dropped += 1;
            return out;
        };
        let answers = match id.kind() {
            FrameKind::Dcp => self.dcp(src, dst, payload, now),
            FrameKind::Rt => self.rt(id, payload, now),
            FrameKind::Alarm { .. } => self.alarm_frame(payload, now),
            FrameKind::Other => {
                self.dropped += 1;
                Vec::new()
            }
        };
        out.extend(answers);
        out
    }

    /// Handles one UDP datagram to the RPC port from `from` at `now`; returns what to send.
    pub fn datagram(&mut self, from: SocketAddr, datagram: &[u8], now: Duration) -> Vec<Out> {
        let mut out = self.timers(now);
        out.extend(self.call(from, datagram, now));
        out
    }

    /// Handles one RPC datagram without running the timers: for a host whose other thread
    /// polls the device on its clock (and sends the frames that come of it). Only datagrams
    /// come back.
    pub fn call(&mut self, from: SocketAddr, datagram: &[u8], now: Duration) -> Vec<Out> {
        self.rpc(from, datagram, now)
    }

    /// Lets time pass: the input CR's frames, the watchdog, alarms, ApplicationReady retries,
    /// the drive model.
    pub fn poll(&mut self, now: Duration) -> Vec<Out> {
        self.timers(now)
    }

    /// Everything that runs on time.
    fn timers(&mut self, now: Duration) -> Vec<Out> {
        let mut out = Vec::new();
        self.watchdog(now);
        self.device.tick(now);
        if self.ar.as_ref().is_some_and(|ar| ar.gave_up(now)) {
            // No ApplicationReady confirmation after every retry: the AR is abandoned.
            self.ar = None;
        }
        if self.access.as_ref().is_some_and(|a| a.expired(now)) {
            self.access = None;
        }
        self.fault_alarms();
        self.test_alarms();
        if let Some(ar) = self.ar.as_mut() {
            out.extend(ar.due(now));
        }
        out.extend(self.alarms_due(now));
        out.extend(self.send_input(now));
        if now >= self.next_lldp {
            self.next_lldp = now + LLDP_INTERVAL;
            out.push(self.lldp());
        }
        out
    }

    /// The LLDP frame of conformance class B (BU 0620 §2.5.3 "Topology detection with the Link
    /// Layer Discovery Protocol"): chassis ID the name of station, port ID "port-001".
    fn lldp(&self) -> Out {
        let du = proto::lldp::Lldpdu {
            chassis: (
                proto::lldp::LOCALLY_ASSIGNED,
                self.name().as_bytes().to_vec(),
            ),
            port: (proto::lldp::LOCALLY_ASSIGNED, b"port-001".to_vec()),
            ttl: LLDP_TTL_S,
        };
        Out::Frame(
            EthernetRepr {
                dst: proto::lldp::MULTICAST,
                src: self.mac,
                ethertype: proto::eth::ETHERTYPE_LLDP,
            }
            .emit(&du.emit()),
        )
    }

    /// What the interface's information parameters say of the bus: SK 550P P870 = 1
    /// "PROFINET IO" (BU 0620 §4.3) and P878 the MAC address (§4.4.3); SK TU3-PNT P181 the MAC
    /// address (BU 0590 §5.1.4).
    fn show_identity(&mut self) {
        let mac = self.mac.0;
        let product = self.product;
        let Ok(store) = self.device.store(crate::link::Unit::Interface) else {
            return;
        };
        let mac_param = match product {
            Product::Sk550p => {
                store.set_info(870, 1, i32::from(def::BUS_PROTOCOL_CODE));
                878
            }
            _ => 181,
        };
        for (e, b) in (1..).zip(mac) {
            store.set_info(mac_param, e, i32::from(b));
        }
    }

    /// An Ethernet frame from the device to `dst`.
    fn ethernet(&self, dst: MacAddr, payload: Vec<u8>) -> Out {
        Out::Frame(
            EthernetRepr {
                dst,
                src: self.mac,
                ethertype: ETHERTYPE_PROFINET,
            }
            .emit(&payload),
        )
    }
}
