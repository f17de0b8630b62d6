//! The inverter status machine: states A–H, transitions 1–15.
//!
//! BU 0620 §6.1.2.3 (p. 108–111). The transitions are data ([`TRANSITIONS`]); [`next`] applies
//! them in the priority order of §6.1.2.1 (disable voltage 1, emergency stop 2, shut down 3,
//! enable operation 4, switch on 5, disable operation 6, acknowledge 7). A control word without
//! bit 10 ("control data valid") is not evaluated.
//!
//! The manual names the states differently in its state table ("Not on standby", "Standby",
//! "Activated", "Error reaction active"), its transition table ("Not ready for switch-on",
//! "Ready for switch-on", "Switched on") and its decoded-status table ("Ready to start",
//! "Error active"). [`State::name`] uses the transition table's names; [`State::aliases`] lists
//! the others.

use std::fmt;

use super::control::ControlWord;
use super::status::StatusWord;

/// A state of the inverter.
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

impl State {
    /// All states, A..H.
    pub const ALL: [State; 8] = [
        State::NotReadyForSwitchOn,
        State::SwitchOnBlock,
        State::ReadyForSwitchOn,
        State::SwitchedOn,
        State::OperationEnabled,
        State::EmergencyStopActive,
        State::ErrorReactionActive,
        State::Fault,
    ];

    /// The letter of the state table.
    pub fn letter(self) -> char {
        (b'A' + self as u8) as char
    }

    /// The name used in the transition table.
    pub fn name(self) -> &'static str {
        match self {
            State::NotReadyForSwitchOn => "Not ready for switch-on",
            State::SwitchOnBlock => "Switch-on block",
            State::ReadyForSwitchOn => "Ready for switch-on",
            State::SwitchedOn => "Switched on",
            State::OperationEnabled => "Operation enabled",
            State::EmergencyStopActive => "Emergency stop active",
            State::ErrorReactionActive => "Error reaction active",
            State::Fault => "Fault",
        }
    }

    /// Other names the manual gives the same state (state table, decoded-status table).
    pub fn aliases(self) -> &'static [&'static str] {
        match self {
            State::NotReadyForSwitchOn => &["Not on standby"],
            State::SwitchOnBlock => &["Starting disabled"],
            State::ReadyForSwitchOn => &["Standby", "Ready to start"],
            State::SwitchedOn => &["Activated"],
            State::OperationEnabled => &[],
            State::EmergencyStopActive => &[],
            State::ErrorReactionActive => &["Error active"],
            State::Fault => &[],
        }
    }

    /// Parses a letter or any of the names.
    pub fn from_name(s: &str) -> Option<State> {
        State::ALL.into_iter().find(|st| {
            s.eq_ignore_ascii_case(st.name())
                || st.aliases().iter().any(|a| s.eq_ignore_ascii_case(a))
                || (s.len() == 1 && s.starts_with(st.letter()))
        })
    }

    /// Status bits 0–6 as the decoded-status table gives them: (mask, value) — X bits are out
    /// of the mask (§6.1.2.3 "Decoded frequency inverter statuses").
    pub fn status_pattern(self) -> (u16, u16) {
        match self {
            State::NotReadyForSwitchOn => (0b100_1111, 0b000_0000),
            State::SwitchOnBlock => (0b100_1111, 0b100_0000),
            State::ReadyForSwitchOn => (0b111_1111, 0b011_0001),
            State::SwitchedOn => (0b111_1111, 0b011_0011),
            State::OperationEnabled => (0b111_1111, 0b011_0111),
            State::Fault => (0b100_1111, 0b000_1000),
            State::ErrorReactionActive => (0b100_1111, 0b000_1111),
            State::EmergencyStopActive => (0b111_1111, 0b001_0111),
        }
    }

    /// The state a status word shows, by the decoded-status table.
    pub fn from_status(s: StatusWord) -> Option<State> {
        State::ALL.into_iter().find(|st| {
            let (mask, value) = st.status_pattern();
            s.0 & mask == value
        })
    }
}

impl fmt::Display for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.name(), self.letter())
    }
}

/// What triggers a transition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trigger {
    /// Control bits 0–7 must match `(word & mask) == value`.
    Control {
        /// The command's name.
        command: &'static str,
        /// Bits that matter.
        mask: u16,
        /// Their values.
        value: u16,
        /// Priority of §6.1.2.1 (1 = highest).
        priority: u8,
    },
    /// Bit 7 rising edge: acknowledge the error.
    AcknowledgeEdge,
    /// Automatic (charging relay, fault, end of the fault reaction).
    Automatic(&'static str),
}

/// One row of the transition table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transition {
    /// Number 1..15.
    pub number: u8,
    /// Source states (13 applies from any state).
    pub from: &'static [State],
    /// Target.
    pub to: State,
    /// Trigger.
    pub trigger: Trigger,
}

const fn ctl(command: &'static str, mask: u16, value: u16, priority: u8) -> Trigger {
    Trigger::Control {
        command,
        mask,
        value,
        priority,
    }
}

use State::*;

const DISABLE_VOLTAGE: Trigger = ctl("Disable voltage", 0b0000_0010, 0b0000_0000, 1);
const QUICK_STOP: Trigger = ctl("Quick stop", 0b0000_0110, 0b0000_0010, 2);
const SHUT_DOWN: Trigger = ctl("Shut down", 0b0000_0111, 0b0000_0110, 3);
const ENABLE_OPERATION: Trigger = ctl("Enable operation", 0b0111_1111, 0b0111_1111, 4);
const SWITCH_ON: Trigger = ctl("Switch on", 0b0000_0111, 0b0000_0111, 5);
const DISABLE_OPERATION: Trigger = ctl("Disable operation", 0b0000_1111, 0b0000_0111, 6);

/// The transition table of §6.1.2.3, rows 7 and 10 split by command.
pub const TRANSITIONS: &[Transition] = &[
    Transition {
        number: 1,
        from: &[NotReadyForSwitchOn],
        to: SwitchOnBlock,
        trigger: Trigger::Automatic("charging relay engaged"),
    },
    Transition {
        number: 2,
        from: &[SwitchOnBlock],
        to: ReadyForSwitchOn,
        trigger: SHUT_DOWN,
    },
    Transition {
        number: 3,
        from: &[ReadyForSwitchOn],
        to: SwitchedOn,
        trigger: SWITCH_ON,
    },
    Transition {
        number: 4,
        from: &[SwitchedOn],
        to: OperationEnabled,
        trigger: ENABLE_OPERATION,
    },
    Transition {
        number: 5,
        from: &[OperationEnabled],
        to: SwitchedOn,
        trigger: DISABLE_OPERATION,
    },
    Transition {
        number: 6,
        from: &[SwitchedOn],
        to: ReadyForSwitchOn,
        trigger: SHUT_DOWN,
    },
    Transition {
        number: 7,
        from: &[ReadyForSwitchOn],
        to: SwitchOnBlock,
        trigger: DISABLE_VOLTAGE,
    },
    Transition {
        number: 7,
        from: &[ReadyForSwitchOn],
        to: SwitchOnBlock,
        trigger: QUICK_STOP,
    },
    Transition {
        number: 8,
        from: &[OperationEnabled],
        to: ReadyForSwitchOn,
        trigger: SHUT_DOWN,
    },
    Transition {
        number: 9,
        from: &[OperationEnabled],
        to: SwitchOnBlock,
        trigger: DISABLE_VOLTAGE,
    },
    Transition {
        number: 10,
        from: &[SwitchedOn],
        to: SwitchOnBlock,
        trigger: DISABLE_VOLTAGE,
    },
    Transition {
        number: 10,
        from: &[SwitchedOn],
        to: SwitchOnBlock,
        trigger: QUICK_STOP,
    },
    Transition {
        number: 11,
        from: &[OperationEnabled],
        to: EmergencyStopActive,
        trigger: QUICK_STOP,
    },
    Transition {
        number: 12,
        from: &[EmergencyStopActive],
        to: SwitchOnBlock,
        trigger: DISABLE_VOLTAGE,
    },
    Transition {
        number: 13,
        from: &[
            NotReadyForSwitchOn,
            SwitchOnBlock,
            ReadyForSwitchOn,
            SwitchedOn,
            OperationEnabled,
            EmergencyStopActive,
        ],
        to: ErrorReactionActive,
        trigger: Trigger::Automatic("a fault occurs"),
    },
    Transition {
        number: 14,
        from: &[ErrorReactionActive],
        to: Fault,
        trigger: Trigger::Automatic("fault reaction completed"),
    },
    Transition {
        number: 15,
        from: &[Fault],
        to: SwitchOnBlock,
        trigger: Trigger::AcknowledgeEdge,
    },
];

/// The transition a control word triggers from `state`, by priority, or `None`.
///
/// `previous` is the control word of the previous telegram (for the acknowledge edge). A word
/// without bit 10 is not evaluated (§6.1.2.3 "Control bit 10").
pub fn next(
    state: State,
    control: ControlWord,
    previous: ControlWord,
) -> Option<&'static Transition> {
    if !control.valid() {
        return None;
    }
    let mut best: Option<(&'static Transition, u8)> = None;
    for t in TRANSITIONS.iter().filter(|t| t.from.contains(&state)) {
        let priority = match t.trigger {
            Trigger::Control {
                mask,
                value,
                priority,
                ..
            } if control.0 & mask == value => priority,
            Trigger::AcknowledgeEdge if control.bit(7) && !previous.bit(7) => 7,
            _ => continue,
        };
        if best.is_none_or(|(_, p)| priority < p) {
            best = Some((t, priority));
        }
    }
    best.map(|(t, _)| t)
}

/// The automatic transition out of `state` (1, 13 or 14), for the drive model.
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
    // §6.1.3: 047Eh from switch-on block → ready for switch-on (2).
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
    #[case(OperationEnabled, 0x047B, Some((11, EmergencyStopActive)))]
    #[case(EmergencyStopActive, 0x0479, Some((12, SwitchOnBlock)))]
    // Control bit 10 = 0: not evaluated.
    #[case(SwitchOnBlock, 0x007E, None)]
    // Priority: disable voltage (1) wins over quick stop (2) and shut down (3).
    #[case(OperationEnabled, 0x0478, Some((9, SwitchOnBlock)))]
    fn transitions(#[case] from: State, #[case] word: u16, #[case] want: Option<(u8, State)>) {
        let got = next(from, cw(word), cw(0)).map(|t| (t.number, t.to));
        assert_eq!(got, want);
    }

    #[test]
    fn acknowledge_needs_a_rising_edge() {
        assert_eq!(
            next(Fault, cw(0x04FE), cw(0x047E)).map(|t| t.number),
            Some(15)
        );
        assert_eq!(next(Fault, cw(0x04FE), cw(0x04FE)), None);
    }

    #[rstest]
    #[case(0x0B31, Some(ReadyForSwitchOn))]
    #[case(0x0B37, Some(OperationEnabled))]
    #[case(0x0040, Some(SwitchOnBlock))]
    #[case(0x0000, Some(NotReadyForSwitchOn))]
    #[case(0x0033, Some(SwitchedOn))]
    #[case(0x0008, Some(Fault))]
    #[case(0x000F, Some(ErrorReactionActive))]
    #[case(0x0017, Some(EmergencyStopActive))]
    #[case(0x0002, None)]
    fn decoded_status_table(#[case] word: u16, #[case] want: Option<State>) {
        assert_eq!(State::from_status(StatusWord(word)), want);
    }

    #[test]
    fn names_and_letters() {
        assert_eq!(State::from_name("Standby"), Some(ReadyForSwitchOn));
        assert_eq!(State::from_name("E"), Some(OperationEnabled));
        assert_eq!(Fault.letter(), 'H');
    }
}
