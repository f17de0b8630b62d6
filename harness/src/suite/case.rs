//! Validated cases: what the runner executes. Built from the schema with every value checked.

use proto::nord::{ArrayElement, Inverter, ParamNumber, ParamSet, Product};
use serde_json::{Map, Value};
use std::time::Duration;

use super::fields::Fields;
use super::schema::{CaseDoc, StepDoc};
use super::Vocabulary;
use crate::model::{self, ComputeFn};
use crate::notation::{int_of, Matcher};
use crate::outcome::{CaseKind, Erratum, ManualRef};
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

impl Case {
    /// Whether the case checks the device (it requires something of the DUT, or a step reaches
    /// it) or only the reference model (every step is a `compute`): the same rule the runner
    /// labels results with, for reports that have the suites but no run (`harness coverage`).
    pub(crate) fn kind(&self) -> CaseKind {
        if !self.requires.is_empty() || self.steps.iter().any(|s| !s.needs().is_empty()) {
            CaseKind::Device
        } else {
            CaseKind::Model
        }
    }
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

impl Target {
    /// The inverter, or `None` for the interface.
    pub(crate) fn inverter(self) -> Option<Inverter> {
        match self {
            Target::Inverter(fi) => Some(fi),
            Target::Interface => None,
        }
    }
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
    /// A plain read of `number` at `target`: no set, no element, the default labels (what a
    /// binding reads for itself, e.g. before a write or in a cleanup).
    pub(crate) fn read(target: Target, number: ParamNumber) -> OrderSpec {
        OrderSpec {
            target,
            number,
            set: None,
            element: None,
            ak: None,
            value: None,
            eeprom: true,
            dword: None,
        }
    }

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
    /// A step in a bus's own terms, performed only by that bus's binding.
    Bus(Box<dyn super::BusStep>),
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
            Action::Observe { what, .. } if what == "system-bus" => Some(Capability::SystemBus),
            Action::Observe { .. } => Some(Capability::Observe),
            Action::Bus(step) => Some(Capability::Bus(step.bus())),
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

/// The manual-level actions a step may have (besides a bus's own step).
const ACTIONS: &str = "compute, read, write, pkw, process, wait, inject, observe";

fn action(vocabulary: &Vocabulary, step: StepDoc) -> Result<Action, String> {
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
    ] {
        if present {
            found.push(name);
        }
    }
    for key in step.bus.keys() {
        if vocabulary.step_parser(key).is_none() {
            return Err(format!(
                "a step has no key `{key}` (actions: {ACTIONS}, or a bus: {})",
                vocabulary.bus_names()
            ));
        }
        found.push(key);
    }
    if found.len() != 1 {
        return Err(format!(
            "a step needs exactly one action ({ACTIONS}, or a bus: {}); found {}",
            vocabulary.bus_names(),
            if found.is_empty() {
                "none".to_string()
            } else {
                found.join(", ")
            }
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
    if let Some((key, value)) = step.bus.into_iter().next() {
        let parse = vocabulary.step_parser(&key).expect("checked above");
        return Ok(Action::Bus(parse(&value)?));
    }
    let m = step.observe.unwrap_or_default();
    let f = Fields::new("observe", &m, &["what", "inverter"])?;
    Ok(Action::Observe {
        what: f.text("what")?.ok_or("`observe` needs `what`")?,
        inverter: f.inverter()?,
    })
}

/// Converts one step; the error text is placed by the loader.
pub(super) fn step(vocabulary: &Vocabulary, doc: StepDoc) -> Result<Step, String> {
    let expect = doc
        .expect
        .as_ref()
        .map(Matcher::parse)
        .transpose()
        .map_err(|e| format!("expect: {e}"))?;
    let setup = doc.setup;
    Ok(Step {
        action: action(vocabulary, doc)?,
        expect,
        setup,
    })
}

/// Converts the case-level fields (not the steps).
pub(super) fn case_head(
    vocabulary: &Vocabulary,
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
        quote: doc.reference.quote.clone(),
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
                    Product::from_name(n).ok_or_else(|| match vocabulary.catalog.by_name(n) {
                        Ok(p) => format!(
                            "`profiles` names products; `{n}` is a profile: give `{}` and \
                             `requires: [{}]`",
                            p.product.map_or("a product", |p| p.name()),
                            p.bus.unwrap_or("BUS")
                        ),
                        Err(e) => e,
                    })
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .transpose()?;
    let requires = doc
        .requires
        .iter()
        .map(|r| {
            vocabulary.catalog.capability(r).ok_or_else(|| {
                let caps = vocabulary.catalog.capabilities();
                let known: Vec<&str> = caps.iter().map(|c| c.name()).collect();
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
