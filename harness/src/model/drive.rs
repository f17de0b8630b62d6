//! Compute functions of the `drive` theme: control/status words, the status machine, scaling.

use proto::nord::control::ControlWord;
use proto::nord::scaling;
use proto::nord::state_machine::{self, State};
use proto::nord::status::StatusWord;
use serde_json::{json, Value};

use super::{Args, ComputeError, ComputeFn, Ctx};

fn word(a: &Args, name: &str) -> Result<u16, ComputeError> {
    let v = a.int(name)?;
    u16::try_from(v).map_err(|_| ComputeError::Refused(format!("{v} does not fit 16 bits")))
}

fn to_json<T: serde::Serialize>(v: T) -> Result<Value, ComputeError> {
    serde_json::to_value(v).map_err(|e| ComputeError::Refused(e.to_string()))
}

fn next(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let from = a.str("state")?;
    let state = State::from_name(from).ok_or_else(|| ComputeError::BadArg {
        arg: "state".into(),
        why: format!("no state `{from}`"),
    })?;
    let previous = ControlWord(a.opt_int("previous")?.unwrap_or(0) as u16);
    Ok(
        match state_machine::next(state, ControlWord(word(a, "control")?), previous) {
            Some(t) => {
                json!({ "transition": t.number, "to": t.to.name(), "letter": t.to.letter().to_string() })
            }
            None => {
                json!({ "transition": null, "to": state.name(), "letter": state.letter().to_string() })
            }
        },
    )
}

fn state_bits(_: &Ctx, a: &Args) -> Result<Value, ComputeError> {
    let name = a.str("state")?;
    let s = State::from_name(name).ok_or_else(|| ComputeError::BadArg {
        arg: "state".into(),
        why: format!("no state `{name}`"),
    })?;
    let (mask, value) = s.status_pattern();
    Ok(json!({ "mask": mask, "value": value, "letter": s.letter().to_string(), "name": s.name() }))
}

/// The functions of this theme.
pub(super) const FNS: &[ComputeFn] = &[
    ComputeFn {
        name: "drive.control",
        doc: "Control word bits by name (BU 0620 §6.1.2.1)",
        run: |_: &Ctx, a: &Args| to_json(ControlWord(word(a, "word")?).fields()),
    },
    ComputeFn {
        name: "drive.status",
        doc: "Status word bits by name and the decoded state (BU 0620 §6.1.2.2, §6.1.2.3)",
        run: |_: &Ctx, a: &Args| to_json(StatusWord(word(a, "word")?).fields()),
    },
    ComputeFn {
        name: "drive.next",
        doc: "Transition a control word triggers from a state (§6.1.2.3)",
        run: next,
    },
    ComputeFn {
        name: "drive.state_bits",
        doc: "Status bits 0–6 (mask, value) of a state (§6.1.2.3)",
        run: state_bits,
    },
    ComputeFn {
        name: "drive.percent",
        doc: "Raw process value of a percentage and back (4000h = 100 %, §6.1.2.4)",
        run: |_: &Ctx, a: &Args| match a.opt_int("raw")? {
            Some(raw) => {
                Ok(json!({ "percent": scaling::raw_to_percent(raw as i16), "raw": raw as i16 }))
            }
            None => {
                let p = a.int("percent")?;
                Ok(json!({ "raw": scaling::percent_to_raw(p as f64) }))
            }
        },
    },
    ComputeFn {
        name: "drive.value",
        doc: "Physical value of a raw process value: raw × reference / 16384 (§6.1.2.4)",
        run: |_: &Ctx, a: &Args| {
            let reference = a.int("reference_tenths")? as f64 / 10.0;
            Ok(json!({ "value": scaling::raw_to_value(a.int("raw")? as i16, reference) }))
        },
    },
    ComputeFn {
        name: "drive.resolution",
        doc: "Transferred integer of a value at a resolution (99.99 s at 0.01 → 9999, §2.5.6.3)",
        run: |_: &Ctx, a: &Args| {
            let hundredths = a.int("hundredths")?;
            let decimals = a.int("decimals")? as u8;
            Ok(json!({ "raw": scaling::to_raw(hundredths as f64 / 100.0, decimals) }))
        },
    },
    ComputeFn {
        name: "drive.position",
        doc: "A 32-bit position as low and high word (§6.1.2.4)",
        run: |_: &Ctx, a: &Args| {
            let p = i32::try_from(a.int("position")?)
                .map_err(|_| ComputeError::Refused("position does not fit 32 bits".into()))?;
            if p.abs() > scaling::POSITION_LIMIT {
                return Err(ComputeError::Refused(format!(
                    "position {p} is beyond ±50000.00 rotations"
                )));
            }
            let (low, high) = scaling::position_words(p);
            Ok(json!({ "low": low, "high": high }))
        },
    },
];
