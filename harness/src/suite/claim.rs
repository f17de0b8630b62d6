//! Whether a step's expectation carries an inventory statement's value: the check that keeps
//! a claim "this case asserts what the manual says" from naming a case that checks something
//! else (a step that reads P186 for a statement about P161, a baud rate cited to a case that
//! never looks at one).
//!
//! A value is written in the suites' notation (`0B31h`, `xx37h`, `"70 66 xx 00"`, `10.0`,
//! `Operation enabled`) and parsed as an expectation is ([`Matcher::parse`]), so the two
//! compare leaf by leaf. An expectation carries the value when one of its leaves, anywhere in
//! its fields, lists and `one_of` options, names it:
//! - a number: equal (a decimal written as text, `10.0`, compares as a number);
//! - a pattern with `x` digits: the same pattern, or a number it accepts;
//! - `{mask, value}`: its value or its mask (the bit a statement names);
//! - `{range: [min, max]}`: one of its limits (a statement's range is its limits);
//! - bytes: the value's bytes as a run within them;
//! - text (`contains:` too): the value's letters and digits within the leaf's, case and
//!   punctuation aside (`Pre-Operational 1` is in `PRE_OPERATIONAL_1`); a number written as
//!   text is a whole token of the leaf (`10.0` is in `E10.0`, `1.3` not in `P1300`), and bytes
//!   compare as their text (`60 00` is in a reply containing `FD 00 60 00`).
//!
//! `not:` carries nothing: it says what the value is not. `null` (the field must be absent)
//! carries only the value `null`: a statement that there is none ("no error, no alarm").

use crate::notation::Matcher;

/// Whether `expect` carries `value` (see the module doc).
pub(crate) fn carries(expect: &Matcher, value: &Matcher) -> bool {
    match expect {
        Matcher::Object(fields) => fields.iter().any(|(_, m)| carries(m, value)),
        Matcher::List(items) | Matcher::OneOf(items) => items.iter().any(|m| carries(m, value)),
        Matcher::Not(_) => false,
        // "None": a field that must be absent carries the statement that there is none.
        Matcher::Null => matches!(value, Matcher::Null),
        leaf => leaf_carries(leaf, value),
    }
}

/// A number the value names, if it names one (`10.0` written as text too).
fn number(m: &Matcher) -> Option<f64> {
    match m {
        Matcher::Int(i) => Some(*i as f64),
        Matcher::Float(f) => Some(*f),
        Matcher::Text(t) => t.trim().parse().ok(),
        _ => None,
    }
}

/// Letters and digits, lower case: text compared case and punctuation aside.
fn letters(t: &str) -> String {
    t.chars()
        .filter(char::is_ascii_alphanumeric)
        .map(|c| c.to_ascii_lowercase())
        .collect()
}

fn text_contains(leaf: &str, value: &str) -> bool {
    let v = letters(value);
    !v.is_empty() && letters(leaf).contains(&v)
}

fn leaf_carries(leaf: &Matcher, value: &Matcher) -> bool {
    let same_number = |n: f64| number(value).is_some_and(|v| (v - n).abs() < 1e-9);
    match (leaf, value) {
        (Matcher::Int(i), _) => same_number(*i as f64),
        (Matcher::Float(f), _) => same_number(*f),
        (
            Matcher::Pattern { mask, value: v, .. },
            Matcher::Pattern {
                mask: m2,
                value: v2,
                ..
            },
        ) => (mask, v) == (m2, v2),
        (Matcher::Pattern { mask, value: v, .. }, Matcher::Int(i)) => (*i as u64) & mask == *v,
        (Matcher::Mask(mask, v), Matcher::Int(i)) => *i as u64 == *v || *i as u64 == *mask,
        (Matcher::Range(lo, hi), Matcher::Int(i)) => i == lo || i == hi,
        (Matcher::Bytes(bytes, _), Matcher::Bytes(run, _)) => {
            !run.is_empty() && bytes.windows(run.len()).any(|w| w == run.as_slice())
        }
        (Matcher::Text(t) | Matcher::Contains(t), _) => match (number(value), value) {
            // A number in a text is a whole token of it (`1.3` is not in `P1300`).
            (Some(_), _) => t
                .split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
                .any(|token| number(&Matcher::Text(token.into())).is_some_and(same_number)),
            (None, Matcher::Text(v) | Matcher::Bytes(_, v)) => text_contains(t, v),
            (None, _) => false,
        },
        (Matcher::Bool(b), Matcher::Bool(v)) => b == v,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;
    use serde_json::{json, Value};

    fn m(v: Value) -> Matcher {
        Matcher::parse(&v).unwrap()
    }

    #[rstest]
    #[case(json!({"status": "0B31h"}), json!("0B31h"))]
    #[case(json!({"status": "0B31h"}), json!(2865))]
    #[case(json!({"status": "xx37h"}), json!("xx37h"))]
    #[case(json!({"status": "xx37h"}), json!("0B37h"))]
    #[case(json!({"value": {"mask": "0004h", "value": "0004h"}}), json!("0004h"))]
    #[case(json!({"value": {"mask": "0040h", "value": 0}}), json!("0040h"))]
    #[case(json!({"min": 0, "max": {"range": [0, 55]}}), json!(55))]
    #[case(json!({"bytes": "70 66 xx 00 00 00 03 E8"}), json!("03 E8"))]
    #[case(json!({"error": "10.0"}), json!(10.0))]
    #[case(json!({"error": "10.0"}), json!("10.0"))]
    #[case(json!({"version": 1.3}), json!("1.3"))]
    #[case(json!({"state": "PRE_OPERATIONAL_1"}), json!("Pre-Operational 1"))]
    #[case(json!({"text": {"contains": "Access failed due to hardware error"}}), json!("hardware error"))]
    #[case(json!({"frames": [{"cob": "0624h"}, {"cob": "05A4h"}]}), json!("05A4h"))]
    #[case(json!({"value": {"one_of": [1, 4, 5]}}), json!(4))]
    #[case(json!({"enabled": true}), json!(true))]
    #[case(json!({"alarm": null}), json!(null))]
    #[case(json!({"shown": "E10.0 / 7585h"}), json!("10.0"))]
    #[case(json!({"rule": {"contains": "63"}}), json!(63))]
    #[case(json!({"reply": {"contains": "FD 00 60 00"}}), json!("60 00"))]
    fn an_expectation_carries_the_value_it_names(#[case] expect: Value, #[case] value: Value) {
        assert!(
            carries(&m(expect.clone()), &m(value.clone())),
            "{expect} {value}"
        );
    }

    #[rstest]
    // P161 written, P186 checked: 255 is not the statement's 0.
    #[case(json!({"value": 255}), json!(0))]
    #[case(json!({"value": {"not": 0}}), json!(0))]
    #[case(json!({"value": {"range": [0, 55]}}), json!(30))]
    #[case(json!({"status": "xx37h"}), json!("0B31h"))]
    #[case(json!({"text": "Operation enabled"}), json!("Switched on"))]
    #[case(json!({"bytes": "70 66 00 00"}), json!("66 70"))]
    #[case(json!({"value": null}), json!(0))]
    #[case(json!({"value": 0}), json!(null))]
    #[case(json!({"enabled": true}), json!(1))]
    #[case(json!({"name": "P1300"}), json!("1.3"))]
    fn an_expectation_does_not_carry_another_value(#[case] expect: Value, #[case] value: Value) {
        assert!(
            !carries(&m(expect.clone()), &m(value.clone())),
            "{expect} {value}"
        );
    }
}
