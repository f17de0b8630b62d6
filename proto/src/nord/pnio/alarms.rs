//! Diagnosis alarms (BU 0620 §5.4.2, BU 0590 §5.1.2 P163 and §6.1), what a lost IO controller
//! raises (BU 0620 §5.1/§5.3, BU 0590 §4.1.7), and the PROFINET LEDs per state (BU 0620
//! §5.5.2.4, BU 0590 §2.2.4; the row tables themselves are in `led`).

use serde::Serialize;

use super::{inverter_slot, PnioError, IO_SUBSLOT};
use crate::nord::errors;
use crate::nord::led::{self, Row};
use crate::nord::product::Product;
use crate::nord::types::Inverter;

/// AlarmType "Diagnosis" (IEC 61158-6-10).
pub const ALARM_TYPE_DIAGNOSIS: u16 = 0x0001;
/// USI of a channel diagnosis (IEC 61158-6-10 "ChannelDiagnosis").
pub const USI_CHANNEL_DIAGNOSIS: u16 = 0x8000;
/// AlarmType "Diagnosis disappears" (IEC 61158-6-10): the "outgoing event".
pub const ALARM_TYPE_DIAGNOSIS_DISAPPEARS: u16 = 0x000C;
/// The alarm types a NORD device raises: a diagnostic alarm as "incoming event" when an
/// inverter (or the module) has an error, and as "outgoing event" when it is remedied (BU 0620
/// §5.4.2 p. 98; BU 0590 §6.1 and P163 in §5.1.2). The manuals name no other: a process alarm,
/// say, is none a controller of these devices can expect.
pub const ALARM_TYPES: [u16; 2] = [ALARM_TYPE_DIAGNOSIS, ALARM_TYPE_DIAGNOSIS_DISAPPEARS];

/// The alarm number (ChannelErrorType, BU 0590 P163 p. 35) of an inverter error: P700 + 100h
/// (BU 0620 §5.4.2 p. 98: E10.3 → 359). Same as [`errors::profinet_alarm`].
pub fn fi_error_alarm(p700: u16) -> u16 {
    errors::profinet_alarm(p700)
}

/// The alarm of an inverter lost from the system bus: 256 + 1000 = 1256 (BU 0620 §5.4.2).
pub fn lost_inverter_alarm() -> u16 {
    errors::profinet_alarm(errors::LOST_INVERTER.get())
}

/// The alarm of an SK TU3-PNT module error: P170 + 100h (BU 0590 §6.1 p. 44 "Error number
/// (P700 or P170) = Alarm number – 0x100"; P170 1020 bus time-out → 1276).
pub fn module_error_alarm(product: Product, p170: u16) -> Option<u16> {
    (product == Product::Tu3Pnt).then(|| errors::profinet_alarm(p170))
}

/// The error number an alarm number carries (alarm − 100h), `None` below 100h.
pub fn alarm_error_number(alarm: u16) -> Option<u16> {
    alarm.checked_sub(0x100)
}

/// Whether a ChannelErrorType lies in the manufacturer range 0100h…7FFFh (IEC 61158-6-10),
/// where every NORD alarm number falls (P700 ≤ 25.x, P170 ≤ 5420, 1256).
pub fn manufacturer_error_type(channel_error_type: u16) -> bool {
    (0x0100..=0x7FFF).contains(&channel_error_type)
}

/// "incoming event" / "outgoing event" (BU 0620 §5.4.2, BU 0590 P163).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AlarmEvent {
    /// The error occurred.
    Incoming,
    /// The error was remedied or acknowledged ("resets the error in the IO controller").
    Outgoing,
}

impl AlarmEvent {
    /// ChannelProperties.Specifier: 1 appears, 2 disappears (IEC 61158-6-10).
    pub fn specifier(self) -> u8 {
        match self {
            AlarmEvent::Incoming => 1,
            AlarmEvent::Outgoing => 2,
        }
    }
}

/// Who raised an alarm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AlarmSource {
    /// FI n (its error, or its loss from the system bus).
    Inverter(Inverter),
    /// The SK TU3-PNT itself (P170).
    BusModule,
}

/// Slot and subslot an alarm is reported from: the FI's slot, the SK TU3-PNT's slot 2.
pub fn alarm_location(product: Product, source: AlarmSource) -> Result<(u16, u16), PnioError> {
    match source {
        AlarmSource::Inverter(fi) => Ok((inverter_slot(product, fi)?, IO_SUBSLOT)),
        AlarmSource::BusModule if product == Product::Tu3Pnt => Ok((2, IO_SUBSLOT)),
        AlarmSource::BusModule => Err(PnioError::NotProfinet(product.name())),
    }
}

/// The slot a P163 "Test alarm" element raises its alarm from: [-n] → slot n − 1 (BU 0590
/// §5.1.2: [-01] slot 0 (DAP) … [-04] slot 3 (FI) … [-07] slot 6).
pub fn test_alarm_slot(element: u8) -> Option<u16> {
    (1..=7).contains(&element).then(|| u16::from(element) - 1)
}

/// The P700 error (tenths) a lost controller raises where the telegram time-out is set: SK
/// 550P E10.2 "time-out through PLC" (7591h, BU 0620 §5.3), as its EtherCAT and POWERLINK
/// interfaces do on a watchdog; SK TU3-PNT E10.3 (BU 0590 §4.1.7 "no further cyclical data …
/// (E10.3)", table 29).
pub fn controller_loss_error(product: Product) -> Option<u16> {
    match product {
        Product::Sk550p => Some(102),
        Product::Tu3Pnt => Some(103),
        _ => None,
    }
}

/// The telegram time-out parameter and element: P513 [-04] "Ethernet" (BU 0620 §4.5), P513
/// (BU 0590 §5.2.1: −0.1 no error, 0.0 off, 0.1…100.0 s).
pub fn telegram_timeout_parameter(product: Product) -> Option<(u16, Option<u8>)> {
    match product {
        Product::Sk550p => Some((513, Some(4))),
        Product::Tu3Pnt => Some((513, None)),
        _ => None,
    }
}

/// The module error shown on a time-out: SK TU3-PNT P170 [-01] = 1020 "Bus Time Out via P151
/// (TU4-PNT) or P513 (TU3-PNT)" (BU 0590 §5.1.3).
pub fn timeout_module_error(product: Product) -> Option<u16> {
    (product == Product::Tu3Pnt).then_some(1020)
}

// ---------------------------------------------------------------------------------------------
// LEDs
// ---------------------------------------------------------------------------------------------

/// The state of the PROFINET interface as its LEDs show it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LedState {
    /// Switched off or initialising.
    Initialising,
    /// No Ethernet link on either port.
    NoLink,
    /// Link, no application relation (yet, or lost).
    WaitingForAr,
    /// Application relation established.
    ArEstablished,
}

/// The two PROFINET LEDs: SK 550P "BF" (LED A) and "RUN" (LED B) (BU 0620 §5.5.2.4, table as
/// corrected in `led::PROFINET_RUN`); SK TU3-PNT "RUN" and "ERR" (BU 0590 §2.2.4 tables 4, 5).
/// `alarm`: a diagnosis alarm is incoming and not yet outgoing; `timeout`: the IO controller
/// monitoring (P513) has tripped.
pub fn status_leds(
    product: Product,
    state: LedState,
    alarm: bool,
    timeout: bool,
) -> Option<[(&'static str, Row); 2]> {
    let run = match state {
        LedState::Initialising => led::PROFINET_RUN[0],
        LedState::NoLink | LedState::WaitingForAr => led::PROFINET_RUN[1],
        LedState::ArEstablished => led::PROFINET_RUN[2],
    };
    match product {
        Product::Sk550p => Some([("bf", led::PROFINET_BF[usize::from(alarm)]), ("run", run)]),
        Product::Tu3Pnt => {
            let err = match (state, timeout) {
                (LedState::NoLink, _) => led::TU3_PNT_ERR[2],
                (_, true) => led::TU3_PNT_ERR[1],
                _ => led::TU3_PNT_ERR[0],
            };
            Some([("run", run), ("err", err)])
        }
        _ => None,
    }
}

/// A pattern of the SK TU3-PNT's link/activity and DS/DE LEDs (BU 0590 tables 6, 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "pattern")]
pub enum ModuleLed {
    /// Dark.
    Off,
    /// Steady.
    On,
    /// Flashing with the given cycle.
    Flashing {
        /// Cycle in ms ("Cycle 0.50 sec" = 500).
        cycle_ms: u16,
    },
    /// Steady or flickering with the traffic ("On / Flashing").
    Traffic,
    /// `min`..`max` flashes of 0.25 s, then a pause of 1 s.
    Flashes {
        /// Fewest flashes.
        min: u8,
        /// Most flashes.
        max: u8,
    },
}

/// One row of tables 6 and 7: the two LEDs and the meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct ModuleLedRow {
    /// "L" (green, link) or "DS" (green).
    pub first: ModuleLed,
    /// "A" (yellow, activity) or "DE" (red).
    pub second: ModuleLed,
    /// The manual's meaning.
    pub meaning: &'static str,
}

const fn mrow(first: ModuleLed, second: ModuleLed, meaning: &'static str) -> ModuleLedRow {
    ModuleLedRow {
        first,
        second,
        meaning,
    }
}

const HALF_SECOND: ModuleLed = ModuleLed::Flashing { cycle_ms: 500 };

/// Table 6 (p. 11) "L / A" on each RJ45 socket, rows reconstructed from the flattened text.
pub const TU3_PNT_LINK_ACTIVITY: &[ModuleLedRow] = &[
    mrow(
        ModuleLed::Off,
        ModuleLed::Off,
        "Port (RJ45 socket) is not connected to the PROFINET network",
    ),
    mrow(
        HALF_SECOND,
        HALF_SECOND,
        "Identification signal of the station if a flashing test is performed in the planning tool",
    ),
    mrow(
        ModuleLed::On,
        ModuleLed::Off,
        "Port (RJ45 socket) is connected to the PROFINET network, but there is no exchange of data",
    ),
    mrow(
        ModuleLed::On,
        ModuleLed::Traffic,
        "Data exchange via PROFINET active",
    ),
];

/// Table 7 (p. 12) "DS" (green) / "DE" (red), rows reconstructed from the flattened text.
pub const TU3_PNT_DS_DE: &[ModuleLedRow] = &[
    mrow(
        ModuleLed::Off,
        ModuleLed::Off,
        "The technology unit does not have a power supply",
    ),
    mrow(
        ModuleLed::Off,
        ModuleLed::Flashes { min: 1, max: 7 },
        "The technology unit has a fatal system error",
    ),
    mrow(
        HALF_SECOND,
        ModuleLed::Off,
        "Technology unit OK but no FI (frequency inverter) detected",
    ),
    mrow(
        ModuleLed::On,
        ModuleLed::Flashes { min: 1, max: 1 },
        "The FI is in an error condition",
    ),
    mrow(
        ModuleLed::On,
        ModuleLed::Off,
        "Technology unit OK and FI detected",
    ),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nord::led::Pattern;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn alarm_numbers() {
        // BU 0620 §5.4.2 p. 98: E10.3 = 103 → 167h = 359; lost inverter 1256.
        assert_eq!(fi_error_alarm(103), 0x167);
        assert_eq!(lost_inverter_alarm(), 1256);
        // BU 0590 §5.1.2 P163: error 5.0 → ChannelErrorType 132h.
        assert_eq!(fi_error_alarm(50), 0x132);
        assert_eq!(module_error_alarm(Product::Tu3Pnt, 1020), Some(1276));
        assert_eq!(module_error_alarm(Product::Sk550p, 1020), None);
        assert_eq!(alarm_error_number(359), Some(103));
        assert!(manufacturer_error_type(1276) && manufacturer_error_type(0x132));
        assert!(!manufacturer_error_type(0x8000));
        assert_eq!(
            (
                AlarmEvent::Incoming.specifier(),
                AlarmEvent::Outgoing.specifier()
            ),
            (1, 2)
        );
        assert_eq!(
            alarm_location(Product::Sk550p, AlarmSource::Inverter(fi(2))),
            Ok((4, 1))
        );
        assert_eq!(
            alarm_location(Product::Tu3Pnt, AlarmSource::BusModule),
            Ok((2, 1))
        );
        // P163 [-04] is slot 3, the FI (the manual's example says "Slot 2").
        assert_eq!(test_alarm_slot(4), Some(3));
        assert_eq!((test_alarm_slot(0), test_alarm_slot(8)), (None, None));
    }

    #[test]
    fn controller_loss() {
        assert_eq!(controller_loss_error(Product::Sk550p), Some(102));
        assert_eq!(controller_loss_error(Product::Tu3Pnt), Some(103));
        assert_eq!(
            telegram_timeout_parameter(Product::Sk550p),
            Some((513, Some(4)))
        );
        assert_eq!(timeout_module_error(Product::Tu3Pnt), Some(1020));
        assert_eq!(timeout_module_error(Product::Sk550p), None);
    }

    #[test]
    fn leds_per_state() {
        let [bf, run] =
            status_leds(Product::Sk550p, LedState::ArEstablished, false, false).unwrap();
        assert_eq!(
            (bf.0, bf.1.pattern, run.0, run.1.pattern),
            ("bf", Pattern::Off, "run", Pattern::Green)
        );
        let [bf, run] = status_leds(Product::Sk550p, LedState::WaitingForAr, true, false).unwrap();
        assert_eq!((bf.1.meaning, run.1.meaning), ("Alarm", "Waiting for AR"));
        let [_, err] = status_leds(Product::Tu3Pnt, LedState::WaitingForAr, false, true).unwrap();
        assert_eq!(err.1.pattern, Pattern::DoubleFlashRed);
        let [run, err] = status_leds(Product::Tu3Pnt, LedState::NoLink, false, false).unwrap();
        assert_eq!(
            (run.1.pattern, err.1.pattern),
            (Pattern::FlashingGreen { tenths_hz: 20 }, Pattern::Red)
        );
        assert_eq!(
            status_leds(Product::Tu3Eip, LedState::NoLink, false, false),
            None
        );
        assert_eq!(TU3_PNT_LINK_ACTIVITY.len(), 4);
        assert_eq!(TU3_PNT_DS_DE[3].meaning, "The FI is in an error condition");
    }
}
