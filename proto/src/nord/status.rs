//! The status word (ZSW), first word of the process data from the inverter.
//!
//! BU 0620 §6.1.2.2 (p. 107) — the same table in BU 2100 §6.2.3 (p. 34), BU 2200 §6.3.2
//! (p. 33, German) and the Chinese BU 0620; BU 0590 §4.1.3 Table 15 (p. 20) words it after
//! PROFIdrive ("OFF 2", "OFF 3").

use std::fmt;

use serde::Serialize;

use super::control::{active_names, bits, BitDef};
use super::state_machine::State;

/// A status word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct StatusWord(pub u16);

const fn def(name: &'static str, when_0: &'static str, when_1: &'static str) -> BitDef {
    BitDef {
        name,
        when_0,
        when_1,
        priority: [None, None],
        active_low: false,
    }
}

/// The status-word table of BU 0620 §6.1.2.2 (p. 107), bit by bit. Bits 4 and 5 report a
/// command by 0: "Disable voltage" / "Emergency stop" present.
pub const BITS: [BitDef; 16] = [
    def(
        "Ready to start",
        "",
        "Initialisation completed, charging relay switched on, output voltage disabled",
    ),
    def(
        "Ready for operation",
        "No switch-on command present, or there is a fault, or the command \"Disable voltage\" or \"Emergency stop\" is present, or the status is \"Switch-on block\".",
        "There is a switch-on command and there is no fault. The inverter can be started with the command \"Enable operation\"",
    ),
    def(
        "Operation enabled",
        "",
        "The output voltage is enabled; ramp of the frequency inverter up to the existing setpoint",
    ),
    def(
        "Fault",
        "",
        "Drive unit defective and therefore \"Not ready for operation\". After acknowledgement, the frequency goes into status \"Switch-on block\".",
    ),
    def("Voltage enabled", "\"Disable voltage\" command present.", ""),
    def("Emergency stop", "\"Emergency stop\" command present.", ""),
    def(
        "Starting disabled",
        "",
        "With the command \"Standby\" the frequency goes into status \"Ready for switch-on\".",
    ),
    def(
        "Warning active",
        "",
        "Drive operation continues, no acknowledgement necessary",
    ),
    def(
        "Setpoint reached",
        "Actual value does not correspond to the setpoint",
        "Actual value matches the setpoint (setpoint reached)",
    ),
    def(
        "Bus control active",
        "Control on local device active",
        "The master has been requested to take over control.",
    ),
    def(
        "Start function 481.9",
        "",
        "Bus bit 10 of the status word is set (P481)",
    ),
    def(
        "Rotation right is on",
        "",
        "The frequency inverter output voltage has a right-hand rotation field.",
    ),
    def(
        "Rotation left is on",
        "",
        "The frequency inverter output voltage has a left-hand rotation field.",
    ),
    def(
        "Start function 481.10",
        "",
        "Bus bit 13 of the status word is set (P481)",
    ),
    def(
        "Parameter set Bit 0 ON",
        "",
        "Bits 15/14 show the active parameter set 1..4",
    ),
    def(
        "Parameter set Bit 1 On",
        "",
        "Bits 15/14 show the active parameter set 1..4",
    ),
];

/// The bits of a status word by name, with the decoded state.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StatusFields {
    /// The word.
    pub word: u16,
    /// Bits 0..15 as 0/1.
    pub bits: Vec<u8>,
    /// Designations of the set bits (§6.1.2.2 "Meaning" column).
    pub set: Vec<&'static str>,
    /// Active parameter set (bits 14–15).
    pub parameter_set: u8,
    /// State per the decoded-status table (§6.1.2.3), or `None` when bits 0–6 match no row.
    pub state: Option<&'static str>,
    /// The state's letter A..H.
    pub letter: Option<char>,
}

impl StatusWord {
    /// Bit 3 "Fault".
    pub const FAULT: u8 = 3;
    /// Bit 4 "Voltage enabled": 0 while "Disable voltage" is commanded.
    pub const VOLTAGE_ENABLED: u8 = 4;
    /// Bit 5 "Emergency stop": 0 while "Emergency stop" is commanded.
    pub const EMERGENCY_STOP: u8 = 5;
    /// Bit 8 "Setpoint reached".
    pub const SETPOINT_REACHED: u8 = 8;
    /// Bit 9 "Bus control active".
    pub const BUS_CONTROL: u8 = 9;
    /// Bit 11 "Rotation right is on".
    pub const ROTATION_RIGHT: u8 = 11;
    /// Bit 12 "Rotation left is on".
    pub const ROTATION_LEFT: u8 = 12;
    /// Bit 14, low bit of the active parameter set.
    pub const PARAMETER_SET: u8 = 14;

    /// Bit `n` (false for n > 15).
    pub fn bit(self, n: u8) -> bool {
        n < 16 && self.0 & (1 << n) != 0
    }

    /// The state the word shows (decoded-status table, §6.1.2.3 p. 111).
    pub fn state(self) -> Option<State> {
        State::from_status(self)
    }

    /// Whether the word shows "Switch-on block" under "Disable voltage": the state B row of the
    /// decoded-status table (bits 6–0 = 1XX0000b, §6.1.2.3 p. 111) with bits 4 and 5 at 0, the
    /// "Disable voltage" and "Emergency stop" commands present (§6.1.2.2 p. 107): xx40h, what
    /// an inverter answers once it has evaluated 0400h. The table leaves bits 4 and 5 open in
    /// state B, so xx50h, xx60h and xx70h are "Switch-on block" too, still showing an earlier
    /// control word.
    pub fn switch_on_block_disabled(self) -> bool {
        self.state() == Some(State::SwitchOnBlock)
            && !self.bit(Self::VOLTAGE_ENABLED)
            && !self.bit(Self::EMERGENCY_STOP)
    }

    /// The bits by name and the decoded state.
    pub fn fields(self) -> StatusFields {
        let state = self.state();
        StatusFields {
            word: self.0,
            bits: bits(self.0),
            set: active_names(self.0, &BITS),
            parameter_set: ((self.0 >> 14) & 3) as u8 + 1,
            state: state.map(State::name),
            letter: state.map(State::letter),
        }
    }

    /// One line in the manual's terms.
    pub fn describe(self) -> String {
        self.to_string()
    }
}

impl fmt::Display for StatusWord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = self.fields();
        write!(
            f,
            "status word {:04X}h ({:016b}b): {}; state: {}; parameter set {}",
            self.0,
            self.0,
            s.set.join(", "),
            self.state()
                .map_or("no row of the decoded-status table".to_string(), |st| st
                    .to_string()),
            s.parameter_set
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answer_0b31h_is_ready_for_switch_on() {
        // BU 0620 §6.1.2.2 p. 107: "0B31h" ("101100110001b") indicates "Ready for switch-on".
        let f = StatusWord(0x0B31).fields();
        assert_eq!(f.state, Some("Ready for switch-on"));
        assert_eq!(f.letter, Some('C'));
        assert_eq!(
            f.set,
            [
                "Ready to start",
                "Voltage enabled",
                "Emergency stop",
                "Setpoint reached",
                "Bus control active",
                "Rotation right is on"
            ]
        );
        assert!(StatusWord(0x0B31)
            .describe()
            .contains("Ready for switch-on (C)"));
    }

    #[test]
    fn switch_on_block_under_disable_voltage_is_xx40h_only() {
        // State B (bits 6–0 1XX0000b) with bits 4/5 showing the commands of 0400h.
        assert!(StatusWord(0x0B40).switch_on_block_disabled());
        assert!(StatusWord(0x0040).switch_on_block_disabled());
        for w in [0x0B50, 0x0B60, 0x0B70, 0x0B31, 0x0000, 0x0248] {
            assert!(!StatusWord(w).switch_on_block_disabled(), "{w:04X}h");
        }
        assert_eq!(StatusWord(0x0B60).state(), Some(State::SwitchOnBlock));
    }

    #[test]
    fn unknown_pattern_and_parameter_set() {
        assert_eq!(StatusWord(0x0002).state(), None);
        assert_eq!(StatusWord(0x8000).fields().parameter_set, 3);
        assert!(!StatusWord(0xFFFF).bit(16));
    }
}
