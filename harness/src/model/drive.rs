//! Compute functions of the `drive` theme: control/status words, the status machine, scaling
//! (BU 0620 §6.1.2–§6.1.3, §2.5.6.3; BU 2100 §6.2; BU 2200 §6.3; BU 0590 §4.1).

use proto::nord::control::{self, BitDef, ControlWord};
use proto::nord::scaling::{self, ProcessFunction, ScalingError, Transmission};
use proto::nord::state_machine::{self, State};
use proto::nord::status::{self, StatusWord};
use serde_json::{json, Value};

use super::{Args, ComputeError, ComputeFn, Ctx};

fn bad(arg: &str, why: impl Into<String>) -> ComputeError {
    ComputeError::BadArg {
        arg: arg.to_string(),
        why: why.into(),
    }
}

fn refused(e: ScalingError) -> ComputeError {
    ComputeError::Refused(e.to_string())
}

/// A 16-bit word: 0..=FFFFh.
fn word(a: &Args, name: &str) -> Result<u16, ComputeError> {
    let v = a.int(name)?;
    u16::try_from(v).map_err(|_| ComputeError::Refused(format!("{name} {v} does not fit 16 bits")))
}

/// A 16-bit process value, signed (-32768..=32767) or as its word (8000h..FFFFh).
fn process_value(a: &Args, name: &str) -> Result<i16, ComputeError> {
    let v = a.int(name)?;
    i16::try_from(v)
        .or_else(|_| u16::try_from(v).map(|w| w as i16))
        .map_err(|_| {
            refused(ScalingError::ProcessRange {
                what: "process value",
                value: v.to_string(),
            })
        })
}

/// A decimal number given as text (`"99.99"`) or as a YAML number.
fn decimal_text(a: &Args, name: &str) -> Result<Option<String>, ComputeError> {
    match a.0.get(name) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::String(s)) => Ok(Some(s.clone())),
        Some(Value::Number(n)) => Ok(Some(n.to_string())),
        Some(other) => Err(bad(name, format!("expected a decimal number, got {other}"))),
    }
}

fn decimals(a: &Args) -> Result<u8, ComputeError> {
    let d = a.int("decimals")?;
    u8::try_from(d)
        .ok()
        .filter(|d| *d <= 6)
        .ok_or_else(|| bad("decimals", format!("{d} is not 0..6")))
}

fn state_arg(a: &Args) -> Result<State, ComputeError> {
    let name = a.str("state")?;
    State::from_name(name).ok_or_else(|| bad("state", format!("no state `{name}`")))
}

fn to_json<T: serde::Serialize>(v: T) -> Result<Value, ComputeError> {
    serde_json::to_value(v).map_err(|e| ComputeError::Refused(e.to_string()))
}

/// One row of a bit table (`bit` 0..15).
fn bit_row(a: &Args, table: &[BitDef; 16]) -> Result<Value, ComputeError> {
    let n = a.int("bit")?;
    let row = usize::try_from(n)
        .ok()
        .and_then(|i| table.get(i))
        .ok_or_else(|| ComputeError::Refused(format!("bit {n} is not 0..15")))?;
    Ok(json!({
        "bit": n,
        "name": row.name,
        "when_0": row.when_0,
        "when_1": row.when_1,
        "priority_0": row.priority[0],
        "priority_1": row.priority[1],
    }))
}

fn next(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let state = state_arg(a)?;
    let control = ControlWord(word(a, "control")?);
    let previous = ControlWord(
        a.opt_int("previous")?
            .map_or(Ok(0), |_| word(a, "previous"))?,
    );
    Ok(match state_machine::next(state, control, previous) {
        Some(t) => json!({
            "transition": t.number,
            "to": t.to.name(),
            "letter": t.to.letter().to_string(),
            "command": t.trigger.name(),
            "priority": t.trigger.priority(),
        }),
        None => json!({
            "transition": null,
            "to": state.name(),
            "letter": state.letter().to_string(),
            "command": null,
            "priority": null,
        }),
    })
}

fn state_bits(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let s = state_arg(a)?;
    let (mask, value) = s.status_bits();
    Ok(json!({ "mask": mask, "value": value, "letter": s.letter().to_string(), "name": s.name() }))
}

fn percent(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    if a.raw_present("raw") {
        let raw = process_value(a, "raw")?;
        return Ok(
            json!({ "percent": scaling::raw_to_percent(raw), "raw": raw, "word": raw as u16 }),
        );
    }
    let text =
        decimal_text(a, "percent")?.ok_or_else(|| bad("percent", "missing (or give raw)"))?;
    let p: f64 = text
        .parse()
        .map_err(|_| bad("percent", format!("`{text}` is not a number")))?;
    let raw = scaling::percent_to_raw(p).map_err(refused)?;
    Ok(json!({ "raw": raw, "word": raw as u16 }))
}

fn resolution(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let d = decimals(a)?;
    if a.raw_present("raw") {
        let raw = a.int("raw")?;
        return Ok(json!({ "value": scaling::from_raw(raw, d), "raw": raw }));
    }
    let text = match (decimal_text(a, "value")?, a.opt_int("hundredths")?) {
        (Some(t), _) => t,
        // `hundredths: 9999` is 99.99 (older suites).
        (None, Some(h)) => scaling::from_raw(h, 2),
        (None, None) => return Err(bad("value", "missing (or give raw)")),
    };
    let raw = scaling::to_raw(&text, d).map_err(refused)?;
    Ok(json!({ "raw": raw, "value": text }))
}

fn position(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    if a.raw_present("low") && a.raw_present("high") {
        let p = scaling::position_of(word(a, "low")?, word(a, "high")?);
        return Ok(json!({
            "position": p,
            "rotations": scaling::from_raw(i64::from(p), 3),
        }));
    }
    if a.raw_present("low") {
        let p = scaling::position_of_low_word(word(a, "low")?);
        return Ok(json!({ "position": p, "rotations": scaling::from_raw(i64::from(p), 3) }));
    }
    let increments = match decimal_text(a, "rotations")? {
        Some(r) => i64::from(scaling::rotations_to_increments(&r).map_err(refused)?),
        None => a.int("position")?,
    };
    let (low, high) = scaling::position_words(increments).map_err(refused)?;
    Ok(json!({ "low": low, "high": high, "position": increments }))
}

fn function(
    table: &'static str,
    f: Option<&ProcessFunction>,
    code: i64,
) -> Result<Value, ComputeError> {
    let f = f.ok_or_else(|| {
        ComputeError::Refused(format!(
            "{table} {code} is reserved or not listed in these manuals"
        ))
    })?;
    let (transmission, reference) = match f.transmission {
        Transmission::Off => ("off", None),
        Transmission::Percent { reference } => ("percent", Some(reference)),
        Transmission::Binary => ("binary", None),
        Transmission::PositionLow => ("position_low", None),
        Transmission::PositionHigh => ("position_high", None),
        Transmission::Integer => ("integer", None),
        Transmission::Unstated => ("unstated", None),
    };
    Ok(
        json!({ "code": f.code, "name": f.name, "transmission": transmission, "reference": reference }),
    )
}

fn code(a: &Args) -> Result<(i64, i32), ComputeError> {
    let c = a.int("code")?;
    Ok((c, i32::try_from(c).unwrap_or(-1)))
}

/// The functions of this theme.
pub(super) const FNS: &[ComputeFn] = &[
    ComputeFn {
        name: "drive.control",
        doc: "Control word bits by name, its commands and priority (BU 0620 §6.1.2.1)",
        run: |_: &Ctx, a: &Args| to_json(ControlWord(word(a, "word")?).fields()),
    },
    ComputeFn {
        name: "drive.control_bit",
        doc: "One row of the control-word table: name, meaning of 0/1, priority (§6.1.2.1)",
        run: |_: &Ctx, a: &Args| bit_row(a, &control::BITS),
    },
    ComputeFn {
        name: "drive.status",
        doc: "Status word bits by name and the decoded state (BU 0620 §6.1.2.2, §6.1.2.3)",
        run: |_: &Ctx, a: &Args| to_json(StatusWord(word(a, "word")?).fields()),
    },
    ComputeFn {
        name: "drive.status_bit",
        doc: "One row of the status-word table: name, meaning of 0/1 (§6.1.2.2)",
        run: |_: &Ctx, a: &Args| bit_row(a, &status::BITS),
    },
    ComputeFn {
        name: "drive.next",
        doc: "Transition a control word triggers from a state (§6.1.2.3; `previous` for bit 7)",
        run: next,
    },
    ComputeFn {
        name: "drive.state_bits",
        doc: "Status bits 0–6 (mask, value) of a state (§6.1.2.3 decoded statuses)",
        run: state_bits,
    },
    ComputeFn {
        name: "drive.percent",
        doc: "Raw process value of a percentage and back (4000h = 100 %, §6.1.2.4)",
        run: percent,
    },
    ComputeFn {
        name: "drive.value",
        doc: "Physical value of a raw process value: raw × reference / 16384 (§6.1.2.4)",
        run: |_: &Ctx, a: &Args| {
            let reference = a.int("reference_tenths")? as f64 / 10.0;
            Ok(json!({ "value": scaling::raw_to_value(process_value(a, "raw")?, reference) }))
        },
    },
    ComputeFn {
        name: "drive.resolution",
        doc: "Transferred integer of a value at a resolution and back (99.99 at 0.01 → 9999, §2.5.6.3)",
        run: resolution,
    },
    ComputeFn {
        name: "drive.position",
        doc: "32-bit position ↔ low/high word; rotations ↔ increments (±50000.00, §6.1.2.4)",
        run: position,
    },
    ComputeFn {
        name: "drive.actual_fn",
        doc: "P543 actual-value function code: name and scaling (BU 0590 §5, BU 0620 §3.9)",
        run: |_: &Ctx, a: &Args| {
            let (c, i) = code(a)?;
            let mut v = function("P543", scaling::actual_function(i), c)?;
            if i == 5 {
                v["bits"] = json!(scaling::DIGITAL_IO_BITS);
            }
            Ok(v)
        },
    },
    ComputeFn {
        name: "drive.setpoint_fn",
        doc: "P546 setpoint function code: name and scaling (BU 0590 §5, BU 0620 §3.9)",
        run: |_: &Ctx, a: &Args| {
            let (c, i) = code(a)?;
            function("P546", scaling::setpoint_function(i), c)
        },
    },
];
