//! Range-checked newtypes for the quantities every address formula takes.

use serde::{Deserialize, Serialize};
use std::fmt;

/// A value outside the range the manuals allow.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{what} {value} is out of range {min}..={max}")]
pub struct RangeError {
    /// What was out of range ("inverter", "parameter number", …).
    pub what: &'static str,
    /// The offending value.
    pub value: i64,
    /// Smallest allowed value.
    pub min: i64,
    /// Largest allowed value.
    pub max: i64,
}

macro_rules! ranged {
    ($(#[$m:meta])* $name:ident($t:ty), $what:literal, $min:expr, $max:expr) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
        #[serde(try_from = "i64", into = "i64")]
        pub struct $name($t);

        impl $name {
            /// Smallest allowed value.
            pub const MIN: $t = $min;
            /// Largest allowed value.
            pub const MAX: $t = $max;

            /// Checks the range.
            pub const fn new(value: i64) -> Result<Self, RangeError> {
                if value >= Self::MIN as i64 && value <= Self::MAX as i64 {
                    Ok(Self(value as $t))
                } else {
                    Err(RangeError { what: $what, value, min: Self::MIN as i64, max: Self::MAX as i64 })
                }
            }

            /// The number as the manuals write it.
            pub fn get(self) -> $t {
                self.0
            }
        }

        impl TryFrom<i64> for $name {
            type Error = RangeError;
            fn try_from(v: i64) -> Result<Self, RangeError> {
                Self::new(v)
            }
        }

        impl From<$name> for i64 {
            fn from(v: $name) -> i64 {
                v.0 as i64
            }
        }
    };
}

ranged!(
    /// Inverter on the bus interface, FI 1..8 (BU 0620 §2.1: up to 8 inverters on the system bus).
    Inverter(u8), "inverter", 1, 8
);
ranged!(
    /// NORD parameter number P000..P999 (BU 0620 §2.2.7: "NORD parameter numbers (0 to 999)").
    ParamNumber(u16), "parameter number", 0, 999
);
ranged!(
    /// Parameter set 1..4 (BU 0620 §2.5.6.3: IND bits 8–9, 0 = parameter set 1).
    ParamSet(u8), "parameter set", 1, 4
);
ranged!(
    /// Array element [-01]..[-64] (BU 0620 §2.5.6.3: IND bits 10–15, "Arrays 1...64").
    ArrayElement(u8), "array element", 1, 64
);

impl fmt::Display for ParamNumber {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "P{:03}", self.0)
    }
}

impl fmt::Display for Inverter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "FI {}", self.0)
    }
}

/// A parameter as the manuals name it: inverter, number, parameter set, array element.
///
/// `set` is `None` for parameters that do not depend on the parameter set; `element` is `None`
/// for parameters without an array.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct ParamAddress {
    /// FI 1..8.
    pub inverter: Inverter,
    /// P000..P999.
    pub number: ParamNumber,
    /// Parameter set, for set-dependent parameters.
    pub set: Option<ParamSet>,
    /// Array element, for array parameters.
    pub element: Option<ArrayElement>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case(0, false)]
    #[case(1, true)]
    #[case(8, true)]
    #[case(9, false)]
    fn inverter_range(#[case] v: i64, #[case] ok: bool) {
        assert_eq!(Inverter::new(v).is_ok(), ok);
    }

    #[test]
    fn range_error_names_the_quantity() {
        let e = ParamNumber::new(1000).unwrap_err();
        assert_eq!(
            e.to_string(),
            "parameter number 1000 is out of range 0..=999"
        );
    }
}
