//! The `ecat:` steps of the EtherCAT suites: AL state requests, register and SII access,
//! datagrams and frames as written, CoE SDO transfers and raw mailboxes, a pause of the
//! process data, and the Hot Connect identification.

use serde_json::Value;
use std::any::Any;
use std::time::Duration;

use crate::hex::hex;
use crate::notation::int_of;
use crate::suite::fields::FieldError;
use crate::suite::fields::{hex_bytes, Fields};
use crate::suite::parse_duration;
use crate::suite::BusStep;

/// An `ecat:` step.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum EcatStep {
    /// Writes AL control with `state` (1 INIT, 2 PRE-OP, 3 BOOT, 4 SAFE-OP, 8 OP, or any other
    /// value on purpose) and reads AL status and AL status code once the slave settled.
    State {
        /// The AL control state bits.
        state: u8,
        /// Sets the error-acknowledge bit (10h).
        ack: bool,
    },
    /// Reads ESC registers (FPRD).
    ReadRegister {
        /// First register.
        address: u16,
        /// Bytes to read.
        length: u16,
    },
    /// Writes ESC registers (FPWR).
    WriteRegister {
        /// First register.
        address: u16,
        /// Bytes to write.
        data: Vec<u8>,
    },
    /// An EtherCAT frame as written (frame header and datagrams, after the Ethernet header),
    /// sent as it is, even when it lies about its lengths.
    Frame {
        /// The EtherCAT payload of the Ethernet frame.
        bytes: Vec<u8>,
    },
    /// One datagram: any command, address and data.
    Datagram {
        /// Command byte (e.g. 4 = FPRD, 0Eh = FRMW, 0Fh or above: unknown).
        command: u8,
        /// ADP (position or station address) or, for logical commands, the address's low word.
        adp: u16,
        /// ADO (register) or the logical address's high word.
        ado: u16,
        /// Data bytes (a read sends this many zero bytes).
        data: Vec<u8>,
    },
    /// Reads SII EEPROM words through the ESC's EEPROM interface.
    Sii {
        /// First word address.
        word: u16,
        /// Words to read.
        words: u16,
    },
    /// CoE SDO upload.
    Upload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access (every sub-index at once).
        complete: bool,
    },
    /// CoE SDO download.
    Download {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The data, little-endian as CoE carries it.
        data: Vec<u8>,
        /// Complete access.
        complete: bool,
    },
    /// Mailbox bytes as written (mailbox header and body, maybe malformed), written to the
    /// receive mailbox; the reply in the send mailbox is read.
    Mailbox {
        /// The mailbox message.
        bytes: Vec<u8>,
    },
    /// The master stops the cyclic process data for this long (the SM watchdog runs out).
    StopPdo {
        /// How long.
        time: Duration,
    },
    /// Hot Connect explicit device identification: the ID request bit of AL control, the ID
    /// answered in the AL status code register (ETG.1020).
    Identify,
    /// The CoE emergencies the slave sent since the case began (or since the last such step).
    Emergencies,
}

/// AL states by the names suites write.
const STATES: [(&str, u8); 5] = [
    ("INIT", 1),
    ("PREOP", 2),
    ("BOOT", 3),
    ("SAFEOP", 4),
    ("OP", 8),
];

/// The name of an AL state value, or its number.
pub(crate) fn state_name(state: u8) -> String {
    STATES
        .iter()
        .find(|(_, v)| *v == state)
        .map_or_else(|| format!("{state:02X}h"), |(n, _)| (*n).to_string())
}

impl BusStep for EcatStep {
    fn bus(&self) -> &'static str {
        "ecat"
    }

    fn effect(&self) -> crate::effect::Effect {
        super::effect::of(self)
    }

    fn describe(&self) -> String {
        match self {
            EcatStep::State { state, ack } => format!(
                "AL control {}{}",
                state_name(*state),
                if *ack { " + error acknowledge" } else { "" }
            ),
            EcatStep::ReadRegister { address, length } => {
                format!("read register {address:04X}h, {length} bytes")
            }
            EcatStep::WriteRegister { address, data } => {
                format!("write register {address:04X}h = {}", hex(data))
            }
            EcatStep::Frame { bytes } => format!("frame {}", hex(bytes)),
            EcatStep::Datagram {
                command,
                adp,
                ado,
                data,
            } => format!(
                "datagram command {command:02X}h ADP {adp:04X}h ADO {ado:04X}h, {} bytes",
                data.len()
            ),
            EcatStep::Sii { word, words } => format!("SII words {word:04X}h, {words} words"),
            EcatStep::Upload {
                index,
                sub,
                complete,
            } => format!(
                "SDO upload {index:04X}h:{sub:02X}h{}",
                if *complete { " complete access" } else { "" }
            ),
            EcatStep::Download {
                index,
                sub,
                data,
                complete,
            } => format!(
                "SDO download {index:04X}h:{sub:02X}h = {}{}",
                hex(data),
                if *complete { " complete access" } else { "" }
            ),
            EcatStep::Mailbox { bytes } => format!("mailbox {}", hex(bytes)),
            EcatStep::StopPdo { time } => format!("no process data for {time:?}"),
            EcatStep::Identify => "explicit device identification (AL control ID request)".into(),
            EcatStep::Emergencies => "CoE emergencies received".into(),
        }
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// Parses an `ecat:` step.
pub(super) fn parse(v: &Value) -> Result<Box<dyn BusStep>, FieldError> {
    let m = v
        .as_object()
        .ok_or_else(|| FieldError::value("ecat", format!("expected a map of fields, got {v}")))?;
    let has = |k: &str| m.contains_key(k);
    let word = |f: &Fields, k: &str| -> Result<u16, FieldError> {
        let v = f.req_int(k)?;
        u16::try_from(v)
            .map_err(|_| FieldError::value(format!("ecat.{k}"), format!("{v} is not 0..=FFFFh")))
    };
    let byte = |f: &Fields, k: &str, default: u8| -> Result<u8, FieldError> {
        match f.int(k)? {
            None => Ok(default),
            Some(v) => u8::try_from(v)
                .map_err(|_| FieldError::value(format!("ecat.{k}"), format!("{v} is not a byte"))),
        }
    };
    let bytes = |f: &Fields, k: &str| -> Result<Vec<u8>, FieldError> {
        hex_bytes(&format!("ecat.{k}"), &f.text(k)?.unwrap_or_default())
    };
    let step = if has("state") {
        let f = Fields::new("ecat", m, &["state", "ack"])?;
        let state = match m.get("state") {
            Some(Value::String(s)) if STATES.iter().any(|(n, _)| n == s) => {
                STATES.iter().find(|(n, _)| n == s).map(|(_, v)| *v)
            }
            Some(other) => int_of(other).ok().and_then(|v| u8::try_from(v).ok()),
            None => None,
        }
        .ok_or_else(|| {
            "`ecat.state`: give INIT, PREOP, BOOT, SAFEOP, OP or a byte like 0Fh".to_string()
        })?;
        EcatStep::State {
            state,
            ack: f.bool("ack")?.unwrap_or(false),
        }
    } else if has("read") {
        let f = Fields::new("ecat", m, &["read", "length"])?;
        EcatStep::ReadRegister {
            address: word(&f, "read")?,
            length: word(&f, "length")?,
        }
    } else if has("write") {
        let f = Fields::new("ecat", m, &["write", "data"])?;
        EcatStep::WriteRegister {
            address: word(&f, "write")?,
            data: bytes(&f, "data")?,
        }
    } else if has("frame") {
        let f = Fields::new("ecat", m, &["frame"])?;
        EcatStep::Frame {
            bytes: bytes(&f, "frame")?,
        }
    } else if has("datagram") {
        let f = Fields::new("ecat", m, &["datagram", "adp", "ado", "data", "length"])?;
        let mut data = bytes(&f, "data")?;
        if let Some(n) = f.int("length")? {
            let n = usize::try_from(n)
                .ok()
                .filter(|n| *n <= 1486)
                .ok_or(FieldError::value(
                    "ecat.length",
                    format!("{n} is not 0..=1486"),
                ))?;
            data.resize(n, 0);
        }
        EcatStep::Datagram {
            command: byte(&f, "datagram", 0)?,
            adp: f.int("adp")?.map_or(Ok(0), |_| word(&f, "adp"))?,
            ado: f.int("ado")?.map_or(Ok(0), |_| word(&f, "ado"))?,
            data,
        }
    } else if has("sii") {
        let f = Fields::new("ecat", m, &["sii", "words"])?;
        EcatStep::Sii {
            word: word(&f, "sii")?,
            words: f.int("words")?.map_or(Ok(1), |_| word(&f, "words"))?,
        }
    } else if has("upload") {
        let f = Fields::new("ecat", m, &["upload", "sub", "complete"])?;
        EcatStep::Upload {
            index: word(&f, "upload")?,
            sub: byte(&f, "sub", 0)?,
            complete: f.bool("complete")?.unwrap_or(false),
        }
    } else if has("download") {
        let f = Fields::new("ecat", m, &["download", "sub", "data", "complete"])?;
        EcatStep::Download {
            index: word(&f, "download")?,
            sub: byte(&f, "sub", 0)?,
            data: bytes(&f, "data")?,
            complete: f.bool("complete")?.unwrap_or(false),
        }
    } else if has("mailbox") {
        let f = Fields::new("ecat", m, &["mailbox"])?;
        EcatStep::Mailbox {
            bytes: bytes(&f, "mailbox")?,
        }
    } else if has("stop_pdo") {
        let f = Fields::new("ecat", m, &["stop_pdo"])?;
        EcatStep::StopPdo {
            time: parse_duration(&f.text("stop_pdo")?.unwrap_or_default())?,
        }
    } else if has("identify") {
        Fields::new("ecat", m, &["identify"])?;
        EcatStep::Identify
    } else if has("emergencies") {
        Fields::new("ecat", m, &["emergencies"])?;
        EcatStep::Emergencies
    } else {
        return Err(
            "`ecat` needs one of `state`, `read`, `write`, `frame`, `datagram`, `sii`, \
                    `upload`, `download`, `mailbox`, `stop_pdo`, `identify`, `emergencies`"
                .into(),
        );
    };
    Ok(Box::new(step))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn step(v: Value) -> EcatStep {
        let b = parse(&v).unwrap();
        b.as_any().downcast_ref::<EcatStep>().unwrap().clone()
    }

    #[test]
    fn steps_parse_in_the_manuals_notation() {
        assert_eq!(
            step(json!({ "state": "SAFEOP", "ack": true })),
            EcatStep::State {
                state: 4,
                ack: true
            }
        );
        assert_eq!(
            step(json!({ "state": "0Fh" })),
            EcatStep::State {
                state: 15,
                ack: false
            }
        );
        assert_eq!(
            step(json!({ "upload": "3066h", "sub": 1 })),
            EcatStep::Upload {
                index: 0x3066,
                sub: 1,
                complete: false
            }
        );
        assert_eq!(
            step(json!({ "download": "3066h", "sub": 1, "data": "E8 03" })),
            EcatStep::Download {
                index: 0x3066,
                sub: 1,
                data: vec![0xE8, 3],
                complete: false
            }
        );
        assert_eq!(
            step(json!({ "datagram": "04h", "ado": "0130h", "length": 2 })),
            EcatStep::Datagram {
                command: 4,
                adp: 0,
                ado: 0x130,
                data: vec![0, 0]
            }
        );
        assert_eq!(
            step(json!({ "stop_pdo": "200ms" })),
            EcatStep::StopPdo {
                time: Duration::from_millis(200)
            }
        );
        assert_eq!(step(json!({ "identify": true })), EcatStep::Identify);
        assert_eq!(step(json!({ "emergencies": true })), EcatStep::Emergencies);
    }

    #[test]
    fn bad_steps_say_what_is_wrong() {
        let e = |v: Value| parse(&v).unwrap_err().to_string();
        // Each error names the field it is about.
        assert_eq!(
            parse(&json!({ "read": "0130h" })).unwrap_err(),
            FieldError::Missing {
                action: "ecat".into(),
                field: "length".into()
            }
        );
        assert!(matches!(
            parse(&json!({ "upload": "1018h", "index": 1 })).unwrap_err(),
            FieldError::Unknown { field, .. } if field == "index"
        ));
        assert!(e(json!({ "state": "RUN" })).contains("give INIT, PREOP"));
        assert!(e(json!({ "upload": "10000h" })).contains("is not 0..=FFFFh"));
        assert!(e(json!({ "upload": "1018h", "sub": 300 })).contains("is not a byte"));
        assert!(e(json!({ "read": "0130h" })).contains("needs `length`"));
        assert!(e(json!({ "mailbox": "0G" })).contains("is not hex bytes"));
        assert!(e(json!({ "upload": "1018h", "index": 1 })).contains("has no field `index`"));
        assert!(e(json!({ "reset": true })).contains("needs one of"));
        assert!(e(json!("OP")).contains("expected a map"));
    }

    #[test]
    fn state_names_round_trip() {
        for (name, v) in STATES {
            assert_eq!(state_name(v), name);
        }
        assert_eq!(state_name(0x0F), "0Fh");
    }
}
