//! The controlled node: NMT state machine, PReq/PRes, SoA services, NMT commands, SDO over
//! ASnd and UDP, error history — around one [`Device`].

use std::collections::VecDeque;
use std::net::{Ipv4Addr, SocketAddr};
use std::time::Duration;

use proto::epl::asnd::{ErrorEntry, Flags, IdentResponse, NmtCommandFrame, StatusResponse};
use proto::epl::frame::{Asnd, Body, Pres};
use proto::epl::sdo::SdoFrame;
use proto::epl::{
    EplRepr, NmtState, RequestedService, ServiceId, BROADCAST_NODE_ID, MN_NODE_ID, MULTICAST_ASND,
    MULTICAST_PRES,
};
use proto::eth::{EthernetFrame, EthernetRepr, MacAddr, ETHERTYPE_POWERLINK};
use proto::nord::epl::{self as def, Slot};
use proto::nord::led::{self, Row};
use proto::nord::nmt::PlState;
use proto::nord::{ArrayElement, Inverter, ParamNumber, Product, Protocol};

use super::mapping::PdoMap;
use super::od::{Context, Dictionary, NodeVars, HISTORY_LEN};
use super::sdo::{Peer, Server};
use crate::device::Device;
use crate::ecat::pdo::{self, ProcessWords};
use crate::link::Unit;

/// How often the node wants [`Node::poll`] (timers, drive model).
pub const POLL_PERIOD: Duration = Duration::from_millis(10);

/// How long the node goes without a SoC in a cycling state before it counts the MN as lost:
/// ten cycles, at least 100 ms. DS 301 counts lost SoCs against a threshold (DLL_CNLossSoC_REC,
/// 1C0Bh) the manuals do not give; ten cycles keeps a served node on a loaded host from
/// seeing losses that are only scheduling jitter.
fn loss_of_soc(cycle_us: u32) -> Duration {
    Duration::from_micros(u64::from(cycle_us) * 10).max(Duration::from_millis(100))
}

/// The error a spurious emergency signals: P700 E12.0, "External watchdog" (BU 0620 §5.4.1.2:
/// 9000h, error register 1).
const SPURIOUS_ERROR: i32 = 120;

/// DS 301 error code E_DLL_LOSS_SOC_TH: the loss of SoC passed its threshold.
const LOSS_OF_SOC: u16 = 0x8245;
/// P170 [-01] of the modules when the gateway (P164) is outside 192.168.100.1…240 at
/// start-up: "5605 Konfig. setzen" (BU 2200 §5.2.5, BU 0620 §3.7.3 "5605 set config.").
const SET_CONFIG_ERROR: i32 = 5605;

/// The manuals' state of an NMT state, where they have it.
fn pl_state(s: NmtState) -> Option<PlState> {
    Some(match s {
        NmtState::NOT_ACTIVE => PlState::Initialisation,
        NmtState::PRE_OPERATIONAL_1 => PlState::PreOperational1,
        NmtState::PRE_OPERATIONAL_2 => PlState::PreOperational2,
        NmtState::READY_TO_OPERATE => PlState::ReadyToOperate,
        NmtState::OPERATIONAL => PlState::Operational,
        NmtState::STOPPED => PlState::Stopped,
        NmtState::BASIC_ETHERNET => PlState::BasicEthernet,
        _ => return None,
    })
}

/// The parameter that sets the node id: P850 of the SK 550P (under POWERLINK "Node ID", BU 0620
/// §4.2.3; the catalogue keeps EtherNet/IP's four elements, the node id is the first), P160 of
/// the modules (BU 2200 §5.2.5).
fn node_id_parameter(product: Product) -> u16 {
    if product == Product::Sk550p {
        850
    } else {
        160
    }
}

/// The I/O word the modules send: bit 15 "valid flag" (BU 2200 §6.3.7), the digital inputs
/// (none set) below.
const IO_VALID: u16 = 0x8000;

/// How the node is set up beyond its device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeConfig {
    /// The node id (SK 550P P850, modules P160 / DIP switches; 1..239 for a CN).
    pub node_id: u8,
    /// The node's MAC address.
    pub mac: MacAddr,
}

impl NodeConfig {
    /// Node `node_id` with the NORD MAC address F0-5F-5A-00-00-`node_id` (BU 0620 §4.4.2
    /// P878: manufacturer id "F0.5F.5A", then the free address area).
    pub fn new(node_id: u8) -> NodeConfig {
        NodeConfig {
            node_id,
            mac: MacAddr([0xF0, 0x5F, 0x5A, 0x00, 0x00, node_id]),
        }
    }
}

/// A device that cannot be a controlled node.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NodeError {
    /// The product has no POWERLINK interface.
    #[error("{0} has no POWERLINK interface")]
    NoPowerlink(&'static str),
    /// Not a controlled node's id (BU 0620 §2.4.3.1: 1…239).
    #[error("node id {0} is not a controlled node's (1…239, BU 0620 §2.4.3.1)")]
    NodeId(u8),
}

/// A POWERLINK controlled node (sans-IO).
#[derive(Debug)]
pub struct Node {
    device: Device,
    product: Product,
    mac: MacAddr,
    vars: NodeVars,
    od: Dictionary,
    sdo: Server,
    words: ProcessWords,
    /// When the state was entered.
    since: Duration,
    last_soc: Option<Duration>,
    /// LED "BE": a POWERLINK error (the MN lost) until the cycle runs again.
    error: bool,
    /// ASnd payloads waiting for an invitation (SDO answers to the MN).
    queued: VecDeque<Vec<u8>>,
    /// EN: toggled with every new error entry (DS 301 §6.5.2 exception signalling).
    en: bool,
    faults: [i32; 8],
    dropped: u64,
    gateway: Ipv4Addr,
    /// Losses of the SoC since power-on (modules: P184 [-01]).
    losses: i32,
    /// When the node wants [`Node::poll`] next as an endpoint: a [`POLL_PERIOD`] after the
    /// last.
    pub(super) next_poll: Duration,
}

impl Node {
    /// The controlled node of `device`, in NOT_ACTIVE from time zero.
    pub fn new(device: Device, config: NodeConfig) -> Result<Node, NodeError> {
        let product = device.config().product;
        if !product.protocols().contains(&Protocol::Powerlink) {
            return Err(NodeError::NoPowerlink(product.name()));
        }
        if !(1..=239).contains(&config.node_id) {
            return Err(NodeError::NodeId(config.node_id));
        }
        let mut node = Node {
            gateway: Ipv4Addr::UNSPECIFIED,
            losses: 0,
            device,
            product,
            mac: config.mac,
            vars: NodeVars {
                node_id: config.node_id,
                state: NmtState::NOT_ACTIVE,
                cycle_us: def::DEFAULT_CYCLE_US,
                basic_ethernet_us: def::BASIC_ETHERNET_TIMEOUT_US,
                error_register: 0,
                history: Vec::new(),
                rx_map: PdoMap::fixed(product, true),
                tx_map: PdoMap::fixed(product, false),
                lost: 0,
            },
            od: Dictionary::new(product),
            sdo: Server::default(),
            words: ProcessWords::default(),
            since: Duration::ZERO,
            last_soc: None,
            error: false,
            queued: VecDeque::new(),
            en: false,
            faults: [0; 8],
            dropped: 0,
            next_poll: Duration::ZERO,
        };
        // The node id is the addressing parameter's value (SK 550P P850, BU 0620 §3.7.3; the
        // modules' P160 "Node Id/IP Adresse 4" with the DIP switches off, BU 2200 §5.2.5):
        // the device starts with the one it was given.
        if let Ok(s) = node.device.store(Unit::Interface) {
            s.set_info(node_id_parameter(product), 1, i32::from(config.node_id));
        }
        node.start_up();
        node.show_state();
        // The interface's status parameters from power-on (P872 / P173: module ready, the FIs
        // online), before the first poll.
        node.device.tick(Duration::ZERO);
        Ok(node)
    }

    /// The NMT state.
    pub fn state(&self) -> NmtState {
        self.vars.state
    }

    /// The node id.
    pub fn node_id(&self) -> u8 {
        self.vars.node_id
    }

    /// The node's MAC address.
    pub fn mac(&self) -> MacAddr {
        self.mac
    }

    /// Frames that were not POWERLINK the node could parse (ignored, as DS 301's DLL does).
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// FI `fi` drops off the system bus (switched off, cable cut): its parameter objects answer
    /// 08000020h from now on (BU 2200 §5.2.4: an interface that cannot reach its inverter
    /// "kann keine Daten im Gerät speichern und antwortet mit einem Fehler").
    /// The module's P173 shows it "lost or switched off" ([`Device::lose`]).
    pub fn lose_inverter(&mut self, fi: Inverter) {
        self.vars.lost |= 1 << (fi.get() - 1);
        self.device.lose(fi);
    }

    /// The simulated device.
    pub fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// LED A "BS" (BU 0620 §5.5.2.3: the NMT state) and LED B "BE" (red: a POWERLINK error;
    /// the modules' BE in Pre-Operational 1/2, Ready To Operate and Basic Ethernet: the MN has
    /// failed, BU 2200 §6.2).
    pub fn leds(&self) -> (Row, Row) {
        let bs = match self.vars.state {
            NmtState::PRE_OPERATIONAL_1 => 1,
            NmtState::PRE_OPERATIONAL_2 => 2,
            NmtState::READY_TO_OPERATE => 3,
            NmtState::OPERATIONAL => 4,
            NmtState::BASIC_ETHERNET => 5,
            NmtState::STOPPED => 6,
            _ => 0,
        };
        let be = match (self.error, self.product) {
            (false, _) => led::POWERLINK_BE[0],
            (true, Product::Sk550p) => led::POWERLINK_BE[1],
            (true, _) => {
                pl_state(self.vars.state).map_or(led::POWERLINK_BE[1], led::powerlink_module_be_red)
            }
        };
        (led::POWERLINK_BS[bs], be)
    }

    /// Handles one whole Ethernet frame received at `now`; returns the frames to send.
    pub fn receive(&mut self, frame: &[u8], now: Duration) -> Vec<Vec<u8>> {
        self.timers(now);
        let Ok(eth) = EthernetFrame::new_checked(frame) else {
            self.dropped += 1;
            return Vec::new();
        };
        if eth.inner_ethertype() != ETHERTYPE_POWERLINK {
            return Vec::new();
        }
        let Ok(repr) = EplRepr::parse_bytes(eth.inner_payload()) else {
            self.dropped += 1;
            return Vec::new();
        };
        let from_mn = repr.src == MN_NODE_ID;
        let me = self.vars.node_id;
        match self.vars.state {
            NmtState::BASIC_ETHERNET => {
                self.enter(NmtState::PRE_OPERATIONAL_1, now);
                return Vec::new();
            }
            NmtState::NOT_ACTIVE if from_mn && matches!(repr.body, Body::Soc(_) | Body::Soa(_)) => {
                self.enter(NmtState::PRE_OPERATIONAL_1, now);
                return Vec::new();
            }
            NmtState::NOT_ACTIVE => return Vec::new(),
            _ => {}
        }
        if !from_mn {
            return Vec::new();
        }
        let mut out = Vec::new();
        match repr.body {
            Body::Soc(_) => {
                self.last_soc = Some(now);
                if self.vars.state == NmtState::PRE_OPERATIONAL_1 {
                    self.error = false;
                    self.enter(NmtState::PRE_OPERATIONAL_2, now);
                }
            }
            Body::Preq(p) if repr.dst == me => {
                if matches!(
                    self.vars.state,
                    NmtState::PRE_OPERATIONAL_2
                        | NmtState::READY_TO_OPERATE
                        | NmtState::OPERATIONAL
                ) {
                    self.outputs(&p.payload, p.rd, now);
                    out.push(self.pres());
                }
            }
            Body::Soa(s) if s.target == me => match s.service {
                RequestedService::IDENT_REQUEST => out.push(self.asnd(
                    ServiceId::IDENT_RESPONSE,
                    self.ident().emit().unwrap_or_default(),
                )),
                RequestedService::STATUS_REQUEST => {
                    out.push(self.asnd(ServiceId::STATUS_RESPONSE, self.status().emit()))
                }
                RequestedService::UNSPECIFIED_INVITE => {
                    if let Some(payload) = self.queued.pop_front() {
                        out.push(self.asnd(ServiceId::SDO, payload));
                    }
                }
                _ => {}
            },
            Body::Asnd(a) if repr.dst == me || repr.dst == BROADCAST_NODE_ID => {
                self.asnd_in(a, repr.dst == me, now);
            }
            _ => {}
        }
        out
    }

    /// Handles an SDO datagram from `from` on UDP port 3819; returns the datagrams to answer.
    /// UDP is the only way in while the node is in Basic Ethernet (BU 0620 §2.4.4).
    pub fn udp(&mut self, from: SocketAddr, datagram: &[u8], now: Duration) -> Vec<Vec<u8>> {
        self.timers(now);
        if self.vars.state == NmtState::NOT_ACTIVE {
            // Initialisation: "Keine Prozessdaten- und Parameterkommunikation" (BU 2200 §6.2,
            // BU 0620 §2.4.4); the node only watches for POWERLINK frames.
            self.dropped += 1;
            return Vec::new();
        }
        let Ok(frame) = SdoFrame::strip_udp(datagram).and_then(SdoFrame::parse) else {
            self.dropped += 1;
            return Vec::new();
        };
        self.sdo_frames(Peer::Udp(from), &frame, now)
            .into_iter()
            .filter_map(|f| f.emit_udp().ok())
            .collect()
    }

    /// Runs the timers due at `now`, the drive model outside OPERATIONAL (in OPERATIONAL each
    /// PReq drives it) and the error history; wanted every [`POLL_PERIOD`].
    pub fn poll(&mut self, now: Duration) {
        self.timers(now);
        match self.vars.state {
            NmtState::OPERATIONAL => {}
            // PRes goes out but the PReq data are not evaluated (§2.4.4): the inverters see no
            // valid control word, their status words and actual values are refreshed here.
            NmtState::PRE_OPERATIONAL_2 | NmtState::READY_TO_OPERATE => {
                pdo::cycle(&mut self.device, &mut self.words, None, false, now)
            }
            _ => self.device.tick(now),
        }
        self.errors(now);
    }

    fn asnd_in(&mut self, a: Asnd, to_me: bool, now: Duration) {
        match a.service {
            ServiceId::NMT_COMMAND => {
                let Ok(c) = NmtCommandFrame::parse(&a.payload) else {
                    return;
                };
                // NMT commands reach a node from PRE_OPERATIONAL_1 on (DS 301 §7.1.4.1).
                if self.vars.state == NmtState::NOT_ACTIVE {
                    return;
                }
                if let Some(next) = c.command.next_state(self.vars.state) {
                    self.enter(next, now);
                }
            }
            ServiceId::SDO if to_me => {
                let Ok(frame) = SdoFrame::parse(&a.payload) else {
                    self.dropped += 1;
                    return;
                };
                for f in self.sdo_frames(Peer::Asnd(MN_NODE_ID), &frame, now) {
                    if let Ok(b) = f.emit() {
                        self.queued.push_back(b);
                    }
                }
            }
            _ => {}
        }
    }

    /// One SDO frame of `peer`, and the device's monitoring at once: what a parameter write
    /// sets off (P899's protocol change) has happened before the next frame, whenever the
    /// next poll comes.
    fn sdo_frames(&mut self, peer: Peer, frame: &SdoFrame, now: Duration) -> Vec<SdoFrame> {
        let mut cx = Context {
            device: &mut self.device,
            words: &self.words,
            vars: &mut self.vars,
        };
        let answers = self.sdo.handle(peer, frame, &self.od, &mut cx);
        self.device.tick(now);
        answers
    }

    /// Enters `to`: resets pass through to NOT_ACTIVE (DS 301 NMT_GT2…GT8: the node
    /// re-initialises and then watches for POWERLINK frames again).
    pub(super) fn enter(&mut self, to: NmtState, now: Duration) {
        let from = self.vars.state;
        let to = match to {
            NmtState::RESET_APPLICATION
            | NmtState::RESET_COMMUNICATION
            | NmtState::RESET_CONFIGURATION
            | NmtState::INITIALISING => {
                self.sdo.reset();
                self.queued.clear();
                self.last_soc = None;
                // The communication profile area (1000h…1FFFh) returns to its power-on values
                // (DS 301 NMT_GS_RESET_COMMUNICATION): the fixed mapping (BU 2200 §6.3.5).
                self.vars.rx_map = PdoMap::fixed(self.product, true);
                self.vars.tx_map = PdoMap::fixed(self.product, false);
                if to != NmtState::RESET_COMMUNICATION {
                    // A reset of the application is the restart the manuals ask for after
                    // changing the addressing parameters ("so that the parameter settings
                    // are read in", BU 0620 §3.7.3, BU 2200 §5.2.5).
                    self.start_up();
                }
                NmtState::NOT_ACTIVE
            }
            s => s,
        };
        if from == NmtState::OPERATIONAL && to != NmtState::OPERATIONAL {
            // The inverters get no valid control word from now on (as in Safe Operational
            // under EtherCAT): they keep their state.
            pdo::cycle(&mut self.device, &mut self.words, None, false, now);
        }
        self.vars.state = to;
        self.since = now;
        self.show_state();
    }

    /// The NMT timers: the Basic Ethernet timeout, the loss of the MN.
    fn timers(&mut self, now: Duration) {
        let state = self.vars.state;
        if state == NmtState::NOT_ACTIVE
            && now.saturating_sub(self.since)
                >= Duration::from_micros(u64::from(self.vars.basic_ethernet_us))
        {
            // No MN within the time-out: "If the red LED BE illuminates, the Managing Node has
            // failed" (BU 0620 §2.4.4 Basic Ethernet, BU 2200 §6.2).
            self.error = true;
            self.enter(NmtState::BASIC_ETHERNET, now);
        }
        let cycling = matches!(
            state,
            NmtState::PRE_OPERATIONAL_2 | NmtState::READY_TO_OPERATE | NmtState::OPERATIONAL
        );
        let last = self.last_soc.unwrap_or(self.since);
        if cycling && now.saturating_sub(last) > loss_of_soc(self.vars.cycle_us) {
            // Loss of SoC: the MN has failed (BU 0620 §2.4.4: "If the red LED BE illuminates
            // in this state, the Managing Node has failed"); the node falls back to
            // PRE_OPERATIONAL_1 (DS 301 NMT_CT11). Inverters whose monitoring is on raise
            // E10.2 as under EtherCAT's watchdog (BU 0620 §5.3).
            self.error = true;
            if state == NmtState::OPERATIONAL {
                pdo::watchdog_expired(&mut self.device);
            }
            self.losses += 1;
            self.show_error(LOSS_OF_SOC);
            self.enter(NmtState::PRE_OPERATIONAL_1, now);
        }
    }

    /// PReq data: drives the inverters in OPERATIONAL when the MN marks it valid (RD) and
    /// carries every mapped word; otherwise (PRE_OPERATIONAL_2, READY_TO_OPERATE: "cyclic data
    /// are not evaluated", §2.4.4) they are ignored.
    fn outputs(&mut self, payload: &[u8], rd: bool, now: Duration) {
        let evaluate = self.vars.state == NmtState::OPERATIONAL
            && rd
            && payload.len() >= 2 * self.vars.rx_map.words.len();
        if !evaluate {
            // Not evaluated: the PRes carries the inputs [`Node::poll`] refreshes.
            return;
        }
        let mut image = vec![0u8; 8 * 12];
        let mut io = None;
        for (m, w) in self.vars.rx_map.words.iter().zip(payload.chunks_exact(2)) {
            match m.slot {
                Slot::Inverter { fi, word } => {
                    let at = usize::from(fi - 1) * 12 + usize::from(word) * 2;
                    image[at..at + 2].copy_from_slice(w);
                }
                Slot::Io => io = Some(u16::from_le_bytes([w[0], w[1]])),
            }
        }
        if let Some(word) = io {
            self.digital_outputs(word);
        }
        pdo::cycle(&mut self.device, &mut self.words, Some(&image), true, now);
        self.device.set_fieldbus_timeout(false);
    }

    /// The I/O word of an SK TU4-POL / CU4-POL (BU 2200 §6.3.7): valid only with bit 15 set,
    /// DO1/DO2 in bits 0–1 (SK TU4-POL: P175 "Zustand Relais" shows them); P176 [-01] shows
    /// the word, P177 [-01] the inputs' word (the module has no inputs set: the valid flag).
    fn digital_outputs(&mut self, word: u16) {
        let relays = self.product == Product::Tu4Pol && word & 0x8000 != 0;
        if let Ok(s) = self.device.store(Unit::Interface) {
            s.set_info(176, 1, i32::from(word as i16));
            s.set_info(177, 1, i32::from(IO_VALID as i16));
            s.set_info(174, 1, 0);
            if relays {
                s.set_info(175, 1, i32::from(word & 0x03));
            }
        }
        // P150 1…4 overrides the bus (BU 2200 §7.1.1).
        self.device.set_relays();
    }

    fn pres(&self) -> Vec<u8> {
        let payload: Vec<u8> = self
            .vars
            .tx_map
            .words
            .iter()
            .flat_map(|m| {
                let w = match m.slot {
                    Slot::Inverter { fi, word } => {
                        self.words.inputs[usize::from(fi - 1)][usize::from(word)]
                    }
                    Slot::Io => IO_VALID,
                };
                w.to_le_bytes()
            })
            .collect();
        let repr = EplRepr {
            dst: BROADCAST_NODE_ID,
            src: self.vars.node_id,
            body: Body::Pres(Pres {
                state: self.vars.state,
                en: self.en,
                rd: self.vars.state == NmtState::OPERATIONAL,
                rs: self.queued.len().min(7) as u8,
                pr: if self.queued.is_empty() { 0 } else { 3 },
                pdo_version: 0x20,
                payload,
                ..Pres::default()
            }),
        };
        self.frame(MULTICAST_PRES, &repr)
    }

    fn asnd(&self, service: ServiceId, payload: Vec<u8>) -> Vec<u8> {
        let repr = EplRepr {
            dst: MN_NODE_ID,
            src: self.vars.node_id,
            body: Body::Asnd(Asnd { service, payload }),
        };
        self.frame(MULTICAST_ASND, &repr)
    }

    fn frame(&self, dst: MacAddr, repr: &EplRepr) -> Vec<u8> {
        let eth = EthernetRepr {
            dst,
            src: self.mac,
            ethertype: ETHERTYPE_POWERLINK,
        };
        eth.emit(&repr.emit().unwrap_or_default())
    }

    fn flags(&self) -> Flags {
        Flags {
            en: self.en,
            ec: false,
            pr: 0,
            rs: self.queued.len().min(7) as u8,
        }
    }

    /// The IdentResponse: identity of `proto::nord::epl`, the node's addresses.
    pub fn ident(&self) -> IdentResponse {
        let n = self.vars.node_id;
        let bytes = |outputs: bool| {
            let map = if outputs {
                &self.vars.rx_map
            } else {
                &self.vars.tx_map
            };
            2 * map.words.len() as u16
        };
        IdentResponse {
            flags: self.flags(),
            state: self.vars.state,
            epl_version: def::EPL_VERSION,
            feature_flags: def::FEATURE_FLAGS,
            mtu: def::ASYNC_MTU,
            poll_in_size: bytes(true),
            poll_out_size: bytes(false),
            response_time: def::RESPONSE_TIME_NS,
            device_type: def::DEVICE_TYPE,
            vendor_id: def::VENDOR_ID,
            product_code: def::product_code(self.product),
            revision: def::revision(self.product),
            serial: 0,
            vendor_ext1: 0,
            dates: [0; 4],
            ip: def::ip_address(n),
            subnet: def::SUBNET,
            gateway: self.gateway,
            hostname: def::default_hostname(n),
            vendor_ext2: [0; 48],
        }
    }

    /// What the node reads in when it starts: the gateway, checked against the POWERLINK
    /// range, and the identity it shows in its information parameters.
    fn start_up(&mut self) {
        let product = self.product;
        if let (Ok(n), Ok(s)) = (
            ParamNumber::new(i64::from(node_id_parameter(product))),
            self.device.store(Unit::Interface),
        ) {
            let id = s
                .read(
                    n,
                    None,
                    ArrayElement::new(1)
                        .ok()
                        .filter(|_| product == Product::Sk550p),
                )
                .unwrap_or(0);
            // A value outside 1…239 is no controlled node's id (§2.4.3.1): the node keeps its own.
            if let Ok(id @ 1..=239) = u8::try_from(id) {
                self.vars.node_id = id;
            }
        }
        self.gateway = Node::read_gateway(&mut self.device, self.product);
        let [a, b, c, d] = self.gateway.octets();
        let valid = self.gateway == def::MODULE_GATEWAY
            || self.gateway.is_unspecified()
            || ([a, b, c] == def::IP_PREFIX && (1..=240).contains(&d));
        if self.product != Product::Sk550p {
            if let Ok(s) = self.device.store(Unit::Interface) {
                s.set_info(170, 1, if valid { 0 } else { SET_CONFIG_ERROR });
            }
            self.device.set_config_error(!valid);
        }
        self.show_identity();
    }

    /// P183 "NMT Error" (modules, BU 2200 §7.1.4): the last DS 301 error code, as the
    /// parameter shows a 16-bit value; P184 [-01] counts the losses of the SoC.
    fn show_error(&mut self, code: u16) {
        if self.product == Product::Sk550p {
            return;
        }
        let losses = self.losses;
        if let Ok(s) = self.device.store(Unit::Interface) {
            s.set_info(183, 1, i32::from(code as i16));
            s.set_info(184, 1, losses);
        }
    }

    /// The gateway read in at power-on (BU 0620 §3.7.3 P852, BU 2200 §5.2.5 P164: "restart
    /// … so that the parameter settings are read in").
    fn read_gateway(device: &mut Device, product: Product) -> Ipv4Addr {
        let number = if product == Product::Sk550p { 852 } else { 164 };
        let mut b = [0u8; 4];
        if let (Ok(n), Ok(s)) = (ParamNumber::new(number), device.store(Unit::Interface)) {
            for (e, byte) in (1..).zip(b.iter_mut()) {
                let Ok(el) = ArrayElement::new(e) else {
                    continue;
                };
                *byte = s.read(n, None, Some(el)).unwrap_or(0) as u8;
            }
        }
        Ipv4Addr::from(b)
    }

    /// The StatusResponse: state, error register and the error history.
    pub fn status(&self) -> StatusResponse {
        StatusResponse {
            flags: self.flags(),
            state: self.vars.state,
            error_register: self.vars.error_register,
            specific: [0; 6],
            entries: self.vars.history.clone(),
        }
    }

    /// An error entry for each inverter error that appeared (P700 [-01] from 0 to a value).
    fn errors(&mut self, now: Duration) {
        for (fi, value) in self.device.fault_changes(&mut self.faults) {
            if value != 0 {
                self.signal(fi.get(), value, now);
            }
        }
        if self.faults.iter().all(|&f| f == 0) {
            self.vars.error_register = 0;
        }
    }

    /// Signals FI `fi`'s error `value` (P700, tenths) as DS 301 has a CN signal a new error
    /// (§6.5 error signalling): an entry first in its history (1003h), which the
    /// StatusResponse lists, the error register's bits, and EN toggled in PRes and
    /// StatusResponse so that the MN fetches it. The code is BU 0620 §5.4.1.2's allocation
    /// table's (1000h with error index 1 where the table has none), the FI id and the P700
    /// value in ASCII the additional information (§5.4.1.2 "FI-ID (ASCII)", "FI Error Code
    /// (ASCII)"). Returns the entry.
    fn signal(&mut self, fi: u8, value: i32, now: Duration) -> ErrorEntry {
        let (code, register) = proto::nord::errors::powerlink_error(value as u16)
            .map_or((0x1000, 1), |e| (e.code, e.register));
        let text = format!("{fi}{:>7}", format!("{}.{}", value / 10, value % 10));
        let mut info = [0u8; 8];
        info.copy_from_slice(&text.as_bytes()[..8]);
        let entry = ErrorEntry {
            entry_type: ErrorEntry::MODE_HISTORY | 0x0001,
            code,
            time: now.as_micros() as u64,
            info: u64::from_le_bytes(info),
        };
        self.vars.history.insert(0, entry);
        self.vars.history.truncate(HISTORY_LEN);
        self.vars.error_register |= register;
        self.en = !self.en;
        entry
    }

    /// Signals an error though none occurred (a served node that misbehaves on purpose,
    /// `--misbehave alarm=`): FI 1's E12.0 "External watchdog" (§5.4.1.2: 9000h), which no
    /// drive of the simulator raises on its own. `None` before the node takes part in the
    /// cycle (NOT_ACTIVE, Basic Ethernet): no MN would fetch it.
    pub fn raise_spurious(&mut self, now: Duration) -> Option<ErrorEntry> {
        if matches!(
            self.vars.state,
            NmtState::NOT_ACTIVE | NmtState::BASIC_ETHERNET
        ) {
            return None;
        }
        Some(self.signal(1, SPURIOUS_ERROR, now))
    }

    /// EN as the node sends it in PRes and StatusResponse.
    pub fn exception_new(&self) -> bool {
        self.en
    }

    /// The interface's information parameters that say who the node is: SK 550P P870 = 4
    /// "Powerlink", P875 IP address, P876 subnet mask, P878 MAC address (BU 0620 §4.3, §4.4.2);
    /// modules P185 IP address, P186 subnet mask, P181 MAC address (BU 2200 §7.1.4).
    fn show_identity(&mut self) {
        let ip = def::ip_address(self.vars.node_id).octets();
        let mac = self.mac.0;
        let product = self.product;
        let Ok(s) = self.device.store(Unit::Interface) else {
            return;
        };
        let (ip_p, mac_p) = match product {
            Product::Sk550p => {
                s.set_info(870, 1, 4);
                for (e, b) in (1..).zip(def::SUBNET.octets()) {
                    s.set_info(876, e, i32::from(b));
                }
                (875, 878)
            }
            _ => {
                for (e, b) in (1..).zip(def::SUBNET.octets()) {
                    s.set_info(186, e, i32::from(b));
                }
                (185, 181)
            }
        };
        for (e, b) in (1..).zip(ip) {
            s.set_info(ip_p, e, i32::from(b));
        }
        for (e, b) in (1..).zip(mac) {
            s.set_info(mac_p, e, i32::from(b));
        }
    }

    /// P182 "NMT State" of the modules (BU 2200 §7.1.4: the state code).
    fn show_state(&mut self) {
        if self.product == Product::Sk550p {
            return;
        }
        let code = self.vars.state.0;
        if let Ok(s) = self.device.store(Unit::Interface) {
            s.set_info(182, 1, i32::from(code));
        }
    }
}
