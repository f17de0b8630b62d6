//! The `epl:` steps of the POWERLINK suites: NMT commands and states, the node's
//! IdentResponse and StatusResponse, SDO transfers over ASnd or UDP, raw frames and raw SDO
//! bytes as written, a silent MN and idle cycles.

use serde_json::Value;
use std::any::Any;
use std::time::Duration;

use proto::epl::{NmtCommand, NmtState};

use super::mn::Via;
use crate::hex::hex;
use crate::notation::int_of;
use crate::suite::fields::FieldError;
use crate::suite::fields::{hex_bytes, Fields};
use crate::suite::parse_duration;
use crate::suite::BusStep;

/// An `epl:` step.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum EplStep {
    /// An NMT command from the MN, then the node's state once settled.
    Nmt(NmtCommand),
    /// The MN boots the node to this state the normal way.
    State(NmtState),
    /// SoA IdentRequest, to the node the binding talks to or (after readdressing) to
    /// another, which the binding talks to from then on.
    Ident(Option<u8>),
    /// SoA StatusRequest.
    Status,
    /// SDO read.
    Upload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Transport (`None`: the binding's default).
        via: Option<Via>,
    },
    /// SDO write.
    Download {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// The data, little-endian.
        data: Vec<u8>,
        /// Transport.
        via: Option<Via>,
    },
    /// A POWERLINK frame as written (from the message-type byte on).
    Frame(Vec<u8>),
    /// Raw SDO bytes (sequence and command layers).
    Sdo {
        /// The bytes.
        bytes: Vec<u8>,
        /// Transport.
        via: Option<Via>,
    },
    /// The MN sends nothing for this long.
    Silence(Duration),
    /// This many cycles as they run.
    Cycles(u64),
}

impl BusStep for EplStep {
    fn bus(&self) -> &'static str {
        "epl"
    }

    fn effect(&self) -> crate::effect::Effect {
        super::effect::of(self)
    }

    fn describe(&self) -> String {
        let via = |v: &Option<Via>| match v {
            Some(Via::Udp) => " over UDP",
            Some(Via::Asnd) => " over ASnd",
            None => "",
        };
        match self {
            EplStep::Nmt(c) => format!("NMT command {c}"),
            EplStep::State(s) => format!("boot the node to {s}"),
            EplStep::Ident(None) => "SoA IdentRequest".into(),
            EplStep::Ident(Some(n)) => format!("SoA IdentRequest to node {n}"),
            EplStep::Status => "SoA StatusRequest".into(),
            EplStep::Upload { index, sub, via: v } => {
                format!("SDO read {index:04X}h/{sub:02X}h{}", via(v))
            }
            EplStep::Download {
                index,
                sub,
                data,
                via: v,
            } => format!(
                "SDO write {index:04X}h/{sub:02X}h = {}{}",
                hex(data),
                via(v)
            ),
            EplStep::Frame(b) => format!("frame {}", hex(b)),
            EplStep::Sdo { bytes, via: v } => format!("SDO bytes {}{}", hex(bytes), via(v)),
            EplStep::Silence(d) => format!("MN silent for {d:?}"),
            EplStep::Cycles(n) => format!("{n} cycles"),
        }
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

fn named<T>(
    key: &str,
    v: &Value,
    by_name: fn(&str) -> Option<T>,
    from_byte: fn(u8) -> T,
    known: &str,
) -> Result<T, FieldError> {
    match v {
        Value::String(s) => by_name(s).or_else(|| {
            int_of(v)
                .ok()
                .and_then(|n| u8::try_from(n).ok())
                .map(from_byte)
        }),
        other => int_of(other)
            .ok()
            .and_then(|n| u8::try_from(n).ok())
            .map(from_byte),
    }
    .ok_or_else(|| {
        FieldError::value(
            format!("epl.{key}"),
            format!("give {known} or a byte like 21h"),
        )
    })
}

/// Parses an `epl:` step.
pub(super) fn parse(v: &Value) -> Result<Box<dyn BusStep>, FieldError> {
    let m = v
        .as_object()
        .ok_or_else(|| FieldError::value("epl", format!("expected a map of fields, got {v}")))?;
    let has = |k: &str| m.contains_key(k);
    let via = |f: &Fields| -> Result<Option<Via>, FieldError> {
        f.text("via")?
            .map(|s| Via::parse(&s).map_err(|e| FieldError::value("epl.via", e)))
            .transpose()
    };
    let index = |f: &Fields, k: &str| -> Result<u16, FieldError> {
        let v = f.req_int(k)?;
        u16::try_from(v)
            .map_err(|_| FieldError::value(format!("epl.{k}"), format!("{v} is not 0..=FFFFh")))
    };
    let sub = |f: &Fields| -> Result<u8, FieldError> {
        match f.int("sub")? {
            None => Ok(0),
            Some(v) => u8::try_from(v)
                .map_err(|_| FieldError::value("epl.sub", format!("{v} is not a byte"))),
        }
    };
    let bytes = |f: &Fields, k: &str| -> Result<Vec<u8>, FieldError> {
        hex_bytes(&format!("epl.{k}"), &f.text(k)?.unwrap_or_default())
    };
    let step = if has("nmt") {
        Fields::new("epl", m, &["nmt"])?;
        EplStep::Nmt(named(
            "nmt",
            &m["nmt"],
            |s| NmtCommand::by_name(&s.replace('-', "")),
            NmtCommand,
            "start-node, stop-node, enter-pre-operational-2, enable-ready-to-operate, \
             reset-node, reset-communication, reset-configuration, sw-reset",
        )?)
    } else if has("state") {
        Fields::new("epl", m, &["state"])?;
        EplStep::State(named(
            "state",
            &m["state"],
            NmtState::by_name,
            NmtState,
            "PRE_OPERATIONAL_1, PRE_OPERATIONAL_2, READY_TO_OPERATE, OPERATIONAL, STOPPED",
        )?)
    } else if has("ident") {
        let f = Fields::new("epl", m, &["ident", "node"])?;
        let node = match f.int("node")? {
            None => None,
            Some(n) => Some(
                u8::try_from(n)
                    .ok()
                    .filter(|n| (1..=239).contains(n))
                    .ok_or(FieldError::value(
                        "epl.node",
                        format!("{n} is not a controlled node's id (1…239)"),
                    ))?,
            ),
        };
        EplStep::Ident(node)
    } else if has("status") {
        Fields::new("epl", m, &["status"])?;
        EplStep::Status
    } else if has("upload") {
        let f = Fields::new("epl", m, &["upload", "sub", "via"])?;
        EplStep::Upload {
            index: index(&f, "upload")?,
            sub: sub(&f)?,
            via: via(&f)?,
        }
    } else if has("download") {
        let f = Fields::new("epl", m, &["download", "sub", "data", "via"])?;
        EplStep::Download {
            index: index(&f, "download")?,
            sub: sub(&f)?,
            data: bytes(&f, "data")?,
            via: via(&f)?,
        }
    } else if has("frame") {
        let f = Fields::new("epl", m, &["frame"])?;
        EplStep::Frame(bytes(&f, "frame")?)
    } else if has("sdo") {
        let f = Fields::new("epl", m, &["sdo", "via"])?;
        EplStep::Sdo {
            bytes: bytes(&f, "sdo")?,
            via: via(&f)?,
        }
    } else if has("silence") {
        let f = Fields::new("epl", m, &["silence"])?;
        EplStep::Silence(parse_duration(&f.text("silence")?.unwrap_or_default())?)
    } else if has("cycles") {
        let f = Fields::new("epl", m, &["cycles"])?;
        let n = f.req_int("cycles")?;
        EplStep::Cycles(
            u64::try_from(n)
                .ok()
                .filter(|n| (1..=100_000).contains(n))
                .ok_or(FieldError::value(
                    "epl.cycles",
                    format!("{n} is not 1..=100000"),
                ))?,
        )
    } else {
        return Err(
            "`epl` needs one of `nmt`, `state`, `ident`, `status`, `upload`, \
                    `download`, `frame`, `sdo`, `silence`, `cycles`"
                .into(),
        );
    };
    Ok(Box::new(step))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn step(v: Value) -> EplStep {
        let b = parse(&v).unwrap();
        b.as_any().downcast_ref::<EplStep>().unwrap().clone()
    }

    #[test]
    fn steps_parse() {
        assert_eq!(
            step(json!({ "nmt": "start-node" })),
            EplStep::Nmt(NmtCommand::START_NODE)
        );
        assert_eq!(
            step(json!({ "nmt": "enable-ready-to-operate" })),
            EplStep::Nmt(NmtCommand::ENABLE_READY_TO_OPERATE)
        );
        assert_eq!(
            step(json!({ "nmt": "30h" })),
            EplStep::Nmt(NmtCommand(0x30))
        );
        assert_eq!(
            step(json!({ "state": "READY_TO_OPERATE" })),
            EplStep::State(NmtState::READY_TO_OPERATE)
        );
        assert_eq!(
            step(json!({ "upload": "3866h", "sub": 1, "via": "udp" })),
            EplStep::Upload {
                index: 0x3866,
                sub: 1,
                via: Some(Via::Udp)
            }
        );
        assert_eq!(
            step(json!({ "silence": "300ms" })),
            EplStep::Silence(Duration::from_millis(300))
        );
    }

    #[test]
    fn bad_steps_say_what_is_wrong() {
        let e = |v: Value| parse(&v).unwrap_err().to_string();
        assert!(e(json!({ "nmt": "jump" })).contains("give start-node"));
        assert!(e(json!({ "upload": "1018h", "via": "tcp" })).contains("asnd or udp"));
        assert!(e(json!({ "cycles": 0 })).contains("1..=100000"));
        assert!(e(json!({ "reset": true })).contains("needs one of"));
    }
}
