//! The PNIO status (IEC 61158-6-10 "PNIOStatus"): four bytes — ErrorCode, ErrorDecode,
//! ErrorCode1, ErrorCode2 — in every RPC response, every response block and every alarm
//! acknowledge. All zero is "OK".

/// A PNIO status as it travels: ErrorCode, ErrorDecode, ErrorCode1, ErrorCode2.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct PnioStatus {
    /// 81h "PNIO" for the CM services, DFh / DEh for record-service errors of IODWrite /
    /// IODRead, CFh Alarm ack, 00h none.
    pub code: u8,
    /// 80h "PNIORW" (record services, ErrorCode1 from the application), 81h "PNIO"
    /// (ErrorCode1 = the block or service in error).
    pub decode: u8,
    /// With PNIORW: the error class (high nibble) and code (low nibble); with PNIO: the block.
    pub code1: u8,
    /// With PNIORW: user specific; with PNIO: the field in error.
    pub code2: u8,
}

impl PnioStatus {
    /// No error.
    pub const OK: PnioStatus = PnioStatus::new(0, 0, 0, 0);
    /// ErrorCode "PNIO" (81h).
    pub const CODE_PNIO: u8 = 0x81;
    /// ErrorCode of an IODRead error (DEh "IODReadRes").
    pub const CODE_READ: u8 = 0xDE;
    /// ErrorCode of an IODWrite error (DFh "IODWriteRes").
    pub const CODE_WRITE: u8 = 0xDF;
    /// ErrorDecode "PNIORW": ErrorCode1 is a record-service error class/code.
    pub const DECODE_PNIORW: u8 = 0x80;
    /// ErrorDecode "PNIO": ErrorCode1 names the block or service, ErrorCode2 the field.
    pub const DECODE_PNIO: u8 = 0x81;

    /// A status from its four bytes.
    pub const fn new(code: u8, decode: u8, code1: u8, code2: u8) -> PnioStatus {
        PnioStatus {
            code,
            decode,
            code1,
            code2,
        }
    }

    /// An IODRead (`write == false`) or IODWrite record-service error, PNIORW class/code in
    /// ErrorCode1 (e.g. B0h "invalid index", B6h "access denied", B8h "invalid parameter").
    pub const fn record(write: bool, code1: u8) -> PnioStatus {
        let code = if write {
            Self::CODE_WRITE
        } else {
            Self::CODE_READ
        };
        PnioStatus::new(code, Self::DECODE_PNIORW, code1, 0)
    }

    /// A CM error of `service` (an ErrorCode of [`cm`]): ErrorCode1 the block or protocol
    /// machine in error, ErrorCode2 the field or reason.
    pub const fn cm(service: u8, code1: u8, code2: u8) -> PnioStatus {
        PnioStatus::new(service, Self::DECODE_PNIO, code1, code2)
    }

    /// The four bytes, as they travel.
    pub const fn to_bytes(self) -> [u8; 4] {
        [self.code, self.decode, self.code1, self.code2]
    }

    /// From the four bytes as they travel.
    pub const fn from_bytes(b: [u8; 4]) -> PnioStatus {
        PnioStatus::new(b[0], b[1], b[2], b[3])
    }

    /// Whether it is "OK".
    pub fn is_ok(self) -> bool {
        self == PnioStatus::OK
    }

    /// What the four bytes say, as far as IEC 61158-6-10's tables name them (ErrorCode,
    /// ErrorDecode, then ErrorCode1 and ErrorCode2 as the decode reads them), for a verdict:
    /// "DB 81 40 06: IODConnectRes, PNIO: CMRPC: state conflict". A value the tables here do
    /// not name is left as its hex value.
    pub fn meaning(self) -> String {
        let [code, decode, code1, code2] = self.to_bytes();
        let hex = format!("{code:02X} {decode:02X} {code1:02X} {code2:02X}");
        if self.is_ok() {
            return format!("{hex}: OK");
        }
        let named = |name: Option<&str>, v: u8| name.map_or(format!("{v:02X}h"), str::to_string);
        let mut parts = vec![
            named(error_code_name(code), code),
            named(error_decode_name(decode), decode),
        ];
        match decode {
            Self::DECODE_PNIO => {
                parts.push(named(cm::code1_name(code1), code1));
                if code1 == cm::CMRPC {
                    parts.push(named(cm::cmrpc_name(code2), code2));
                } else {
                    parts.push(format!("field {code2}"));
                }
            }
            Self::DECODE_PNIORW => parts.push(named(pniorw::name(code1), code1)),
            _ => {}
        }
        format!("{hex}: {}", parts.join(": ").replacen(": ", ", ", 1))
    }
}

/// The service an ErrorCode names (IEC 61158-6-10 "ErrorCode").
fn error_code_name(code: u8) -> Option<&'static str> {
    Some(match code {
        PnioStatus::CODE_PNIO => "PNIO",
        0xCF => "RTA error",
        0xDA => "AlarmAck",
        cm::CONNECT => "IODConnectRes",
        cm::RELEASE => "IODReleaseRes",
        cm::CONTROL => "IODControlRes",
        PnioStatus::CODE_READ => "IODReadRes",
        PnioStatus::CODE_WRITE => "IODWriteRes",
        _ => return None,
    })
}

/// What an ErrorDecode says ErrorCode1 and ErrorCode2 are.
fn error_decode_name(decode: u8) -> Option<&'static str> {
    Some(match decode {
        PnioStatus::DECODE_PNIORW => "PNIORW",
        PnioStatus::DECODE_PNIO => "PNIO",
        0x82 => "manufacturer specific",
        _ => return None,
    })
}

impl std::fmt::Display for PnioStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "PNIO status {:02X} {:02X} {:02X} {:02X}",
            self.code, self.decode, self.code1, self.code2
        )
    }
}

/// PNIORW ErrorCode1 values (class in the high nibble, code in the low one) that a NORD
/// device's record services give (IEC 61158-6-10 "ErrorCode1 with ErrorDecode PNIORW").
pub mod pniorw {
    /// Class Ah "application", code 0: read error.
    pub const READ_ERROR: u8 = 0xA0;
    /// Class Ah, code 1: write error.
    pub const WRITE_ERROR: u8 = 0xA1;
    /// Class Ah, code 9: feature not supported.
    pub const FEATURE_NOT_SUPPORTED: u8 = 0xA9;
    /// Class Bh "access", code 0: invalid index.
    pub const INVALID_INDEX: u8 = 0xB0;
    /// Class Bh, code 1: write length error.
    pub const WRITE_LENGTH: u8 = 0xB1;
    /// Class Bh, code 2: invalid slot/subslot.
    pub const INVALID_SLOT: u8 = 0xB2;
    /// Class Bh, code 5: state conflict — PROFIdrive devices answer a read of a parameter
    /// response that is not ready yet with it, the "Read Response (−)" of BU 0620 §2.5.6.1.
    pub const STATE_CONFLICT: u8 = 0xB5;
    /// Class Bh, code 6: access denied.
    pub const ACCESS_DENIED: u8 = 0xB6;
    /// Class Bh, code 7: invalid range.
    pub const INVALID_RANGE: u8 = 0xB7;
    /// Class Bh, code 8: invalid parameter.
    pub const INVALID_PARAMETER: u8 = 0xB8;
    /// Class Ch "resource", code 2: resource busy.
    pub const RESOURCE_BUSY: u8 = 0xC2;
    /// Class Ch, code 3: resource unavailable.
    pub const RESOURCE_UNAVAILABLE: u8 = 0xC3;

    /// The name of an ErrorCode1 above.
    pub(super) fn name(code1: u8) -> Option<&'static str> {
        Some(match code1 {
            READ_ERROR => "read error",
            WRITE_ERROR => "write error",
            FEATURE_NOT_SUPPORTED => "feature not supported",
            INVALID_INDEX => "invalid index",
            WRITE_LENGTH => "write length error",
            INVALID_SLOT => "invalid slot/subslot",
            STATE_CONFLICT => "state conflict",
            ACCESS_DENIED => "access denied",
            INVALID_RANGE => "invalid range",
            INVALID_PARAMETER => "invalid parameter",
            RESOURCE_BUSY => "resource busy",
            RESOURCE_UNAVAILABLE => "resource unavailable",
            _ => return None,
        })
    }
}

/// The PNIO status of the context-management services (IEC 61158-6-10 "ErrorCode",
/// "ErrorCode1 with ErrorDecode PNIO", "ErrorCode2" of CMRPC): a refused Connect, Control or
/// Release names the service, the block and the field in error.
pub mod cm {
    /// ErrorCode of an IODConnectRes.
    pub const CONNECT: u8 = 0xDB;
    /// ErrorCode of an IODReleaseRes.
    pub const RELEASE: u8 = 0xDC;
    /// ErrorCode of an IODControlRes.
    pub const CONTROL: u8 = 0xDD;
    /// ErrorCode1: faulty ARBlockReq (ErrorCode2: the field, BlockType = 0).
    pub const FAULTY_AR_BLOCK: u8 = 0x01;
    /// ErrorCode1: faulty IOCRBlockReq.
    pub const FAULTY_IOCR_BLOCK: u8 = 0x02;
    /// ErrorCode1: faulty ExpectedSubmoduleBlockReq.
    pub const FAULTY_EXPECTED_SUBMODULE_BLOCK: u8 = 0x03;
    /// ErrorCode1: faulty AlarmCRBlockReq.
    pub const FAULTY_ALARM_CR_BLOCK: u8 = 0x04;
    /// ErrorCode1: faulty IODControlReq (ControlBlockConnect).
    pub const FAULTY_CONTROL_BLOCK: u8 = 0x14;
    /// ErrorCode1: faulty IODReleaseReq (ControlBlockRelease).
    pub const FAULTY_RELEASE_BLOCK: u8 = 0x15;
    /// ErrorCode1: the CMRPC protocol machine; ErrorCode2 one of the `CMRPC_*` values.
    pub const CMRPC: u8 = 0x40;
    /// CMRPC: ArgsLength invalid.
    pub const CMRPC_ARGS_LENGTH: u8 = 0;
    /// CMRPC: unknown blocks.
    pub const CMRPC_UNKNOWN_BLOCKS: u8 = 1;
    /// CMRPC: IOCR missing.
    pub const CMRPC_IOCR_MISSING: u8 = 2;
    /// CMRPC: wrong AlarmCRBlock count.
    pub const CMRPC_ALARM_CR_COUNT: u8 = 3;
    /// CMRPC: out of AR resources (another AR holds the device).
    pub const CMRPC_OUT_OF_AR: u8 = 4;
    /// CMRPC: AR UUID unknown.
    pub const CMRPC_AR_UNKNOWN: u8 = 5;
    /// CMRPC: state conflict.
    pub const CMRPC_STATE_CONFLICT: u8 = 6;

    /// The name of an ErrorCode1 above (with ErrorDecode PNIO).
    pub(super) fn code1_name(code1: u8) -> Option<&'static str> {
        Some(match code1 {
            FAULTY_AR_BLOCK => "faulty ARBlockReq",
            FAULTY_IOCR_BLOCK => "faulty IOCRBlockReq",
            FAULTY_EXPECTED_SUBMODULE_BLOCK => "faulty ExpectedSubmoduleBlockReq",
            FAULTY_ALARM_CR_BLOCK => "faulty AlarmCRBlockReq",
            FAULTY_CONTROL_BLOCK => "faulty IODControlReq",
            FAULTY_RELEASE_BLOCK => "faulty IODReleaseReq",
            CMRPC => "CMRPC",
            _ => return None,
        })
    }

    /// The name of a CMRPC ErrorCode2 above.
    pub(super) fn cmrpc_name(code2: u8) -> Option<&'static str> {
        Some(match code2 {
            CMRPC_ARGS_LENGTH => "ArgsLength invalid",
            CMRPC_UNKNOWN_BLOCKS => "unknown blocks",
            CMRPC_IOCR_MISSING => "IOCR missing",
            CMRPC_ALARM_CR_COUNT => "wrong AlarmCRBlock count",
            CMRPC_OUT_OF_AR => "out of AR resources",
            CMRPC_AR_UNKNOWN => "AR UUID unknown",
            CMRPC_STATE_CONFLICT => "state conflict",
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statuses_travel_as_four_bytes() {
        // DF 80 B0 00: IODWrite, PNIORW, "invalid index".
        let s = PnioStatus::record(true, pniorw::INVALID_INDEX);
        assert_eq!(s.to_bytes(), [0xDF, 0x80, 0xB0, 0x00]);
        assert_eq!(PnioStatus::from_bytes(s.to_bytes()), s);
        assert!(!s.is_ok());
        assert!(PnioStatus::OK.is_ok());
        assert_eq!(s.to_string(), "PNIO status DF 80 B0 00");
        // DB 81 40 04: Connect refused by CMRPC, out of AR resources.
        assert_eq!(
            PnioStatus::cm(cm::CONNECT, cm::CMRPC, cm::CMRPC_OUT_OF_AR).to_bytes(),
            [0xDB, 0x81, 0x40, 0x04]
        );
    }

    #[test]
    fn a_status_says_what_its_bytes_mean() {
        for (bytes, says) in [
            ([0, 0, 0, 0], "00 00 00 00: OK"),
            (
                [0xDB, 0x81, 0x40, 0x06],
                "DB 81 40 06: IODConnectRes, PNIO: CMRPC: state conflict",
            ),
            // A faulty block names the field by its number.
            (
                [0xDB, 0x81, 0x02, 0x10],
                "DB 81 02 10: IODConnectRes, PNIO: faulty IOCRBlockReq: field 16",
            ),
            (
                [0xDF, 0x80, 0xB0, 0x00],
                "DF 80 B0 00: IODWriteRes, PNIORW: invalid index",
            ),
            // Values the tables here do not name stay hex.
            (
                [0x12, 0x81, 0x77, 0x09],
                "12 81 77 09: 12h, PNIO: 77h: field 9",
            ),
            ([0xDE, 0x99, 0x01, 0x02], "DE 99 01 02: IODReadRes, 99h"),
        ] {
            assert_eq!(PnioStatus::from_bytes(bytes).meaning(), says);
        }
    }
}
