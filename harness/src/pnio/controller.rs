//! The harness as PROFINET IO controller of one device: DCP to find and name it, the context
//! management calls over RPC (Connect, PrmEnd, the device's ApplicationReady, Release, record
//! read/write), the cyclic RT exchange and the alarm CR.
//!
//! Everything goes through one [`Controller::pump`]: while the controller waits for an RPC
//! answer, a DCP response or the next cycle, it keeps sending the output CR's frame every
//! cycle (a device whose watchdog sees no outputs ends the AR), takes the input CR's frames,
//! acknowledges alarm PDUs at transport level and queues their notifications, and answers
//! the device's own ApplicationReady call.
//!
//! Every wait for the device is its limit on the link's clock ([`crate::net::wait::Wait`]: on
//! a network moved by the time the host lost meanwhile): an RPC answer and a DCP response
//! within the harness's `--timeout` (IEC 61158-6-10 leaves the controller's RPC and DCP
//! time-outs to it), a by-name Identify within [`IDENTIFY_WINDOW`], each cycle's input within
//! the input CR's data hold time ([`Controller::data_hold`]). A limit that passes is
//! [`PnioError::NoReply`] with the limit and the time waited, which the binding reports as the
//! device being late.

use std::collections::VecDeque;
use std::net::SocketAddr;
use std::time::Duration;

use proto::eth::{EthernetFrame, EthernetRepr, MacAddr, ETHERTYPE_PROFINET};
use proto::nord::pnio::IpSuite;
use proto::pnio::alarm::{AlarmAck, AlarmNotification, AlarmRepr, RtaBody, RtaPduType};
use proto::pnio::block::ar_properties;
use proto::pnio::block::{
    iocr_properties, AlarmCrBlockReq, AlarmCrType, ArBlockReq, ArType, Block, BlockType,
    IocrBlockReq, IocrType, IodControl, IodReadReq, IodWriteReq, ModuleDiffBlock, RecordAddress,
};
use proto::pnio::dcp::{BlockError, BlockValue, DcpBlock, DcpRepr, ServiceId};
use proto::pnio::plan::{ExpectedSub, Plan};
use proto::pnio::rpc::{
    Drep, NcaStatus, NdrRequest, NdrResponse, Opnum, PacketType, RpcRepr, Uuid,
};
use proto::pnio::rt::{DataStatus, Iox, RtRepr};
use proto::pnio::status::cm;
use proto::pnio::{FrameId, FrameKind, PnioStatus, MULTICAST_DCP_IDENTIFY};

use super::consumer::{Consumer, StoodStill};
use super::link::Link;
use crate::hex::hex;
use crate::net::wait::Wait;
use crate::net::LinkError;
use crate::outcome::Exchange;

/// The controller's alarm reference.
const ALARM_REF: u16 = 0x0003;
/// AckSeqNum before any alarm PDU came (IEC 61158-6-10); the first SendSeqNum due is 0.
const NOTHING_RECEIVED: u16 = 0xFFFE;
/// The frame ids of the controller's CRs, which declare RT_CLASS_2 in their IOCRProperties:
/// unicast RT_CLASS_2 ids, 8000h–BBFFh (IEC 61158-6-10, the FrameID table; C000h–F7FFh would
/// be RT_CLASS_1's, which a device refuses under RT_CLASS_2). The input CR's is the one its
/// frames come with; the output CR's is proposed, and the device's IOCRBlockRes says which.
const INPUT_FRAME_ID: u16 = 0x8000;
const OUTPUT_FRAME_ID: u16 = 0x8001;
/// SendClockFactor 32: a 1 ms send clock.
const SEND_CLOCK_FACTOR: u16 = 32;
/// The watchdog time: how long the device waits without output frames before it gives the AR
/// up, and the data hold time of both CRs (how long a consumer keeps the last valid data). 100
/// ms, not the 3 cycles a PLC with a real-time scheduler uses: the harness is a process on a
/// shared host, and being descheduled for a few milliseconds is not losing the controller. A
/// time rather than a number of cycles, so that it stays the same at any reduction ratio (the
/// embedded run's 4 ms cycle, `?rr=N`). The watchdog steps wait longer than this.
const HOLD_TIME_MS: u16 = 100;
/// The fewest cycles of a watchdog or data hold factor: one late frame is not a lost AR.
const MIN_HOLD_FACTOR: u16 = 3;
/// The longest watchdog and data hold time of an RT CR, in send clocks of 1 ms: IEC
/// 61158-6-10 bounds factor × ReductionRatio × SendClockFactor × 31.25 µs by 1.92 s (p-net
/// refused 100 cycles at ReductionRatio 128 with DB 81 02 10, docs/interop.md).
const MAX_HOLD_CLOCKS: u16 = 1920;

/// The WatchdogFactor and DataHoldFactor at reduction ratio `rr`: the cycles of
/// [`HOLD_TIME_MS`], at least [`MIN_HOLD_FACTOR`], fewer where that would pass the standard's
/// 1.92 s.
fn hold_factor(rr: u16) -> u16 {
    let rr = rr.max(1);
    HOLD_TIME_MS
        .div_ceil(rr)
        .max(MIN_HOLD_FACTOR)
        .min(MAX_HOLD_CLOCKS / rr)
        .max(1)
}
/// ArgsMaximum the controller offers for answers.
const ARGS_MAXIMUM: u32 = 4096;
/// The longest a DCP Identify collects answers on a network (the embedded device answers at
/// once).
const IDENTIFY_WINDOW: Duration = Duration::from_millis(400);

/// Why a controller request failed.
#[derive(Debug, thiserror::Error)]
pub(crate) enum PnioError {
    /// The link broke.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// Nothing answered within the device's limit.
    #[error(
        "no {what} from the device within its limit of {} (waited {})",
        crate::timing::ms(*limit),
        crate::timing::ms(*waited)
    )]
    NoReply {
        what: &'static str,
        limit: Duration,
        waited: Duration,
    },
    /// No input frame has come since the AR started.
    #[error("no input frame from the device yet")]
    NoInput,
    /// The answer broke the protocol.
    #[error("malformed {what}: {error}")]
    Malformed { what: &'static str, error: String },
    /// The RPC layer refused the call (reject or fault).
    #[error("RPC {packet} with status {status}")]
    Nca {
        packet: &'static str,
        status: NcaStatus,
    },
    /// No device answered Identify (by that name).
    #[error("no PROFINET IO device answered Identify{0}")]
    NotFound(String),
    /// The call needs an AR and there is none.
    #[error("no application relation is up (connect first)")]
    NotConnected,
    /// The input CR's data hold time expired on frames whose cycle counter did not move: the
    /// consumer's time-out, which ended the AR.
    #[error(transparent)]
    StoodStill(#[from] StoodStill),
}

/// A device as DCP Identify found it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Station {
    pub(crate) mac: MacAddr,
    pub(crate) name: String,
    pub(crate) ip: Option<IpSuite>,
    pub(crate) vendor_id: u16,
    pub(crate) device_id: u16,
    pub(crate) type_of_station: String,
}

impl Station {
    fn of(src: MacAddr, res: &DcpRepr) -> Station {
        let mut s = Station {
            mac: src,
            name: String::new(),
            ip: None,
            vendor_id: 0,
            device_id: 0,
            type_of_station: String::new(),
        };
        for b in res.blocks() {
            match &b.value {
                BlockValue::NameOfStation(n) => s.name = n.clone(),
                BlockValue::IpParameter(p) => {
                    s.ip = Some(IpSuite {
                        ip: p.ip,
                        mask: p.mask,
                        gateway: p.gateway,
                    })
                }
                BlockValue::DeviceId {
                    vendor_id,
                    device_id,
                } => (s.vendor_id, s.device_id) = (*vendor_id, *device_id),
                BlockValue::DeviceVendor(v) => s.type_of_station = v.clone(),
                _ => {}
            }
        }
        s
    }
}

/// An answered RPC call: its PNIO status and blocks.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Answer {
    pub(crate) status: PnioStatus,
    pub(crate) blocks: Vec<Block>,
}

/// The running application relation.
#[derive(Debug, Clone)]
struct Ar {
    uuid: Uuid,
    session_key: u16,
    plan: Plan,
    input_frame_id: u16,
    output_frame_id: u16,
    device_alarm_ref: u16,
    /// The output C_SDU sent every cycle.
    outputs: Vec<u8>,
    /// The last input frame with new data.
    inputs: Option<RtRepr>,
    /// Which input frames carry new data.
    consumer: Consumer,
    /// ApplicationReady came and was answered.
    ready: bool,
    /// The next alarm PDU's SendSeqNum, and the last one received.
    alarm_seq: u16,
    alarm_received: u16,
}

/// The cyclic traffic of a step, summed up for its transcript.
#[derive(Debug, Clone, Default)]
pub(crate) struct CycleLog {
    pub(crate) sent: u64,
    pub(crate) received: u64,
    pub(crate) last_sent: Vec<u8>,
    pub(crate) last_received: Vec<u8>,
}

/// The IO controller over a link.
pub(crate) struct Controller<L> {
    link: L,
    mac: MacAddr,
    timeout: Duration,
    /// What every wait's limit is multiplied by ([`Controller::set_patience`]).
    patience: u32,
    /// Whether the link runs on the real clock, where the host's own delays move a wait.
    real_time: bool,
    /// ReductionRatio of both CRs (the cycle is 1 ms × it).
    reduction_ratio: u16,
    station: Option<Station>,
    ar: Option<Ar>,
    /// The DeviceAccess AR this controller holds as an engineering tool would (its UUID and
    /// session key): record access without I/O.
    access: Option<(Uuid, u16)>,
    /// A DCP Set since [`Controller::take_unsure`] was last called may have changed the
    /// device's name or address unseen.
    unsure: bool,
    next_send: Duration,
    xid: u32,
    calls: u32,
    session_key: u16,
    /// Alarm notifications received and not yet acknowledged.
    alarms: VecDeque<AlarmNotification>,
    /// The alarm types the device's manual says it raises (`None`: any, for another maker's
    /// device); [`Controller::take_departure`].
    alarm_types: Option<&'static [u16]>,
    /// The first thing since the last look that the device did on its own and its manual or
    /// the standard rules out ([`Controller::take_departure`]).
    departure: Option<Departure>,
    exchanges: Vec<Exchange>,
    cycles: CycleLog,
    recording: bool,
    /// The last LLDP frame's payload (BU 0620 §2.5.3 topology detection) and how many came.
    lldp: Option<Vec<u8>>,
    lldp_frames: u64,
    /// The DAP's submodules a Connect expects: NORD's, or those of another maker's GSDML.
    dap: Vec<ExpectedSub>,
    /// The DCE RPC activity of this controller's calls, each with the next sequence number
    /// (DCE RPC's client activity). A device may tie the AR to the activity of its Connect:
    /// p-net raises its PrmEnd event only for a DControl of the Connect's activity, so a
    /// fresh activity per call left its application waiting (docs/interop.md).
    activity: Uuid,
}

/// Controllers of a device on the network made so far in this process: each gets an activity
/// of its own.
static CONTROLLERS: std::sync::atomic::AtomicU16 = std::sync::atomic::AtomicU16::new(1);

/// The number in the DCE RPC activity of a new controller. A device on the network (on the real
/// clock) outlives each controller, one per case: each controller of the process takes an
/// activity of its own, since a DCE RPC server may take calls of an activity it has served,
/// numbered from 0 again, for ones it has answered. The embedded device is made afresh with
/// each controller: activity 0, the same in every case, so a case's transcript does not depend
/// on the cases before it (a sharded run merges into the unsharded one).
fn activity_number(real_time: bool) -> u16 {
    if real_time {
        CONTROLLERS.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    } else {
        0
    }
}

impl<L: Link> Controller<L> {
    /// A controller with Ethernet address `mac` that waits `timeout` for each answer, on a link
    /// that runs on the real clock (a network) or not (the embedded device's virtual clock).
    pub(crate) fn new(link: L, mac: MacAddr, timeout: Duration, real_time: bool) -> Controller<L> {
        Controller {
            link,
            mac,
            timeout,
            patience: 1,
            real_time,
            reduction_ratio: 1,
            station: None,
            ar: None,
            access: None,
            unsure: false,
            next_send: Duration::ZERO,
            xid: 0x4E52_0000,
            calls: 0,
            session_key: 0,
            alarms: VecDeque::new(),
            alarm_types: Some(&proto::nord::pnio::ALARM_TYPES),
            departure: None,
            exchanges: Vec::new(),
            cycles: CycleLog::default(),
            recording: true,
            lldp: None,
            lldp_frames: 0,
            dap: proto::nord::pnio::expected_dap(),
            activity: Uuid::of_sender(0x4E52_4450, activity_number(real_time), mac, 0),
        }
    }

    /// The DAP's submodules a Connect expects from now on.
    pub(crate) fn set_dap(&mut self, dap: Vec<ExpectedSub>) {
        self.dap = dap;
    }

    /// The alarm types the device raises from now on (`None`: any).
    pub(crate) fn set_alarm_types(&mut self, types: Option<&'static [u16]>) {
        self.alarm_types = types;
    }

    /// The link, for the embedded device behind it.
    pub(crate) fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    /// The cycle: 1 ms × the reduction ratio.
    pub(crate) fn cycle(&self) -> Duration {
        Duration::from_micros(1000 * u64::from(self.reduction_ratio))
    }

    /// How long the device waits without output frames before it ends the AR.
    pub(crate) fn watchdog(&self) -> Duration {
        self.cycle() * u32::from(hold_factor(self.reduction_ratio))
    }

    /// The data hold time of the input CR (IEC 61158-6-10: DataHoldFactor × the cycle): the
    /// longest the device may leave the controller without a new input frame, its limit for
    /// each cycle's answer.
    pub(crate) fn data_hold(&self) -> Duration {
        self.cycle() * u32::from(hold_factor(self.reduction_ratio))
    }

    /// Sets the reduction ratio of the next Connect.
    pub(crate) fn set_reduction_ratio(&mut self, rr: u16) {
        self.reduction_ratio = rr.max(1);
    }

    /// The device found last, with the name and address it has as far as the controller set
    /// them.
    pub(crate) fn station(&self) -> Option<&Station> {
        self.station.as_ref()
    }

    /// Whether an AR is in data exchange.
    pub(crate) fn connected(&self) -> bool {
        self.ar.as_ref().is_some_and(|a| a.ready)
    }

    /// Turns transcript recording on or off (bring-up is not part of a case).
    pub(crate) fn set_recording(&mut self, on: bool) {
        self.recording = on;
    }

    /// The exchanges since the last call.
    pub(crate) fn take_exchanges(&mut self) -> Vec<Exchange> {
        std::mem::take(&mut self.exchanges)
    }

    /// The cyclic traffic since the last call.
    pub(crate) fn take_cycles(&mut self) -> CycleLog {
        std::mem::take(&mut self.cycles)
    }

    fn record(&mut self, sent_hex: &[u8], sent: String, received_hex: &[u8], received: String) {
        if self.recording {
            self.exchanges.push(Exchange {
                sent_hex: hex(sent_hex),
                sent,
                received_hex: hex(received_hex),
                received,
            });
        }
    }

    fn ethernet(&self, dst: MacAddr, payload: &[u8]) -> Vec<u8> {
        EthernetRepr {
            dst,
            src: self.mac,
            ethertype: ETHERTYPE_PROFINET,
        }
        .emit(payload)
    }

    // -----------------------------------------------------------------------------------------
    // The pump
    // -----------------------------------------------------------------------------------------

    /// Runs the cyclic exchange and takes what comes until `until`, or until `want` takes a
    /// frame or the RPC answer of `call` arrives — whichever is first.
    fn pump(
        &mut self,
        until: Duration,
        want: &dyn Fn(&[u8]) -> bool,
        call: Option<Uuid>,
    ) -> Result<Option<Got>, PnioError> {
        loop {
            let now = self.link.now();
            if now >= until {
                // The frame due now goes out with the next step's data.
                return Ok(None);
            }
            if self.ar.is_some() && now >= self.next_send {
                self.send_now()?;
            }
            if let Some(answer) = self.datagrams(call)? {
                return Ok(Some(Got::Answer(answer)));
            }
            let now = self.link.now();
            if now >= until {
                return Ok(None);
            }
            let mut wake = until;
            if self.ar.is_some() {
                wake = wake.min(self.next_send);
            }
            if call.is_some() {
                // Datagrams are looked at between frames: a short wait on the frames.
                wake = wake.min(now + POLL_SLICE);
            }
            let Some((frame, stamp)) = self.link.recv(wake.max(now))? else {
                continue;
            };
            let Ok(eth) = EthernetFrame::new_checked(&frame[..]) else {
                continue;
            };
            if eth.inner_ethertype() == proto::eth::ETHERTYPE_LLDP {
                self.lldp = Some(eth.inner_payload().to_vec());
                self.lldp_frames += 1;
                continue;
            }
            if eth.inner_ethertype() != ETHERTYPE_PROFINET {
                continue;
            }
            let payload = eth.inner_payload();
            if want(payload) {
                return Ok(Some(Got::Frame {
                    src: eth.src(),
                    payload: payload.to_vec(),
                    stamp,
                }));
            }
            let payload = payload.to_vec();
            self.cyclic_or_alarm(&payload, stamp)?;
        }
    }

    /// A wait of the device's `limit` from now.
    fn wait(&self, limit: Duration) -> Wait {
        Wait::new(self.link.now(), limit * self.patience, self.real_time)
    }

    /// Multiplies the limit of every wait from now on by `factor` (1: the device's own
    /// limits): a second look at a device that let a limit pass, to tell a late one from an
    /// absent one (`crate::net::wait::bring_up`).
    pub(crate) fn set_patience(&mut self, factor: u32) {
        self.patience = factor.max(1);
    }

    /// [`Controller::pump`] until `wait` is over.
    fn pump_within(
        &mut self,
        wait: &Wait,
        want: &dyn Fn(&[u8]) -> bool,
        call: Option<Uuid>,
    ) -> Result<Option<Got>, PnioError> {
        loop {
            let now = self.link.now();
            if wait.passed(now) {
                return Ok(None);
            }
            if let Some(got) = self.pump(wait.end(now), want, call)? {
                return Ok(Some(got));
            }
        }
    }

    /// `wait` for `what` passed.
    fn no_reply(&self, what: &'static str, wait: &Wait) -> PnioError {
        PnioError::NoReply {
            what,
            limit: wait.limit(),
            waited: wait.waited(self.link.now()),
        }
    }

    /// Lets `d` pass with the cycle running and returns the LLDP frames that came in that time
    /// (their number, the last one's payload).
    pub(crate) fn lldp_for(&mut self, d: Duration) -> Result<(u64, Option<Vec<u8>>), PnioError> {
        let before = self.lldp_frames;
        self.lldp = None;
        self.run_for(d)?;
        Ok((self.lldp_frames - before, self.lldp.take()))
    }

    /// Lets `d` pass with the cycle running.
    pub(crate) fn run_for(&mut self, d: Duration) -> Result<(), PnioError> {
        let until = self.link.now() + d;
        self.pump(until, &|_| false, None).map(|_| ())
    }

    /// One cycle of the exchange: the output frame now, then the first input frame that left
    /// the device after that frame reached it, which carries the device's answer to it.
    /// `false` when none came within the data hold time ([`Controller::data_hold`]): a device
    /// that provides its inputs every cycle answers within a cycle or two, and one the host
    /// held back for a moment is not taken for silent.
    ///
    /// The output goes out at once rather than on the controller's own clock: a run of
    /// cycles then follows the device's send clock (each output right after the input before
    /// it), one cycle per input frame, so that a step's cycles take the time they stand for
    /// on the device's drive model.
    pub(crate) fn exchange_cycle(&mut self) -> Result<bool, PnioError> {
        let Some(input_id) = self.ar.as_ref().map(|a| a.input_frame_id) else {
            return Err(PnioError::NotConnected);
        };
        let wait = self.wait(self.data_hold());
        self.send_now()?;
        // When the output left: on the link's clock, and on the real-time clock the kernel
        // stamps received frames with.
        let (sent_at, sent_wall) = (self.link.now(), wall_clock());
        let is_input = move |p: &[u8]| frame_id(p).is_some_and(|id| id.0 == input_id);
        while let Some(Got::Frame { payload, stamp, .. }) =
            self.pump_within(&wait, &is_input, None)?
        {
            let new = self.cyclic_or_alarm(&payload, stamp)?;
            let fresh = match stamp {
                Some(at) => at >= sent_wall + FRESH,
                None => self.link.now() >= sent_at + FRESH,
            };
            if new && fresh {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Input frames and alarms, the frame received at `stamp` (the kernel's, where the link
    /// has one); anything else is dropped. Whether it was an input frame with new data. An
    /// input frame that finds the data hold time expired ends the AR, as a consumer's
    /// time-out does (IEC 61158-6-10: the CPM's DHT expiry aborts the AR).
    fn cyclic_or_alarm(
        &mut self,
        payload: &[u8],
        stamp: Option<Duration>,
    ) -> Result<bool, PnioError> {
        let Some(id) = frame_id(payload) else {
            return Ok(false);
        };
        match id.kind() {
            FrameKind::Rt => {
                // When it came, on the link's clock.
                let now = self.link.now();
                let at = stamp.map_or(now, |s| now.saturating_sub(wall_clock().saturating_sub(s)));
                let Some(ar) = self.ar.as_mut().filter(|a| a.input_frame_id == id.0) else {
                    return Ok(false);
                };
                let len = usize::from(ar.plan.input.data_length);
                let Ok(rt) = RtRepr::parse(payload, Some(len)) else {
                    return Ok(false);
                };
                self.cycles.received += 1;
                self.cycles.last_received = payload.to_vec();
                match ar.consumer.take(rt.cycle_counter, at) {
                    Ok(true) => {
                        ar.inputs = Some(rt);
                        Ok(true)
                    }
                    Ok(false) => Ok(false),
                    Err(e) => {
                        self.ar = None;
                        Err(e.into())
                    }
                }
            }
            FrameKind::Alarm { .. } => self.alarm_pdu(payload).map(|()| false),
            _ => Ok(false),
        }
    }

    /// The output frame now, and the next on the send clock: one cycle after this one, or
    /// after the one due, whichever is later (a frame sent early restarts the clock).
    fn send_now(&mut self) -> Result<(), PnioError> {
        let now = self.link.now();
        self.send_outputs()?;
        let cycle = self.cycle();
        self.next_send = if now.saturating_sub(self.next_send) > cycle || now < self.next_send {
            now + cycle
        } else {
            self.next_send + cycle
        };
        Ok(())
    }

    fn send_outputs(&mut self) -> Result<(), PnioError> {
        let (Some(ar), Some(dst)) = (self.ar.as_ref(), self.station.as_ref().map(|s| s.mac)) else {
            return Ok(());
        };
        let now = self.link.now();
        let rt = RtRepr {
            frame_id: FrameId(ar.output_frame_id),
            data: ar.outputs.clone(),
            cycle_counter: (now.as_nanos() / 31_250) as u16,
            data_status: DataStatus::GOOD,
            transfer_status: 0,
        };
        let bytes = rt.emit();
        let frame = self.ethernet(dst, &bytes);
        self.link.send(&frame)?;
        self.cycles.sent += 1;
        self.cycles.last_sent = bytes;
        Ok(())
    }

    /// Datagrams from the device: the answer to `call` is returned, the device's own calls
    /// (ApplicationReady) are answered at once, anything else is dropped.
    fn datagrams(&mut self, call: Option<Uuid>) -> Result<Option<RpcRepr>, PnioError> {
        let now = self.link.now();
        while let Some(d) = self.link.recv_udp(now + Duration::from_micros(1))? {
            let Ok(rpc) = RpcRepr::parse_bytes(&d) else {
                continue;
            };
            if rpc.packet_type == PacketType::REQUEST {
                self.application_ready(&rpc, &d)?;
            } else if Some(rpc.activity) == call {
                return Ok(Some(rpc));
            }
        }
        Ok(None)
    }

    /// The device's ApplicationReady call `req` (as it came: `call`), answered.
    fn application_ready(&mut self, req: &RpcRepr, call: &[u8]) -> Result<(), PnioError> {
        let Ok(ndr) = NdrRequest::parse(&req.body, req.drep) else {
            return Ok(());
        };
        let Ok(blocks) = Block::parse_all(&ndr.data) else {
            return Ok(());
        };
        let Some(Block::Control(c)) = blocks.first() else {
            return Ok(());
        };
        let ours = self.ar.as_ref().is_some_and(|a| a.uuid == c.ar_uuid);
        let ok = ours && c.block_type == BlockType::APPLICATION_READY_REQ;
        let status = if ok {
            PnioStatus::OK
        } else {
            PnioStatus::cm(cm::CONTROL, cm::CMRPC, cm::CMRPC_AR_UNKNOWN)
        };
        let data = Block::emit_all(&[Block::Control(c.done())]).unwrap_or_default();
        let Ok(body) = NdrResponse::answering(&ndr, status, data) else {
            return Ok(());
        };
        let answer = req
            .reply(PacketType::RESPONSE, body.emit(req.drep))
            .emit()
            .map_err(malformed("ApplicationReady answer"))?;
        self.link.send_udp_reply(&answer)?;
        if let Some(ar) = self.ar.as_mut().filter(|_| ok) {
            ar.ready = true;
        }
        self.record(
            call,
            "(the device's call) Control ApplicationReady".into(),
            &answer,
            format!("answered: {status}"),
        );
        Ok(())
    }

    // -----------------------------------------------------------------------------------------
    // DCP
    // -----------------------------------------------------------------------------------------

    fn next_xid(&mut self) -> u32 {
        self.xid = self.xid.wrapping_add(1);
        self.xid
    }

    /// DCP Identify (all, or by name): every station that answers within the window.
    pub(crate) fn identify(&mut self, name: Option<&str>) -> Result<Vec<Station>, PnioError> {
        self.identify_within(name).map(|(stations, _)| stations)
    }

    /// [`Controller::identify`], and the window it waited.
    fn identify_within(&mut self, name: Option<&str>) -> Result<(Vec<Station>, Wait), PnioError> {
        let xid = self.next_xid();
        let req = match name {
            Some(n) => DcpRepr::identify_name(xid, 1, n),
            None => DcpRepr::identify_all(xid, 1),
        };
        let bytes = emit_dcp(&req)?;
        let frame = self.ethernet(MULTICAST_DCP_IDENTIFY, &bytes);
        self.link.send(&frame)?;
        let wait = self.wait(IDENTIFY_WINDOW.min(self.timeout));
        let mut stations = Vec::new();
        let mut first = Vec::new();
        // Every Identify response frame carrying the request's Xid, parsed or not: a station
        // that answers with bytes that are no DCP telegram is found out, not taken for none.
        let is_answer = move |p: &[u8]| {
            frame_id(p) == Some(FrameId::DCP_IDENTIFY_RES)
                && p.get(4..8).is_some_and(|x| x == xid.to_be_bytes())
        };
        let mut broken = None;
        while let Some(Got::Frame { src, payload, .. }) =
            self.pump_within(&wait, &is_answer, None)?
        {
            if first.is_empty() {
                first = payload.clone();
            }
            match DcpRepr::parse(&payload) {
                Ok(res) => stations.push(Station::of(src, &res)),
                Err(e) => {
                    broken.get_or_insert(format!("{e} (from {src})"));
                    continue;
                }
            }
            if name.is_some() {
                break;
            }
        }
        let text = if stations.is_empty() {
            "(nothing)".to_string()
        } else {
            stations
                .iter()
                .map(|s| {
                    format!(
                        "{:?} at {} (vendor {:04X}h, device {:04X}h)",
                        s.name, s.mac, s.vendor_id, s.device_id
                    )
                })
                .collect::<Vec<_>>()
                .join("; ")
        };
        self.record(&bytes, dcp_text(&req), &first, text);
        match (stations.is_empty(), broken) {
            (true, Some(error)) => Err(PnioError::Malformed {
                what: "DCP Identify response",
                error,
            }),
            _ => Ok((stations, wait)),
        }
    }

    /// Finds the device (by name, or the only one that answers) and keeps it as the target.
    pub(crate) fn locate(&mut self, name: Option<&str>) -> Result<Station, PnioError> {
        let (found, wait) = self.identify_within(name)?;
        let station = match (name, found.len()) {
            // The device to test, by its name, missed the window.
            (Some(_), 0) => return Err(self.no_reply("DCP Identify response", &wait)),
            (None, 0) => return Err(PnioError::NotFound(String::new())),
            (None, n) if n > 1 => {
                return Err(PnioError::NotFound(format!(
                    ": {n} devices answered; name the one to test (pnio://IFACE/NAME)"
                )))
            }
            _ => found[0].clone(),
        };
        if let Some(ip) = station.ip.filter(|i| !i.ip.is_unspecified()) {
            self.link
                .set_udp_peer(SocketAddr::from((ip.ip, proto::pnio::RPC_PORT)))?;
        }
        self.station = Some(station.clone());
        Ok(station)
    }

    /// A DCP Get or Set to the device; its response.
    pub(crate) fn dcp(&mut self, req: DcpRepr) -> Result<DcpRepr, PnioError> {
        let dst = self.target()?.mac;
        let xid = self.next_xid();
        let req = DcpRepr { xid, ..req };
        let bytes = emit_dcp(&req)?;
        let frame = self.ethernet(dst, &bytes);
        self.link.send(&frame)?;
        let wait = self.wait(self.timeout);
        let is_answer = move |p: &[u8]| {
            DcpRepr::parse(p).is_ok_and(|r| r.xid == xid && r.service_type.is_response())
        };
        let Some(Got::Frame { payload, .. }) = self.pump_within(&wait, &is_answer, None)? else {
            self.record(&bytes, dcp_text(&req), &[], "(nothing)".into());
            return Err(self.no_reply("DCP response", &wait));
        };
        let res = DcpRepr::parse(&payload).map_err(malformed("DCP response"))?;
        self.record(&bytes, dcp_text(&req), &payload, format!("{:?}", res.data));
        Ok(res)
    }

    /// A DCP Set of one block; the device's Control/Response error for it. A name or address
    /// the device took becomes the controller's view of it.
    pub(crate) fn dcp_set(&mut self, block: DcpBlock) -> Result<BlockError, PnioError> {
        let option = block.option();
        let value = block.value.clone();
        let res = self.dcp(DcpRepr::set(0, vec![block]))?;
        let error = res
            .blocks()
            .iter()
            .find_map(|b| match &b.value {
                BlockValue::Response { option: o, error } if *o == option => Some(*error),
                _ => None,
            })
            .ok_or(PnioError::Malformed {
                what: "DCP Set response",
                error: format!("no Control/Response block for option {option:?}"),
            })?;
        // A name or address taken is followed below; anything else may have changed them
        // unseen: a refusal the device acted on all the same, a reset to factory.
        let followed = matches!(
            value,
            BlockValue::NameOfStation(_) | BlockValue::IpParameter(_)
        );
        if error != BlockError::OK || !followed {
            self.unsure = true;
        }
        if let (Some(s), BlockError::OK) = (self.station.as_mut(), error) {
            match value {
                BlockValue::NameOfStation(n) => s.name = n,
                BlockValue::IpParameter(p) => {
                    s.ip = Some(IpSuite {
                        ip: p.ip,
                        mask: p.mask,
                        gateway: p.gateway,
                    })
                }
                _ => {}
            }
        }
        Ok(error)
    }

    /// Whether a DCP Set since the last call may have changed the device's name or address
    /// without the controller following: a refusal the device acted on all the same (p-net
    /// does), a reset to factory. Its view is then to be checked.
    pub(crate) fn take_unsure(&mut self) -> bool {
        std::mem::take(&mut self.unsure)
    }

    /// A frame from its frame id on, as given, to the device; the first PROFINET frame that
    /// is not cyclic or alarm traffic within the timeout.
    pub(crate) fn raw_frame(&mut self, payload: &[u8]) -> Result<Option<Vec<u8>>, PnioError> {
        let dst = self.target()?.mac;
        let frame = self.ethernet(dst, payload);
        self.link.send(&frame)?;
        let wait = self.wait(self.timeout.min(IDENTIFY_WINDOW));
        let is_answer =
            |p: &[u8]| frame_id(p).is_some_and(|id| matches!(id.kind(), FrameKind::Dcp));
        let got = match self.pump_within(&wait, &is_answer, None)? {
            Some(Got::Frame { payload, .. }) => Some(payload),
            _ => None,
        };
        self.record(
            payload,
            "frame as written".into(),
            got.as_deref().unwrap_or_default(),
            if got.is_some() {
                "answer".into()
            } else {
                "(nothing)".into()
            },
        );
        Ok(got)
    }

    fn target(&self) -> Result<&Station, PnioError> {
        self.station
            .as_ref()
            .ok_or_else(|| PnioError::NotFound(" (no device located yet)".into()))
    }

    // -----------------------------------------------------------------------------------------
    // RPC
    // -----------------------------------------------------------------------------------------

    /// One RPC call to the device's PNIO interface (or `interface`), waiting for its answer
    /// with the cycle running.
    pub(crate) fn call(
        &mut self,
        opnum: Opnum,
        data: Vec<u8>,
        interface: Uuid,
        what: String,
    ) -> Result<Answer, PnioError> {
        let station = self.target()?.clone();
        self.calls += 1;
        let activity = self.activity;
        let body = NdrRequest::new(ARGS_MAXIMUM, data).map_err(malformed("NDR request"))?;
        let req = RpcRepr::request(
            Uuid::pnio_object(1, station.device_id, station.vendor_id),
            interface,
            activity,
            self.calls,
            opnum,
            body.emit(Drep::LITTLE_ENDIAN),
        );
        let bytes = req.emit().map_err(malformed("RPC request"))?;
        self.link.send_udp(&bytes)?;
        let wait = self.wait(self.timeout);
        let Some(Got::Answer(res)) = self.pump_within(&wait, &|_| false, Some(activity))? else {
            self.record(&bytes, what, &[], "(nothing)".into());
            return Err(self.no_reply("RPC answer", &wait));
        };
        let res_bytes = res.emit().unwrap_or_default();
        match res.packet_type {
            PacketType::RESPONSE => {}
            PacketType::REJECT | PacketType::FAULT => {
                let status = res.nca_status().map_err(malformed("RPC reject"))?;
                let packet = if res.packet_type == PacketType::REJECT {
                    "reject"
                } else {
                    "fault"
                };
                self.record(&bytes, what, &res_bytes, format!("RPC {packet}: {status}"));
                return Err(PnioError::Nca { packet, status });
            }
            other => {
                return Err(PnioError::Malformed {
                    what: "RPC answer",
                    error: format!("packet type {other:?}"),
                })
            }
        }
        let ndr = NdrResponse::parse(&res.body, res.drep).map_err(malformed("NDR response"))?;
        let blocks = Block::parse_all(&ndr.data).map_err(malformed("blocks of the answer"))?;
        let text = blocks
            .iter()
            .map(|b| format!("{:?}", b.block_type()))
            .collect::<Vec<_>>()
            .join(", ");
        self.record(&bytes, what, &res_bytes, format!("{}: {text}", ndr.status));
        Ok(Answer {
            status: ndr.status,
            blocks,
        })
    }

    fn call_blocks(
        &mut self,
        opnum: Opnum,
        blocks: &[Block],
        what: String,
    ) -> Result<Answer, PnioError> {
        let data = Block::emit_all(blocks).map_err(malformed("request blocks"))?;
        self.call(opnum, data, Uuid::PNIO_DEVICE_INTERFACE, what)
    }

    /// Connect with the DAP and `modules`, then PrmEnd and the device's ApplicationReady: the
    /// Connect's answer (with the ModuleDiffBlock if any). A refused Connect leaves no AR.
    pub(crate) fn connect(&mut self, modules: &[ExpectedSub]) -> Result<Connected, PnioError> {
        self.ar = None;
        let mut subs = self.dap.clone();
        subs.extend_from_slice(modules);
        let plan = Plan::new(&subs).map_err(malformed("expected submodules"))?;
        self.session_key = self.session_key.wrapping_add(1);
        self.calls += 1;
        let uuid = Uuid::of_sender(0x4E52_4152, self.session_key, self.mac, self.calls as u16);
        let rr = self.reduction_ratio;
        let iocr = |iocr_type, layout: &proto::pnio::plan::CrLayout, frame_id| {
            Block::IocrReq(IocrBlockReq {
                iocr_type,
                reference: iocr_type.0,
                lt: ETHERTYPE_PROFINET,
                properties: iocr_properties::RT_CLASS_2,
                data_length: layout.data_length,
                frame_id,
                send_clock_factor: SEND_CLOCK_FACTOR,
                reduction_ratio: rr,
                phase: 1,
                frame_send_offset: 0xFFFF_FFFF,
                watchdog_factor: hold_factor(rr),
                data_hold_factor: hold_factor(rr),
                tag_header: 0xC000,
                apis: vec![layout.api.clone()],
                ..IocrBlockReq::default()
            })
        };
        let blocks = vec![
            Block::ArReq(ArBlockReq {
                ar_type: ArType::IOC_AR_SINGLE,
                ar_uuid: uuid,
                session_key: self.session_key,
                initiator_mac: self.mac,
                initiator_object: Uuid::pnio_object(1, 0x0001, proto::nord::pnio::VENDOR_ID),
                properties: ar_properties::STATE_ACTIVE | ar_properties::PRM_SERVER_CM_INITIATOR,
                activity_timeout_factor: 100,
                udp_rt_port: ETHERTYPE_PROFINET,
                station_name: b"nord-harness".to_vec(),
            }),
            iocr(IocrType::INPUT, &plan.input, INPUT_FRAME_ID),
            iocr(IocrType::OUTPUT, &plan.output, OUTPUT_FRAME_ID),
            Block::AlarmCrReq(AlarmCrBlockReq {
                alarm_cr_type: AlarmCrType::ALARM_CR,
                lt: ETHERTYPE_PROFINET,
                properties: 0,
                rta_timeout_factor: 1,
                rta_retries: 3,
                local_alarm_reference: ALARM_REF,
                max_alarm_data_length: 200,
                tag_header_high: 0xC000,
                tag_header_low: 0xA000,
            }),
            Block::ExpectedSubmoduleReq(plan.expected.clone()),
        ];
        let answer = self.call_blocks(Opnum::CONNECT, &blocks, "Connect".into())?;
        let diff = answer.blocks.iter().find_map(|b| match b {
            Block::ModuleDiff(d) => Some(d.clone()),
            _ => None,
        });
        if !answer.status.is_ok() {
            return Ok(Connected {
                status: answer.status,
                diff,
                prm_end: None,
                ready: false,
            });
        }
        let frame_id = |iocr_type, proposed| {
            answer
                .blocks
                .iter()
                .find_map(|b| match b {
                    Block::IocrRes(r) if r.iocr_type == iocr_type => Some(r.frame_id),
                    _ => None,
                })
                .unwrap_or(proposed)
        };
        let input_frame_id = frame_id(IocrType::INPUT, INPUT_FRAME_ID);
        let output_frame_id = frame_id(IocrType::OUTPUT, OUTPUT_FRAME_ID);
        let device_alarm_ref = answer
            .blocks
            .iter()
            .find_map(|b| match b {
                Block::AlarmCrRes(r) => Some(r.local_alarm_reference),
                _ => None,
            })
            .unwrap_or(0);
        let mut outputs = vec![0u8; usize::from(plan.output.data_length)];
        // Every IOPS and IOCS of the controller good.
        for p in &plan.output.data {
            outputs[p.offset + p.len] = Iox::GOOD.0;
        }
        for p in &plan.output.iocs {
            outputs[p.offset] = Iox::GOOD.0;
        }
        self.ar = Some(Ar {
            uuid,
            session_key: self.session_key,
            plan,
            input_frame_id,
            output_frame_id,
            device_alarm_ref,
            outputs,
            inputs: None,
            consumer: Consumer::new(input_frame_id, self.data_hold()),
            ready: false,
            alarm_seq: 0,
            alarm_received: NOTHING_RECEIVED,
        });
        self.next_send = self.link.now();
        let prm_end = self.call_blocks(
            Opnum::CONTROL,
            &[Block::Control(IodControl::prm_end(uuid, self.session_key))],
            "Control PrmEnd".into(),
        )?;
        // The device calls ApplicationReady; the pump answers it.
        let wait = self.wait(self.timeout);
        while !self.connected() && !wait.passed(self.link.now()) {
            let slice = (self.link.now() + self.cycle()).min(wait.end(self.link.now()));
            self.pump(slice, &|_| false, None)?;
        }
        Ok(Connected {
            status: answer.status,
            diff,
            prm_end: Some(prm_end.status),
            ready: self.connected(),
        })
    }

    /// Opens a DeviceAccess AR, as engineering tools do to read records without I/O
    /// (IEC 61158-6-10: ARType IOSAR, ARProperties.DeviceAccess, the ARBlockReq alone): the
    /// Connect's PNIO status. Record calls go to it while no IO AR is up.
    pub(crate) fn open_access(&mut self) -> Result<PnioStatus, PnioError> {
        self.access = None;
        self.session_key = self.session_key.wrapping_add(1);
        self.calls += 1;
        let uuid = Uuid::of_sender(0x4E52_4441, self.session_key, self.mac, self.calls as u16);
        let req = Block::ArReq(ArBlockReq {
            ar_type: ArType::IOS_AR,
            ar_uuid: uuid,
            session_key: self.session_key,
            initiator_mac: self.mac,
            initiator_object: Uuid::pnio_object(1, 0x0001, proto::nord::pnio::VENDOR_ID),
            properties: ar_properties::STATE_ACTIVE | ar_properties::DEVICE_ACCESS,
            activity_timeout_factor: 100,
            udp_rt_port: ETHERTYPE_PROFINET,
            station_name: b"nord-harness".to_vec(),
        });
        let answer = self.call_blocks(Opnum::CONNECT, &[req], "Connect DeviceAccess AR".into())?;
        if answer.status.is_ok() {
            self.access = Some((uuid, self.session_key));
        }
        Ok(answer.status)
    }

    /// Release: the IO AR ends, or else the DeviceAccess AR.
    pub(crate) fn release(&mut self) -> Result<PnioStatus, PnioError> {
        let (uuid, key, access) = match (&self.ar, self.access) {
            (Some(ar), _) => (ar.uuid, ar.session_key, false),
            (None, Some((uuid, key))) => (uuid, key, true),
            (None, None) => return Err(PnioError::NotConnected),
        };
        let block = Block::Control(IodControl::release(uuid, key));
        let answer = self.call_blocks(Opnum::RELEASE, &[block], "Release".into())?;
        if answer.status.is_ok() {
            match access {
                true => self.access = None,
                false => self.ar = None,
            }
        }
        Ok(answer.status)
    }

    /// Whether a DeviceAccess AR is held (a case's cleanup releases it).
    pub(crate) fn holds_access(&self) -> bool {
        self.access.is_some()
    }

    /// The AR record calls go in: the IO AR, else the DeviceAccess AR.
    fn record_ar(&self) -> Option<Uuid> {
        self.ar
            .as_ref()
            .map(|a| a.uuid)
            .or(self.access.map(|a| a.0))
    }

    fn address(&self, slot: u16, subslot: u16, index: u16) -> RecordAddress {
        RecordAddress {
            seq_number: self.calls as u16,
            ar_uuid: self.record_ar().unwrap_or_default(),
            api: 0,
            slot,
            subslot,
            index,
        }
    }

    /// IODWrite of a record in the AR: the PNIO status.
    pub(crate) fn write_record(
        &mut self,
        slot: u16,
        subslot: u16,
        index: u16,
        data: &[u8],
        what: String,
    ) -> Result<PnioStatus, PnioError> {
        let block = Block::WriteReq(IodWriteReq {
            addr: self.address(slot, subslot, index),
            data: data.to_vec(),
        });
        let answer = self.call_blocks(Opnum::WRITE, &[block], what)?;
        Ok(answer.status)
    }

    /// IODRead of a record (in an AR, or implicit without one): the PNIO status and data.
    pub(crate) fn read_record(
        &mut self,
        slot: u16,
        subslot: u16,
        index: u16,
        what: String,
    ) -> Result<(PnioStatus, Vec<u8>), PnioError> {
        let opnum = if self.record_ar().is_some() {
            Opnum::READ
        } else {
            Opnum::READ_IMPLICIT
        };
        let block = Block::ReadReq(IodReadReq {
            addr: self.address(slot, subslot, index),
            record_data_length: 1024,
            target_ar_uuid: Uuid::default(),
        });
        let answer = self.call_blocks(opnum, &[block], what)?;
        let data = answer
            .blocks
            .into_iter()
            .find_map(|b| match b {
                Block::ReadRes(r) => Some(r.data),
                _ => None,
            })
            .unwrap_or_default();
        Ok((answer.status, data))
    }

    // -----------------------------------------------------------------------------------------
    // Cyclic data
    // -----------------------------------------------------------------------------------------

    /// Provides `modules` (slot, output data) with their IOPS good and marks every other
    /// module's outputs bad (IOPS "bad by controller"): the device takes no data for them, as
    /// an inverter gets no telegram in a cycle that addresses another.
    pub(crate) fn provide(&mut self, modules: &[(u16, &[u8])]) -> Result<(), PnioError> {
        let ar = self.ar.as_mut().ok_or(PnioError::NotConnected)?;
        for p in ar.plan.output.data.iter().filter(|p| p.slot != 0) {
            let iops = match modules.iter().find(|(s, _)| *s == p.slot) {
                Some((_, data)) => {
                    let n = data.len().min(p.len);
                    ar.outputs[p.offset..p.offset + n].copy_from_slice(&data[..n]);
                    Iox::GOOD
                }
                None => Iox::BAD_BY_CONTROLLER,
            };
            ar.outputs[p.offset + p.len] = iops.0;
        }
        Ok(())
    }

    /// The ident number of the module the AR expects in `slot`.
    pub(crate) fn module_ident(&self, slot: u16) -> Option<u32> {
        let ar = self.ar.as_ref()?;
        ar.plan
            .expected
            .apis
            .iter()
            .find(|a| a.slot == slot)
            .map(|a| a.module_ident)
    }

    /// The input data and IOPS of the submodule in `slot` from the last input frame.
    pub(crate) fn input(&self, slot: u16) -> Option<(Vec<u8>, Iox)> {
        let ar = self.ar.as_ref()?;
        let rt = ar.inputs.as_ref()?;
        let p = ar.plan.input.data.iter().find(|p| p.slot == slot)?;
        Some((
            rt.data.get(p.offset..p.offset + p.len)?.to_vec(),
            Iox(*rt.data.get(p.offset + p.len)?),
        ))
    }

    /// The DataStatus of the last input frame.
    pub(crate) fn input_status(&self) -> Option<DataStatus> {
        Some(self.ar.as_ref()?.inputs.as_ref()?.data_status)
    }

    // -----------------------------------------------------------------------------------------
    // Alarms
    // -----------------------------------------------------------------------------------------

    fn alarm_pdu(&mut self, payload: &[u8]) -> Result<(), PnioError> {
        let Ok(pdu) = AlarmRepr::parse(payload) else {
            return Ok(());
        };
        let (Some(ar), Some(dst)) = (self.ar.as_mut(), self.station.as_ref().map(|s| s.mac)) else {
            return Ok(());
        };
        if pdu.pdu_type != RtaPduType::DATA || pdu.dst_endpoint != ALARM_REF {
            return Ok(());
        }
        let repeated = pdu.send_seq == ar.alarm_received;
        let due = match ar.alarm_received {
            NOTHING_RECEIVED => 0,
            last => (last + 1) & 0x7FFF,
        };
        // IEC 61158-6-10 APMR: a DATA PDU that is neither the one due nor a repeat of the last
        // is not taken; it is answered with a NACK (as p-net's APMR does), the others with an
        // ACK.
        let taken = repeated || pdu.send_seq == due;
        let (pdu_type, ack_seq) = match taken {
            true => (RtaPduType::ACK, pdu.send_seq),
            false => (RtaPduType::NACK, ar.alarm_received),
        };
        if taken {
            ar.alarm_received = pdu.send_seq;
        }
        let answer = AlarmRepr {
            pdu_type,
            ..AlarmRepr::ack(
                pdu.frame_id,
                ar.device_alarm_ref,
                ALARM_REF,
                ar.alarm_seq.wrapping_sub(1) & 0x7FFF,
                ack_seq,
            )
        };
        let bytes = answer.emit().map_err(malformed("alarm ACK"))?;
        let frame = self.ethernet(dst, &bytes);
        self.link.send(&frame)?;
        if !taken {
            let got = pdu.send_seq;
            self.departure
                .get_or_insert(Departure::Sequence { got, due });
            return Ok(());
        }
        let (false, RtaBody::Notification(n)) = (repeated, pdu.body) else {
            return Ok(());
        };
        self.record(&[], "(the device's alarm)".into(), payload, alarm_text(&n));
        let expected = self
            .alarm_types
            .is_none_or(|types| types.contains(&n.alarm_type.0));
        if expected {
            // A case's `alarm:` step takes and acknowledges it.
            self.alarms.push_back(n);
        } else {
            // Acknowledged at once (IEC 61158-6-10: the controller answers every notification
            // with an AlarmAck), and kept for the verdict.
            self.send_alarm_ack(&n)?;
            self.departure.get_or_insert(Departure::Alarm(n));
        }
        Ok(())
    }

    /// The first departure since the last call: an alarm of a type the device's manual does
    /// not name ([`Controller::set_alarm_types`]), already acknowledged, or an alarm PDU out
    /// of sequence.
    pub(crate) fn take_departure(&mut self) -> Option<Departure> {
        self.departure.take()
    }

    /// The AlarmAck (status OK) of notification `n`, as a DATA PDU with the controller's next
    /// SendSeqNum.
    fn send_alarm_ack(&mut self, n: &AlarmNotification) -> Result<(), PnioError> {
        let (Some(ar), Some(dst)) = (self.ar.as_mut(), self.station.as_ref().map(|s| s.mac)) else {
            return Err(PnioError::NotConnected);
        };
        let seq = ar.alarm_seq;
        ar.alarm_seq = (ar.alarm_seq + 1) & 0x7FFF;
        let pdu = AlarmRepr::data(
            ar.device_alarm_ref,
            ALARM_REF,
            seq,
            ar.alarm_received,
            RtaBody::Ack(AlarmAck::of(n, PnioStatus::OK)),
        );
        let bytes = pdu.emit().map_err(malformed("AlarmAck"))?;
        let frame = self.ethernet(dst, &bytes);
        self.link.send(&frame)?;
        self.record(
            &bytes,
            format!("AlarmAck of {}", alarm_text(n)),
            &[],
            String::new(),
        );
        Ok(())
    }

    /// Waits up to `wait` for an alarm notification and acknowledges it (AlarmAck, status
    /// OK); the notification, or `None`.
    pub(crate) fn acknowledge_alarm(
        &mut self,
        wait: Duration,
    ) -> Result<Option<AlarmNotification>, PnioError> {
        let wait = self.wait(wait);
        while self.alarms.is_empty() && !wait.passed(self.link.now()) {
            let slice = (self.link.now() + self.cycle()).min(wait.end(self.link.now()));
            self.pump(slice, &|_| false, None)?;
        }
        let Some(n) = self.alarms.pop_front() else {
            return Ok(None);
        };
        self.send_alarm_ack(&n)?;
        // The device's transport ACK comes with the cycle.
        self.run_for(self.cycle())?;
        Ok(Some(n))
    }

    /// Lets `d` pass without sending anything (the device's watchdog runs out); frames that
    /// come are taken and dropped.
    pub(crate) fn silence(&mut self, d: Duration) -> Result<(), PnioError> {
        let until = self.link.now() + d;
        let ar = self.ar.take();
        let r = self.pump(until, &|_| false, None);
        self.ar = ar;
        r.map(|_| ())
    }
}

/// What the device did on its own that its manual or the standard rules out, seen by the
/// pump whatever the case was waiting for; the binding fails the step it came by.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum Departure {
    /// An alarm of a type the device's manual does not name, acknowledged.
    #[error(
        "the device raised a {} alarm (AlarmType {:04X}h) from slot {} subslot {}, \
         AlarmSpecifier sequence {}, acknowledged: its manual names diagnosis alarms only \
         (BU 0620 §5.4.2, BU 0590 §6.1)",
        .0.alarm_type.name().unwrap_or("unknown"),
        .0.alarm_type.0,
        .0.slot,
        .0.subslot,
        .0.specifier.sequence()
    )]
    Alarm(AlarmNotification),
    /// An alarm DATA PDU whose SendSeqNum was neither the one due nor the last one again.
    #[error(
        "the device's alarm DATA-RTA-PDU came with SendSeqNum {got} where {due} was due \
         (IEC 61158-6-10 RTA: neither the next nor a repeat), answered with a NACK"
    )]
    Sequence { got: u16, due: u16 },
}

/// Something the pump was asked for.
enum Got {
    Frame {
        src: MacAddr,
        payload: Vec<u8>,
        /// The kernel's receive stamp (real-time clock), where the link has one.
        stamp: Option<Duration>,
    },
    Answer(RpcRepr),
}

/// What a Connect came to.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Connected {
    /// The Connect's PNIO status.
    pub(crate) status: PnioStatus,
    /// The device's ModuleDiffBlock, if it sent one.
    pub(crate) diff: Option<ModuleDiffBlock>,
    /// PrmEnd's status, when the Connect was accepted.
    pub(crate) prm_end: Option<PnioStatus>,
    /// Whether ApplicationReady came: data exchange.
    pub(crate) ready: bool,
}

impl Connected {
    /// Why the AR did not reach data exchange, for a verdict: the refusal (its PNIO status
    /// decoded) or the call that did not come.
    pub(crate) fn why_not_running(&self) -> String {
        match self.prm_end {
            _ if !self.status.is_ok() => {
                format!("Connect response PNIO status {}", self.status.meaning())
            }
            Some(s) if !s.is_ok() => format!("Control PrmEnd response PNIO status {}", s.meaning()),
            _ => "the device did not call ApplicationReady".into(),
        }
    }
}

/// How long after an output frame an input frame must arrive to carry the device's answer to
/// it: the frame's way to the device and its handling there.
const FRESH: Duration = Duration::from_micros(100);

/// The real-time clock as a duration since the Unix epoch (what receive stamps are on).
fn wall_clock() -> Duration {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap_or_default()
}

/// How long the pump waits on frames before it looks at the datagrams again.
const POLL_SLICE: Duration = Duration::from_micros(200);

fn frame_id(payload: &[u8]) -> Option<FrameId> {
    payload
        .get(..2)
        .map(|b| FrameId(u16::from_be_bytes([b[0], b[1]])))
}

fn malformed<E: std::fmt::Display>(what: &'static str) -> impl Fn(E) -> PnioError {
    move |e| PnioError::Malformed {
        what,
        error: e.to_string(),
    }
}

fn emit_dcp(req: &DcpRepr) -> Result<Vec<u8>, PnioError> {
    req.emit().map_err(malformed("DCP request"))
}

fn dcp_text(req: &DcpRepr) -> String {
    let what = match req.service {
        ServiceId::IDENTIFY => "Identify",
        ServiceId::GET => "Get",
        ServiceId::SET => "Set",
        _ => "request",
    };
    format!("DCP {what} (xid {:08X}h)", req.xid)
}

/// An alarm notification in a line.
pub(crate) fn alarm_text(n: &AlarmNotification) -> String {
    format!(
        "{} alarm, slot {} subslot {}, sequence {}: {:?}",
        n.alarm_type.name().unwrap_or("unknown"),
        n.slot,
        n.subslot,
        n.specifier.sequence(),
        n.items
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::peer::Link as _;
    use crate::pnio::link::{EmbeddedLink, EMBEDDED_PEER};
    use proto::nord::pnio::{self as def, ModuleKind};
    use proto::nord::ppo::PpoType;
    use proto::nord::{Inverter, Product};
    use proto::pnio::alarm::AlarmType;
    use sim::device::{Device, DeviceConfig};
    use sim::endpoint::Endpoint;
    use sim::pnio::{IoConfig, IoDevice};

    /// The embedded SK 550P in data exchange with PPO 4 in FI 1's slot.
    fn running() -> Controller<EmbeddedLink> {
        let product = Product::Sk550p;
        let config = IoConfig {
            name: "nord-device".into(),
            ..IoConfig::new(product)
        };
        let io = IoDevice::new(Device::new(DeviceConfig::new(product)), config).unwrap();
        let link = EmbeddedLink::new(io, EMBEDDED_PEER);
        let mac = MacAddr([0x02, 0, 0, 0, 0, 0xC1]);
        let mut ctl = Controller::new(link, mac, Duration::from_millis(500), false);
        ctl.locate(Some("nord-device")).unwrap();
        let slot = def::inverter_slot(product, Inverter::new(1).unwrap()).unwrap();
        let ppo4 = def::module(product, ModuleKind::Ppo(PpoType::TYPE_4)).unwrap();
        let c = ctl.connect(&[def::expected_module(slot, &ppo4)]).unwrap();
        assert!(c.ready, "{c:?}");
        ctl
    }

    #[test]
    fn an_alarm_the_manual_does_not_name_is_acknowledged_at_once_and_kept_for_the_verdict() {
        let mut ctl = running();
        let (io, now) = ctl.link_mut().device().unwrap();
        // Raised, its first PDU lost: the device repeats it after its RTA time-out (100 ms).
        io.raise_alarm(now).expect("an AR to raise it in");
        ctl.run_for(Duration::from_millis(150)).unwrap();
        let Some(Departure::Alarm(n)) = ctl.take_departure() else {
            panic!("the process alarm")
        };
        assert_eq!(
            (n.alarm_type, n.slot, n.subslot),
            (AlarmType::PROCESS, 3, 1)
        );
        assert_eq!(ctl.take_departure(), None, "taken once");
        // Not left for an `alarm:` step: that one waits for a diagnosis alarm.
        assert_eq!(
            ctl.acknowledge_alarm(Duration::from_millis(10)).unwrap(),
            None
        );
        // The AlarmAck cleared it: the device no longer reports a problem in its inputs, and
        // raises the next one at once.
        assert!(ctl.input_status().unwrap().station_ok());
        let (io, now) = ctl.link_mut().device().unwrap();
        assert!(!io.raise_alarm(now).unwrap().outputs.is_empty());
    }

    #[test]
    fn any_makers_device_may_raise_any_alarm_for_a_step_to_take() {
        let mut ctl = running();
        ctl.set_alarm_types(None);
        let (io, now) = ctl.link_mut().device().unwrap();
        io.raise_alarm(now).unwrap();
        let n = ctl.acknowledge_alarm(Duration::from_millis(150)).unwrap();
        assert_eq!(n.map(|n| n.alarm_type), Some(AlarmType::PROCESS));
        assert_eq!(ctl.take_departure(), None);
    }
}
