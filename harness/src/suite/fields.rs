//! Reading a step's fields: the helpers every step parser uses, the manual-level ones here and
//! each bus's own (`crate::<bus>::step`), so that every step reports a bad field alike.

use proto::nord::Inverter;
use serde_json::{Map, Value};

use crate::notation::int_of;

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
    ) -> Result<Self, String> {
        if let Some(k) = map.keys().find(|k| !allowed.contains(&k.as_str())) {
            return Err(format!(
                "`{action}` has no field `{k}` (fields: {})",
                allowed.join(", ")
            ));
        }
        Ok(Fields { action, map })
    }

    pub(crate) fn int(&self, key: &str) -> Result<Option<i64>, String> {
        self.map
            .get(key)
            .map(|v| int_of(v).map_err(|e| format!("`{}.{key}`: {e}", self.action)))
            .transpose()
    }

    pub(crate) fn req_int(&self, key: &str) -> Result<i64, String> {
        self.int(key)?
            .ok_or_else(|| format!("`{}` needs `{key}`", self.action))
    }

    pub(crate) fn ranged<T>(
        &self,
        key: &str,
        f: fn(i64) -> Result<T, proto::nord::RangeError>,
    ) -> Result<Option<T>, String> {
        self.int(key)?
            .map(|v| f(v).map_err(|e| format!("`{}.{key}`: {e}", self.action)))
            .transpose()
    }

    pub(crate) fn inverter(&self) -> Result<Inverter, String> {
        Ok(self
            .ranged("inverter", Inverter::new)?
            .unwrap_or(Inverter::new(1).expect("FI 1 exists")))
    }

    pub(crate) fn word(&self, key: &str) -> Result<u16, String> {
        let v = self.req_int(key)?;
        u16::try_from(v).map_err(|_| format!("`{}.{key}`: {v} is not a 16-bit word", self.action))
    }

    pub(crate) fn text(&self, key: &str) -> Result<Option<String>, String> {
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

    pub(crate) fn bool(&self, key: &str) -> Result<Option<bool>, String> {
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

/// Hex bytes in wire order: `"65 00 04 00"`, or grouped as `"6500 0400"`.
pub(crate) fn hex_bytes(action: &str, text: &str) -> Result<Vec<u8>, String> {
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
