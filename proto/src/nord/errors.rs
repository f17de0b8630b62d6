//! Error tables: inverter communication errors (P700) with their DS402 codes, PROFINET alarm
//! numbers, POWERLINK error codes, and the SDO abort codes of EtherCAT and POWERLINK (which
//! differ).

use std::fmt;

use super::mutant::{Constant, Row, Table};
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
pub static COMM_ERRORS: Table<CommError> = Table::new(
    "comm-errors",
    "BU 0620 §5.3 error messages, general communication errors",
    &[
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
    ],
);

/// The PROFINET diagnostic alarm of an inverter error: 100h + P700 value (BU 0620 §5.4.2: E10.3
/// → "359 (100h + 103 = 256 + 103)").
pub fn profinet_alarm(p700: u16) -> u16 {
    PROFINET_ALARM_BASE.get() + p700
}

/// The 100h an inverter error's PROFINET alarm adds to its P700 number.
pub static PROFINET_ALARM_BASE: Constant<u16> = Constant::new(
    "profinet-alarm-base",
    0x100,
    "PROFINET alarm offset",
    "BU 0620 §5.4.2 PROFINET diagnostic alarms",
);

/// The error number reported when an inverter on the system bus is lost (BU 0620 §5.4.2
/// "Information": alarm 256 + 1000 = 1256).
pub static LOST_INVERTER: Constant<u16> = Constant::new(
    "lost-inverter",
    1000,
    "error number of a lost inverter",
    "BU 0620 §5.4.2 PROFINET diagnostic alarms",
);

/// An SDO abort code (open: unknown codes are kept).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct SdoAbort(pub u32);

/// BU 0620 §2.2.7.2 (p. 21): EtherCAT SDO error codes.
pub static ETHERCAT_ABORTS: Table<(u32, &str)> = Table::new(
    "ethercat-aborts",
    "BU 0620 §2.2.7.2 EtherCAT SDO error codes",
    &[
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
    ],
);

/// BU 0620 §2.4.7 (p. 38): POWERLINK SDO error codes (EPSG DS-301).
pub static POWERLINK_ABORTS: Table<(u32, &str)> = Table::new(
    "powerlink-aborts",
    "BU 0620 §2.4.7 POWERLINK SDO error codes",
    &[
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
    ],
);

impl SdoAbort {
    /// The manual's description for the protocol, if its list has the code.
    pub fn describe(self, protocol: Protocol) -> Option<&'static str> {
        let list = match protocol {
            Protocol::Ethercat => &*ETHERCAT_ABORTS,
            Protocol::Powerlink => &*POWERLINK_ABORTS,
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

/// One row of "Allocation of frequency inverter error codes" (BU 0620 §5.4.1.2, p. 96–97):
/// the DS-301 error code and error register ("error index") POWERLINK reports for P700 errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlError {
    /// DS-301 error code.
    pub code: u16,
    /// Error register value (1 generic, 3 current, 5 voltage, 9 temperature, 17 communication,
    /// 129 manufacturer specific).
    pub register: u8,
    /// P700 errors (tenths: 10.3 → 103) as inclusive ranges.
    pub p700: &'static [(u16, u16)],
    /// Meaning.
    pub text: &'static str,
}

const fn pl(code: u16, register: u8, p700: &'static [(u16, u16)], text: &'static str) -> PlError {
    PlError {
        code,
        register,
        p700,
        text,
    }
}

/// §5.4.1.2 table. The first row prints "1000h, error index 0, P700 0: No error"; the table's
/// own error groups ("00xxh No error", "10xxh Undefined error type") and CiA 301's emergency
/// error codes (0000h "error reset or no error", 1000h "generic error") say no error is
/// 0000h, so the row is kept as 0000h (the case `tables-error-rows/no-error-is-0000h` records
/// the printed value). The second 1000h row (error index 1) has no P700 number: the error
/// must be read from P700. Rows 7332h, 7334h, 8612h and 8711h print no meaning of their own:
/// the meaning stands in a cell merged with the row above (the extractions of BU 0620 and of
/// BU 2200 §8.3.2, whose table is row for row the same, place it between the two rows).
pub static POWERLINK_ERRORS: Table<PlError> = Table::new(
    "powerlink-errors",
    "BU 0620 §5.4.1.2 allocation of frequency inverter error codes",
    &[
        pl(0x0000, 0, &[(0, 0)], "No error"),
        pl(
            0x1000,
            1,
            &[],
            "The error number must be read out via parameter P700 or an actual value.",
        ),
        pl(
            0x2200,
            3,
            &[(40, 41)],
            "Overcurrent frequency inverter/current measurement",
        ),
        pl(0x2310, 3, &[(30, 30)], "Overcurrent I2t-limit"),
        pl(0x2311, 3, &[(32, 32)], "IGBT overcurrent 125 %"),
        pl(0x2312, 3, &[(33, 33)], "IGBT overcurrent 150 %"),
        pl(0x3110, 5, &[(51, 51)], "Mains voltage too high"),
        pl(0x3120, 5, &[(61, 61)], "Mains voltage too low"),
        pl(0x3130, 5, &[(70, 70)], "Mains connection failure"),
        pl(0x3210, 5, &[(50, 50)], "Link circuit voltage too high"),
        pl(0x3230, 5, &[(60, 60)], "Link circuit voltage too low"),
        pl(
            0x4210,
            9,
            &[(11, 11)],
            "Overtemperature in frequency inverter",
        ),
        pl(0x4310, 9, &[(20, 22)], "Motor overtemperature"),
        pl(
            0x5000,
            1,
            &[(108, 108)],
            "Bus interface communication error",
        ),
        pl(0x5110, 1, &[(110, 110)], "External bus error"),
        pl(0x5300, 1, &[(170, 170)], "EMC fault"),
        pl(0x5510, 1, &[(200, 200)], "Reserved"),
        pl(0x5520, 1, &[(208, 208)], "EEPROM error"),
        pl(0x5530, 1, &[(82, 82)], "External copy error"),
        pl(
            0x6000,
            1,
            &[(150, 158), (201, 207), (213, 213)],
            "System error",
        ),
        pl(
            0x6310,
            1,
            &[(80, 80)],
            "Parameter loss (maximum EEPROM value exceeded)",
        ),
        pl(0x7112, 3, &[(31, 31)], "Brake chopper overcurrent"),
        pl(0x7120, 1, &[(160, 161)], "Motor error"),
        pl(0x7300, 1, &[(143, 143)], "Absolute encoder error"),
        pl(0x7305, 1, &[(130, 130)], "Encoder error"),
        pl(0x7306, 1, &[(144, 144)], "Absolute encoder error"),
        pl(0x7310, 1, &[(145, 145)], "Position difference"),
        pl(0x7320, 1, &[(146, 148)], "Position error"),
        pl(0x7330, 1, &[(250, 250)], "Position deviation"),
        pl(
            0x7331,
            1,
            &[(251, 251)],
            "Universal encoder communication error",
        ),
        pl(
            0x7332,
            1,
            &[(252, 252)],
            "Universal encoder communication error",
        ),
        pl(0x7333, 1, &[(253, 253)], "Universal encoder error"),
        pl(0x7334, 1, &[(254, 254)], "Universal encoder error"),
        pl(0x8100, 17, &[(100, 102)], "Bus timeout"),
        pl(
            0x8111,
            17,
            &[(103, 107), (109, 109)],
            "Bus interface communication error",
        ),
        pl(0x8300, 1, &[(132, 132)], "Slip error switch-off monitoring"),
        pl(0x8400, 1, &[(131, 131)], "Speed slip error"),
        pl(0x8600, 1, &[(140, 141)], "Reference point error"),
        pl(0x8612, 1, &[(142, 142)], "Reference point error"),
        pl(0x8710, 1, &[(135, 135)], "Acceleration path error"),
        pl(0x8711, 1, &[(136, 136)], "Acceleration path error"),
        pl(0x9000, 1, &[(120, 122)], "External watchdog"),
        pl(0xFF10, 129, &[(180, 180)], "Reserved"),
        pl(0xFF11, 129, &[(190, 190)], "Connected motor not identified"),
    ],
);

/// The POWERLINK error row of a P700 error (tenths).
pub fn powerlink_error(p700: u16) -> Option<&'static PlError> {
    POWERLINK_ERRORS
        .iter()
        .find(|e| e.p700.iter().any(|(lo, hi)| (*lo..=*hi).contains(&p700)))
}

/// The rows of a DS-301 error code.
pub fn powerlink_rows(code: u16) -> impl Iterator<Item = &'static PlError> {
    POWERLINK_ERRORS.iter().filter(move |e| e.code == code)
}

/// The extended error P700 [-04] shows for a present error (tenths): the DS402 code of
/// §5.3's table ("DS402: Extended error number", its first row where several share the
/// P700 number), else the error's code of §5.4.1.2's allocation table, else 0.
pub fn extended_code(p700: u16) -> u16 {
    COMM_ERRORS
        .iter()
        .find(|e| e.p700 == p700)
        .map(|e| e.ds402)
        .or_else(|| powerlink_error(p700).map(|e| e.code))
        .unwrap_or(0)
}

/// The bus interface's own errors in P170 of the modules, in tenths (102.0 → 1020), with their
/// meaning: BU 2200 §8.4 (p. 67), BU 2100 §8.3. Ranges are inclusive. BU 2200 prints "560.1
/// Allgemeiner Netzwerkfehler" inside its own 560.0…560.9 "Interner Fehler"; BU 2100 prints
/// 561.0, which the 561.x network group (watchdog, cable, IP address) confirms: 561.0 here.
pub static MODULE_ERRORS: Table<(u16, u16, &str)> = Table::new(
    "module-errors",
    "BU 2200 §8.4 and BU 2100 §8.3 bus interface errors (P170)",
    &[
        (1000, 1000, "EEPROM error"),
        (1020, 1020, "Bus timeout P151"),
        (1030, 1030, "System bus off"),
        (1040, 1040, "Overtemperature bus interface"),
        (5501, 5501, "DIP switch error"),
        (5600, 5609, "Internal error"),
        (5610, 5610, "General network error"),
        (5611, 5611, "Ethernet watchdog timeout"),
        (5612, 5612, "Bus cable fault"),
        (5613, 5613, "IP address error"),
        (5630, 5630, "Firmware version incompatible"),
        (5640, 5640, "MAC address error"),
    ],
);

/// The inverter's errors caused by a POWERLINK bus interface (E010, P700 in tenths): BU 2200
/// §8.4 (p. 67).
pub static POWERLINK_MODULE_E10: Table<(u16, &str)> = Table::new(
    "powerlink-module-e10",
    "BU 2200 §8.4 inverter errors caused by the bus interface (E010)",
    &[
        (100, "Connection error"),
        (101, "Temperature too high"),
        (102, "Timeout POWERLINK watchdog"),
        (103, "Timeout by P151/P513"),
        (104, "IP address error"),
        (105, "Internal error"),
        (106, "Bus cable fault"),
        (108, "Connection error timeout (SK TU3-POL)"),
        (
            109,
            "Connection error timeout between inverter and bus interface (SK CU4/TU4-POL)",
        ),
    ],
);

impl Row for CommError {
    fn changes(&self) -> Vec<(&'static str, String, CommError)> {
        vec![
            (
                "ds402",
                format!(
                    "{} DS402 {:04X}h → {:04X}h",
                    self.text,
                    self.ds402,
                    self.ds402 + 1
                ),
                CommError {
                    ds402: self.ds402 + 1,
                    ..*self
                },
            ),
            (
                "p700",
                format!(
                    "{} P700 {} → {}",
                    self.text,
                    tenths(self.p700),
                    tenths(self.p700 + 1)
                ),
                CommError {
                    p700: self.p700 + 1,
                    ..*self
                },
            ),
        ]
    }
}

/// An SDO abort code and its meaning.
impl Row for (u32, &'static str) {
    fn changes(&self) -> Vec<(&'static str, String, Self)> {
        vec![(
            "code",
            format!("{} {:08X}h → {:08X}h", self.1, self.0, self.0 + 1),
            (self.0 + 1, self.1),
        )]
    }
}

impl Row for PlError {
    fn changes(&self) -> Vec<(&'static str, String, PlError)> {
        vec![
            (
                "code",
                format!(
                    "{} {:04X}h → {:04X}h",
                    self.text,
                    self.code,
                    u32::from(self.code) + 1
                ),
                PlError {
                    code: self.code.wrapping_add(1),
                    ..*self
                },
            ),
            (
                "register",
                format!(
                    "{} error register {} → {}",
                    self.text,
                    self.register,
                    self.register + 1
                ),
                PlError {
                    register: self.register + 1,
                    ..*self
                },
            ),
        ]
    }
}

/// A module error range (P170) and its meaning: the range moved up by one.
impl Row for (u16, u16, &'static str) {
    fn changes(&self) -> Vec<(&'static str, String, Self)> {
        vec![(
            "number",
            format!("{} {} → {}", self.2, tenths(self.0), tenths(self.0 + 1)),
            (self.0 + 1, self.1 + 1, self.2),
        )]
    }
}

/// An inverter error (E010, P700) and its meaning.
impl Row for (u16, &'static str) {
    fn changes(&self) -> Vec<(&'static str, String, Self)> {
        vec![(
            "number",
            format!("{} {} → {}", self.1, tenths(self.0), tenths(self.0 + 1)),
            (self.0 + 1, self.1),
        )]
    }
}

/// An error number in tenths as the manuals print it: 103 → "10.3".
fn tenths(n: u16) -> String {
    super::scaling::from_raw(i64::from(n), 1)
}

/// The meaning of a module's P170 error (tenths).
pub fn module_error(p170: u16) -> Option<&'static str> {
    MODULE_ERRORS
        .iter()
        .find(|(lo, hi, _)| (*lo..=*hi).contains(&p170))
        .map(|(_, _, t)| *t)
}

/// DS-301 error group of a code (§5.4.1.2 "Error Groups").
pub fn error_group(code: u16) -> &'static str {
    if code == 0xFF00 || code >= 0xFF00 {
        return "Specific to device";
    }
    match code >> 12 {
        0 => "No error",
        1 => "Undefined error type",
        2 => "Current error",
        3 => "Voltage error",
        4 => "Temperature error",
        5 => "Hardware error",
        6 => "Software error",
        7 => "Additional module",
        8 => "Communication",
        9 => "External error",
        _ => "Not a DS-301 group",
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
    fn powerlink_codes_of_p700_errors() {
        assert_eq!(
            powerlink_error(103).map(|e| (e.code, e.register)),
            Some((0x8111, 17))
        );
        assert_eq!(powerlink_error(108).map(|e| e.code), Some(0x5000));
        assert_eq!(powerlink_error(205).map(|e| e.code), Some(0x6000));
        assert_eq!(powerlink_error(999), None);
        assert_eq!(error_group(0x8111), "Communication");
        assert_eq!(error_group(0xFF11), "Specific to device");
        // The rows that print no meaning, and no error as 0000h (CiA 301: 00xxh).
        for (p700, code) in [(252, 0x7332), (254, 0x7334), (142, 0x8612), (136, 0x8711)] {
            assert_eq!(
                powerlink_error(p700).map(|e| (e.code, e.register)),
                Some((code, 1))
            );
        }
        assert_eq!(
            powerlink_error(0).map(|e| (e.code, e.register)),
            Some((0, 0))
        );
        assert_eq!(
            powerlink_rows(0x1000)
                .map(|e| e.register)
                .collect::<Vec<_>>(),
            [1]
        );
    }

    #[test]
    fn extended_codes_of_p700() {
        assert_eq!(extended_code(103), 0x7592);
        assert_eq!(extended_code(102), 0x7591);
        assert_eq!(extended_code(105), 0x7594);
        assert_eq!(extended_code(30), 0x2310);
        assert_eq!(extended_code(0), 0);
        assert_eq!(extended_code(999), 0);
    }

    #[test]
    fn p513_timeout_alarm() {
        let e = COMM_ERRORS.iter().find(|e| e.ds402 == 0x7592).unwrap();
        assert_eq!(e.p700, 103);
        assert_eq!(profinet_alarm(e.p700), 359);
        assert_eq!(profinet_alarm(LOST_INVERTER.get()), 1256);
    }

    #[test]
    fn module_errors_in_tenths() {
        // BU 2200 §8.4: 102.0 bus timeout, 561.3 IP address twice; 560.x internal.
        assert_eq!(module_error(1020), Some("Bus timeout P151"));
        assert_eq!(module_error(5613), Some("IP address error"));
        assert_eq!(module_error(5601), Some("Internal error"));
        assert_eq!(module_error(5610), Some("General network error"));
        assert_eq!(module_error(5620), None);
    }
}
