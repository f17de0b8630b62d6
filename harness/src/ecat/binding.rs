//! The EtherCAT binding: the harness as EtherCAT master of the SK 550P's integrated interface
//! (BU 0620 §2.2), in-process against the simulated slave or on a network interface.
//!
//! Opening a DUT scans the segment, gives the slave its station address, reads its SII and
//! brings it to Pre-Operational (mailbox running), as a master does at start-up. The
//! manual-level steps go over CoE and process data: `read`/`write` are SDO transfers of the
//! parameter objects 2000h + 800h·(FI−1) + P (§2.2.7), `process`/`wait` exchange the 12 bytes
//! of each inverter cyclically (1 ms) in Operational, which the binding enters the first time
//! a case needs process data. The `ecat:` steps go to the master as written. A device that
//! refuses answers with its own code: an SDO abort code, an AL status code, a mailbox error.
//!
//! On a device on the network (one device for the whole run) every SDO download goes through
//! the shared [`Ledger`]; when the case ends the binding stops the drives, writes back what the
//! case changed and leaves the slave in Pre-Operational, as it found it.

use proto::ecat::al::EcState;
use proto::ecat::mailbox::{MailboxError, MailboxRepr, MailboxType};
use proto::ecat::{DatagramRepr, EcatFrameRepr};
use proto::nord::ecat::{BYTES_PER_INVERTER, VENDOR_ID};
use proto::nord::params;
use proto::nord::{addr, Inverter, ParamAddress, Product};
use serde_json::{json, Value};
use sim::ecat::Slave;
use std::time::Duration;

use super::master::{
    EmbeddedSegment, ErrorKind, LinkFailure, Master, MasterConfig, MasterError, NetSegment,
    ProtocolError, Refusal, Segment,
};
use super::step::{state_name, EcatStep};
use crate::binding::ledger::{self, Account, Ledger, Problem};
use crate::binding::objects::{self, Object, Unit};
use crate::binding::settle::{self, Cycling, Drives};
use crate::binding::simulator::{observe_device, OBSERVABLE};
use crate::binding::{process_run, process_time, Binding, CleanupError, Observation, StepError};
use crate::hex::hex;
use crate::net::wait::BringUpError;
use crate::outcome::{Exchange, Identity};
use crate::profile::Capability;
use crate::suite::{Action, OrderSpec};

/// A segment the binding can run on: the embedded one also hands out the simulated slave,
/// for `inject` and `observe`.
pub(crate) trait DutSegment: Segment {
    /// The simulated slave and the segment's time, when the slave is in-process.
    fn simulated(&mut self) -> Option<(&mut Slave, Duration)>;
}

impl DutSegment for EmbeddedSegment {
    fn simulated(&mut self) -> Option<(&mut Slave, Duration)> {
        let now = self.now();
        Some((self.slave_mut(), now))
    }
}

impl DutSegment for NetSegment {
    fn simulated(&mut self) -> Option<(&mut Slave, Duration)> {
        None
    }
}

/// What the embedded simulator offers (the parameters are CoE objects) and what a device on
/// the network offers.
pub(crate) const EMBEDDED_CAPABILITIES: [Capability; 9] = objects::embedded_capabilities("ecat");
pub(crate) const NETWORK_CAPABILITIES: [Capability; 3] = objects::network_capabilities("ecat");

/// How long the interface may go on showing cyclic process data after the cycle stopped,
/// and how often the cleanup looks.
const QUIET_TIME: Duration = Duration::from_secs(2);
const QUIET_POLL: Duration = Duration::from_millis(10);
/// P872 bit 1 "Cyclic PZD communication" (BU 0620 §4.3).
const CYCLIC: u8 = 1 << 1;

/// The harness as master of one EtherCAT slave.
pub(crate) struct EcatBinding<S> {
    master: Master<S>,
    /// The NORD product; `None` for any maker's slave (profile `any@ecat`).
    product: Option<Product>,
    station: u16,
    what: String,
    capabilities: &'static [Capability],
    /// What the case wrote, on a persistent device.
    ledger: Option<Ledger<Object>>,
    /// Exchanges taken from the master already (a process-data run, compacted).
    pending: Vec<Exchange>,
    /// The inverters the case sent control words.
    commanded: Vec<Inverter>,
    /// The emergencies set aside that were checked against the inverter already
    /// ([`super::emergency`]).
    emergencies_checked: usize,
}

impl<S: DutSegment> EcatBinding<S> {
    /// Scans `segment` and brings its first slave to Pre-Operational; `persistent` for a
    /// device on the network (a ledger, a cleanup).
    pub(crate) fn open(
        segment: S,
        product: Option<Product>,
        what: String,
        persistent: bool,
        cycle: Duration,
    ) -> Result<EcatBinding<S>, crate::binding::OpenError> {
        let config = MasterConfig {
            cycle,
            ..MasterConfig::default()
        };
        let mut master = Master::new(segment, config);
        master.set_recording(false);
        crate::net::wait::bring_up(
            |patience| {
                master.set_patience(patience);
                master.bring_up(EcState::PreOperational)
            },
            |e| match e {
                MasterError::Link(LinkFailure::Timeout { limit, waited, .. }) => {
                    Some((*limit, *waited))
                }
                _ => None,
            },
        )
        .map_err(|e| match e {
            BringUpError::Failed(e) => open_error(e),
            BringUpError::Late(e) => crate::binding::OpenError::Late(e.to_string()),
        })?;
        master.set_patience(1);
        let slave = &master.slaves()[0];
        let station = slave.station;
        let what = format!(
            "{what}: {} (vendor {:08X}h, product {:08X}h)",
            slave.name().unwrap_or("unnamed slave"),
            slave.vendor(),
            slave.product()
        );
        master.take_exchanges();
        master.set_recording(true);
        Ok(EcatBinding {
            master,
            product,
            station,
            what,
            capabilities: if persistent {
                &NETWORK_CAPABILITIES
            } else {
                &EMBEDDED_CAPABILITIES
            },
            ledger: persistent.then(Ledger::default),
            pending: Vec::new(),
            commanded: Vec::new(),
            emergencies_checked: 0,
        })
    }

    /// The vendor ID of the slave found.
    pub(crate) fn vendor(&self) -> u32 {
        self.master.slaves()[0].vendor()
    }

    /// The NORD product, for what only NORD's slave has (its parameter objects).
    fn nord(&self) -> Result<Product, StepError> {
        self.product.ok_or_else(|| {
            StepError::NotApplicable("any maker's slave has no NORD parameter objects".into())
        })
    }

    /// The CoE object of a `read`/`write` step (§2.2.7: 2000h + 800h·(FI−1) + P; the SK
    /// 550P's interface parameters are FI 1's) and the parameter's definition.
    fn object(
        &self,
        o: &OrderSpec,
    ) -> Result<(Object, Option<&'static params::ParamDef>), StepError> {
        let product = self.nord()?;
        let a = objects::address(product, o)?;
        let Unit::Inverter(inverter) = a.unit else {
            return Err(StepError::Suite(
                "the SK 550P has no module parameters".into(),
            ));
        };
        let coe = addr::coe(
            product,
            ParamAddress {
                inverter,
                number: o.number,
                set: a.set,
                element: a.element,
            },
        )
        .map_err(|e| StepError::Suite(e.into()))?;
        Ok((
            Object {
                index: coe.index,
                sub: coe.subindex,
            },
            a.def,
        ))
    }

    fn read(&mut self, o: &OrderSpec) -> Result<Observation, StepError> {
        let (obj, def) = self.object(o)?;
        let data = match self
            .master
            .sdo_upload(self.station, obj.index, obj.sub, false)
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
        self.download(obj, &data, false)
    }

    /// An SDO download, through the ledger on a persistent device.
    fn download(
        &mut self,
        obj: Object,
        data: &[u8],
        complete: bool,
    ) -> Result<Observation, StepError> {
        if !complete && self.ledger.as_ref().is_some_and(|l| l.wants_original(&obj)) {
            let before = self
                .master
                .sdo_upload(self.station, obj.index, obj.sub, false)
                .map_err(|e| e.to_string());
            if let Some(l) = self.ledger.as_mut() {
                l.original(obj, before);
            }
        }
        let r = self
            .master
            .sdo_download(self.station, obj.index, obj.sub, data, complete);
        // A refusal is the slave's answer (an observation); any other error the step's.
        let r = match r {
            Err(e) if e.kind() != ErrorKind::Refused => Err(step_error(e)),
            r => Ok(r),
        };
        if let Some(l) = self.ledger.as_mut() {
            let outcome = match &r {
                Ok(Ok(())) => Ok(true),
                Ok(Err(_)) => Ok(false),
                Err(e) => Err(e),
            };
            l.wrote(&obj, ledger::may_have_taken_effect(outcome));
        }
        match r? {
            Ok(()) => Ok(json!({ "abort": null }).into()),
            Err(e) => refused_or(e),
        }
    }

    /// Brings the slave to Operational with the cycle running, unless it is there.
    fn operational(&mut self) -> Result<(), StepError> {
        let s = self.master.al_status(self.station).map_err(step_error)?;
        if s.state() == Some(EcState::Operational) && !s.error() && self.master.is_cycling() {
            return Ok(());
        }
        self.master.set_recording(false);
        let r = self.enter(EcState::Operational);
        self.master.set_recording(true);
        r.map_err(|e| match e.refusal() {
            Some(r) => {
                StepError::Refused(format!("the slave did not enter Operational: {r}").into())
            }
            None => step_error(e),
        })
    }

    /// Requests `target` as a master does: state by state upwards, the mailbox configured
    /// before Pre-Operational (an ESC forgets its sync managers in Init), the process data
    /// configured and cycling before Safe-Operational, some cycles before Operational; a
    /// state at or below the present one at once. An error indication is acknowledged first.
    fn enter(&mut self, target: EcState) -> Result<(), MasterError> {
        let now = self.master.al_status(self.station)?;
        if now.error() {
            self.master.acknowledge_error(self.station)?;
        }
        let mut at = now.state();
        let at_rank = at.map_or(0, rank);
        if at_rank >= rank(target) || matches!(target, EcState::Init | EcState::Bootstrap) {
            self.prepare(at, target)?;
            return self.master.set_state(self.station, target);
        }
        for step in [
            EcState::PreOperational,
            EcState::SafeOperational,
            EcState::Operational,
        ] {
            if rank(step) > at_rank && rank(step) <= rank(target) {
                self.prepare(at, step)?;
                self.master.set_state(self.station, step)?;
                at = Some(step);
            }
        }
        Ok(())
    }

    /// What a master sets up before requesting `target` from `from`.
    fn prepare(&mut self, from: Option<EcState>, target: EcState) -> Result<(), MasterError> {
        let below = |s: EcState| from.is_none_or(|f| rank(f) < rank(s));
        if target != EcState::Init && from.is_none_or(|f| f == EcState::Init) {
            self.master.configure_mailbox(self.station)?;
        }
        if matches!(target, EcState::SafeOperational | EcState::Operational)
            && below(EcState::SafeOperational)
        {
            self.master.configure_process_data(self.station)?;
            self.master.start_cycling();
        }
        if target == EcState::Operational && from != Some(EcState::Operational) {
            self.master.start_cycling();
            self.master.run_cycles(3)?;
        }
        if matches!(
            target,
            EcState::Init | EcState::PreOperational | EcState::Bootstrap
        ) {
            self.master.stop_cycling();
        }
        Ok(())
    }

    /// Process data for `cycles`, or for `time` on the segment's clock when given.
    fn process(
        &mut self,
        inverter: Inverter,
        words: Option<[u16; 6]>,
        cycles: u32,
        time: Option<Duration>,
    ) -> Result<Value, StepError> {
        self.operational()?;
        let fi = inverter.get();
        if let Some(w) = words {
            if !self.commanded.contains(&inverter) {
                self.commanded.push(inverter);
            }
            self.master
                .set_inverter_outputs(self.station, fi, w)
                .map_err(step_error)?;
        }
        // The inputs of a cycle were written by the slave before it saw that cycle's outputs:
        // one more cycle brings the inverter's answer to the last of them.
        match time {
            Some(d) => self.cycles_for(d),
            None => self.cycles(u64::from(cycles) + 1),
        }
        .map_err(step_error)?;
        let i = self
            .master
            .inverter_inputs(self.station, fi)
            .map_err(step_error)?;
        Ok(crate::binding::process_fields(i[0], &i[1..]))
    }
}

impl<S: DutSegment> EcatBinding<S> {
    /// An `ecat:` step, as written.
    fn ecat_step(&mut self, step: &EcatStep) -> Result<Observation, StepError> {
        let st = self.station;
        let m = &mut self.master;
        let fields = match step {
            EcatStep::State { state, ack } => {
                let target = EcState::from_code(*state);
                if let Some(t) = target {
                    let now = m.al_status(st).map_err(step_error)?;
                    if !now.error() {
                        // Set up what the state needs, as a master does; the request itself
                        // is sent as written, so invalid transitions are refused as such.
                        self.prepare(now.state(), t).map_err(step_error)?;
                    }
                }
                let control = u16::from(*state) | if *ack { 0x10 } else { 0 };
                let s = self.master.request_state(st, control).map_err(step_error)?;
                let fields = al_fields(s.state_bits(), s.error(), s.code.0);
                if s.error() {
                    let r = Refusal::Al(super::master::AlRefused {
                        requested: *state,
                        state: s.state_bits(),
                        code: s.code,
                    });
                    return Ok(Observation::refused(fields, r.to_outcome()));
                }
                fields
            }
            EcatStep::ReadRegister { address, length } => {
                match m.read_register(st, *address, usize::from(*length)) {
                    Ok(d) => data_fields(&d),
                    Err(e) => return refused_or(e),
                }
            }
            EcatStep::WriteRegister { address, data } => match m.write_register(st, *address, data)
            {
                Ok(()) => json!({}),
                Err(e) => return refused_or(e),
            },
            EcatStep::Frame { bytes } => match m.raw_frame(bytes).map_err(step_error)? {
                None => json!({ "answered": false, "reply": null }),
                Some(reply) => {
                    let mut f = json!({ "answered": true, "reply": hex(&reply) });
                    if let Ok(frame) = EcatFrameRepr::parse_bytes(&reply) {
                        f["datagrams"] = frame.datagrams.iter().map(datagram_fields).collect();
                        if let Some(d) = frame.datagrams.first() {
                            f["wkc"] = json!(d.wkc);
                            f["data"] = json!(hex(&d.data));
                        }
                    }
                    f
                }
            },
            EcatStep::Datagram {
                command,
                adp,
                ado,
                data,
            } => {
                let d = DatagramRepr::physical(
                    proto::ecat::Command(*command),
                    0,
                    *adp,
                    *ado,
                    data.clone(),
                );
                match m.raw_datagrams(&[d]).map_err(step_error)? {
                    None => json!({ "answered": false }),
                    Some(r) => {
                        let mut f = r.first().map(datagram_fields).unwrap_or_else(|| json!({}));
                        f["answered"] = json!(true);
                        f
                    }
                }
            }
            EcatStep::Sii { word, words } => match m.read_sii(st, *word, *words) {
                Ok(d) => data_fields(&d),
                Err(e) => return refused_or(e),
            },
            EcatStep::Upload {
                index,
                sub,
                complete,
            } => match m.sdo_upload(st, *index, *sub, *complete) {
                Ok(d) => {
                    let mut f = data_fields(&d);
                    f["size"] = json!(d.len());
                    f["abort"] = Value::Null;
                    if let Some(t) = visible_string(&d) {
                        f["text"] = json!(t);
                    }
                    f
                }
                Err(e) => return refused_or(e),
            },
            EcatStep::Download {
                index,
                sub,
                data,
                complete,
            } => {
                let obj = Object {
                    index: *index,
                    sub: *sub,
                };
                return self.download(obj, data, *complete);
            }
            EcatStep::Mailbox { bytes } => match m.mailbox_raw(st, bytes).map_err(step_error)? {
                None => json!({ "answered": false, "reply": null }),
                Some(reply) => mailbox_fields(&reply),
            },
            EcatStep::StopPdo { time } => {
                let was = m.is_cycling();
                m.stop_cycling();
                m.idle(*time);
                let s = m.al_status(st).map_err(step_error)?;
                if was {
                    m.start_cycling();
                }
                al_fields(s.state_bits(), s.error(), s.code.0)
            }
            EcatStep::Identify => match m.identify(st) {
                Ok(id) => json!({ "id": id }),
                Err(e) => return refused_or(e),
            },
            EcatStep::Emergencies => {
                let list = m.collect_emergencies(st).map_err(step_error)?;
                let each: Vec<Value> = list
                    .iter()
                    .map(
                        |e| json!({ "code": e.code, "register": e.register, "data": hex(&e.data) }),
                    )
                    .collect();
                json!({ "count": each.len(), "emergencies": each })
            }
        };
        Ok(fields.into())
    }

    /// `inject`/`observe` reach into the simulated slave.
    fn simulated(&mut self) -> Result<(&mut Slave, Duration), StepError> {
        self.master
            .segment_mut()
            .simulated()
            .ok_or_else(|| StepError::Refused("only the embedded slave can be looked into".into()))
    }

    fn observe(&mut self, what: &str, inverter: Inverter) -> Result<Value, StepError> {
        let (slave, now) = self.simulated()?;
        if what == "al" {
            return Ok(json!({
                "state": state_name((slave.al_status() & 0x0F) as u8),
                "code": slave.al_status_code(),
            }));
        }
        let (run, err) = (slave.run_led(), slave.err_led());
        let mut v = observe_device(slave.device_mut(), what, inverter, now)
            .map_err(|e| StepError::Refused(e.into()))?
            .ok_or_else(|| {
                StepError::Refused(format!("cannot observe `{what}` ({OBSERVABLE}, al)").into())
            })?;
        if what == "leds" {
            v["run"] = json!(run);
            v["err"] = json!(err);
        }
        Ok(v)
    }

    /// A persistent device's cleanup, whatever the case's verdict: the drives the case ran
    /// back in "Switch-on block" without a fault ([`Drives`]; the interface brought back to
    /// Operational for it, acknowledging an AL error such as a watchdog's), the case's writes
    /// put back (the shared [`Ledger`]), the interface in Pre-Operational without an error
    /// indication, and no cyclic process data shown any more (P872 bit 1, BU 0620 §4.3), so
    /// that what needs "no communication via Ethernet" (§3.3) holds in the next case as it did
    /// before this one. Stops at the first link error and names what it did not attempt.
    fn restore(&mut self) -> Result<(), String> {
        let Some(ledger) = self.ledger.take() else {
            return Ok(());
        };
        let mut account = Account::default();
        let st = self.station;
        let drove = !self.commanded.is_empty();
        if drove && account.attempt(|| "settling the drives".into()) {
            account.note(self.settle());
        }
        ledger.restore(&mut account, |obj, before| {
            self.master
                .sdo_download(st, obj.index, obj.sub, before, false)
                .map_err(|e| Problem::step(format!("setting back {obj}"), step_error(e)))
        });
        if account.attempt(|| "back to Pre-Operational".into()) {
            let r = self.enter(EcState::PreOperational);
            account.note(r.map_err(|e| Problem::step("back to Pre-Operational", step_error(e))));
        }
        if drove && account.attempt(|| "waiting for the end of cyclic communication".into()) {
            account.note(self.quiet());
        }
        self.ledger = Some(Ledger::default());
        self.commanded.clear();
        account.into_result()
    }

    /// Runs `n` cycles, the transcript compacted.
    fn cycles(&mut self, n: u64) -> Result<(), MasterError> {
        let mut c = SlaveCycle {
            master: &mut self.master,
            station: self.station,
        };
        settle::run_cycles(&mut c, &mut self.pending, n)
    }

    /// Runs cycles for `d` on the segment's clock and one more, the transcript compacted.
    fn cycles_for(&mut self, d: Duration) -> Result<(), MasterError> {
        let mut c = SlaveCycle {
            master: &mut self.master,
            station: self.station,
        };
        settle::run_cycles_for(&mut c, &mut self.pending, d)
    }

    /// Cycles the drives back to "Switch-on block".
    fn settle(&mut self) -> Result<(), Problem> {
        let what = |e: MasterError| Problem::step("settling the drives", step_error(e));
        self.enter(EcState::Operational).map_err(what)?;
        let inverters = (self.master.inputs().len() / usize::from(BYTES_PER_INVERTER)) as u8;
        let period = self.master.config().cycle;
        let mut c = SlaveCycle {
            master: &mut self.master,
            station: self.station,
        };
        Drives::new(inverters, &self.commanded).settle(&mut c, &mut self.pending, period, what)
    }

    /// Waits until P872 no longer shows cyclic process data (bit 1).
    fn quiet(&mut self) -> Result<(), Problem> {
        let p872 = addr::coe(
            self.nord().map_err(|e| Problem::step("reading P872", e))?,
            ParamAddress {
                inverter: Inverter::new(1).map_err(|e| Problem::other(e.to_string()))?,
                number: proto::nord::ParamNumber::new(872)
                    .map_err(|e| Problem::other(e.to_string()))?,
                set: None,
                element: None,
            },
        )
        .map_err(|e| Problem::other(e.to_string()))?;
        let deadline = self.master.now() + QUIET_TIME;
        loop {
            let v = self
                .master
                .sdo_upload(self.station, p872.index, p872.subindex, false)
                .map_err(|e| Problem::step("reading P872", step_error(e)))?;
            let bits = v.first().copied().unwrap_or(0);
            if bits & CYCLIC == 0 {
                return Ok(());
            }
            if self.master.now() >= deadline {
                return Err(Problem::other(format!(
                    "P872 still shows cyclic process data {QUIET_TIME:?} after the cycle stopped"
                )));
            }
            self.master.idle(QUIET_POLL);
        }
    }
}

impl<S: DutSegment> EcatBinding<S> {
    /// Object 1018h (identity, ETG.1000.6 / CiA 301): vendor, product code, revision and
    /// serial as the slave's dictionary gives them; where the SII header (read at the scan)
    /// disagrees, the source says so.
    fn identity_object(&mut self) -> Result<Identity, StepError> {
        let mut subs = [0u32; 4];
        for (sub, v) in (1u8..).zip(subs.iter_mut()) {
            let d = self
                .master
                .sdo_upload(self.station, 0x1018, sub, false)
                .map_err(step_error)?;
            let b: [u8; 4] = d.get(..4).and_then(|b| b.try_into().ok()).ok_or_else(|| {
                StepError::Protocol(format!("1018h:{sub:02X}h is {} bytes, not 4", d.len()).into())
            })?;
            *v = u32::from_le_bytes(b);
        }
        let [vendor, product, revision, serial] = subs;
        let h = &self.master.slaves()[0].sii.header;
        let sii = [h.vendor_id, h.product_code, h.revision, h.serial];
        let source = if sii == subs {
            "object 1018h (the SII header agrees)".to_string()
        } else {
            format!(
                "object 1018h (the SII header says vendor {:08X}h, product {:08X}h, revision {:08X}h, serial {:08X}h)",
                sii[0], sii[1], sii[2], sii[3]
            )
        };
        Ok(Identity {
            source,
            vendor: Some(format!("{vendor:08X}h")),
            product_code: Some(format!("{product:08X}h")),
            product_name: self.master.slaves()[0].name().map(str::to_string),
            revision: Some(format!("{revision:08X}h")),
            serial: Some(format!("{serial:08X}h")),
        })
    }
}

impl<S: DutSegment> Binding for EcatBinding<S> {
    fn describe(&self) -> String {
        self.what.clone()
    }

    fn identity(&mut self) -> Option<Result<Identity, StepError>> {
        Some(self.identity_object())
    }

    fn capabilities(&self) -> &[Capability] {
        self.capabilities
    }

    /// The step, then the emergencies it met that the case did not ask for
    /// ([`super::emergency`]): one for an error the inverter does not have fails the step.
    fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
        let observed = self.step(action)?;
        if let Action::Bus(step) = action {
            if let Some(EcatStep::Emergencies) = step.as_ref().as_any().downcast_ref::<EcatStep>() {
                // It took them all: asked for, not checked.
                self.emergencies_checked = 0;
                return Ok(observed);
            }
        }
        let Some(product) = self.product else {
            return Ok(observed);
        };
        let from = self.emergencies_checked;
        match super::emergency::check(&mut self.master, self.station, product, from) {
            Ok(Ok(checked)) => {
                self.emergencies_checked = checked;
                Ok(observed)
            }
            Ok(Err(spurious)) => Err(StepError::Departed(spurious.into())),
            Err(e) => Err(step_error(e)),
        }
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        let mut v = std::mem::take(&mut self.pending);
        v.extend(self.master.take_exchanges());
        v
    }

    fn finish(&mut self) -> Result<(), CleanupError> {
        self.restore().map_err(CleanupError)
    }
}

impl<S: DutSegment> EcatBinding<S> {
    /// One step of a case.
    fn step(&mut self, action: &Action) -> Result<Observation, StepError> {
        let fields = match action {
            Action::Compute { .. } => {
                return Err(StepError::Suite("compute is not a DUT step".into()))
            }
            Action::Read(o) => return self.read(o),
            Action::Write(o) => return self.write(o),
            Action::Pkw { .. } => {
                return Err(StepError::NotApplicable(
                    "EtherCAT has no PKW parameter channel: parameters are CoE objects \
                     (BU 0620 §2.2.7)"
                        .into(),
                ))
            }
            Action::Process { .. } | Action::Wait(_) => {
                let (fi, words, cycles) = process_run(action, self.master.config().cycle)?;
                let time = process_time(action, self.master.real_time());
                self.process(fi, words, cycles, time)?
            }
            Action::Inject { inverter, error } => {
                let (slave, _) = self.simulated()?;
                slave
                    .device_mut()
                    .inject_fault(*inverter, error)
                    .map_err(|e| StepError::Refused(e.into()))?;
                json!({})
            }
            Action::Observe { what, inverter } => self.observe(what, *inverter)?,
            Action::Bus(step) => {
                let step = crate::binding::own_step::<EcatStep>(step.as_ref(), "EtherCAT")?;
                return self.ecat_step(step);
            }
        };
        Ok(fields.into())
    }
}

/// The master's cycle with one slave's process data, as the shared loops run it.
struct SlaveCycle<'a, S> {
    master: &'a mut Master<S>,
    station: u16,
}

impl<S: DutSegment> Cycling for SlaveCycle<'_, S> {
    type Error = MasterError;
    fn run_cycles(&mut self, n: u64) -> Result<(), MasterError> {
        self.master.run_cycles(n)
    }
    fn take_exchanges(&mut self) -> Vec<Exchange> {
        self.master.take_exchanges()
    }
    fn set_recording(&mut self, on: bool) {
        self.master.set_recording(on)
    }
    fn set_words(&mut self, fi: Inverter, words: [u16; 6]) -> Result<(), MasterError> {
        self.master
            .set_inverter_outputs(self.station, fi.get(), words)
    }
    fn status_word(&mut self, fi: Inverter) -> Result<u16, MasterError> {
        self.master.input_word(self.station, fi.get(), 0)
    }
}

impl<S: DutSegment> settle::Clocked for SlaveCycle<'_, S> {
    fn now(&self) -> Duration {
        self.master.now()
    }
    fn run_cycles_until(&mut self, end: Duration) -> Result<u64, MasterError> {
        self.master.run_cycles_until(end)
    }
}

/// Order of the states on the way up (Bootstrap beside Init).
fn rank(s: EcState) -> u8 {
    match s {
        EcState::Init | EcState::Bootstrap => 0,
        EcState::PreOperational => 1,
        EcState::SafeOperational => 2,
        EcState::Operational => 3,
    }
}

/// A master error that is not a refusal, as the runner's step error: frames that are no
/// EtherCAT replies at all (unparsable, or other datagrams than were sent) are garbage, an
/// error verdict like silence — nothing can be judged; a slave that answers but breaks the
/// rules (working counter, mailbox, CoE) fails.
fn step_error(e: MasterError) -> StepError {
    match e.kind() {
        ErrorKind::Protocol => match &e {
            MasterError::Protocol(ProtocolError::Malformed(_) | ProtocolError::Mismatch { .. }) => {
                StepError::Garbage(e.into())
            }
            _ => StepError::Protocol(e.into()),
        },
        ErrorKind::Refused => StepError::Refused(e.into()),
        ErrorKind::Link => match &e {
            MasterError::Usage(_) => StepError::Suite(e.into()),
            // The slave's limit passed: late unless the host was (the runner judges that).
            MasterError::Link(LinkFailure::Timeout {
                awaited,
                limit,
                waited,
            }) => StepError::Late {
                what: awaited.to_string(),
                limit: *limit,
                waited: *waited,
            },
            _ => StepError::Link(e.into()),
        },
    }
}

/// The device's refusal as an observation (the fields suites match: `abort`, `state`/`code`,
/// `mailbox_error`); any other error as the step's error.
fn refused_or(e: MasterError) -> Result<Observation, StepError> {
    let Some(r) = e.refusal() else {
        return Err(step_error(e));
    };
    let fields = match r {
        Refusal::SdoAbort { code, .. } => json!({ "abort": code.0 }),
        Refusal::Al(a) => al_fields(a.state, true, a.code.0),
        Refusal::Mailbox(code) => json!({ "mailbox_error": code.0 }),
    };
    Ok(Observation::refused(fields, r.to_outcome()))
}

/// AL status as the fields suites match: the state's name, the error indication, the AL
/// status code.
fn al_fields(state: u8, error: bool, code: u16) -> Value {
    json!({ "state": state_name(state), "error": error, "code": code })
}

/// Bytes as `data` (hex) and, up to 8 bytes, `value` (little-endian, as EtherCAT carries it).
fn data_fields(d: &[u8]) -> Value {
    let mut f = json!({ "data": hex(d) });
    if d.len() <= 8 {
        let mut b = [0u8; 8];
        b[..d.len()].copy_from_slice(d);
        f["value"] = json!(u64::from_le_bytes(b));
    }
    f
}

/// Data that reads as a VISIBLE_STRING (printable ASCII, maybe NUL-padded), as text.
fn visible_string(d: &[u8]) -> Option<String> {
    let end = d.iter().position(|b| *b == 0).unwrap_or(d.len());
    let (text, pad) = d.split_at(end);
    let printable = !text.is_empty() && text.iter().all(|b| (0x20..0x7F).contains(b));
    (printable && pad.iter().all(|b| *b == 0)).then(|| String::from_utf8_lossy(text).into_owned())
}

/// A datagram that came back: command, working counter, data.
fn datagram_fields(d: &DatagramRepr) -> Value {
    let mut f = data_fields(&d.data);
    f["command"] = json!(d.command.0);
    f["wkc"] = json!(d.wkc);
    f
}

/// A mailbox reply as given: its type and counter, and for an error reply its code, for a CoE
/// SDO abort its abort code.
fn mailbox_fields(reply: &[u8]) -> Value {
    let mut f = json!({ "answered": true, "reply": hex(reply) });
    let Ok(m) = MailboxRepr::parse_bytes(reply) else {
        return f;
    };
    f["type"] = json!(m.kind.0);
    f["counter"] = json!(m.counter);
    if m.kind == MailboxType::ERR {
        if let Ok(e) = MailboxError::parse(&m.data) {
            f["mailbox_error"] = json!(e.detail.0);
        }
    }
    if m.kind == MailboxType::COE {
        if let Ok(proto::ecat::coe::SdoResponse::Abort { code, .. }) =
            proto::ecat::coe::SdoResponse::parse_coe(&m.data)
        {
            f["abort"] = json!(code.0);
        }
    }
    f
}

/// The error of a master that could not open the DUT.
pub(crate) fn open_error(e: MasterError) -> crate::binding::OpenError {
    use crate::binding::OpenError;
    match e.kind() {
        ErrorKind::Link => OpenError::Unreachable(e.to_string()),
        _ => OpenError::BringUp(e.to_string()),
    }
}

/// Whether the slave found is NORD's (vendor 538h, BU 0620 §2.2.7.1 object 1018h), for a
/// NORD product's profile; any maker's slave is what it is.
pub(crate) fn check_vendor<S: DutSegment>(
    b: &EcatBinding<S>,
) -> Result<(), crate::binding::OpenError> {
    match b.vendor() {
        _ if b.product.is_none() => Ok(()),
        VENDOR_ID => Ok(()),
        other => Err(crate::binding::OpenError::BringUp(format!(
            "the slave's vendor ID is {other:08X}h, not NORD's {VENDOR_ID:08X}h"
        ))),
    }
}

#[cfg(test)]
impl<S: DutSegment> DutSegment for super::master::Faulty<S> {
    fn simulated(&mut self) -> Option<(&mut Slave, Duration)> {
        self.inner_mut().simulated()
    }
}

#[cfg(test)]
mod tests {
    use super::super::master::{al_limit, Fault, Faulty};
    use super::*;
    use crate::embedded::EmbeddedFactory;
    use crate::outcome::Verdict;
    use crate::profile::Profile;
    use crate::runner::{run, RunOptions};
    use crate::suite::load_text_for_tests;
    use crate::suite::Run;
    use crate::suite::Target;
    use proto::nord::ParamNumber;
    use sim::device::{Device, DeviceConfig};

    #[test]
    fn the_identity_is_object_1018h_checked_against_the_sii() {
        let id = crate::embedded::identity_over(Product::Sk550p, "ecat");
        assert_eq!(id.source, "object 1018h (the SII header agrees)");
        assert_eq!(id.vendor.as_deref(), Some("00000538h"));
        assert!(id.product_code.is_some() && id.revision.is_some() && id.serial.is_some());
    }

    fn binding() -> EcatBinding<Faulty<EmbeddedSegment>> {
        let device = Device::new(DeviceConfig::new(Product::Sk550p));
        let segment = Faulty::new(EmbeddedSegment::new(Slave::new(device).unwrap()));
        EcatBinding::open(
            segment,
            Some(Product::Sk550p),
            "test".into(),
            false,
            MasterConfig::default().cycle,
        )
        .unwrap()
    }

    fn read_p102() -> Action {
        Action::Read(OrderSpec::read(
            Target::Inverter(Inverter::new(3).unwrap()),
            ParamNumber::new(102).unwrap(),
        ))
    }

    #[test]
    fn parameters_go_over_coe_at_the_manuals_index() {
        let mut b = binding();
        let o = b.perform(&read_p102()).unwrap();
        // P102 factory 2.00 s; FI 3's P102 is 3066h, set 1 at sub-index 1 (BU 0620 §2.2.7).
        assert_eq!(o.fields["value"], 200);
        assert!(o.refusal.is_none());
        let x = b.take_exchanges();
        assert!(
            x.iter().any(|e| e.sent.contains("3066h:01h")),
            "{:?}",
            x.iter().map(|e| &e.sent).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_refusal_is_the_sdo_abort_code() {
        let mut b = binding();
        let Action::Read(mut o) = read_p102() else {
            unreachable!()
        };
        o.value = Some(32001);
        let obs = b.perform(&Action::Write(o)).unwrap();
        let r = obs.refusal.expect("refused");
        assert_eq!((r.kind.as_ref(), r.code), ("SDO abort code", 0x0609_0031));
        assert_eq!(obs.fields["abort"], 0x0609_0031);
    }

    #[test]
    fn a_pkw_step_is_not_applicable() {
        let mut b = binding();
        let e = b
            .perform(&Action::Pkw {
                inverter: Inverter::new(1).unwrap(),
                bytes: [0; 8],
            })
            .unwrap_err();
        assert_eq!(e.verdict(), Verdict::NotApplicable);
    }

    /// A segment that loops every frame back unprocessed or returns garbage gives an error
    /// verdict; one that goes silent is a slave past its limit (a fail, unless the runner
    /// finds the host late); each within the master's limits (on the embedded segment's
    /// clock).
    #[test]
    fn a_broken_segment_is_an_error_verdict_and_a_silent_one_late_within_the_limits() {
        for fault in [Fault::Silent, Fault::Loop, Fault::Garbage] {
            let mut b = binding();
            b.master.segment_mut().set_fault(fault);
            let start = b.master.now();
            let process = Action::Process {
                inverter: Inverter::new(1).unwrap(),
                control: 0x047E,
                setpoints: vec![],
                run: Run::Cycles(3),
            };
            for action in [read_p102(), process] {
                let e = b.perform(&action).unwrap_err();
                if fault == Fault::Silent {
                    assert!(matches!(e, StepError::Late { .. }), "{e:?}");
                    assert_eq!(
                        e.to_string(),
                        "a frame back: no answer within the device's limit of 50 ms (waited 50 ms)"
                    );
                } else {
                    assert_eq!(e.verdict(), Verdict::Error, "{fault:?}: {e}");
                }
            }
            let took = b.master.now() - start;
            let bound = b.master.config().mailbox_response * 2 + al_limit(0x0F);
            assert!(took <= bound, "{fault:?}: {took:?}");
        }
    }
    /// Opens nothing: a case of a bus's own steps under a profile of another bus.
    struct NoOpen;

    impl crate::binding::DutFactory for NoOpen {
        fn describe(&self) -> String {
            "a DUT that must not be opened".into()
        }
        fn open(
            &mut self,
            profile: &Profile,
            _: u32,
        ) -> Result<Box<dyn Binding>, crate::binding::OpenError> {
            panic!("opened a DUT for {}", profile.name())
        }
    }

    #[test]
    fn a_bus_step_under_another_bus_is_not_applicable_without_opening_the_dut() {
        let loaded = load_text_for_tests(
            r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: al-state
    title: t
    ref: { section: "2.2.5", page: 18 }
    steps:
      - ecat: { state: PREOP }
"#,
        );
        let ecat = Profile::on_bus(Product::Sk550p, "ecat");
        let opts = RunOptions {
            retries: 25,
            ..RunOptions::new(vec![
                Profile::builtin(Product::Sk550p),
                Profile::on_bus(Product::Sk550p, "enip"),
            ])
        };
        let r = run(&loaded, &opts, &mut NoOpen);
        for c in &r.cases {
            assert_eq!(c.verdict, Verdict::NotApplicable, "{}", c.profile);
            assert!(c.message.contains("needs `ecat`"), "{}", c.message);
        }
        // Under its own bus it does run.
        let opts = RunOptions {
            profiles: vec![ecat],
            ..opts
        };
        let r = run(
            &loaded,
            &opts,
            &mut EmbeddedFactory::new(crate::buses::BUSES),
        );
        assert_eq!(r.cases[0].verdict, Verdict::Pass, "{}", r.cases[0].message);
    }
}
