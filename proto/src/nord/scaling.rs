//! Scaling of setpoints, actual values and parameter values.
//!
//! BU 0620 §6.1.2.4 (p. 112): percentages are 16-bit integers, 4000h = 100 % (of P105 for
//! frequencies, P112 for currents), range 8000h..7FFFh; positions are 32-bit values in a low and
//! a high word. §2.5.6.3: parameters with resolution 0.1 / 0.01 are transferred multiplied by
//! the inverse of the resolution (99.99 s → 9999).

/// 100 % in process data.
pub const FULL_SCALE: i32 = 0x4000;

/// Raw process value of a percentage, saturated to the 16-bit range.
pub fn percent_to_raw(percent: f64) -> i16 {
    (percent * f64::from(FULL_SCALE) / 100.0)
        .round()
        .clamp(-32768.0, 32767.0) as i16
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

/// The transferred integer of a parameter value with `decimals` decimal places (0.01 → 2).
pub fn to_raw(value: f64, decimals: u8) -> i64 {
    (value * 10f64.powi(i32::from(decimals))).round() as i64
}

/// The parameter value of a transferred integer.
pub fn from_raw(raw: i64, decimals: u8) -> f64 {
    raw as f64 / 10f64.powi(i32::from(decimals))
}

/// A 32-bit position split into (low word, high word) as transferred (§6.1.2.4).
pub fn position_words(position: i32) -> (u16, u16) {
    (position as u16, (position >> 16) as u16)
}

/// The 32-bit position of a low and a high word.
pub fn position_of(low: u16, high: u16) -> i32 {
    ((u32::from(high) << 16) | u32::from(low)) as i32
}

/// Positions range ±50000.00 rotations at up to 1000 increments per rotation (§6.1.2.4).
pub const POSITION_LIMIT: i32 = 50_000 * 1000;

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case(100.0, 0x4000)]
    #[case(50.0, 0x2000)]
    #[case(25.0, 0x1000)]
    #[case(-100.0, -0x4000)]
    #[case(300.0, 0x7FFF)]
    fn percentages(#[case] p: f64, #[case] raw: i16) {
        assert_eq!(percent_to_raw(p), raw);
    }

    #[test]
    fn frequencies_of_the_setpoint_example() {
        // §6.1.3: P105 = 50 Hz; 2000h → 25 Hz, 1000h → 12.5 Hz.
        assert_eq!(raw_to_value(0x2000, 50.0), 25.0);
        assert_eq!(raw_to_value(0x1000, 50.0), 12.5);
        // "-16384 (C000 hex)" is -100 %.
        assert_eq!(raw_to_percent(-16384), -100.0);
    }

    #[test]
    fn resolutions_and_positions() {
        assert_eq!(to_raw(99.99, 2), 9999);
        assert_eq!(to_raw(2.5, 2), 250);
        assert_eq!(from_raw(9999, 2), 99.99);
        assert_eq!(position_words(-1), (0xFFFF, 0xFFFF));
        assert_eq!(position_words(POSITION_LIMIT), (0xF080, 0x02FA));
        assert_eq!(position_of(0xF080, 0x02FA), POSITION_LIMIT);
    }
}
