//! Bindings: how the harness reaches a DUT.
//!
//! A [`Binding`] performs the manual-level steps of a case over one protocol and answers with
//! an [`Observation`]: the decoded answer as fields the suites match, and the device's refusal
//! in its bus's own terms when it refused. Each bus's binding lives in its own folder
//! (`crate::enip`, `crate::ecat`); this module holds what they share and the PPO link: a
//! [`Dut`] moving link frames (real bytes) one bus cycle at a time, with
//! [`channel::Channel`] holding the parameter-channel logic above it.

pub(crate) mod channel;
pub(crate) mod emergency;
pub(crate) mod ledger;
pub(crate) mod objects;
pub(crate) mod settle;
pub(crate) mod simulator;

use serde_json::Value;
use std::time::Duration;

pub(crate) use channel::StepError;

use crate::outcome::{Exchange, Identity, Refusal};
use crate::profile::{Capability, Profile};
use crate::suite::Action;
use proto::nord::Inverter;

/// What a step observed.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Observation {
    /// The decoded answer, as the fields suites match (`value`, `status`, `abort`, …).
    pub(crate) fields: Value,
    /// The device refused the request (AK 7 + error number, CIP general status, SDO abort
    /// code, AL status code…): data about the device, not a broken link.
    pub(crate) refusal: Option<Refusal>,
}

impl Observation {
    /// A refusal, with the fields that show it.
    pub(crate) fn refused(fields: Value, refusal: Refusal) -> Observation {
        Observation {
            fields,
            refusal: Some(refusal),
        }
    }
}

impl From<Value> for Observation {
    fn from(fields: Value) -> Observation {
        Observation {
            fields,
            refusal: None,
        }
    }
}

/// The fields of a process-data step: the status word, `actuals` IW1..IW3 (the actual values
/// every binding carries: PPO types 2 and 4 have three), so that manual-level expectations
/// hold over every bus, and `actuals_4_5` for the further ones a bus carries (EtherNet/IP
/// assemblies, EtherCAT PDOs).
pub(crate) fn process_fields(status: u16, actuals: &[u16]) -> Value {
    let (common, extra) = actuals.split_at(actuals.len().min(3));
    serde_json::json!({ "status": status, "actuals": common, "actuals_4_5": extra })
}

/// How long a process-data step runs on a real clock: a step "for" a time (`process: … for`,
/// `wait:`) lasts that time, however many cycles fit; `None` on a virtual clock, where the
/// cycles [`process_run`] counts all fit, and for a step of a number of cycles.
pub(crate) fn process_time(action: &Action, real_time: bool) -> Option<Duration> {
    match action {
        Action::Process {
            run: crate::suite::Run::For(d),
            ..
        }
        | Action::Wait(d) => Some(*d).filter(|_| real_time),
        _ => None,
    }
}

/// The process-data run a `process` or `wait` step asks of a bus with six words per inverter:
/// the inverter, its output words (control word, setpoints 1..5; none for `wait`, which runs
/// FI 1's as they are) and the cycles at `cycle`.
pub(crate) fn process_run(
    action: &Action,
    cycle: Duration,
) -> Result<(Inverter, Option<[u16; 6]>, u32), StepError> {
    match action {
        Action::Process {
            inverter,
            control,
            setpoints,
            run,
        } => {
            let mut words = [0; 6];
            words[0] = *control;
            for (w, s) in words[1..].iter_mut().zip(setpoints) {
                *w = *s;
            }
            let cycles = match run {
                crate::suite::Run::Cycles(n) => *n,
                crate::suite::Run::For(d) => crate::timing::cycles_for(*d, cycle),
            };
            Ok((*inverter, Some(words), cycles))
        }
        Action::Wait(d) => Ok((
            Inverter::new(1).map_err(|e| StepError::Suite(e.into()))?,
            None,
            crate::timing::cycles_for(*d, cycle),
        )),
        _ => Err(StepError::Suite("not a process-data step".into())),
    }
}

/// Why a DUT could not be opened.
#[derive(Debug, thiserror::Error)]
pub(crate) enum OpenError {
    /// The profile does not fit the binding (no such product, no such bus on it).
    #[error("{0}")]
    Profile(String),
    /// The DUT cannot be reached (no such host or interface, refused connection, no answer).
    #[error("cannot reach the DUT: {0}")]
    Unreachable(String),
    /// The DUT answered, but not as the bus requires (bring-up failed).
    #[error("the DUT did not come up: {0}")]
    BringUp(String),
    /// The host does not allow it (raw sockets need root or CAP_NET_RAW).
    #[error("not permitted here: {0}")]
    NotPermitted(String),
    /// The DUT answers, but past its limits: a wait of the bring-up passed with the host on
    /// time, and given [`crate::net::wait::REACH`] times its limits the device came up. A fail,
    /// as a late answer to a step is.
    #[error(
        "the DUT answers late: {0}; given {reach} times its limits, it came up",
        reach = crate::net::wait::REACH
    )]
    Late(String),
}

impl OpenError {
    /// The verdict of a case that could not open the DUT for this.
    pub(crate) fn verdict(&self) -> crate::outcome::Verdict {
        match self {
            OpenError::Late(_) => crate::outcome::Verdict::Fail,
            _ => crate::outcome::Verdict::Error,
        }
    }
}

/// What a cleanup could not put back, by name.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub(crate) struct CleanupError(pub(crate) String);

/// Why the harness could not act on the DUT outside the protocol (`inject`, `observe`).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub(crate) struct DutError(pub(crate) String);

impl From<String> for DutError {
    fn from(s: String) -> DutError {
        DutError(s)
    }
}

/// The harness's end of a binding: performs the manual-level steps over one protocol.
pub(crate) trait Binding {
    /// What is being tested, for reports.
    fn describe(&self) -> String;
    /// What this binding lets the harness do.
    fn capabilities(&self) -> &[Capability];
    /// Runs one DUT step, returning what was observed. A manual-level step the bus cannot
    /// perform is [`StepError::NotApplicable`] with the reason.
    fn perform(&mut self, action: &Action) -> Result<Observation, StepError>;
    /// The exchanges since the last call, for the transcript.
    fn take_exchanges(&mut self) -> Vec<Exchange>;
    /// Leaves the DUT as the case found it, once the case's steps are over, whatever the
    /// verdict: a persistent DUT (a device on the network) must not carry one case's changes
    /// into the next. Its exchanges are taken with [`Binding::take_exchanges`] afterwards.
    /// The error names what could not be restored. A DUT opened afresh for every case (the
    /// embedded simulator) has nothing to do.
    fn finish(&mut self) -> Result<(), CleanupError> {
        Ok(())
    }
    /// Whether [`Binding::finish`] also undoes what opening set up, as a PROFINET binding
    /// releases the AR its opening brought to data exchange: a case whose recovery ran the
    /// cleanup then needs the binding opened again.
    fn finish_closes(&self) -> bool {
        false
    }
    /// The device's identity as it reports it over the bus (ListIdentity, SII and 1018h,
    /// IdentResponse, DCP and I&M0), for the run's record and its connection check. `None`
    /// where the link has no identity service of its own: the runner then asks the NORD
    /// information parameters (`crate::identity`).
    fn identity(&mut self) -> Option<Result<Identity, StepError>> {
        None
    }
}

/// A device under test, one bus cycle at a time.
pub(crate) trait Dut {
    /// What is being tested, for reports.
    fn describe(&self) -> String;
    /// What this DUT lets the harness do.
    fn capabilities(&self) -> &[Capability];
    /// The bus cycle time.
    fn cycle_time(&self) -> Duration;
    /// One bus cycle: sends `frame`, returns the frame the DUT answered within the cycle, if any;
    /// an error when the bus itself found the DUT at fault meanwhile (a PROFINET input CR
    /// whose data hold time expired), so that the verdict names that rather than silence.
    fn cycle(&mut self, frame: &[u8]) -> Result<Option<Vec<u8>>, StepError>;
    /// Raises an inverter error (`fault-injection`).
    fn inject(&mut self, inverter: Inverter, error: &str) -> Result<(), DutError>;
    /// Shows internal state (`observe`).
    fn observe(&mut self, what: &str, inverter: Inverter) -> Result<Value, DutError>;
}

/// Opens a DUT for a profile; called once per case so every case starts from a known state.
pub(crate) trait DutFactory {
    /// What is tested, for reports.
    fn describe(&self) -> String;
    /// A DUT in its power-on state for the profile, behind the profile's binding.
    fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError>;
    /// A factory of its own for another thread, when the DUTs this one opens share nothing
    /// (the embedded simulator's): the runner then runs profiles side by side. `None` for a
    /// device on the network, which is one device however many profiles test it.
    fn fork(&self) -> Option<Box<dyn DutFactory + Send>> {
        None
    }
}

/// Downcasts a bus step to the bus's own step type; the error is a suite error naming the
/// bus, for a step handed to the wrong binding.
pub(crate) fn own_step<'a, T: 'static>(
    step: &'a dyn crate::suite::BusStep,
    binding: &str,
) -> Result<&'a T, StepError> {
    step.as_any().downcast_ref::<T>().ok_or_else(|| {
        StepError::NotApplicable(format!(
            "a `{}:` step cannot run over {binding}",
            step.bus()
        ))
    })
}
