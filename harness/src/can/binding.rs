//! The system-bus binding: the harness as CANopen SDO client of a product's inverters, each a
//! node at its P515 address (FI n at 32 + 2·(n − 1), `proto::nord::can`).
//!
//! `read`/`write` are SDO transfers of parameter P at object 2000h + P of the inverter's node,
//! its set or element the sub-index (`proto::nord::can::cia301::parameter_sdo`; not stated by
//! the manuals, CiA 301's pre-defined connection set). A refusal is the node's SDO abort
//! code. On the SK 550P, FI 1 also answers the interface's parameters (the interface is
//! built into it); a bus module's own parameters are not on the system bus.
//!
//! `can:` steps (`step.rs`) put a frame or an NMT command on the bus and observe every frame
//! for the step's time. `process`/`wait` steps run the inverters' PDOs on SYNC in the bus
//! interface's place (`process.rs`).

use std::time::Duration;

use proto::canopen::SdoAbortCode;
use proto::nord::can::parameter_sdo;
use proto::nord::{Inverter, ParamAddress, Product};
use serde_json::{json, Value};

use super::link::CanLink;
use super::process::{nmt, PdoCycle, PdoError, Pdos};
use super::sdo::{describe, Client, SdoError};
use super::step::CanStep;
use crate::binding::ledger::{Account, Ledger, Problem};
use crate::binding::objects::{self, Object, Unit};
use crate::binding::settle::{self, Cycling, Drives};
use crate::binding::simulator::{observe_device, OBSERVABLE};
use crate::binding::{Binding, CleanupError, Observation, OpenError, StepError};
use crate::hex::can_frame;
use crate::hex::hex;
use crate::outcome::{Exchange, Identity, Refusal};
use crate::profile::Capability;
use crate::suite::{Action, OrderSpec};
use proto::can::socketcan::ErrorFrame;
use proto::can::CanFrame;

/// What the embedded segment offers: parameters over SDO, process data over PDOs, `can:`
/// steps, and the simulator's own powers.
const EMBEDDED_CAPABILITIES: [Capability; 7] = [
    Capability::ParameterAccess,
    Capability::ProcessData,
    Capability::Bus("can"),
    Capability::FaultInjection,
    Capability::Observe,
    Capability::PowerOn,
    Capability::FactoryState,
];
/// What a segment on the network offers.
const NETWORK_CAPABILITIES: [Capability; 3] = [
    Capability::ParameterAccess,
    Capability::ProcessData,
    Capability::Bus("can"),
];

/// Cycles a process step runs on past its own for an inverter's TPDO1 that did not come in
/// the last one (a node on a loaded host), before the step fails.
const LATE_CYCLES: u32 = 20;

/// What any maker's node offers: the bus's own steps.
const ANY_CAPABILITIES: [Capability; 1] = [Capability::Bus("can")];

/// The frames a `can:` step takes at most (a babbling node ends the step there).
const MAX_FRAMES_PER_STEP: usize = 1000;

/// An object of one node: the ledger's key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct NodeObject {
    node: u8,
    object: Object,
}

impl std::fmt::Display for NodeObject {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} of node {}", self.object, self.node)
    }
}

/// The harness as SDO client of a product's inverters on one segment, or of any maker's
/// CANopen node (`any@can`: no product, only `can:` steps).
pub(crate) struct CanBinding<L> {
    client: Client<L>,
    product: Option<Product>,
    what: String,
    capabilities: &'static [Capability],
    /// On a segment on the network: what the case wrote, to be written back.
    ledger: Option<Ledger<NodeObject>>,
    /// The DUT's node: FI 1's, whose identity the device reports, or any maker's node.
    node: u8,
    /// The inverters' process data (none on any maker's node).
    pdos: Option<Pdos>,
    /// Exchanges of process-data cycles taken ahead of the step's end (compacted).
    pending: Vec<Exchange>,
}

/// The refusal of an SDO abort code.
fn abort(code: SdoAbortCode) -> Observation {
    Observation::refused(
        json!({ "abort": code.0 }),
        Refusal {
            kind: "SDO abort code".into(),
            code: code.0,
            text: code.to_string(),
        },
    )
}

fn step_error(e: SdoError) -> StepError {
    match e {
        SdoError::Abort(code) => StepError::Refused(format!("SDO abort {code}").into()),
        SdoError::Silent { node, what, limit } => StepError::Late {
            what: format!("node {node}, {what}"),
            limit,
            waited: limit,
        },
        e @ SdoError::Protocol { .. } => StepError::Garbage(e.into()),
        SdoError::Link(l) => StepError::Link(l.into()),
    }
}

fn pdo_error(e: PdoError) -> StepError {
    match e {
        PdoError::Link(l) => StepError::Link(l.into()),
        e @ PdoError::Frame(_) => StepError::Suite(e.into()),
        e @ PdoError::NoNode(_) => StepError::NotApplicable(e.to_string()),
        PdoError::Silent {
            fi,
            node,
            cycles,
            cycle,
        } => StepError::Late {
            what: format!("TPDO1 of node {node} (FI {fi}) after SYNC"),
            limit: cycle,
            waited: cycle * cycles,
        },
    }
}

/// The vendor-ID (1018h:01) of `node`, the first thing asked of a DUT: no answer is an
/// unreachable DUT, a refusal one that did not come up.
fn vendor_id<L: CanLink>(client: &mut Client<L>, node: u8) -> Result<u32, OpenError> {
    let vendor = client.upload(node, 0x1018, 1).map_err(|e| match e {
        SdoError::Link(_) | SdoError::Silent { .. } => OpenError::Unreachable(e.to_string()),
        _ => OpenError::BringUp(e.to_string()),
    })?;
    Ok(u32::from_le_bytes(vendor.try_into().unwrap_or([0; 4])))
}

fn refused_or(e: SdoError) -> Result<Observation, StepError> {
    match e {
        SdoError::Abort(code) => Ok(abort(code)),
        other => Err(step_error(other)),
    }
}

impl<L: CanLink> CanBinding<L> {
    /// The binding over `link`; FI 1's node must answer its identity (1018h:01, NORD's vendor
    /// id 538h) before a case runs.
    pub(crate) fn open(
        link: L,
        limit: Duration,
        product: Product,
        inverters: u8,
        what: String,
        persistent: bool,
    ) -> Result<CanBinding<L>, OpenError> {
        let mut client = Client::new(link, limit);
        let fi1 = Inverter::new(1).map_err(|e| OpenError::Profile(e.to_string()))?;
        let node = proto::nord::can::SystemBusAddress::for_inverter(product, fi1)
            .map_err(|e| OpenError::Profile(e.to_string()))?
            .get();
        let vendor = vendor_id(&mut client, node)?;
        if vendor != proto::nord::ecat::VENDOR_ID {
            return Err(OpenError::BringUp(format!(
                "node {node} has vendor id {vendor:08X}h, not NORD's {:08X}h",
                proto::nord::ecat::VENDOR_ID
            )));
        }
        client.take_exchanges();
        Ok(CanBinding {
            client,
            product: Some(product),
            what: format!("{what}: FI 1 at node {node} (vendor {vendor:08X}h)"),
            capabilities: if persistent {
                &NETWORK_CAPABILITIES
            } else {
                &EMBEDDED_CAPABILITIES
            },
            ledger: persistent.then(Ledger::default),
            node,
            pdos: Some(Pdos::new(product, inverters)),
            pending: Vec::new(),
        })
    }

    /// Any maker's CANopen node `node` over `link`: it must answer an upload of its vendor id
    /// (1018h:01, mandatory in CiA 301 §7.5.2.24) before a case runs. Only `can:` steps apply.
    pub(crate) fn open_any(
        link: L,
        limit: Duration,
        node: u8,
        what: String,
    ) -> Result<CanBinding<L>, OpenError> {
        let mut client = Client::new(link, limit);
        let vendor = vendor_id(&mut client, node)?;
        client.take_exchanges();
        Ok(CanBinding {
            client,
            product: None,
            what: format!("{what}: node {node} (vendor {vendor:08X}h)"),
            capabilities: &ANY_CAPABILITIES,
            ledger: None,
            node,
            pdos: None,
            pending: Vec::new(),
        })
    }

    /// The NORD product behind the binding; not applicable on any maker's node.
    fn product(&self) -> Result<Product, StepError> {
        self.product.ok_or_else(|| {
            StepError::NotApplicable(
                "any maker's node: NORD parameters and process data are not its objects".into(),
            )
        })
    }

    /// A `process` or `wait` step: cycles of every inverter's PDOs, then the status word and
    /// actual values of the step's inverter from its last TPDOs.
    fn process(&mut self, action: &Action) -> Result<Value, StepError> {
        self.product()?;
        let Some(pdos) = self.pdos.as_mut() else {
            return Err(StepError::Suite("no process data".into()));
        };
        let (fi, words, _) = crate::binding::process_run(action, pdos.cycle())?;
        match words {
            Some(w) => pdos.set_words(fi, w).map_err(pdo_error)?,
            // `wait` before any words: FI 1's process data run, 0000h.
            None if pdos.commanded.is_empty() => pdos.set_words(fi, [0; 6]).map_err(pdo_error)?,
            None => {}
        }
        // The cycle depends on how many inverters run.
        let (_, _, cycles) = crate::binding::process_run(action, pdos.cycle())?;
        let real_time = self.client.link.segment().is_none();
        let time = crate::binding::process_time(action, real_time);
        let Some(pdos) = self.pdos.as_mut() else {
            return Err(StepError::Suite("no process data".into()));
        };
        let mut c = PdoCycle {
            client: &mut self.client,
            pdos,
        };
        match time {
            Some(d) => settle::run_cycles_for(&mut c, &mut self.pending, d),
            None => settle::run_cycles(&mut c, &mut self.pending, u64::from(cycles.max(1))),
        }
        .map_err(pdo_error)?;
        for _ in 0..LATE_CYCLES {
            if c.pdos.inputs(fi).map_err(pdo_error)?.is_some() {
                break;
            }
            c.run_cycles(1).map_err(pdo_error)?;
        }
        let words = match c.pdos.inputs(fi).map_err(pdo_error)? {
            Some(w) => w,
            None => {
                return Err(pdo_error(PdoError::Silent {
                    fi: fi.get(),
                    node: c.pdos.node(fi).map_err(pdo_error)?,
                    cycles: LATE_CYCLES + 1,
                    cycle: c.pdos.cycle(),
                }))
            }
        };
        Ok(crate::binding::process_fields(words[0], &words[1..]))
    }

    /// After a case that ran process data: on a segment that outlives the case, the drives
    /// it moved back to "Switch-on block"; then every node back to pre-operational, where a
    /// case finds them.
    fn stop_process_data(&mut self) -> Result<(), Problem> {
        let (Some(product), Some(pdos)) = (self.product, self.pdos.as_mut()) else {
            return Ok(());
        };
        if !pdos.started() {
            return Ok(());
        }
        if self.ledger.is_some() {
            let period = pdos.cycle();
            let mut drives = Drives::only(&pdos.commanded);
            let mut c = PdoCycle {
                client: &mut self.client,
                pdos,
            };
            drives.settle(&mut c, &mut self.pending, period, |e| {
                Problem::step("settling the drives", pdo_error(e))
            })?;
        }
        let stop = nmt(proto::canopen::NmtCommand::ENTER_PRE_OPERATIONAL, 0)
            .map_err(|e| Problem::step("NMT pre-operational", pdo_error(e)))?;
        self.client
            .link
            .send(&stop)
            .map_err(|e| Problem::step("NMT pre-operational", StepError::Link(e.into())))?;
        let inverters = self.pdos.as_ref().map_or(1, Pdos::len);
        self.pdos = Some(Pdos::new(product, inverters));
        Ok(())
    }

    /// The node and object of a `read`/`write` step, and the parameter's definition.
    fn object(
        &self,
        o: &OrderSpec,
    ) -> Result<(NodeObject, Option<&'static proto::nord::params::ParamDef>), StepError> {
        let product = self.product()?;
        let a = objects::address(product, o)?;
        let Unit::Inverter(inverter) = a.unit else {
            return Err(StepError::NotApplicable(
                "a bus module's own parameters are not on the system bus (its nodes are the \
                 inverters)"
                    .into(),
            ));
        };
        let (node, sdo) = parameter_sdo(
            product,
            ParamAddress {
                inverter,
                number: o.number,
                set: a.set,
                element: a.element,
            },
        )
        .map_err(|e| StepError::NotApplicable(e.to_string()))?;
        Ok((
            NodeObject {
                node: node.get(),
                object: Object {
                    index: sdo.index,
                    sub: sdo.subindex,
                },
            },
            a.def,
        ))
    }

    fn read(&mut self, o: &OrderSpec) -> Result<Observation, StepError> {
        let (at, def) = self.object(o)?;
        let data = match self.client.upload(at.node, at.object.index, at.object.sub) {
            Ok(d) => d,
            Err(e) => return refused_or(e),
        };
        let value = objects::value_of(at.object, &data, def)?;
        Ok(json!({ "value": value, "data": hex(&data), "abort": null }).into())
    }

    fn write(&mut self, o: &OrderSpec) -> Result<Observation, StepError> {
        let (at, def) = self.object(o)?;
        let data = objects::bytes_of(o, def)?;
        let (index, sub) = (at.object.index, at.object.sub);
        if self.ledger.as_ref().is_some_and(|l| l.wants_original(&at)) {
            let before = self
                .client
                .upload(at.node, index, sub)
                .map_err(|e| e.to_string());
            if let Some(l) = self.ledger.as_mut() {
                l.original(at, before);
            }
        }
        let r = self.client.download(at.node, index, sub, &data);
        if let Some(l) = self.ledger.as_mut() {
            // Only the node's refusal (an abort) surely left the object as it was.
            l.wrote(&at, !matches!(r, Err(SdoError::Abort(_))));
        }
        match r {
            Ok(()) => Ok(json!({ "abort": null, "ok": true }).into()),
            Err(e) => refused_or(e),
        }
    }

    /// A `can:` step: its frame on the bus, then every frame for its time.
    fn can_step(&mut self, step: &CanStep) -> Result<Value, StepError> {
        // Error frames from before the step (an SDO read's time) are not this step's.
        let _ = self.client.link.take_error_frames();
        let sent = match &step.send {
            Some(s) => {
                let f = s.frame(self.node).map_err(|e| StepError::Suite(e.into()))?;
                self.client
                    .link
                    .send(&f)
                    .map_err(|e| StepError::Link(e.into()))?;
                Some(f)
            }
            None => None,
        };
        let end = self.client.link.now() + step.wait;
        let mut frames = Vec::new();
        while frames.len() < MAX_FRAMES_PER_STEP {
            let left = end.saturating_sub(self.client.link.now());
            match self
                .client
                .link
                .recv(left)
                .map_err(|e| StepError::Link(e.into()))?
            {
                Some(f) => frames.push(f),
                None => break,
            }
            if left.is_zero() {
                break;
            }
        }
        let errors = self.client.link.take_error_frames();
        let abort = frames.iter().find_map(|f| {
            let d = f.data();
            ((0x581..=0x5FF).contains(&f.id()) && d.len() == 8 && d[0] == 0x80)
                .then(|| u32::from_le_bytes([d[4], d[5], d[6], d[7]]))
        });
        let joined =
            |each: fn(&CanFrame) -> String| frames.iter().map(each).collect::<Vec<_>>().join("; ");
        let node = self.node;
        let from_node: Vec<String> = frames
            .iter()
            .filter(|f| f.id() > 0x080 && f.id() & 0x7F == u16::from(node))
            .map(|f| {
                let hex = can_frame(f);
                let data = hex.split_once(' ').map_or("", |(_, d)| d);
                format!("{:03X}+N {data}", f.id() - u16::from(node))
                    .trim_end()
                    .to_string()
            })
            .collect();
        let error_frames: Vec<String> = errors.iter().map(error_frame_hex).collect();
        let with_errors = |text: String, each: fn(&ErrorFrame) -> String| {
            let errors = errors.iter().map(each);
            std::iter::once(text)
                .filter(|t| !t.is_empty())
                .chain(errors)
                .collect::<Vec<_>>()
                .join("; ")
        };
        self.client.record(Exchange {
            sent_hex: sent.as_ref().map(can_frame).unwrap_or_default(),
            sent: sent.as_ref().map_or_else(|| "(listening)".into(), describe),
            received_hex: with_errors(joined(can_frame), error_frame_hex),
            received: if frames.is_empty() && errors.is_empty() {
                "(nothing received)".into()
            } else {
                with_errors(joined(describe), |e| format!("error frame {:?}", e.class))
            },
        });
        let mut fields = json!({
            "answered": !frames.is_empty(),
            "count": frames.len(),
            "frames": joined(can_frame),
            "from_node": from_node.join("; "),
            "abort": abort,
        });
        // Only when there were any: a step on a bus without errors shows what it always did.
        if !errors.is_empty() {
            fields["error_frames"] = json!(error_frames.join("; "));
            fields["error_count"] = json!(errors.len());
        }
        Ok(fields)
    }

    /// FI 1's identity object 1018h (vendor, product code, revision, serial) and its device
    /// name 1008h.
    fn identity_object(&mut self) -> Result<Identity, StepError> {
        let node = self.node;
        // CiA 301 §7.5.2.24: 1018h:00 counts the entries; only the vendor id (01h) is
        // mandatory, product code, revision and serial number (02h–04h) are optional.
        let count = self.client.upload(node, 0x1018, 0).map_err(step_error)?;
        let count = count.first().copied().unwrap_or(0).min(4);
        let mut subs = [const { None }; 4];
        for (sub, v) in (1u8..=count).zip(subs.iter_mut()) {
            let d = self.client.upload(node, 0x1018, sub).map_err(step_error)?;
            let b: [u8; 4] = d.as_slice().try_into().map_err(|_| {
                StepError::Protocol(format!("1018h:{sub:02X}h is {} bytes, not 4", d.len()).into())
            })?;
            *v = Some(format!("{:08X}h", u32::from_le_bytes(b)));
        }
        // 1008h is optional too (CiA 301 §7.5.2.7).
        let name = match self.client.upload(node, 0x1008, 0) {
            Ok(n) => Some(
                String::from_utf8_lossy(&n)
                    .trim_end_matches('\0')
                    .to_string(),
            ),
            Err(SdoError::Abort(_)) => None,
            Err(e) => return Err(step_error(e)),
        };
        let [vendor, product_code, revision, serial] = subs;
        Ok(Identity {
            source: match self.product {
                Some(_) => format!("objects 1018h and 1008h of node {node} (FI 1)"),
                None => format!("objects 1018h and 1008h of node {node}"),
            },
            vendor,
            product_code,
            product_name: name,
            revision,
            serial,
        })
    }

    fn simulated(&mut self) -> Result<(&mut sim::can::Segment, Duration), StepError> {
        self.client
            .link
            .segment()
            .ok_or_else(|| StepError::NotApplicable("only the simulator can be looked into".into()))
    }

    /// One step of a case.
    fn step(&mut self, action: &Action) -> Result<Observation, StepError> {
        let fields: Value = match action {
            Action::Compute { .. } => {
                return Err(StepError::Suite("compute is not a DUT step".into()))
            }
            Action::Read(o) => return self.read(o),
            Action::Write(o) => return self.write(o),
            Action::Pkw { .. } => {
                return Err(StepError::NotApplicable(
                    "the system bus has no PKW parameter channel: parameters are SDO objects"
                        .into(),
                ))
            }
            Action::Process { .. } | Action::Wait(_) => self.process(action)?,
            Action::Inject { inverter, error } => {
                let (segment, now) = self.simulated()?;
                segment
                    .inject_fault_at(*inverter, error, now)
                    .map_err(|e| StepError::Refused(e.into()))?;
                json!({})
            }
            Action::Observe { what, inverter } => {
                let (segment, now) = self.simulated()?;
                match observe_device(segment.device_mut(), what, *inverter, now)
                    .map_err(|e| StepError::Refused(e.into()))?
                {
                    Some(v) => v,
                    None => {
                        return Err(StepError::Suite(
                            format!(
                                "cannot observe `{what}` over the system bus (can: {OBSERVABLE})"
                            )
                            .into(),
                        ))
                    }
                }
            }
            Action::Bus(step) => {
                let step = crate::binding::own_step::<CanStep>(step.as_ref(), "the system bus")?;
                self.can_step(step)?
            }
        };
        Ok(fields.into())
    }
}

impl<L: CanLink> Binding for CanBinding<L> {
    fn describe(&self) -> String {
        self.what.clone()
    }

    fn capabilities(&self) -> &[Capability] {
        self.capabilities
    }

    /// The step, then the EMCYs it heard that the case did not ask for
    /// ([`crate::binding::emergency`]): one for an error the inverter does not have fails the
    /// step. A `can:` step looks at the bus's frames itself: what it heard is its own.
    fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
        let observed = self.step(action);
        let heard = self.client.take_emergencies();
        let observed = observed?;
        if matches!(action, Action::Bus(_)) {
            return Ok(observed);
        }
        let Some(product) = self.product else {
            return Ok(observed);
        };
        for (node, e) in heard.into_iter().take(crate::binding::emergency::AT_MOST) {
            let client = &mut self.client;
            let read = |at| -> Result<Option<Vec<u8>>, StepError> {
                let Ok((node, sdo)) = parameter_sdo(product, at) else {
                    return Ok(None);
                };
                match client.upload(node.get(), sdo.index, sdo.subindex) {
                    Ok(d) => Ok(Some(d)),
                    Err(SdoError::Abort(_)) => Ok(None),
                    Err(e) => Err(step_error(e)),
                }
            };
            let what = format!("node {node}'s EMCY");
            if let Some(spurious) = crate::binding::emergency::judge(&e, &what, read)? {
                return Err(StepError::Departed(spurious.into()));
            }
        }
        Ok(observed)
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        let mut all = std::mem::take(&mut self.pending);
        all.extend(self.client.take_exchanges());
        all
    }

    fn identity(&mut self) -> Option<Result<Identity, StepError>> {
        Some(self.identity_object())
    }

    fn finish(&mut self) -> Result<(), CleanupError> {
        let mut account = Account::default();
        if account.attempt(|| "stopping the process data".into()) {
            let r = self.stop_process_data();
            account.note(r);
        }
        let Some(ledger) = self.ledger.take() else {
            return account.into_result().map_err(CleanupError);
        };
        ledger.restore(&mut account, |at, before| {
            self.client
                .download(at.node, at.object.index, at.object.sub, before)
                .map_err(|e| Problem::step(format!("setting back {at}"), step_error(e)))
        });
        self.ledger = Some(Ledger::default());
        account.into_result().map_err(CleanupError)
    }
}

/// An error frame as a `can:` step shows it, apart from the frames: `error`, its class
/// (`can_id` & `CAN_ERR_MASK`, hex, as socketcand writes it: `< error 088 … >`) and its 8 data
/// bytes (zero where raw-mode socketcand leaves them out): `error 088 00 00 04 0A 00 00 00 00`.
pub(super) fn error_frame_hex(e: &ErrorFrame) -> String {
    format!("error {:03X} {}", e.class.0, hex(&e.data))
}

#[cfg(test)]
mod identity_tests {
    use proto::nord::Product;

    #[test]
    fn the_identity_is_fi_1s_objects_1018h_and_1008h() {
        let id = crate::embedded::identity_over(Product::Sk550p, "can");
        assert!(
            id.source.starts_with("objects 1018h and 1008h of node "),
            "{id:?}"
        );
        assert!(id.vendor.is_some(), "{id:?}");
        // A node's 1018h need hold only the vendor id (CiA 301); the simulated inverters'
        // name is their 1008h.
        assert!(id.product_name.is_some(), "{id:?}");
    }
}
