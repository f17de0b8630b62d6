//! Scaling of setpoints, actual values and parameter values.
//!
//! - BU 0620 §6.1.2.4 (p. 112–113), BU 2100 §6.2.5 (p. 39–40), BU 2200 §6.3.4 (p. 38),
//!   BU 0590 §4.1.5 (p. 23): percentages are 16-bit integers, 4000h = 100 % (of P105 for
//!   frequencies, P112 for currents), range 8000h..7FFFh; positions are 32-bit values in a low
//!   and a high word, ±50000.00 rotations of up to 1000 increments.
//! - BU 0620 §2.5.6.3 (p. 57), BU 0590 §4.2.3 (p. 29): parameters with resolution 0.1 / 0.01
//!   are transferred multiplied by the inverse of the resolution (99.99 s → 9999).
//! - Setpoint functions (P546) and actual-value functions (P543): BU 0590 §5 (p. 39–40) lists
//!   the codes; BU 0620 §3.9 (p. 73) and BU 2100 §5.3 (p. 28) add the position words 10/15
//!   and 23/24 (POSICON, BU 0510), which BU 0590's list shows as reserved.

use serde::Serialize;

/// 100 % in process data (16384 = 4000h).
pub const FULL_SCALE: i32 = 0x4000;
/// Increments per motor rotation at most (§6.1.2.4 "Transmission of positions").
pub const INCREMENTS_PER_ROTATION: i32 = 1000;
/// Positions range ±50000.00 rotations: ±50,000,000 increments (§6.1.2.4).
pub const POSITION_LIMIT: i32 = 50_000 * INCREMENTS_PER_ROTATION;

/// A value the scaling rules cannot represent.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ScalingError {
    /// Outside the 16-bit process value range -32768..=32767 (8000h..7FFFh).
    #[error("{what} {value} is outside the process value range -32768..=32767 (8000h..7FFFh)")]
    ProcessRange {
        /// Which value.
        what: &'static str,
        /// The value as given.
        value: String,
    },
    /// Not a decimal number.
    #[error("{what} `{text}` is not a decimal number")]
    NotDecimal {
        /// Which value.
        what: &'static str,
        /// The text.
        text: String,
    },
    /// More decimal places than the resolution has.
    #[error("{what} `{text}` is finer than the resolution of {decimals} decimal places")]
    FinerThanResolution {
        /// Which value.
        what: &'static str,
        /// The text.
        text: String,
        /// Decimal places of the resolution.
        decimals: u8,
    },
    /// Beyond ±50000.00 rotations.
    #[error("position {increments} increments is beyond ±50000.00 rotations (±{POSITION_LIMIT})")]
    PositionRange {
        /// The position in increments.
        increments: i64,
    },
}

/// Raw process value of a percentage (4000h = 100 %); refused outside 8000h..7FFFh.
pub fn percent_to_raw(percent: f64) -> Result<i16, ScalingError> {
    let raw = (percent * f64::from(FULL_SCALE) / 100.0).round();
    if (-32768.0..=32767.0).contains(&raw) {
        Ok(raw as i16)
    } else {
        Err(ScalingError::ProcessRange {
            what: "percentage",
            value: format!("{percent} % = {raw}"),
        })
    }
}

/// Percentage of a raw process value.
pub fn raw_to_percent(raw: i16) -> f64 {
    f64::from(raw) * 100.0 / f64::from(FULL_SCALE)
}

/// The physical value of a raw process value: `raw × reference / 16384` (§6.1.2.4 formulae,
/// reference = P105 for frequency, P112 for current).
pub fn raw_to_value(raw: i16, reference: f64) -> f64 {
    f64::from(raw) * reference / f64::from(FULL_SCALE)
}

/// The raw process value of a physical value, `value × 16384 / reference`, saturated to the
/// 16-bit range: what an inverter sends for an actual value (0 when `reference` is 0).
pub fn value_to_raw_saturating(value: f64, reference: f64) -> i16 {
    if reference == 0.0 {
        return 0;
    }
    (value * f64::from(FULL_SCALE) / reference)
        .round()
        .clamp(-32768.0, 32767.0) as i16
}

/// The transferred integer of a parameter value written in decimal (`"99.99"`) at a
/// resolution of `decimals` places (0.01 → 2): exact, without floating point.
pub fn to_raw(text: &str, decimals: u8) -> Result<i64, ScalingError> {
    let bad = || ScalingError::NotDecimal {
        what: "parameter value",
        text: text.to_string(),
    };
    let t = text.trim();
    let (negative, digits) = match t.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, t),
    };
    let (int, frac) = digits.split_once('.').unwrap_or((digits, ""));
    let all_digits = |s: &str| s.bytes().all(|b| b.is_ascii_digit());
    if int.is_empty() || !all_digits(int) || !all_digits(frac) {
        return Err(bad());
    }
    let frac = frac.trim_end_matches('0');
    if frac.len() > usize::from(decimals) {
        return Err(ScalingError::FinerThanResolution {
            what: "parameter value",
            text: text.to_string(),
            decimals,
        });
    }
    let padded = format!("{int}{frac:0<width$}", width = usize::from(decimals));
    let magnitude: i64 = padded.parse().map_err(|_| bad())?;
    Ok(if negative { -magnitude } else { magnitude })
}

/// The parameter value of a transferred integer, in decimal (`9999`, 2 → `"99.99"`).
pub fn from_raw(raw: i64, decimals: u8) -> String {
    let scale = 10u64.pow(u32::from(decimals.min(18)));
    let sign = if raw < 0 { "-" } else { "" };
    let m = raw.unsigned_abs();
    if decimals == 0 {
        format!("{sign}{m}")
    } else {
        let width = usize::from(decimals.min(18));
        format!("{sign}{}.{:0width$}", m / scale, m % scale)
    }
}

/// Increments (1000 per rotation) of a position in rotations written in decimal
/// (`"50000.00"`), checked against ±50000.00 rotations.
pub fn rotations_to_increments(text: &str) -> Result<i32, ScalingError> {
    let increments = to_raw(text, 3)?;
    check_position(increments)
}

fn check_position(increments: i64) -> Result<i32, ScalingError> {
    i32::try_from(increments)
        .ok()
        .filter(|p| p.abs() <= POSITION_LIMIT)
        .ok_or(ScalingError::PositionRange { increments })
}

/// A 32-bit position (increments) split into (low word, high word) as transferred (§6.1.2.4).
pub fn position_words(increments: i64) -> Result<(u16, u16), ScalingError> {
    let p = check_position(increments)?;
    Ok((p as u16, (p >> 16) as u16))
}

/// The 32-bit position of a low and a high word.
pub fn position_of(low: u16, high: u16) -> i32 {
    ((u32::from(high) << 16) | u32::from(low)) as i32
}

/// The position of a low word sent alone: a signed 16-bit value, ±32.767 rotations at 1000
/// increments per rotation ("Only the 'Low' word ...", §6.1.2.4 p. 113).
pub fn position_of_low_word(low: u16) -> i32 {
    i32::from(low as i16)
}

/// How a setpoint or actual value is transferred (§6.1.2.4 "three different methods").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Transmission {
    /// The function is off: nothing is transferred.
    Off,
    /// Percentage transmission, 4000h = 100 % of parameter `reference` (P105 or P112).
    Percent {
        /// The parameter whose value is 100 %.
        reference: u16,
    },
    /// Binary transmission, evaluated bit by bit.
    Binary,
    /// Low word of a 32-bit position.
    PositionLow,
    /// High word of a 32-bit position.
    PositionHigh,
    /// An integer as is (an error number).
    Integer,
    /// The manuals here give no scaling (they refer to the inverter manual).
    Unstated,
}

/// One function code of P543 (actual values) or P546 (setpoints).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct ProcessFunction {
    /// The parameter value.
    pub code: u8,
    /// The manual's name.
    pub name: &'static str,
    /// How the value is scaled.
    pub transmission: Transmission,
}

const fn f(code: u8, name: &'static str, transmission: Transmission) -> ProcessFunction {
    ProcessFunction {
        code,
        name,
        transmission,
    }
}

const FREQ: Transmission = Transmission::Percent { reference: 105 };
const CURRENT: Transmission = Transmission::Percent { reference: 112 };
const UNSTATED: Transmission = Transmission::Unstated;

/// P543 "Actual bus value" codes: BU 0590 §5 p. 39 (0–24; 6–7, 11, 13–14, 16 reserved) with
/// BU 0620 §3.9 p. 73 for 10 and 15 (the POSICON position words).
pub const ACTUAL_FUNCTIONS: &[ProcessFunction] = &[
    f(0, "Off", Transmission::Off),
    f(1, "Actual frequency", FREQ),
    f(2, "Actual speed", UNSTATED),
    f(3, "Current", CURRENT),
    f(4, "Torque current (100% = P112)", CURRENT),
    f(5, "Digital IO status", Transmission::Binary),
    f(8, "Setpoint frequency", FREQ),
    f(9, "Error number", Transmission::Integer),
    f(
        10,
        "Actual Position incl. LowWord",
        Transmission::PositionLow,
    ),
    f(12, "BusIO Out Bits 0...7", Transmission::Binary),
    f(
        15,
        "Actual Position incl. HighWord",
        Transmission::PositionHigh,
    ),
    f(17, "Value analog input 1", UNSTATED),
    f(18, "Value analog input 2", UNSTATED),
    f(19, "Setpoint frequency master value", FREQ),
    f(20, "Setpoint frequency master value after ramp", FREQ),
    f(21, "Actual frequency without slip master value", FREQ),
    f(22, "Speed encoder", UNSTATED),
    f(23, "Actual frequency with slip", FREQ),
    f(24, "Master value, actual frequency with slip", FREQ),
];

/// P546 "Function bus setpoint" codes: BU 0590 §5 p. 40 (0–20, 46, 48, 53–55; 12, 21–45, 47,
/// 49, 56–57 reserved or POSICON) with BU 0620 §3.9 p. 73 / BU 2100 §5.3 p. 28 for 23 and 24.
pub const SETPOINT_FUNCTIONS: &[ProcessFunction] = &[
    f(0, "Off", Transmission::Off),
    f(1, "Setpoint frequency", FREQ),
    f(2, "Torque current limit (P112)", CURRENT),
    f(3, "Actual frequency PID", FREQ),
    f(4, "Frequency addition", FREQ),
    f(5, "Frequency subtraction", FREQ),
    f(6, "Current limit (P536)", UNSTATED),
    f(7, "Maximum frequency (P105)", UNSTATED),
    f(8, "Actual PID frequency limited", FREQ),
    f(9, "Actual PID frequency monitored", FREQ),
    f(10, "Torque servo mode (P300)", UNSTATED),
    f(11, "Torque precontrol (P214)", UNSTATED),
    f(13, "Multiplication", UNSTATED),
    f(14, "Process controller actual value", UNSTATED),
    f(15, "Process controller setpoint", UNSTATED),
    f(16, "Process controller lead", UNSTATED),
    f(17, "BusIO In Bits 0...7", Transmission::Binary),
    f(18, "Curve travel calculator", UNSTATED),
    f(19, "Set relays (output status)", Transmission::Binary),
    f(20, "Set analog output", UNSTATED),
    f(
        23,
        "Setpoint position incl. LowWord",
        Transmission::PositionLow,
    ),
    f(
        24,
        "Setpoint position incl. HighWord",
        Transmission::PositionHigh,
    ),
    f(46, "Setpoint torque process controller", UNSTATED),
    f(48, "Motor temperature", UNSTATED),
    f(53, "d-correction F process", UNSTATED),
    f(54, "d-correction Torque", UNSTATED),
    f(55, "d-correction F+torque", UNSTATED),
];

/// The bits of the actual value "Digital IO status" (P543 = 5), bit 0 first (BU 0590 §5.2.1,
/// p. 39: "The assignment of the digital inputs in P543/544/545 = 5").
pub const DIGITAL_IO_BITS: [&str; 16] = [
    "DigIn 1",
    "DigIn 2",
    "DigIn 3",
    "DigIn 4",
    "DigIn 5",
    "DigIn 6 (SK 520E and above)",
    "DigIn 7 (SK 520E and above)",
    "Dig. func. AIN1",
    "Dig. func. AIN2",
    "DigIn 8 (SK 540E and above)",
    "DigIn 1, 1st IOE (SK 540E and above)",
    "DigIn 2, 1st IOE (SK 540E and above)",
    "Out 1/ MFR1",
    "Out 2/ MFR2",
    "Out 3/ DOUT1 (SK 520E and above)",
    "Out 4/ DOUT2 (SK 520E and above)",
];

/// The P543 function `code`, or `None` when reserved or not in these manuals.
pub fn actual_function(code: i32) -> Option<&'static ProcessFunction> {
    ACTUAL_FUNCTIONS.iter().find(|p| i32::from(p.code) == code)
}

/// The P546 function `code`, or `None` when reserved or not in these manuals.
pub fn setpoint_function(code: i32) -> Option<&'static ProcessFunction> {
    SETPOINT_FUNCTIONS
        .iter()
        .find(|p| i32::from(p.code) == code)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    // §6.1.2.4 p. 112 and the §6.1.3 example (2000h = 50 %, 1000h = 25 %).
    #[case(100.0, 0x4000)]
    #[case(50.0, 0x2000)]
    #[case(25.0, 0x1000)]
    #[case(-100.0, -0x4000)]
    #[case(-200.0, -0x8000)]
    fn percentages(#[case] p: f64, #[case] raw: i16) {
        assert_eq!(percent_to_raw(p), Ok(raw));
    }

    #[test]
    fn beyond_the_range_is_refused() {
        assert!(matches!(
            percent_to_raw(200.0),
            Err(ScalingError::ProcessRange { .. })
        ));
        assert_eq!(value_to_raw_saturating(200.0, 50.0), 32767);
        assert_eq!(value_to_raw_saturating(25.0, 50.0), 0x2000);
        assert_eq!(value_to_raw_saturating(1.0, 0.0), 0);
    }

    #[test]
    fn frequencies_of_the_setpoint_example() {
        // §6.1.3 p. 114: P105 = 50 Hz; 2000h → 25 Hz, 1000h → 12.5 Hz.
        assert_eq!(raw_to_value(0x2000, 50.0), 25.0);
        assert_eq!(raw_to_value(0x1000, 50.0), 12.5);
        // "-16384 (C000 hex)" is -100 %.
        assert_eq!(raw_to_percent(-16384), -100.0);
    }

    #[rstest]
    // §2.5.6.3 p. 57: 99.99 s at 0.01 → 9999 (270Fh); §2.5.6.4: 10 s → 1000 (3E8h).
    #[case("99.99", 2, Ok(9999))]
    #[case("10", 2, Ok(1000))]
    #[case("2.5", 1, Ok(25))]
    #[case("-0.01", 2, Ok(-1))]
    #[case("1.230", 2, Ok(123))]
    #[case("99.999", 2, Err(()))]
    #[case("9x", 2, Err(()))]
    #[case(".5", 1, Err(()))]
    fn resolutions(#[case] text: &str, #[case] decimals: u8, #[case] want: Result<i64, ()>) {
        assert_eq!(to_raw(text, decimals).map_err(|_| ()), want);
    }

    #[test]
    fn raw_back_to_text() {
        assert_eq!(from_raw(9999, 2), "99.99");
        assert_eq!(from_raw(-1, 2), "-0.01");
        assert_eq!(from_raw(500, 1), "50.0");
        assert_eq!(from_raw(7, 0), "7");
    }

    #[test]
    fn positions() {
        // §6.1.2.4 p. 113: ±50000.00 rotations of 1000 increments, low and high word.
        assert_eq!(position_words(-1), Ok((0xFFFF, 0xFFFF)));
        assert_eq!(
            position_words(i64::from(POSITION_LIMIT)),
            Ok((0xF080, 0x02FA))
        );
        assert!(position_words(i64::from(POSITION_LIMIT) + 1).is_err());
        assert_eq!(position_of(0xF080, 0x02FA), POSITION_LIMIT);
        assert_eq!(rotations_to_increments("-50000.00"), Ok(-POSITION_LIMIT));
        assert!(rotations_to_increments("50000.001").is_err());
        // The low word alone: 32767 increments = 32.767 rotations.
        assert_eq!(position_of_low_word(0x8000), -32768);
        assert_eq!(
            from_raw(i64::from(position_of_low_word(0x7FFF)), 3),
            "32.767"
        );
    }

    #[test]
    fn function_tables() {
        assert_eq!(actual_function(1).map(|f| f.transmission), Some(FREQ));
        assert_eq!(
            actual_function(15).map(|f| f.transmission),
            Some(Transmission::PositionHigh)
        );
        assert_eq!(actual_function(6), None);
        assert_eq!(setpoint_function(23).map(|f| f.code), Some(23));
        assert_eq!(setpoint_function(12), None);
        assert_eq!(setpoint_function(-1), None);
    }
}
