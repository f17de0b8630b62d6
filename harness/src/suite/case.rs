//! Validated cases: what the runner executes. Built from the schema with every value checked.

use proto::nord::{ArrayElement, Inverter, ParamNumber, ParamSet, Product};
use serde_json::{Map, Value};
use std::time::Duration;

use super::schema::{CaseDoc, StepDoc};
use crate::model::{self, ComputeFn};
use crate::notation::{int_of, Matcher};
use crate::outcome::{Erratum, ManualRef};
use crate::profile::Capability;

/// A case ready to run.
#[derive(Debug)]
pub(crate) struct Case {
    /// Full id, `<folder>/<file>/<id>`.
    pub(crate) id: String,
    pub(crate) title: String,
    pub(crate) manual: ManualRef,
    /// Products the case is about; `None` = all.
    pub(crate) products: Option<Vec<Product>>,
    pub(crate) requires: Vec<Capability>,
    pub(crate) errata: Vec<Erratum>,
    pub(crate) steps: Vec<Step>,
}

/// One step.
#[derive(Debug)]
pub(crate) struct Step {
    pub(crate) action: Action,
    pub(crate) expect: Option<Matcher>,
    /// A failing setup step makes the case inconclusive.
    pub(crate) setup: bool,
}

impl Step {
    /// What the step needs from the DUT: its action's capability, and the parameter channel
    /// itself when a read/write forces an order label, writes RAM only (labels 11–14), or
    /// expects fields only a PKW response has (response label, error number, PNU, IND).
    pub(crate) fn needs(&self) -> Vec<Capability> {
        let mut v: Vec<Capability> = self.action.needs().into_iter().collect();
        if let Action::Read(o) | Action::Write(o) = &self.action {
            let pkw_fields = self
                .expect
                .as_ref()
                .is_some_and(|m| ["ak", "error", "pnu", "ind"].iter().any(|k| m.mentions(k)));
            if o.ak.is_some() || !o.eeprom || o.dword.is_some() || pkw_fields {
                v.push(Capability::ParameterChannel);
            }
        }
        v
    }
}

/// Where a parameter order goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Target {
    /// The bus interface's own parameters.
    Interface,
    /// An inverter.
    Inverter(Inverter),
}

/// A `read:` or `write:` step's order.
#[derive(Debug, Clone)]
pub(crate) struct OrderSpec {
    pub(crate) target: Target,
    pub(crate) number: ParamNumber,
    pub(crate) set: Option<ParamSet>,
    pub(crate) element: Option<ArrayElement>,
    /// Forced order label.
    pub(crate) ak: Option<u8>,
    /// Value to write.
    pub(crate) value: Option<i64>,
    /// `false`: RAM-only labels 11–14.
    pub(crate) eeprom: bool,
    /// Forced double-word transfer.
    pub(crate) dword: Option<bool>,
}

impl OrderSpec {
    /// `P102 set 3 [-02] FI 5`, or `P850 interface`.
    pub(crate) fn describe(&self) -> String {
        let mut s = self.number.to_string();
        if let Some(set) = self.set {
            s += &format!(" set {}", set.get());
        }
        if let Some(e) = self.element {
            s += &format!(" [-{:02}]", e.get());
        }
        match self.target {
            Target::Interface => s + " interface",
            Target::Inverter(i) => format!("{s} {i}"),
        }
    }
}

/// What a step does.
#[derive(Debug)]
pub(crate) enum Action {
    /// Call a reference-model function.
    Compute {
        func: &'static ComputeFn,
        args: Map<String, Value>,
        product: Option<Product>,
    },
    /// Read a parameter.
    Read(OrderSpec),
    /// Write a parameter.
    Write(OrderSpec),
    /// Send one raw PKW order.
    Pkw { inverter: Inverter, bytes: [u8; 8] },
    /// Exchange process data.
    Process {
        inverter: Inverter,
        control: u16,
        setpoints: Vec<u16>,
        run: Run,
    },
    /// Keep the process data running.
    Wait(Duration),
    /// Raise an inverter error.
    Inject { inverter: Inverter, error: String },
    /// Look at internal state.
    Observe { what: String, inverter: Inverter },
    /// An EtherNet/IP message of the protocol suites.
    Enip(EnipStep),
}

/// An `enip:` step. `client` picks the TCP connection: 1 is the scanner's own, 2.. are other
/// clients of the same target (each with its own session), to show a target keeps serving
/// others after one client misbehaved.
#[derive(Debug, Clone)]
pub(crate) enum EnipStep {
    /// Encapsulation bytes as written; `session` puts the client's session handle in bytes
    /// 4..8 (registering one first).
    Raw {
        bytes: Vec<u8>,
        session: bool,
        client: u8,
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
    ForwardOpen(crate::binding::enip::ForwardOpenSpec),
    /// The scanner stops sending O→T data for this long.
    StopIo { time: Duration },
    /// The run/idle header of the following O→T frames: run (`true`) or idle.
    Run(bool),
}

/// How long a `process:` step runs.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Run {
    Cycles(u32),
    For(Duration),
}

impl Action {
    /// The capabilities a step needs.
    pub(crate) fn needs(&self) -> Option<Capability> {
        match self {
            Action::Compute { .. } => None,
            Action::Read(_) | Action::Write(_) => Some(Capability::ParameterAccess),
            Action::Pkw { .. } => Some(Capability::ParameterChannel),
            Action::Process { .. } | Action::Wait(_) => Some(Capability::ProcessData),
            Action::Inject { .. } => Some(Capability::FaultInjection),
            Action::Observe { .. } => Some(Capability::Observe),
            Action::Enip(_) => Some(Capability::Ethernetip),
        }
    }
}

/// Parses `200ms`, `2s`, `1.5s`.
pub(crate) fn parse_duration(s: &str) -> Result<Duration, String> {
    let t = s.trim();
    let (num, scale) = if let Some(n) = t.strip_suffix("ms") {
        (n, 1e-3)
    } else if let Some(n) = t.strip_suffix('s') {
        (n, 1.0)
    } else {
        return Err(format!("`{s}` is not a duration (write 200ms or 2s)"));
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v >= 0.0 && v.is_finite() && v * scale <= 3600.0 => {
            Ok(Duration::from_secs_f64(v * scale))
        }
        _ => Err(format!("`{s}` is not a duration between 0 and 1 h")),
    }
}

/// Reads the fields of an action map, refusing unknown keys.
struct Fields<'a> {
    action: &'static str,
    map: &'a Map<String, Value>,
}

impl<'a> Fields<'a> {
    fn new(
        action: &'static str,
        map: &'a Map<String, Value>,
        allowed: &[&str],
    ) -> Result<Self, String> {
        if let Some(k) = map.keys().find(|k| !allowed.contains(&k.as_str())) {
            return Err(format!(
                "`{action}` has no field `{k}` (fields: {})",
                allowed.join(", ")
            ));
        }
        Ok(Fields { action, map })
    }

    fn int(&self, key: &str) -> Result<Option<i64>, String> {
        self.map
            .get(key)
            .map(|v| int_of(v).map_err(|e| format!("`{}.{key}`: {e}", self.action)))
            .transpose()
    }

    fn req_int(&self, key: &str) -> Result<i64, String> {
        self.int(key)?
            .ok_or_else(|| format!("`{}` needs `{key}`", self.action))
    }

    fn ranged<T>(
        &self,
        key: &str,
        f: fn(i64) -> Result<T, proto::nord::RangeError>,
    ) -> Result<Option<T>, String> {
        self.int(key)?
            .map(|v| f(v).map_err(|e| format!("`{}.{key}`: {e}", self.action)))
            .transpose()
    }

    fn inverter(&self) -> Result<Inverter, String> {
        Ok(self
            .ranged("inverter", Inverter::new)?
            .unwrap_or(Inverter::new(1).expect("FI 1 exists")))
    }

    fn word(&self, key: &str) -> Result<u16, String> {
        let v = self.req_int(key)?;
        u16::try_from(v).map_err(|_| format!("`{}.{key}`: {v} is not a 16-bit word", self.action))
    }

    fn text(&self, key: &str) -> Result<Option<String>, String> {
        match self.map.get(key) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.clone())),
            Some(Value::Number(n)) => Ok(Some(n.to_string())),
            Some(other) => Err(format!(
                "`{}.{key}`: expected text, got {other}",
                self.action
            )),
        }
    }

    fn bool(&self, key: &str) -> Result<Option<bool>, String> {
        match self.map.get(key) {
            None => Ok(None),
            Some(Value::Bool(b)) => Ok(Some(*b)),
            Some(other) => Err(format!(
                "`{}.{key}`: expected true or false, got {other}",
                self.action
            )),
        }
    }
}

fn order(action: &'static str, map: &Map<String, Value>, write: bool) -> Result<OrderSpec, String> {
    let mut allowed = vec!["param", "inverter", "set", "element", "target", "ak"];
    if write {
        allowed.extend(["value", "eeprom", "width"]);
    }
    let f = Fields::new(action, map, &allowed)?;
    let target = match f.text("target")?.as_deref() {
        None | Some("inverter") => Target::Inverter(f.inverter()?),
        Some("interface") => Target::Interface,
        Some(other) => {
            return Err(format!(
                "`{action}.target`: `{other}` is neither `interface` nor `inverter`"
            ))
        }
    };
    let ak = f
        .int("ak")?
        .map(|v| {
            u8::try_from(v)
                .ok()
                .filter(|a| *a <= 15)
                .ok_or(format!("`{action}.ak`: {v} is not 0..=15"))
        })
        .transpose()?;
    let dword = match f.text("width")?.as_deref() {
        None => None,
        Some("word") => Some(false),
        Some("dword") => Some(true),
        Some(other) => {
            return Err(format!(
                "`{action}.width`: `{other}` is neither `word` nor `dword`"
            ))
        }
    };
    let value = if write {
        Some(f.req_int("value")?)
    } else {
        None
    };
    Ok(OrderSpec {
        target,
        number: f
            .ranged("param", ParamNumber::new)?
            .ok_or(format!("`{action}` needs `param`"))?,
        set: f.ranged("set", ParamSet::new)?,
        element: f.ranged("element", ArrayElement::new)?,
        ak,
        value,
        eeprom: f.bool("eeprom")?.unwrap_or(true),
        dword,
    })
}

fn hex8(text: &str) -> Result<[u8; 8], String> {
    let bytes: Result<Vec<u8>, _> = text
        .split_whitespace()
        .map(|t| u8::from_str_radix(t, 16))
        .collect();
    match bytes {
        Ok(b) if b.len() == 8 => Ok(b.try_into().expect("length checked")),
        Ok(b) => Err(format!("`pkw.bytes` needs 8 bytes, got {}", b.len())),
        Err(_) => Err(format!(
            "`pkw.bytes`: `{text}` is not hex bytes like \"70 66 02 00 00 00 03 E8\""
        )),
    }
}

fn action(step: StepDoc) -> Result<Action, String> {
    let mut found: Vec<&str> = Vec::new();
    for (name, present) in [
        ("compute", step.compute.is_some()),
        ("read", step.read.is_some()),
        ("write", step.write.is_some()),
        ("pkw", step.pkw.is_some()),
        ("process", step.process.is_some()),
        ("wait", step.wait.is_some()),
        ("inject", step.inject.is_some()),
        ("observe", step.observe.is_some()),
        ("enip", step.enip.is_some()),
    ] {
        if present {
            found.push(name);
        }
    }
    if found.len() != 1 {
        return Err(format!(
            "a step needs exactly one action (compute, read, write, pkw, process, wait, inject, observe, enip); found {}",
            if found.is_empty() { "none".to_string() } else { found.join(", ") }
        ));
    }
    if step.args.is_some() && step.compute.is_none() {
        return Err("`args` goes with `compute`".into());
    }
    if let Some(name) = step.compute {
        let func = model::find(&name).ok_or_else(|| {
            format!("no compute function `{name}` (see `harness list --functions`)")
        })?;
        let mut args = step.args.unwrap_or_default();
        let product = match args.remove("product") {
            None => None,
            Some(Value::String(p)) => Some(
                Product::from_name(&p).ok_or(format!("`args.product`: unknown product `{p}`"))?,
            ),
            Some(other) => {
                return Err(format!(
                    "`args.product`: expected a product name, got {other}"
                ))
            }
        };
        return Ok(Action::Compute {
            func,
            args,
            product,
        });
    }
    if let Some(m) = step.read {
        return Ok(Action::Read(order("read", &m, false)?));
    }
    if let Some(m) = step.write {
        return Ok(Action::Write(order("write", &m, true)?));
    }
    if let Some(m) = step.pkw {
        let f = Fields::new("pkw", &m, &["inverter", "bytes"])?;
        let bytes = hex8(&f.text("bytes")?.ok_or("`pkw` needs `bytes`")?)?;
        return Ok(Action::Pkw {
            inverter: f.inverter()?,
            bytes,
        });
    }
    if let Some(m) = step.process {
        let f = Fields::new(
            "process",
            &m,
            &["inverter", "control", "setpoints", "cycles", "for"],
        )?;
        let setpoints = match m.get("setpoints") {
            None => Vec::new(),
            Some(Value::Array(items)) => items
                .iter()
                .map(|v| {
                    int_of(v).and_then(|i| {
                        u16::try_from(i)
                            .or_else(|_| i16::try_from(i).map(|s| s as u16))
                            .map_err(|_| format!("{i} is not a 16-bit word"))
                    })
                })
                .collect::<Result<_, _>>()
                .map_err(|e| format!("`process.setpoints`: {e}"))?,
            Some(other) => {
                return Err(format!("`process.setpoints`: expected a list, got {other}"))
            }
        };
        let run = match (f.int("cycles")?, f.text("for")?) {
            (Some(_), Some(_)) => return Err("`process` takes `cycles` or `for`, not both".into()),
            (Some(c), None) => Run::Cycles(
                u32::try_from(c)
                    .ok()
                    .filter(|c| (1..=100_000).contains(c))
                    .ok_or(format!("`process.cycles`: {c} is not 1..=100000"))?,
            ),
            (None, Some(d)) => Run::For(parse_duration(&d)?),
            (None, None) => Run::Cycles(1),
        };
        return Ok(Action::Process {
            inverter: f.inverter()?,
            control: f.word("control")?,
            setpoints,
            run,
        });
    }
    if let Some(d) = step.wait {
        return Ok(Action::Wait(parse_duration(&d)?));
    }
    if let Some(m) = step.inject {
        let f = Fields::new("inject", &m, &["inverter", "error"])?;
        return Ok(Action::Inject {
            inverter: f.inverter()?,
            error: f.text("error")?.ok_or("`inject` needs `error`")?,
        });
    }
    if let Some(m) = step.enip {
        return Ok(Action::Enip(enip_step(&m)?));
    }
    let m = step.observe.unwrap_or_default();
    let f = Fields::new("observe", &m, &["what", "inverter"])?;
    Ok(Action::Observe {
        what: f.text("what")?.ok_or("`observe` needs `what`")?,
        inverter: f.inverter()?,
    })
}

/// Hex bytes separated by spaces (`"65 00 04 00"`); empty text is no bytes.
/// Hex bytes in wire order: `"65 00 04 00"`, or grouped as `"6500 0400"`.
fn hex_bytes(action: &str, text: &str) -> Result<Vec<u8>, String> {
    let bad = || format!("`{action}`: `{text}` is not hex bytes like \"65 00 04 00\"");
    let mut out = Vec::new();
    for t in text.split_whitespace() {
        if t.len() % 2 != 0 {
            return Err(bad());
        }
        for i in (0..t.len()).step_by(2) {
            let b = t.get(i..i + 2).ok_or_else(bad)?;
            out.push(u8::from_str_radix(b, 16).map_err(|_| bad())?);
        }
    }
    Ok(out)
}

fn enip_step(m: &Map<String, Value>) -> Result<EnipStep, String> {
    let client = |f: &Fields| -> Result<u8, String> {
        match f.int("client")? {
            None => Ok(1),
            Some(v @ 1..=99) => Ok(v as u8),
            Some(v) => Err(format!("`enip.client`: {v} is not 1..=99")),
        }
    };
    if m.contains_key("raw") {
        let f = Fields::new("enip", m, &["raw", "session", "client"])?;
        return Ok(EnipStep::Raw {
            bytes: hex_bytes("enip.raw", &f.text("raw")?.unwrap_or_default())?,
            session: f.bool("session")?.unwrap_or(false),
            client: client(&f)?,
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
            ],
        )?;
        let d = crate::binding::enip::ForwardOpenSpec::default();
        let small = |k: &str| -> Result<Option<u16>, String> {
            f.int(k)?
                .map(|v| u16::try_from(v).map_err(|_| format!("`enip.{k}`: {v} is not 0..=65535")))
                .transpose()
        };
        let byte = |k: &str| -> Result<Option<u8>, String> {
            f.int(k)?
                .map(|v| u8::try_from(v).map_err(|_| format!("`enip.{k}`: {v} is not a byte")))
                .transpose()
        };
        let rpi = f
            .int("rpi_us")?
            .map(|v| u32::try_from(v).map_err(|_| format!("`enip.rpi_us`: {v} is not 32-bit")))
            .transpose()?;
        return Ok(EnipStep::ForwardOpen(
            crate::binding::enip::ForwardOpenSpec {
                o_t_point: small("o_t")?.unwrap_or(d.o_t_point),
                t_o_point: small("t_o")?.unwrap_or(d.t_o_point),
                o_t_size: small("o_t_size")?.ok_or("`enip` needs `o_t_size`")?,
                t_o_size: small("t_o_size")?.ok_or("`enip` needs `t_o_size`")?,
                rpi_us: rpi.unwrap_or(d.rpi_us),
                transport: byte("transport")?.unwrap_or(d.transport),
                multiplier: byte("multiplier")?.unwrap_or(d.multiplier),
                large: f.bool("large")?.unwrap_or(false),
                run_idle: f.bool("run_idle")?.unwrap_or(d.run_idle),
            },
        ));
    }
    if m.contains_key("stop_io") {
        let f = Fields::new("enip", m, &["stop_io"])?;
        return Ok(EnipStep::StopIo {
            time: parse_duration(&f.text("stop_io")?.unwrap_or_default())?,
        });
    }
    if m.contains_key("run") {
        let f = Fields::new("enip", m, &["run"])?;
        return Ok(EnipStep::Run(f.bool("run")?.unwrap_or(true)));
    }
    Err("`enip` needs one of `raw`, `mr`, `service`, `forward_open`, `stop_io`, `run`".into())
}

/// Converts one step; the error text is placed by the loader.
pub(super) fn step(doc: StepDoc) -> Result<Step, String> {
    let expect = doc
        .expect
        .as_ref()
        .map(Matcher::parse)
        .transpose()
        .map_err(|e| format!("expect: {e}"))?;
    let setup = doc.setup;
    Ok(Step {
        action: action(doc)?,
        expect,
        setup,
    })
}

/// Converts the case-level fields (not the steps).
pub(super) fn case_head(
    id: String,
    doc: &CaseDoc,
    file_doc: &str,
    file_edition: &str,
) -> Result<Case, String> {
    if doc.id.is_empty()
        || !doc
            .id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '.' || c == '_')
    {
        return Err(format!("case id `{}` must be non-empty kebab-case", doc.id));
    }
    let manual = ManualRef {
        doc: doc
            .reference
            .doc
            .clone()
            .unwrap_or_else(|| file_doc.to_string()),
        edition: doc
            .reference
            .edition
            .clone()
            .unwrap_or_else(|| file_edition.to_string()),
        section: doc.reference.section.clone(),
        page: doc.reference.page,
    };
    // A NORD manual is cited by page as printed; a specification (the ODVA CIP volumes) by
    // section and table.
    if manual.page.is_none() && manual.doc.starts_with("BU ") {
        return Err(format!("`ref` of a case from {} needs `page`", manual.doc));
    }
    let products = doc
        .profiles
        .as_ref()
        .map(|names| {
            names
                .iter()
                .map(|n| {
                    Product::from_name(n)
                        .ok_or_else(|| crate::profile::Profile::by_name(n).unwrap_err())
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .transpose()?;
    let requires = doc
        .requires
        .iter()
        .map(|r| {
            Capability::from_name(r).ok_or_else(|| {
                let known: Vec<&str> = Capability::ALL.iter().map(|c| c.name()).collect();
                format!("unknown capability `{r}` (one of {})", known.join(", "))
            })
        })
        .collect::<Result<_, _>>()?;
    Ok(Case {
        id,
        title: doc.title.clone(),
        manual,
        products,
        requires,
        errata: Vec::new(),
        steps: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    #[case("200ms", Duration::from_millis(200))]
    #[case("2s", Duration::from_secs(2))]
    #[case("1.5s", Duration::from_millis(1500))]
    fn durations(#[case] s: &str, #[case] d: Duration) {
        assert_eq!(parse_duration(s), Ok(d));
    }

    #[rstest]
    #[case("200")]
    #[case("-1s")]
    #[case("2h")]
    fn bad_durations(#[case] s: &str) {
        assert!(parse_duration(s).is_err());
    }

    #[test]
    fn pkw_bytes_need_eight() {
        assert_eq!(
            hex8("70 66 02 00 00 00 03 E8"),
            Ok([0x70, 0x66, 2, 0, 0, 0, 3, 0xE8])
        );
        assert!(hex8("70 66").unwrap_err().contains("8 bytes"));
        assert!(hex8("zz 66 02 00 00 00 03 E8").is_err());
    }
}
