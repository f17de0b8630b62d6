//! The `pnio:` steps of the PROFINET suites: DCP (identify, set name or IP, signal, factory
//! reset), the application relation (connect with the expected modules, release), record
//! read/write, alarms, a silent controller, idle cycles, and raw frames and RPC calls as
//! written for the bad-input cases.

use serde_json::Value;
use std::any::Any;
use std::net::Ipv4Addr;
use std::time::Duration;

use proto::nord::ppo::PpoType;

use crate::hex::hex;
use crate::notation::int_of;
use crate::suite::fields::FieldError;
use crate::suite::fields::{hex_bytes, Fields};
use crate::suite::parse_duration;
use crate::suite::BusStep;

/// What the controller expects in one inverter's slot at Connect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Module {
    /// A PPO type's module, as the device description gives it.
    Ppo(PpoType),
    /// A module ident number as written (a wrong one, for the device's ModuleDiffBlock).
    Ident(u32),
}

/// A `pnio:` step.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum PnioStep {
    /// DCP Identify: all stations, or the one of this name.
    Identify(Option<String>),
    /// DCP Identify by the name the run found the device by (`identify: own`): the device's
    /// own name, whoever made it.
    IdentifyOwn,
    /// DCP Set NameOfStation, kept over a power cycle (`permanent`) or not.
    SetName { name: String, permanent: bool },
    /// DCP Set IP parameter.
    SetIp {
        ip: Ipv4Addr,
        mask: Ipv4Addr,
        gateway: Ipv4Addr,
        permanent: bool,
    },
    /// DCP Set Control "Signal" (the device flashes its LED).
    Signal,
    /// DCP Set Control "Reset to factory".
    ResetFactory,
    /// Connect, PrmEnd, ApplicationReady with these modules in the inverters' slots (FI 1
    /// first; empty: the profile's default for each inverter), both CRs at this reduction
    /// ratio of the 1 ms send clock (1 unless given).
    Connect {
        modules: Vec<Module>,
        reduction_ratio: u16,
    },
    /// Release of the application relation (the IO AR, else the DeviceAccess AR).
    Release,
    /// Connect of a DeviceAccess AR, as engineering tools read records without I/O (ARType
    /// IOSAR with ARProperties.DeviceAccess; the ARBlockReq alone).
    DeviceAccess,
    /// IODRead of a record.
    Read {
        index: u16,
        slot: Option<u16>,
        subslot: Option<u16>,
    },
    /// IODWrite of a record.
    Write {
        index: u16,
        slot: Option<u16>,
        subslot: Option<u16>,
        data: Vec<u8>,
    },
    /// Waits this long at most for an alarm, and acknowledges it.
    Alarm(Duration),
    /// The controller sends no RT frames for this long (the device's watchdog).
    Silence(Duration),
    /// The cycle runs this long; the LLDP frames the device sent meanwhile.
    Lldp(Duration),
    /// This many cycles as they run.
    Cycles(u64),
    /// A PROFINET frame as written (from the frame id on), and what comes back.
    Frame(Vec<u8>),
    /// An RPC request to the device's PNIO interface: the opnum and the NDR body as written
    /// (the args header is added), under another interface UUID if given.
    Rpc {
        opnum: u16,
        body: Vec<u8>,
        interface: Option<String>,
    },
}

impl BusStep for PnioStep {
    fn bus(&self) -> &'static str {
        "pnio"
    }

    fn effect(&self) -> crate::effect::Effect {
        super::effect::of(self)
    }

    fn describe(&self) -> String {
        let keep = |p: &bool| if *p { "permanent" } else { "temporary" };
        let at = |slot: &Option<u16>, subslot: &Option<u16>| match (slot, subslot) {
            (None, None) => String::new(),
            (s, ss) => format!(
                " at slot {} subslot {}",
                s.map_or("-".into(), |s| s.to_string()),
                ss.map_or("-".into(), |s| format!("{s:X}h"))
            ),
        };
        match self {
            PnioStep::Identify(None) => "DCP Identify all".into(),
            PnioStep::Identify(Some(n)) => format!("DCP Identify {n:?}"),
            PnioStep::IdentifyOwn => "DCP Identify by the device's own name".into(),
            PnioStep::SetName { name, permanent } => {
                format!("DCP Set NameOfStation {name:?} ({})", keep(permanent))
            }
            PnioStep::SetIp {
                ip,
                mask,
                gateway,
                permanent,
            } => format!("DCP Set IP {ip}/{mask} gw {gateway} ({})", keep(permanent)),
            PnioStep::Signal => "DCP Set Control Signal".into(),
            PnioStep::ResetFactory => "DCP Set Control Reset to factory".into(),
            PnioStep::Connect {
                modules: m,
                reduction_ratio: rr,
            } => {
                let v: Vec<String> = m
                    .iter()
                    .map(|m| match m {
                        Module::Ppo(p) => format!("PPO{}", p.0),
                        Module::Ident(i) => format!("{i:08X}h"),
                    })
                    .collect();
                let with = if v.is_empty() {
                    String::new()
                } else {
                    format!(" with {}", v.join(", "))
                };
                format!("Connect{with} at {rr} ms, PrmEnd, ApplicationReady")
            }
            PnioStep::Release => "Release".into(),
            PnioStep::DeviceAccess => "Connect a DeviceAccess AR (IOSAR, no I/O)".into(),
            PnioStep::Read {
                index,
                slot,
                subslot,
            } => format!("IODRead record {index}{}", at(slot, subslot)),
            PnioStep::Write {
                index,
                slot,
                subslot,
                data,
            } => format!(
                "IODWrite record {index}{} = {}",
                at(slot, subslot),
                hex(data)
            ),
            PnioStep::Alarm(d) => format!("wait {d:?} for an alarm, acknowledge it"),
            PnioStep::Silence(d) => format!("controller silent for {d:?}"),
            PnioStep::Lldp(d) => format!("LLDP frames within {d:?}"),
            PnioStep::Cycles(n) => format!("{n} cycles"),
            PnioStep::Frame(b) => format!("frame {}", hex(b)),
            PnioStep::Rpc {
                opnum,
                body,
                interface,
            } => format!(
                "RPC opnum {opnum}{} body {}",
                interface
                    .as_ref()
                    .map_or(String::new(), |i| format!(" to interface {i}")),
                hex(body)
            ),
        }
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// A module: `ppo1`…`ppo6` or an ident number.
fn module(v: &Value) -> Result<Module, FieldError> {
    let bad = || {
        FieldError::value(
            "pnio.connect",
            format!("{v} is not ppo1, ppo2, ppo3, ppo4, ppo6 or a number"),
        )
    };
    if let Some(s) = v.as_str() {
        if let Some(n) = s.to_ascii_lowercase().strip_prefix("ppo") {
            let n: u8 = n.parse().map_err(|_| bad())?;
            return PpoType::new(n).map(Module::Ppo).map_err(|_| bad());
        }
    }
    int_of(v)
        .ok()
        .and_then(|n| u32::try_from(n).ok())
        .map(Module::Ident)
        .ok_or_else(bad)
}

fn ipv4(f: &Fields, key: &str) -> Result<Ipv4Addr, FieldError> {
    f.text(key)?
        .ok_or(format!("`pnio.set-ip` needs `{key}`"))?
        .parse()
        .map_err(|e| FieldError::value(format!("pnio.{key}"), format!("{e}")))
}

fn word(f: &Fields, key: &str) -> Result<Option<u16>, FieldError> {
    f.int(key)?
        .map(|v| {
            u16::try_from(v).map_err(|_| {
                FieldError::value(format!("pnio.{key}"), format!("{v} is not 0..=FFFFh"))
            })
        })
        .transpose()
}

/// Parses a `pnio:` step.
pub(super) fn parse(v: &Value) -> Result<Box<dyn BusStep>, FieldError> {
    let m = v
        .as_object()
        .ok_or_else(|| FieldError::value("pnio", format!("expected a map of fields, got {v}")))?;
    let has = |k: &str| m.contains_key(k);
    let permanent =
        |f: &Fields| -> Result<bool, FieldError> { Ok(f.bool("permanent")?.unwrap_or(true)) };
    let bytes = |f: &Fields, k: &str| -> Result<Vec<u8>, FieldError> {
        hex_bytes(&format!("pnio.{k}"), &f.text(k)?.unwrap_or_default())
    };
    let duration = |f: &Fields, k: &str| -> Result<Duration, FieldError> {
        Ok(parse_duration(&f.text(k)?.ok_or(FieldError::value(
            format!("pnio.{k}"),
            "give a time like 200ms",
        ))?)?)
    };
    let step = if has("identify") {
        let f = Fields::new("pnio", m, &["identify"])?;
        match &m["identify"] {
            Value::Bool(true) => PnioStep::Identify(None),
            Value::String(s) if s == "all" => PnioStep::Identify(None),
            Value::String(s) if s == "own" => PnioStep::IdentifyOwn,
            _ => PnioStep::Identify(f.text("identify")?),
        }
    } else if has("set-name") {
        let f = Fields::new("pnio", m, &["set-name", "permanent"])?;
        PnioStep::SetName {
            name: f.text("set-name")?.unwrap_or_default(),
            permanent: permanent(&f)?,
        }
    } else if has("set-ip") {
        let f = Fields::new("pnio", m, &["set-ip", "mask", "gateway", "permanent"])?;
        PnioStep::SetIp {
            ip: ipv4(&f, "set-ip")?,
            mask: ipv4(&f, "mask")?,
            gateway: f
                .text("gateway")?
                .map(|g| {
                    g.parse()
                        .map_err(|e| FieldError::value("pnio.gateway", format!("{e}")))
                })
                .transpose()?
                .unwrap_or(Ipv4Addr::UNSPECIFIED),
            permanent: permanent(&f)?,
        }
    } else if has("signal") {
        Fields::new("pnio", m, &["signal"])?;
        PnioStep::Signal
    } else if has("reset-factory") {
        Fields::new("pnio", m, &["reset-factory"])?;
        PnioStep::ResetFactory
    } else if has("connect") {
        let f = Fields::new("pnio", m, &["connect", "reduction-ratio"])?;
        let reduction_ratio = match f.int("reduction-ratio")? {
            None => 1,
            // IEC 61158-6-10: 1…512 for RT class 1 frames.
            Some(n @ 1..=512) => n as u16,
            Some(n) => {
                return Err(FieldError::value(
                    "pnio.reduction-ratio",
                    format!("{n} is not 1…512"),
                ))
            }
        };
        let modules = match &m["connect"] {
            Value::Array(a) => a.iter().map(module).collect::<Result<_, _>>()?,
            Value::Bool(true) | Value::Null => Vec::new(),
            other => vec![module(other)?],
        };
        PnioStep::Connect {
            modules,
            reduction_ratio,
        }
    } else if has("release") {
        Fields::new("pnio", m, &["release"])?;
        PnioStep::Release
    } else if has("device-access") {
        Fields::new("pnio", m, &["device-access"])?;
        PnioStep::DeviceAccess
    } else if has("read") {
        let f = Fields::new("pnio", m, &["read", "slot", "subslot"])?;
        PnioStep::Read {
            index: word(&f, "read")?.ok_or("`pnio.read`: give a record index")?,
            slot: word(&f, "slot")?,
            subslot: word(&f, "subslot")?,
        }
    } else if has("write") {
        let f = Fields::new("pnio", m, &["write", "slot", "subslot", "data"])?;
        PnioStep::Write {
            index: word(&f, "write")?.ok_or("`pnio.write`: give a record index")?,
            slot: word(&f, "slot")?,
            subslot: word(&f, "subslot")?,
            data: bytes(&f, "data")?,
        }
    } else if has("alarm") {
        let f = Fields::new("pnio", m, &["alarm"])?;
        PnioStep::Alarm(duration(&f, "alarm")?)
    } else if has("silence") {
        let f = Fields::new("pnio", m, &["silence"])?;
        PnioStep::Silence(duration(&f, "silence")?)
    } else if has("lldp") {
        let f = Fields::new("pnio", m, &["lldp"])?;
        PnioStep::Lldp(duration(&f, "lldp")?)
    } else if has("cycles") {
        let f = Fields::new("pnio", m, &["cycles"])?;
        let n = f.req_int("cycles")?;
        PnioStep::Cycles(
            u64::try_from(n)
                .ok()
                .filter(|n| (1..=100_000).contains(n))
                .ok_or(FieldError::value(
                    "pnio.cycles",
                    format!("{n} is not 1..=100000"),
                ))?,
        )
    } else if has("frame") {
        let f = Fields::new("pnio", m, &["frame"])?;
        PnioStep::Frame(bytes(&f, "frame")?)
    } else if has("rpc") {
        let f = Fields::new("pnio", m, &["rpc", "body", "interface"])?;
        PnioStep::Rpc {
            opnum: word(&f, "rpc")?.ok_or("`pnio.rpc`: give an opnum")?,
            body: bytes(&f, "body")?,
            interface: f.text("interface")?,
        }
    } else {
        return Err(
            "`pnio` needs one of `identify`, `set-name`, `set-ip`, `signal`, \
                    `reset-factory`, `connect`, `release`, `device-access`, `read`, `write`, `alarm`, \
                    `silence`, `lldp`, `cycles`, `frame`, `rpc`"
                .into(),
        );
    };
    Ok(Box::new(step))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn step(v: Value) -> PnioStep {
        let b = parse(&v).unwrap();
        b.as_any().downcast_ref::<PnioStep>().unwrap().clone()
    }

    #[test]
    fn steps_parse() {
        assert_eq!(step(json!({ "identify": "all" })), PnioStep::Identify(None));
        assert_eq!(step(json!({ "identify": "own" })), PnioStep::IdentifyOwn);
        assert_eq!(
            step(json!({ "identify": "sk550p-1" })),
            PnioStep::Identify(Some("sk550p-1".into()))
        );
        assert_eq!(
            step(json!({ "set-name": "drive-1", "permanent": false })),
            PnioStep::SetName {
                name: "drive-1".into(),
                permanent: false
            }
        );
        assert_eq!(
            step(json!({ "connect": ["ppo4", "ppo1", "0x99"], "reduction-ratio": 4 })),
            PnioStep::Connect {
                modules: vec![
                    Module::Ppo(PpoType::TYPE_4),
                    Module::Ppo(PpoType::TYPE_1),
                    Module::Ident(0x99)
                ],
                reduction_ratio: 4
            }
        );
        assert_eq!(
            step(json!({ "write": 101, "data": "24 4E 01 00 00 00 00 FA" })),
            PnioStep::Write {
                index: 101,
                slot: None,
                subslot: None,
                data: vec![0x24, 0x4E, 1, 0, 0, 0, 0, 0xFA]
            }
        );
        assert_eq!(
            step(json!({ "set-ip": "192.168.0.7", "mask": "255.255.255.0" })),
            PnioStep::SetIp {
                ip: Ipv4Addr::new(192, 168, 0, 7),
                mask: Ipv4Addr::new(255, 255, 255, 0),
                gateway: Ipv4Addr::UNSPECIFIED,
                permanent: true
            }
        );
        assert_eq!(
            step(json!({ "device-access": true })),
            PnioStep::DeviceAccess
        );
        assert_eq!(
            step(json!({ "silence": "300ms" })),
            PnioStep::Silence(Duration::from_millis(300))
        );
    }

    #[test]
    fn bad_steps_say_what_is_wrong() {
        let e = |v: Value| parse(&v).unwrap_err().to_string();
        assert!(e(json!({ "connect": ["ppo5"] })).contains("is not ppo1"));
        assert!(e(json!({ "read": 70000 })).contains("not 0..=FFFFh"));
        assert!(e(json!({ "set-ip": "300.1.1.1", "mask": "255.0.0.0" })).contains("pnio.set-ip"));
        assert!(e(json!({ "cycles": 0 })).contains("1..=100000"));
        assert!(e(json!({ "connect": true, "reduction-ratio": 0 })).contains("1…512"));
        assert!(e(json!({ "jump": true })).contains("needs one of"));
        assert!(e(json!({ "read": 100, "slott": 3 })).contains("no field `slott`"));
    }
}
