//! The application relation and the RPC calls of the context management (IEC 61158-6-10
//! "IPNIO_Connect", "_Control", "_Release", "_Read", "_Write", "_ReadImplicit").
//!
//! Connect checks the controller's blocks (one IOCARSingle AR, one input and one output IO
//! CR of RT class 1, one alarm CR, the expected submodules) against the product's slots
//! ([`def::slot_role`], [`def::module_by_ident`]): a module that is not the one the slot can
//! take is answered in a ModuleDiffBlock and the AR comes up without it, as PROFINET devices
//! do; a malformed request is refused with the PNIO status naming the block and field. Then
//! PrmEnd, and the device's own ApplicationReady call to the controller; once it is
//! confirmed the AR runs. A second controller gets "out of AR resources".
//!
//! Beside it the device keeps one DeviceAccess AR ([`Access`]): what engineering tools open
//! to read and write records without I/O. Reads outside any AR are ReadImplicit.

use std::net::SocketAddr;
use std::time::Duration;

use proto::eth::MacAddr;
use proto::nord::pnio::{self as def, ModuleKind, SlotRole};
use proto::nord::Inverter;
use proto::pnio::block::{ar_properties, iocr_properties, ArBlockReq, BlockType, ControlCommand};
use proto::pnio::block::{
    AlarmCrBlockRes, ArBlockRes, ArType, Block, DiffApi, DiffModule, DiffSubmodule,
    ExpectedSubmoduleBlockReq, IocrBlockReq, IocrBlockRes, IocrType, IodControl, IodReadRes,
    IodWriteRes, ModuleDiffBlock, ModuleState, SubmoduleState,
};
use proto::pnio::rpc::{NcaStatus, NdrRequest, NdrResponse, Opnum, PacketType, RpcRepr, Uuid};
use proto::pnio::status::cm;
use proto::pnio::{PnioStatus, RPC_PORT};

use super::alarms::AlarmCr;
use super::cyclic::{Cr, Image, Submodule};
use super::{IoDevice, Out};

/// How often the device calls ApplicationReady before it gives the AR up, and how long it
/// waits for each answer.
const APPL_READY_TRIES: u8 = 5;
const APPL_READY_WAIT: Duration = Duration::from_millis(500);
/// The device's alarm reference (its alarm CR endpoint).
const DEVICE_ALARM_REF: u16 = 0x0001;
/// The largest alarm data the device takes and sends (IEC 61158-6-10: 200…1432).
const MAX_ALARM_DATA: u16 = 200;
/// ArgsMaximum of the device's own calls.
const ARGS_MAXIMUM: u32 = 1024;

/// Where the AR is.
#[derive(Debug, Clone)]
enum ArState {
    /// Connected; the controller parameterises and ends with PrmEnd.
    AwaitPrmEnd,
    /// PrmEnd answered; the device's ApplicationReady call is out.
    ApplReady {
        request: Vec<u8>,
        activity: Uuid,
        sent: Duration,
        tries: u8,
    },
    /// ApplicationReady confirmed: data exchange.
    Running,
}

/// The application relation with one controller.
#[derive(Debug)]
pub(super) struct Ar {
    pub(super) uuid: Uuid,
    session_key: u16,
    pub(super) controller_mac: MacAddr,
    controller_rpc: SocketAddr,
    /// The controller's object (CMInitiatorObjectUUID), the target of ApplicationReady.
    controller_object: Uuid,
    state: ArState,
    pub(super) input: Cr,
    pub(super) output: Cr,
    pub(super) alarm: AlarmCr,
    /// The submodules as plugged, with what the controller expected.
    pub(super) submodules: Vec<Submodule>,
    /// The cyclic data of the submodules.
    pub(super) image: Image,
}

impl Ar {
    pub(super) fn running(&self) -> bool {
        matches!(self.state, ArState::Running)
    }

    /// What is due at `now`: ApplicationReady (again).
    pub(super) fn due(&mut self, now: Duration) -> Vec<Out> {
        let to = self.controller_rpc;
        match &mut self.state {
            ArState::ApplReady {
                request,
                sent,
                tries,
                ..
            } if now.saturating_sub(*sent) >= APPL_READY_WAIT && *tries < APPL_READY_TRIES => {
                *sent = now;
                *tries += 1;
                vec![Out::Datagram {
                    to,
                    bytes: request.clone(),
                }]
            }
            _ => Vec::new(),
        }
    }

    /// Whether the device gave up on ApplicationReady.
    pub(super) fn gave_up(&self, now: Duration) -> bool {
        matches!(&self.state, ArState::ApplReady { sent, tries, .. }
            if *tries >= APPL_READY_TRIES && now.saturating_sub(*sent) >= APPL_READY_WAIT)
    }
}

/// A DeviceAccess AR (IEC 61158-6-10: ARType IOSAR with ARProperties.DeviceAccess set): record
/// access without IO CRs, alarm CR or expected submodules, usable right after its Connect (no
/// PrmEnd). It ends with Release, or when its initiator has made no call for
/// CMInitiatorActivityTimeoutFactor × 100 ms, so a tool that vanished does not hold it.
#[derive(Debug)]
pub(super) struct Access {
    uuid: Uuid,
    session_key: u16,
    /// The initiator's last call.
    last: Duration,
    /// CMInitiatorActivityTimeoutFactor × 100 ms.
    timeout: Duration,
}

impl Access {
    /// Whether the initiator has been silent for longer than its activity time-out.
    pub(super) fn expired(&self, now: Duration) -> bool {
        now.saturating_sub(self.last) > self.timeout
    }
}

/// CMInitiatorActivityTimeoutFactor: 1…1000 (× 100 ms), IEC 61158-6-10.
const ACTIVITY_TIMEOUT_FACTORS: std::ops::RangeInclusive<u16> = 1..=1000;

/// A refused call: the PNIO status.
type Refusal = PnioStatus;

impl IoDevice {
    /// One RPC datagram from `from`.
    pub(super) fn rpc(&mut self, from: SocketAddr, datagram: &[u8], now: Duration) -> Vec<Out> {
        let Ok(req) = RpcRepr::parse_bytes(datagram) else {
            self.dropped += 1;
            return Vec::new();
        };
        let reply = |r: RpcRepr| match r.emit() {
            Ok(bytes) => vec![Out::Datagram { to: from, bytes }],
            Err(_) => Vec::new(),
        };
        match req.packet_type {
            PacketType::RESPONSE => {
                self.confirmed(&req);
                return Vec::new();
            }
            PacketType::REQUEST => {}
            // Pings, acks, cancels: nothing the device keeps state for.
            _ => return Vec::new(),
        }
        if req.interface != Uuid::PNIO_DEVICE_INTERFACE {
            return reply(req.reject(NcaStatus::UNK_IF));
        }
        let Ok(ndr) = NdrRequest::parse(&req.body, req.drep) else {
            return reply(req.reject(NcaStatus::PROTO_ERROR));
        };
        let answer = match req.opnum {
            Opnum::CONNECT => self.connect(&ndr, from, now),
            Opnum::CONTROL => self.control(&ndr, from),
            Opnum::RELEASE => self.release(&ndr),
            Opnum::READ | Opnum::READ_IMPLICIT => self.read(&ndr, req.opnum, now),
            Opnum::WRITE => self.write(&ndr, now),
            _ => return reply(req.reject(NcaStatus::OP_RNG_ERROR)),
        };
        let (status, blocks) = match answer {
            Ok(blocks) => (PnioStatus::OK, blocks),
            Err((status, blocks)) => (status, blocks),
        };
        let data = Block::emit_all(&blocks).unwrap_or_default();
        let Ok(body) = NdrResponse::answering(&ndr, status, data) else {
            return Vec::new();
        };
        let mut out = reply(req.reply(PacketType::RESPONSE, body.emit(req.drep)));
        if let Some(call) = self.appl_ready_call(now) {
            out.push(call);
        }
        out
    }

    /// Connect: the AR, its CRs and the module check.
    fn connect(
        &mut self,
        ndr: &NdrRequest,
        from: SocketAddr,
        now: Duration,
    ) -> Result<Vec<Block>, (Refusal, Vec<Block>)> {
        let refuse = |code1, code2| Err((PnioStatus::cm(cm::CONNECT, code1, code2), Vec::new()));
        let Ok(blocks) = Block::parse_all(&ndr.data) else {
            return refuse(cm::CMRPC, cm::CMRPC_UNKNOWN_BLOCKS);
        };
        let mut ar_req = None;
        let (mut iocrs, mut alarms, mut expected) = (Vec::new(), Vec::new(), Vec::new());
        for b in blocks {
            match b {
                Block::ArReq(a) if ar_req.is_none() => ar_req = Some(a),
                Block::IocrReq(c) => iocrs.push(c),
                Block::AlarmCrReq(a) => alarms.push(a),
                Block::ExpectedSubmoduleReq(e) => expected.push(e),
                _ => return refuse(cm::CMRPC, cm::CMRPC_UNKNOWN_BLOCKS),
            }
        }
        let Some(ar_req) = ar_req else {
            return refuse(cm::FAULTY_AR_BLOCK, 0);
        };
        let device_access = ar_req.properties & ar_properties::DEVICE_ACCESS != 0;
        match (ar_req.ar_type, device_access) {
            (ArType::IOS_AR, true) => {
                // Only the ARBlockReq: a DeviceAccess AR has no CRs and expects no modules.
                if !(iocrs.is_empty() && alarms.is_empty() && expected.is_empty()) {
                    return refuse(cm::CMRPC, cm::CMRPC_UNKNOWN_BLOCKS);
                }
                return self.connect_access(&ar_req, now);
            }
            (ArType::IOC_AR_SINGLE, false) => {}
            // Field 9: ARProperties — DeviceAccess is for an IOSAR only.
            (_, true) => return refuse(cm::FAULTY_AR_BLOCK, 9),
            // Field 4: ARType — an IOCARSingle, or an IOSAR for device access.
            _ => return refuse(cm::FAULTY_AR_BLOCK, 4),
        }
        if let Some(ar) = &self.ar {
            if ar.uuid != ar_req.ar_uuid {
                return refuse(cm::CMRPC, cm::CMRPC_OUT_OF_AR);
            }
            // The same AR again: the controller restarts it.
        }
        let input = iocrs.iter().find(|c| c.iocr_type == IocrType::INPUT);
        let output = iocrs.iter().find(|c| c.iocr_type == IocrType::OUTPUT);
        let (Some(input), Some(output)) = (input, output) else {
            return refuse(cm::CMRPC, cm::CMRPC_IOCR_MISSING);
        };
        if iocrs.len() != 2 {
            return refuse(cm::CMRPC, cm::CMRPC_IOCR_MISSING);
        }
        if alarms.len() != 1 {
            return refuse(cm::CMRPC, cm::CMRPC_ALARM_CR_COUNT);
        }
        let alarm_req = &alarms[0];
        if alarm_req.lt != proto::eth::ETHERTYPE_PROFINET {
            // Field 5: LT.
            return Err((
                PnioStatus::cm(cm::CONNECT, cm::FAULTY_ALARM_CR_BLOCK, 5),
                Vec::new(),
            ));
        }
        let (submodules, diff) = self.plug(&expected);
        // The consumer's frame ids: the controller's for the input CR; for the output CR the
        // controller's, or the device's choice where it left it open (FFFFh).
        let faulty = |field| {
            (
                PnioStatus::cm(cm::CONNECT, cm::FAULTY_IOCR_BLOCK, field),
                Vec::new(),
            )
        };
        let input_cr = check_iocr(input, input.frame_id, &submodules).map_err(faulty)?;
        let output_frame_id = match output.frame_id {
            FRAME_ID_OPEN => frame_ids(output.properties)
                .and_then(|mut ids| ids.find(|id| *id != input.frame_id))
                .ok_or_else(|| faulty(7))?,
            id => id,
        };
        let output_cr = check_iocr(output, output_frame_id, &submodules).map_err(|field| {
            (
                PnioStatus::cm(cm::CONNECT, cm::FAULTY_IOCR_BLOCK, field),
                Vec::new(),
            )
        })?;
        self.show_modules(&submodules);
        let ar = Ar {
            uuid: ar_req.ar_uuid,
            session_key: ar_req.session_key,
            controller_mac: ar_req.initiator_mac,
            controller_rpc: SocketAddr::new(from.ip(), RPC_PORT),
            controller_object: ar_req.initiator_object,
            state: ArState::AwaitPrmEnd,
            input: input_cr,
            output: output_cr,
            alarm: AlarmCr::new(alarm_req, DEVICE_ALARM_REF),
            image: Image::new(&submodules),
            submodules,
        };
        let mut answer = vec![
            Block::ArRes(ArBlockRes {
                ar_type: ar_req.ar_type,
                ar_uuid: ar_req.ar_uuid,
                session_key: ar_req.session_key,
                responder_mac: self.mac,
                udp_rt_port: proto::eth::ETHERTYPE_PROFINET,
            }),
            Block::IocrRes(IocrBlockRes {
                iocr_type: IocrType::INPUT,
                reference: input.reference,
                frame_id: ar.input.frame_id,
            }),
            Block::IocrRes(IocrBlockRes {
                iocr_type: IocrType::OUTPUT,
                reference: output.reference,
                frame_id: ar.output.frame_id,
            }),
            Block::AlarmCrRes(AlarmCrBlockRes {
                alarm_cr_type: alarm_req.alarm_cr_type,
                local_alarm_reference: DEVICE_ALARM_REF,
                max_alarm_data_length: MAX_ALARM_DATA,
            }),
        ];
        if !diff.apis.is_empty() {
            answer.push(Block::ModuleDiff(diff));
        }
        self.ar = Some(ar);
        self.lost = false;
        Ok(answer)
    }

    /// Connect of a DeviceAccess AR: the ARBlockRes alone. The device holds one; another
    /// initiator's gets "out of AR resources" until it is released or times out.
    fn connect_access(
        &mut self,
        req: &ArBlockReq,
        now: Duration,
    ) -> Result<Vec<Block>, (Refusal, Vec<Block>)> {
        if !ACTIVITY_TIMEOUT_FACTORS.contains(&req.activity_timeout_factor) {
            // Field 10: CMInitiatorActivityTimeoutFactor.
            return Err((
                PnioStatus::cm(cm::CONNECT, cm::FAULTY_AR_BLOCK, 10),
                Vec::new(),
            ));
        }
        if let Some(held) = self.access.as_ref().filter(|a| !a.expired(now)) {
            if held.uuid != req.ar_uuid {
                return Err((
                    PnioStatus::cm(cm::CONNECT, cm::CMRPC, cm::CMRPC_OUT_OF_AR),
                    Vec::new(),
                ));
            }
        }
        self.access = Some(Access {
            uuid: req.ar_uuid,
            session_key: req.session_key,
            last: now,
            timeout: Duration::from_millis(100) * u32::from(req.activity_timeout_factor),
        });
        Ok(vec![Block::ArRes(ArBlockRes {
            ar_type: req.ar_type,
            ar_uuid: req.ar_uuid,
            session_key: req.session_key,
            responder_mac: self.mac,
            udp_rt_port: proto::eth::ETHERTYPE_PROFINET,
        })])
    }

    /// Whether `uuid` names an AR the device holds (the IO AR or the DeviceAccess AR); a
    /// call in the DeviceAccess AR keeps it alive.
    fn holds(&mut self, uuid: Uuid, now: Duration) -> bool {
        if let Some(access) = self.access.as_mut().filter(|a| a.uuid == uuid) {
            access.last = now;
            return true;
        }
        self.ar.as_ref().is_some_and(|a| a.uuid == uuid)
    }

    /// The expected submodules against the product's slots: what is plugged, and the
    /// differences the controller is told.
    fn plug(&self, expected: &[ExpectedSubmoduleBlockReq]) -> (Vec<Submodule>, ModuleDiffBlock) {
        let inverters = self.device.config().inverters;
        let mut subs = Vec::new();
        let mut diff = DiffApi {
            api: 0,
            modules: Vec::new(),
        };
        for api in expected.iter().flat_map(|e| &e.apis) {
            let role = def::slot_role(self.product, api.slot);
            let (module_ok, kind) = match role {
                Some(SlotRole::Dap) => (api.module_ident == def::DAP_MODULE_IDENT, None),
                Some(SlotRole::Inverter(fi)) if fi.get() <= inverters => {
                    match def::module_by_ident(self.product, api.module_ident) {
                        Some(m) if def::fits(self.product, api.slot, m.kind) => (true, Some(m)),
                        _ => (false, None),
                    }
                }
                Some(SlotRole::BusModule) => {
                    match def::module_by_ident(self.product, api.module_ident) {
                        Some(m) if m.kind == ModuleKind::DigIo => (true, Some(m)),
                        _ => (false, None),
                    }
                }
                _ => (false, None),
            };
            let present = !matches!(role, None | Some(SlotRole::Reserved))
                && !matches!(role, Some(SlotRole::Inverter(fi)) if fi.get() > inverters);
            let mut diff_subs = Vec::new();
            for s in &api.submodules {
                let sub_ok = module_ok
                    && match (role, kind) {
                        (Some(SlotRole::Dap), _) => dap_submodule(s.subslot, s.ident),
                        (_, Some(m)) => {
                            s.subslot == def::IO_SUBSLOT && s.ident == m.submodule_ident
                        }
                        _ => false,
                    };
                let (mut input_len, mut output_len) = (0, 0);
                for d in &s.data {
                    if d.direction == proto::pnio::block::DataDirection::INPUT {
                        input_len = usize::from(d.length);
                    } else {
                        output_len = usize::from(d.length);
                    }
                }
                let fi = match (role, kind) {
                    (Some(SlotRole::Inverter(fi)), Some(m)) if sub_ok => match m.kind {
                        ModuleKind::Ppo(t) => Some((fi, t)),
                        ModuleKind::DigIo => None,
                    },
                    _ => None,
                };
                let lengths_ok = match kind {
                    Some(m) if sub_ok => input_len == m.input_len && output_len == m.output_len,
                    _ => true,
                };
                let proper = sub_ok && lengths_ok;
                subs.push(Submodule {
                    slot: api.slot,
                    subslot: s.subslot,
                    input_len,
                    output_len,
                    proper,
                    fi,
                });
                if !proper {
                    diff_subs.push(DiffSubmodule {
                        subslot: s.subslot,
                        ident: s.ident,
                        state: if present && module_ok {
                            SubmoduleState::wrong()
                        } else {
                            SubmoduleState::no_submodule()
                        },
                    });
                }
            }
            if !diff_subs.is_empty() || !module_ok {
                diff.modules.push(DiffModule {
                    slot: api.slot,
                    ident: api.module_ident,
                    state: match (present, module_ok) {
                        (false, _) => ModuleState::NO_MODULE,
                        (true, false) => ModuleState::WRONG_MODULE,
                        (true, true) => ModuleState::PROPER_MODULE,
                    },
                    submodules: diff_subs,
                });
            }
        }
        let apis = if diff.modules.is_empty() {
            Vec::new()
        } else {
            vec![diff]
        };
        (subs, ModuleDiffBlock { apis })
    }

    /// The PPO-type display of every inverter slot (SK 550P P879 [-n]: 3 = empty slot, 6…10
    /// the PPO types; SK TU3-PNT P180 [-03]).
    fn show_modules(&mut self, subs: &[Submodule]) {
        let product = self.product;
        let plugged = |fi: Inverter| {
            subs.iter().find_map(|s| {
                s.fi.filter(|(f, _)| *f == fi)
                    .map(|(_, t)| ModuleKind::Ppo(t))
            })
        };
        let inverters = self.device.config().inverters;
        let Ok(store) = self.device.store(crate::link::Unit::Interface) else {
            return;
        };
        for n in 1..=inverters {
            let Ok(fi) = Inverter::new(i64::from(n)) else {
                continue;
            };
            if let (Ok((number, element)), Some(value)) = (
                def::ppo_display(product, fi),
                def::slot_display(product, plugged(fi)),
            ) {
                store.set_info(number, element, i32::from(value));
            }
        }
    }

    /// Control: PrmEnd from the controller (then the device calls ApplicationReady).
    fn control(
        &mut self,
        ndr: &NdrRequest,
        from: SocketAddr,
    ) -> Result<Vec<Block>, (Refusal, Vec<Block>)> {
        let refuse = |code1, code2| Err((PnioStatus::cm(cm::CONTROL, code1, code2), Vec::new()));
        let Ok(blocks) = Block::parse_all(&ndr.data) else {
            return refuse(cm::CMRPC, cm::CMRPC_UNKNOWN_BLOCKS);
        };
        let Some(Block::Control(c)) = blocks.into_iter().next() else {
            return refuse(cm::CMRPC, cm::CMRPC_UNKNOWN_BLOCKS);
        };
        if c.block_type != BlockType::PRM_END_REQ || c.command != ControlCommand::PRM_END {
            // Field 8: ControlCommand (the checking rules of ControlBlockConnect number the
            // fields BlockType 0 … Padding 4, ARUUID 5, SessionKey 6, Padding 7,
            // ControlCommand 8, ControlBlockProperties 9; p-net and Wireshark agree).
            return refuse(cm::FAULTY_CONTROL_BLOCK, 8);
        }
        let Some(ar) = self.ar.as_mut().filter(|a| a.uuid == c.ar_uuid) else {
            return refuse(cm::CMRPC, cm::CMRPC_AR_UNKNOWN);
        };
        if c.session_key != ar.session_key {
            // Field 6: SessionKey.
            return refuse(cm::FAULTY_CONTROL_BLOCK, 6);
        }
        if !matches!(ar.state, ArState::AwaitPrmEnd) {
            return refuse(cm::CMRPC, cm::CMRPC_STATE_CONFLICT);
        }
        ar.controller_rpc = SocketAddr::new(from.ip(), RPC_PORT);
        self.calls += 1;
        let activity = Uuid::of_sender(0x4E4F_5244, 0, self.mac, self.calls as u16);
        let body = Block::emit_all(&[Block::Control(IodControl::application_ready(
            ar.uuid,
            ar.session_key,
        ))])
        .ok()
        .and_then(|data| NdrRequest::new(ARGS_MAXIMUM, data).ok());
        if let Some(body) = body {
            let req = RpcRepr::request(
                ar.controller_object,
                Uuid::PNIO_CONTROLLER_INTERFACE,
                activity,
                0,
                Opnum::CONTROL,
                body.emit(proto::pnio::rpc::Drep::LITTLE_ENDIAN),
            );
            if let Ok(request) = req.emit() {
                ar.state = ArState::ApplReady {
                    request,
                    activity,
                    sent: Duration::MAX,
                    tries: 0,
                };
            }
        }
        Ok(vec![Block::Control(c.done())])
    }

    /// The ApplicationReady call, when it is to go out right after PrmEnd's answer.
    fn appl_ready_call(&mut self, now: Duration) -> Option<Out> {
        let ar = self.ar.as_mut()?;
        let to = ar.controller_rpc;
        match &mut ar.state {
            ArState::ApplReady {
                request,
                sent,
                tries,
                ..
            } if *sent == Duration::MAX => {
                *sent = now;
                *tries = 1;
                Some(Out::Datagram {
                    to,
                    bytes: request.clone(),
                })
            }
            _ => None,
        }
    }

    /// The controller's answer to ApplicationReady: the AR runs.
    fn confirmed(&mut self, res: &RpcRepr) {
        let Some(ar) = self.ar.as_mut() else {
            return;
        };
        let ArState::ApplReady { activity, .. } = &ar.state else {
            return;
        };
        if res.activity != *activity {
            return;
        }
        let ok = NdrResponse::parse(&res.body, res.drep)
            .ok()
            .filter(|r| r.status.is_ok())
            .and_then(|r| Block::parse_all(&r.data).ok())
            .is_some_and(|b| {
                b.iter().any(|b| {
                    matches!(b, Block::Control(c) if c.block_type == BlockType::APPLICATION_READY_RES)
                })
            });
        if ok {
            ar.state = ArState::Running;
        }
    }

    /// Release: the AR ends.
    fn release(&mut self, ndr: &NdrRequest) -> Result<Vec<Block>, (Refusal, Vec<Block>)> {
        let refuse = |code1, code2| Err((PnioStatus::cm(cm::RELEASE, code1, code2), Vec::new()));
        let Ok(blocks) = Block::parse_all(&ndr.data) else {
            return refuse(cm::CMRPC, cm::CMRPC_UNKNOWN_BLOCKS);
        };
        let Some(Block::Control(c)) = blocks.into_iter().next() else {
            return refuse(cm::CMRPC, cm::CMRPC_UNKNOWN_BLOCKS);
        };
        // The release block is numbered as the control block: ControlCommand field 8,
        // SessionKey field 6.
        if c.block_type != BlockType::RELEASE_REQ || c.command != ControlCommand::RELEASE {
            return refuse(cm::FAULTY_RELEASE_BLOCK, 8);
        }
        if let Some(access) = self.access.as_ref().filter(|a| a.uuid == c.ar_uuid) {
            if access.session_key != c.session_key {
                return refuse(cm::FAULTY_RELEASE_BLOCK, 6);
            }
            self.access = None;
            return Ok(vec![Block::Control(c.done())]);
        }
        match &self.ar {
            Some(ar) if ar.uuid == c.ar_uuid && ar.session_key == c.session_key => {}
            Some(ar) if ar.uuid == c.ar_uuid => return refuse(cm::FAULTY_RELEASE_BLOCK, 6),
            _ => return refuse(cm::CMRPC, cm::CMRPC_AR_UNKNOWN),
        }
        self.ar = None;
        Ok(vec![Block::Control(c.done())])
    }

    /// IODRead (in an AR, or implicit without one).
    fn read(
        &mut self,
        ndr: &NdrRequest,
        op: Opnum,
        now: Duration,
    ) -> Result<Vec<Block>, (Refusal, Vec<Block>)> {
        let read_error = PnioStatus::record(false, proto::pnio::status::pniorw::READ_ERROR);
        let Ok(blocks) = Block::parse_all(&ndr.data) else {
            return Err((read_error, Vec::new()));
        };
        let Some(Block::ReadReq(r)) = blocks.into_iter().next() else {
            return Err((read_error, Vec::new()));
        };
        let implicit = op == Opnum::READ_IMPLICIT;
        if !implicit && !self.holds(r.addr.ar_uuid, now) {
            return Err((
                PnioStatus::cm(0xDE, cm::CMRPC, cm::CMRPC_AR_UNKNOWN),
                Vec::new(),
            ));
        }
        let a = r.addr;
        let answer = |data: Vec<u8>| {
            Block::ReadRes(IodReadRes {
                addr: a,
                additional_value1: 0,
                additional_value2: 0,
                data,
            })
        };
        let data = if a.index == proto::pnio::im0::INDEX {
            super::im0::read(self.product, self.mac, a.slot, a.subslot)
        } else {
            self.records
                .read(&mut self.device, a.slot, a.subslot, a.index)
        };
        match data {
            Ok(data) => Ok(vec![answer(data)]),
            Err(status) => Err((status, vec![answer(Vec::new())])),
        }
    }

    /// IODWrite in an AR.
    fn write(
        &mut self,
        ndr: &NdrRequest,
        now: Duration,
    ) -> Result<Vec<Block>, (Refusal, Vec<Block>)> {
        let write_error = PnioStatus::record(true, proto::pnio::status::pniorw::WRITE_ERROR);
        let Ok(blocks) = Block::parse_all(&ndr.data) else {
            return Err((write_error, Vec::new()));
        };
        let Some(Block::WriteReq(w)) = blocks.into_iter().next() else {
            return Err((write_error, Vec::new()));
        };
        if !self.holds(w.addr.ar_uuid, now) {
            return Err((
                PnioStatus::cm(0xDF, cm::CMRPC, cm::CMRPC_AR_UNKNOWN),
                Vec::new(),
            ));
        }
        let a = w.addr;
        let status = match self
            .records
            .write(&mut self.device, a.slot, a.subslot, a.index, &w.data)
        {
            Ok(()) => PnioStatus::OK,
            Err(s) => s,
        };
        let res = Block::WriteRes(IodWriteRes {
            addr: a,
            record_data_length: w.data.len() as u32,
            additional_value1: 0,
            additional_value2: 0,
            status,
        });
        if status.is_ok() {
            Ok(vec![res])
        } else {
            Err((status, vec![res]))
        }
    }
}

/// The DAP's submodules: the DAP itself in subslot 1, the interface in 8000h, the ports.
fn dap_submodule(subslot: u16, ident: u32) -> bool {
    match subslot {
        def::DAP_SUBSLOT => ident == def::DAP_SUBMODULE_IDENT,
        def::INTERFACE_SUBSLOT => ident == def::INTERFACE_SUBMODULE_IDENT,
        s => def::PORT_SUBSLOTS
            .iter()
            .zip(def::PORT_SUBMODULE_IDENTS)
            .any(|(p, i)| *p == s && i == ident),
    }
}

/// The longest watchdog and data hold time of an RT class 1/2 CR, in µs (1.92 s).
const MAX_HOLD_US: u64 = 1_920_000;

/// The FrameID an IOCRBlockReq leaves for the device to choose.
const FRAME_ID_OPEN: u16 = 0xFFFF;

/// The unicast frame ids of the RT class an IOCRProperties declares, for the classes the
/// device runs (IEC 61158-6-10, the FrameID table): RT_CLASS_1 (the legacy value) C000h–F7FFh,
/// RT_CLASS_2 8000h–BBFFh. `None` for RT_CLASS_3, RT_CLASS_UDP and reserved values.
fn frame_ids(properties: u32) -> Option<std::ops::RangeInclusive<u16>> {
    match properties & iocr_properties::RT_CLASS_MASK {
        iocr_properties::RT_CLASS_1 => Some(proto::pnio::FrameId::RT_CLASS_1_UNICAST),
        iocr_properties::RT_CLASS_2 => Some(proto::pnio::FrameId::RT_CLASS_2_UNICAST),
        _ => None,
    }
}

/// An IO CR the device can run, or the field (its position in the IOCRBlockReq, BlockType =
/// 0) that it cannot: 6 LT, 7 IOCRProperties (RT_CLASS_1 or RT_CLASS_2 only), 8 DataLength
/// (40…1440 and room for every entry), 9 FrameID (in the range of the declared RT class:
/// C000h–F7FFh for RT_CLASS_1, 8000h–BBFFh for RT_CLASS_2, as IEC 61158-6-10 assigns them; a
/// frame id of the other class is refused, as p-net refuses it), 10 SendClockFactor, 11
/// ReductionRatio, 15 WatchdogFactor, 16 DataHoldFactor (its time at most 1.92 s).
fn check_iocr(req: &IocrBlockReq, frame_id: u16, subs: &[Submodule]) -> Result<Cr, u8> {
    if req.lt != proto::eth::ETHERTYPE_PROFINET {
        return Err(6);
    }
    let Some(ids) = frame_ids(req.properties) else {
        return Err(7);
    };
    let len = usize::from(req.data_length);
    if !(proto::pnio::rt::MIN_C_SDU..=proto::pnio::rt::MAX_C_SDU).contains(&len) {
        return Err(8);
    }
    if !ids.contains(&frame_id) {
        return Err(9);
    }
    if !(1..=128).contains(&req.send_clock_factor) || !req.send_clock_factor.is_power_of_two() {
        return Err(10);
    }
    if !(1..=512).contains(&req.reduction_ratio) {
        return Err(11);
    }
    if !(1..=7680).contains(&req.watchdog_factor) {
        return Err(15);
    }
    // The data hold time, DataHoldFactor × ReductionRatio × SendClockFactor × 31.25 µs, is at
    // most 1.92 s for RT classes 1 and 2 (IEC 61158-6-10; p-net checks the same).
    // (WatchdogFactor, the legacy field, has no such bound here, nor in p-net.)
    let hold_us = u64::from(req.data_hold_factor)
        * u64::from(req.reduction_ratio)
        * u64::from(req.send_clock_factor)
        * 3125
        / 100;
    if !(1..=7680).contains(&req.data_hold_factor) || hold_us > MAX_HOLD_US {
        return Err(16);
    }
    Cr::new(req, frame_id, subs).ok_or(8)
}
