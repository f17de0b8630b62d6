//! The inverter status machine: states A–H, transitions 1–15.
//!
//! BU 0620 §6.1.2.3 (p. 108–111); the same tables in BU 2100 §6.2.4 (p. 35–38), BU 2200
//! §6.3.3 (p. 34–37, German) and the Chinese BU 0620; BU 0590 §4.1.4 (p. 21–22) gives only the
//! decoded-status table (Table 16) and a figure. The transitions are data ([`TRANSITIONS`]);
//! [`next`] applies them in the priority order of §6.1.2.1 (disable voltage 1, emergency stop 2,
//! shut down 3, enable operation 4, switch on 5, disable operation 6, acknowledge 7). A control
//! word without bit 10 ("control data valid") is not evaluated.
//!
//! The manual names the states differently in its state table ("Not on standby", "Standby",
//! "Activated"), its transition table ("Not ready for switch-on", "Ready for switch-on",
//! "Switched on") and its decoded-status table ("Starting disabled", "Ready to start", "Error
//! active"); BU 2200 uses one German name per state. [`State::name`] uses the English
//! transition table's names; [`State::aliases`] lists the others.
//!
//! Not in the transition table: state F's description ("the drive is stopped, the frequency
//! inverter changes to the status 'Switch-on block'"), control bit 2 ("At f = 0 Hz ... the FI
//! goes into 'Switch-on block'") and BU 0590's figure ("f = 0 reached (emergency stop
//! complete)") leave "Emergency stop active" automatically at standstill, a transition the
//! table of 1–15 does not number. [`EMERGENCY_STOP_COMPLETE`] is that row.

use std::fmt;

use super::control::ControlWord;
use super::status::StatusWord;

/// A state of the inverter (letters A–H of BU 0620 Figure 19, p. 108).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum State {
    /// A: initial state after switching on.
    NotReadyForSwitchOn,
    /// B: switch-on block (left only with "Shut down").
    SwitchOnBlock,
    /// C: ready for switch-on, output voltage blocked.
    ReadyForSwitchOn,
    /// D: switched on, ready for operation.
    SwitchedOn,
    /// E: operation enabled, setpoints processed.
    OperationEnabled,
    /// F: emergency stop active.
    EmergencyStopActive,
    /// G: error reaction active.
    ErrorReactionActive,
    /// H: fault (left only with "Acknowledge fault").
    Fault,
}

use State::*;

impl State {
    /// All states, A..H.
    pub const ALL: [State; 8] = [
        NotReadyForSwitchOn,
        SwitchOnBlock,
        ReadyForSwitchOn,
        SwitchedOn,
        OperationEnabled,
        EmergencyStopActive,
        ErrorReactionActive,
        Fault,
    ];

    /// The letter of the state table.
    pub fn letter(self) -> char {
        (b'A' + self as u8) as char
    }

    /// The name used in the English transition table (BU 0620 §6.1.2.3 p. 110).
    pub fn name(self) -> &'static str {
        match self {
            NotReadyForSwitchOn => "Not ready for switch-on",
            SwitchOnBlock => "Switch-on block",
            ReadyForSwitchOn => "Ready for switch-on",
            SwitchedOn => "Switched on",
            OperationEnabled => "Operation enabled",
            EmergencyStopActive => "Emergency stop active",
            ErrorReactionActive => "Error reaction active",
            Fault => "Fault",
        }
    }

    /// Other names of the same state: BU 0620 state table (p. 109) and decoded-status table
    /// (p. 111), BU 0590 §4.1.4 (Table 16, Fig. 10), BU 2200 §6.3.3 (German).
    pub fn aliases(self) -> &'static [&'static str] {
        match self {
            NotReadyForSwitchOn => &[
                "Not on standby",
                "Not ready to start",
                "Nicht einschaltbereit",
            ],
            SwitchOnBlock => &[
                "Switch on block",
                "Starting disabled",
                "Switch-on disabled",
                "Einschaltsperre",
            ],
            ReadyForSwitchOn => &["Standby", "Ready to start", "Einschaltbereit"],
            SwitchedOn => &["Activated", "Eingeschaltet"],
            OperationEnabled => &["Betrieb freigegeben"],
            EmergencyStopActive => &["Schnellhalt aktiv"],
            ErrorReactionActive => &["Error active", "Störungsreaktion aktiv", "Störung aktiv"],
            Fault => &["Error", "Störung"],
        }
    }

    /// Parses a letter or any of the names (ASCII case ignored).
    pub fn from_name(s: &str) -> Option<State> {
        let s = s.trim();
        State::ALL.into_iter().find(|st| {
            s.eq_ignore_ascii_case(st.name())
                || st.aliases().iter().any(|a| s.eq_ignore_ascii_case(a))
                || (s.len() == 1 && s.starts_with(st.letter()))
        })
    }

    /// Status bits 0–6 as the decoded-status table gives them: (mask, value) — X bits are out
    /// of the mask (BU 0620 §6.1.2.3 "Decoded frequency inverter statuses", p. 111).
    pub fn status_bits(self) -> (u16, u16) {
        match self {
            NotReadyForSwitchOn => (0b100_1111, 0b000_0000),
            SwitchOnBlock => (0b100_1111, 0b100_0000),
            ReadyForSwitchOn => (0b111_1111, 0b011_0001),
            SwitchedOn => (0b111_1111, 0b011_0011),
            OperationEnabled => (0b111_1111, 0b011_0111),
            Fault => (0b100_1111, 0b000_1000),
            ErrorReactionActive => (0b100_1111, 0b000_1111),
            EmergencyStopActive => (0b111_1111, 0b001_0111),
        }
    }

    /// The state a status word shows, by the decoded-status table.
    pub fn from_status(s: StatusWord) -> Option<State> {
        State::ALL.into_iter().find(|st| {
            let (mask, value) = st.status_bits();
            s.0 & mask == value
        })
    }
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.name(), self.letter())
    }
}

/// A control command: a pattern of control bits 0–7 with its priority (BU 0620 §6.1.2.3
/// transition table, p. 110; priorities from the §6.1.2.1 table, p. 106).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Command {
    /// The command's name in the transition table.
    pub name: &'static str,
    /// Bits that matter (the non-X columns).
    pub mask: u16,
    /// Their values.
    pub value: u16,
    /// Priority, 1 = highest.
    pub priority: u8,
}

impl Command {
    /// Whether the control word carries this command.
    pub fn matches(&self, control: ControlWord) -> bool {
        control.0 & self.mask == self.value
    }
}

/// "Disable voltage": bit 1 = 0 (XXXXXX0X), priority 1.
pub const DISABLE_VOLTAGE: Command = cmd("Disable voltage", 0b0000_0010, 0b0000_0000, 1);
/// "Quick stop": bits 2..1 = 01 (XXXXX01X), priority 2 (bit 2 "Emergency stop").
pub const QUICK_STOP: Command = cmd("Quick stop", 0b0000_0110, 0b0000_0010, 2);
/// "Shut down": bits 2..0 = 110, priority 3 (bit 0 = 0).
pub const SHUT_DOWN: Command = cmd("Shut down", 0b0000_0111, 0b0000_0110, 3);
/// "Enable operation": bits 6..0 = 1111111, priority 4 (bit 3 = 1).
pub const ENABLE_OPERATION: Command = cmd("Enable operation", 0b0111_1111, 0b0111_1111, 4);
/// "Switch on": bits 2..0 = 111, priority 5 (bit 0 = 1).
pub const SWITCH_ON: Command = cmd("Switch on", 0b0000_0111, 0b0000_0111, 5);
/// "Disable operation": bits 3..0 = 0111, priority 6 (bit 3 = 0).
pub const DISABLE_OPERATION: Command = cmd("Disable operation", 0b0000_1111, 0b0000_0111, 6);
/// Priority of "Acknowledge error" (bit 7 0→1), the lowest (§6.1.2.1).
pub const ACKNOWLEDGE_PRIORITY: u8 = 7;

/// The commands a single control word can carry, in priority order.
pub const COMMANDS: [Command; 6] = [
    DISABLE_VOLTAGE,
    QUICK_STOP,
    SHUT_DOWN,
    ENABLE_OPERATION,
    SWITCH_ON,
    DISABLE_OPERATION,
];

const fn cmd(name: &'static str, mask: u16, value: u16, priority: u8) -> Command {
    Command {
        name,
        mask,
        value,
        priority,
    }
}

/// What triggers a transition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trigger {
    /// A control command in bits 0–7.
    Command(Command),
    /// Bit 7 rising edge: "Acknowledge error".
    AcknowledgeEdge,
    /// Automatic (charging relay, fault, end of the fault reaction, standstill).
    Automatic(&'static str),
}

impl Trigger {
    /// The command's priority, or `None` for automatic transitions.
    pub fn priority(&self) -> Option<u8> {
        match self {
            Trigger::Command(c) => Some(c.priority),
            Trigger::AcknowledgeEdge => Some(ACKNOWLEDGE_PRIORITY),
            Trigger::Automatic(_) => None,
        }
    }

    /// The command's name, or what happens automatically.
    pub fn name(&self) -> &'static str {
        match self {
            Trigger::Command(c) => c.name,
            Trigger::AcknowledgeEdge => "Acknowledge error",
            Trigger::Automatic(what) => what,
        }
    }
}

/// One row of the transition table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transition {
    /// Number 1..15 (0 for the unnumbered end of the emergency stop).
    pub number: u8,
    /// Source states (13 applies from any state).
    pub from: &'static [State],
    /// Target.
    pub to: State,
    /// Trigger.
    pub trigger: Trigger,
}

const fn row(number: u8, from: &'static [State], to: State, trigger: Trigger) -> Transition {
    Transition {
        number,
        from,
        to,
        trigger,
    }
}

const fn on(c: Command) -> Trigger {
    Trigger::Command(c)
}

/// The transition table of BU 0620 §6.1.2.3 (p. 110), rows 7 and 10 split by command.
pub const TRANSITIONS: &[Transition] = &[
    row(
        1,
        &[NotReadyForSwitchOn],
        SwitchOnBlock,
        Trigger::Automatic("Automatic activation of the charging relay"),
    ),
    row(2, &[SwitchOnBlock], ReadyForSwitchOn, on(SHUT_DOWN)),
    row(3, &[ReadyForSwitchOn], SwitchedOn, on(SWITCH_ON)),
    row(4, &[SwitchedOn], OperationEnabled, on(ENABLE_OPERATION)),
    row(5, &[OperationEnabled], SwitchedOn, on(DISABLE_OPERATION)),
    row(6, &[SwitchedOn], ReadyForSwitchOn, on(SHUT_DOWN)),
    row(7, &[ReadyForSwitchOn], SwitchOnBlock, on(DISABLE_VOLTAGE)),
    row(7, &[ReadyForSwitchOn], SwitchOnBlock, on(QUICK_STOP)),
    row(8, &[OperationEnabled], ReadyForSwitchOn, on(SHUT_DOWN)),
    row(9, &[OperationEnabled], SwitchOnBlock, on(DISABLE_VOLTAGE)),
    row(10, &[SwitchedOn], SwitchOnBlock, on(DISABLE_VOLTAGE)),
    row(10, &[SwitchedOn], SwitchOnBlock, on(QUICK_STOP)),
    row(11, &[OperationEnabled], EmergencyStopActive, on(QUICK_STOP)),
    row(
        12,
        &[EmergencyStopActive],
        SwitchOnBlock,
        on(DISABLE_VOLTAGE),
    ),
    row(
        13,
        &[
            NotReadyForSwitchOn,
            SwitchOnBlock,
            ReadyForSwitchOn,
            SwitchedOn,
            OperationEnabled,
            EmergencyStopActive,
        ],
        ErrorReactionActive,
        Trigger::Automatic("Automatically, after the occurrence of a fault from any status"),
    ),
    row(
        14,
        &[ErrorReactionActive],
        Fault,
        Trigger::Automatic("Automatically after completion of the response to a fault"),
    ),
    row(15, &[Fault], SwitchOnBlock, Trigger::AcknowledgeEdge),
];

/// F → B at standstill: state F's description and control bit 2 (§6.1.2.1, §6.1.2.3), BU 0590
/// Fig. 10 "f = 0 reached (emergency stop complete)"; the table of 1–15 has no number for it.
pub const EMERGENCY_STOP_COMPLETE: Transition = row(
    0,
    &[EmergencyStopActive],
    SwitchOnBlock,
    Trigger::Automatic("f = 0 reached (emergency stop complete)"),
);

/// The transition a control word triggers from `state`, or `None` (the state stays).
///
/// `previous` is the control word of the previous telegram: "Acknowledge error" is the 0→1
/// edge of bit 7, which one word cannot show. A word without bit 10 is not evaluated
/// (§6.1.2.3 "Control bit 10", p. 111). Of the rows that leave `state` and whose command the
/// word carries, the one with the highest priority (§6.1.2.1) wins.
pub fn next(
    state: State,
    control: ControlWord,
    previous: ControlWord,
) -> Option<&'static Transition> {
    if !control.valid() {
        return None;
    }
    let ack = control.bit(ControlWord::ACKNOWLEDGE) && !previous.bit(ControlWord::ACKNOWLEDGE);
    TRANSITIONS
        .iter()
        .filter(|t| t.from.contains(&state))
        .filter(|t| match t.trigger {
            Trigger::Command(c) => c.matches(control),
            Trigger::AcknowledgeEdge => ack,
            Trigger::Automatic(_) => false,
        })
        .min_by_key(|t| t.trigger.priority())
}

/// The automatic transition numbered `number` (1, 13 or 14), for the drive model.
pub fn automatic(number: u8) -> Option<&'static Transition> {
    TRANSITIONS
        .iter()
        .find(|t| t.number == number && matches!(t.trigger, Trigger::Automatic(_)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    fn cw(w: u16) -> ControlWord {
        ControlWord(w)
    }

    #[rstest]
    // BU 0620 §6.1.2.3 p. 110, one row each (X bits set as in 047xh words).
    #[case(SwitchOnBlock, 0x047E, Some((2, ReadyForSwitchOn)))]
    #[case(ReadyForSwitchOn, 0x047F, Some((3, SwitchedOn)))]
    #[case(SwitchedOn, 0x047F, Some((4, OperationEnabled)))]
    #[case(OperationEnabled, 0x0477, Some((5, SwitchedOn)))]
    #[case(SwitchedOn, 0x047E, Some((6, ReadyForSwitchOn)))]
    #[case(ReadyForSwitchOn, 0x0400, Some((7, SwitchOnBlock)))]
    #[case(ReadyForSwitchOn, 0x047A, Some((7, SwitchOnBlock)))]
    #[case(OperationEnabled, 0x047E, Some((8, ReadyForSwitchOn)))]
    #[case(OperationEnabled, 0x047D, Some((9, SwitchOnBlock)))]
    #[case(SwitchedOn, 0x047D, Some((10, SwitchOnBlock)))]
    #[case(SwitchedOn, 0x047B, Some((10, SwitchOnBlock)))]
    #[case(OperationEnabled, 0x047B, Some((11, EmergencyStopActive)))]
    #[case(EmergencyStopActive, 0x0479, Some((12, SwitchOnBlock)))]
    // Control bit 10 = 0: not evaluated (p. 111).
    #[case(SwitchOnBlock, 0x007E, None)]
    // B is left only with "Shut down" (state table p. 109).
    #[case(SwitchOnBlock, 0x047F, None)]
    // Enable operation needs bits 4–6: 040Fh leaves D as it is.
    #[case(SwitchedOn, 0x040F, None)]
    // Switch on (5) and enable operation (4) both match 047Fh in D: 4 wins.
    #[case(SwitchedOn, 0x047F, Some((4, OperationEnabled)))]
    // Priority: disable voltage (1) wins over quick stop (2) and shut down (3).
    #[case(OperationEnabled, 0x0478, Some((9, SwitchOnBlock)))]
    // Quick stop does not leave F; only disable voltage does (12).
    #[case(EmergencyStopActive, 0x047B, None)]
    // No command leaves G; H only by acknowledging.
    #[case(ErrorReactionActive, 0x0478, None)]
    #[case(Fault, 0x047E, None)]
    fn transitions(#[case] from: State, #[case] word: u16, #[case] want: Option<(u8, State)>) {
        let got = next(from, cw(word), cw(0)).map(|t| (t.number, t.to));
        assert_eq!(got, want);
    }

    #[test]
    fn acknowledge_needs_a_rising_edge() {
        // Transition 15: bit 7 0 → 1 (p. 110).
        let t = next(Fault, cw(0x04FE), cw(0x047E)).map(|t| (t.number, t.to));
        assert_eq!(t, Some((15, SwitchOnBlock)));
        assert_eq!(next(Fault, cw(0x04FE), cw(0x04FE)), None);
        assert_eq!(next(Fault, cw(0x00FE), cw(0x047E)), None, "bit 10 = 0");
    }

    #[test]
    fn automatic_rows() {
        assert_eq!(automatic(1).map(|t| t.to), Some(SwitchOnBlock));
        assert_eq!(automatic(13).map(|t| t.to), Some(ErrorReactionActive));
        assert_eq!(automatic(14).map(|t| t.to), Some(Fault));
        assert_eq!(automatic(2), None);
        assert!(!automatic(13).is_some_and(|t| t.from.contains(&Fault)));
    }

    #[test]
    fn every_number_1_to_15_is_in_the_table() {
        for n in 1..=15 {
            assert!(TRANSITIONS.iter().any(|t| t.number == n), "transition {n}");
        }
        assert_eq!(COMMANDS.map(|c| c.priority), [1, 2, 3, 4, 5, 6]);
    }

    #[rstest]
    // Decoded-status table p. 111.
    #[case(0x0B31, Some(ReadyForSwitchOn))]
    #[case(0x0B37, Some(OperationEnabled))]
    #[case(0x0040, Some(SwitchOnBlock))]
    #[case(0x0070, Some(SwitchOnBlock))]
    #[case(0x0000, Some(NotReadyForSwitchOn))]
    #[case(0x0033, Some(SwitchedOn))]
    #[case(0x0008, Some(Fault))]
    #[case(0x000F, Some(ErrorReactionActive))]
    #[case(0x0017, Some(EmergencyStopActive))]
    #[case(0x0002, None)]
    #[case(0x0021, None)]
    fn decoded_status_table(#[case] word: u16, #[case] want: Option<State>) {
        assert_eq!(State::from_status(StatusWord(word)), want);
    }

    #[test]
    fn switch_on_block_mask_is_the_decoded_status_tables() {
        // BU 0620 §6.1.2.3 p. 111 "Starting disabled": bit 6 = 1, bits 5 and 4 X, bits 3–0 = 0.
        // The mask is 004Fh, not 007Fh: bits 4/5 report commands (§6.1.2.2), not the state.
        assert_eq!(SwitchOnBlock.status_bits(), (0x004F, 0x0040));
        for w in [0x0040, 0x0050, 0x0060, 0x0070, 0x0B60] {
            assert_eq!(
                State::from_status(StatusWord(w)),
                Some(SwitchOnBlock),
                "{w:04X}h"
            );
        }
    }

    #[test]
    fn names_and_letters() {
        assert_eq!(State::from_name("Standby"), Some(ReadyForSwitchOn));
        assert_eq!(State::from_name("Einschaltsperre"), Some(SwitchOnBlock));
        assert_eq!(State::from_name("E"), Some(OperationEnabled));
        assert_eq!(State::from_name("Z"), None);
        assert_eq!(Fault.letter(), 'H');
        assert_eq!(Fault.to_string(), "Fault (H)");
        for s in State::ALL {
            assert_eq!(State::from_status(StatusWord(s.status_bits().1)), Some(s));
        }
    }
}
