//! One inverter as a CANopen node: NMT state machine, boot-up and heartbeat, node guarding,
//! the SDO server over its object dictionary, EMCY, and its process data (RPDO1/TPDO1 on
//! SYNC).

use std::time::Duration;

use proto::can::CanFrame;
use proto::canopen::cob_id::{Cob, Function};
use proto::canopen::emcy::{register, Emergency};
use proto::canopen::nmt::{ErrorControl, NmtFrame, NmtState};
use proto::canopen::sync::SyncFrame;
use proto::nord::can::{interface_watch, p748_status, InverterSeries};
use proto::nord::errors::SdoAbort;
use proto::nord::{Family, Inverter, ParamNumber, Product};

use crate::device::Device;
use crate::link::Unit;
use crate::objects::{abort, decode_number, emergency_of};
use crate::pdo_image::{PdoError, PdoImage, Read};
use crate::sdo_server::{Objects, ParameterObjects, SdoServer, LAST_PARAMETER, PARAMETERS};

/// Communication objects (CiA 301 §7.5.2).
const DEVICE_TYPE: u16 = 0x1000;
const ERROR_REGISTER: u16 = 0x1001;
const DEVICE_NAME: u16 = 0x1008;
const CONSUMER_HEARTBEAT: u16 = 0x1016;
const HEARTBEAT_TIME: u16 = 0x1017;
const IDENTITY: u16 = 0x1018;

/// CiA 301 emergency error code 8210h "PDO not processed due to length error".
const PDO_TOO_SHORT: u16 = 0x8210;
/// CiA 301 emergency error code 8220h "PDO length exceeded".
const PDO_TOO_LONG: u16 = 0x8220;

/// One node.
#[derive(Debug)]
pub(super) struct Node {
    fi: Inverter,
    id: u8,
    product: Product,
    state: NmtState,
    /// 1017h, ms (0: no heartbeat).
    heartbeat_ms: u16,
    /// When the next heartbeat (or, in Initialisation, the boot-up message) is due.
    due: Option<Duration>,
    /// The toggle bit of the next node guarding response.
    guard_toggle: bool,
    /// Its SDO server.
    sdo: SdoServer,
    /// The error register (1001h) as the last EMCY set it.
    error_register: u8,
    /// Its process image: what the RPDOs brought, taken at each SYNC (in Operational).
    pdo: PdoImage,
    /// 1016h:01, the heartbeat the node consumes: node-ID in bits 16–23, time (ms) in 0–15.
    consumer: u32,
    /// Its P120 monitoring of the interface (`proto::nord::can::InterfaceWatch`).
    watch: Watch,
    /// P748 [-01] as last shown.
    shown_status: Option<i32>,
    /// P120 [-01] as last read; read again after an SDO download to the node.
    p120: Option<i32>,
}

/// The P120 monitoring of the interface's heartbeat.
#[derive(Debug, Clone, Copy, Default)]
struct Watch {
    /// When the node booted (P120 = 2 watches from then).
    booted: Duration,
    /// When the consumed heartbeat came last.
    heard: Option<Duration>,
    /// When the monitoring trips, as P120 stood at the last look (`None`: not watching).
    deadline: Option<Duration>,
    /// Tripped, until the heartbeat comes again.
    tripped: bool,
}

impl Node {
    pub(super) fn new(fi: Inverter, id: u8, product: Product, series: InverterSeries) -> Node {
        Node {
            fi,
            id,
            product,
            state: NmtState::Initialisation,
            heartbeat_ms: 0,
            due: Some(Duration::ZERO),
            guard_toggle: false,
            sdo: SdoServer::default(),
            error_register: 0,
            pdo: PdoImage::new(series),
            consumer: factory_consumer(product),
            watch: Watch::default(),
            shown_status: None,
            p120: None,
        }
    }

    pub(super) fn id(&self) -> u8 {
        self.id
    }

    pub(super) fn inverter(&self) -> Inverter {
        self.fi
    }

    pub(super) fn next_due(&self) -> Option<Duration> {
        match (self.due, self.watch.deadline) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// A frame on the bus, from anyone: the heartbeat the node consumes feeds its monitoring.
    pub(super) fn overhear(&mut self, frame: &CanFrame, now: Duration) {
        let node = (self.consumer >> 16) as u8;
        let heartbeat = Function::ErrorControl.cob_id(node).ok() == Some(frame.id())
            && !frame.is_remote()
            && ErrorControl::parse(frame.data()).is_ok_and(|e| !e.is_boot_up());
        if heartbeat && node != self.id {
            self.watch.heard = Some(now);
            self.watch.tripped = false;
        }
    }

    /// The monitoring of the interface (P120 [-01] of the node's inverter: 0 off, 1 "Auto"
    /// from the first heartbeat, 2 from boot-up) and P748 [-01] (the NMT state) brought up to
    /// date; the inverter loses its interface once the heartbeat is late.
    pub(super) fn look(&mut self, device: &mut Device, now: Duration) {
        let status = p748_status(self.state);
        let Ok(store) = device.store(Unit::Inverter(self.fi)) else {
            return;
        };
        if self.shown_status != Some(status) {
            store.set_info(748, 1, status);
            self.shown_status = Some(status);
        }
        let p120 = *self.p120.get_or_insert_with(|| {
            ParamNumber::new(120)
                .ok()
                .and_then(|n| {
                    store
                        .read(n, None, proto::nord::ArrayElement::new(1).ok())
                        .ok()
                })
                .unwrap_or(0)
        });
        let ms = u64::from(self.consumer as u16);
        let since = match p120 {
            _ if ms == 0 || self.state == NmtState::Initialisation => None,
            1 => self.watch.heard,
            2 => Some(self.watch.heard.unwrap_or(self.watch.booted)),
            _ => None,
        };
        self.watch.deadline = since
            .filter(|_| !self.watch.tripped)
            .map(|t| t + Duration::from_millis(ms));
        if self.watch.deadline.is_some_and(|d| d <= now) {
            self.watch.tripped = true;
            self.watch.deadline = None;
            let _ = device.lose_interface(self.fi);
        }
    }

    fn frame(&self, function: Function, data: &[u8]) -> Option<CanFrame> {
        let id = function.cob_id(self.id).ok()?;
        CanFrame::new(id, data).ok()
    }

    /// Boot-up when initialisation ends, heartbeats when due.
    pub(super) fn poll(&mut self, now: Duration) -> Vec<CanFrame> {
        let Some(due) = self.due.filter(|d| *d <= now) else {
            return Vec::new();
        };
        let message = if self.state == NmtState::Initialisation {
            self.state = NmtState::PreOperational;
            self.watch = Watch {
                booted: now,
                ..Watch::default()
            };
            ErrorControl::BOOT_UP
        } else {
            ErrorControl::heartbeat(self.state)
        };
        self.due = (self.heartbeat_ms > 0)
            .then(|| due.max(now) + Duration::from_millis(u64::from(self.heartbeat_ms)));
        self.frame(Function::ErrorControl, &message.emit())
            .into_iter()
            .collect()
    }

    /// An EMCY for the inverter's present error `p700` (0: the error went), of extended
    /// code `extended` (P700 [-04]).
    pub(super) fn emergency(&mut self, p700: i32, extended: Option<u16>) -> Option<CanFrame> {
        let emcy = emergency_of(p700, extended, self.fi);
        self.error_register = emcy.register;
        if matches!(self.state, NmtState::Stopped | NmtState::Initialisation) {
            return None;
        }
        self.frame(Function::Emcy, &emcy.emit())
    }

    /// What the node answers to `frame`.
    pub(super) fn receive(
        &mut self,
        frame: &CanFrame,
        device: &mut Device,
        now: Duration,
    ) -> Vec<CanFrame> {
        let Some(cob) = Cob::classify(frame.id()) else {
            return Vec::new();
        };
        if cob.function == Function::Sync {
            return match SyncFrame::parse(frame.data()) {
                Ok(_) if !frame.is_remote() => self.sync(device, now),
                _ => Vec::new(),
            };
        }
        self.answer(frame, cob, device, now).into_iter().collect()
    }

    /// The one frame, if any, the node answers to a frame other than SYNC.
    fn answer(
        &mut self,
        frame: &CanFrame,
        cob: Cob,
        device: &mut Device,
        now: Duration,
    ) -> Option<CanFrame> {
        match cob.function {
            Function::Nmt => {
                let nmt = NmtFrame::parse(frame.data()).ok()?;
                if nmt.node == 0 || nmt.node == self.id {
                    self.command(nmt, now);
                }
                None
            }
            Function::ErrorControl if cob.node == self.id && frame.is_remote() => {
                // Node guarding: the state with the toggle bit, alternating.
                let mut answer = ErrorControl::heartbeat(self.state);
                answer.toggle = self.guard_toggle;
                self.guard_toggle = !self.guard_toggle;
                self.frame(Function::ErrorControl, &answer.emit())
            }
            Function::SdoRx if cob.node == self.id => {
                // SDO is served in Pre-operational and Operational only; an SDO frame is 8
                // bytes, a shorter one is no SDO request (CiA 301 §7.2.4.3.1).
                if !matches!(self.state, NmtState::PreOperational | NmtState::Operational)
                    || frame.is_remote()
                    || frame.data().len() != 8
                {
                    return None;
                }
                self.p120 = None;
                let mut od = Dictionary { node: self, device };
                let mut sdo = std::mem::take(&mut od.node.sdo);
                let answer = sdo.serve(frame.data(), &mut od);
                self.sdo = sdo;
                self.frame(Function::SdoTx, &answer?.emit())
            }
            Function::Rpdo { .. } if cob.node == self.id => {
                // PDOs only in Operational; a remote frame requests no RPDO.
                if self.state != NmtState::Operational || frame.is_remote() {
                    return None;
                }
                // Fewer bytes than mapped: not processed; more: processed. An EMCY says which
                // (CiA 301).
                match self.pdo.receive(cob.function, frame.data()) {
                    Ok(Read::Exact) | Err(PdoError::NotMapped) => None,
                    Ok(Read::Longer) => self.pdo_length_error(PDO_TOO_LONG),
                    Err(PdoError::TooShort) => self.pdo_length_error(PDO_TOO_SHORT),
                }
            }
            _ => None,
        }
    }

    /// The EMCY of a communication error `code` of its CAN controller (CiA 301 8120h, 8140h):
    /// none in Stopped or Initialisation, where EMCY is not sent (CiA 301 §7.3.2.2).
    pub(super) fn communication_error(&self, code: u16) -> Option<CanFrame> {
        if matches!(self.state, NmtState::Stopped | NmtState::Initialisation) {
            return None;
        }
        self.pdo_length_error(code)
    }

    /// The EMCY of an RPDO of the wrong length.
    fn pdo_length_error(&self, code: u16) -> Option<CanFrame> {
        let emcy = Emergency {
            code,
            register: self.error_register | register::GENERIC | register::COMMUNICATION,
            data: [0; 5],
        };
        self.frame(Function::Emcy, &emcy.emit())
    }

    /// SYNC: the inverter takes the control word and setpoints the RPDOs brought and answers
    /// with its TPDOs, once its process data started (an RPDO1 in Operational). The node is
    /// the inverter itself: the words go to its drive ([`Device::drive_process`]).
    fn sync(&mut self, device: &mut Device, now: Duration) -> Vec<CanFrame> {
        if self.state != NmtState::Operational {
            return Vec::new();
        }
        let fi = self.fi;
        self.pdo.sync(self.id, |control, setpoints| {
            device.drive_process(fi, control, setpoints, now).ok()
        })
    }

    fn command(&mut self, nmt: NmtFrame, now: Duration) {
        let Some(to) = self.state.on_command(nmt.command) else {
            return;
        };
        if to == NmtState::Initialisation {
            // Reset node / reset communication: the communication objects return to their
            // factory values and the node boots again.
            self.heartbeat_ms = 0;
            self.consumer = factory_consumer(self.product);
            self.guard_toggle = false;
            self.sdo.reset();
            self.due = Some(now);
        }
        if to != NmtState::Operational {
            // Out of Operational no PDO: the process data start again with an RPDO1.
            self.pdo.stop();
        }
        self.state = to;
    }
}

/// The node's objects, the inverter's parameters among them.
struct Dictionary<'a> {
    node: &'a mut Node,
    device: &'a mut Device,
}

impl Dictionary<'_> {
    /// The parameter objects of the node's inverter (of the SK 550P's interface, for its own
    /// parameters at FI 1): the store that has parameter `index` − 2000h.
    fn parameters(&mut self, index: u16) -> Result<ParameterObjects<'_>, SdoAbort> {
        let number =
            ParamNumber::new(i64::from(index - PARAMETERS)).map_err(|_| abort::NO_OBJECT)?;
        // The SK 550P's interface is built into FI 1: its P85x–P89x answer there.
        let integrated =
            self.node.fi.get() == 1 && self.node.product.family() == Family::Integrated;
        let interface = self
            .device
            .store(Unit::Interface)
            .is_ok_and(|s| s.def(number).is_some());
        let unit = match integrated && interface {
            true => Unit::Interface,
            false => Unit::Inverter(self.node.fi),
        };
        let store = self.device.store(unit).map_err(|_| abort::NO_OBJECT)?;
        Ok(ParameterObjects::new(store))
    }
}

impl Objects for Dictionary<'_> {
    fn upload(&mut self, index: u16, sub: u8) -> Result<Vec<u8>, SdoAbort> {
        match (index, sub) {
            (DEVICE_TYPE, 0) => Ok(0u32.to_le_bytes().to_vec()),
            (ERROR_REGISTER, 0) => Ok(vec![self.node.error_register]),
            (DEVICE_NAME, 0) => Ok(self.node.product.name().as_bytes().to_vec()),
            (HEARTBEAT_TIME, 0) => Ok(self.node.heartbeat_ms.to_le_bytes().to_vec()),
            (CONSUMER_HEARTBEAT, 0) => Ok(vec![1]),
            (CONSUMER_HEARTBEAT, 1) => Ok(self.node.consumer.to_le_bytes().to_vec()),
            (IDENTITY, 0) => Ok(vec![1]),
            (IDENTITY, 1) => Ok(proto::nord::ecat::VENDOR_ID.to_le_bytes().to_vec()),
            (
                DEVICE_TYPE | ERROR_REGISTER | DEVICE_NAME | CONSUMER_HEARTBEAT | HEARTBEAT_TIME
                | IDENTITY,
                _,
            ) => Err(abort::NO_SUBINDEX),
            (PARAMETERS..=LAST_PARAMETER, _) => self.parameters(index)?.upload(index, sub),
            _ => Err(abort::NO_OBJECT),
        }
    }

    fn download(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        match (index, sub) {
            (HEARTBEAT_TIME, 0) => {
                let ms = decode_number(data, proto::nord::ecat::DataType::U16)?;
                self.node.heartbeat_ms = ms as u16;
                // The first heartbeat at once, then one every `ms`.
                self.node.due = (ms > 0).then_some(Duration::ZERO);
                Ok(())
            }
            (CONSUMER_HEARTBEAT, 1) => {
                let value = decode_number(data, proto::nord::ecat::DataType::U32)? as u32;
                // A node-ID of 0 or above 127 is not valid (CiA 301 §7.5.2.32: value range).
                let node = (value >> 16) as u8;
                if value >> 24 != 0 || (value as u16 != 0 && !(1..=127).contains(&node)) {
                    return Err(abort::VALUE_RANGE);
                }
                self.node.consumer = value;
                self.node.watch.tripped = false;
                Ok(())
            }
            (DEVICE_TYPE | ERROR_REGISTER | DEVICE_NAME | IDENTITY | CONSUMER_HEARTBEAT, 0)
            | (IDENTITY, 1) => Err(abort::READ_ONLY),
            (
                DEVICE_TYPE | ERROR_REGISTER | DEVICE_NAME | CONSUMER_HEARTBEAT | HEARTBEAT_TIME
                | IDENTITY,
                _,
            ) => Err(abort::NO_SUBINDEX),
            (PARAMETERS..=LAST_PARAMETER, _) => self.parameters(index)?.download(index, sub, data),
            _ => Err(abort::NO_OBJECT),
        }
    }
}

/// 1016h:01 at power-on: the interface's heartbeat, watched for 600 ms (not stated by the
/// manuals, `proto::nord::can::InterfaceWatch`).
fn factory_consumer(product: Product) -> u32 {
    interface_watch(product).consumer_entry()
}
