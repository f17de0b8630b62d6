//! `harness addr` and `harness decode`: the reference model at the command line.
//!
//! Both print the manuals' terms, or JSON with `--json`; bad input (inverter 9, parameter 1000,
//! malformed hex) is a one-line error naming the problem (exit 2).

use clap::{Args, Subcommand};
use proto::nord::pkw::PkwRepr;
use proto::nord::{addr, control::ControlWord, status::StatusWord};
use proto::nord::{ArrayElement, Inverter, ParamAddress, ParamNumber, ParamSet, Product};
use serde_json::json;

use crate::cli::EXIT_PASS;
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
    /// Print JSON.
    #[arg(long, global = true)]
    json: bool,
}

#[derive(Subcommand, Debug)]
enum DecodeWhat {
    /// A status word, e.g. `0B31h`.
    Status {
        /// The word: `0B31h`, `2865` or `101100110001b`.
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
    let v = number("word", text)?;
    u16::try_from(v).map_err(|_| format!("word: {v} does not fit 16 bits (0..=FFFFh)"))
}

/// Runs `harness addr`.
pub(crate) fn addr(a: AddrArgs) -> Result<i32, String> {
    let product = Product::from_name(&a.profile)
        .ok_or_else(|| crate::profile::Profile::by_name(&a.profile).unwrap_err())?;
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
    let all = addr::all(product, address).map_err(|e| e.to_string())?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&all).map_err(|e| e.to_string())?
        );
    } else {
        print!("{all}");
    }
    Ok(EXIT_PASS)
}

/// Runs `harness decode`.
pub(crate) fn decode(a: DecodeArgs) -> Result<i32, String> {
    let (text, value) = match a.what {
        DecodeWhat::Status { word: w } => {
            let s = StatusWord(word(&w)?);
            (
                s.describe(),
                serde_json::to_value(s.fields()).map_err(|e| e.to_string())?,
            )
        }
        DecodeWhat::Control { word: w } => {
            let c = ControlWord(word(&w)?);
            (
                c.describe(),
                serde_json::to_value(c.fields()).map_err(|e| e.to_string())?,
            )
        }
        DecodeWhat::Pkw { bytes, response } => {
            let joined = bytes.join(" ");
            let raw: Vec<u8> = joined
                .split_whitespace()
                .map(|t| {
                    u8::from_str_radix(t.trim_end_matches(['h', 'H']), 16)
                        .map_err(|_| format!("pkw: `{t}` is not a hex byte"))
                })
                .collect::<Result<_, _>>()?;
            if raw.len() > proto::nord::pkw::PKW_LEN {
                return Err(format!("pkw: a telegram is 8 bytes, got {}", raw.len()));
            }
            let r = PkwRepr::parse(&raw).map_err(|e| format!("pkw: {e}"))?;
            let text = if response {
                r.describe_response()
            } else {
                r.describe_order()
            };
            (
                text.clone(),
                json!({ "ak": r.ak, "spm": r.spm, "pnu": r.pnu, "ind": r.ind, "pwe": r.pwe, "meaning": text }),
            )
        }
    };
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&value).map_err(|e| e.to_string())?
        );
    } else {
        println!("{text}");
    }
    Ok(EXIT_PASS)
}
