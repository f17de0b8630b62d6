//! Suites: YAML files of cases, checked at load and turned into validated [`Case`]s.

mod case;
mod load;
mod schema;

pub(crate) use case::{Action, Case, OrderSpec, Run, Step, Target};
pub(crate) use load::{load_dir, Loaded};
