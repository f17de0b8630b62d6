//! Bindings: how the harness reaches a DUT.
//!
//! A [`Dut`] moves link frames (real bytes) one bus cycle at a time; [`channel::Channel`] holds
//! the protocol logic above it (parameter orders repeated until answered, process data), so the
//! same logic drives the embedded simulator and any other DUT.

pub(crate) mod channel;
pub(crate) mod embedded;
pub(crate) mod enip;

use serde_json::Value;
use std::time::Duration;

pub(crate) use channel::StepError;

use crate::outcome::Exchange;
use crate::profile::Capability;
use crate::suite::Action;
use proto::nord::Inverter;

/// The harness's end of a binding: performs the manual-level steps over one protocol.
pub(crate) trait Binding {
    /// What is being tested, for reports.
    fn describe(&self) -> String;
    /// What this binding lets the harness do.
    fn capabilities(&self) -> &[Capability];
    /// Runs one DUT step, returning what was observed.
    fn perform(&mut self, action: &Action) -> Result<Value, StepError>;
    /// The exchanges since the last call, for the transcript.
    fn take_exchanges(&mut self) -> Vec<Exchange>;
    /// Leaves the DUT as the case found it, once the case's steps are over, whatever the
    /// verdict: a persistent DUT (a device on the network) must not carry one case's changes
    /// into the next. Its exchanges are taken with [`Binding::take_exchanges`] afterwards.
    /// The error names what could not be restored. A DUT opened afresh for every case (the
    /// embedded simulator) has nothing to do.
    fn finish(&mut self) -> Result<(), String> {
        Ok(())
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
    /// One bus cycle: sends `frame`, returns the frame the DUT answered within the cycle, if any.
    fn cycle(&mut self, frame: &[u8]) -> Option<Vec<u8>>;
    /// Raises an inverter error (`fault-injection`).
    fn inject(&mut self, inverter: Inverter, error: &str) -> Result<(), String>;
    /// Shows internal state (`observe`).
    fn observe(&mut self, what: &str, inverter: Inverter) -> Result<Value, String>;
}
