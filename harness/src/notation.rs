//! Values in the manuals' notation, and the matchers suites write expectations with.
//!
//! The manuals write `0B31h` (hex), `101100110001b` (binary), `xx37h` (any nibble), decimal.
//! Suites add `one_of`, `range`, `mask`, `contains`, `not` and byte strings (`"70 66 xx 00"`).
//! A matcher is parsed once when the suite loads, so a malformed expectation is a load error
//! that names its place, not a surprise during the run.

use serde_json::{Map, Value};
use std::fmt;

/// Reads an integer written as a JSON number or in the manuals' notation (`1000`, `-5`,
/// `0B31h`, `101b`).
pub(crate) fn int_of(v: &Value) -> Result<i64, String> {
    match v {
        Value::Number(n) => n
            .as_i64()
            .ok_or_else(|| format!("{n} is not a whole number")),
        Value::String(s) => match parse_scalar(s) {
            Scalar::Int(i) => Ok(i),
            _ => Err(format!(
                "`{s}` is not a number (write 1000, 0B31h or 1011b)"
            )),
        },
        other => Err(format!("expected a number, got {other}")),
    }
}

/// A wire value as the manuals print them — status and control words, PKW bytes: hex, with
/// its mark or without (`0B31h`, `0x0B31` and `0B31` are one value, as `70h`, `0x70` and `70`
/// are one byte), or binary with its `b` mark, 0/1 digits only and more of them than a hex
/// value of the width has (`0000101100110001b`, `01110000b`); at most `bits` bits. Words and bytes read alike, so one syntax serves every wire value on the
/// command line. (Suite fields keep the suites' rule: a bare number is decimal.)
pub(crate) fn wire_value(text: &str, bits: u32) -> Result<u64, String> {
    let t = text.trim();
    // Binary needs more digits than a hex value of the width has (`1B` is a hex byte, `011b`
    // a binary one), so a `b` that is a hex digit is never taken for the mark.
    let binary = t.strip_suffix(['b', 'B']).filter(|d| {
        d.len() > (bits as usize).div_ceil(4) && d.chars().all(|c| c == '0' || c == '1')
    });
    let (body, radix) = match binary {
        Some(d) => (d, 2),
        None => (
            t.strip_prefix("0x")
                .or_else(|| t.strip_prefix("0X"))
                .or_else(|| t.strip_suffix(['h', 'H']))
                .unwrap_or(t),
            16,
        ),
    };
    let v = u64::from_str_radix(body, radix)
        .ok()
        .filter(|_| !body.is_empty() && !body.starts_with(['+', '-']))
        .ok_or_else(|| {
            format!("`{t}` is not a hex value (0B31h, 0x0B31 or 0B31) or a binary one (1011b)")
        })?;
    if bits < 64 && v >> bits != 0 {
        return Err(format!("`{t}` does not fit {bits} bits"));
    }
    Ok(v)
}

/// A text's reading in the notation.
#[derive(Debug, Clone, PartialEq)]
enum Scalar {
    Int(i64),
    /// Hex or binary with `x` digits: `(actual & mask) == value`.
    Pattern {
        mask: u64,
        value: u64,
    },
    /// Hex bytes with optional `x` nibbles, each byte as (mask, value).
    Bytes(Vec<(u8, u8)>),
    Text(String),
}

/// Parses one digit string in base 16 or 2 where `x` stands for any digit.
fn digits(body: &str, bits_per_digit: u32) -> Option<(u64, u64, bool)> {
    let radix = 1u32 << bits_per_digit;
    if body.is_empty() || body.len() as u32 * bits_per_digit > 64 {
        return None;
    }
    let (mut mask, mut value, mut wild) = (0u64, 0u64, false);
    let digit_mask = (1u64 << bits_per_digit) - 1;
    for c in body.chars() {
        mask <<= bits_per_digit;
        value <<= bits_per_digit;
        if c == 'x' || c == 'X' {
            wild = true;
        } else {
            let d = c.to_digit(radix)? as u64;
            mask |= digit_mask;
            value |= d;
        }
    }
    Some((mask, value, wild))
}

fn parse_bytes(s: &str) -> Option<Vec<(u8, u8)>> {
    let tokens: Vec<&str> = s.split_whitespace().collect();
    if tokens.len() < 2 {
        return None;
    }
    tokens
        .iter()
        .map(|t| {
            if t.len() != 2 {
                return None;
            }
            let (mask, value, _) = digits(t, 4)?;
            Some((mask as u8, value as u8))
        })
        .collect()
}

fn parse_scalar(s: &str) -> Scalar {
    let t = s.trim();
    if let Ok(i) = t.parse::<i64>() {
        return Scalar::Int(i);
    }
    let (neg, body) = match t.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, t),
    };
    let radix_body = body
        .strip_suffix('h')
        .or_else(|| body.strip_suffix('H'))
        .map(|b| (b, 4))
        .or_else(|| body.strip_suffix('b').map(|b| (b, 1)))
        .or_else(|| body.strip_prefix("0x").map(|b| (b, 4)));
    if let Some((b, bits)) = radix_body {
        if let Some((mask, value, wild)) = digits(b, bits) {
            return match (wild, neg) {
                (false, false) => Scalar::Int(value as i64),
                (false, true) => Scalar::Int(-(value as i64)),
                (true, false) => Scalar::Pattern { mask, value },
                (true, true) => Scalar::Text(s.to_string()),
            };
        }
    }
    match parse_bytes(t) {
        Some(bytes) => Scalar::Bytes(bytes),
        None => Scalar::Text(s.to_string()),
    }
}

/// An expectation, parsed from a suite's `expect:` value.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Matcher {
    /// An integer in any notation.
    Int(i64),
    /// A floating-point number (compared to 1e-9).
    Float(f64),
    /// `xx37h`, `1x01b`.
    Pattern {
        /// Bits that must match.
        mask: u64,
        /// Their values.
        value: u64,
        /// As written, for messages.
        text: String,
    },
    /// `"70 66 xx 00"`.
    Bytes(Vec<(u8, u8)>, String),
    /// Literal text.
    Text(String),
    /// `true` / `false`.
    Bool(bool),
    /// `null`: the field must be absent or null.
    Null,
    /// `{one_of: [...]}`.
    OneOf(Vec<Matcher>),
    /// `{range: [min, max]}`, inclusive.
    Range(i64, i64),
    /// `{mask: m, value: v}`.
    Mask(u64, u64),
    /// `{contains: "text"}`.
    Contains(String),
    /// `{not: v}`.
    Not(Box<Matcher>),
    /// Field by field (only the fields named).
    Object(Vec<(String, Matcher)>),
    /// Element by element, same length.
    List(Vec<Matcher>),
}

impl Matcher {
    /// Whether an object matcher names `field` at its top level.
    pub(crate) fn mentions(&self, field: &str) -> bool {
        matches!(self, Matcher::Object(fields) if fields.iter().any(|(k, _)| k == field))
    }
}

/// Why an actual value does not match.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Mismatch {
    /// Where in the result (`status`, `actuals[1]`).
    pub(crate) path: String,
    /// What was expected, as written.
    pub(crate) expected: String,
    /// What was there.
    pub(crate) actual: String,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let at = if self.path.is_empty() {
            String::new()
        } else {
            format!("{}: ", self.path)
        };
        write!(f, "{at}expected {}, got {}", self.expected, self.actual)
    }
}

/// Keys that make a one-key map an operator (`{mask, value}` is the two-key one); any other map
/// compares fields, so results may have fields called `mask` or `value`.
const OPERATORS: [&str; 4] = ["one_of", "range", "contains", "not"];

impl Matcher {
    /// Parses an expectation. The error says what is wrong, for the loader to place.
    pub(crate) fn parse(v: &Value) -> Result<Matcher, String> {
        Ok(match v {
            Value::Null => Matcher::Null,
            Value::Bool(b) => Matcher::Bool(*b),
            Value::Number(n) => match n.as_i64() {
                Some(i) => Matcher::Int(i),
                None => Matcher::Float(n.as_f64().unwrap_or(f64::NAN)),
            },
            Value::String(s) => match parse_scalar(s) {
                Scalar::Int(i) => Matcher::Int(i),
                Scalar::Pattern { mask, value } => Matcher::Pattern {
                    mask,
                    value,
                    text: s.clone(),
                },
                Scalar::Bytes(b) => Matcher::Bytes(b, s.clone()),
                Scalar::Text(t) => Matcher::Text(t),
            },
            Value::Array(items) => {
                Matcher::List(items.iter().map(Matcher::parse).collect::<Result<_, _>>()?)
            }
            Value::Object(map) => Self::parse_object(map)?,
        })
    }

    fn parse_object(map: &Map<String, Value>) -> Result<Matcher, String> {
        let keys: Vec<&str> = map.keys().map(String::as_str).collect();
        let operator = match keys.as_slice() {
            [k] => OPERATORS.contains(k),
            [a, b] => matches!((*a, *b), ("mask", "value") | ("value", "mask")),
            _ => false,
        };
        if !operator {
            return Ok(Matcher::Object(
                map.iter()
                    .map(|(k, v)| {
                        Matcher::parse(v)
                            .map(|m| (k.clone(), m))
                            .map_err(|e| format!("{k}: {e}"))
                    })
                    .collect::<Result<_, _>>()?,
            ));
        }
        if let Some(v) = map.get("one_of") {
            let Value::Array(items) = v else {
                return Err("one_of takes a list".into());
            };
            return Ok(Matcher::OneOf(
                items.iter().map(Matcher::parse).collect::<Result<_, _>>()?,
            ));
        }
        if let Some(v) = map.get("range") {
            return match v {
                Value::Array(b) if b.len() == 2 => {
                    Ok(Matcher::Range(int_of(&b[0])?, int_of(&b[1])?))
                }
                _ => Err("range takes [min, max]".into()),
            };
        }
        if let Some(m) = map.get("mask") {
            let v = map.get("value").ok_or("mask needs value")?;
            return Ok(Matcher::Mask(int_of(m)? as u64, int_of(v)? as u64));
        }
        if let Some(v) = map.get("contains") {
            let Value::String(s) = v else {
                return Err("contains takes text".into());
            };
            return Ok(Matcher::Contains(s.clone()));
        }
        if let Some(v) = map.get("not") {
            return Ok(Matcher::Not(Box::new(Matcher::parse(v)?)));
        }
        Err("unknown operator".into())
    }

    /// Checks `actual` against the expectation.
    pub(crate) fn check(&self, actual: &Value) -> Result<(), Mismatch> {
        self.check_at("", actual)
    }

    fn check_at(&self, path: &str, actual: &Value) -> Result<(), Mismatch> {
        let miss = || Mismatch {
            path: path.to_string(),
            expected: self.to_string(),
            actual: show(actual),
        };
        let int = || int_of(actual).ok();
        let ok = match self {
            Matcher::Int(i) => int() == Some(*i),
            Matcher::Float(f) => actual.as_f64().is_some_and(|a| (a - f).abs() < 1e-9),
            Matcher::Pattern { mask, value, .. } | Matcher::Mask(mask, value) => {
                int().is_some_and(|a| (a as u64) & mask == *value)
            }
            Matcher::Bytes(exp, _) => match actual {
                Value::String(s) => {
                    match parse_bytes(s).or_else(|| parse_bytes(&format!("{s} "))) {
                        Some(act) => {
                            act.len() == exp.len()
                                && exp.iter().zip(&act).all(|((m, v), (_, a))| a & m == *v)
                        }
                        None => false,
                    }
                }
                _ => false,
            },
            Matcher::Text(t) => actual.as_str() == Some(t.as_str()),
            Matcher::Bool(b) => actual.as_bool() == Some(*b),
            Matcher::Null => actual.is_null(),
            Matcher::OneOf(options) => options.iter().any(|m| m.check_at(path, actual).is_ok()),
            Matcher::Range(lo, hi) => int().is_some_and(|a| (*lo..=*hi).contains(&a)),
            Matcher::Contains(t) => actual.as_str().is_some_and(|s| contains(s, t)),
            Matcher::Not(m) => m.check_at(path, actual).is_err(),
            Matcher::Object(fields) => {
                let Value::Object(map) = actual else {
                    return Err(miss());
                };
                for (k, m) in fields {
                    let sub = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    match map.get(k) {
                        Some(v) => m.check_at(&sub, v)?,
                        None if *m == Matcher::Null => {}
                        None => {
                            return Err(Mismatch {
                                path: sub,
                                expected: m.to_string(),
                                actual: "no such field".into(),
                            })
                        }
                    }
                }
                true
            }
            Matcher::List(items) => {
                let Value::Array(act) = actual else {
                    return Err(miss());
                };
                if act.len() != items.len() {
                    return Err(miss());
                }
                for (i, (m, v)) in items.iter().zip(act).enumerate() {
                    m.check_at(&format!("{path}[{i}]"), v)?;
                }
                true
            }
        };
        if ok {
            Ok(())
        } else {
            Err(miss())
        }
    }
}

/// Shows an actual value; integers also in hex, as the manuals would print them.
fn show(v: &Value) -> String {
    match v {
        Value::Number(n) => match n.as_i64() {
            Some(i) if i >= 10 => format!("{i} ({i:04X}h)"),
            _ => n.to_string(),
        },
        Value::String(s) => format!("\"{s}\""),
        other => other.to_string(),
    }
}

impl fmt::Display for Matcher {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Matcher::Int(i) if *i >= 10 => write!(f, "{i} ({i:04X}h)"),
            Matcher::Int(i) => write!(f, "{i}"),
            Matcher::Float(x) => write!(f, "{x}"),
            Matcher::Pattern { text, .. } | Matcher::Bytes(_, text) => write!(f, "{text}"),
            Matcher::Text(t) => write!(f, "\"{t}\""),
            Matcher::Bool(b) => write!(f, "{b}"),
            Matcher::Null => write!(f, "nothing"),
            Matcher::OneOf(ms) => {
                write!(f, "one of [")?;
                for (i, m) in ms.iter().enumerate() {
                    write!(f, "{}{m}", if i > 0 { ", " } else { "" })?;
                }
                write!(f, "]")
            }
            Matcher::Range(a, b) => write!(f, "{a}..={b}"),
            Matcher::Mask(m, v) => write!(f, "value & {m:04X}h == {v:04X}h"),
            Matcher::Contains(t) => write!(f, "text containing \"{t}\""),
            Matcher::Not(m) => write!(f, "not {m}"),
            Matcher::Object(fields) => {
                write!(f, "{{")?;
                for (i, (k, m)) in fields.iter().enumerate() {
                    write!(f, "{}{k}: {m}", if i > 0 { ", " } else { "" })?;
                }
                write!(f, "}}")
            }
            Matcher::List(items) => write!(f, "a list of {} items", items.len()),
        }
    }
}

/// Whether `text` contains `pattern`. A pattern of hex bytes with `x` nibbles (`"04 FF 01 6D xx
/// xx 60 00"`) matches hex bytes whatever those nibbles are, spaces aside, at a byte
/// boundary; any other pattern is plain text.
fn contains(text: &str, pattern: &str) -> bool {
    let squeeze = |s: &str| -> Vec<u8> { s.bytes().filter(|b| !b.is_ascii_whitespace()).collect() };
    let p = squeeze(pattern);
    let wild = p.iter().any(|b| matches!(b, b'x' | b'X'))
        && p.len() % 2 == 0
        && p.iter()
            .all(|b| b.is_ascii_hexdigit() || matches!(b, b'x' | b'X'));
    if !wild {
        return text.contains(pattern);
    }
    let t = squeeze(text);
    if t.len() < p.len() {
        return false;
    }
    (0..=t.len() - p.len()).step_by(2).any(|at| {
        t[at..at + p.len()]
            .iter()
            .zip(&p)
            .all(|(a, b)| matches!(b, b'x' | b'X') || a.eq_ignore_ascii_case(b))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;
    use serde_json::json;

    #[rstest]
    #[case(json!(1000), 1000)]
    #[case(json!("0B31h"), 0x0B31)]
    #[case(json!("3066h"), 0x3066)]
    #[case(json!("101100110001b"), 0b1011_0011_0001)]
    #[case(json!("-5"), -5)]
    #[case(json!("0x1F"), 0x1F)]
    fn integers_in_manual_notation(#[case] v: Value, #[case] want: i64) {
        assert_eq!(int_of(&v), Ok(want));
    }

    #[rstest]
    #[case(json!("P102"))]
    #[case(json!(1.5))]
    #[case(json!("xx37h"))]
    fn not_integers(#[case] v: Value) {
        assert!(int_of(&v).is_err());
    }

    #[rstest]
    // BU 0620 §6.1.3: status xx37h after 047Fh; 0B37h and 0237h match, 0B31h does not.
    #[case(json!("xx37h"), json!(0x0B37), true)]
    #[case(json!("xx37h"), json!(0x0237), true)]
    #[case(json!("xx37h"), json!(0x0B31), false)]
    #[case(json!("1x11b"), json!(0b1011), true)]
    #[case(json!("1x11b"), json!(0b1010), false)]
    #[case(json!("0B31h"), json!(2865), true)]
    #[case(json!({"one_of": [1, 2]}), json!(2), true)]
    #[case(json!({"one_of": [1, 2]}), json!(4), false)]
    #[case(json!({"range": [10, "14h"]}), json!(20), true)]
    #[case(json!({"range": [10, "14h"]}), json!(21), false)]
    #[case(json!({"mask": "0F00h", "value": "0B00h"}), json!(0x0B31), true)]
    #[case(json!({"contains": "out of range"}), json!("inverter 9 is out of range 1..=8"), true)]
    #[case(json!({"contains": "04 FF xx 6D"}), json!("00 04 FF 01 6D 00"), true)]
    #[case(json!({"contains": "04FF xx6D"}), json!("00 04 FF 01 6E 00"), false)]
    #[case(json!({"contains": "4F Fx"}), json!("04 FF 01"), false)]
    #[case(json!({"not": 0}), json!(0), false)]
    #[case(json!("70 66 xx 00"), json!("70 66 02 00"), true)]
    #[case(json!("70 66 xx 00"), json!("70 67 02 00"), false)]
    #[case(json!("70 66 xx 00"), json!("70 66 02"), false)]
    #[case(json!({"status": "xx31h", "actuals": [0, "2000h"]}), json!({"status": 0x0B31, "actuals": [0, 0x2000], "extra": 1}), true)]
    #[case(json!({"status": "xx31h"}), json!({"actuals": []}), false)]
    #[case(json!({"error": null}), json!({"value": 3}), true)]
    #[case(json!({"value": 1000, "ak": 1}), json!({"value": 1000, "ak": 1}), true)]
    // Result fields named like operators compare as fields.
    #[case(json!({"ip": "192.168.100.1", "mask": "255.255.255.0"}), json!({"ip": "192.168.100.1", "mask": "255.255.255.0"}), true)]
    #[case(json!({"mask": "255.255.255.0"}), json!({"mask": "255.255.0.0"}), false)]
    #[case(json!(50.0), json!(50.0), true)]
    fn matching(#[case] expect: Value, #[case] actual: Value, #[case] ok: bool) {
        let m = Matcher::parse(&expect).unwrap();
        assert_eq!(m.check(&actual).is_ok(), ok, "{m} vs {actual}");
    }

    #[rstest]
    #[case("0B31h", 16, Ok(0x0B31))]
    #[case("0x0B31", 16, Ok(0x0B31))]
    #[case("0B31", 16, Ok(0x0B31))]
    #[case("0000101100110001b", 16, Ok(0x0B31))]
    #[case("70", 8, Ok(0x70))]
    #[case("70h", 8, Ok(0x70))]
    #[case("0x70", 8, Ok(0x70))]
    #[case("01110000b", 8, Ok(0x70))]
    #[case("1B", 8, Ok(0x1B))]
    #[case("10b", 8, Err("`10b` does not fit 8 bits"))]
    #[case("101b", 8, Ok(5))]
    #[case("0B31", 8, Err("`0B31` does not fit 8 bits"))]
    #[case("zz", 8, Err("`zz` is not a hex value"))]
    #[case("-5", 16, Err("`-5` is not a hex value"))]
    #[case("h", 16, Err("`h` is not a hex value"))]
    #[case("0x", 16, Err("`0x` is not a hex value"))]
    fn wire_values_read_alike_for_words_and_bytes(
        #[case] text: &str,
        #[case] bits: u32,
        #[case] want: Result<u64, &str>,
    ) {
        match (wire_value(text, bits), want) {
            (Ok(v), Ok(w)) => assert_eq!(v, w),
            (Err(e), Err(w)) => assert!(e.starts_with(w), "{e}"),
            (got, want) => panic!("{text}: got {got:?}, want {want:?}"),
        }
    }

    #[test]
    fn mismatch_names_the_path_and_both_values() {
        let m = Matcher::parse(&json!({"status": "0B31h"})).unwrap();
        let e = m.check(&json!({"status": 0x0B37})).unwrap_err();
        assert_eq!(
            e.to_string(),
            "status: expected 2865 (0B31h), got 2871 (0B37h)"
        );
    }

    #[rstest]
    #[case(json!({"range": [1]}))]
    #[case(json!({"one_of": 3}))]
    fn malformed_expectations_are_errors(#[case] v: Value) {
        assert!(Matcher::parse(&v).is_err());
    }
}
