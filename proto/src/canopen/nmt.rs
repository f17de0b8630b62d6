//! Network management (CiA 301 "Network management": NMT module control services, the NMT
//! state machine, and the error control protocols heartbeat, boot-up and node guarding).
//!
//! | message | COB-ID | bytes |
//! |---|---|---|
//! | NMT module control | 000h | command specifier; node id (0: all nodes) |
//! | boot-up | 700h + node | 00h |
//! | heartbeat | 700h + node | state (bit 7 reserved, 0) |
//! | node guarding request | 700h + node | remote frame, DLC 1 |
//! | node guarding response | 700h + node | toggle (bit 7), state (bits 6–0) |

use std::fmt;

use super::cob_id::MAX_NODE;
use crate::wire::{Error, Reader};

/// An NMT command specifier (CiA 301 NMT module control services; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct NmtCommand(pub u8);

impl NmtCommand {
    /// Start remote node: → Operational.
    pub const START: NmtCommand = NmtCommand(0x01);
    /// Stop remote node: → Stopped.
    pub const STOP: NmtCommand = NmtCommand(0x02);
    /// Enter pre-operational: → Pre-operational.
    pub const ENTER_PRE_OPERATIONAL: NmtCommand = NmtCommand(0x80);
    /// Reset node: → Initialisation (reset application, then reset communication).
    pub const RESET_NODE: NmtCommand = NmtCommand(0x81);
    /// Reset communication: → Initialisation (reset communication).
    pub const RESET_COMMUNICATION: NmtCommand = NmtCommand(0x82);

    /// The service's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        NMT_TRANSITIONS
            .iter()
            .find(|t| t.command == self)
            .map(|t| t.name)
    }
}

impl fmt::Debug for NmtCommand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "NmtCommand({:02X}h", self.0)?;
        match self.name() {
            Some(n) => write!(f, " {n})"),
            None => write!(f, ")"),
        }
    }
}

/// The NMT states of a device (CiA 301 "NMT state machine"; Initialisation covers its
/// sub-states initialising, reset application and reset communication, which end in
/// Pre-operational with the boot-up message).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum NmtState {
    /// Initialisation.
    Initialisation,
    /// Pre-operational: SDO, SYNC, EMCY, NMT; no PDO.
    PreOperational,
    /// Operational: all objects.
    Operational,
    /// Stopped: NMT and error control only.
    Stopped,
}

/// One row of the NMT state machine: a command, the state it leads to from Pre-operational,
/// Operational or Stopped (a command naming the present state leaves it there).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NmtTransition {
    /// The command.
    pub command: NmtCommand,
    /// CiA 301's name of the service.
    pub name: &'static str,
    /// The state it leads to.
    pub to: NmtState,
}

/// The NMT state machine as data.
pub const NMT_TRANSITIONS: &[NmtTransition] = &[
    NmtTransition {
        command: NmtCommand::START,
        name: "Start remote node",
        to: NmtState::Operational,
    },
    NmtTransition {
        command: NmtCommand::STOP,
        name: "Stop remote node",
        to: NmtState::Stopped,
    },
    NmtTransition {
        command: NmtCommand::ENTER_PRE_OPERATIONAL,
        name: "Enter pre-operational",
        to: NmtState::PreOperational,
    },
    NmtTransition {
        command: NmtCommand::RESET_NODE,
        name: "Reset node",
        to: NmtState::Initialisation,
    },
    NmtTransition {
        command: NmtCommand::RESET_COMMUNICATION,
        name: "Reset communication",
        to: NmtState::Initialisation,
    },
];

impl NmtState {
    /// The state `command` leads to; `None` for an unknown command, or in Initialisation,
    /// where a device does not take NMT commands.
    pub fn on_command(self, command: NmtCommand) -> Option<NmtState> {
        if self == NmtState::Initialisation {
            return None;
        }
        NMT_TRANSITIONS
            .iter()
            .find(|t| t.command == command)
            .map(|t| t.to)
    }

    /// The state code this state sends in heartbeat and node guarding (Initialisation: the
    /// boot-up code, sent once on leaving it).
    pub fn code(self) -> StateCode {
        match self {
            NmtState::Initialisation => StateCode::BOOT_UP,
            NmtState::PreOperational => StateCode::PRE_OPERATIONAL,
            NmtState::Operational => StateCode::OPERATIONAL,
            NmtState::Stopped => StateCode::STOPPED,
        }
    }
}

/// An NMT module control frame on COB-ID 000h: 2 bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct NmtFrame {
    /// The command specifier.
    pub command: NmtCommand,
    /// The node addressed, 0 for all.
    pub node: u8,
}

impl NmtFrame {
    /// Parses the 2 data bytes: an unknown command specifier is [`Error::Unknown`], a node id
    /// above 127 [`Error::Invalid`].
    pub fn parse(bytes: &[u8]) -> Result<NmtFrame, Error> {
        let mut r = Reader::new(bytes);
        let command = NmtCommand(r.u8("NMT command specifier")?);
        let node = r.u8("NMT node id")?;
        r.finish("NMT frame")?;
        if command.name().is_none() {
            return Err(Error::Unknown {
                field: "NMT command specifier",
                value: u32::from(command.0),
            });
        }
        if node > MAX_NODE {
            return Err(Error::Invalid {
                field: "NMT node id",
                value: u32::from(node),
                why: "a node id is 1 to 127, or 0 for all nodes",
            });
        }
        Ok(NmtFrame { command, node })
    }

    /// The 2 data bytes.
    pub fn emit(&self) -> [u8; 2] {
        [self.command.0, self.node]
    }
}

/// The state code of heartbeat, boot-up and node guarding messages (bits 6–0; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct StateCode(pub u8);

impl StateCode {
    /// Boot-up (the boot-up message).
    pub const BOOT_UP: StateCode = StateCode(0x00);
    /// Stopped.
    pub const STOPPED: StateCode = StateCode(0x04);
    /// Operational.
    pub const OPERATIONAL: StateCode = StateCode(0x05);
    /// Pre-operational.
    pub const PRE_OPERATIONAL: StateCode = StateCode(0x7F);

    /// The NMT state the code reports, if defined (boot-up: the device left Initialisation
    /// for Pre-operational).
    pub fn state(self) -> Option<NmtState> {
        match self {
            StateCode::BOOT_UP => Some(NmtState::Initialisation),
            StateCode::STOPPED => Some(NmtState::Stopped),
            StateCode::OPERATIONAL => Some(NmtState::Operational),
            StateCode::PRE_OPERATIONAL => Some(NmtState::PreOperational),
            _ => None,
        }
    }
}

impl fmt::Debug for StateCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.state() {
            Some(_) if *self == StateCode::BOOT_UP => write!(f, "StateCode(00h boot-up)"),
            Some(s) => write!(f, "StateCode({:02X}h {s:?})", self.0),
            None => write!(f, "StateCode({:02X}h)", self.0),
        }
    }
}

/// An NMT error control message on 700h + node: 1 byte, the state code in bits 6–0 and the
/// toggle bit 7 (node guarding responses alternate it, starting with 0; heartbeat and boot-up
/// send 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ErrorControl {
    /// The state.
    pub state: StateCode,
    /// Bit 7.
    pub toggle: bool,
}

impl ErrorControl {
    /// The boot-up message.
    pub const BOOT_UP: ErrorControl = ErrorControl {
        state: StateCode::BOOT_UP,
        toggle: false,
    };

    /// A heartbeat reporting `state`.
    pub fn heartbeat(state: NmtState) -> ErrorControl {
        ErrorControl {
            state: state.code(),
            toggle: false,
        }
    }

    /// Parses the 1 data byte; an undefined state code is [`Error::Unknown`].
    pub fn parse(bytes: &[u8]) -> Result<ErrorControl, Error> {
        let mut r = Reader::new(bytes);
        let b = r.u8("NMT error control state")?;
        r.finish("NMT error control")?;
        let state = StateCode(b & 0x7F);
        if state.state().is_none() {
            return Err(Error::Unknown {
                field: "NMT error control state",
                value: u32::from(state.0),
            });
        }
        Ok(ErrorControl {
            state,
            toggle: b & 0x80 != 0,
        })
    }

    /// The data byte.
    pub fn emit(&self) -> [u8; 1] {
        [self.state.0 & 0x7F | if self.toggle { 0x80 } else { 0 }]
    }

    /// Whether this is the boot-up message.
    pub fn is_boot_up(&self) -> bool {
        *self == ErrorControl::BOOT_UP
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use NmtState::*;

    #[test]
    fn nmt_frames() {
        // 01 05: start node 5; 81 00: reset all nodes.
        let start = NmtFrame::parse(&[0x01, 0x05]).unwrap();
        assert_eq!(
            start,
            NmtFrame {
                command: NmtCommand::START,
                node: 5
            }
        );
        assert_eq!(start.emit(), [0x01, 0x05]);
        assert_eq!(
            NmtFrame::parse(&[0x81, 0x00]).unwrap().command,
            NmtCommand::RESET_NODE
        );
        assert_eq!(
            format!("{:?}", NmtCommand::RESET_COMMUNICATION),
            "NmtCommand(82h Reset communication)"
        );
        assert_eq!(format!("{:?}", NmtCommand(3)), "NmtCommand(03h)");
        assert_eq!(
            NmtFrame::parse(&[0x03, 0x05]),
            Err(Error::Unknown {
                field: "NMT command specifier",
                value: 3
            })
        );
        assert!(matches!(
            NmtFrame::parse(&[0x01, 0x80]),
            Err(Error::Invalid {
                field: "NMT node id",
                ..
            })
        ));
        assert_eq!(
            NmtFrame::parse(&[0x01]),
            Err(Error::Truncated {
                what: "NMT node id",
                need: 1,
                got: 0
            })
        );
        assert_eq!(
            NmtFrame::parse(&[0x01, 0x05, 0x00]),
            Err(Error::Trailing {
                what: "NMT frame",
                extra: 1
            })
        );
    }

    #[test]
    fn state_machine_row_by_row() {
        // CiA 301 NMT state diagram: every command from every state.
        let rows = [
            (PreOperational, NmtCommand::START, Some(Operational)),
            (Stopped, NmtCommand::START, Some(Operational)),
            (Operational, NmtCommand::START, Some(Operational)),
            (PreOperational, NmtCommand::STOP, Some(Stopped)),
            (Operational, NmtCommand::STOP, Some(Stopped)),
            (
                Operational,
                NmtCommand::ENTER_PRE_OPERATIONAL,
                Some(PreOperational),
            ),
            (
                Stopped,
                NmtCommand::ENTER_PRE_OPERATIONAL,
                Some(PreOperational),
            ),
            (PreOperational, NmtCommand::RESET_NODE, Some(Initialisation)),
            (
                Operational,
                NmtCommand::RESET_COMMUNICATION,
                Some(Initialisation),
            ),
            (
                Stopped,
                NmtCommand::RESET_COMMUNICATION,
                Some(Initialisation),
            ),
            (Initialisation, NmtCommand::START, None),
            (Operational, NmtCommand(0x03), None),
        ];
        for (from, command, to) in rows {
            assert_eq!(from.on_command(command), to, "{from:?} {command:?}");
        }
    }

    #[test]
    fn error_control() {
        // 00: boot-up; 05: heartbeat operational; 85: node guarding, toggle 1, operational.
        let b = ErrorControl::parse(&[0x00]).unwrap();
        assert!(b.is_boot_up());
        assert_eq!(b.state.state(), Some(Initialisation));
        assert_eq!(
            ErrorControl::parse(&[0x05]).unwrap(),
            ErrorControl::heartbeat(Operational)
        );
        let g = ErrorControl::parse(&[0x85]).unwrap();
        assert_eq!((g.state, g.toggle), (StateCode::OPERATIONAL, true));
        assert_eq!(g.emit(), [0x85]);
        assert_eq!(ErrorControl::heartbeat(PreOperational).emit(), [0x7F]);
        assert_eq!(ErrorControl::heartbeat(Stopped).emit(), [0x04]);
        assert_eq!(
            format!("{:?}", StateCode(0x7F)),
            "StateCode(7Fh PreOperational)"
        );
        assert_eq!(format!("{:?}", StateCode(0)), "StateCode(00h boot-up)");
        assert_eq!(
            ErrorControl::parse(&[0x01]),
            Err(Error::Unknown {
                field: "NMT error control state",
                value: 1
            })
        );
        assert!(matches!(
            ErrorControl::parse(&[]),
            Err(Error::Truncated { .. })
        ));
        assert!(matches!(
            ErrorControl::parse(&[5, 0]),
            Err(Error::Trailing { .. })
        ));
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        fn nmt_frame() -> impl Strategy<Value = NmtFrame> {
            (
                proptest::sample::select(
                    NMT_TRANSITIONS
                        .iter()
                        .map(|t| t.command)
                        .collect::<Vec<_>>(),
                ),
                0..=MAX_NODE,
            )
                .prop_map(|(command, node)| NmtFrame { command, node })
        }

        fn error_control() -> impl Strategy<Value = ErrorControl> {
            (
                proptest::sample::select(vec![
                    StateCode::BOOT_UP,
                    StateCode::STOPPED,
                    StateCode::OPERATIONAL,
                    StateCode::PRE_OPERATIONAL,
                ]),
                any::<bool>(),
            )
                .prop_map(|(state, toggle)| ErrorControl { state, toggle })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn nmt_frame_round_trips(f in nmt_frame()) {
                prop_assert_eq!(NmtFrame::parse(&f.emit()), Ok(f));
            }

            #[test]
            fn error_control_round_trips(e in error_control()) {
                prop_assert_eq!(ErrorControl::parse(&e.emit()), Ok(e));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..4)) {
                let _ = NmtFrame::parse(&bytes);
                let _ = ErrorControl::parse(&bytes);
            }
        }
    }
}
