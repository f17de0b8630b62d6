//! LED patterns per state: the SK 550P's "DEV" and "BUS" LEDs and the EtherCAT RUN/ERR LEDs.
//!
//! BU 0620 §5.5.1 (p. 100) and §5.5.2 (p. 101–104), BU 0590 §2.2.4 (SK TU3-PNT) and BU 2200
//! §6.2 (the POWERLINK modules' "BE" LED per NMT state). BU 2100 and BU 2200 print their LED
//! tables only as figures of the data sheets, which the text editions do not carry. The tables
//! are data; [`dev`] and [`bus`] derive the pattern from the inverter's state, as the simulator
//! shows it.

use serde::Serialize;

use super::mutant::{self, Table};
use super::nmt::PlState;
use super::state_machine::State;

/// What an LED shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "pattern")]
pub enum Pattern {
    /// Dark.
    Off,
    /// Steady green.
    Green,
    /// Steady red.
    Red,
    /// Green flashing at `tenths_hz` / 10 Hz.
    FlashingGreen {
        /// Frequency in 0.1 Hz.
        tenths_hz: u16,
    },
    /// Red flashing at `tenths_hz` / 10 Hz.
    FlashingRed {
        /// Frequency in 0.1 Hz.
        tenths_hz: u16,
    },
    /// Red flashes giving an error number ("Error 3: flashes three times and then pauses").
    ErrorCode {
        /// The number flashed.
        flashes: u16,
    },
    /// Single green flash.
    SingleFlashGreen,
    /// Single red flash.
    SingleFlashRed,
    /// Double red flash.
    DoubleFlashRed,
    /// Green `count` flashes, then a pause (POWERLINK BS, §5.5.2.3).
    FlashesGreen {
        /// Flashes per group.
        count: u8,
    },
    /// Green and red alternately (power up, self test).
    FlashingGreenRed,
    /// Green and red alternately at `tenths_hz` / 10 Hz (the "DEV" LED's warning, §5.5.1.1).
    AlternatingGreenRed {
        /// Frequency in 0.1 Hz.
        tenths_hz: u16,
    },
    /// Green and red flashing together (the "DEV" LED while update data are communicated).
    SimultaneousGreenRed,
}

/// One row of an LED table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Row {
    /// The pattern.
    #[serde(flatten)]
    pub pattern: Pattern,
    /// What it means, as the manual says.
    pub meaning: &'static str,
}

const fn row(pattern: Pattern, meaning: &'static str) -> Row {
    Row { pattern, meaning }
}

/// "DEV" LED (§5.5.1.1): the rows the simulator shows ([`dev`]), then the warning and update
/// rows (the simulator has no warnings and no update mode). "Flashing red (2 Hz/1 Hz)", the
/// error number, is [`Pattern::ErrorCode`], made by [`dev`].
pub static DEV: Table<Row> = Table::new(
    "led-dev",
    "BU 0620 §5.5.1.1 DEV LED",
    &[
        row(
            Pattern::Off,
            "FI not ready for operation, no mains or control voltage",
        ),
        row(Pattern::Green, "FI is enabled"),
        row(
            Pattern::FlashingGreen { tenths_hz: 40 },
            "FI is in switch-on block",
        ),
        row(
            Pattern::FlashingGreen { tenths_hz: 5 },
            "FI is in standby but not enabled",
        ),
        row(Pattern::AlternatingGreenRed { tenths_hz: 40 }, "Warning"),
        row(Pattern::FlashingGreenRed, "FI in Update mode"),
        row(
            Pattern::SimultaneousGreenRed,
            "Update data are communicated",
        ),
    ],
);

/// "BUS" LED (§5.5.1.2).
pub static BUS: Table<Row> = Table::new(
    "led-bus",
    "BU 0620 §5.5.1.2 BUS LED",
    &[
        row(Pattern::Off, "No process data communication"),
        row(Pattern::Green, "Process data communication active"),
        row(Pattern::FlashingGreen { tenths_hz: 40 }, "Bus warning"),
        row(
            Pattern::FlashingRed { tenths_hz: 40 },
            "Monitoring error P120 or P513 (E10.0/E10.9)",
        ),
        row(
            Pattern::FlashingRed { tenths_hz: 10 },
            "Field bus interface telegram timeout (E10.2/E10.3)",
        ),
        row(Pattern::Red, "System bus in state \"Bus off\""),
    ],
);

/// EtherCAT LED A "RUN" per EtherCAT state (§5.5.2.1). The manual gives no flashing rate; 2.5 Hz
/// is the EtherCAT indicator rate (ETG.1300) and is an assumption here.
pub static ETHERCAT_RUN: Table<Row> = Table::new(
    "led-ethercat-run",
    "BU 0620 §5.5.2.1 EtherCAT RUN LED",
    &[
        row(Pattern::Off, "Init"),
        row(Pattern::FlashingGreen { tenths_hz: 25 }, "Pre-Operational"),
        row(Pattern::SingleFlashGreen, "Safe Operational"),
        row(Pattern::Green, "Operational"),
    ],
);

/// EtherCAT LED B "ERR" (§5.5.2.1).
pub static ETHERCAT_ERR: Table<Row> = Table::new(
    "led-ethercat-err",
    "BU 0620 §5.5.2.1 EtherCAT ERR LED",
    &[
        row(Pattern::Off, "No Error"),
        row(
            Pattern::FlashingRed { tenths_hz: 25 },
            "Invalid Configuration",
        ),
        row(Pattern::SingleFlashRed, "Unsolicited State Change"),
        row(Pattern::DoubleFlashRed, "Application Watchdog Timeout"),
    ],
);

/// EtherNet/IP LED A "MS" (module state, §5.5.2.2). The manual gives no flashing rate; 1 Hz is
/// the CIP indicator rate (Vol. 1 §9-4) and is an assumption here, as for "NS".
pub static ETHERNETIP_MS: Table<Row> = Table::new(
    "led-ethernetip-ms",
    "BU 0620 §5.5.2.2 EtherNet/IP MS LED",
    &[
        row(Pattern::Off, "No operating voltage"),
        row(
            Pattern::FlashingGreen { tenths_hz: 10 },
            "Bus interface not configured in FI",
        ),
        row(Pattern::Green, "Bus interface in FI working correctly"),
        row(
            Pattern::FlashingRed { tenths_hz: 10 },
            "Insignificant error Incorrect configuration",
        ),
        row(Pattern::Red, "Error cannot be corrected"),
        row(Pattern::FlashingGreenRed, "Power up, self test"),
    ],
);

/// EtherNet/IP LED B "NS" (network state, §5.5.2.2).
pub static ETHERNETIP_NS: Table<Row> = Table::new(
    "led-ethernetip-ns",
    "BU 0620 §5.5.2.2 EtherNet/IP NS LED",
    &[
        row(Pattern::Off, "No operating voltage"),
        row(
            Pattern::FlashingGreen { tenths_hz: 10 },
            "IP address configured but no CIP connection available",
        ),
        row(Pattern::Green, "CIP connection(s) available"),
        row(
            Pattern::FlashingRed { tenths_hz: 10 },
            "Time-out, an \"exclusive owner connection\" has a time-out error",
        ),
        row(
            Pattern::Red,
            "Dual IP. The IP address is already being used",
        ),
        row(Pattern::FlashingGreenRed, "Power up, self test"),
    ],
);

/// POWERLINK LED A "BS" per NMT state (§5.5.2.3).
pub static POWERLINK_BS: Table<Row> = Table::new(
    "led-powerlink-bs",
    "BU 0620 §5.5.2.3 POWERLINK BS LED",
    &[
        row(Pattern::Off, "No communication"),
        row(Pattern::FlashesGreen { count: 1 }, "Pre-Operational 1"),
        row(Pattern::FlashesGreen { count: 2 }, "Pre-Operational 2"),
        row(Pattern::FlashesGreen { count: 3 }, "Ready To Operate"),
        row(Pattern::Green, "Operational"),
        row(Pattern::FlashingGreen { tenths_hz: 100 }, "Basic Ethernet"),
        row(Pattern::FlashingGreen { tenths_hz: 25 }, "Stopped"),
    ],
);

/// POWERLINK LED B "BE" (§5.5.2.3).
pub static POWERLINK_BE: Table<Row> = Table::new(
    "led-powerlink-be",
    "BU 0620 §5.5.2.3 POWERLINK BE LED",
    &[
        row(Pattern::Off, "No POWERLINK error"),
        row(Pattern::Red, "General POWERLINK error"),
    ],
);

/// What a lit red "BE" LED of a POWERLINK module (SK TU3/TU4/CU4-POL) means in an NMT state
/// (BU 2200 §6.2, p. 30): in "Pre-Operational 1", "Pre-Operational 2", "Ready To Operate" and
/// "Basic Ethernet" the Managing Node has failed; elsewhere the general meaning of
/// [`POWERLINK_BE`] applies.
pub fn powerlink_module_be_red(state: PlState) -> Row {
    match state {
        PlState::PreOperational1
        | PlState::PreOperational2
        | PlState::ReadyToOperate
        | PlState::BasicEthernet => row(Pattern::Red, "Managing Node has failed"),
        PlState::Initialisation | PlState::Operational | PlState::Stopped => POWERLINK_BE[1],
    }
}

/// PROFINET LED B "RUN" (Ethernet state). BU 0620 §5.5.2.4 prints "Lights up green: No Ethernet
/// connection", against PROFINET practice and BU 0590 table 4 (off: initialisation, flashing:
/// waiting for AR, on: AR established), which this table follows; the erratum is recorded in
/// suites/bu0620/leds.yaml. Neither manual gives the flashing rate (2 Hz assumed).
pub static PROFINET_RUN: Table<Row> = Table::new(
    "led-profinet-run",
    "BU 0590 §2.2.4 table 4 PROFINET RUN LED",
    &[
        row(Pattern::Off, "Device switched off or initialisation"),
        row(Pattern::FlashingGreen { tenths_hz: 20 }, "Waiting for AR"),
        row(Pattern::Green, "AR established"),
    ],
);

/// SK TU3-PNT red "ERR" LED (BU 0590 §2.2.4 table 5): off, double flash (2 × 0.25 s, pause
/// 1 s) on an IO-controller timeout (P151 or P513), on for an Ethernet error.
pub static TU3_PNT_ERR: Table<Row> = Table::new(
    "led-tu3-pnt-err",
    "BU 0590 §2.2.4 table 5 ERR LED",
    &[
    row(Pattern::Off, "No error PROFINET IO functioning normally"),
    row(
        Pattern::DoubleFlashRed,
        "Timeout (double flash, cycle 2 x 0.25 s, pause 1 s): the IO controller monitoring has detected an error (see parameter P151 or P513)",
    ),
    row(
        Pattern::Red,
        "Ethernet error, no mains: TU3-PNT not connected to any Ethernet participant",
    ),
    ],
);

/// SK TU3-PNT green "DS" LED (BU 0590 §2.2.4 table 7, the module's own state; cycle 0.5 s =
/// 2 Hz).
pub static TU3_PNT_DS: Table<Row> = Table::new(
    "led-tu3-pnt-ds",
    "BU 0590 §2.2.4 table 7 DS LED",
    &[
        row(
            Pattern::Off,
            "The technology unit does not have a power supply (DE off)",
        ),
        row(
            Pattern::FlashingGreen { tenths_hz: 20 },
            "The technology unit has a fatal system error (DE off)",
        ),
        row(
            Pattern::Green,
            "Technology unit OK (DE tells the FI's state)",
        ),
    ],
);

/// SK TU3-PNT red "DE" LED with DS on (BU 0590 §2.2.4 table 7; cycle 0.25 s, pause 1 s). The
/// table prints one flash both for "no FI detected" and as the first of the FI's "1…7" error
/// flashes.
pub static TU3_PNT_DE: Table<Row> = Table::new(
    "led-tu3-pnt-de",
    "BU 0590 §2.2.4 table 7 DE LED",
    &[
    row(Pattern::Off, "Technology unit OK and FI detected"),
    row(
        Pattern::SingleFlashRed,
        "Technology unit OK but no FI detected: the FI has no power supply or the technology unit is not correctly plugged in",
    ),
    row(
        Pattern::FlashingRed { tenths_hz: 40 },
        "Flashing 1...7x (cycle 0.25 s, pause 1 s): the FI is in an error condition",
    ),
    ],
);

/// PROFINET LED A "BF" (Ethernet error, §5.5.2.4).
pub static PROFINET_BF: Table<Row> = Table::new(
    "led-profinet-bf",
    "BU 0620 §5.5.2.4 PROFINET BF LED",
    &[row(Pattern::Off, "No error"), row(Pattern::Red, "Alarm")],
);

impl mutant::Row for Row {
    /// A flashing light steady (several manuals give no rate, so the rate is no datum to
    /// change), one flash more, or a steady light swapped for dark (dark for green).
    fn changes(&self) -> Vec<(&'static str, String, Row)> {
        let pattern = match self.pattern {
            Pattern::FlashingGreen { .. } | Pattern::SingleFlashGreen => Pattern::Green,
            Pattern::FlashingRed { .. }
            | Pattern::SingleFlashRed
            | Pattern::DoubleFlashRed
            | Pattern::ErrorCode { .. } => Pattern::Red,
            Pattern::FlashesGreen { count } => Pattern::FlashesGreen { count: count + 1 },
            Pattern::Off => Pattern::Green,
            _ => Pattern::Off,
        };
        vec![(
            "pattern",
            format!("\"{}\": {:?} → {pattern:?}", self.meaning, self.pattern),
            Row { pattern, ..*self },
        )]
    }
}

/// The "DEV" LED of an inverter in `state`; a present error is flashed as its group number.
pub fn dev(state: State, error_group: Option<u16>) -> Row {
    match (state, error_group) {
        (State::Fault | State::ErrorReactionActive, Some(n)) => row(
            Pattern::ErrorCode { flashes: n },
            "Output of the error number",
        ),
        (State::NotReadyForSwitchOn, _) => DEV[0],
        (State::OperationEnabled, _) => DEV[1],
        (State::SwitchOnBlock | State::EmergencyStopActive, _) => DEV[2],
        _ => DEV[3],
    }
}

/// A CAN controller on the system bus as the "BUS" LED tells it apart (ISO 11898-1 fault
/// confinement): active, past the error warning limit (a transmit or receive error counter at
/// 96 or more, error passive included: "Bus warning"), or bus off.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum BusState {
    /// Error active, below the warning limit.
    #[default]
    Active,
    /// At or past the warning limit, not bus off.
    Warning,
    /// Bus off: takes no part in the bus.
    Off,
}

/// What the "BUS" LED looks at (BU 0620 §5.5.1.2).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BusLed {
    /// Process data flowing.
    pub process_data: bool,
    /// A field bus telegram timeout (E10.2/E10.3).
    pub telegram_timeout: bool,
    /// A monitoring error of P120 or P513 (E10.0/E10.9).
    pub monitoring_error: bool,
    /// The inverter's controller on the system bus.
    pub bus: BusState,
}

/// The "BUS" LED. Where several rows apply the manual does not say which shows (not stated by
/// the manuals); the most severe does: the system bus off, then the monitoring of the system
/// bus (E10.0/E10.9), then the field bus's telegram timeout, then a bus warning, then process
/// data. The table's row "Flashing green (0.5 Hz): FI is in standby but not enabled" is the
/// DEV LED's, repeated (an erratum the suites record): no system-bus condition gives it.
pub fn bus(s: BusLed) -> Row {
    match s {
        BusLed {
            bus: BusState::Off, ..
        } => BUS[5],
        BusLed {
            monitoring_error: true,
            ..
        } => BUS[3],
        BusLed {
            telegram_timeout: true,
            ..
        } => BUS[4],
        BusLed {
            bus: BusState::Warning,
            ..
        } => BUS[2],
        BusLed {
            process_data: true, ..
        } => BUS[1],
        _ => BUS[0],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dev_led_follows_the_status_machine() {
        assert_eq!(dev(State::OperationEnabled, None).pattern, Pattern::Green);
        assert_eq!(
            dev(State::SwitchOnBlock, None).pattern,
            Pattern::FlashingGreen { tenths_hz: 40 }
        );
        assert_eq!(
            dev(State::ReadyForSwitchOn, None).pattern,
            Pattern::FlashingGreen { tenths_hz: 5 }
        );
        assert_eq!(
            dev(State::Fault, Some(10)).pattern,
            Pattern::ErrorCode { flashes: 10 }
        );
        assert_eq!(dev(State::NotReadyForSwitchOn, None).pattern, Pattern::Off);
    }

    #[rstest::rstest]
    #[case(PlState::PreOperational1, "Managing Node has failed")]
    #[case(PlState::PreOperational2, "Managing Node has failed")]
    #[case(PlState::ReadyToOperate, "Managing Node has failed")]
    #[case(PlState::BasicEthernet, "Managing Node has failed")]
    #[case(PlState::Operational, "General POWERLINK error")]
    #[case(PlState::Stopped, "General POWERLINK error")]
    #[case(PlState::Initialisation, "General POWERLINK error")]
    fn module_be_led(#[case] state: PlState, #[case] meaning: &str) {
        let r = powerlink_module_be_red(state);
        assert_eq!((r.pattern, r.meaning), (Pattern::Red, meaning));
    }

    #[test]
    fn bus_led() {
        let flowing = BusLed {
            process_data: true,
            ..BusLed::default()
        };
        assert_eq!(bus(flowing).meaning, "Process data communication active");
        assert_eq!(bus(BusLed::default()).pattern, Pattern::Off);
        let timeout = BusLed {
            telegram_timeout: true,
            ..flowing
        };
        assert_eq!(bus(timeout).pattern, Pattern::FlashingRed { tenths_hz: 10 });
        let warning = BusLed {
            bus: BusState::Warning,
            ..flowing
        };
        assert_eq!(
            (bus(warning).pattern, bus(warning).meaning),
            (Pattern::FlashingGreen { tenths_hz: 40 }, "Bus warning")
        );
        let monitoring = BusLed {
            monitoring_error: true,
            ..timeout
        };
        assert_eq!(
            bus(monitoring).pattern,
            Pattern::FlashingRed { tenths_hz: 40 }
        );
        // Bus off outranks everything else.
        let off = BusLed {
            bus: BusState::Off,
            ..monitoring
        };
        assert_eq!(
            (bus(off).pattern, bus(off).meaning),
            (Pattern::Red, "System bus in state \"Bus off\"")
        );
    }
}
