//! Network-management state machines of the bus interface: POWERLINK (BU 0620 §2.4.4, p. 33)
//! and EtherCAT (BU 0620 §2.2.5, p. 18), plus the POWERLINK node-id ranges (§2.4.3.1, p. 32).
//!
//! States are explicit enums named as the manual names them; transitions are data rows. A
//! tester must be able to ask for illegal transitions, so [`powerlink_next`] and
//! [`ethercat_next`] answer `Err(IllegalTransition)` rather than refusing at compile time.
//!
//! The EtherCAT figure of §2.2.5 is an image the text extraction lost; its transitions are the
//! standard EtherCAT state machine's (ETG.1000.6: Init ↔ Pre-Op ↔ Safe-Op ↔ Op, any state back
//! to Init or Pre-Op, Init ↔ Bootstrap).

use serde::Serialize;

/// A refused transition.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("no transition from {from} on {event}")]
pub struct IllegalTransition {
    /// State the machine was in.
    pub from: &'static str,
    /// What was asked.
    pub event: String,
}

/// POWERLINK Controlled Node states (§2.4.4 table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum PlState {
    /// No communication; watches for POWERLINK frames.
    Initialisation,
    /// Parameter communication possible; waits for SoC.
    PreOperational1,
    /// Configured by the Managing Node.
    PreOperational2,
    /// Limited process data; cyclic data not evaluated.
    ReadyToOperate,
    /// Normal operation.
    Operational,
    /// Parameters via UDP/IP only.
    BasicEthernet,
    /// Entered and left only by MN command.
    Stopped,
}

impl PlState {
    /// Every state.
    pub const ALL: [PlState; 7] = [
        PlState::Initialisation,
        PlState::PreOperational1,
        PlState::PreOperational2,
        PlState::ReadyToOperate,
        PlState::Operational,
        PlState::BasicEthernet,
        PlState::Stopped,
    ];

    /// The manual's name.
    pub fn name(self) -> &'static str {
        match self {
            PlState::Initialisation => "Initialisation",
            PlState::PreOperational1 => "Pre-Operational 1",
            PlState::PreOperational2 => "Pre-Operational 2",
            PlState::ReadyToOperate => "Ready To Operate",
            PlState::Operational => "Operational",
            PlState::BasicEthernet => "Basic Ethernet",
            PlState::Stopped => "Stopped",
        }
    }

    /// Parses the manual's name (case-insensitive).
    pub fn from_name(s: &str) -> Option<PlState> {
        PlState::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(s))
    }

    /// Whether parameters (SDO) can be exchanged in the state.
    pub fn parameters(self) -> bool {
        !matches!(self, PlState::Initialisation | PlState::Stopped)
    }

    /// Whether process data is exchanged and evaluated.
    pub fn process_data(self) -> bool {
        self == PlState::Operational
    }
}

/// One display value of P182 "NMT State" (BU 2200 §7.1.4, p. 57).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct NmtStateCode {
    /// The value P182 shows.
    pub code: u8,
    /// The name as the manual prints it (`PRE_OPERATIONAL_1`).
    pub name: &'static str,
    /// The state of the §2.4.4 state machine, where it is one of them.
    #[serde(skip)]
    pub state: Option<PlState>,
}

const fn nmt(code: u8, name: &'static str, state: Option<PlState>) -> NmtStateCode {
    NmtStateCode { code, name, state }
}

/// P182 "NMT State" of the POWERLINK modules: the communication state (start-up phase) as a
/// code (BU 2200 §7.1.4, p. 57, "Anzeigewerte"). The codes of the seven states of the state
/// machine plus the reset and transition states the machine passes through.
pub const P182_CODES: &[NmtStateCode] = &[
    nmt(0x00, "OFF", None),
    nmt(0x19, "INITIALISING", Some(PlState::Initialisation)),
    nmt(0x1C, "NOT_ACTIVE", None),
    nmt(0x1D, "PRE_OPERATIONAL_1", Some(PlState::PreOperational1)),
    nmt(0x1E, "BASIC_ETHERNET", Some(PlState::BasicEthernet)),
    nmt(0x29, "RESET_APPLICATION", None),
    nmt(0x39, "RESET_COMMUNICATION", None),
    nmt(0x4D, "STOPPED", Some(PlState::Stopped)),
    nmt(0x5D, "PRE_OPERATIONAL_2", Some(PlState::PreOperational2)),
    nmt(0x6D, "READY_TO_OPERATE", Some(PlState::ReadyToOperate)),
    nmt(0x79, "RESET_CONFIGURATION", None),
    nmt(0xFD, "OPERATIONAL", Some(PlState::Operational)),
];

/// The P182 entry of a displayed value, or `None` for a value the manual does not list.
pub fn p182(code: i64) -> Option<&'static NmtStateCode> {
    P182_CODES.iter().find(|c| i64::from(c.code) == code)
}

impl PlState {
    /// The value P182 shows in this state (BU 2200 §7.1.4).
    pub fn p182(self) -> u8 {
        P182_CODES
            .iter()
            .find(|c| c.state == Some(self))
            .map_or(0, |c| c.code)
    }
}

/// What drives the POWERLINK state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum PlEvent {
    /// A POWERLINK frame was seen.
    PowerlinkFrame,
    /// The initialisation timeout elapsed without one.
    Timeout,
    /// A Start-of-Cycle frame arrived.
    SoC,
    /// MN command after configuration: to "Ready to operate".
    EnableReadyToOperate,
    /// MN command: start the node.
    StartNode,
    /// MN command: stop the node.
    StopNode,
    /// MN command: back to Pre-Operational 2.
    EnterPreOperational2,
}

impl PlEvent {
    /// Every event.
    pub const ALL: [PlEvent; 7] = [
        PlEvent::PowerlinkFrame,
        PlEvent::Timeout,
        PlEvent::SoC,
        PlEvent::EnableReadyToOperate,
        PlEvent::StartNode,
        PlEvent::StopNode,
        PlEvent::EnterPreOperational2,
    ];

    /// Name as suites write it.
    pub fn name(self) -> &'static str {
        match self {
            PlEvent::PowerlinkFrame => "powerlink-frame",
            PlEvent::Timeout => "timeout",
            PlEvent::SoC => "soc",
            PlEvent::EnableReadyToOperate => "enable-ready-to-operate",
            PlEvent::StartNode => "start-node",
            PlEvent::StopNode => "stop-node",
            PlEvent::EnterPreOperational2 => "enter-pre-operational-2",
        }
    }

    /// Parses a suite's name.
    pub fn from_name(s: &str) -> Option<PlEvent> {
        PlEvent::ALL.into_iter().find(|e| e.name() == s)
    }
}

/// The POWERLINK transitions §2.4.4 describes: (from, event, to).
pub const POWERLINK_TRANSITIONS: &[(PlState, PlEvent, PlState)] = &[
    (
        PlState::Initialisation,
        PlEvent::Timeout,
        PlState::BasicEthernet,
    ),
    (
        PlState::Initialisation,
        PlEvent::PowerlinkFrame,
        PlState::PreOperational1,
    ),
    (
        PlState::BasicEthernet,
        PlEvent::PowerlinkFrame,
        PlState::PreOperational1,
    ),
    (
        PlState::PreOperational1,
        PlEvent::SoC,
        PlState::PreOperational2,
    ),
    (
        PlState::PreOperational2,
        PlEvent::EnableReadyToOperate,
        PlState::ReadyToOperate,
    ),
    (
        PlState::ReadyToOperate,
        PlEvent::StartNode,
        PlState::Operational,
    ),
    (
        PlState::PreOperational2,
        PlEvent::StopNode,
        PlState::Stopped,
    ),
    (PlState::ReadyToOperate, PlEvent::StopNode, PlState::Stopped),
    (PlState::Operational, PlEvent::StopNode, PlState::Stopped),
    (
        PlState::Stopped,
        PlEvent::EnterPreOperational2,
        PlState::PreOperational2,
    ),
    (
        PlState::Operational,
        PlEvent::EnterPreOperational2,
        PlState::PreOperational2,
    ),
    (
        PlState::ReadyToOperate,
        PlEvent::EnterPreOperational2,
        PlState::PreOperational2,
    ),
];

/// The next POWERLINK state, or the refusal.
pub fn powerlink_next(state: PlState, event: PlEvent) -> Result<PlState, IllegalTransition> {
    POWERLINK_TRANSITIONS
        .iter()
        .find(|(f, e, _)| *f == state && *e == event)
        .map(|(_, _, t)| *t)
        .ok_or(IllegalTransition {
            from: state.name(),
            event: event.name().to_string(),
        })
}

/// EtherCAT states (§2.2.5; §5.5.2.1 names them for the RUN LED).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
pub enum EcState {
    /// Init.
    Init,
    /// Pre-Operational.
    PreOperational,
    /// Safe Operational.
    SafeOperational,
    /// Operational.
    Operational,
    /// Bootstrap (firmware update).
    Bootstrap,
}

impl EcState {
    /// Every state.
    pub const ALL: [EcState; 5] = [
        EcState::Init,
        EcState::PreOperational,
        EcState::SafeOperational,
        EcState::Operational,
        EcState::Bootstrap,
    ];

    /// The manual's name.
    pub fn name(self) -> &'static str {
        match self {
            EcState::Init => "Init",
            EcState::PreOperational => "Pre-Operational",
            EcState::SafeOperational => "Safe Operational",
            EcState::Operational => "Operational",
            EcState::Bootstrap => "Bootstrap",
        }
    }

    /// Parses a name.
    pub fn from_name(s: &str) -> Option<EcState> {
        EcState::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(s))
    }
}

/// The EtherCAT transitions (requested state by the master): (from, to).
pub const ETHERCAT_TRANSITIONS: &[(EcState, EcState)] = &[
    (EcState::Init, EcState::PreOperational),
    (EcState::Init, EcState::Bootstrap),
    (EcState::Bootstrap, EcState::Init),
    (EcState::PreOperational, EcState::SafeOperational),
    (EcState::PreOperational, EcState::Init),
    (EcState::SafeOperational, EcState::Operational),
    (EcState::SafeOperational, EcState::PreOperational),
    (EcState::SafeOperational, EcState::Init),
    (EcState::Operational, EcState::SafeOperational),
    (EcState::Operational, EcState::PreOperational),
    (EcState::Operational, EcState::Init),
];

/// Whether the master may request `to` from `from`.
pub fn ethercat_next(from: EcState, to: EcState) -> Result<EcState, IllegalTransition> {
    if ETHERCAT_TRANSITIONS.contains(&(from, to)) {
        Ok(to)
    } else {
        Err(IllegalTransition {
            from: from.name(),
            event: format!("request {}", to.name()),
        })
    }
}

/// What a POWERLINK node id is (§2.4.3.1 table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct NodeIdKind {
    /// The POWERLINK designation (C_ADR_…), or `None` for controlled nodes.
    pub designation: Option<&'static str>,
    /// The meaning column.
    pub meaning: &'static str,
    /// Whether the bus interface (a CN) may use it.
    pub valid_for_cn: bool,
}

/// Classifies a node id (the fourth byte of the IP address).
pub fn node_id(id: u8) -> NodeIdKind {
    let k = |designation, meaning, valid_for_cn| NodeIdKind {
        designation,
        meaning,
        valid_for_cn,
    };
    match id {
        0 => k(Some("C_ADR_INVALID"), "Invalid POWERLINK address", false),
        1..=239 => k(None, "POWERLINK address for field bus slave (CN)", true),
        240 => k(
            Some("C_ADR_MN_DEF_NODE_ID"),
            "POWERLINK address for the bus master (MN)",
            false,
        ),
        241..=250 => k(None, "Reserved (EPSG profile DS-302-A)", false),
        251 => k(
            Some("C_ADR_SELF_ADR_NODE_ID"),
            "POWERLINK address for self-addressing of a bus participant",
            false,
        ),
        252 => k(
            Some("C_ADR_DUMMY_NODE_ID"),
            "POWERLINK address as place holder",
            false,
        ),
        253 => k(
            Some("C_ADR_DIAG_DEF_NODE_ID"),
            "POWERLINK standard address for diagnostic devices",
            false,
        ),
        254 => k(
            Some("C_ADR_RT1_DEF_NODE_ID"),
            "POWERLINK standard address for Type 1 routers",
            false,
        ),
        255 => k(
            Some("C_ADR_BROADCAST"),
            "POWERLINK broadcast address",
            false,
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn powerlink_start_up() {
        let mut s = PlState::Initialisation;
        for e in [
            PlEvent::PowerlinkFrame,
            PlEvent::SoC,
            PlEvent::EnableReadyToOperate,
            PlEvent::StartNode,
        ] {
            s = powerlink_next(s, e).unwrap();
        }
        assert_eq!(s, PlState::Operational);
        assert!(s.process_data());
        assert_eq!(
            powerlink_next(PlState::Initialisation, PlEvent::Timeout),
            Ok(PlState::BasicEthernet)
        );
    }

    #[test]
    fn illegal_transitions_are_errors_not_panics() {
        let e = powerlink_next(PlState::PreOperational1, PlEvent::StartNode).unwrap_err();
        assert_eq!(
            e.to_string(),
            "no transition from Pre-Operational 1 on start-node"
        );
        assert!(ethercat_next(EcState::Init, EcState::Operational).is_err());
        assert_eq!(
            ethercat_next(EcState::SafeOperational, EcState::Operational),
            Ok(EcState::Operational)
        );
    }

    #[rstest::rstest]
    #[case(PlState::Initialisation, 0x19)]
    #[case(PlState::PreOperational1, 0x1D)]
    #[case(PlState::PreOperational2, 0x5D)]
    #[case(PlState::ReadyToOperate, 0x6D)]
    #[case(PlState::Operational, 0xFD)]
    #[case(PlState::BasicEthernet, 0x1E)]
    #[case(PlState::Stopped, 0x4D)]
    fn p182_codes_of_the_states(#[case] state: PlState, #[case] code: u8) {
        assert_eq!(state.p182(), code);
        assert_eq!(p182(i64::from(code)).and_then(|c| c.state), Some(state));
    }

    #[test]
    fn p182_other_codes() {
        assert_eq!(P182_CODES.len(), 12);
        assert_eq!(p182(0x79).map(|c| c.name), Some("RESET_CONFIGURATION"));
        assert_eq!(p182(0).map(|c| c.name), Some("OFF"));
        assert_eq!(p182(0x20), None);
        assert_eq!(p182(-1), None);
        // Every state of the §2.4.4 machine has its own code.
        let mut codes: Vec<u8> = PlState::ALL.iter().map(|s| s.p182()).collect();
        codes.sort_unstable();
        codes.dedup();
        assert!(codes.iter().all(|c| *c != 0) && codes.len() == 7);
    }

    #[test]
    fn node_ids() {
        assert!(!node_id(0).valid_for_cn);
        assert!(node_id(1).valid_for_cn && node_id(239).valid_for_cn);
        assert_eq!(node_id(240).designation, Some("C_ADR_MN_DEF_NODE_ID"));
        assert!(!node_id(245).valid_for_cn);
        assert_eq!(node_id(255).designation, Some("C_ADR_BROADCAST"));
    }
}
