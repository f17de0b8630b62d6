//! The POWERLINK binding: the harness as managing node of one NORD controlled node (BU 0620
//! §2.4, BU 2200), in-process against the simulated node or on a network interface.
//!
//! Opening a DUT boots the node to PRE_OPERATIONAL_2 as an MN does (IdentRequest in the
//! reduced cycle, then the isochronous cycle) and reads its IdentResponse. `read`/`write` are
//! SDO transfers (over ASnd, or UDP with `--sdo udp`) of the parameter objects at device id +
//! parameter number (BU 0620 §2.4.6: 2000h + 600h·(FI−1); BU 2200 §6.4: the module at 2000h,
//! FU n at 2000h + 800h·n); `process`/`wait` run the cycle in OPERATIONAL with the control
//! word and setpoints of each inverter in the PReq and its status word and actual values in
//! the PRes, where the product's process map puts them. The `epl:` steps go to the MN as
//! written. A refusal is the node's SDO abort code.
//!
//! On a device on the network every SDO write goes through the shared [`Ledger`]; when the
//! case ends the binding stops the drives it ran, writes back what the case changed and
//! leaves the node in PRE_OPERATIONAL_2.

use std::time::Duration;

use proto::epl::asnd::ErrorEntry;
use proto::epl::sdo::Command;
use proto::epl::{MessageType, NmtCommand, NmtState};
use proto::nord::epl::{self as def, Slot};
use proto::nord::errors::SdoAbort;
use proto::nord::params;
use proto::nord::{addr, Inverter, ParamAddress, Product, Protocol};
use serde_json::{json, Value};

use super::mn::link::Link;
use super::mn::{describe, Manager, MnError, Via};
use super::step::EplStep;
use crate::binding::ledger::{Account, Ledger, Problem};
use crate::binding::objects::{self, Object, Unit};
use crate::binding::settle::{self, Cycling, Drives};
use crate::binding::simulator::{observe_device, OBSERVABLE};
use crate::binding::{
    process_run, process_time, Binding, CleanupError, Observation, OpenError, StepError,
};
use crate::hex::hex;
use crate::outcome::{Exchange, Identity, Refusal};
use crate::profile::Capability;
use crate::suite::{Action, OrderSpec};

/// What the embedded simulator offers (the parameters are SDO objects) and what a device on
/// the network offers.
pub(crate) const EMBEDDED_CAPABILITIES: [Capability; 9] = objects::embedded_capabilities("epl");
pub(crate) const NETWORK_CAPABILITIES: [Capability; 3] = objects::network_capabilities("epl");

/// How long the interface may go on showing cyclic process data after the drives stopped.
const QUIET_TIME: Duration = Duration::from_secs(2);
/// The "cyclic communication" bit of P872 / P173 [-01].
const CYCLIC: u8 = 1 << 1;
/// Cycles a process step runs on at most for a PRes in time after one came late.
const LATE_CYCLES: u32 = 20;

/// The harness as MN of one controlled node.
pub(crate) struct EplBinding<L> {
    mn: Manager<L>,
    /// The NORD product; `None` for any maker's node (profile `any@epl`).
    product: Option<Product>,
    what: String,
    capabilities: &'static [Capability],
    ledger: Option<Ledger<Object>>,
    pending: Vec<Exchange>,
    commanded: Vec<Inverter>,
    via: Via,
    /// The node id it was opened with.
    node: u8,
    /// NMT_FeatureFlags_U32 (1F82h) as the node's IdentResponse gives them: bit 1 "SDO by
    /// UDP/IP" decides whether the UDP cases apply (DS 301 §7.3.3.2.1, feature flags).
    feature_flags: u32,
    /// The case restarted the node, which then read in its addressing parameters (P160,
    /// P164; P850…P852): settings the cleanup puts back are read in only by another restart.
    restarted: bool,
    /// The case did something after which the node may signal an error (an injected fault,
    /// the MN's silence, a raw frame, a parameter written: P899 while controlled is E10.5).
    provoked: bool,
}

/// The refusal of an SDO abort code, with the manual's words for it.
fn abort(code: u32) -> Observation {
    let text = match SdoAbort(code).describe(Protocol::Powerlink) {
        Some(t) => format!("{code:08X}h {t}"),
        None => format!("{code:08X}h"),
    };
    Observation::refused(
        json!({ "abort": code }),
        Refusal {
            kind: "SDO abort code".into(),
            code,
            text,
        },
    )
}

/// The step error of the MN's: a node silent past its limit is late (a failure, unless the
/// runner finds the host was late meanwhile), not a broken link.
fn step_error(e: MnError) -> StepError {
    match e {
        MnError::Link(l) => StepError::Link(l.into()),
        MnError::NoReply {
            node,
            what,
            limit,
            waited,
        } => StepError::Late {
            what: format!("node {node}, {what}"),
            limit,
            waited,
        },
        e @ MnError::Malformed { .. } => StepError::Garbage(e.into()),
        e @ (MnError::LossOfPres { .. } | MnError::PresState { .. }) => {
            StepError::Departed(e.into())
        }
        e @ MnError::State { .. } => StepError::Refused(e.into()),
        MnError::Abort(code) => StepError::Refused(format!("SDO abort {code:08X}h").into()),
    }
}

fn refused_or(e: MnError) -> Result<Observation, StepError> {
    match e {
        MnError::Abort(code) => Ok(abort(code)),
        other => Err(step_error(other)),
    }
}

/// Why the node could not be opened.
pub(crate) fn open_error(e: MnError) -> OpenError {
    match e {
        MnError::Link(_) | MnError::NoReply { .. } => OpenError::Unreachable(e.to_string()),
        _ => OpenError::BringUp(e.to_string()),
    }
}

impl<L: Link> EplBinding<L> {
    /// Boots the node behind `mn` to PRE_OPERATIONAL_2 and reads who it is; `persistent` for
    /// a device on the network.
    pub(crate) fn open(
        mut mn: Manager<L>,
        product: Option<Product>,
        what: String,
        persistent: bool,
    ) -> Result<EplBinding<L>, OpenError> {
        let via = mn.config().via;
        mn.set_recording(false);
        mn.boot(NmtState::PRE_OPERATIONAL_2).map_err(open_error)?;
        mn.close_sdo().map_err(open_error)?;
        let id = mn.ident().map_err(open_error)?;
        if product.is_some() && id.vendor_id != def::VENDOR_ID {
            return Err(OpenError::BringUp(format!(
                "node {} has vendor id {:08X}h, not NORD's {:08X}h",
                mn.config().node,
                id.vendor_id,
                def::VENDOR_ID
            )));
        }
        let what = format!(
            "{what}: node {} \"{}\" (vendor {:08X}h, product {:08X}h, revision {:08X}h, IP {})",
            mn.config().node,
            id.hostname,
            id.vendor_id,
            id.product_code,
            id.revision,
            id.ip
        );
        mn.take_exchanges();
        mn.set_recording(true);
        let outputs = 2 * process_map(product, true).len();
        mn.set_outputs(vec![0; outputs], false);
        let node = mn.config().node;
        Ok(EplBinding {
            mn,
            product,
            what,
            capabilities: if persistent {
                &NETWORK_CAPABILITIES
            } else {
                &EMBEDDED_CAPABILITIES
            },
            ledger: persistent.then(Ledger::default),
            pending: Vec::new(),
            commanded: Vec::new(),
            via,
            node,
            feature_flags: id.feature_flags,
            restarted: false,
            provoked: false,
        })
    }

    /// The SDO object of a `read`/`write` step (BU 0620 §2.4.6: device id 2000h + 600h·(FI−1)
    /// + P, the interface's parameters FI 1's; BU 2200 §6.4: the module at 2000h + P, FU n at
    /// 2000h + 800h·n + P) and the parameter's definition.
    fn object(
        &self,
        o: &OrderSpec,
    ) -> Result<(Object, Option<&'static params::ParamDef>), StepError> {
        let product = self.product.ok_or_else(|| {
            StepError::NotApplicable("any maker's node has no NORD parameter objects".into())
        })?;
        let a = objects::address(product, o)?;
        let index = match a.unit {
            Unit::Interface => 0x2000 + o.number.get(),
            Unit::Inverter(inverter) => {
                addr::powerlink(
                    product,
                    ParamAddress {
                        inverter,
                        number: o.number,
                        set: a.set,
                        element: a.element,
                    },
                )
                .map_err(|e| StepError::Suite(e.into()))?
                .index
            }
        };
        let sub = addr::sdo_subindex(a.set, a.element);
        Ok((Object { index, sub }, a.def))
    }

    fn read(&mut self, o: &OrderSpec) -> Result<Observation, StepError> {
        let (obj, def) = self.object(o)?;
        let data = match self
            .mn
            .sdo(self.via, Command::read_by_index(0, obj.index, obj.sub))
        {
            Ok(d) => d,
            Err(e) => return refused_or(e),
        };
        let value = objects::value_of(obj, &data, def)?;
        Ok(json!({ "value": value, "data": hex(&data), "abort": null }).into())
    }

    fn write(&mut self, o: &OrderSpec) -> Result<Observation, StepError> {
        let (obj, def) = self.object(o)?;
        let data = objects::bytes_of(o, def)?;
        self.download(obj, &data, self.via)
    }

    /// An SDO write, through the ledger on a persistent device.
    fn download(&mut self, obj: Object, data: &[u8], via: Via) -> Result<Observation, StepError> {
        if self.ledger.as_ref().is_some_and(|l| l.wants_original(&obj)) {
            let before = self
                .mn
                .sdo(via, Command::read_by_index(0, obj.index, obj.sub))
                .map_err(|e| e.to_string());
            if let Some(l) = self.ledger.as_mut() {
                l.original(obj, before);
            }
        }
        let r = self
            .mn
            .sdo(via, Command::write_by_index(0, obj.index, obj.sub, data));
        if let Some(l) = self.ledger.as_mut() {
            // Only the node's refusal (an abort) surely left the object as it was.
            l.wrote(&obj, !matches!(r, Err(MnError::Abort(_))));
        }
        match r {
            Ok(_) => Ok(json!({ "abort": null, "ok": true }).into()),
            Err(e) => refused_or(e),
        }
    }

    /// The node in OPERATIONAL with the cycle running (booted the MN's way).
    fn operational(&mut self) -> Result<(), StepError> {
        if self.mn.node_state() == Some(NmtState::OPERATIONAL) && self.mn.is_cycling() {
            return Ok(());
        }
        self.mn.set_recording(false);
        let r = self.mn.boot(NmtState::OPERATIONAL);
        self.mn.set_recording(true);
        r.map(|_| ()).map_err(|e| match e {
            MnError::State { .. } => {
                StepError::Refused(format!("the node did not enter OPERATIONAL: {e}").into())
            }
            other => step_error(other),
        })
    }

    /// Process data for `cycles`, or for `time` on the link's clock when given.
    fn process(
        &mut self,
        inverter: Inverter,
        words: Option<[u16; 6]>,
        cycles: u32,
        time: Option<Duration>,
    ) -> Result<Value, StepError> {
        self.operational()?;
        self.mn.set_ready(true);
        if let Some(w) = words {
            if !self.commanded.contains(&inverter) {
                self.commanded.push(inverter);
            }
            set_words(&mut self.mn, self.product, inverter, w);
        }
        // The PRes of a cycle carries what the node had before that cycle's PReq: one more
        // cycle brings the inverter's answer to the last of them.
        match time {
            Some(d) => self.cycles_for(d),
            None => self.cycles(u64::from(cycles) + 1),
        }
        .map_err(step_error)?;
        // A PRes that missed its reply time (a node on a loaded host) leaves the inputs of the
        // cycle before it: the status is read from one that came in time, a few cycles on at
        // most. The transcript shows the PReq that got no answer.
        for _ in 0..LATE_CYCLES {
            if self.mn.in_time() {
                break;
            }
            self.cycles(1).map_err(step_error)?;
        }
        let i = inputs_of(&self.mn, self.product, inverter);
        Ok(crate::binding::process_fields(i[0], &i[1..]))
    }

    /// Runs `n` cycles, the transcript compacted.
    fn cycles(&mut self, n: u64) -> Result<(), MnError> {
        let mut c = NodeCycle {
            mn: &mut self.mn,
            product: self.product,
        };
        settle::run_cycles(&mut c, &mut self.pending, n)
    }

    /// Runs cycles for `d` on the link's clock and one more, the transcript compacted.
    fn cycles_for(&mut self, d: Duration) -> Result<(), MnError> {
        let mut c = NodeCycle {
            mn: &mut self.mn,
            product: self.product,
        };
        settle::run_cycles_for(&mut c, &mut self.pending, d)
    }

    /// The way of an SDO step: as it asks, else the run's; UDP only for a node whose feature
    /// flags declare SDO by UDP/IP (1F82h bit 1).
    fn via(&self, asked: Option<Via>) -> Result<Via, StepError> {
        let via = asked.unwrap_or(self.via);
        if via == Via::Udp && self.feature_flags & UDP_SDO == 0 {
            return Err(StepError::NotApplicable(format!(
                "node {} declares no SDO over UDP/IP (feature flags 1F82h = {:08X}h, bit 1 clear)",
                self.node, self.feature_flags
            )));
        }
        Ok(via)
    }

    /// An `epl:` step, as written.
    fn epl_step(&mut self, step: &EplStep) -> Result<Observation, StepError> {
        let fields = match step {
            EplStep::Nmt(c) => {
                self.restarted |= reads_in(*c);
                match self.mn.nmt(*c).map_err(step_error)? {
                    Some(state) => self.state_fields(state),
                    // A reset: the node restarts; the MN asks nothing that would move it on.
                    None => self.seen_fields(),
                }
            }
            EplStep::State(s) => {
                let state = self.mn.boot(*s).map_err(step_error)?;
                self.state_fields(state)
            }
            EplStep::Ident(node) => {
                if let Some(n) = node {
                    self.mn.set_node(*n);
                }
                let i = self.mn.ident().map_err(step_error)?;
                json!({
                    "node": self.mn.config().node,
                    "state": i.state.to_string(),
                    "vendor": i.vendor_id,
                    "product": i.product_code,
                    "revision": i.revision,
                    "serial": i.serial,
                    "device_type": i.device_type,
                    "epl_version": i.epl_version,
                    "feature_flags": i.feature_flags,
                    "mtu": i.mtu,
                    "poll_in": i.poll_in_size,
                    "poll_out": i.poll_out_size,
                    "ip": i.ip.to_string(),
                    "subnet": i.subnet.to_string(),
                    "gateway": i.gateway.to_string(),
                    "hostname": i.hostname,
                })
            }
            EplStep::Status => {
                let s = self.mn.status().map_err(step_error)?;
                let entries: Vec<Value> = s
                    .entries
                    .iter()
                    .map(|e| {
                        json!({
                            "type": e.entry_type,
                            "code": e.code,
                            "info": hex(&e.info.to_le_bytes()),
                            "text": String::from_utf8_lossy(&e.info.to_le_bytes()).trim().to_string(),
                        })
                    })
                    .collect();
                json!({
                    "state": s.state.to_string(),
                    "error_register": s.error_register,
                    "errors": entries.len(),
                    "entry": entries.first().cloned().unwrap_or(Value::Null),
                    "entries": entries,
                    "en": s.flags.en,
                })
            }
            EplStep::Upload { index, sub, via } => {
                let via = self.via(*via)?;
                match self.mn.sdo(via, Command::read_by_index(0, *index, *sub)) {
                    Ok(d) => {
                        let mut f =
                            json!({ "data": hex(&d), "size": d.len(), "abort": null, "ok": true });
                        if let Some(v) = number(&d) {
                            f["value"] = json!(v);
                        }
                        if !d.is_empty() && d.iter().all(|b| b.is_ascii_graphic() || *b == b' ') {
                            f["text"] = json!(String::from_utf8_lossy(&d));
                        }
                        f
                    }
                    Err(e) => return refused_or(e),
                }
            }
            EplStep::Download {
                index,
                sub,
                data,
                via,
            } => {
                let obj = Object {
                    index: *index,
                    sub: *sub,
                };
                return self.download(obj, data, self.via(*via)?);
            }
            EplStep::Frame(bytes) => {
                let preq = bytes.first().map(|t| MessageType(t & 0x7F)) == Some(MessageType::PREQ);
                if preq && bytes.get(4).is_some_and(|f| f & RD != 0) {
                    // A PReq as written, its payload valid (RD), carries control words the
                    // binding does not read: every inverter counts as commanded, and the
                    // cleanup takes each one back.
                    self.commanded = (1..=self.product.map_or(0, Product::max_inverters))
                        .filter_map(|n| Inverter::new(n.into()).ok())
                        .collect();
                }
                let got = self.mn.raw_exchange(bytes).map_err(step_error)?;
                let state = self.mn.node_state();
                let mut f = json!({
                    "answered": got.is_some(),
                    "reply": got.as_ref().map(|r| hex(&r.bytes)),
                    "state": state.map(|s| s.to_string()),
                });
                if let Some(r) = got.as_ref().and_then(|r| r.repr.as_ref()) {
                    f["type"] = json!(r.message_type().name());
                    f["decoded"] = json!(describe(r));
                }
                if let Some(e) = got.as_ref().and_then(|r| r.ether) {
                    // The Ethernet frame around it (BU 2200 §3.3): EtherType, multicast or
                    // unicast destination, length without the FCS (64 bytes with it).
                    f["ethertype"] = json!(e.ethertype);
                    f["multicast"] = json!(e.dst.is_multicast());
                    f["frame_length"] = json!(e.len);
                }
                f
            }
            EplStep::Sdo { bytes, via } => {
                let answers = self
                    .mn
                    .sdo_raw(self.via(*via)?, bytes)
                    .map_err(step_error)?;
                let mut f = json!({
                    "answered": !answers.is_empty(),
                    "reply": answers.first().map(|a| hex(a)),
                    "abort": null,
                });
                if let Some(a) = answers.first() {
                    if let Ok(sf) = proto::epl::sdo::SdoFrame::parse(a) {
                        f["rcon"] = json!(format!("{:?}", sf.seq.rcon));
                        if let Some(code) = sf.command.as_ref().and_then(|c| c.abort_code()) {
                            f["abort"] = json!(code);
                            return Ok(Observation::refused(
                                f,
                                abort(code).refusal.unwrap_or(Refusal {
                                    kind: "SDO abort code".into(),
                                    code,
                                    text: String::new(),
                                }),
                            ));
                        }
                    }
                }
                f
            }
            EplStep::Silence(d) => {
                self.mn.silence(*d);
                if self.mn.link_mut().device().is_some() || self.mn.node_state().is_none() {
                    // Embedded: looked into. On the network after a reset: asked nothing (a
                    // SoA would end the Basic Ethernet the silence may have led to).
                    self.seen_fields()
                } else {
                    // A node on the network is asked with a SoA alone, which leaves a node
                    // that lost its MN in PRE_OPERATIONAL_1.
                    let s = self.mn.peek_status().map_err(step_error)?;
                    self.state_fields(s.state)
                }
            }
            EplStep::Cycles(n) => {
                self.cycles(*n).map_err(step_error)?;
                let state = self.mn.node_state();
                json!({ "state": state.map(|s| s.to_string()) })
            }
        };
        Ok(fields.into())
    }

    /// A state as the node reported it, with the LEDs where the node can be looked into.
    fn state_fields(&mut self, state: NmtState) -> Value {
        let mut f = json!({ "state": state.to_string(), "code": state.0 });
        if let Some((node, _)) = self.mn.link_mut().device() {
            let (bs, be) = node.leds();
            f["leds"] = json!({ "bs": bs, "be": be });
        }
        f
    }

    /// The state without asking the node (an embedded node is looked into; a node on the
    /// network that has just been reset is asked nothing: any SoA would move it on).
    fn seen_fields(&mut self) -> Value {
        match self.mn.link_mut().device().map(|(n, _)| n.state()) {
            Some(state) => self.state_fields(state),
            None => json!({ "state": null }),
        }
    }

    /// `inject`/`observe` reach into the simulated node.
    fn simulated(&mut self) -> Result<(&mut sim::epl::Node, Duration), StepError> {
        self.mn
            .link_mut()
            .device()
            .ok_or_else(|| StepError::Refused("only the embedded node can be looked into".into()))
    }

    fn observe(&mut self, what: &str, inverter: Inverter) -> Result<Value, StepError> {
        let (node, now) = self.simulated()?;
        if what == "nmt" {
            return Ok(json!({ "state": node.state().to_string(), "code": node.state().0 }));
        }
        let (bs, be) = node.leds();
        let mut v = observe_device(node.device_mut(), what, inverter, now)
            .map_err(|e| StepError::Refused(e.into()))?
            .ok_or_else(|| {
                StepError::Refused(format!("cannot observe `{what}` ({OBSERVABLE}, nmt)").into())
            })?;
        if what == "leds" {
            v["bs"] = json!(bs);
            v["be"] = json!(be);
        }
        Ok(v)
    }

    /// A persistent device's cleanup: the drives the case ran back in "Switch-on block", the
    /// case's writes put back, the node in PRE_OPERATIONAL_2.
    fn restore(&mut self) -> Result<(), String> {
        let Some(ledger) = self.ledger.take() else {
            return Ok(());
        };
        let mut account = Account::default();
        let drove = !self.commanded.is_empty();
        if drove && account.attempt(|| "settling the drives".into()) {
            account.note(self.settle());
        }
        // SDO first needs a state that serves it, and a PDO mapping is written back only in
        // PRE_OPERATIONAL_2 (08000022h in OPERATIONAL, DS 301 §6.4.9).
        self.pre_operational_2(&mut account);
        let via = self.via;
        ledger.restore(&mut account, |obj, before| {
            self.mn
                .sdo(via, Command::write_by_index(0, obj.index, obj.sub, before))
                .map(|_| ())
                .map_err(|e| Problem::step(format!("setting back {obj}"), step_error(e)))
        });
        let restored = ledger.restores().next().is_some();
        if self.restarted
            && restored
            && account.attempt(|| "restarting the node to read the settings back in".into())
        {
            let r = self.mn.nmt(NmtCommand::SW_RESET);
            self.mn.set_node(self.node);
            account.note(
                r.map(|_| ())
                    .map_err(|e| Problem::step("restarting the node (NMTSwReset)", step_error(e))),
            );
            self.pre_operational_2(&mut account);
        }
        if drove && account.attempt(|| "waiting for the end of cyclic communication".into()) {
            account.note(self.quiet());
        }
        self.ledger = Some(Ledger::default());
        self.commanded.clear();
        self.restarted = false;
        account.into_result()
    }

    /// Boots the node back to PRE_OPERATIONAL_2, under `account`.
    fn pre_operational_2(&mut self, account: &mut Account) {
        if account.attempt(|| "back to PRE_OPERATIONAL_2".into()) {
            let r = self.mn.boot(NmtState::PRE_OPERATIONAL_2);
            account.note(
                r.map(|_| ())
                    .map_err(|e| Problem::step("back to PRE_OPERATIONAL_2", step_error(e))),
            );
        }
    }

    /// Waits until the interface no longer shows cyclic process data (SK 550P P872 bit 1,
    /// BU 0620 §4.3; the modules' P173 [-01] bit 1, BU 2200 §7.1.3), as the case found it.
    fn quiet(&mut self) -> Result<(), Problem> {
        let (number, sub) = if self.product == Some(Product::Sk550p) {
            (872, 0)
        } else {
            (173, 1)
        };
        let index = 0x2000 + number;
        let deadline = self.mn.now() + QUIET_TIME;
        loop {
            let v = self
                .mn
                .sdo(self.via, Command::read_by_index(0, index, sub))
                .map_err(|e| Problem::step(format!("reading P{number}"), step_error(e)))?;
            if v.first().copied().unwrap_or(0) & CYCLIC == 0 {
                return Ok(());
            }
            if self.mn.now() >= deadline {
                return Err(Problem::other(format!(
                    "P{number} still shows cyclic process data {QUIET_TIME:?} after the drives stopped"
                )));
            }
            self.mn
                .run_cycles(10)
                .map_err(|e| Problem::step("waiting", step_error(e)))?;
        }
    }

    /// Cycles the drives back to "Switch-on block".
    fn settle(&mut self) -> Result<(), Problem> {
        let what = |e: MnError| Problem::step("settling the drives", step_error(e));
        self.mn.boot(NmtState::OPERATIONAL).map_err(what)?;
        // A case whose control words came in PReq frames as written may not have set RD.
        self.mn.set_ready(true);
        let period = self.mn.config().cycle;
        let mut drives = Drives::new(
            self.product.map_or(0, Product::max_inverters),
            &self.commanded,
        );
        let mut c = NodeCycle {
            mn: &mut self.mn,
            product: self.product,
        };
        drives.settle(&mut c, &mut self.pending, period, what)
    }
}

/// NMT_FeatureFlags_U32 bit 1: SDO by UDP/IP (DS 301).
const UDP_SDO: u32 = 1 << 1;

/// The PReq's "ready" flag in its byte 4 (DS 301 §4.6.1.1.3): the payload is valid.
const RD: u8 = 0x01;

/// Whether the node reads its settings in again after `c`: every reset but that of the
/// communication profile alone (DS 301 NMT_GS_RESET_APPLICATION and _CONFIGURATION; "so that
/// the parameter settings are read in", BU 0620 §3.7.3, BU 2200 §5.2.5).
fn reads_in(c: NmtCommand) -> bool {
    matches!(
        c,
        NmtCommand::SW_RESET | NmtCommand::RESET_NODE | NmtCommand::RESET_CONFIGURATION
    )
}

/// The words of a NORD product's process map (BU 0620 §2.4.5, BU 2200 §6.3); any maker's
/// node has none the harness knows of.
fn process_map(product: Option<Product>, outputs: bool) -> Vec<def::MappedWord> {
    product.map_or_else(Vec::new, |p| def::process_map(p, outputs))
}

/// Puts FI `fi`'s six words into the PReq payload where the product's process map has them.
fn set_words<L: Link>(
    mn: &mut Manager<L>,
    product: Option<Product>,
    fi: Inverter,
    words: [u16; 6],
) {
    let out = mn.outputs_mut();
    for (i, m) in process_map(product, true).iter().enumerate() {
        if let Slot::Inverter { fi: f, word } = m.slot {
            if let (true, Some(b)) = (f == fi.get(), out.get_mut(2 * i..2 * i + 2)) {
                b.copy_from_slice(&words[usize::from(word)].to_le_bytes());
            }
        }
    }
}

/// FI `fi`'s six words from the last PRes.
fn inputs_of<L: Link>(mn: &Manager<L>, product: Option<Product>, fi: Inverter) -> [u16; 6] {
    let mut w = [0u16; 6];
    let inputs = mn.inputs();
    for (i, m) in process_map(product, false).iter().enumerate() {
        if let Slot::Inverter { fi: f, word } = m.slot {
            if let (true, Some(b)) = (f == fi.get(), inputs.get(2 * i..2 * i + 2)) {
                w[usize::from(word)] = u16::from_le_bytes([b[0], b[1]]);
            }
        }
    }
    w
}

/// The MN's cycle with the node's process data, as the shared loops run it.
struct NodeCycle<'a, L> {
    mn: &'a mut Manager<L>,
    product: Option<Product>,
}

impl<L: Link> Cycling for NodeCycle<'_, L> {
    type Error = MnError;
    fn run_cycles(&mut self, n: u64) -> Result<(), MnError> {
        self.mn.run_cycles(n)
    }
    fn take_exchanges(&mut self) -> Vec<Exchange> {
        self.mn.take_exchanges()
    }
    fn set_recording(&mut self, on: bool) {
        self.mn.set_recording(on)
    }
    fn set_words(&mut self, fi: Inverter, w: [u16; 6]) -> Result<(), MnError> {
        set_words(self.mn, self.product, fi, w);
        Ok(())
    }
    fn status_word(&mut self, fi: Inverter) -> Result<u16, MnError> {
        Ok(inputs_of(self.mn, self.product, fi)[0])
    }
}

impl<L: Link> settle::Clocked for NodeCycle<'_, L> {
    fn now(&self) -> Duration {
        self.mn.now()
    }
    fn run_cycles_until(&mut self, end: Duration) -> Result<u64, MnError> {
        self.mn.run_cycles_until(end)
    }
}

/// A little-endian number of 1, 2, 4 or 8 bytes (PDO mapping entries are UNSIGNED64).
fn number(d: &[u8]) -> Option<i64> {
    Some(match d {
        [a] => i64::from(*a),
        [a, b] => i64::from(u16::from_le_bytes([*a, *b])),
        [a, b, c, e] => i64::from(u32::from_le_bytes([*a, *b, *c, *e])),
        [..] if d.len() == 8 => {
            let mut b = [0u8; 8];
            b.copy_from_slice(d);
            i64::try_from(u64::from_le_bytes(b)).ok()?
        }
        _ => return None,
    })
}

impl<L: Link> Binding for EplBinding<L> {
    /// The node's IdentResponse (EPSG DS 301 §7.3.3.2.1): vendor, product code, revision and
    /// serial number, as the node sends them.
    fn identity(&mut self) -> Option<Result<Identity, StepError>> {
        Some(self.mn.ident().map_err(step_error).map(|i| Identity {
            source: format!(
                "IdentResponse of node {} (host name {:?})",
                self.mn.config().node,
                i.hostname
            ),
            vendor: Some(format!("{:08X}h", i.vendor_id)),
            product_code: Some(format!("{:08X}h", i.product_code)),
            // DS 301's identity has no product name; the host name is the node's, not the product's.
            product_name: None,
            revision: Some(format!("{:08X}h", i.revision)),
            serial: Some(format!("{:08X}h", i.serial)),
        }))
    }

    fn describe(&self) -> String {
        self.what.clone()
    }

    fn capabilities(&self) -> &[Capability] {
        self.capabilities
    }

    /// Performs the step; a node that signals an error the case neither provoked nor reads
    /// fails it (see [`unasked_error`]).
    fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
        let step = match action {
            Action::Bus(step) => step.as_any().downcast_ref::<EplStep>(),
            _ => None,
        };
        self.provoked |= matches!(action, Action::Inject { .. } | Action::Write(_))
            || matches!(
                step,
                Some(
                    EplStep::Silence(_)
                        | EplStep::Frame(_)
                        | EplStep::Download { .. }
                        | EplStep::Sdo { .. }
                )
            );
        let reads = matches!(step, Some(EplStep::Status));
        let r = self.act(action);
        let signalled = self.mn.take_signalled();
        match unasked_error(self.node, &signalled) {
            Some(e) if !self.provoked && !reads && r.is_ok() => Err(e),
            _ => r,
        }
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        let mut v = std::mem::take(&mut self.pending);
        v.extend(self.mn.take_exchanges());
        v
    }

    fn finish(&mut self) -> Result<(), CleanupError> {
        self.restore().map_err(CleanupError)
    }
}

/// The failure of a node that signalled `entries` (DS 301 §6.5: EN toggled, the MN fetched
/// its StatusResponse) in a case that neither provoked an error nor reads them: an error the
/// node reports though nothing in the case made one is a fault of the node's, and a case that
/// passed over it would hide it. A case that may provoke errors (an injected fault, the MN's
/// silence, a raw frame, a parameter written) judges them itself from then on, and a step
/// that reads the node's StatusResponse judges what it reads.
fn unasked_error(node: u8, entries: &[ErrorEntry]) -> Option<StepError> {
    let first = entries.first()?;
    let text = proto::nord::errors::powerlink_rows(first.code)
        .next()
        .map_or(String::new(), |r| format!(" {}", r.text));
    let info = String::from_utf8_lossy(&first.info.to_le_bytes())
        .trim()
        .to_string();
    let more = match entries.len() {
        1 => String::new(),
        n => format!(" and {} more", n - 1),
    };
    Some(StepError::Departed(
        format!(
            "node {node} signalled an error no step provoked (EN toggled; its StatusResponse \
             lists entry {:04X}h{text}, \"{info}\"{more})",
            first.code
        )
        .into(),
    ))
}

impl<L: Link> EplBinding<L> {
    /// A step of the case, as the runner asks it.
    fn act(&mut self, action: &Action) -> Result<Observation, StepError> {
        let fields = match action {
            Action::Compute { .. } => {
                return Err(StepError::Suite("compute is not a DUT step".into()))
            }
            Action::Read(o) => return self.read(o),
            Action::Write(o) => return self.write(o),
            Action::Pkw { .. } => {
                return Err(StepError::NotApplicable(
                    "POWERLINK has no PKW parameter channel: parameters are SDO objects \
                     (BU 0620 §2.4.6, BU 2200 §6.4)"
                        .into(),
                ))
            }
            Action::Process { .. } | Action::Wait(_) => {
                let (fi, words, cycles) = process_run(action, self.mn.config().cycle)?;
                let time = process_time(action, self.mn.link_mut().device().is_none());
                self.process(fi, words, cycles, time)?
            }
            Action::Inject { inverter, error } => {
                let (node, _) = self.simulated()?;
                if error == "lost" {
                    // The inverter drops off the system bus (as `inject: {error: lost}` over
                    // PROFINET).
                    node.lose_inverter(*inverter);
                } else {
                    node.device_mut()
                        .inject_fault(*inverter, error)
                        .map_err(|e| StepError::Refused(e.into()))?;
                }
                json!({})
            }
            Action::Observe { what, inverter } => self.observe(what, *inverter)?,
            Action::Bus(step) => {
                let step = crate::binding::own_step::<EplStep>(step.as_ref(), "POWERLINK")?;
                return self.epl_step(step);
            }
        };
        Ok(fields.into())
    }
}

#[cfg(test)]
mod tests {
    use std::cell::Cell;
    use std::net::SocketAddr;
    use std::rc::Rc;
    use std::time::Duration;

    use proto::eth::MacAddr;
    use proto::nord::{ParamNumber, Product};
    use sim::device::{Device, DeviceConfig};
    use sim::epl::{Node, NodeConfig};

    #[test]
    fn the_identity_is_the_ident_response() {
        let id = crate::embedded::identity_over(Product::Tu3Pol, "epl");
        assert!(id.source.starts_with("IdentResponse of node 1"), "{id:?}");
        assert_eq!(id.product_code.as_deref(), Some("00002203h"));
        assert!(id.revision.is_some() && id.serial.is_some(), "{id:?}");
    }

    use super::super::mn::link::{EmbeddedLink, NetLink, EMBEDDED_PEER};
    use super::super::mn::{Manager, MnConfig};
    use super::*;
    use crate::net::LinkError;
    use crate::outcome::Verdict;
    use crate::suite::Target;

    /// How the node behind [`Faulty`] misbehaves.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Fault {
        None,
        /// Nothing comes back.
        Silent,
        /// Every frame is answered with bytes that are no POWERLINK frame, from node 1.
        Garbage,
    }

    /// The embedded node behind a link that can turn silent or send garbage.
    struct Faulty {
        inner: EmbeddedLink,
        fault: Rc<Cell<Fault>>,
    }

    impl crate::net::peer::Link for Faulty {
        type Device = Node;
        fn now(&self) -> Duration {
            self.inner.now()
        }
        fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
            match self.fault.get() {
                Fault::None => self.inner.send(frame),
                _ => Ok(()),
            }
        }
        fn recv(
            &mut self,
            deadline: Duration,
        ) -> Result<Option<(Vec<u8>, Option<Duration>)>, LinkError> {
            match self.fault.get() {
                Fault::None => self.inner.recv(deadline),
                Fault::Silent => {
                    self.inner.wait_until(deadline);
                    Ok(None)
                }
                // Ethernet header from the node, EtherType 88ABh, message type 7Fh.
                Fault::Garbage => {
                    let mut f = vec![0xFF; 6];
                    f.extend([0xF0, 0x5F, 0x5A, 0, 0, 1, 0x88, 0xAB, 0x7F, 0xF0, 0x01]);
                    f.resize(60, 0xA5);
                    Ok(Some((f, None)))
                }
            }
        }
        fn send_udp(&mut self, d: &[u8]) -> Result<(), LinkError> {
            self.inner.send_udp(d)
        }
        fn recv_udp(&mut self, deadline: Duration) -> Result<Option<Vec<u8>>, LinkError> {
            self.inner.recv_udp(deadline)
        }
        fn wait_until(&mut self, until: Duration) {
            self.inner.wait_until(until)
        }
        fn udp_ends(&mut self) -> (SocketAddr, SocketAddr) {
            self.inner.udp_ends()
        }
        fn device(&mut self) -> Option<(&mut Node, Duration)> {
            self.inner.device()
        }
    }

    fn binding(fault: Rc<Cell<Fault>>) -> Result<EplBinding<Faulty>, OpenError> {
        let device = Device::new(DeviceConfig::new(Product::Sk550p));
        let node = Node::new(device, NodeConfig::new(1)).unwrap();
        let link = Faulty {
            inner: EmbeddedLink::new(node, EMBEDDED_PEER),
            fault,
        };
        let mn = Manager::new(link, MnConfig::default(), MacAddr([2, 0, 0, 0, 0, 0xF0]));
        EplBinding::open(mn, Some(Product::Sk550p), "test".into(), false)
    }

    fn read_p102() -> Action {
        Action::Read(OrderSpec {
            target: Target::Inverter(Inverter::new(1).unwrap()),
            number: ParamNumber::new(102).unwrap(),
            set: None,
            element: None,
            ak: None,
            value: None,
            eeprom: true,
            dword: None,
        })
    }

    /// The served node (`harness serve epl`) on one end of a veth pair, its SDO answers 300 ms
    /// late (`--misbehave late=300ms`); the MN on the other end. Within the MN's SDO limit the read
    /// passes; past it the step fails, naming the node's limit and the time waited.
    #[test]
    fn a_served_node_late_past_its_sdo_limit_fails_naming_both_times() {
        use crate::epl::serve::{start, ServeOptions};
        let Some(v) = crate::net::veth::Veth::new("d") else {
            return;
        };
        let served = start(&ServeOptions {
            misbehave: crate::net::misbehave::Misbehaviour::late(Duration::from_millis(300)),
            ..ServeOptions::new(&v.0)
        })
        .expect("serve");
        let open = |sdo: Duration| {
            let peer = SocketAddr::from((def::ip_address(1), proto::epl::SDO_UDP_PORT));
            let link = NetLink::open(&v.1, proto::eth::ETHERTYPE_POWERLINK, peer, 0).unwrap();
            let mac = MacAddr(link.mac());
            let config = MnConfig {
                sdo,
                ..MnConfig::default()
            };
            let mn = Manager::new(link, config, mac);
            EplBinding::open(mn, Some(Product::Sk550p), "served".into(), false).expect("open")
        };
        let mut b = open(Duration::from_secs(1));
        let r = b.perform(&read_p102());
        assert!(r.as_ref().is_ok_and(|o| o.refusal.is_none()), "{r:?}");
        drop(b);
        let mut b = open(Duration::from_millis(40));
        let e = b.perform(&read_p102()).unwrap_err();
        assert_eq!(e.verdict(), Verdict::Fail, "{e}");
        assert!(
            matches!(&e, StepError::Late { limit, waited, .. }
                if *limit == Duration::from_millis(40) && *waited >= *limit),
            "{e:?}"
        );
        let text = e.to_string();
        assert!(text.starts_with("node 1, SDO"), "{text}");
        assert!(text.contains("limit of 40 ms (waited "), "{text}");
        served.stop().expect("served to the end");
    }

    #[test]
    fn an_error_the_node_signals_unasked_fails_the_step_naming_its_entry() {
        let mut b = binding(Rc::new(Cell::new(Fault::None))).unwrap();
        let cycles = Action::Bus(Box::new(EplStep::Cycles(5)));
        assert!(b.perform(&cycles).is_ok());
        let raise = |b: &mut EplBinding<Faulty>| {
            let (node, now) = crate::net::peer::Link::device(b.mn.link_mut()).unwrap();
            node.raise_spurious(now).unwrap()
        };
        // EN toggles in the PRes; the MN fetches the StatusResponse in the next free slot.
        assert_eq!(raise(&mut b).code, 0x9000);
        let e = b.perform(&cycles).unwrap_err();
        assert_eq!(e.verdict(), Verdict::Fail);
        assert_eq!(
            e.to_string(),
            "the DUT departed from the protocol: node 1 signalled an error no step provoked (EN \
             toggled; its StatusResponse lists entry 9000h External watchdog, \"1   12.0\")"
        );
        assert!(
            b.perform(&cycles).is_ok(),
            "acknowledged (EA), reported once"
        );
        // A step that reads the StatusResponse judges what it reads.
        raise(&mut b);
        let status = Action::Bus(Box::new(EplStep::Status));
        let o = b.perform(&status).unwrap();
        assert_eq!(o.fields["entry"]["code"], 0x9000);
        assert!(b.perform(&cycles).is_ok());
    }

    #[test]
    fn a_silent_or_garbage_sending_node_is_an_error_within_the_time_out() {
        // Silent from the start: the node cannot be opened, within the MN's few cycles.
        let fault = Rc::new(Cell::new(Fault::Silent));
        assert!(matches!(
            binding(fault),
            Err(OpenError::Unreachable(e)) if e.contains("no reply")
        ));
        // Silent after a good start: the SDO read runs the cycle, whose PRes stop coming; two
        // lost in a row reach DS 301's loss-of-PRes threshold (8 + 8 ≥ 15), decided once 50 ms
        // passed without them: a failure in the standard's words, before the SDO time (200
        // ms). Garbage is an error.
        for (f, verdict) in [
            (Fault::Silent, Verdict::Fail),
            (Fault::Garbage, Verdict::Error),
        ] {
            let fault = Rc::new(Cell::new(Fault::None));
            let mut b = binding(fault.clone()).unwrap();
            assert!(b.perform(&read_p102()).is_ok());
            fault.set(f);
            let start = b.mn.now();
            let e = b.perform(&read_p102()).unwrap_err();
            assert_eq!(e.verdict(), verdict, "{f:?}: {e}");
            assert!(b.mn.now() - start <= Duration::from_millis(250), "{f:?}");
            if f == Fault::Silent {
                assert!(matches!(&e, StepError::Departed(_)), "{e:?}");
                assert_eq!(
                    e.to_string(),
                    "the DUT departed from the protocol: no PRes from node 1 in 2 of 2 cycles: \
                     loss of PRes, threshold counter \
                     (1C08h) 16 reached the threshold 15 (1C09h DLL_MNCNLossPResThreshold): \
                     E_DLL_LOSS_PRES_TH"
                );
                assert!(b.mn.now() - start <= Duration::from_millis(55), "50 ms on");
            }
        }
    }
}
