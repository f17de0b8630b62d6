//! What a step can do to a real device beyond what it tests: make a motor turn, or wear the
//! device's EEPROM. A drive on the network (`--dut`) may have a motor attached, and its
//! EEPROM allows "100,000 cycles" of writing (BU 0620 §2.5.6 p. 51, BU 0590 §4.2.4); the
//! embedded simulator has neither, so this only governs runs against a DUT.
//!
//! The classification is conservative: where the bytes do not tell, a step counts as able to
//! make a motor turn, and a parameter write counts as an EEPROM write unless its order label
//! says RAM only. The firmware under test is what is being checked, so a rule of the manual
//! that would make a word harmless (control bit 10 "control data valid" clear: "the process
//! data will not be evaluated", BU 0620 §6.1.2.1) is not relied upon.
//!
//! A case is judged whole, before any of its steps is sent ([`Guard::refuse`]): a case is
//! never cut off halfway with the drive in a state its later steps were meant to undo.

use crate::effect::{parameter_write, pkw, process, Effect};
use crate::suite::{Action, Case};
use proto::nord::pkw::OrderLabel;

/// What a step can do to a real device.
pub(crate) fn of_action(action: &Action) -> Effect {
    match action {
        Action::Compute { .. }
        | Action::Read(_)
        | Action::Wait(_)
        | Action::Inject { .. }
        | Action::Observe { .. } => Effect::NONE,
        Action::Write(o) => {
            let label = o.ak.map(OrderLabel);
            if label.is_some_and(|l| !l.is_change()) {
                return Effect::NONE;
            }
            let ram_only = !o.eeprom || label.is_some_and(OrderLabel::is_ram_only);
            parameter_write(o.target.inverter(), o.number.get(), ram_only)
        }
        Action::Pkw { bytes, .. } => pkw(bytes),
        Action::Process {
            control, setpoints, ..
        } => process(*control, setpoints),
        Action::Bus(step) => step.effect(),
    }
}

/// What the steps of `case` can do, together.
pub(crate) fn of_steps<'a>(steps: impl IntoIterator<Item = &'a crate::suite::Step>) -> Effect {
    steps
        .into_iter()
        .fold(Effect::NONE, |e, s| e.and(of_action(&s.action)))
}

/// What a run against a DUT on the network allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Limits {
    /// `--allow-motion`.
    pub(crate) allow_motion: bool,
    /// `--max-eeprom-writes`.
    pub(crate) max_eeprom_writes: u32,
}

/// The run's account of [`Limits`]: which cases may run, and the EEPROM writes so far.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Guard {
    limits: Limits,
    eeprom_writes: u32,
}

/// Each EEPROM write a case makes is counted twice: the cleanup of a device on the network
/// writes the value before back the same way ([`crate::binding::ledger`]), at most once per write.
const WITH_RESTORE: u32 = 2;

impl Guard {
    /// A run's guard, nothing written yet.
    pub(crate) fn new(limits: Limits) -> Guard {
        Guard {
            limits,
            eeprom_writes: 0,
        }
    }

    /// Why `case` must not run, if it must not: decided from all its steps before any is
    /// sent.
    pub(crate) fn refuse(&self, case: &Case) -> Option<String> {
        let effect = of_steps(&case.steps);
        if let (false, Some(why)) = (self.limits.allow_motion, &effect.motion) {
            return Some(format!("motion not allowed (--allow-motion): {why}"));
        }
        let after = self
            .eeprom_writes
            .saturating_add(effect.eeprom_writes.saturating_mul(WITH_RESTORE));
        (after > self.limits.max_eeprom_writes).then(|| {
            format!(
                "EEPROM write cap reached (--max-eeprom-writes {}): {} written, the case needs {} with its restores",
                self.limits.max_eeprom_writes,
                self.eeprom_writes,
                effect.eeprom_writes.saturating_mul(WITH_RESTORE)
            )
        })
    }

    /// The first steps of `case` were sent, one for each of `taken`, which says whether the
    /// device took the step (it did not refuse it: no SDO abort, no CIP error status, no PKW
    /// error answer). The EEPROM writes of the steps it took, and their restores by the
    /// cleanup, count; a refused write wrote nothing and needs no restore. A step left without
    /// an answer counts: the device may have taken it.
    pub(crate) fn ran(&mut self, case: &Case, taken: &[bool]) {
        let steps = case.steps.iter().zip(taken).filter(|(_, t)| **t);
        let effect = of_steps(steps.map(|(s, _)| s));
        self.eeprom_writes = self
            .eeprom_writes
            .saturating_add(effect.eeprom_writes.saturating_mul(WITH_RESTORE));
    }

    /// The EEPROM writes counted so far.
    pub(crate) fn eeprom_writes(&self) -> u32 {
        self.eeprom_writes
    }

    /// Whether motion is allowed.
    pub(crate) fn motion_allowed(&self) -> bool {
        self.limits.allow_motion
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::suite::load_text_for_tests;

    const SUITE: &str = r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: runs
    title: runs the drive
    ref: { section: "6.1.3", page: 114 }
    steps:
      - read: { param: 102 }
      - process: { control: "047Eh", for: 40ms }
      - process: { control: "047Fh", setpoints: ["2000h"], for: 2s }
  - id: writes
    title: writes P102 twice
    ref: { section: "2.5.6", page: 51 }
    steps:
      - write: { param: 102, value: 100 }
      - write: { param: 102, value: 200 }
  - id: ram
    title: writes P102 in RAM
    ref: { section: "2.5.6", page: 51 }
    steps:
      - write: { param: 102, value: 100, eeprom: false }
"#;

    #[test]
    fn a_case_is_refused_whole_for_motion_and_for_the_eeprom_cap() {
        let loaded = load_text_for_tests(SUITE);
        let [runs, writes, ram] = &loaded.cases[..] else {
            panic!("three cases")
        };
        let mut g = Guard::new(Limits {
            allow_motion: false,
            max_eeprom_writes: 6,
        });
        let why = g.refuse(runs).unwrap();
        assert!(
            why.starts_with("motion not allowed (--allow-motion): control word 047Fh"),
            "{why}"
        );
        // Two writes and their two restores: 4 of 6; the next such case would need 8.
        assert_eq!(g.refuse(writes), None);
        // Two writes the device refused wrote nothing.
        g.ran(writes, &[false, false]);
        assert_eq!(g.eeprom_writes(), 0);
        g.ran(writes, &[true, true]);
        assert_eq!(g.eeprom_writes(), 4);
        let why = g.refuse(writes).unwrap();
        assert!(
            why.starts_with("EEPROM write cap reached (--max-eeprom-writes 6)"),
            "{why}"
        );
        // RAM only costs nothing; a case stopped after its first step counts that one.
        assert_eq!(g.refuse(ram), None);
        g.ran(writes, &[true]);
        assert_eq!(g.eeprom_writes(), 6);
        let g = Guard::new(Limits {
            allow_motion: true,
            max_eeprom_writes: 6,
        });
        assert_eq!(g.refuse(runs), None);
    }
}
