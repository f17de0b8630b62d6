//! The harness side of the NORD parameter channel and process data, over any [`Dut`].
//!
//! Sans-IO above the DUT: every bus cycle sends one link frame (data record + PPO telegram,
//! see `sim::link`) and reads the answer. A parameter order is repeated every cycle until the
//! answer carries it (BU 0620 §2.5.6: "A parameter order must be repeated until the inverter
//! responds with the corresponding response telegram"), bounded by `retries`; process data
//! keeps the last control word and setpoints of each inverter running.

use proto::nord::params::{self, Owner};
use proto::nord::pkw::{Ind, OrderLabel, PkwRepr};
use proto::nord::ppo::{PpoRepr, PpoType};
use proto::nord::{Inverter, ParamSet, Product};
use serde_json::{json, Value};
use sim::link::{LinkRepr, Unit};

use super::Dut;
use crate::hex::hex;
use crate::outcome::{Exchange, Verdict};
use crate::suite::{Action, OrderSpec, Target};
use crate::timing::cycles_for;

/// What a [`StepError`] says past its kind. An error the step met (a link's, a codec's, a
/// simulator's) is kept whole, not its text, so that `source()` reaches its own chain (the
/// I/O error under a link error); where the harness found the problem itself, its own words
/// (`"…".into()`, `format!(…).into()`). Boxed: each bus has its own link and codec errors.
pub(crate) type Cause = Box<dyn std::error::Error + Send + Sync>;

/// Why a DUT step produced no observation.
#[derive(Debug, thiserror::Error)]
pub(crate) enum StepError {
    /// Nothing came back: the DUT is silent or hung.
    #[error("no answer from the DUT within {cycles} bus cycles")]
    Silent {
        /// Cycles waited.
        cycles: u32,
    },
    /// Answers came, but never the one the order asked for.
    #[error("the DUT did not answer the order within {cycles} bus cycles (last answer: {last})")]
    Unanswered {
        /// Cycles waited.
        cycles: u32,
        /// The last answer, decoded.
        last: String,
    },
    /// The DUT answered with bytes that break the protocol (the codec's error, or what breaks).
    #[error("malformed answer from the DUT: {0}")]
    Protocol(#[source] Cause),
    /// The DUT's answer `what` does not parse: the codec's own error, naming the field.
    #[error("malformed answer from the DUT: {what}: {error}")]
    Malformed {
        /// What was parsed (`Forward_Open reply`).
        what: &'static str,
        /// Why it does not parse.
        #[source]
        error: proto::wire::Error,
    },
    /// The DUT (simulator) refused a harness request (`inject`, `observe`).
    #[error("the DUT refused: {0}")]
    Refused(#[source] Cause),
    /// The suite asked for something impossible.
    #[error("suite error: {0}")]
    Suite(#[source] Cause),
    /// The link to the DUT broke or a request went unanswered (a hung, closing or silent DUT):
    /// the link's own error, where it gave one.
    #[error("link error: {0}")]
    Link(#[source] Cause),
    /// The device closed (or reset) a connection it had accepted, in the middle of a request:
    /// a departure of the device's, judged (a device that never accepts one is unreachable).
    #[error("the device closed the connection: {0}")]
    Closed(#[source] Cause),
    /// The device did not answer within its limit (the manual's or the standard's), the wait
    /// moved by the time the host lost meanwhile (`crate::timing::Deadline`).
    #[error(
        "{what}: no answer within the device's limit of {} (waited {})",
        crate::timing::ms(*limit),
        crate::timing::ms(*waited)
    )]
    Late {
        /// What was asked.
        what: String,
        /// The device's limit.
        limit: std::time::Duration,
        /// How long the harness waited, the host's lost time included.
        waited: std::time::Duration,
    },
    /// The DUT did on its own what its manual or the standard rules out, seen on the bus
    /// rather than in an answer: a PROFINET input CR whose cycle counter stood still past the
    /// data hold time, an alarm of a type the manual does not name, an emergency for an error
    /// the inverter does not have, POWERLINK's loss-of-PRes threshold reached, an error a
    /// node signalled that no step provoked.
    #[error("the DUT departed from the protocol: {0}")]
    Departed(#[source] Cause),
    /// The DUT answered with something that is not the protocol at all.
    #[error("the DUT does not speak the protocol: {0}")]
    Garbage(#[source] Cause),
    /// The binding cannot perform this step over its bus (a PKW telegram over EtherCAT).
    #[error("{0}")]
    NotApplicable(String),
}

impl StepError {
    /// A parse of the DUT's answer `what` that failed with `error`.
    pub(crate) fn malformed(what: &'static str) -> impl Fn(proto::wire::Error) -> StepError {
        move |error| StepError::Malformed { what, error }
    }

    /// The time-out of `wait` for `what`: a failure of the device unless the runner finds the
    /// host was late (then the attempt is discarded).
    pub(crate) fn late(wait: &crate::timing::Deadline, what: impl Into<String>) -> StepError {
        StepError::Late {
            what: what.into(),
            limit: wait.limit(),
            waited: wait.waited(),
        }
    }

    /// The verdict this error stands for.
    pub(crate) fn verdict(&self) -> Verdict {
        match self {
            StepError::Unanswered { .. }
            | StepError::Protocol(_)
            | StepError::Malformed { .. }
            | StepError::Late { .. }
            | StepError::Closed(_)
            | StepError::Departed(_) => Verdict::Fail,
            StepError::Silent { .. }
            | StepError::Refused(_)
            | StepError::Suite(_)
            | StepError::Link(_)
            | StepError::Garbage(_) => Verdict::Error,
            StepError::NotApplicable(_) => Verdict::NotApplicable,
        }
    }
}

/// Process data kept running per unit.
#[derive(Debug, Clone, Default)]
struct Process {
    control: u16,
    setpoints: Vec<u16>,
}

/// The harness's end of the link.
pub(crate) struct Channel {
    dut: Box<dyn Dut>,
    product: Product,
    retries: u32,
    ppo: PpoType,
    process: [Process; 9],
    exchanges: Vec<Exchange>,
    /// Whether an exchange goes into the transcript: off for the middle cycles of a long
    /// process-data run, which the transcript leaves out (see [`compact`]).
    recording: bool,
}

impl super::Binding for Channel {
    fn describe(&self) -> String {
        self.dut.describe()
    }

    fn capabilities(&self) -> &[crate::profile::Capability] {
        self.dut.capabilities()
    }

    fn perform(&mut self, action: &Action) -> Result<super::Observation, StepError> {
        Channel::perform(self, action)
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        Channel::take_exchanges(self)
    }
}

impl Channel {
    /// A channel using the product's largest PPO type with a parameter channel.
    pub(crate) fn new(dut: Box<dyn Dut>, product: Product, retries: u32) -> Channel {
        Channel {
            dut,
            product,
            retries: retries.max(1),
            ppo: PpoType::TYPE_2,
            process: Default::default(),
            exchanges: Vec::new(),
            recording: true,
        }
    }

    /// The exchanges since the last call.
    pub(crate) fn take_exchanges(&mut self) -> Vec<Exchange> {
        std::mem::take(&mut self.exchanges)
    }

    /// Runs one DUT step.
    pub(crate) fn perform(&mut self, action: &Action) -> Result<super::Observation, StepError> {
        Ok(match action {
            Action::Compute { .. } => {
                return Err(StepError::Suite("compute is not a DUT step".into()))
            }
            Action::Read(o) | Action::Write(o) => {
                let order = self.order_for(o)?;
                let unit = unit(o.target);
                let (resp, cycles) = self.param_order(unit, order)?;
                pkw_result(&resp, json!({ "cycles": cycles }))
            }
            Action::Pkw { inverter, bytes } => {
                let order = PkwRepr::parse(bytes)
                    .map_err(|e| StepError::Suite(format!("pkw bytes: {e}").into()))?;
                let (resp, cycles) = self.param_order(Unit::Inverter(*inverter), order)?;
                let extra = json!({
                    "bytes": hex(&resp.emit_bytes()),
                    "pwe": resp.pwe,
                    "cycles": cycles,
                });
                pkw_result(&resp, extra)
            }
            Action::Process {
                inverter,
                control,
                setpoints,
                run,
            } => {
                let p = &mut self.process[usize::from(inverter.get())];
                p.control = *control;
                p.setpoints = setpoints.clone();
                let cycles = match run {
                    crate::suite::Run::Cycles(n) => *n,
                    crate::suite::Run::For(d) => cycles_for(*d, self.dut.cycle_time()),
                };
                self.run_process(*inverter, cycles)?.into()
            }
            Action::Wait(d) => {
                let cycles = cycles_for(*d, self.dut.cycle_time());
                self.run_process(Inverter::new(1).expect("FI 1 exists"), cycles)?
                    .into()
            }
            Action::Inject { inverter, error } => {
                self.dut
                    .inject(*inverter, error)
                    .map_err(|e| StepError::Refused(e.into()))?;
                json!({}).into()
            }
            Action::Observe { what, inverter } => self
                .dut
                .observe(what, *inverter)
                .map_err(|e| StepError::Refused(e.into()))?
                .into(),
            Action::Bus(step) => {
                return Err(StepError::NotApplicable(format!(
                    "the PPO link carries no `{}:` steps",
                    step.bus()
                )))
            }
        })
    }

    /// The parameter set an order addresses: the step's, else set 1 for an array element of a
    /// parameter the product's catalogue marks set-dependent — its IND carries the element in
    /// bits 10–15 and the set in bits 8–9, where a set-independent array's carries the
    /// sub-index in bits 8–15 (BU 0590 §4.2.3.2, BU 0620 §2.5.6.3). Without an element IND 0 is
    /// set 1 either way.
    fn set_for(&self, o: &OrderSpec) -> Option<ParamSet> {
        if o.set.is_some() || o.element.is_none() {
            return o.set;
        }
        let owner = match o.target {
            Target::Interface => Owner::Interface,
            Target::Inverter(_) => Owner::Inverter,
        };
        params::lookup(self.product, owner, o.number)
            .filter(|d| d.set_dependent)
            .and(ParamSet::new(1).ok())
    }

    /// Builds the order for a `read`/`write` step (BU 0620 §2.5.6.3: array elements need the
    /// array labels 6/7/8 (11/12 RAM only); RAM-only writes use 11–14).
    fn order_for(&self, o: &OrderSpec) -> Result<PkwRepr, StepError> {
        let dword = o.dword.unwrap_or_else(|| {
            o.value
                .is_some_and(|v| v > i64::from(u16::MAX) || v < i64::from(i16::MIN))
        });
        let ak = match (o.ak, o.value, o.element.is_some()) {
            (Some(ak), _, _) => OrderLabel(ak),
            (None, None, false) => OrderLabel::REQUEST_VALUE,
            (None, None, true) => OrderLabel::REQUEST_ARRAY_VALUE,
            (None, Some(_), array) => OrderLabel::change(array, dword, !o.eeprom),
        };
        let value = o.value.unwrap_or(0);
        let pwe = i32::try_from(value)
            .map_err(|_| StepError::Suite(format!("value {value} does not fit 32 bits").into()))?;
        Ok(PkwRepr {
            ak: ak.0,
            spm: false,
            pnu: proto::nord::addr::profinet_pnu(self.product, o.number),
            ind: Ind::for_address(self.set_for(o), o.element).raw(),
            pwe: pwe as u32,
        })
    }

    /// One bus cycle for `unit` with `pkw` and the unit's process data.
    fn exchange(&mut self, unit: Unit, pkw: Option<PkwRepr>) -> Result<Option<PpoRepr>, StepError> {
        let process = match unit {
            Unit::Interface => Process::default(),
            Unit::Inverter(i) => self.process[usize::from(i.get())].clone(),
        };
        let mut pzd = vec![process.control];
        pzd.extend(process.setpoints.iter().copied());
        pzd.resize(self.ppo.pzd_words(), 0);
        let ppo = PpoRepr {
            pkw: self.ppo.has_pkw().then(|| pkw.unwrap_or_default()),
            pzd,
        };
        let frame = LinkRepr {
            unit,
            ppo_type: self.ppo.0,
            payload: ppo.emit(self.ppo),
        };
        let sent_bytes = frame.emit();
        let answer = self.dut.cycle(&sent_bytes)?;
        let decoded = answer.as_deref().map(|b| decode_answer(b, unit, self.ppo));
        if !self.recording && !matches!(decoded, Some(Err(_))) {
            return decoded.transpose().map_err(StepError::Protocol);
        }
        self.exchanges.push(Exchange {
            sent_hex: hex(&sent_bytes),
            sent: ppo.describe_order(),
            received_hex: answer.as_deref().map(hex).unwrap_or_default(),
            received: match &decoded {
                None => "(nothing)".into(),
                Some(Ok(r)) => r.describe_response(),
                Some(Err(e)) => format!("malformed: {e}"),
            },
        });
        decoded.transpose().map_err(StepError::Protocol)
    }

    /// Repeats `order` every cycle until the answer carries its PNU with a response label;
    /// returns the answer and the bus cycles it took (1: the first answer carried it).
    fn param_order(&mut self, unit: Unit, order: PkwRepr) -> Result<(PkwRepr, u32), StepError> {
        if !self.ppo.has_pkw() {
            return Err(StepError::Suite(
                format!("PPO type {} has no parameter channel", self.ppo.0).into(),
            ));
        }
        let mut last = None;
        for cycle in 1..=self.retries {
            if let Some(ppo) = self.exchange(unit, Some(order))? {
                if let Some(resp) = ppo.pkw {
                    if resp.ak != 0 && resp.pnu == order.pnu {
                        return Ok((resp, cycle));
                    }
                    last = Some(resp);
                }
            }
        }
        Err(match last {
            None => StepError::Silent {
                cycles: self.retries,
            },
            Some(r) => StepError::Unanswered {
                cycles: self.retries,
                last: r.describe_response(),
            },
        })
    }

    /// Runs process data for `cycles`, returning the inverter's last status and actual values.
    fn run_process(&mut self, inverter: Inverter, cycles: u32) -> Result<Value, StepError> {
        let mut last = None;
        let first = self.exchanges.len();
        let long = cycles as usize > KEEP_HEAD + 2;
        for i in 0..cycles {
            // Only what the transcript keeps is formatted: the first cycles and the last.
            self.recording = !long || (i as usize) < KEEP_HEAD || i + 1 == cycles;
            let answer = self.exchange(Unit::Inverter(inverter), None);
            self.recording = true;
            if let Some(ppo) = answer? {
                last = Some(ppo);
            }
        }
        if long {
            self.exchanges.insert(
                first + KEEP_HEAD,
                cycles_left_out(u64::from(cycles) - KEEP_HEAD as u64 - 1),
            );
        }
        let ppo = last.ok_or(StepError::Silent { cycles })?;
        let status = ppo
            .pzd
            .first()
            .copied()
            .ok_or_else(|| StepError::Protocol("answer without a status word".into()))?;
        Ok(json!({ "status": status, "actuals": ppo.pzd.get(1..).unwrap_or_default() }))
    }
}

/// Exchanges a long process-data run's transcript keeps before the cycles it leaves out.
const KEEP_HEAD: usize = 2;

/// Keeps the first two and the last exchange of a long process-data run, so transcripts stay
/// readable; the note says how many cycles were left out.
pub(crate) fn compact(exchanges: &mut Vec<Exchange>, from: usize) {
    let n = exchanges.len().saturating_sub(from);
    if n <= KEEP_HEAD + 2 {
        return;
    }
    let skipped = n - KEEP_HEAD - 1;
    let last = exchanges.pop();
    exchanges.truncate(from + KEEP_HEAD);
    exchanges.push(cycles_left_out(skipped as u64));
    exchanges.extend(last);
}

/// The transcript's note standing for `n` process-data cycles left out.
pub(crate) fn cycles_left_out(n: u64) -> Exchange {
    Exchange {
        sent_hex: String::new(),
        sent: format!("… {n} more cycles with the same process data …"),
        received_hex: String::new(),
        received: String::new(),
    }
}

fn unit(target: Target) -> Unit {
    match target {
        Target::Interface => Unit::Interface,
        Target::Inverter(i) => Unit::Inverter(i),
    }
}

fn decode_answer(bytes: &[u8], sent_to: Unit, ppo: PpoType) -> Result<PpoRepr, Cause> {
    let frame = LinkRepr::parse(bytes)?;
    if frame.unit != sent_to {
        return Err(format!(
            "answer from data record {}, the order went to {}",
            frame.unit.record(),
            sent_to.record()
        )
        .into());
    }
    if frame.ppo_type != ppo.0 {
        return Err(format!(
            "answer is PPO type {}, the order was PPO type {}",
            frame.ppo_type, ppo.0
        )
        .into());
    }
    Ok(PpoRepr::parse(&frame.payload, ppo)?)
}

/// A parameter response as step result fields (suites/README.md).
/// A PKW response as the fields suites match (plus `extra`), refused when its response label
/// is 7 (BU 0620 §2.5.6.3: "order cannot be executed", with the error number in PWE).
fn pkw_result(r: &PkwRepr, mut fields: Value) -> super::Observation {
    let error = (r.ak == 7).then(|| r.error_number());
    fields["ak"] = json!(r.ak);
    fields["pnu"] = json!(r.pnu);
    fields["ind"] = json!(r.ind);
    fields["value"] = json!(r.pwe as i32);
    fields["error"] = json!(error.map(|e| e.0));
    match error {
        None => fields.into(),
        Some(e) => super::Observation::refused(
            fields,
            crate::outcome::Refusal {
                kind: "parameter channel".into(),
                code: u32::from(e.0),
                text: format!("response label 7, error {} ({})", e.0, e.meaning()),
            },
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_malformed_answer_keeps_the_codecs_error_and_fails_the_device() {
        let error = proto::wire::Error::Truncated {
            what: "Forward_Open reply",
            need: 26,
            got: 4,
        };
        let e = StepError::malformed("Forward_Open reply")(error.clone());
        assert!(matches!(&e, StepError::Malformed { error: inner, .. } if *inner == error));
        assert_eq!(e.verdict(), Verdict::Fail);
        assert_eq!(
            e.to_string(),
            "malformed answer from the DUT: Forward_Open reply: Forward_Open reply: truncated, need 26 bytes, got 4"
        );
        let source = std::error::Error::source(&e).expect("the codec's error");
        assert_eq!(source.downcast_ref::<proto::wire::Error>(), Some(&error));
    }

    #[test]
    fn a_step_error_keeps_the_error_it_met_and_says_the_same() {
        let io = std::io::Error::new(std::io::ErrorKind::TimedOut, "no frame within 10 ms");
        let e = StepError::Link(io.into());
        assert_eq!(e.to_string(), "link error: no frame within 10 ms");
        let source = std::error::Error::source(&e).expect("the link's error");
        assert_eq!(
            source
                .downcast_ref::<std::io::Error>()
                .map(std::io::Error::kind),
            Some(std::io::ErrorKind::TimedOut)
        );
        let own = StepError::Suite("compute is not a DUT step".into());
        assert_eq!(own.to_string(), "suite error: compute is not a DUT step");
    }
}
