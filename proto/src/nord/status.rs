//! The status word (ZSW), first word of the process data from the inverter.
//!
//! BU 0620 §6.1.2.2 (p. 107).

use serde::Serialize;

use super::control::{bits, set_names};
use super::state_machine::State;

/// A status word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct StatusWord(pub u16);

/// Names of the 16 bits when set, after BU 0620 §6.1.2.2. Bit 5 "Emergency stop" is 0 while
/// the command is present, so set it reads "no emergency stop".
pub const BIT_NAMES: [&str; 16] = [
    "Ready to start",
    "Ready for operation",
    "Operation enabled",
    "Fault",
    "Voltage enabled",
    "No emergency stop",
    "Starting disabled",
    "Warning active",
    "Setpoint reached",
    "Bus control active",
    "Start function 481.9",
    "Rotation right is on",
    "Rotation left is on",
    "Start function 481.10",
    "Parameter set Bit 0 ON",
    "Parameter set Bit 1 On",
];

/// The bits of a status word by name, with the decoded state.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StatusFields {
    /// The word.
    pub word: u16,
    /// Bits 0..15 as 0/1.
    pub bits: Vec<u8>,
    /// Names of the set bits.
    pub set: Vec<&'static str>,
    /// Active parameter set (bits 14–15).
    pub parameter_set: u8,
    /// State per the decoded-status table (§6.1.2.3), or `None` when bits 0–6 match no row.
    pub state: Option<&'static str>,
    /// The state's letter A..H.
    pub letter: Option<char>,
}

impl StatusWord {
    /// Bit `n`.
    pub fn bit(self, n: u8) -> bool {
        n < 16 && self.0 & (1 << n) != 0
    }

    /// The bits by name and the decoded state.
    pub fn fields(self) -> StatusFields {
        let state = State::from_status(self);
        StatusFields {
            word: self.0,
            bits: bits(self.0),
            set: set_names(self.0, &BIT_NAMES),
            parameter_set: ((self.0 >> 14) & 3) as u8 + 1,
            state: state.map(State::name),
            letter: state.map(State::letter),
        }
    }

    /// One line in the manual's terms.
    pub fn describe(self) -> String {
        let f = self.fields();
        format!(
            "status word {:04X}h ({:016b}b): {}; state: {}; parameter set {}",
            self.0,
            self.0,
            f.set.join(", "),
            f.state.unwrap_or("no row of the decoded-status table"),
            f.parameter_set
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answer_0b31h_is_ready_for_switch_on() {
        // §6.1.2.2: "0B31h" ("101100110001b") indicates "Ready for switch-on".
        let f = StatusWord(0x0B31).fields();
        assert_eq!(f.state, Some("Ready for switch-on"));
        assert_eq!(f.letter, Some('C'));
        assert!(f.set.contains(&"Bus control active") && f.set.contains(&"Setpoint reached"));
    }
}
