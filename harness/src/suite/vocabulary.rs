//! What the loader must know beyond the suites' text: the profiles and capabilities a case may
//! name, and how each bus parses the steps written under its key. Whoever holds the list of
//! buses builds it (`crate::bus::vocabulary`); the loader reads no list of its own.

use serde_json::Value;

use super::fields::FieldError;
use super::BusStep;
use crate::profile::Catalog;

/// Parses a suite step written under a bus's key; the error says what is wrong.
pub(crate) type ParseStep = fn(&Value) -> Result<Box<dyn BusStep>, FieldError>;

/// The names a suite may use.
#[derive(Debug, Clone)]
pub(crate) struct Vocabulary {
    /// The profiles and capabilities.
    pub(crate) catalog: Catalog,
    /// Each bus's step key and parser, in report order.
    pub(crate) steps: Vec<(&'static str, ParseStep)>,
}

impl Vocabulary {
    /// The parser of the steps written under `key`, if a bus has that name.
    pub(crate) fn step_parser(&self, key: &str) -> Option<ParseStep> {
        self.steps.iter().find(|(k, _)| *k == key).map(|(_, p)| *p)
    }

    /// The bus names, for messages.
    pub(crate) fn bus_names(&self) -> String {
        let v: Vec<&str> = self.steps.iter().map(|(k, _)| *k).collect();
        v.join(", ")
    }
}
