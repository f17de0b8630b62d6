//! The control word (STW), first word of the process data to the inverter.
//!
//! BU 0620 §6.1.2.1 (p. 106): bits, meanings and the priority of simultaneous commands.

use serde::Serialize;

/// A control word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ControlWord(pub u16);

/// Names of the 16 bits when set, after BU 0620 §6.1.2.1. Bits 1 and 2 act when 0 ("Disable
/// voltage", "Emergency stop"); set, they mean the value-1 column: the command is cancelled.
pub const BIT_NAMES: [&str; 16] = [
    "Ready for operation",
    "Disable voltage cancelled",
    "Emergency stop cancelled",
    "Enable operation",
    "Enable pulses",
    "Enable ramp",
    "Enable setpoint",
    "Acknowledge the error (0→1)",
    "Start function 480.11",
    "Start function 480.12",
    "Control data valid",
    "Rotation right is on",
    "Rotation left is on",
    "Reserved",
    "Parameter set Bit 0 On",
    "Parameter set Bit 1 On",
];

/// Bits 0..15 of a word as 0/1, for the control and status word tables.
pub(crate) fn bits(word: u16) -> Vec<u8> {
    (0..16).map(|n| u8::from(word & (1 << n) != 0)).collect()
}

/// The names of the set bits of a word.
pub(crate) fn set_names(word: u16, names: &[&'static str; 16]) -> Vec<&'static str> {
    (0..16)
        .filter(|n| word & (1 << n) != 0)
        .map(|n| names[n])
        .collect()
}

/// The bits of a control word by name, for `harness decode control` and compute steps.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ControlFields {
    /// The word.
    pub word: u16,
    /// Bits 0..15 as 0/1.
    pub bits: Vec<u8>,
    /// Names of the set bits.
    pub set: Vec<&'static str>,
    /// Parameter set selected by bits 14–15 (1..4).
    pub parameter_set: u8,
    /// Control bit 10: the inverter evaluates the telegram only when set.
    pub valid: bool,
}

impl ControlWord {
    /// "047Eh": shut down → "Ready for switch-on" (§6.1.2.1 first control command).
    pub const SHUT_DOWN: ControlWord = ControlWord(0x047E);
    /// "047Fh": enable operation (§6.1.3).
    pub const ENABLE_OPERATION: ControlWord = ControlWord(0x047F);

    /// Bit `n`.
    pub fn bit(self, n: u8) -> bool {
        n < 16 && self.0 & (1 << n) != 0
    }

    /// Bit 10 "Control data valid" (§6.1.2.1 note ²).
    pub fn valid(self) -> bool {
        self.bit(10)
    }

    /// Parameter set 1..4 from bits 14–15.
    pub fn parameter_set(self) -> u8 {
        ((self.0 >> 14) & 0x3) as u8 + 1
    }

    /// Rotation left is requested (bit 12 has priority over bit 11, note ³).
    pub fn left(self) -> bool {
        self.bit(12)
    }

    /// The bits by name.
    pub fn fields(self) -> ControlFields {
        ControlFields {
            word: self.0,
            bits: bits(self.0),
            set: set_names(self.0, &BIT_NAMES),
            parameter_set: self.parameter_set(),
            valid: self.valid(),
        }
    }

    /// One line in the manual's terms.
    pub fn describe(self) -> String {
        let f = self.fields();
        format!(
            "control word {:04X}h ({:016b}b): {}; parameter set {}{}",
            self.0,
            self.0,
            f.set.join(", "),
            f.parameter_set,
            if f.valid {
                ""
            } else {
                "; control data NOT valid (bit 10 = 0): the inverter ignores it"
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_command_047eh() {
        // §6.1.2.1: "047Eh" ("10001111110b") sets the inverter to "Ready for switch-on".
        let c = ControlWord::SHUT_DOWN;
        assert_eq!(c.0, 0b100_0111_1110);
        assert!(c.valid() && !c.bit(0) && c.bit(1) && c.bit(2) && c.bit(3));
        assert_eq!(c.parameter_set(), 1);
        assert!(c.describe().contains("Control data valid"));
    }

    #[test]
    fn parameter_set_bits() {
        assert_eq!(ControlWord(0xC000).parameter_set(), 4);
        assert_eq!(ControlWord(0x4000).parameter_set(), 2);
        assert!(!ControlWord(0x007F).valid());
    }
}
