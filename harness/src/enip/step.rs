//! The `enip:` steps of the EtherNet/IP suites: encapsulation and CIP messages as written,
//! Forward_Open variants, and control of the scanner's I/O.

use serde_json::{Map, Value};
use std::any::Any;
use std::time::Duration;

use super::ForwardOpenSpec;
use crate::hex::hex;
use crate::suite::fields::FieldError;
use crate::suite::fields::{hex_bytes, Fields};
use crate::suite::parse_duration;
use crate::suite::BusStep;

/// How a raw message leaves in two TCP segments (`split: N`, `gap: 50ms`): its first `at`
/// bytes, then, `gap` later, the rest. TCP is a byte stream, so a target must put an
/// encapsulation message together from however many segments it arrives in (CIP Vol 2
/// §2-3: the header's length field, not the segment, tells where a message ends).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Split {
    /// Bytes in the first segment: at least 1, fewer than the message has.
    pub(crate) at: usize,
    /// The pause before the second segment.
    pub(crate) gap: Duration,
}

/// The pause between the two segments of a split message unless `gap` says otherwise.
const DEFAULT_GAP: Duration = Duration::from_millis(50);

/// An `enip:` step. `client` picks the TCP connection: 1 is the scanner's own, 2.. are other
/// clients of the same target (each with its own session), to show a target keeps serving
/// others after one client misbehaved.
#[derive(Debug, Clone)]
pub(crate) enum EnipStep {
    /// Encapsulation bytes as written; `session` puts the client's session handle in bytes
    /// 4..8 (registering one first); `split` sends them in two TCP segments.
    Raw {
        bytes: Vec<u8>,
        session: bool,
        client: u8,
        split: Option<Split>,
    },
    /// A message-router request as written (service, path size, path, data; may be malformed)
    /// in a SendRRData of the client's session.
    Mr { bytes: Vec<u8>, client: u8 },
    /// An unconnected CIP request.
    Request {
        service: u8,
        path: Vec<u8>,
        data: Vec<u8>,
        client: u8,
    },
    /// A Forward_Open with the given parameters; an accepted owner connection carries the
    /// following process-data steps.
    ForwardOpen(ForwardOpenSpec),
    /// The scanner stops sending O→T data for this long; with `foreign_id` it keeps sending
    /// frames, but under a connection ID that is not the connection's (BU 0620 §2.3.1: a
    /// consumer decides by the connection ID whether a telegram is for it).
    StopIo { time: Duration, foreign_id: bool },
    /// The run/idle header of the following O→T frames: run (`true`) or idle.
    Run(bool),
}

impl BusStep for EnipStep {
    fn bus(&self) -> &'static str {
        "enip"
    }

    fn describe(&self) -> String {
        describe(self)
    }

    fn effect(&self) -> crate::effect::Effect {
        super::effect::of(self)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// The step as one line, for reports.
fn describe(e: &EnipStep) -> String {
    let on = |client: u8| {
        if client == 1 {
            String::new()
        } else {
            format!(" (client {client})")
        }
    };
    match e {
        EnipStep::Raw {
            bytes,
            session,
            client,
            split,
        } => {
            let s = if *session { ", session filled in" } else { "" };
            let parts = match split {
                Some(p) => format!(
                    ", in two TCP segments: {} bytes, then {} more {:?} later",
                    p.at,
                    bytes.len().saturating_sub(p.at),
                    p.gap
                ),
                None => String::new(),
            };
            format!("raw {}{s}{parts}{}", hex(bytes), on(*client))
        }
        EnipStep::Mr { bytes, client } => {
            format!("message-router request {}{}", hex(bytes), on(*client))
        }
        EnipStep::Request {
            service,
            path,
            data,
            client,
        } => format!(
            "service {service:02X}h path {} data [{}]{}",
            hex(path),
            hex(data),
            on(*client)
        ),
        EnipStep::ForwardOpen(f) if f.declared.is_some() => {
            let (o, t) = f.declared.unwrap_or_default();
            format!(
                "{} on the connection the EDS declares, sizes {o:+}/{t:+} bytes, RPI {} µs, transport {:02X}h",
                if f.large { "Large_Forward_Open" } else { "Forward_Open" },
                f.rpi_us,
                f.transport
            )
        }
        EnipStep::ForwardOpen(f) => format!(
            "{} {} -> {}, sizes {}/{}, RPI {} µs, transport {:02X}h, multiplier {}{}",
            if f.large {
                "Large_Forward_Open"
            } else {
                "Forward_Open"
            },
            f.o_t_point,
            f.t_o_point,
            f.o_t_size,
            f.t_o_size,
            f.rpi_us,
            f.transport,
            f.multiplier,
            if f.run_idle {
                ""
            } else {
                ", no run/idle header"
            }
        ),
        EnipStep::StopIo {
            time,
            foreign_id: false,
        } => format!("stop O→T data for {time:?}"),
        EnipStep::StopIo {
            time,
            foreign_id: true,
        } => format!("O→T data under a foreign connection ID for {time:?}"),
        EnipStep::Run(true) => "run/idle header: run".into(),
        EnipStep::Run(false) => "run/idle header: idle".into(),
    }
}

/// Parses an `enip:` step.
pub(super) fn parse(v: &Value) -> Result<Box<dyn BusStep>, FieldError> {
    let m = v
        .as_object()
        .ok_or_else(|| FieldError::value("enip", format!("expected a map of fields, got {v}")))?;
    Ok(Box::new(enip_step(m)?))
}

/// `split: N` and `gap: T` of a raw message of `len` bytes: N must leave bytes on both sides;
/// `gap` alone is an error (there is nothing to pause between).
fn split(f: &Fields, len: usize) -> Result<Option<Split>, FieldError> {
    let gap = f.text("gap")?.map(|g| parse_duration(&g)).transpose()?;
    let Some(at) = f.int("split")? else {
        return match gap {
            Some(_) => Err("`enip.gap` needs `split` (the bytes of the first segment)".into()),
            None => Ok(None),
        };
    };
    match usize::try_from(at) {
        Ok(at) if at >= 1 && at < len => Ok(Some(Split {
            at,
            gap: gap.unwrap_or(DEFAULT_GAP),
        })),
        _ => Err(FieldError::value(
            "enip.split",
            format!(
                "{at} does not split a message of {len} bytes (1..={})",
                len.saturating_sub(1)
            ),
        )),
    }
}

fn enip_step(m: &Map<String, Value>) -> Result<EnipStep, FieldError> {
    let client = |f: &Fields| -> Result<u8, FieldError> {
        match f.int("client")? {
            None => Ok(1),
            Some(v @ 1..=99) => Ok(v as u8),
            Some(v) => Err(FieldError::value(
                "enip.client",
                format!("{v} is not 1..=99"),
            )),
        }
    };
    if m.contains_key("raw") {
        let f = Fields::new("enip", m, &["raw", "session", "client", "split", "gap"])?;
        let bytes = hex_bytes("enip.raw", &f.text("raw")?.unwrap_or_default())?;
        let split = split(&f, bytes.len())?;
        return Ok(EnipStep::Raw {
            bytes,
            session: f.bool("session")?.unwrap_or(false),
            client: client(&f)?,
            split,
        });
    }
    if m.contains_key("mr") {
        let f = Fields::new("enip", m, &["mr", "client"])?;
        return Ok(EnipStep::Mr {
            bytes: hex_bytes("enip.mr", &f.text("mr")?.unwrap_or_default())?,
            client: client(&f)?,
        });
    }
    if m.contains_key("service") {
        let f = Fields::new("enip", m, &["service", "path", "data", "client"])?;
        let service = u8::try_from(f.req_int("service")?)
            .map_err(|_| "`enip.service` is not a byte".to_string())?;
        return Ok(EnipStep::Request {
            service,
            path: hex_bytes("enip.path", &f.text("path")?.unwrap_or_default())?,
            data: hex_bytes("enip.data", &f.text("data")?.unwrap_or_default())?,
            client: client(&f)?,
        });
    }
    if m.contains_key("forward_open") {
        let f = Fields::new(
            "enip",
            m,
            &[
                "forward_open",
                "o_t",
                "t_o",
                "o_t_size",
                "t_o_size",
                "rpi_us",
                "transport",
                "multiplier",
                "large",
                "run_idle",
                "o_t_size_delta",
                "t_o_size_delta",
            ],
        )?;
        let d = ForwardOpenSpec::default();
        let small = |k: &str| -> Result<Option<u16>, FieldError> {
            f.int(k)?
                .map(|v| {
                    u16::try_from(v).map_err(|_| {
                        FieldError::value(format!("enip.{k}"), format!("{v} is not 0..=65535"))
                    })
                })
                .transpose()
        };
        let byte = |k: &str| -> Result<Option<u8>, FieldError> {
            f.int(k)?
                .map(|v| {
                    u8::try_from(v).map_err(|_| {
                        FieldError::value(format!("enip.{k}"), format!("{v} is not a byte"))
                    })
                })
                .transpose()
        };
        let rpi = f
            .int("rpi_us")?
            .map(|v| {
                u32::try_from(v)
                    .map_err(|_| FieldError::value("enip.rpi_us", format!("{v} is not 32-bit")))
            })
            .transpose()?;
        // `forward_open: declared`: the connection of the device's EDS, its sizes changed by
        // `o_t_size_delta` / `t_o_size_delta` bytes.
        if f.text("forward_open").ok().flatten().as_deref() == Some("declared") {
            let delta = |k: &str| -> Result<i32, FieldError> {
                f.int(k)?.map_or(Ok(0), |v| {
                    i32::try_from(v).map_err(|_| {
                        FieldError::value(format!("enip.{k}"), format!("{v} is too big"))
                    })
                })
            };
            return Ok(EnipStep::ForwardOpen(ForwardOpenSpec {
                declared: Some((delta("o_t_size_delta")?, delta("t_o_size_delta")?)),
                rpi_us: rpi.unwrap_or(d.rpi_us),
                rpi_given: rpi.is_some(),
                transport: byte("transport")?.unwrap_or(d.transport),
                large: f.bool("large")?.unwrap_or(false),
                ..d
            }));
        }
        return Ok(EnipStep::ForwardOpen(ForwardOpenSpec {
            o_t_point: small("o_t")?.unwrap_or(d.o_t_point),
            t_o_point: small("t_o")?.unwrap_or(d.t_o_point),
            o_t_size: small("o_t_size")?.ok_or("`enip` needs `o_t_size`")?,
            t_o_size: small("t_o_size")?.ok_or("`enip` needs `t_o_size`")?,
            rpi_us: rpi.unwrap_or(d.rpi_us),
            transport: byte("transport")?.unwrap_or(d.transport),
            multiplier: byte("multiplier")?.unwrap_or(d.multiplier),
            large: f.bool("large")?.unwrap_or(false),
            run_idle: f.bool("run_idle")?.unwrap_or(d.run_idle),
            ..d
        }));
    }
    if m.contains_key("stop_io") {
        let f = Fields::new("enip", m, &["stop_io", "foreign_id"])?;
        return Ok(EnipStep::StopIo {
            time: parse_duration(&f.text("stop_io")?.unwrap_or_default())?,
            foreign_id: f.bool("foreign_id")?.unwrap_or(false),
        });
    }
    if m.contains_key("run") {
        let f = Fields::new("enip", m, &["run"])?;
        return Ok(EnipStep::Run(f.bool("run")?.unwrap_or(true)));
    }
    Err("`enip` needs one of `raw`, `mr`, `service`, `forward_open`, `stop_io`, `run`".into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    const LIST_IDENTITY: &str = "6300 0000 00000000 00000000 0000000000000000 00000000";

    /// A raw step with these fields beside `raw`.
    fn raw(extra: Value) -> Result<EnipStep, FieldError> {
        let mut m = extra.as_object().cloned().unwrap_or_default();
        m.insert("raw".into(), json!(LIST_IDENTITY));
        enip_step(&m)
    }

    fn split_of(step: Result<EnipStep, FieldError>) -> Option<Split> {
        match step {
            Ok(EnipStep::Raw { bytes, split, .. }) => {
                assert_eq!(bytes.len(), 24);
                split
            }
            other => panic!("not a raw step: {other:?}"),
        }
    }

    #[test]
    fn a_raw_message_splits_in_two_segments() {
        assert_eq!(
            split_of(raw(json!({ "split": 10, "gap": "20ms" }))),
            Some(Split {
                at: 10,
                gap: Duration::from_millis(20)
            })
        );
        // The gap defaults to 50 ms; without `split` the message goes whole.
        assert_eq!(
            split_of(raw(json!({ "split": 23 }))),
            Some(Split {
                at: 23,
                gap: DEFAULT_GAP
            })
        );
        assert_eq!(split_of(raw(json!({}))), None);
        // A split that leaves one side empty, a gap without a split, a gap that is no
        // duration: each a load error.
        for bad in [
            json!({ "split": 0 }),
            json!({ "split": 24 }),
            json!({ "split": -1 }),
            json!({ "gap": "50ms" }),
            json!({ "split": 4, "gap": "5" }),
        ] {
            assert!(raw(bad.clone()).is_err(), "{bad} loaded");
        }
        let e = raw(json!({ "split": 24 })).unwrap_err();
        assert!(
            matches!(&e, FieldError::Value { at, why } if at == "enip.split"
                && why.contains("does not split a message of 24 bytes")),
            "{e:?}"
        );
    }
}
