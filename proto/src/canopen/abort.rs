//! SDO abort codes (CiA 301 "SDO abort codes", the table of the "Abort SDO transfer"
//! protocol): the u32 an SDO abort carries in bytes 4–7, little-endian, on CAN as in an
//! EtherCAT mailbox (CoE, `ecat::coe`). One code space: the codes ETG.1000.6 adds for
//! CoE (0601_0003h–0601_0006h) are defined and explained in `ecat::coe`
//! (`SdoAbortCode::ETG_1000_6`), and [`SdoAbortCode::name`] knows both tables.

use std::fmt;

/// An SDO abort code (open: unknown codes are kept and print as hex).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct SdoAbortCode(pub u32);

/// Defines abort codes as constants of [`SdoAbortCode`] and a table `$table` of them with their
/// meanings (used here for CiA 301 and in `ecat::coe` for the codes ETG.1000.6 adds).
macro_rules! abort_codes {
    ($(#[$tm:meta])* $table:ident { $($name:ident = $v:literal, $text:literal;)* }) => {
        impl $crate::canopen::SdoAbortCode {
            $(
                #[doc = concat!($text, ".")]
                pub const $name: $crate::canopen::SdoAbortCode = $crate::canopen::SdoAbortCode($v);
            )*

            $(#[$tm])*
            pub const $table: &'static [($crate::canopen::SdoAbortCode, &'static str)] = &[
                $(($crate::canopen::SdoAbortCode($v), $text),)*
            ];
        }
    };
}
pub(crate) use abort_codes;

abort_codes! {
    /// Every code of CiA 301, with its meaning.
    CIA_301 {
        TOGGLE_BIT = 0x0503_0000, "Toggle bit not alternated";
        TIMEOUT = 0x0504_0000, "SDO protocol timed out";
        COMMAND_SPECIFIER = 0x0504_0001, "Client/server command specifier not valid or unknown";
        INVALID_BLOCK_SIZE = 0x0504_0002, "Invalid block size (block mode only)";
        INVALID_SEQUENCE = 0x0504_0003, "Invalid sequence number (block mode only)";
        CRC_ERROR = 0x0504_0004, "CRC error (block mode only)";
        OUT_OF_MEMORY = 0x0504_0005, "Out of memory";
        UNSUPPORTED_ACCESS = 0x0601_0000, "Unsupported access to an object";
        WRITE_ONLY = 0x0601_0001, "Attempt to read a write only object";
        READ_ONLY = 0x0601_0002, "Attempt to write a read only object";
        NO_OBJECT = 0x0602_0000, "Object does not exist in the object dictionary";
        NOT_MAPPABLE = 0x0604_0041, "Object cannot be mapped to the PDO";
        PDO_TOO_LONG = 0x0604_0042, "The number and length of the objects to be mapped would exceed the PDO length";
        PARAMETER_INCOMPATIBLE = 0x0604_0043, "General parameter incompatibility reason";
        INTERNAL_INCOMPATIBLE = 0x0604_0047, "General internal incompatibility in the device";
        HARDWARE_ERROR = 0x0606_0000, "Access failed due to a hardware error";
        LENGTH_MISMATCH = 0x0607_0010, "Data type does not match, length of service parameter does not match";
        LENGTH_TOO_HIGH = 0x0607_0012, "Data type does not match, length of service parameter too high";
        LENGTH_TOO_LOW = 0x0607_0013, "Data type does not match, length of service parameter too low";
        NO_SUBINDEX = 0x0609_0011, "Sub-index does not exist";
        VALUE_RANGE = 0x0609_0030, "Invalid value for parameter (download only)";
        VALUE_TOO_HIGH = 0x0609_0031, "Value of parameter written too high (download only)";
        VALUE_TOO_LOW = 0x0609_0032, "Value of parameter written too low (download only)";
        MAX_BELOW_MIN = 0x0609_0036, "Maximum value is less than minimum value";
        NO_SDO_CONNECTION = 0x060A_0023, "Resource not available: SDO connection";
        GENERAL = 0x0800_0000, "General error";
        CANNOT_STORE = 0x0800_0020, "Data cannot be transferred or stored to the application";
        LOCAL_CONTROL = 0x0800_0021, "Data cannot be transferred or stored to the application because of local control";
        DEVICE_STATE = 0x0800_0022, "Data cannot be transferred or stored to the application because of the present device state";
        NO_OD = 0x0800_0023, "Object dictionary dynamic generation fails or no object dictionary is present";
        NO_DATA = 0x0800_0024, "No data available";
    }
}

impl SdoAbortCode {
    /// Every defined code with its meaning: CiA 301's, then those ETG.1000.6 adds.
    pub fn all() -> impl Iterator<Item = (SdoAbortCode, &'static str)> {
        SdoAbortCode::CIA_301
            .iter()
            .chain(SdoAbortCode::ETG_1000_6)
            .copied()
    }

    /// The standard's meaning, if CiA 301 or ETG.1000.6 defines the code.
    pub fn name(self) -> Option<&'static str> {
        SdoAbortCode::all()
            .find(|(c, _)| *c == self)
            .map(|(_, n)| n)
    }
}

impl fmt::Display for SdoAbortCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "{:08X}h ({n})", self.0),
            None => write!(f, "{:08X}h", self.0),
        }
    }
}

impl fmt::Debug for SdoAbortCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SdoAbortCode({:08X}h)", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_print_their_meaning() {
        assert_eq!(
            SdoAbortCode::TOGGLE_BIT.to_string(),
            "05030000h (Toggle bit not alternated)"
        );
        // An ETG.1000.6 code is named too.
        assert_eq!(
            SdoAbortCode(0x0601_0005).name(),
            Some("Object length exceeds mailbox size")
        );
        assert_eq!(SdoAbortCode(0x0601_0007).to_string(), "06010007h");
        assert_eq!(
            format!("{:?}", SdoAbortCode::CRC_ERROR),
            "SdoAbortCode(05040004h)"
        );
    }

    #[test]
    fn the_tables_are_disjoint_and_sorted() {
        let codes: Vec<u32> = SdoAbortCode::all().map(|(c, _)| c.0).collect();
        let mut sorted = codes.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), codes.len());
        assert_eq!(SdoAbortCode::CIA_301.len(), 31);
        assert!(SdoAbortCode::CIA_301.windows(2).all(|w| w[0].0 < w[1].0));
        // CiA 301 leaves 0601_0003h–0601_0006h to others (ETG.1000.6).
        assert!(SdoAbortCode::CIA_301
            .iter()
            .all(|(c, _)| !(0x0601_0003..=0x0601_0006).contains(&c.0)));
    }
}
