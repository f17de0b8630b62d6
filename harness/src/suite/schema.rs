//! The suite files as written: serde structs that reject unknown keys.
//!
//! Values that use the manuals' notation stay JSON values here; `case.rs` reads them and
//! reports what is wrong with the step's line.

use crate::outcome::ErratumCheck;
use serde::Deserialize;
use serde_json::{Map, Value};
use serde_saphyr::Spanned;

/// A suite file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FileDoc {
    /// Manual, default for the cases.
    pub(super) doc: String,
    /// Edition, default for the cases.
    pub(super) edition: String,
    /// The cases.
    pub(super) cases: Vec<Spanned<CaseDoc>>,
}

/// A case as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CaseDoc {
    pub(super) id: String,
    pub(super) title: String,
    #[serde(rename = "ref")]
    pub(super) reference: RefDoc,
    #[serde(default)]
    pub(super) profiles: Option<Vec<String>>,
    #[serde(default)]
    pub(super) requires: Vec<String>,
    #[serde(default)]
    pub(super) manual_says: ManualSays,
    pub(super) steps: Vec<Spanned<StepDoc>>,
}

/// `ref:` of a case.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RefDoc {
    #[serde(default)]
    pub(super) doc: Option<String>,
    #[serde(default)]
    pub(super) edition: Option<String>,
    pub(super) section: String,
    #[serde(default)]
    pub(super) page: Option<u32>,
    /// The requirement quoted from the manual, for the reports.
    #[serde(default)]
    pub(super) quote: Option<String>,
}

/// `manual_says:` may be one erratum or a list.
#[derive(Debug, Deserialize, Default)]
#[serde(untagged)]
pub(super) enum ManualSays {
    #[default]
    None,
    One(ErratumDoc),
    Many(Vec<ErratumDoc>),
}

impl ManualSays {
    pub(super) fn into_vec(self) -> Vec<ErratumDoc> {
        match self {
            ManualSays::None => Vec::new(),
            ManualSays::One(e) => vec![e],
            ManualSays::Many(v) => v,
        }
    }
}

/// One wrong value a manual prints.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ErratumDoc {
    pub(super) printed: String,
    pub(super) correct: String,
    pub(super) why: String,
    /// The manual is ambiguous rather than wrong: the case accepts every reading its text
    /// allows, and `why` says which.
    #[serde(default)]
    pub(super) ambiguous: bool,
    /// Which check of the errata pass found it.
    pub(super) check: ErratumCheck,
    /// The standard's clause; required when `check: standard`.
    #[serde(default)]
    pub(super) standard: Option<String>,
}

/// A step as written: exactly one action key, checked in `case.rs`. A key that is no
/// manual-level action lands in `bus`, where `case.rs` accepts only a registered bus's name
/// (so an unknown key is still refused, naming the keys there are).
#[derive(Debug, Deserialize)]
pub(super) struct StepDoc {
    #[serde(default)]
    pub(super) compute: Option<String>,
    #[serde(default)]
    pub(super) args: Option<Map<String, Value>>,
    #[serde(default)]
    pub(super) read: Option<Map<String, Value>>,
    #[serde(default)]
    pub(super) write: Option<Map<String, Value>>,
    #[serde(default)]
    pub(super) pkw: Option<Map<String, Value>>,
    #[serde(default)]
    pub(super) process: Option<Map<String, Value>>,
    #[serde(default)]
    pub(super) wait: Option<String>,
    #[serde(default)]
    pub(super) inject: Option<Map<String, Value>>,
    #[serde(default)]
    pub(super) observe: Option<Map<String, Value>>,
    #[serde(flatten)]
    pub(super) bus: std::collections::BTreeMap<String, Value>,
    #[serde(default)]
    pub(super) expect: Option<Value>,
    #[serde(default)]
    pub(super) setup: bool,
}
