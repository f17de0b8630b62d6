//! The application layer state machine's registers: AL control (0120h), AL status (0130h) and
//! AL status code (0134h) (ETG.1000.6 "AL control" / "AL status" and table 11 "AL status
//! codes"; ETG.1000.4 register descriptions; ET1100 datasheet section II, registers
//! 0120h–0135h).
//!
//! The state set is [`EcState`] of `proto::nord::nmt` (BU 0620 §2.2.5): this module gives it
//! its wire codes (INIT 1, PRE-OP 2, BOOT 3, SAFE-OP 4, OP 8 — ETG.1000.6 "AL control") rather
//! than defining the states a second time. The registers keep the raw 4-bit state so that a tester
//! can request an undefined state (the slave must answer 0012h "unknown requested state").
//!
//! | AL control bits | | AL status bits | |
//! |---|---|---|---|
//! | 0–3 | requested state | 0–3 | actual state |
//! | 4 | error indication acknowledge | 4 | error indication (status code valid) |
//! | 5 | device identification request | 5 | device identification loaded |
//! | 8–15 | application specific | 8–15 | application specific |

use std::fmt;

pub use crate::nord::nmt::EcState;
use crate::wire::{Error, Reader};

/// The error flag (bit 4) of AL control (acknowledge) and AL status (error indication).
pub const ERROR_FLAG: u8 = 0x10;
/// The device identification bit (bit 5): request in AL control, loaded in AL status (Explicit
/// Device Identification, ETG.1020 §4; BU 0620 §2.2.4 "Hot Connect").
pub const DEVICE_ID_FLAG: u8 = 0x20;
/// Mask of the state bits 0–3.
pub const STATE_MASK: u8 = 0x0F;

impl EcState {
    /// The state's code in AL control/status bits 0–3 (ETG.1000.6 "AL control"): INIT 1,
    /// PRE-OP 2, BOOT 3, SAFE-OP 4, OP 8.
    pub const fn code(self) -> u8 {
        match self {
            EcState::Init => 1,
            EcState::PreOperational => 2,
            EcState::Bootstrap => 3,
            EcState::SafeOperational => 4,
            EcState::Operational => 8,
        }
    }

    /// The state of a 4-bit code (`None` for the undefined codes 0, 5–7, 9–15).
    pub fn from_code(code: u8) -> Option<EcState> {
        EcState::ALL.into_iter().find(|s| s.code() == code)
    }

    /// The abbreviation masters print (`"PRE-OP"`).
    pub fn short_name(self) -> &'static str {
        match self {
            EcState::Init => "INIT",
            EcState::PreOperational => "PRE-OP",
            EcState::Bootstrap => "BOOT",
            EcState::SafeOperational => "SAFE-OP",
            EcState::Operational => "OP",
        }
    }
}

/// Names a raw state code: the abbreviation, or the hex value of an undefined code.
pub fn state_name(code: u8) -> String {
    match EcState::from_code(code) {
        Some(s) => s.short_name().to_string(),
        None => format!("state {code:X}h"),
    }
}

/// AL control (0120h), written by the master.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AlControl {
    /// Requested state (bits 0–3; any value, defined or not).
    pub state: u8,
    /// Error indication acknowledge (bit 4).
    pub ack: bool,
    /// Device identification request (bit 5).
    pub device_id: bool,
    /// Application specific byte (bits 8–15).
    pub app: u8,
}

impl AlControl {
    /// A request for `state`, with or without acknowledging an error.
    pub fn request(state: EcState, ack: bool) -> Self {
        AlControl {
            state: state.code(),
            ack,
            ..AlControl::default()
        }
    }

    /// From the register word.
    pub fn from_word(w: u16) -> Self {
        let lo = w as u8;
        AlControl {
            state: lo & STATE_MASK,
            ack: lo & ERROR_FLAG != 0,
            device_id: lo & DEVICE_ID_FLAG != 0,
            app: (w >> 8) as u8,
        }
    }

    /// The register word (bits 6–7 are 0).
    pub fn to_word(self) -> u16 {
        u16::from(
            self.state & STATE_MASK
                | if self.ack { ERROR_FLAG } else { 0 }
                | if self.device_id { DEVICE_ID_FLAG } else { 0 },
        ) | u16::from(self.app) << 8
    }

    /// Parses the 2 register bytes.
    pub fn parse(bytes: &[u8]) -> Result<Self, Error> {
        let mut r = Reader::new(bytes);
        let w = r.u16("AL control")?;
        r.finish("AL control")?;
        Ok(AlControl::from_word(w))
    }

    /// The 2 register bytes.
    pub fn emit(self) -> [u8; 2] {
        self.to_word().to_le_bytes()
    }

    /// The requested state, if the code is defined.
    pub fn ec_state(self) -> Option<EcState> {
        EcState::from_code(self.state)
    }
}

/// AL status (0130h), written by the slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct AlStatus {
    /// Actual state (bits 0–3).
    pub state: u8,
    /// Error indication (bit 4): the slave refused a request or fell back; 0134h says why.
    pub error: bool,
    /// Device identification loaded (bit 5): 0134h holds the identification value.
    pub device_id: bool,
    /// Application specific byte (bits 8–15).
    pub app: u8,
}

impl AlStatus {
    /// A status in `state`, with or without the error indication.
    pub fn new(state: EcState, error: bool) -> Self {
        AlStatus {
            state: state.code(),
            error,
            ..AlStatus::default()
        }
    }

    /// From the register word.
    pub fn from_word(w: u16) -> Self {
        let lo = w as u8;
        AlStatus {
            state: lo & STATE_MASK,
            error: lo & ERROR_FLAG != 0,
            device_id: lo & DEVICE_ID_FLAG != 0,
            app: (w >> 8) as u8,
        }
    }

    /// The register word.
    pub fn to_word(self) -> u16 {
        u16::from(
            self.state & STATE_MASK
                | if self.error { ERROR_FLAG } else { 0 }
                | if self.device_id { DEVICE_ID_FLAG } else { 0 },
        ) | u16::from(self.app) << 8
    }

    /// Parses the 2 register bytes.
    pub fn parse(bytes: &[u8]) -> Result<Self, Error> {
        let mut r = Reader::new(bytes);
        let w = r.u16("AL status")?;
        r.finish("AL status")?;
        Ok(AlStatus::from_word(w))
    }

    /// Parses the 6 bytes from 0130h that masters read at once: AL status, 2 reserved bytes,
    /// AL status code.
    pub fn parse_with_code(bytes: &[u8]) -> Result<(Self, AlStatusCode), Error> {
        let mut r = Reader::new(bytes);
        let w = r.u16("AL status")?;
        r.bytes(2, "AL status reserved")?;
        let code = r.u16("AL status code")?;
        r.finish("AL status block")?;
        Ok((AlStatus::from_word(w), AlStatusCode(code)))
    }

    /// The 2 register bytes.
    pub fn emit(self) -> [u8; 2] {
        self.to_word().to_le_bytes()
    }

    /// The actual state, if the code is defined.
    pub fn ec_state(self) -> Option<EcState> {
        EcState::from_code(self.state)
    }
}

impl fmt::Display for AlStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&state_name(self.state))?;
        if self.error {
            f.write_str(" + error")?;
        }
        if self.device_id {
            f.write_str(" + device id")?;
        }
        Ok(())
    }
}

/// An AL status code (register 0134h; ETG.1000.6 table 11; open: unknown and vendor codes
/// 8000h–FFFFh are kept).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct AlStatusCode(pub u16);

macro_rules! al_codes {
    ($($name:ident = $v:literal, $text:literal;)*) => {
        impl AlStatusCode {
            $(
                #[doc = concat!($text, " (", stringify!($v), ").")]
                pub const $name: AlStatusCode = AlStatusCode($v);
            )*

            /// Every code ETG.1000.6 table 11 defines, with its name.
            pub const ALL: &'static [(AlStatusCode, &'static str)] = &[
                $((AlStatusCode($v), $text),)*
            ];
        }
    };
}

al_codes! {
    NO_ERROR = 0x0000, "No error";
    UNSPECIFIED = 0x0001, "Unspecified error";
    NO_MEMORY = 0x0002, "No memory";
    INVALID_DEVICE_SETUP = 0x0003, "Invalid device setup";
    RESERVED_0005 = 0x0005, "Reserved (compatibility)";
    INVALID_STATE_CHANGE = 0x0011, "Invalid requested state change";
    UNKNOWN_STATE = 0x0012, "Unknown requested state";
    BOOTSTRAP_NOT_SUPPORTED = 0x0013, "Bootstrap not supported";
    NO_VALID_FIRMWARE = 0x0014, "No valid firmware";
    INVALID_MAILBOX_BOOT = 0x0015, "Invalid mailbox configuration (BOOT)";
    INVALID_MAILBOX_PREOP = 0x0016, "Invalid mailbox configuration (PRE-OP)";
    INVALID_SM_CONFIG = 0x0017, "Invalid sync manager configuration";
    NO_VALID_INPUTS = 0x0018, "No valid inputs available";
    NO_VALID_OUTPUTS = 0x0019, "No valid outputs";
    SYNC_ERROR = 0x001A, "Synchronization error";
    SM_WATCHDOG = 0x001B, "Sync manager watchdog";
    INVALID_SM_TYPES = 0x001C, "Invalid sync manager types";
    INVALID_OUTPUT_CONFIG = 0x001D, "Invalid output configuration";
    INVALID_INPUT_CONFIG = 0x001E, "Invalid input configuration";
    INVALID_WATCHDOG_CONFIG = 0x001F, "Invalid watchdog configuration";
    NEEDS_COLD_START = 0x0020, "Slave needs cold start";
    NEEDS_INIT = 0x0021, "Slave needs INIT";
    NEEDS_PREOP = 0x0022, "Slave needs PRE-OP";
    NEEDS_SAFEOP = 0x0023, "Slave needs SAFE-OP";
    INVALID_INPUT_MAPPING = 0x0024, "Invalid input mapping";
    INVALID_OUTPUT_MAPPING = 0x0025, "Invalid output mapping";
    INCONSISTENT_SETTINGS = 0x0026, "Inconsistent settings";
    FREERUN_NOT_SUPPORTED = 0x0027, "Free-run not supported";
    SYNC_NOT_SUPPORTED = 0x0028, "Synchronization not supported";
    FREERUN_NEEDS_3BUFFER = 0x0029, "Free-run needs 3-buffer mode";
    BACKGROUND_WATCHDOG = 0x002A, "Background watchdog";
    NO_VALID_IO = 0x002B, "No valid inputs and outputs";
    FATAL_SYNC_ERROR = 0x002C, "Fatal sync error";
    NO_SYNC_ERROR = 0x002D, "No sync error";
    INVALID_INPUT_FMMU = 0x002E, "Invalid input FMMU configuration";
    INVALID_DC_SYNC = 0x0030, "Invalid DC SYNC configuration";
    INVALID_DC_LATCH = 0x0031, "Invalid DC latch configuration";
    PLL_ERROR = 0x0032, "PLL error";
    DC_SYNC_IO_ERROR = 0x0033, "DC sync IO error";
    DC_SYNC_TIMEOUT = 0x0034, "DC sync timeout error";
    DC_INVALID_CYCLE = 0x0035, "DC invalid sync cycle time";
    DC_INVALID_SYNC0 = 0x0036, "DC invalid SYNC0 cycle time";
    DC_INVALID_SYNC1 = 0x0037, "DC invalid SYNC1 cycle time";
    MBX_AOE = 0x0041, "Mailbox AoE error";
    MBX_EOE = 0x0042, "Mailbox EoE error";
    MBX_COE = 0x0043, "Mailbox CoE error";
    MBX_FOE = 0x0044, "Mailbox FoE error";
    MBX_SOE = 0x0045, "Mailbox SoE error";
    MBX_VOE = 0x004F, "Mailbox VoE error";
    EEPROM_NO_ACCESS = 0x0050, "EEPROM no access";
    EEPROM_ERROR = 0x0051, "EEPROM error";
    RESTARTED_LOCALLY = 0x0060, "Slave restarted locally";
    DEVICE_ID_UPDATED = 0x0061, "Device identification value updated";
    APPLICATION_CONTROLLER = 0x00F0, "Application controller available";
}

impl AlStatusCode {
    /// The code's name, if ETG.1000.6 table 11 defines it.
    pub fn name(self) -> Option<&'static str> {
        AlStatusCode::ALL
            .iter()
            .find(|(c, _)| *c == self)
            .map(|(_, n)| *n)
    }

    /// Vendor-specific range 8000h–FFFFh.
    pub fn is_vendor_specific(self) -> bool {
        self.0 >= 0x8000
    }
}

impl fmt::Display for AlStatusCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "{:04X}h ({n})", self.0),
            None if self.is_vendor_specific() => write!(f, "{:04X}h (vendor specific)", self.0),
            None => write!(f, "{:04X}h", self.0),
        }
    }
}

impl fmt::Debug for AlStatusCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AlStatusCode({:04X}h)", self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_codes() {
        let codes: Vec<u8> = EcState::ALL.iter().map(|s| s.code()).collect();
        assert_eq!(codes, [1, 2, 4, 8, 3]);
        for s in EcState::ALL {
            assert_eq!(EcState::from_code(s.code()), Some(s));
        }
        for undefined in [0, 5, 6, 7, 9, 15] {
            assert_eq!(EcState::from_code(undefined), None);
        }
        assert_eq!(state_name(4), "SAFE-OP");
        assert_eq!(state_name(5), "state 5h");
    }

    #[test]
    fn al_control_word() {
        // 0120h = 0x0012: request PRE-OP, acknowledge the error.
        let c = AlControl::parse(&[0x12, 0x00]).unwrap();
        assert_eq!(c, AlControl::request(EcState::PreOperational, true));
        assert_eq!(c.ec_state(), Some(EcState::PreOperational));
        assert_eq!(c.emit(), [0x12, 0x00]);
        // An undefined state is kept, the device-id request and the app byte too.
        let c = AlControl::from_word(0xAB25);
        assert_eq!((c.state, c.ack, c.device_id, c.app), (5, false, true, 0xAB));
        assert_eq!(c.ec_state(), None);
        assert_eq!(c.to_word(), 0xAB25);
        assert!(matches!(
            AlControl::parse(&[1]),
            Err(Error::Truncated { .. })
        ));
        assert!(matches!(
            AlControl::parse(&[1, 0, 0]),
            Err(Error::Trailing { .. })
        ));
    }

    #[test]
    fn al_status_block() {
        let b = [
            0x14, 0x00, // AL status: SAFE-OP + error
            0x00, 0x00, // reserved
            0x1B, 0x00, // AL status code 001Bh: SM watchdog
        ];
        let (s, code) = AlStatus::parse_with_code(&b).unwrap();
        assert_eq!(s, AlStatus::new(EcState::SafeOperational, true));
        assert_eq!(code, AlStatusCode::SM_WATCHDOG);
        assert_eq!(s.to_string(), "SAFE-OP + error");
        assert_eq!(s.emit(), [0x14, 0x00]);
        for n in 0..6 {
            assert!(matches!(
                AlStatus::parse_with_code(&b[..n]),
                Err(Error::Truncated { .. })
            ));
        }
        assert_eq!(AlStatus::parse(&b[..2]).unwrap(), s);
        assert_eq!(AlStatus::from_word(0x0028).to_string(), "OP + device id");
    }

    #[test]
    fn status_codes() {
        assert_eq!(
            AlStatusCode::INVALID_STATE_CHANGE.to_string(),
            "0011h (Invalid requested state change)"
        );
        assert_eq!(
            AlStatusCode(0x0016).name(),
            Some("Invalid mailbox configuration (PRE-OP)")
        );
        assert_eq!(AlStatusCode(0x0099).to_string(), "0099h");
        assert_eq!(AlStatusCode(0x8001).to_string(), "8001h (vendor specific)");
        assert_eq!(format!("{:?}", AlStatusCode(0x1B)), "AlStatusCode(001Bh)");
        // Table 11 has no duplicates and is sorted.
        let mut v: Vec<u16> = AlStatusCode::ALL.iter().map(|(c, _)| c.0).collect();
        let n = v.len();
        v.dedup();
        assert_eq!(v.len(), n);
        assert!(v.windows(2).all(|w| w[0] < w[1]));
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn al_control_round_trips(state in 0..=STATE_MASK, ack in any::<bool>(), device_id in any::<bool>(), app in any::<u8>()) {
                let c = AlControl { state, ack, device_id, app };
                prop_assert_eq!(AlControl::parse(&c.emit()), Ok(c));
            }

            #[test]
            fn al_status_round_trips(state in 0..=STATE_MASK, error in any::<bool>(), device_id in any::<bool>(), app in any::<u8>()) {
                let s = AlStatus { state, error, device_id, app };
                prop_assert_eq!(AlStatus::parse(&s.emit()), Ok(s));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..8)) {
                let _ = AlControl::parse(&bytes);
                let _ = AlStatus::parse(&bytes);
                let _ = AlStatus::parse_with_code(&bytes);
            }
        }
    }
}
