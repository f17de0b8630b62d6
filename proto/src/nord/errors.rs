//! Error tables: inverter communication errors (P700) with their DS402 codes, PROFINET alarm
//! numbers, and the SDO abort codes of EtherCAT and POWERLINK (which differ).

use std::fmt;

use super::product::Protocol;

/// A communication error as P700 [-01] shows it and its DS402 extended code (P700 [-04]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CommError {
    /// Error number, tenths: 10.3 → 103.
    pub p700: u16,
    /// DS402 extended error code.
    pub ds402: u16,
    /// The manual's description.
    pub text: &'static str,
}

/// BU 0620 §5.3 "Error messages – general communication errors" (p. 94).
pub const COMM_ERRORS: &[CommError] = &[
    CommError {
        p700: 100,
        ds402: 0x7580,
        text: "CAN /CANopen connection error",
    },
    CommError {
        p700: 100,
        ds402: 0x7581,
        text: "CAN Broadcast telegram timeout",
    },
    CommError {
        p700: 100,
        ds402: 0x7582,
        text: "CANopen NodeGuard telegram timeout",
    },
    CommError {
        p700: 100,
        ds402: 0x7583,
        text: "CANopen HeartBeat monitoring telegram timeout",
    },
    CommError {
        p700: 100,
        ds402: 0x7584,
        text: "USS telegram timeout",
    },
    CommError {
        p700: 100,
        ds402: 0x7585,
        text: "CAN in Bus Off state",
    },
    CommError {
        p700: 100,
        ds402: 0x7586,
        text: "USB telegram timeout",
    },
    CommError {
        p700: 100,
        ds402: 0x7587,
        text: "Ini CAN Hardware Problem",
    },
    CommError {
        p700: 101,
        ds402: 0x7590,
        text: "Reserve",
    },
    CommError {
        p700: 102,
        ds402: 0x7591,
        text: "Telegram timeout for field bus interface (Time-out through PLC)",
    },
    CommError {
        p700: 103,
        ds402: 0x7592,
        text: "Telegram timeout for field bus interface (Time-out through P513)",
    },
    CommError {
        p700: 104,
        ds402: 0x7593,
        text: "External bus module initialisation failure",
    },
    CommError {
        p700: 105,
        ds402: 0x7594,
        text: "External Bus module system failure",
    },
    CommError {
        p700: 105,
        ds402: 0x7595,
        text: "System error; netX and controller not compatible",
    },
    CommError {
        p700: 105,
        ds402: 0x7596,
        text: "Error when changing the field bus protocol",
    },
    CommError {
        p700: 105,
        ds402: 0x7597,
        text: "System errors: Package to field bus interface too long",
    },
    CommError {
        p700: 105,
        ds402: 0x7598,
        text: "Condition for change of field bus protocol not present",
    },
    CommError {
        p700: 106,
        ds402: 0x7599,
        text: "Ethernet cable not connected",
    },
    CommError {
        p700: 107,
        ds402: 0x759A,
        text: "Reserve",
    },
    CommError {
        p700: 108,
        ds402: 0x759B,
        text: "Communication error to field bus interface",
    },
];

/// The PROFINET diagnostic alarm of an inverter error: 100h + P700 value (BU 0620 §5.4.2: E10.3
/// → "359 (100h + 103 = 256 + 103)").
pub fn profinet_alarm(p700: u16) -> u16 {
    0x100 + p700
}

/// An SDO abort code (open: unknown codes are kept).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct SdoAbort(pub u32);

/// BU 0620 §2.2.7.2 (p. 21): EtherCAT SDO error codes.
pub const ETHERCAT_ABORTS: &[(u32, &str)] = &[
    (0x0503_0000, "Toggle bit unchanged"),
    (0x0504_0000, "Timeout SDO message (timeout for the SDO response of the bus interface)"),
    (0x0504_0001, "SDO command invalid/unknown"),
    (0x0504_0005, "No memory (Insufficient memory)"),
    (0x0601_0000, "Illegal access to an object"),
    (0x0601_0001, "Reading access to write-only parameter"),
    (0x0602_0002, "Writing access to read-only object"),
    (0x0602_0000, "Object does not exist in the object dictionary (access to a non-existent parameter)"),
    (0x0604_0043, "Parameter incompatibility"),
    (0x0606_0047, "Internal incompatibility in the bus interface"),
    (0x0606_0000, "Access failed due to hardware error"),
    (0x0607_0012, "Incorrect data type, parameter too long"),
    (0x0607_0013, "Incorrect data type, parameter too short"),
    (0x0609_0011, "Sub-Index of parameter does not exist"),
    (0x0609_0030, "Parameter value range overflow"),
    (0x0609_0031, "Parameter value too large"),
    (0x0609_0032, "Parameter value too small"),
    (0x0609_0036, "Maximum value smaller than the minimum value"),
    (0x0800_0000, "General error"),
    (0x0800_0020, "Data transfer or saving not possible, as there is no communication between the bus interface and the frequency inverter"),
];

/// BU 0620 §2.4.7 (p. 38): POWERLINK SDO error codes (EPSG DS-301).
pub const POWERLINK_ABORTS: &[(u32, &str)] = &[
    (0x0504_0000, "Timeout SDO message (timeout for the SD response from the bus interface)"),
    (0x0504_0001, "SDO command invalid/unknown"),
    (0x0504_0002, "Impermissible size of transferred data"),
    (0x0504_0003, "Error in sequence layer"),
    (0x0504_0005, "No memory (Insufficient memory)"),
    (0x0601_0000, "Illegal access to an object"),
    (0x0601_0001, "Reading access to write-only parameter"),
    (0x0602_0002, "Writing access to a read-only parameter"),
    (0x0602_0000, "Access to a non-existent parameter"),
    (0x0604_0043, "Parameter incompatibility"),
    (0x0606_0047, "Internal incompatibility in the bus interface"),
    (0x0606_0000, "Access failed due to hardware error"),
    (0x0607_0010, "The data type does not match the length of access"),
    (0x0607_0012, "Incorrect data type, parameter too long"),
    (0x0607_0013, "Incorrect data type, parameter too short"),
    (0x0609_0011, "Sub-Index of parameter does not exist"),
    (0x0609_0030, "Parameter value range overflow"),
    (0x0609_0031, "Parameter value too large"),
    (0x0609_0032, "Parameter value too small"),
    (0x0609_0036, "Maximum value smaller than the minimum value"),
    (0x0800_0000, "General error"),
    (0x0800_0020, "Data transfer or saving not possible, as there is no communication between the bus interface and the frequency inverter"),
    (0x0800_0021, "Bus interface does not respond"),
];

impl SdoAbort {
    /// The manual's description for the protocol, if its list has the code.
    pub fn describe(self, protocol: Protocol) -> Option<&'static str> {
        let list = match protocol {
            Protocol::Ethercat => ETHERCAT_ABORTS,
            Protocol::Powerlink => POWERLINK_ABORTS,
            _ => return None,
        };
        list.iter().find(|(c, _)| *c == self.0).map(|(_, t)| *t)
    }
}

impl fmt::Debug for SdoAbort {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SDO abort {:08X}h", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_abort_lists_differ() {
        assert_eq!(
            SdoAbort(0x0503_0000).describe(Protocol::Ethercat),
            Some("Toggle bit unchanged")
        );
        assert_eq!(SdoAbort(0x0503_0000).describe(Protocol::Powerlink), None);
        assert_eq!(
            SdoAbort(0x0800_0021).describe(Protocol::Powerlink),
            Some("Bus interface does not respond")
        );
        assert_eq!(SdoAbort(0x0800_0021).describe(Protocol::Ethercat), None);
        assert_eq!((ETHERCAT_ABORTS.len(), POWERLINK_ABORTS.len()), (20, 23));
    }

    #[test]
    fn p513_timeout_alarm() {
        let e = COMM_ERRORS.iter().find(|e| e.ds402 == 0x7592).unwrap();
        assert_eq!(e.p700, 103);
        assert_eq!(profinet_alarm(e.p700), 359);
    }
}
