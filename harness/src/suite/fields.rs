//! Reading a step's fields: the helpers every step parser uses, the manual-level ones here and
//! each bus's own (`crate::<bus>::step`), so that every step reports a bad field alike.

use proto::nord::Inverter;
use serde_json::{Map, Value};

use crate::notation::int_of;

/// Why a step's fields do not make a step; every variant names where, so a load error points
/// at the field. What a bus's parser finds wrong with the step as a whole is [`FieldError::Step`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum FieldError {
    /// A key the action does not have.
    #[error("`{action}` has no field `{field}` (fields: {allowed})")]
    Unknown {
        /// The action (`ecat`, `read`).
        action: String,
        /// The key.
        field: String,
        /// The keys it has.
        allowed: String,
    },
    /// A key the action needs is not there.
    #[error("`{action}` needs `{field}`")]
    Missing {
        /// The action.
        action: String,
        /// The key.
        field: String,
    },
    /// A field's value is not one the action takes.
    #[error("`{at}`: {why}")]
    Value {
        /// The field, as `action.key` (`ecat.length`).
        at: String,
        /// What is wrong with it.
        why: String,
    },
    /// The step as a whole (a combination of fields, an action of no bus).
    #[error("{0}")]
    Step(String),
}

impl FieldError {
    /// The value of the field `at` is wrong because `why`.
    pub(crate) fn value(at: impl Into<String>, why: impl ToString) -> FieldError {
        FieldError::Value {
            at: at.into(),
            why: why.to_string(),
        }
    }
}

/// A whole-step complaint of a bus's parser.
impl From<String> for FieldError {
    fn from(why: String) -> FieldError {
        FieldError::Step(why)
    }
}

impl From<&str> for FieldError {
    fn from(why: &str) -> FieldError {
        FieldError::Step(why.to_string())
    }
}

/// The loader's messages are text.
impl From<FieldError> for String {
    fn from(e: FieldError) -> String {
        e.to_string()
    }
}

/// Reads the fields of an action map, refusing unknown keys.
pub(crate) struct Fields<'a> {
    action: &'static str,
    map: &'a Map<String, Value>,
}

impl<'a> Fields<'a> {
    pub(crate) fn new(
        action: &'static str,
        map: &'a Map<String, Value>,
        allowed: &[&str],
    ) -> Result<Self, FieldError> {
        if let Some(k) = map.keys().find(|k| !allowed.contains(&k.as_str())) {
            return Err(FieldError::Unknown {
                action: action.to_string(),
                field: k.clone(),
                allowed: allowed.join(", "),
            });
        }
        Ok(Fields { action, map })
    }

    /// `action.key`, where a value is wrong.
    fn at(&self, key: &str) -> String {
        format!("{}.{key}", self.action)
    }

    pub(crate) fn int(&self, key: &str) -> Result<Option<i64>, FieldError> {
        self.map
            .get(key)
            .map(|v| int_of(v).map_err(|e| FieldError::value(self.at(key), e)))
            .transpose()
    }

    pub(crate) fn req_int(&self, key: &str) -> Result<i64, FieldError> {
        self.int(key)?.ok_or_else(|| FieldError::Missing {
            action: self.action.to_string(),
            field: key.to_string(),
        })
    }

    pub(crate) fn ranged<T>(
        &self,
        key: &str,
        f: fn(i64) -> Result<T, proto::nord::RangeError>,
    ) -> Result<Option<T>, FieldError> {
        self.int(key)?
            .map(|v| f(v).map_err(|e| FieldError::value(self.at(key), e)))
            .transpose()
    }

    pub(crate) fn inverter(&self) -> Result<Inverter, FieldError> {
        Ok(self
            .ranged("inverter", Inverter::new)?
            .unwrap_or(Inverter::new(1).expect("FI 1 exists")))
    }

    pub(crate) fn word(&self, key: &str) -> Result<u16, FieldError> {
        let v = self.req_int(key)?;
        u16::try_from(v)
            .map_err(|_| FieldError::value(self.at(key), format!("{v} is not a 16-bit word")))
    }

    pub(crate) fn text(&self, key: &str) -> Result<Option<String>, FieldError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.clone())),
            Some(Value::Number(n)) => Ok(Some(n.to_string())),
            Some(other) => Err(FieldError::value(
                self.at(key),
                format!("expected text, got {other}"),
            )),
        }
    }

    pub(crate) fn bool(&self, key: &str) -> Result<Option<bool>, FieldError> {
        match self.map.get(key) {
            None => Ok(None),
            Some(Value::Bool(b)) => Ok(Some(*b)),
            Some(other) => Err(FieldError::value(
                self.at(key),
                format!("expected true or false, got {other}"),
            )),
        }
    }
}

/// Hex bytes in wire order: `"65 00 04 00"`, or grouped as `"6500 0400"`.
pub(crate) fn hex_bytes(action: &str, text: &str) -> Result<Vec<u8>, FieldError> {
    let bad = || {
        FieldError::value(
            action,
            format!("`{text}` is not hex bytes like \"65 00 04 00\""),
        )
    };
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
