//! The NORD system bus as a virtual CAN segment: the inverters of a product as CANopen nodes
//! (CiA 301) at their system-bus addresses (P515: FI n at 32 + 2·(n − 1), BU 0620 §2.6,
//! `proto::nord::can`), fed CAN frames and the time, answering frames.
//!
//! What the manuals do not state, and where this simulator follows CiA 301 instead (each
//! choice "not stated by the manuals"):
//! - COB-IDs: the pre-defined connection set (SDO 600h/580h + node, heartbeat 700h + node,
//!   EMCY 80h + node, NMT 000h).
//! - SDO access to parameters: NORD's object layout as the project maps it for EtherCAT, one
//!   node per inverter: parameter P at object 2000h + P, its sets or elements as sub-indices
//!   (`proto::nord::ecat::parameter_subindex`).
//! - The communication objects: 1000h device type 0 (no standard device profile), 1001h error
//!   register (bit 0 while the inverter has an error), 1008h the product's name, 1017h the
//!   producer heartbeat time (ms, 0 = off, the factory value), 1018h identity (NORD's vendor id
//!   538h, as its EtherCAT interface reports it).
//! - EMCY: one when an inverter error appears (P700 [-01] from 0), the code as the SK 550P's
//!   EtherCAT interface sends it (BU 0620 §5.3's DS402 code for a communication error, else
//!   FF00h).
//! - Process data: the layout `proto::nord::can::pdo_words` chooses, RPDO1 (200h + node) the
//!   control word and setpoints 1–3 and RPDO2 (300h + node) setpoints 4–5, TPDO1 (180h + node)
//!   the status word and actual values 1–3 and TPDO2 (280h + node) actual values 4–5, each word
//!   UNSIGNED16 little-endian; PDO 2 only for an inverter with five values (`process_values`:
//!   SK 5x0P, SK 54xE). All are synchronous (transmission type 1): at each SYNC (080h) a node in
//!   Operational takes the words its RPDOs brought last and answers with its TPDOs; a node that
//!   has received no RPDO1 since it entered Operational sends none. An RPDO shorter than its
//!   mapping is not processed and gives an EMCY 8210h, a longer one is processed and gives an
//!   EMCY 8220h (CiA 301 "PDO not processed due to length error", "PDO length exceeded").
//! - P120 monitoring: each node consumes the interface's heartbeat (1016h:01, node 1 behind a
//!   module, FI 1's node 32 behind the SK 550P, 600 ms; `proto::nord::can::InterfaceWatch`),
//!   from boot-up with P120 [-01] = 2, from the first heartbeat with 1 "Auto", not with 0. Every
//!   node hears every frame on the segment, its neighbours' heartbeats too. A late heartbeat is
//!   the error `interface_loss_error` names (E10.0 with 7583h behind the SK 550P, E10.8 behind
//!   an SK TU3, E10.9 behind an SK CU4/TU4), with its EMCY, unless P513 [-03] is −0.1 "no
//!   error". P748 [-01] shows the node's NMT state (`proto::nord::can::p748_status`).
//! - The inverters' series: SK 5x0P behind the SK 550P (BU 0620 §2.1); behind a bus module
//!   SK 54xE, whose five setpoints and actual values (BU 2100 §6.2.5, BU 2200 §6.3.4) the
//!   simulator's drives take on the modules' other buses too.
//! - Faults of the bus a case injects (`inject: { inverter: N, error: … }`): [`OFF_BUS`] (the
//!   node's cable pulled), and its CAN controller's: [`BUS_OFF`], [`ERROR_PASSIVE`] and
//!   [`ERROR_FRAMES`] by ISO 11898-1's fault confinement, with CiA 301's EMCY 8120h and 8140h
//!   (`controller`, with the choices the standards leave open), and an SK 5x0P's E10.0 with
//!   7585h "CAN in Bus Off state" when its node goes bus off (BU 0620 §5.3 p. 94). The error frames a listener
//!   sees are kept apart from the frames ([`Segment::take_error_frames`]).

mod controller;
mod endpoint;
mod node;
#[cfg(test)]
mod tests;

use std::time::Duration;

use proto::can::socketcan::ErrorFrame;
use proto::can::CanFrame;
use proto::nord::can::{InverterSeries, SystemBusAddress};
use proto::nord::{ArrayElement, Family, Inverter, ParamNumber, Product};

use crate::device::{Device, DeviceConfig};
use crate::drive::FaultCode;
use crate::link::Unit;
use controller::Controller;
pub use controller::{
    bus_error, BURST, BUS_OFF, ERROR_FRAMES, ERROR_PASSIVE, MIN_RECOVERY, RECOVERY,
};
use node::Node;

/// The most error frames the segment keeps for [`Segment::take_error_frames`].
const MAX_ERROR_FRAMES: usize = 1024;

/// Why a segment cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum SegmentError {
    /// An inverter has no system-bus address.
    #[error("FI {0} has no system-bus address")]
    NoAddress(u8),
}

/// P700 "Current fault".
const P700: ParamNumber = match ParamNumber::new(700) {
    Ok(p) => p,
    Err(_) => panic!("P700 is a parameter number"),
};

/// The series of the simulated inverters of `product` (see the module documentation).
fn series(product: Product) -> InverterSeries {
    match product.family() {
        Family::Integrated => InverterSeries::Sk5x0p,
        _ => InverterSeries::Sk54xe,
    }
}

/// The fault a case injects to take an inverter's node off the segment (`inject: { inverter:
/// N, error: off-bus }`): its cable pulled. The node hears nothing and sends nothing, its
/// heartbeat stops, and its inverter no longer hears the interface's heartbeat either.
pub const OFF_BUS: &str = "off-bus";

/// One CAN segment: the device's inverters as nodes.
#[derive(Debug)]
pub struct Segment {
    device: Device,
    nodes: Vec<Node>,
    /// The inverters whose nodes are off the segment ([`OFF_BUS`]).
    off_bus: Vec<Inverter>,
    /// Each node's CAN controller, in node order.
    controllers: Vec<Controller>,
    /// The error frames since [`Segment::take_error_frames`], with their time.
    errors: Vec<(Duration, ErrorFrame)>,
    /// The latest time the segment was given.
    now: Duration,
    /// P700 [-01] of each inverter as last seen, for EMCY.
    faults: [i32; 8],
    /// Its inverters report their own bus off (E10.0, 7585h: the SK 550P's SK 5x0P).
    reports_bus_off: bool,
}

impl Segment {
    /// The segment of `config`'s inverters, each about to boot.
    pub fn new(config: DeviceConfig) -> Result<Segment, SegmentError> {
        let nodes = (1..=config.inverters)
            .map(|n| {
                let fi = Inverter::new(i64::from(n)).map_err(|_| SegmentError::NoAddress(n))?;
                Ok(Node::new(
                    fi,
                    SystemBusAddress::inverter(fi).get(),
                    config.product,
                    series(config.product),
                ))
            })
            .collect::<Result<Vec<_>, SegmentError>>()?;
        Ok(Segment {
            device: Device::new(config),
            controllers: vec![Controller::default(); nodes.len()],
            errors: Vec::new(),
            now: Duration::ZERO,
            reports_bus_off: series(config.product) == InverterSeries::Sk5x0p,
            nodes,
            off_bus: Vec::new(),
            faults: [0; 8],
        })
    }

    /// Raises `error` on `inverter`: [`OFF_BUS`] takes its node off the segment, [`BUS_OFF`],
    /// [`ERROR_PASSIVE`] and [`ERROR_FRAMES`] are its controller's, anything else is the
    /// device's fault ([`Device::inject_fault`]: an inverter error, or the interface's own
    /// controller, `bus-off`, `bus-warning`).
    pub fn inject_fault(&mut self, inverter: Inverter, error: &str) -> Result<(), String> {
        if ![OFF_BUS, BUS_OFF, ERROR_PASSIVE, ERROR_FRAMES].contains(&error) {
            return self.device.inject_fault(inverter, error);
        }
        let Some(i) = self.nodes.iter().position(|n| n.inverter() == inverter) else {
            return Err(format!("FI {} is not on the system bus", inverter.get()));
        };
        if error != OFF_BUS {
            self.controllers[i].inject(error, self.now);
            self.report_controllers();
        } else if !self.off_bus.contains(&inverter) {
            self.off_bus.push(inverter);
        }
        Ok(())
    }

    /// An SK 5x0P whose node went bus off reports E10.0 with P700 [-04] 7585h "CAN in Bus Off
    /// state" (BU 0620 §5.3 p. 94), unless an error is present or P513 ignores communication
    /// errors ([`Device::raise`]); the node, bus off, cannot send its EMCY.
    ///
    /// Each inverter's "BUS" LED is told its node's controller state here too.
    fn report_controllers(&mut self) {
        for (node, controller) in self.nodes.iter().zip(&self.controllers) {
            self.device
                .set_node_bus(node.inverter(), controller.bus_state());
        }
        for i in 0..self.nodes.len() {
            if !self.controllers[i].went_bus_off() || !self.reports_bus_off {
                continue;
            }
            let fi = self.nodes[i].inverter();
            let cause = proto::nord::can::CanCause::BusOff;
            let code = FaultCode { group: 10, sub: 0 };
            let p700 = |d: &mut Device| {
                d.store(Unit::Inverter(fi))
                    .ok()
                    .and_then(|s| s.read(P700, None, ArrayElement::new(1).ok()).ok())
            };
            let before = p700(&mut self.device);
            if self.device.raise(fi, code).is_err() {
                continue;
            }
            if before == Some(0) && p700(&mut self.device) == Some(i32::from(cause.p700())) {
                if let Ok(store) = self.device.store(Unit::Inverter(fi)) {
                    store.set_info(700, 4, i32::from(cause.ds402()));
                }
            }
        }
    }

    /// [`Segment::inject_fault`] at `now` (a master's clock may run ahead of the last time the
    /// segment was given: a fault of the controller starts then, bus off included).
    pub fn inject_fault_at(
        &mut self,
        inverter: Inverter,
        error: &str,
        now: Duration,
    ) -> Result<(), String> {
        self.now = self.now.max(now);
        self.inject_fault(inverter, error)
    }

    /// The error frames the segment's faults caused since the last call, with their time, as a
    /// listener's controller reports them (`CAN_ERR_FLAG` frames of SocketCAN; none unless a
    /// case injected [`ERROR_FRAMES`]). At most the last 1024 are kept.
    pub fn take_error_frames(&mut self) -> Vec<(Duration, ErrorFrame)> {
        std::mem::take(&mut self.errors)
    }

    /// Whether node `i` takes part in the bus: on it, and not bus off.
    fn takes_part(&self, i: usize) -> bool {
        !self.off_bus.contains(&self.nodes[i].inverter()) && !self.controllers[i].is_bus_off()
    }

    /// `frames` node `i` transmits at `now`, through its controller: those that reach the bus
    /// go to `out`.
    fn transmit(
        &mut self,
        i: usize,
        frames: Vec<CanFrame>,
        now: Duration,
        out: &mut Vec<CanFrame>,
    ) {
        for f in frames {
            out.extend(self.controllers[i].transmit(f, now, &mut self.errors));
        }
        if self.errors.len() > MAX_ERROR_FRAMES {
            let extra = self.errors.len() - MAX_ERROR_FRAMES;
            self.errors.drain(..extra);
        }
    }

    /// The node ids on the segment.
    pub fn nodes(&self) -> Vec<u8> {
        self.nodes.iter().map(Node::id).collect()
    }

    /// The device behind the nodes (its inverters' parameters and drives).
    pub fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// A frame on the bus at `now`: what the nodes answer to it, in node order.
    pub fn receive(&mut self, frame: &CanFrame, now: Duration) -> Vec<CanFrame> {
        self.receive_all(std::slice::from_ref(frame), now)
    }

    /// Frames on the bus one after the other at `now` (a master's RPDOs and SYNC): what the
    /// nodes answer to them, in order, the segment's monitoring run once for all of them.
    pub fn receive_all(&mut self, frames: &[CanFrame], now: Duration) -> Vec<CanFrame> {
        let mut out = self.poll(now);
        for frame in frames {
            for i in 0..self.nodes.len() {
                if !self.takes_part(i) {
                    continue;
                }
                self.nodes[i].overhear(frame, now);
                let answers = self.nodes[i].receive(frame, &mut self.device, now);
                self.transmit(i, answers, now, &mut out);
            }
        }
        self.report_controllers();
        self.overheard(&out, now);
        self.look(now);
        self.emergencies(&mut out);
        out
    }

    /// What the nodes send on their own at `now`: boot-up messages, heartbeats, EMCY.
    pub fn poll(&mut self, now: Duration) -> Vec<CanFrame> {
        self.now = self.now.max(now);
        self.device.tick(now);
        let mut out = Vec::new();
        for i in 0..self.nodes.len() {
            if self.off_bus.contains(&self.nodes[i].inverter()) {
                continue;
            }
            // Back from bus off, or error passive: CiA 301's EMCY first.
            if let Some(code) = self.controllers[i].wake(now) {
                let emcy = self.nodes[i].communication_error(code);
                self.transmit(i, emcy.into_iter().collect(), now, &mut out);
            }
            if self.takes_part(i) {
                let frames = self.nodes[i].poll(now);
                self.transmit(i, frames, now, &mut out);
            }
        }
        self.report_controllers();
        self.overheard(&out, now);
        self.look(now);
        self.emergencies(&mut out);
        out
    }

    /// An EMCY for each inverter error that appeared or went.
    /// A node bus off sends its EMCY once it is back (after its 8140h): the change is left
    /// unseen until then. Off the bus (its cable pulled) the EMCY is lost.
    fn emergencies(&mut self, out: &mut Vec<CanFrame>) {
        let before = self.faults;
        for (fi, value) in self.device.fault_changes(&mut self.faults) {
            let extended = self
                .device
                .store(Unit::Inverter(fi))
                .ok()
                .and_then(|s| s.read(P700, None, ArrayElement::new(4).ok()).ok())
                .and_then(|x| u16::try_from(x).ok());
            let Some(i) = self.nodes.iter().position(|n| n.inverter() == fi) else {
                continue;
            };
            if self.controllers[i].is_bus_off() {
                let k = usize::from(fi.get() - 1);
                self.faults[k] = before[k];
                continue;
            }
            // Off the bus, the node still keeps its error register.
            let emcy = self.nodes[i].emergency(value, extended);
            if self.takes_part(i) {
                self.transmit(i, emcy.into_iter().collect(), self.now, out);
            }
        }
    }

    /// An EMCY of an error no inverter has, from the first node that takes part and may send
    /// one (not Stopped or Initialisation, CiA 301 §7.3.2.2), through its controller: the
    /// manuals' first communication error (BU 0620 §5.3, P700 100, 7580h "CAN /CANopen
    /// connection error"), its error register set as the EMCY says. For a served segment that
    /// misbehaves on purpose (`harness serve can --misbehave alarm=`); what was sent, and the
    /// frames (`None`: no node may send one now).
    pub fn spurious_emergency(&mut self, now: Duration) -> Option<(String, Vec<CanFrame>)> {
        let row = proto::nord::errors::COMM_ERRORS.iter().next()?;
        let i = (0..self.nodes.len()).find(|&i| self.takes_part(i))?;
        let emcy = self.nodes[i].emergency(i32::from(row.p700), Some(row.ds402))?;
        let mut out = Vec::new();
        self.transmit(i, vec![emcy], now, &mut out);
        self.overheard(&out, now);
        let what = format!(
            "EMCY {:04X}h from node {} (P700 {}: {}) though its inverter has no error",
            row.ds402,
            self.nodes[i].id(),
            row.p700,
            row.text
        );
        Some((what, out))
    }

    /// Every node hears what the others sent, as on a real bus.
    fn overheard(&mut self, frames: &[CanFrame], now: Duration) {
        for frame in frames {
            for i in 0..self.nodes.len() {
                if self.takes_part(i) {
                    self.nodes[i].overhear(frame, now);
                }
            }
        }
    }

    /// The nodes' monitoring and status parameters brought up to date.
    fn look(&mut self, now: Duration) {
        for node in &mut self.nodes {
            node.look(&mut self.device, now);
        }
    }

    /// When a node next sends on its own (`None`: nothing scheduled).
    pub fn next_due(&self) -> Option<Duration> {
        (0..self.nodes.len())
            .filter(|&i| !self.off_bus.contains(&self.nodes[i].inverter()))
            .filter_map(|i| match self.takes_part(i) {
                true => min(
                    self.nodes[i].next_due(),
                    self.controllers[i].next_due(self.now),
                ),
                false => self.controllers[i].next_due(self.now),
            })
            .min()
    }
}

/// The earlier of two times, either of which may be missing.
fn min(a: Option<Duration>, b: Option<Duration>) -> Option<Duration> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}
