//! The managing node (sans policy): the POWERLINK cycle — SoC, PReq/PRes with the one
//! controlled node, SoA and the asynchronous frame — the NMT boot of the node, and an SDO
//! client over ASnd and over UDP (EPSG DS 301 §4.2.4 cycle, §7.1.4 NMT, §6.3 SDO; BU 0620
//! §2.4.3 "A transfer cycle starts with the message type SoC. After this, each CN is queried
//! with a PReq by the MN, to which the CN responds with a PRes. … the asynchronous phase
//! starts with the transfer of the SoA package.").
//!
//! Everything it sends and receives is recorded as transcript exchanges, decoded.

mod describe;
mod expect;
pub(crate) mod link;
mod loss;

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use proto::epl::asnd::{ErrorEntry, IdentResponse, NmtCommandFrame, StatusResponse};
use proto::epl::frame::{Asnd, Body, Preq, Soa, Soc};
use proto::epl::sdo::{Command, Con, SdoFrame, Segmentation, Seq, SEQ_MODULO};
use proto::epl::{
    EplRepr, MessageType, NmtCommand, NmtState, RequestedService, ServiceId, BROADCAST_NODE_ID,
    MN_NODE_ID, MULTICAST_ASND, MULTICAST_SOA, MULTICAST_SOC,
};
use proto::eth::{EthernetFrame, EthernetRepr, MacAddr, ETHERTYPE_POWERLINK};

pub(crate) use describe::describe;
use expect::StateWatch;
use link::Link;
use loss::{Decision, PresWatch, Reached};

use crate::hex::hex;
use crate::net::LinkError;
use crate::outcome::Exchange;
use crate::timing::Deadline;

/// How the MN carries SDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Via {
    /// ASnd frames in the asynchronous phase.
    Asnd,
    /// UDP/IP datagrams to port 3819.
    Udp,
}

impl Via {
    pub(crate) fn parse(s: &str) -> Result<Via, String> {
        match s {
            "asnd" => Ok(Via::Asnd),
            "udp" => Ok(Via::Udp),
            other => Err(format!("SDO over `{other}`: asnd or udp")),
        }
    }
}

/// How the MN runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct MnConfig {
    /// The controlled node's id.
    pub(crate) node: u8,
    /// The cycle time (P858: 400…2000 µs, factory 1000 µs).
    pub(crate) cycle: Duration,
    /// How long a PRes or an asked-for ASnd may take after its request.
    pub(crate) reply: Duration,
    /// How long the node may take to answer an SDO request, over ASnd or UDP. Neither manual
    /// prints a time (BU 0620 §2.4.6, BU 2200 §6.4: the processing "depends on the PLC"; their
    /// abort 05040000h is the interface's own time-out towards the inverter), and DS 301's
    /// SDO_SequLayerTimeout_U32 (1300h) bounds a connection's silence, not one answer: the
    /// limit is the harness's, `--timeout` on the network (default 2 s).
    pub(crate) sdo: Duration,
    /// How long the node may take to send an ASnd the MN asks for (IdentResponse,
    /// StatusResponse), the MN asking again each cycle: DS 301 has the CN answer in the
    /// asynchronous phase of the cycle whose SoA asks, but a node on a network shares its
    /// host, so the limit is the harness's, `--timeout` there too.
    pub(crate) asked: Duration,
    /// Default SDO transport.
    pub(crate) via: Via,
}

impl Default for MnConfig {
    fn default() -> MnConfig {
        MnConfig {
            node: 1,
            cycle: Duration::from_millis(1),
            reply: Duration::from_micros(500),
            sdo: Duration::from_millis(200),
            asked: Duration::from_millis(20),
            via: Via::Asnd,
        }
    }
}

/// Why the MN could not do what it was asked.
#[derive(Debug, thiserror::Error)]
pub(crate) enum MnError {
    /// The link failed.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The node did not answer within its limit (the wait moved by the time the host lost
    /// meanwhile, see [`Wait`]).
    #[error(
        "no reply from node {node} to {what} within its limit of {} (waited {})",
        crate::timing::ms(*limit),
        crate::timing::ms(*waited)
    )]
    NoReply {
        /// The node.
        node: u8,
        /// The request.
        what: String,
        /// The node's limit.
        limit: Duration,
        /// How long the MN waited, the host's lost time included.
        waited: Duration,
    },
    /// The node answered with frames that break POWERLINK.
    #[error("node {node} sent a malformed answer to {what}: {why}")]
    Malformed {
        /// The node.
        node: u8,
        /// The request.
        what: String,
        /// What was wrong.
        why: String,
    },
    /// The node refused an SDO transfer.
    #[error("SDO abort {0:08X}h")]
    Abort(u32),
    /// A PRes of the node said another NMT state than the node reported or was commanded
    /// into (EPSG DS 301 §4.6.1.1.4, PRes NMTStatus).
    #[error(
        "node {node}'s PRes says {}, expected {}",
        expect::cs(*said),
        expect::cs(*expected)
    )]
    PresState {
        /// The node.
        node: u8,
        /// What its PRes said.
        said: NmtState,
        /// What the MN expected.
        expected: NmtState,
    },
    /// The node's PRes went missing until the MN's loss-of-PRes threshold counter reached its
    /// threshold (EPSG DS 301 §4.7.4.1, E_DLL_LOSS_PRES_TH): an MN takes the node out of
    /// the cycle.
    #[error(
        "no PRes from node {node} in {} of {} cycles: loss of PRes, threshold counter \
         (1C08h) {} reached the threshold {} (1C09h DLL_MNCNLossPResThreshold): \
         E_DLL_LOSS_PRES_TH",
        reached.lost, reached.cycles, reached.count, reached.threshold
    )]
    LossOfPres {
        /// The node.
        node: u8,
        /// The counts.
        reached: Reached,
    },
    /// The node did not reach the NMT state asked for.
    #[error("node {node} is in {state} after {what}, not {wanted}")]
    State {
        /// The node.
        node: u8,
        /// Its state.
        state: NmtState,
        /// The state asked for.
        wanted: NmtState,
        /// How.
        what: String,
    },
}

/// Whether the MN runs the isochronous phase (SoC, PReq) or only SoA (DS 301 "reduced
/// POWERLINK cycle" of NMT_MS_PRE_OPERATIONAL_1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Reduced,
    Isochronous,
}

/// One SDO connection's sequence numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
struct Connection {
    sent: u8,
    received: u8,
}

/// One wait of the MN for its node: a [`Deadline`] (the node's limit from when the request
/// left, moved by the time the host lost meanwhile) on the link's clock.
#[derive(Debug, Clone, Copy)]
struct Wait {
    deadline: Deadline,
    /// The link's time when the request left.
    from: Duration,
}

/// A frame the node sent, as the MN got it.
#[derive(Debug, Clone)]
pub(crate) struct Received {
    /// The POWERLINK frame.
    pub(crate) repr: Option<EplRepr>,
    /// Its bytes after the Ethernet header.
    pub(crate) bytes: Vec<u8>,
    /// The kernel's receive stamp, on a network link.
    pub(crate) stamp: Option<Duration>,
    /// The Ethernet frame it came in (none over UDP).
    pub(crate) ether: Option<Ether>,
}

/// The Ethernet frame around a node's POWERLINK frame (BU 2200 §3.3 figure 6).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ether {
    /// Destination address (multicast for SoC, PRes, SoA and ASnd; §3.3 table).
    pub(crate) dst: MacAddr,
    /// EtherType (88ABh).
    pub(crate) ethertype: u16,
    /// Frame length without the FCS, padding included.
    pub(crate) len: usize,
}

/// The managing node of one controlled node.
pub(crate) struct Manager<L> {
    link: L,
    config: MnConfig,
    mac: MacAddr,
    /// The node's MAC address, learnt from its frames (PReq is unicast).
    node_mac: MacAddr,
    phase: Phase,
    /// The MN's NMT state as its SoA shows it.
    mn_state: NmtState,
    /// PReq payload and its RD flag.
    outputs: Vec<u8>,
    ready: bool,
    /// The last PRes.
    inputs: Vec<u8>,
    /// The node's state as its last frame showed it.
    node_state: Option<NmtState>,
    next_cycle: Duration,
    exchanges: Vec<Exchange>,
    recording: bool,
    /// ASnd frames of the MN for its next asynchronous slots.
    queued: VecDeque<(ServiceId, Vec<u8>)>,
    /// SDO frames of the node that came after their wait, for the SDO client.
    asnd: VecDeque<Received>,
    /// PRes arrival stamps of the cycles run with [`Manager::record_stamps`] on.
    stamps: Option<Vec<Option<Duration>>>,
    missed: u64,
    /// Whether the last isochronous cycle's PRes came within the reply time.
    in_time: bool,
    asnd_link: Option<Connection>,
    udp_link: Option<Connection>,
    transaction: u8,
    /// The node's loss-of-PRes counters.
    watch: PresWatch<(Instant, Duration)>,
    /// Whether the node answers PReq, as its last frame showed (a PRes; an ASnd in
    /// PRE_OPERATIONAL_2, READY_TO_OPERATE or OPERATIONAL), and nothing since (an NMT stop or
    /// reset, the MN's silence) made it stop: only then is a missing PRes watched.
    answering: bool,
    /// The NMT state its PRes should say.
    expect: StateWatch,
    /// EA: the last EN of the node the MN fetched the StatusResponse for (DS 301 §6.5.2: the
    /// MN acknowledges a new error in its PReq).
    ea: bool,
    /// The node's EN differs from EA: its StatusResponse is fetched in the next free
    /// asynchronous slot.
    exception: bool,
    /// The entries of the node's last StatusResponse (`None`: none read yet).
    entries: Option<Vec<ErrorEntry>>,
    /// Entries that were not in the StatusResponse before, for the binding to judge.
    signalled: Vec<ErrorEntry>,
    /// PRes of the node received and not yet matched to a cycle's window: late ones.
    unmatched: u32,
}

/// The least a wait moves for the host's lost time, however short its limit (a PRes's 500 µs),
/// as [`Deadline::end`] allows.
const MIN_LATE_ROOM: Duration = Duration::from_millis(50);

/// Frames the MN takes from the link in one wait at most, whatever they are.
const MAX_SKIPPED: usize = 256;

/// Late SDO frames the MN keeps for the SDO client at most.
const LATE_KEPT: usize = 16;

/// How often the MN reads the node's state after an NMT command until it shows the command's
/// effect.
const SETTLE_READS: u32 = 5;

fn next(n: u8) -> u8 {
    (n + 1) % SEQ_MODULO
}

impl<L: Link> Manager<L> {
    pub(crate) fn new(link: L, config: MnConfig, mac: MacAddr) -> Manager<L> {
        let now = link.now();
        Manager {
            link,
            config,
            mac,
            node_mac: MacAddr([0xF0, 0x5F, 0x5A, 0, 0, config.node]),
            phase: Phase::Reduced,
            mn_state: NmtState::PRE_OPERATIONAL_1,
            outputs: Vec::new(),
            ready: false,
            inputs: Vec::new(),
            node_state: None,
            next_cycle: now,
            exchanges: Vec::new(),
            recording: true,
            queued: VecDeque::new(),
            asnd: VecDeque::new(),
            stamps: None,
            missed: 0,
            in_time: false,
            asnd_link: None,
            udp_link: None,
            transaction: 0,
            watch: PresWatch::default(),
            answering: false,
            expect: StateWatch::default(),
            ea: false,
            exception: false,
            entries: None,
            signalled: Vec::new(),
            unmatched: 0,
        }
    }

    pub(crate) fn config(&self) -> &MnConfig {
        &self.config
    }

    /// Talks to node `node` from now on (the node was given a new id); its SDO connections
    /// start anew.
    pub(crate) fn set_node(&mut self, node: u8) {
        if node != self.config.node {
            self.config.node = node;
            self.node_state = None;
            self.drop_connections();
            self.watch = PresWatch::default();
            self.stop_watching();
            self.expect.forget();
        }
    }

    pub(crate) fn set_cycle(&mut self, cycle: Duration) {
        self.config.cycle = cycle;
    }

    pub(crate) fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    pub(crate) fn now(&self) -> Duration {
        self.link.now()
    }

    /// The node's NMT state as its last frame showed it.
    pub(crate) fn node_state(&self) -> Option<NmtState> {
        self.node_state
    }

    /// PRes frames that did not come within the reply time.
    pub(crate) fn missed(&self) -> u64 {
        self.missed
    }

    /// Whether the last isochronous cycle's PRes came within the reply time: if not, the
    /// inputs are still those of an earlier cycle.
    pub(crate) fn in_time(&self) -> bool {
        self.in_time
    }

    pub(crate) fn set_recording(&mut self, on: bool) {
        self.recording = on;
    }

    pub(crate) fn take_exchanges(&mut self) -> Vec<Exchange> {
        std::mem::take(&mut self.exchanges)
    }

    /// Starts or stops collecting the kernel stamps of PRes arrivals (bench).
    pub(crate) fn record_stamps(&mut self, on: bool) -> Vec<Option<Duration>> {
        let old = self.stamps.take().unwrap_or_default();
        if on {
            self.stamps = Some(Vec::new());
        }
        old
    }

    /// The PReq payload: `len` bytes, all zero until set.
    pub(crate) fn set_outputs(&mut self, payload: Vec<u8>, ready: bool) {
        self.outputs = payload;
        self.ready = ready;
    }

    /// Sets the PReq's RD flag: the payload is valid, the node takes it (DS 301 §4.6.1.1.3).
    pub(crate) fn set_ready(&mut self, ready: bool) {
        self.ready = ready;
    }

    pub(crate) fn outputs_mut(&mut self) -> &mut Vec<u8> {
        &mut self.outputs
    }

    pub(crate) fn inputs(&self) -> &[u8] {
        &self.inputs
    }

    fn record(&mut self, sent: &[u8], got: Option<&Received>) {
        if !self.recording {
            return;
        }
        let sent_repr = EplRepr::parse_bytes(sent).ok();
        self.exchanges.push(Exchange {
            sent_hex: hex(sent),
            sent: sent_repr
                .as_ref()
                .map_or_else(|| "malformed POWERLINK frame".into(), describe),
            received_hex: got.map_or_else(String::new, |g| hex(&g.bytes)),
            received: got.map_or_else(String::new, |g| {
                g.repr
                    .as_ref()
                    .map_or_else(|| "malformed POWERLINK frame".into(), describe)
            }),
        });
    }

    /// Sends a POWERLINK frame (bytes from the message type on) to the Ethernet address its
    /// type uses.
    pub(crate) fn send_raw(&mut self, bytes: &[u8]) -> Result<(), MnError> {
        let dst = match bytes.first().map(|b| b & 0x7F) {
            Some(0x03) => self.node_mac,
            Some(0x05) => MULTICAST_SOA,
            Some(0x06) => MULTICAST_ASND,
            _ => MULTICAST_SOC,
        };
        let frame = EthernetRepr {
            dst,
            src: self.mac,
            ethertype: ETHERTYPE_POWERLINK,
        }
        .emit(bytes);
        self.link.send(&frame)?;
        Ok(())
    }

    fn send(&mut self, repr: &EplRepr) -> Result<Vec<u8>, MnError> {
        let bytes = repr.emit().map_err(|e| MnError::Malformed {
            node: self.config.node,
            what: "a frame of the MN".into(),
            why: e.to_string(),
        })?;
        self.send_raw(&bytes)?;
        Ok(bytes)
    }

    /// A wait of `limit` for the node from now: made as the request leaves.
    fn wait(&self, limit: Duration) -> Wait {
        Wait {
            deadline: Deadline::after(limit),
            from: self.link.now(),
        }
    }

    /// Whether the link runs on the embedded node's virtual clock, which the host's load does
    /// not reach: there a wait ends at its limit, the same in every run.
    fn is_virtual(&mut self) -> bool {
        self.link.device().is_some()
    }

    /// When `w` ends on the link's clock, as far as is known now: on the real clock moved by
    /// the host's lost time (within the bound [`Deadline::end`] keeps), and never past that
    /// bound on the link's own clock: the MN's spinning can starve the watch, and a wait that
    /// chased it would not end.
    fn end(&mut self, w: &Wait) -> Duration {
        let limit = w.deadline.limit();
        if self.is_virtual() {
            return w.from + limit;
        }
        let latest = w.from + limit + limit.max(MIN_LATE_ROOM);
        (self.link.now() + w.deadline.remaining()).min(latest)
    }

    /// Whether `w` is over.
    fn passed(&mut self, w: &Wait) -> bool {
        self.link.now() >= self.end(w)
    }

    /// The node's time-out on `w`, waiting for an answer to `what`.
    fn timed_out(&mut self, w: &Wait, what: impl Into<String>) -> MnError {
        let waited = if self.is_virtual() {
            self.link.now().saturating_sub(w.from)
        } else {
            w.deadline.waited()
        };
        MnError::NoReply {
            node: self.config.node,
            what: what.into(),
            limit: w.deadline.limit(),
            waited,
        }
    }

    /// The next frame of the node within `w`; while the host's lost time moves its end, the
    /// wait goes on.
    fn receive_within(&mut self, w: &Wait) -> Result<Option<Received>, MnError> {
        loop {
            let end = self.end(w);
            if let Some(r) = self.receive(end)? {
                return Ok(Some(r));
            }
            if self.passed(w) {
                return Ok(None);
            }
        }
    }

    /// The next frame of the node until `deadline`; frames of others are skipped.
    pub(crate) fn receive(&mut self, deadline: Duration) -> Result<Option<Received>, MnError> {
        // A link flooded with frames of no interest must not hold the MN past its cycle.
        for _ in 0..MAX_SKIPPED {
            let Some((frame, stamp)) = self.link.recv(deadline)? else {
                return Ok(None);
            };
            let Ok(eth) = EthernetFrame::new_checked(&frame[..]) else {
                continue;
            };
            if eth.src() == self.mac {
                continue;
            }
            let bytes = eth.inner_payload().to_vec();
            let repr = EplRepr::parse_bytes(&bytes).ok();
            match &repr {
                Some(r) if r.src != self.config.node => continue,
                Some(r) => {
                    self.node_mac = eth.src();
                    match &r.body {
                        Body::Pres(p) => {
                            self.node_state = Some(p.state);
                            self.answering = true;
                            self.unmatched += 1;
                        }
                        Body::Asnd(a) => {
                            if let Some(s) = asnd_state(a) {
                                self.node_state = Some(s);
                                self.answering = answers_preq(s);
                                self.expect.reported(s);
                            }
                        }
                        _ => {}
                    }
                }
                None if bytes.get(2) != Some(&self.config.node) => continue,
                None => {}
            }
            let ether = Some(Ether {
                dst: eth.dst(),
                ethertype: eth.ethertype(),
                len: frame.len(),
            });
            return Ok(Some(Received {
                repr,
                bytes,
                stamp,
                ether,
            }));
        }
        Ok(None)
    }

    /// One cycle: SoC and PReq/PRes in the isochronous phase, then SoA asking `service` of
    /// `target` (or the MN's own slot when it has a frame queued). Returns the asynchronous
    /// frame the node sent, if any.
    pub(crate) fn cycle(&mut self, service: RequestedService) -> Result<Option<Received>, MnError> {
        let start = self.next_cycle.max(self.link.now());
        self.link.wait_until(start);
        // A reply that came after its wait ended belongs to an earlier cycle: it cannot pass
        // for the answer to this one. Late SDO frames are kept for the SDO client, which
        // knows their transfer by its numbers; the rest is dropped.
        let now = self.link.now();
        for _ in 0..MAX_SKIPPED {
            let Some(r) = self.receive(now)? else { break };
            if is_sdo(&r) && self.asnd.len() < LATE_KEPT {
                self.asnd.push_back(r);
            }
        }
        self.next_cycle = start + self.config.cycle;
        let node = self.config.node;
        if self.phase == Phase::Isochronous {
            self.send(&EplRepr {
                dst: BROADCAST_NODE_ID,
                src: MN_NODE_ID,
                body: Body::Soc(Soc {
                    net_time: 0,
                    relative_time: start.as_micros() as u64,
                    ..Soc::default()
                }),
            })?;
            let sent = self.send(&EplRepr {
                dst: node,
                src: MN_NODE_ID,
                body: Body::Preq(Preq {
                    ea: self.ea,
                    rd: self.ready,
                    pdo_version: 0x20,
                    payload: self.outputs.clone(),
                    ..Preq::default()
                }),
            })?;
            // A STOPPED node sends no PRes (DS 301 NMT_CS_STOPPED). Waiting for one put the
            // SoA late, and openPOWERLINK's CN took the late SoA for a lost one and left
            // STOPPED: the SoA follows at once. A node not yet stopped that still answers is
            // passed over next cycle as a late frame.
            if self.node_state == Some(NmtState::STOPPED) {
                self.record(&sent, None);
                return self.asynchronous(service, node);
            }
            let watching = self.answering;
            let sent_at = (Instant::now(), self.link.now());
            let w = self.wait(self.config.reply);
            let pres = self.wait_for(&w, |r| matches!(r.body, Body::Pres(_)))?;
            self.in_time = pres.is_some();
            let (reached, note) = self.watch_pres(watching, pres.is_some(), sent_at);
            let mut unexpected = None;
            match &pres {
                Some(p) => {
                    if let Some(EplRepr {
                        body: Body::Pres(body),
                        ..
                    }) = &p.repr
                    {
                        self.inputs = body.payload.clone();
                        unexpected = self.expect.pres(body.state).err();
                        self.exception |= body.en != self.ea;
                    }
                    if let Some(s) = self.stamps.as_mut() {
                        s.push(p.stamp);
                    }
                }
                None => {
                    self.missed += 1;
                    if let Some(s) = self.stamps.as_mut() {
                        s.push(None);
                    }
                }
            }
            self.record(&sent, pres.as_ref());
            if let (Some(note), true) = (note, self.recording) {
                if let Some(e) = self.exchanges.last_mut() {
                    if !e.received.is_empty() {
                        e.received.push_str("; ");
                    }
                    e.received.push_str(&note);
                }
            }
            if let Some(reached) = reached {
                return Err(MnError::LossOfPres { node, reached });
            }
            if let Some(u) = unexpected {
                return Err(MnError::PresState {
                    node,
                    said: u.said,
                    expected: u.expected,
                });
            }
        }
        self.asynchronous(service, node)
    }

    /// Stops watching for PRes until the node answers a PReq again: it stops answering on
    /// purpose (NMT stop or reset, the MN's silence, another node id).
    fn stop_watching(&mut self) {
        self.answering = false;
        self.watch.forget();
    }

    /// Notes how this cycle's PRes came (`got`: within its window; its PReq left at `sent`,
    /// on the real clock and the link's) when `watching`, after the node's late PRes: the
    /// threshold reached, if it was, and a note for the cycle's exchange (a PRes missing, a
    /// loss counted or not). A PRes still missing is decided [`MIN_LATE_ROOM`] after its PReq
    /// on the link's clock (a node sharing a loaded host is held back that long, and its PRes
    /// then comes late), and excused when the host lost time enough meanwhile to have held it
    /// back longer ([`crate::timing::excuses`], over that span): never on the embedded node's
    /// virtual clock.
    fn watch_pres(
        &mut self,
        watching: bool,
        got: bool,
        sent: (Instant, Duration),
    ) -> (Option<Reached>, Option<String>) {
        if got {
            self.unmatched = self.unmatched.saturating_sub(1);
        }
        let late = std::mem::take(&mut self.unmatched);
        if !watching {
            return (None, None);
        }
        self.watch.came_late(late);
        let real = !self.is_virtual();
        let (now, link_now) = (Instant::now(), self.link.now());
        let decide = |(at, link_at): (Instant, Duration)| {
            if link_now.saturating_sub(link_at) < MIN_LATE_ROOM {
                Decision::Wait
            } else if real && crate::timing::excuses(crate::timing::host_lost(at, now), now - at) {
                Decision::Excused
            } else {
                Decision::Lost
            }
        };
        let before = (self.watch.cumulative(), self.watch.uncounted());
        let reached = if got {
            self.watch.in_time(decide)
        } else {
            self.watch.missing(sent, decide)
        };
        let mut notes = Vec::new();
        if !got {
            notes.push(format!(
                "no PRes within {}",
                crate::timing::ms(self.config.reply)
            ));
        }
        let (late, excused) = self.watch.uncounted();
        if late != before.1 .0 {
            notes.push("a missing PRes came late: no loss".into());
        }
        if excused != before.1 .1 {
            notes.push("a missing PRes not counted lost: the host ran late meanwhile".into());
        }
        if self.watch.cumulative() != before.0 {
            notes.push(format!(
                "a PRes of node {} missing for {} counted lost (1C07h {}, 1C08h {} of \
                 threshold {})",
                self.config.node,
                crate::timing::ms(MIN_LATE_ROOM),
                self.watch.cumulative(),
                self.watch.count(),
                loss::DEFAULT_THRESHOLD
            ));
        }
        (reached, (!notes.is_empty()).then(|| notes.join("; ")))
    }

    /// The asynchronous phase of a cycle: the SoA inviting the MN itself to send what is
    /// queued, or asking `node` for `service`, and its answer.
    fn asynchronous(
        &mut self,
        service: RequestedService,
        node: u8,
    ) -> Result<Option<Received>, MnError> {
        if let Some((service_id, payload)) = self.queued.pop_front() {
            let soa = self.soa(RequestedService::UNSPECIFIED_INVITE, MN_NODE_ID)?;
            self.record(&soa, None);
            let sent = self.send(&EplRepr {
                dst: node,
                src: MN_NODE_ID,
                body: Body::Asnd(Asnd {
                    service: service_id,
                    payload,
                }),
            })?;
            self.record(&sent, None);
            return Ok(None);
        }
        // A new error of the node (EN toggled): its StatusResponse, in a slot nobody asked for.
        let fetch = self.exception && service == RequestedService::NO_SERVICE;
        let service = if fetch {
            RequestedService::STATUS_REQUEST
        } else {
            service
        };
        let sent = self.soa(service, node)?;
        let expects = service != RequestedService::NO_SERVICE;
        let answer = if expects {
            // The asynchronous phase lasts until the next SoC: the asked node may answer
            // until then (at least the reply time).
            let phase = self.next_cycle.saturating_sub(self.link.now());
            let w = self.wait(self.config.reply.max(phase));
            self.wait_for(&w, |r| matches!(r.body, Body::Asnd(_)))?
        } else {
            None
        };
        if expects {
            self.record(&sent, answer.as_ref());
        }
        if let Some(Received {
            repr:
                Some(EplRepr {
                    body: Body::Asnd(a),
                    ..
                }),
            ..
        }) = &answer
        {
            if a.service == ServiceId::STATUS_RESPONSE {
                if let Ok(s) = StatusResponse::parse(&a.payload) {
                    self.status_read(&s);
                }
            }
        }
        Ok(if fetch { None } else { answer })
    }

    /// Takes in a StatusResponse of the node: EA follows its EN (the new error is fetched),
    /// and the entries it did not list before are signalled.
    fn status_read(&mut self, s: &StatusResponse) {
        self.ea = s.flags.en;
        self.exception = false;
        if let Some(before) = &self.entries {
            let new = s.entries.iter().filter(|e| !before.contains(e)).copied();
            self.signalled.extend(new);
        }
        self.entries = Some(s.entries.clone());
    }

    /// The error entries the node signalled (EN toggled, or a StatusResponse read) since the
    /// last call: not in its StatusResponse before.
    pub(crate) fn take_signalled(&mut self) -> Vec<ErrorEntry> {
        std::mem::take(&mut self.signalled)
    }

    fn soa(&mut self, service: RequestedService, target: u8) -> Result<Vec<u8>, MnError> {
        self.send(&EplRepr {
            dst: BROADCAST_NODE_ID,
            src: MN_NODE_ID,
            body: Body::Soa(Soa {
                state: self.mn_state,
                service,
                target,
                epl_version: 0x20,
                ..Soa::default()
            }),
        })
    }

    /// Waits for a frame of the node that `want` accepts; SDO frames are kept for the SDO
    /// client, others dropped.
    fn wait_for(
        &mut self,
        w: &Wait,
        want: impl Fn(&EplRepr) -> bool,
    ) -> Result<Option<Received>, MnError> {
        while let Some(r) = self.receive_within(w)? {
            match &r.repr {
                Some(repr) if want(repr) => return Ok(Some(r)),
                // A frame of the node that is not POWERLINK at all: the caller decides.
                None => return Ok(Some(r)),
                Some(_) if is_sdo(&r) && self.asnd.len() < LATE_KEPT => self.asnd.push_back(r),
                Some(_) => {}
            }
        }
        Ok(None)
    }

    /// Runs `n` cycles with no asynchronous request.
    pub(crate) fn run_cycles(&mut self, n: u64) -> Result<(), MnError> {
        for _ in 0..n {
            self.cycle(RequestedService::NO_SERVICE)?;
        }
        Ok(())
    }

    /// Runs cycles one period apart on a fixed grid until `end` on the link's clock; returns
    /// how many ran. A cycle that starts late does not move the ones after it (a cycle is
    /// isochronous, DS 301 §4.2.4.1), and a run behind its schedule ends on time with fewer
    /// cycles: with the next cycle always one period after the last one started, a thousand
    /// cycles of 1 ms lasted 1.3 s and more on a loaded host, and the node's drive ramped for
    /// that long.
    pub(crate) fn run_cycles_until(&mut self, end: Duration) -> Result<u64, MnError> {
        let mut due = self.next_cycle.max(self.link.now());
        let mut n = 0;
        while due < end && self.link.now() < end {
            self.next_cycle = due;
            self.cycle(RequestedService::NO_SERVICE)?;
            n += 1;
            due += self.config.cycle;
        }
        Ok(n)
    }

    /// Lets `d` pass without sending anything (the MN "fails", the cable is cut); the next
    /// cycle resumes as before, as an MN whose link comes back does.
    pub(crate) fn silence(&mut self, d: Duration) {
        self.stop_watching();
        self.expect.forget();
        let until = self.link.now() + d;
        self.link.wait_until(until);
        self.next_cycle = until;
    }

    /// Asks the node for `service` once per cycle until it answers with an ASnd of `id`, within
    /// the limit of [`MnConfig::asked`].
    fn ask(&mut self, service: RequestedService, id: ServiceId) -> Result<Vec<u8>, MnError> {
        let w = self.wait(self.config.asked);
        loop {
            if let Some(r) = self.cycle(service)? {
                match r.repr {
                    Some(EplRepr {
                        body: Body::Asnd(a),
                        ..
                    }) if a.service == id => return Ok(a.payload),
                    Some(_) => {}
                    None => {
                        return Err(MnError::Malformed {
                            node: self.config.node,
                            what: format!("SoA {}", service),
                            why: format!("not a POWERLINK frame: {}", hex(&r.bytes)),
                        })
                    }
                }
            }
            if self.passed(&w) {
                return Err(self.timed_out(&w, format!("SoA {service}")));
            }
        }
    }

    /// The node's IdentResponse.
    pub(crate) fn ident(&mut self) -> Result<IdentResponse, MnError> {
        let p = self.ask(RequestedService::IDENT_REQUEST, ServiceId::IDENT_RESPONSE)?;
        let id = IdentResponse::parse(&p).map_err(|e| self.malformed("IdentRequest", e))?;
        self.node_state = Some(id.state);
        Ok(id)
    }

    /// The node's StatusResponse to a SoA sent on its own, outside the cycle: no SoC or PReq
    /// goes out, so a node in PRE_OPERATIONAL_1 (after the loss of its MN) stays there.
    pub(crate) fn peek_status(&mut self) -> Result<StatusResponse, MnError> {
        let node = self.config.node;
        let sent = self.soa(RequestedService::STATUS_REQUEST, node)?;
        let w = self.wait(self.config.reply.max(self.config.cycle));
        let got = self.wait_for(
            &w,
            |r| matches!(&r.body, Body::Asnd(a) if a.service == ServiceId::STATUS_RESPONSE),
        )?;
        self.record(&sent, got.as_ref());
        let Some(Received {
            repr:
                Some(EplRepr {
                    body: Body::Asnd(a),
                    ..
                }),
            ..
        }) = got
        else {
            return Err(self.timed_out(&w, "SoA StatusRequest"));
        };
        let s =
            StatusResponse::parse(&a.payload).map_err(|e| self.malformed("StatusRequest", e))?;
        self.status_read(&s);
        self.node_state = Some(s.state);
        Ok(s)
    }

    /// The node's StatusResponse.
    pub(crate) fn status(&mut self) -> Result<StatusResponse, MnError> {
        let p = self.ask(RequestedService::STATUS_REQUEST, ServiceId::STATUS_RESPONSE)?;
        let s = StatusResponse::parse(&p).map_err(|e| self.malformed("StatusRequest", e))?;
        self.node_state = Some(s.state);
        Ok(s)
    }

    fn malformed(&self, what: &str, e: proto::wire::Error) -> MnError {
        MnError::Malformed {
            node: self.config.node,
            what: what.into(),
            why: e.to_string(),
        }
    }

    /// Sends an NMT command in the MN's asynchronous slot, then asks the node's state (a
    /// StatusResponse). After a reset command the node starts over in NOT_ACTIVE, where any
    /// SoA or SoC moves it on: the MN asks nothing (`None`); its cycle, when it runs again,
    /// takes the node back through PRE_OPERATIONAL_1 and 2, with new SDO connections.
    pub(crate) fn nmt(&mut self, command: NmtCommand) -> Result<Option<NmtState>, MnError> {
        let payload = NmtCommandFrame {
            command,
            data: Vec::new(),
        }
        .emit();
        let before = self.node_state;
        let reset = is_reset(command);
        if reset || command == NmtCommand::STOP_NODE {
            self.stop_watching();
        }
        let expected = before.and_then(|b| command.next_state(b));
        if reset {
            self.expect.forget();
        } else {
            self.expect.commanded(before, expected);
        }
        self.queued.push_back((ServiceId::NMT_COMMAND, payload));
        self.cycle(RequestedService::NO_SERVICE)?;
        if reset {
            self.node_state = None;
            self.drop_connections();
            return Ok(None);
        }
        // The MN follows its node (DS 301: the MN enters RTO/OP with its nodes), and polls a
        // node it stopped no more; the state read below corrects it if the node did not stop.
        match command {
            NmtCommand::ENABLE_READY_TO_OPERATE => self.mn_state = NmtState::READY_TO_OPERATE,
            NmtCommand::START_NODE => self.mn_state = NmtState::OPERATIONAL,
            NmtCommand::STOP_NODE => self.node_state = Some(NmtState::STOPPED),
            _ => {}
        }
        // The node acts on the command within a few cycles (at once, if it runs as fast as
        // the simulator): its state is read until it shows the command's effect, a few times.
        let mut state = self.status()?.state;
        for _ in 0..SETTLE_READS {
            if expected.is_none_or(|e| e == state) {
                break;
            }
            state = self.status()?.state;
        }
        Ok(Some(state))
    }

    /// An NMT state command the boot needs to succeed.
    fn nmt_to(&mut self, command: NmtCommand) -> Result<NmtState, MnError> {
        Ok(self.nmt(command)?.unwrap_or(NmtState::NOT_ACTIVE))
    }

    /// Boots the node to `target` the way an MN does (DS 301 §7.1.4.2): SoA alone with
    /// IdentRequests until it answers (it is then in PRE_OPERATIONAL_1), the isochronous
    /// cycle (its SoC takes it to PRE_OPERATIONAL_2), EnableReadyToOperate, StartNode.
    pub(crate) fn boot(&mut self, target: NmtState) -> Result<NmtState, MnError> {
        let mut state = self.status().map(|s| s.state).ok();
        if state.is_none() || state == Some(NmtState::NOT_ACTIVE) {
            self.phase = Phase::Reduced;
            self.mn_state = NmtState::PRE_OPERATIONAL_1;
            state = Some(self.ident()?.state);
        }
        let rank = |s: NmtState| match s {
            NmtState::PRE_OPERATIONAL_1 => 1,
            NmtState::PRE_OPERATIONAL_2 => 2,
            NmtState::READY_TO_OPERATE => 3,
            NmtState::OPERATIONAL => 4,
            _ => 0,
        };
        let mut state = state.unwrap_or(NmtState::NOT_ACTIVE);
        if matches!(state, NmtState::BASIC_ETHERNET) {
            self.cycle(RequestedService::NO_SERVICE)?;
            state = self.status()?.state;
        }
        // Down to PRE_OPERATIONAL_2 the ways the CN takes (EnterPreOperational2 from
        // OPERATIONAL and STOPPED; READY_TO_OPERATE by way of STOPPED).
        if rank(target) >= 2 && rank(target) < rank(state)
            || state == NmtState::STOPPED && target != NmtState::STOPPED
        {
            if state == NmtState::READY_TO_OPERATE {
                self.nmt_to(NmtCommand::STOP_NODE)?;
            }
            state = self.nmt_to(NmtCommand::ENTER_PRE_OPERATIONAL_2)?;
        }
        if rank(target) >= 2 || target == NmtState::STOPPED {
            // From PRE_OPERATIONAL_2 on the node needs the isochronous cycle (it takes a lost
            // SoC for a failed MN): the MN runs it, whatever state it found the node in.
            if self.phase != Phase::Isochronous {
                self.phase = Phase::Isochronous;
                if rank(self.mn_state) < 2 {
                    self.mn_state = NmtState::PRE_OPERATIONAL_2;
                }
            }
            if rank(state) <= 1 {
                self.run_cycles(2)?;
                state = self.status()?.state;
            }
        }
        if rank(target) >= 3 && rank(state) == 2 {
            state = self.nmt_to(NmtCommand::ENABLE_READY_TO_OPERATE)?;
        }
        if rank(target) >= 4 && rank(state) == 3 {
            state = self.nmt_to(NmtCommand::START_NODE)?;
        }
        if target == NmtState::STOPPED && state != NmtState::STOPPED {
            state = self.nmt_to(NmtCommand::STOP_NODE)?;
        }
        if state != target {
            return Err(MnError::State {
                node: self.config.node,
                state,
                wanted: target,
                what: "the boot-up".into(),
            });
        }
        Ok(state)
    }

    /// Whether the isochronous phase runs.
    pub(crate) fn is_cycling(&self) -> bool {
        self.phase == Phase::Isochronous
    }

    /// Sends raw SDO bytes (sequence and command layers) to the node over `via` and collects
    /// what it answers within the SDO time; the connection's numbering is the caller's.
    pub(crate) fn sdo_raw(&mut self, via: Via, bytes: &[u8]) -> Result<Vec<Vec<u8>>, MnError> {
        match via {
            Via::Udp => {
                let mut d = proto::epl::sdo::UDP_PREFIX.to_vec();
                d.extend(bytes);
                let w = self.wait(self.config.sdo);
                // Raw bytes belong to no transfer: the first answer is theirs.
                self.udp_exchange(&d, &w, |_| true)
            }
            Via::Asnd => {
                self.queued.push_back((ServiceId::SDO, bytes.to_vec()));
                self.cycle(RequestedService::NO_SERVICE)?;
                let mut out = Vec::new();
                for _ in 0..4 {
                    if let Some(r) = self.cycle(RequestedService::UNSPECIFIED_INVITE)? {
                        if let Some(EplRepr {
                            body: Body::Asnd(a),
                            ..
                        }) = r.repr
                        {
                            if a.service == ServiceId::SDO {
                                out.push(a.payload);
                            }
                        }
                    }
                }
                Ok(out)
            }
        }
    }

    /// Sends a datagram and gathers the node's answers until one that `ends` the exchange
    /// (it is complete: waiting on for one more would cost the reply time on every request,
    /// rounded up to whole jiffies by SO_RCVTIMEO) or until `w` is over.
    fn udp_exchange(
        &mut self,
        datagram: &[u8],
        w: &Wait,
        ends: impl Fn(&[u8]) -> bool,
    ) -> Result<Vec<Vec<u8>>, MnError> {
        self.link.send_udp(datagram)?;
        let mut out = Vec::new();
        loop {
            let end = self.end(w);
            let Some(d) = self.link.recv_udp(end)? else {
                if self.passed(w) {
                    break;
                }
                continue;
            };
            let got = Received {
                repr: None,
                bytes: d.clone(),
                stamp: None,
                ether: None,
            };
            if self.recording {
                self.exchanges.push(Exchange {
                    sent_hex: hex(datagram),
                    sent: describe::udp(datagram),
                    received_hex: hex(&got.bytes),
                    received: describe::udp(&got.bytes),
                });
            }
            let payload = d
                .get(proto::epl::sdo::UDP_PREFIX.len()..)
                .unwrap_or_default()
                .to_vec();
            let done = ends(&payload);
            out.push(payload);
            if done {
                break;
            }
        }
        if out.is_empty() && self.recording {
            self.exchanges.push(Exchange {
                sent_hex: hex(datagram),
                sent: describe::udp(datagram),
                received_hex: String::new(),
                received: String::new(),
            });
        }
        Ok(out)
    }

    /// One SDO command over `via`, the connection opened first if need be; the answer's
    /// data (segments joined) or the node's abort.
    pub(crate) fn sdo(&mut self, via: Via, mut command: Command) -> Result<Vec<u8>, MnError> {
        let what = || format!("SDO {:?}", command.command);
        self.transaction = (self.transaction + 1) % 16;
        command.transaction = self.transaction;
        let mut conn = match self.connection(via) {
            Some(c) => c,
            None => self.open(via)?,
        };
        conn.sent = next(conn.sent);
        let frame = SdoFrame {
            seq: Seq {
                rsnr: conn.received,
                rcon: Con::Valid,
                ssnr: conn.sent,
                scon: Con::Valid,
            },
            command: Some(command.clone()),
        };
        let bytes = frame
            .emit()
            .map_err(|e| self.malformed("an SDO request", e))?;
        let tid = command.transaction;
        let w = self.wait(self.config.sdo);
        let answers = self.exchange(via, &bytes, &what(), &w, |f| {
            f.seq.rcon == Con::ErrorOrAckRequest
                || f.command
                    .as_ref()
                    .is_some_and(|c| c.transaction == tid && (c.response || c.abort))
        })?;
        let mut data = Vec::new();
        let mut done = false;
        for a in &answers {
            let f = SdoFrame::parse(a).map_err(|e| self.malformed("an SDO request", e))?;
            conn.received = f.seq.ssnr;
            let Some(c) = f.command else { continue };
            if let Some(code) = c.abort_code() {
                self.set_connection(
                    via,
                    if f.seq.rcon == Con::ErrorOrAckRequest {
                        None
                    } else {
                        Some(conn)
                    },
                );
                return Err(MnError::Abort(code));
            }
            if c.transaction != command.transaction || !c.response {
                continue;
            }
            data.extend(&c.payload);
            if matches!(
                c.segmentation,
                Segmentation::Expedited | Segmentation::Complete
            ) {
                done = true;
                break;
            }
        }
        self.set_connection(via, Some(conn));
        if !done {
            return Err(self.timed_out(&w, what()));
        }
        Ok(data)
    }

    fn connection(&self, via: Via) -> Option<Connection> {
        match via {
            Via::Asnd => self.asnd_link,
            Via::Udp => self.udp_link,
        }
    }

    fn set_connection(&mut self, via: Via, c: Option<Connection>) {
        match via {
            Via::Asnd => self.asnd_link = c,
            Via::Udp => self.udp_link = c,
        }
    }

    /// Closes whatever SDO connection of this MN the node still holds (a device on the
    /// network keeps them from case to case), over ASnd and UDP: SendCon "no connection".
    pub(crate) fn close_sdo(&mut self) -> Result<(), MnError> {
        let close = SdoFrame::default();
        let bytes = close
            .emit()
            .map_err(|e| self.malformed("an SDO close", e))?;
        self.queued.push_back((ServiceId::SDO, bytes));
        self.cycle(RequestedService::NO_SERVICE)?;
        let d = close
            .emit_udp()
            .map_err(|e| self.malformed("an SDO close", e))?;
        self.link.send_udp(&d)?;
        self.drop_connections();
        Ok(())
    }

    /// Forgets the SDO connections (the node was reset).
    pub(crate) fn drop_connections(&mut self) {
        self.asnd_link = None;
        self.udp_link = None;
    }

    /// Opens an SDO connection in the four frames of DS 301's connection set-up before any
    /// command: SendCon "initialisation"; the node answers ReceiveCon and SendCon
    /// "initialisation"; the MN confirms with SendCon "valid", ReceiveCon "initialisation"; the
    /// node answers "valid" both ways. A command in the third frame is lost on a server that
    /// takes that frame for the confirmation alone (openPOWERLINK's, docs/interop.md).
    fn open(&mut self, via: Via) -> Result<Connection, MnError> {
        let w = self.wait(self.config.sdo);
        let request = Seq {
            rsnr: 0,
            rcon: Con::None,
            ssnr: 0,
            scon: Con::Init,
        };
        let ack = self.handshake(via, request, "SDO initialisation", &w, |s| {
            s.rcon == Con::Init
        })?;
        let confirm = Seq {
            rsnr: ack.ssnr,
            rcon: Con::Init,
            ssnr: 0,
            scon: Con::Valid,
        };
        let valid = self.handshake(via, confirm, "SDO connection confirmation", &w, |s| {
            s.rcon == Con::Valid && s.scon == Con::Valid
        })?;
        let c = Connection {
            sent: 0,
            received: valid.ssnr,
        };
        self.set_connection(via, Some(c));
        Ok(c)
    }

    /// One frame of the connection set-up, and the node's answer that `accepts` takes.
    fn handshake(
        &mut self,
        via: Via,
        seq: Seq,
        what: &str,
        w: &Wait,
        accepts: impl Fn(&Seq) -> bool,
    ) -> Result<Seq, MnError> {
        let frame = SdoFrame { seq, command: None };
        let bytes = frame
            .emit()
            .map_err(|e| self.malformed("an SDO connection", e))?;
        let answers = self.exchange(via, &bytes, what, w, |f| accepts(&f.seq))?;
        for a in answers {
            let f = SdoFrame::parse(&a).map_err(|e| self.malformed("an SDO connection", e))?;
            if accepts(&f.seq) {
                return Ok(f.seq);
            }
        }
        Err(self.timed_out(w, what))
    }

    /// Sends SDO bytes and gathers the node's SDO frames that `answers` accepts, within `w`
    /// (an answer the node completes ends the wait): over ASnd, invited cycle after cycle
    /// until one answers (then the further segments); over UDP, the datagrams. Frames of
    /// earlier transfers that come late are passed over.
    fn exchange(
        &mut self,
        via: Via,
        bytes: &[u8],
        what: &str,
        w: &Wait,
        answers: impl Fn(&SdoFrame) -> bool,
    ) -> Result<Vec<Vec<u8>>, MnError> {
        let ours = |b: &[u8]| SdoFrame::parse(b).is_ok_and(|f| answers(&f));
        if via == Via::Udp {
            let mut d = proto::epl::sdo::UDP_PREFIX.to_vec();
            d.extend(bytes);
            let mut out = self.udp_exchange(&d, w, |p| ours(p) && !more_follows(p))?;
            out.retain(|b| ours(b));
            if out.is_empty() {
                return Err(self.timed_out(w, what));
            }
            return Ok(out);
        }
        self.queued.push_back((ServiceId::SDO, bytes.to_vec()));
        self.cycle(RequestedService::NO_SERVICE)?;
        let mut out = Vec::new();
        while !self.passed(w) {
            let late = self.asnd.pop_front();
            let got = match late {
                Some(r) => Some(r),
                None => self.cycle(RequestedService::UNSPECIFIED_INVITE)?,
            };
            let Some(r) = got else {
                if out.is_empty() {
                    continue;
                }
                break;
            };
            match r.repr {
                Some(EplRepr {
                    body: Body::Asnd(a),
                    ..
                }) if a.service == ServiceId::SDO && !ours(&a.payload) => {}
                Some(EplRepr {
                    body: Body::Asnd(a),
                    ..
                }) if a.service == ServiceId::SDO => {
                    let more = more_follows(&a.payload);
                    out.push(a.payload);
                    if !more {
                        return Ok(out);
                    }
                }
                Some(_) => {}
                None => {
                    return Err(MnError::Malformed {
                        node: self.config.node,
                        what: what.into(),
                        why: format!("not a POWERLINK frame: {}", hex(&r.bytes)),
                    })
                }
            }
        }
        if out.is_empty() {
            return Err(self.timed_out(w, what));
        }
        Ok(out)
    }

    /// Sends a raw POWERLINK frame and waits for the node's answer to it, up to
    /// [`RAW_ANSWER_CYCLES`] cycles. Frames already queued are dropped first, and a PRes or
    /// ASnd counts only after a PReq or SoA: a late answer to an earlier request (a busy host,
    /// a slow device) is not this frame's.
    pub(crate) fn raw_exchange(&mut self, bytes: &[u8]) -> Result<Option<Received>, MnError> {
        let now = self.link.now();
        while self.receive(now)?.is_some() {}
        self.send_raw(bytes)?;
        let w = self.wait(self.config.reply.max(self.config.cycle) * RAW_ANSWER_CYCLES);
        let sent = bytes.first().map(|b| MessageType(b & 0x7F));
        let mut answer = None;
        while let Some(r) = self.receive_within(&w)? {
            if can_answer(sent, &r) {
                answer = Some(r);
                break;
            }
        }
        if self.recording {
            self.record(bytes, answer.as_ref());
        }
        Ok(answer)
    }
}

/// Cycles a raw frame's answer is waited for. `answered` is no timing check (the cyclic steps
/// check timing): ten cycles let a loaded host's scheduling pass, and stay well inside the
/// node's loss-of-SoC time (ten cycles, at least 100 ms) across consecutive silent steps.
const RAW_ANSWER_CYCLES: u32 = 10;

/// Whether a frame of the node can answer a frame of type `sent`: a PRes answers only a PReq,
/// an ASnd only an SoA (EPSG DS 301: a CN sends PRes when a PReq polls it, ASnd when an SoA
/// invites it).
fn can_answer(sent: Option<MessageType>, reply: &Received) -> bool {
    match reply.bytes.first().map(|b| MessageType(b & 0x7F)) {
        Some(MessageType::PRES) => sent == Some(MessageType::PREQ),
        Some(MessageType::ASND) => sent == Some(MessageType::SOA),
        _ => true,
    }
}

/// Whether a frame of the node is an ASnd SDO frame.
fn is_sdo(r: &Received) -> bool {
    matches!(&r.repr, Some(EplRepr { body: Body::Asnd(a), .. }) if a.service == ServiceId::SDO)
}

/// Whether an SDO frame of the node announces more segments of its answer.
fn more_follows(sdo: &[u8]) -> bool {
    SdoFrame::parse(sdo)
        .ok()
        .and_then(|f| f.command)
        .is_some_and(|c| {
            matches!(
                c.segmentation,
                Segmentation::Initiate | Segmentation::Segment
            ) && c.abort_code().is_none()
        })
}

/// Whether `c` resets the node, which then starts over in NOT_ACTIVE (DS 301 §7.1.3).
fn is_reset(c: NmtCommand) -> bool {
    matches!(
        c,
        NmtCommand::RESET_NODE
            | NmtCommand::RESET_COMMUNICATION
            | NmtCommand::RESET_CONFIGURATION
            | NmtCommand::SW_RESET
    )
}

/// Whether a node in `s` answers a PReq with a PRes (EPSG DS 301 §7.1.4: the isochronous
/// phase of NMT_CS_PRE_OPERATIONAL_2, READY_TO_OPERATE and OPERATIONAL).
fn answers_preq(s: NmtState) -> bool {
    matches!(
        s,
        NmtState::PRE_OPERATIONAL_2 | NmtState::READY_TO_OPERATE | NmtState::OPERATIONAL
    )
}

/// The NMT state an ASnd of the node carries (IdentResponse, StatusResponse).
fn asnd_state(a: &Asnd) -> Option<NmtState> {
    match a.service {
        ServiceId::IDENT_RESPONSE | ServiceId::STATUS_RESPONSE => {
            a.payload.get(2).map(|&s| NmtState(s))
        }
        _ => None,
    }
}
