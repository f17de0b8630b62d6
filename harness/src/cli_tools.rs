//! `harness addr` and `harness decode`: the reference model at the command line.
//!
//! Both print the manuals' terms, or JSON with `--json`; bad input (inverter 9, parameter 1000,
//! malformed hex) is a one-line error naming the problem (exit 2).

use clap::{Args, Subcommand};
use proto::nord::params::{self, Owner};
use proto::nord::pkw::PkwRepr;
use proto::nord::{addr, control::ControlWord, status::StatusWord};
use proto::nord::{ArrayElement, Inverter, ParamAddress, ParamNumber, ParamSet, Product};
use serde_json::{json, Value};

use crate::exit::EXIT_PASS;
use crate::notation::int_of;

/// `harness addr`.
#[derive(Args, Debug)]
pub(crate) struct AddrArgs {
    /// Parameter: `P102` or `102`.
    param: String,
    /// Inverter FI 1..8.
    #[arg(long, default_value = "1")]
    inverter: String,
    /// Parameter set 1..4 (set-dependent parameters).
    #[arg(long)]
    set: Option<String>,
    /// Array element 1..64 (array parameters).
    #[arg(long)]
    index: Option<String>,
    /// Product whose address tables apply.
    #[arg(long, default_value = "sk550p")]
    profile: String,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// `harness decode`.
#[derive(Args, Debug)]
pub(crate) struct DecodeArgs {
    #[command(subcommand)]
    what: DecodeWhat,
    /// Print JSON: every reading as a typed field (PKW: `set`, `element`, `subindex` of IND,
    /// `parameter`, `value`, `error` …), the sentence as `meaning`.
    #[arg(long, global = true)]
    json: bool,
}

#[derive(Subcommand, Debug)]
enum DecodeWhat {
    /// A status word, e.g. `0B31h`.
    Status {
        /// The word, hex as the manuals print it (`0B31h`, `0x0B31` or `0B31`) or binary
        /// (`101100110001b`).
        word: String,
    },
    /// A control word, e.g. `047Eh`.
    Control {
        /// The word.
        word: String,
    },
    /// An 8-byte parameter-channel telegram, e.g. `70 66 02 00 00 00 03 E8`.
    Pkw {
        /// The bytes, in hex.
        #[arg(required = true, num_args = 1..)]
        bytes: Vec<String>,
        /// Read it as the inverter's response rather than the master's order.
        #[arg(long)]
        response: bool,
    },
}

fn number(what: &str, text: &str) -> Result<i64, String> {
    int_of(&json!(text)).map_err(|e| format!("{what}: {e}"))
}

fn word(text: &str) -> Result<u16, String> {
    let v = crate::notation::wire_value(text, 16).map_err(|e| format!("word: {e}"))?;
    // wire_value keeps it within 16 bits.
    Ok(v as u16)
}

/// Refuses an index or a set the catalogued parameter does not have (`--index` on a
/// parameter that is no array, `--set` on one that does not depend on the set): an address
/// for them would be one no device answers. A parameter the catalogue does not hold is taken
/// as given.
fn check_against_catalogue(product: Product, a: &ParamAddress) -> Result<(), String> {
    let Some(def) = params::lookup(product, Owner::Inverter, a.number) else {
        return Ok(());
    };
    let name = format!("P{} \"{}\"", def.number, def.name);
    if let Some(e) = a.element {
        match def.array {
            None => {
                return Err(format!(
                    "`--index {}`: {name} is not an array parameter",
                    e.get()
                ))
            }
            Some(n) if e.get() > n => {
                return Err(format!("`--index {}`: {name} has {n} elements", e.get()))
            }
            Some(_) => {}
        }
    }
    if let (Some(set), false) = (a.set, def.set_dependent) {
        return Err(format!(
            "`--set {}`: {name} does not depend on the parameter set",
            set.get()
        ));
    }
    Ok(())
}

/// Runs `harness addr`.
pub(crate) fn addr(a: AddrArgs) -> Result<i32, String> {
    let product = crate::profile::product_named(&a.profile)?;
    let p = a.param.strip_prefix(['P', 'p']).unwrap_or(&a.param);
    let address = ParamAddress {
        inverter: Inverter::new(number("inverter", &a.inverter)?).map_err(|e| e.to_string())?,
        number: ParamNumber::new(number("parameter", p)?).map_err(|e| e.to_string())?,
        set: a
            .set
            .map(|s| number("set", &s).and_then(|v| ParamSet::new(v).map_err(|e| e.to_string())))
            .transpose()?,
        element: a
            .index
            .map(|s| {
                number("index", &s).and_then(|v| ArrayElement::new(v).map_err(|e| e.to_string()))
            })
            .transpose()?,
    };
    check_against_catalogue(product, &address)?;
    let all = addr::all(product, address).map_err(|e| e.to_string())?;
    print_out(a.json, &all, &all.to_string())
}

/// Runs `harness decode`.
pub(crate) fn decode(a: DecodeArgs) -> Result<i32, String> {
    let (text, value) = decoded(a.what)?;
    print_out(a.json, &value, &format!("{text}\n"))
}

/// Prints `value` as JSON with `--json`, else `text` (its own line ends included).
fn print_out(json: bool, value: &impl serde::Serialize, text: &str) -> Result<i32, String> {
    if json {
        outln!(
            "{}",
            serde_json::to_string_pretty(value).map_err(|e| e.to_string())?
        );
    } else {
        out!("{text}");
    }
    Ok(EXIT_PASS)
}

/// The sentence, and the JSON: every reading as a typed field, with the sentence as `meaning`.
fn decoded(what: DecodeWhat) -> Result<(String, Value), String> {
    let (text, mut value) = match what {
        DecodeWhat::Status { word: w } => {
            let s = StatusWord(word(&w)?);
            (s.describe(), to_json(s.fields())?)
        }
        DecodeWhat::Control { word: w } => {
            let c = ControlWord(word(&w)?);
            (c.describe(), to_json(c.fields())?)
        }
        DecodeWhat::Pkw { bytes, response } => {
            let r = PkwRepr::parse(&pkw_bytes(&bytes)?).map_err(|e| format!("pkw: {e}"))?;
            let fields = if response {
                r.response_fields()
            } else {
                r.order_fields()
            };
            (fields.meaning.clone(), to_json(fields)?)
        }
    };
    if let Value::Object(m) = &mut value {
        m.insert("meaning".into(), Value::String(text.clone()));
    }
    Ok((text, value))
}

fn to_json(fields: impl serde::Serialize) -> Result<Value, String> {
    serde_json::to_value(fields).map_err(|e| e.to_string())
}

/// The bytes of a PKW telegram given as hex tokens (`70`, `66h`), at most 8.
fn pkw_bytes(tokens: &[String]) -> Result<Vec<u8>, String> {
    let joined = tokens.join(" ");
    let raw: Vec<u8> = joined
        .split_whitespace()
        .map(|t| {
            crate::notation::wire_value(t, 8)
                .map(|b| b as u8)
                .map_err(|e| format!("pkw: {e}"))
        })
        .collect::<Result<_, _>>()?;
    if raw.len() > proto::nord::pkw::PKW_LEN {
        return Err(format!("pkw: a telegram is 8 bytes, got {}", raw.len()));
    }
    Ok(raw)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pkw(bytes: &str, response: bool) -> Value {
        let what = DecodeWhat::Pkw {
            bytes: bytes.split(' ').map(String::from).collect(),
            response,
        };
        decoded(what).unwrap().1
    }

    #[test]
    fn pkw_order_ind_0200h_as_set_element_and_subindex() {
        // BU 0590 §4.2.4.4: `70 66 02 00 00 00 03 E8` writes 1000 to P102, IND 0200h.
        let v = pkw("70 66 02 00 00 00 03 E8", false);
        assert_eq!(v["set"], 3);
        assert_eq!(v["element"], 1);
        assert_eq!(v["subindex"], 2);
        assert_eq!(v["ind"], 0x0200);
        assert_eq!(v["ak"], 7);
        assert_eq!(v["label"], "Change parameter value (array, word)");
        assert_eq!(v["pnu"], 0x66);
        assert_eq!(v["parameter"], 102);
        assert_eq!(v["value"], 1000);
        assert_eq!(v["pwe"], 1000);
        assert_eq!(
            (v["array"].clone(), v["dword"].clone()),
            (json!(true), json!(false))
        );
        assert_eq!(v["ram_only"], false);
        assert!(v["meaning"].as_str().unwrap().contains("PWE 1000"), "{v}");
    }

    #[test]
    fn pkw_response_gives_the_value_or_the_error_number() {
        // BU 0620 §2.5.6.4 p. 58: P717 read answered with 1020.
        let v = pkw("16 B5 00 00 00 00 03 FC", true);
        assert_eq!(
            (v["parameter"].clone(), v["value"].clone()),
            (json!(717), json!(1020))
        );
        assert_eq!(v["error"], Value::Null);
        assert!(v.get("array").is_none(), "order-only fields: {v}");
        // AK 7, error 3 "Incorrect sub-index".
        let v = pkw("74 4E 00 00 00 00 00 03", true);
        assert_eq!(v["error"], 3);
        assert_eq!(v["error_meaning"], "Incorrect sub-index");
        assert_eq!(v["value"], Value::Null);
        assert_eq!(v["parameter"], 102);
    }

    #[test]
    fn status_and_control_carry_their_fields_beside_the_sentence() {
        let (text, v) = decoded(DecodeWhat::Status {
            word: "0B31h".into(),
        })
        .unwrap();
        assert_eq!(v["meaning"], text);
        assert_eq!(v["word"], 0x0B31);
        assert_eq!(v["state"], "Ready for switch-on");
        assert_eq!(v["letter"], "C");
        assert_eq!(v["parameter_set"], 1);
        let (text, v) = decoded(DecodeWhat::Control {
            word: "047Eh".into(),
        })
        .unwrap();
        assert_eq!(v["meaning"], text);
        assert_eq!(v["commands"][0], "Shut down");
        assert_eq!(v["valid"], true);
        assert_eq!(v["rotation"], "right");
    }

    #[test]
    fn control_lists_disable_voltage_and_emergency_stop_when_their_bit_is_0() {
        // 047Eh: bits 1 and 2 at 1 cancel "Disable voltage" and "Emergency stop" (BU 0620
        // §6.1.2.1); 0478h gives both.
        let control = |w: &str| decoded(DecodeWhat::Control { word: w.into() }).unwrap().1;
        let v = control("047Eh");
        let active: Vec<&str> = v["active"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(Value::as_str)
            .collect();
        assert_eq!(
            active,
            [
                "Enable operation",
                "Enable pulses",
                "Enable ramp",
                "Enable setpoint",
                "Control data valid"
            ]
        );
        let meaning = v["meaning"].as_str().unwrap();
        assert!(!meaning.contains("Disable voltage"), "{meaning}");
        assert!(!meaning.contains("Emergency stop"), "{meaning}");
        let v = control("0478h");
        assert_eq!(v["active"][0], "Disable voltage");
        assert_eq!(v["active"][1], "Emergency stop");
        assert_eq!(v["commands"][0], "Disable voltage");
    }

    #[test]
    fn bad_pkw_bytes_name_the_problem() {
        let bad = |t: &str| pkw_bytes(&[t.to_string()]).unwrap_err();
        assert!(
            bad("70 zz").contains("`zz` is not a hex value"),
            "{}",
            bad("70 zz")
        );
        assert!(bad("0 1 2 3 4 5 6 7 8").contains("8 bytes, got 9"));
        let what = DecodeWhat::Pkw {
            bytes: vec!["70".into()],
            response: false,
        };
        assert!(decoded(what).unwrap_err().contains("truncated"));
    }
}
