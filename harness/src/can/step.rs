//! The `can:` steps of the system-bus suites: a CAN frame as written, an NMT command, or the
//! bus listened to; what came back within the step's time is the observation.
//!
//! - `can: { frame: "601 40 66 20 01 00 00 00 00" }`: COB-ID (hex), then the data bytes; with
//!   `remote: N` a remote frame of DLC N instead (no data). `600+N` is a COB-ID relative to the
//!   DUT's node (FI 1's on a NORD product, the `--dut` URL's on any maker's node).
//! - `can: { nmt: start|stop|pre-operational|reset-node|reset-communication, node: N }` (node 0:
//!   all nodes; `node: dut` the DUT's).
//! - `can: { listen: 100ms }`: nothing sent.
//!
//! Each listens `wait` (default 20 ms; `listen:` its own time) and observes `answered` (a frame
//! came), `count`, `frames` (each `ID DATA`, joined by `; `), `from_node` (the DUT node's frames
//! alone, their COB-IDs written relative to it: `580+N 43 00 10 …`), `abort` (the code of an SDO
//! abort among them, else null).

use serde_json::Value;
use std::any::Any;
use std::time::Duration;

use proto::can::CanFrame;
use proto::canopen::NmtCommand;

use crate::effect::{self, Effect};
use crate::hex::can_frame;
use crate::suite::fields::FieldError;
use crate::suite::fields::{hex_bytes, Fields};
use crate::suite::parse_duration;
use crate::suite::BusStep;

/// How long a step listens unless it says.
pub(super) const DEFAULT_WAIT: Duration = Duration::from_millis(20);

/// A `can:` step.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CanStep {
    /// What goes on the bus (`None`: nothing).
    pub(super) send: Option<Send>,
    /// How long the bus is listened to afterwards.
    pub(super) wait: Duration,
}

/// What a step puts on the bus.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum Send {
    /// A frame as written; `true`: its COB-ID is relative to the DUT's node (`600+N`).
    Frame(CanFrame, bool),
    /// An NMT command (COB-ID 000h) to a node (0: all; `None`: the DUT's).
    Nmt(NmtCommand, Option<u8>),
}

impl Send {
    /// The frame, with the DUT's node `dut` where the step names it.
    pub(super) fn frame(&self, dut: u8) -> Result<CanFrame, String> {
        match self {
            Send::Frame(f, false) => Ok(*f),
            Send::Frame(f, true) => {
                let id = f.id() + u16::from(dut);
                match f.is_remote() {
                    true => CanFrame::remote(id, f.dlc()),
                    false => CanFrame::new(id, f.data()),
                }
                .map_err(|e| e.to_string())
            }
            Send::Nmt(c, node) => {
                CanFrame::new(0, &[c.0, node.unwrap_or(dut)]).map_err(|e| e.to_string())
            }
        }
    }
}

impl BusStep for CanStep {
    fn bus(&self) -> &'static str {
        "can"
    }

    fn effect(&self) -> Effect {
        match &self.send {
            None => Effect::NONE,
            // Operational, a node's process data runs (CiA 301 §7.3.2.2.4).
            Some(Send::Nmt(c, _)) if *c == NmtCommand::START => {
                Effect::motion("NMT start node lets the node's process data run")
            }
            Some(Send::Nmt(..)) => Effect::NONE,
            // A COB-ID relative to the node is judged as its function's, for node 1.
            Some(Send::Frame(f, relative)) => match f.id() + u16::from(*relative) {
                // SDO download (ccs 1) of an object: what it writes.
                0x601..=0x67F if f.data().first().is_some_and(|b| b >> 5 == 1) => {
                    let d = f.data();
                    let index = u16::from_le_bytes([
                        d.get(1).copied().unwrap_or(0),
                        d.get(2).copied().unwrap_or(0),
                    ]);
                    effect::sdo_download(index, d.get(4..).unwrap_or_default())
                }
                // Other SDO requests read or continue a transfer; NMT, SYNC, heartbeat.
                0x000..=0x0FF | 0x601..=0x67F | 0x700..=0x77F => Effect::NONE,
                // A PDO (180h–57Fh) may carry a control word.
                id => Effect::motion(format!("a frame on COB-ID {id:03X}h may be process data")),
            },
        }
    }

    fn describe(&self) -> String {
        let sent = match &self.send {
            None => "listen".to_string(),
            Some(Send::Frame(f, relative)) if f.is_remote() => format!(
                "remote frame {:03X}h{} DLC {}",
                f.id(),
                if *relative { " + node" } else { "" },
                f.dlc()
            ),
            Some(Send::Frame(f, false)) => format!("frame {}", can_frame(f)),
            Some(Send::Frame(f, true)) => {
                format!("frame {} (COB-ID + the DUT's node)", can_frame(f))
            }
            Some(Send::Nmt(c, Some(node))) => format!("NMT {c:?} to node {node}"),
            Some(Send::Nmt(c, None)) => format!("NMT {c:?} to the DUT's node"),
        };
        format!("{sent}, then {:?} on the bus", self.wait)
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// Parses a `can:` step.
pub(super) fn parse(v: &Value) -> Result<Box<dyn BusStep>, FieldError> {
    let m = v
        .as_object()
        .ok_or_else(|| FieldError::value("can", format!("expected a map of fields, got {v}")))?;
    let wait = |f: &Fields| -> Result<Duration, FieldError> {
        match f.text("wait")? {
            None => Ok(DEFAULT_WAIT),
            Some(t) => parse_duration(&t).map_err(|e| FieldError::value("can.wait", e)),
        }
    };
    let step = if m.contains_key("frame") {
        let f = Fields::new("can", m, &["frame", "remote", "wait"])?;
        let text = f.text("frame")?.unwrap_or_default();
        let (id, data) = text.trim().split_once(' ').unwrap_or((text.trim(), ""));
        let (id, relative) = match id.strip_suffix("+N") {
            Some(base) => (base, true),
            None => (id, false),
        };
        let id = u16::from_str_radix(id.trim_end_matches('h'), 16)
            .ok()
            .filter(|id| *id <= 0x7FF - if relative { 127 } else { 0 })
            .ok_or_else(|| {
                FieldError::value(
                    "can.frame",
                    format!("`{id}` is not an 11-bit COB-ID (000…7FF, hex; `600+N`)"),
                )
            })?;
        let frame = match f.int("remote")? {
            Some(dlc) => {
                let dlc = u8::try_from(dlc)
                    .map_err(|_| FieldError::value("can.remote", format!("DLC {dlc}")))?;
                CanFrame::remote(id, dlc)
            }
            None => CanFrame::new(id, &hex_bytes("can.frame", data)?),
        }
        .map_err(|e| FieldError::value("can.frame", format!("{e}")))?;
        CanStep {
            send: Some(Send::Frame(frame, relative)),
            wait: wait(&f)?,
        }
    } else if m.contains_key("nmt") {
        let f = Fields::new("can", m, &["nmt", "node", "wait"])?;
        let command = match f.text("nmt")?.unwrap_or_default().as_str() {
            "start" => NmtCommand::START,
            "stop" => NmtCommand::STOP,
            "pre-operational" => NmtCommand::ENTER_PRE_OPERATIONAL,
            "reset-node" => NmtCommand::RESET_NODE,
            "reset-communication" => NmtCommand::RESET_COMMUNICATION,
            other => {
                return Err(FieldError::value(
                    "can.nmt",
                    format!(
                        "`{other}` (start, stop, pre-operational, reset-node, \
                     reset-communication)"
                    ),
                ))
            }
        };
        let node = match m.get("node") {
            Some(Value::String(s)) if s == "dut" => None,
            _ => {
                let node = f.int("node")?.unwrap_or(0);
                Some(
                    u8::try_from(node)
                        .ok()
                        .filter(|n| *n <= 127)
                        .ok_or_else(|| {
                            FieldError::value(
                                "can.node",
                                format!("{node} is not 0 (all), a node id 1…127 or `dut`"),
                            )
                        })?,
                )
            }
        };
        CanStep {
            send: Some(Send::Nmt(command, node)),
            wait: wait(&f)?,
        }
    } else if m.contains_key("listen") {
        let f = Fields::new("can", m, &["listen"])?;
        let t = f.text("listen")?.unwrap_or_default();
        CanStep {
            send: None,
            wait: parse_duration(&t).map_err(|e| FieldError::value("can.listen", e))?,
        }
    } else {
        return Err("`can`: give `frame`, `nmt` or `listen`".into());
    };
    Ok(Box::new(step))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn step(v: Value) -> Result<CanStep, FieldError> {
        parse(&v).map(|s| s.as_any().downcast_ref::<CanStep>().unwrap().clone())
    }

    #[test]
    fn frames_nmt_and_listening_are_read_and_bad_ones_named() {
        let s = step(json!({ "frame": "636 40 66 20 01 00 00 00 00" })).unwrap();
        assert_eq!(s.wait, DEFAULT_WAIT);
        assert!(matches!(s.send, Some(Send::Frame(f, false)) if f.id() == 0x636 && f.dlc() == 8));
        let r = step(json!({ "frame": "636", "remote": 8 })).unwrap();
        assert!(matches!(r.send, Some(Send::Frame(f, false)) if f.is_remote()));
        let n = step(json!({ "nmt": "reset-node", "node": 36, "wait": "50ms" })).unwrap();
        assert_eq!(n.send, Some(Send::Nmt(NmtCommand::RESET_NODE, Some(36))));
        // Relative to the DUT's node.
        let rel = step(json!({ "frame": "600+N 40 00 10 00 00 00 00 00" })).unwrap();
        let sent = rel.send.as_ref().unwrap().frame(5).unwrap();
        assert_eq!((sent.id(), sent.data()[0]), (0x605, 0x40));
        let dut = step(json!({ "nmt": "stop", "node": "dut" })).unwrap();
        assert_eq!(dut.send.unwrap().frame(5).unwrap().data(), [0x02, 5]);
        assert!(step(json!({ "frame": "7F0+N" })).is_err());
        assert_eq!(n.wait, Duration::from_millis(50));
        assert_eq!(
            step(json!({ "listen": "1s" })).unwrap().wait,
            Duration::from_secs(1)
        );
        assert!(step(json!({ "frame": "800 00" }))
            .unwrap_err()
            .to_string()
            .contains("11-bit"));
        assert!(step(json!({ "frame": "601 00 00 00 00 00 00 00 00 00" })).is_err());
        assert!(step(json!({ "nmt": "go" }))
            .unwrap_err()
            .to_string()
            .contains("start, stop"));
        assert!(step(json!({ "nmt": "start", "node": 128 })).is_err());
        assert!(step(json!({ "hello": 1 }))
            .unwrap_err()
            .to_string()
            .contains("give `frame`"));
        // Starting a node may start process data; an SDO upload cannot move anything.
        assert!(n.effect().motion.is_none());
        let start = step(json!({ "nmt": "start" })).unwrap();
        assert!(start.effect().motion.is_some());
        assert!(s.effect().motion.is_none());
    }
}
