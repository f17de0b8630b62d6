//! Arguments of compute functions, read in the manuals' notation.

use proto::nord::Product;
use serde_json::{Map, Value};

use crate::notation;

/// What a compute function knows of the run: the profile's product.
pub(crate) struct Ctx {
    /// Product of the profile the case runs under (a case may override it with `product:`).
    pub(crate) product: Product,
}

/// Why a compute function produced no value.
#[derive(Debug, thiserror::Error)]
pub(crate) enum ComputeError {
    /// The case passed wrong arguments: a suite bug, reported as an error verdict.
    #[error("bad argument `{arg}`: {why}")]
    BadArg {
        /// Argument name.
        arg: String,
        /// What is wrong with it.
        why: String,
    },
    /// The model refuses the input as the manuals do (inverter 9, parameter 1000, …). The runner
    /// turns this into the result `{error: "<message>"}` so that a case can expect it.
    #[error("{0}")]
    Refused(String),
}

impl From<proto::nord::RangeError> for ComputeError {
    fn from(e: proto::nord::RangeError) -> Self {
        ComputeError::Refused(e.to_string())
    }
}

/// The `args` map of a compute step.
pub(crate) struct Args(pub(crate) Map<String, Value>);

impl Args {
    fn bad(arg: &str, why: impl Into<String>) -> ComputeError {
        ComputeError::BadArg {
            arg: arg.to_string(),
            why: why.into(),
        }
    }

    /// A required integer, written as a number, `0B31h`, `1011b` or `-5`.
    pub(crate) fn int(&self, name: &str) -> Result<i64, ComputeError> {
        self.opt_int(name)?
            .ok_or_else(|| Self::bad(name, "missing"))
    }

    /// An optional integer in the manuals' notation.
    pub(crate) fn opt_int(&self, name: &str) -> Result<Option<i64>, ComputeError> {
        match self.0.get(name) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => notation::int_of(v)
                .map(Some)
                .map_err(|why| Self::bad(name, why)),
        }
    }

    /// Whether the argument was given.
    pub(crate) fn raw_present(&self, name: &str) -> bool {
        self.0.get(name).is_some_and(|v| !v.is_null())
    }

    /// A required string.
    pub(crate) fn str(&self, name: &str) -> Result<&str, ComputeError> {
        self.opt_str(name)?
            .ok_or_else(|| Self::bad(name, "missing"))
    }

    /// An optional string.
    pub(crate) fn opt_str(&self, name: &str) -> Result<Option<&str>, ComputeError> {
        match self.0.get(name) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(s)) => Ok(Some(s)),
            Some(other) => Err(Self::bad(name, format!("expected text, got {other}"))),
        }
    }

    /// An optional boolean.
    pub(crate) fn opt_bool(&self, name: &str) -> Result<Option<bool>, ComputeError> {
        match self.0.get(name) {
            None | Some(Value::Null) => Ok(None),
            Some(Value::Bool(b)) => Ok(Some(*b)),
            Some(other) => Err(Self::bad(name, format!("expected true/false, got {other}"))),
        }
    }
}
