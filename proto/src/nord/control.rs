//! The control word (STW), first word of the process data to the inverter.
//!
//! BU 0620 §6.1.2.1 (p. 106) — the same table in BU 2100 §6.2.2 (p. 33), BU 2200 §6.3.1
//! (p. 32, German) and the Chinese BU 0620 §6.1.2.1; BU 0590 §4.1.2 Table 14 (p. 19) names the
//! bits after PROFIdrive ("OFF 1", "OFF 2", "OFF 3") with the same meanings.

use std::fmt;

use serde::Serialize;

use super::state_machine::{self, Command};

/// A control word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ControlWord(pub u16);

/// One row of a control- or status-word table: the designation and what each value means.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct BitDef {
    /// The bit's designation in the table ("Disable voltage").
    pub name: &'static str,
    /// The table's text for value 0 (empty where the manual has none).
    pub when_0: &'static str,
    /// The table's text for value 1.
    pub when_1: &'static str,
    /// The priority column for value 0 and value 1 (control word only, 1 = highest).
    pub priority: [Option<u8>; 2],
    /// The designation names what value 0 does: the bit is in effect at 0 (control bits 1
    /// "Disable voltage" and 2 "Emergency stop", whose 1 is "Cancel …"; BU 0590 §4.1.2 Table 14
    /// names them "OFF 2" and "OFF 3" at 0).
    pub active_low: bool,
}

const fn def(
    name: &'static str,
    when_0: &'static str,
    when_1: &'static str,
    priority: [Option<u8>; 2],
) -> BitDef {
    BitDef {
        name,
        when_0,
        when_1,
        priority,
        active_low: false,
    }
}

/// `d` as a row whose designation is the command its value 0 gives.
const fn low(d: BitDef) -> BitDef {
    BitDef {
        active_low: true,
        ..d
    }
}

const NONE: [Option<u8>; 2] = [None, None];

/// The control-word table of BU 0620 §6.1.2.1 (p. 106), bit by bit.
pub const BITS: [BitDef; 16] = [
    def(
        "Ready for operation",
        "Reverse with brake ramp, with voltage enabled at f=0 Hz (ready for operation)",
        "Set the frequency inverter to standby.",
        [Some(3), Some(5)],
    ),
    low(def(
        "Disable voltage",
        "Switch off the frequency inverter output voltage (the frequency inverter goes into the status \"Switch-on block\").",
        "Cancel \"Disable voltage\"",
        [Some(1), None],
    )),
    low(def(
        "Emergency stop",
        "Emergency stop with programmed emergency stop time. At f = 0 Hz voltage enable (the FI goes into \"Switch-on block\" status)",
        "Cancel operating condition \"Emergency stop\"",
        [Some(2), None],
    )),
    def(
        "Enable operation",
        "Block voltage: Switch off the frequency inverter output voltage (the frequency inverter goes into the status \"Ready for switch-on\").",
        "Enable output voltage Acceleration of the frequency inverter to the present setpoint.",
        [Some(6), Some(4)],
    ),
    def(
        "Enable pulses",
        "Acceleration encoder is set to zero; at f = 0 Hz no voltage enable (FI remains in \"Operation enabled\" status).",
        "Enable acceleration encoder",
        NONE,
    ),
    def(
        "Enable ramp",
        "Freeze the setpoint currently provided by the acceleration encoder (maintain frequency).",
        "Enable setpoint on acceleration encoder",
        NONE,
    ),
    def(
        "Enable setpoint",
        "Set the selected setpoint on the acceleration encoder to 0",
        "Activate the selected setpoint on the acceleration encoder.",
        NONE,
    ),
    def(
        "Acknowledge the error (0→1)",
        "With the switch from 0 to 1, inactive errors are acknowledged.",
        "Note: if a digital input is programmed for \"ack.fault\", this bit must not permanently be 1 via the bus (edge evaluation).",
        [Some(7), None],
    ),
    def(
        "Start function 480.11",
        "",
        "Bus bit 8 of the control word is set (P480)",
        NONE,
    ),
    def(
        "Start function 480.12",
        "",
        "Bus bit 9 of the control word is set (P480)",
        NONE,
    ),
    def(
        "Control data valid",
        "The transmitted process data are invalid.",
        "The bus master transfers valid process data",
        NONE,
    ),
    def(
        "Rotation right is on",
        "",
        "Switch on rotation right.",
        NONE,
    ),
    def(
        "Rotation left is on",
        "",
        "Switch on rotation left (priority).",
        NONE,
    ),
    def("Reserved", "", "", NONE),
    def(
        "Parameter set Bit 0 On",
        "",
        "Bits 15/14 select parameter set 1..4",
        NONE,
    ),
    def(
        "Parameter set Bit 1 On",
        "",
        "Bits 15/14 select parameter set 1..4",
        NONE,
    ),
];

/// Bits 0..15 of a word as 0/1, for the control and status word tables.
pub(crate) fn bits(word: u16) -> Vec<u8> {
    (0..16).map(|n| u8::from(word & (1 << n) != 0)).collect()
}

/// The designations in effect in a word: each bit at 1, and each active-low bit
/// ([`BitDef::active_low`]) at 0.
pub(crate) fn active_names(word: u16, table: &[BitDef; 16]) -> Vec<&'static str> {
    table
        .iter()
        .enumerate()
        .filter(|(n, d)| (word & (1 << n) != 0) != d.active_low)
        .map(|(_, d)| d.name)
        .collect()
}

/// The bits of a control word by name, for `harness decode control` and compute steps.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ControlFields {
    /// The word.
    pub word: u16,
    /// Bits 0..15 as 0/1.
    pub bits: Vec<u8>,
    /// Designations in effect (§6.1.2.1 "Designation" column): the bits at 1, and "Disable
    /// voltage" and "Emergency stop" when their bit is 0 (a 1 cancels them).
    pub active: Vec<&'static str>,
    /// Control commands of the transition table (§6.1.2.3) the bits 0–7 form, highest priority
    /// first ("Shut down", "Enable operation", …; the acknowledge edge needs two words).
    pub commands: Vec<&'static str>,
    /// Priority of the first command (§6.1.2.1 priority column), if any.
    pub priority: Option<u8>,
    /// Parameter set selected by bits 14–15 (1..4).
    pub parameter_set: u8,
    /// Control bit 10: the inverter evaluates the telegram only when set.
    pub valid: bool,
    /// Direction of rotation: "left" when bit 12 is set (it has priority), else "right".
    pub rotation: &'static str,
}

impl ControlWord {
    /// Bit 0 "Ready for operation" (0 = "Shut down", 1 = "Switch on").
    pub const READY_FOR_OPERATION: u8 = 0;
    /// Bit 1 "Disable voltage" (0 = the command is present).
    pub const DISABLE_VOLTAGE: u8 = 1;
    /// Bit 2 "Emergency stop" (0 = the command is present).
    pub const EMERGENCY_STOP: u8 = 2;
    /// Bit 3 "Enable operation".
    pub const ENABLE_OPERATION_BIT: u8 = 3;
    /// Bit 4 "Enable pulses" (0 = ramp generator set to zero).
    pub const ENABLE_PULSES: u8 = 4;
    /// Bit 5 "Enable ramp" (0 = freeze the frequency).
    pub const ENABLE_RAMP: u8 = 5;
    /// Bit 6 "Enable setpoint" (0 = setpoint 0).
    pub const ENABLE_SETPOINT: u8 = 6;
    /// Bit 7 "Acknowledge the error (0→1)".
    pub const ACKNOWLEDGE: u8 = 7;
    /// Bit 10 "Control data valid".
    pub const CONTROL_DATA_VALID: u8 = 10;
    /// Bit 11 "Rotation right is on".
    pub const ROTATION_RIGHT: u8 = 11;
    /// Bit 12 "Rotation left is on" (priority over bit 11).
    pub const ROTATION_LEFT: u8 = 12;

    /// "047Eh" ("10001111110b"): the first control command, "Shut down" → "Ready for
    /// switch-on" (BU 0620 §6.1.2.1, p. 106; §6.1.3 p. 114).
    pub const SHUT_DOWN: ControlWord = ControlWord(0x047E);
    /// "047Fh": "Enable operation" (BU 0620 §6.1.3, p. 114).
    pub const ENABLE_OPERATION: ControlWord = ControlWord(0x047F);

    /// Bit `n` (false for n > 15).
    pub fn bit(self, n: u8) -> bool {
        n < 16 && self.0 & (1 << n) != 0
    }

    /// Bit 10 "Control data valid" (§6.1.2.1 note ²).
    pub fn valid(self) -> bool {
        self.bit(Self::CONTROL_DATA_VALID)
    }

    /// Parameter set 1..4 from bits 14–15.
    pub fn parameter_set(self) -> u8 {
        ((self.0 >> 14) & 0x3) as u8 + 1
    }

    /// Rotation left is requested (bit 12 has priority over bit 11, note ³).
    pub fn left(self) -> bool {
        self.bit(Self::ROTATION_LEFT)
    }

    /// The transition-table commands bits 0–7 form, highest priority first (§6.1.2.1,
    /// §6.1.2.3).
    pub fn commands(self) -> Vec<&'static Command> {
        let mut found: Vec<&'static Command> = state_machine::COMMANDS
            .iter()
            .filter(|c| c.matches(self))
            .collect();
        found.sort_by_key(|c| c.priority);
        found
    }

    /// The bits by name.
    pub fn fields(self) -> ControlFields {
        let commands = self.commands();
        ControlFields {
            word: self.0,
            bits: bits(self.0),
            active: active_names(self.0, &BITS),
            priority: commands.first().map(|c| c.priority),
            commands: commands.iter().map(|c| c.name).collect(),
            parameter_set: self.parameter_set(),
            valid: self.valid(),
            rotation: if self.left() { "left" } else { "right" },
        }
    }

    /// One line in the manual's terms.
    pub fn describe(self) -> String {
        self.to_string()
    }
}

impl fmt::Display for ControlWord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = self.fields();
        write!(
            f,
            "control word {:04X}h ({:016b}b): in effect {}; command {}; rotation {}; parameter set {}",
            self.0,
            self.0,
            if c.active.is_empty() {
                "none".to_string()
            } else {
                c.active.join(", ")
            },
            c.commands.first().copied().unwrap_or("none"),
            c.rotation,
            c.parameter_set
        )?;
        if !c.valid {
            f.write_str("; control data NOT valid (bit 10 = 0): the inverter ignores it")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[test]
    fn first_command_047eh() {
        // BU 0620 §6.1.2.1 p. 106: "047Eh" ("10001111110b") sets "Ready for switch-on".
        let c = ControlWord::SHUT_DOWN;
        assert_eq!(c.0, 0b100_0111_1110);
        assert!(c.valid() && !c.bit(0) && c.bit(1) && c.bit(2) && c.bit(3));
        assert_eq!(c.parameter_set(), 1);
        assert_eq!(c.fields().commands, ["Shut down"]);
        assert!(c.describe().contains("in effect Enable operation"));
        assert!(!c.describe().contains("Disable voltage"));
        // "10001111110b": bits 0..15 as 0/1, bit 0 first.
        assert_eq!(
            c.fields().bits,
            [0, 1, 1, 1, 1, 1, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0]
        );
        // Bit 10 set: the inverter evaluates the telegram, so no "NOT valid" note.
        assert!(!c.describe().contains("NOT valid"));
    }

    #[test]
    fn bit_10_clear_is_said_not_valid() {
        // BU 0620 §6.1.2.1 bit 10 "Control data valid", at 0: "The transmitted process data are
        // invalid."
        let text = ControlWord(0x007E).describe();
        assert!(
            text.contains("control data NOT valid (bit 10 = 0)"),
            "{text}"
        );
    }

    #[rstest]
    // §6.1.2.1 priority column: disable voltage 1, emergency stop 2, shut down 3,
    // enable operation 4, switch on 5, disable operation 6.
    #[case(0x0478, &["Disable voltage"], Some(1))]
    #[case(0x047A, &["Quick stop"], Some(2))]
    #[case(0x047F, &["Enable operation", "Switch on"], Some(4))]
    #[case(0x0477, &["Switch on", "Disable operation"], Some(5))]
    #[case(0x0480, &["Disable voltage"], Some(1))]
    fn commands_by_priority(
        #[case] word: u16,
        #[case] want: &[&str],
        #[case] priority: Option<u8>,
    ) {
        let f = ControlWord(word).fields();
        assert_eq!(f.commands, want);
        assert_eq!(f.priority, priority);
    }

    #[rstest]
    // BU 0620 §6.1.2.1: bits 1 and 2 command "Disable voltage" / "Emergency stop" at 0, a 1
    // cancels them; every other designation is in effect at 1.
    #[case(0x047E, &["Enable operation", "Enable pulses", "Enable ramp", "Enable setpoint", "Control data valid"])]
    #[case(0x0478, &["Disable voltage", "Emergency stop", "Enable operation", "Enable pulses", "Enable ramp", "Enable setpoint", "Control data valid"])]
    #[case(0x047A, &["Emergency stop", "Enable operation", "Enable pulses", "Enable ramp", "Enable setpoint", "Control data valid"])]
    #[case(0x047F, &["Ready for operation", "Enable operation", "Enable pulses", "Enable ramp", "Enable setpoint", "Control data valid"])]
    #[case(0x0006, &[])]
    fn active_low_bits_are_in_effect_at_0(#[case] word: u16, #[case] want: &[&str]) {
        let c = ControlWord(word);
        assert_eq!(c.fields().active, want);
        let text = c.describe();
        assert_eq!(
            text.contains("Disable voltage"),
            !c.bit(ControlWord::DISABLE_VOLTAGE),
            "{text}"
        );
    }

    #[test]
    fn only_bits_1_and_2_are_active_low() {
        let low: Vec<usize> = (0..16).filter(|&n| BITS[n].active_low).collect();
        assert_eq!(low, [1, 2]);
        assert!(BITS[1].when_1.starts_with("Cancel") && BITS[2].when_1.starts_with("Cancel"));
    }

    #[test]
    fn bits_and_parameter_sets() {
        // Bits 14/15: 00 → set 1 … 11 → set 4 (§6.1.2.1 p. 106).
        assert_eq!(ControlWord(0xC000).parameter_set(), 4);
        assert_eq!(ControlWord(0x4000).parameter_set(), 2);
        assert!(!ControlWord(0x007F).valid());
        assert!(!ControlWord(0xFFFF).bit(16));
        // Note ³: bit 12 wins over bit 11.
        assert_eq!(ControlWord(0x1800).fields().rotation, "left");
        assert_eq!(ControlWord(0x0800).fields().rotation, "right");
        assert_eq!(BITS[10].name, "Control data valid");
        assert_eq!(BITS[3].priority, [Some(6), Some(4)]);
    }
}
