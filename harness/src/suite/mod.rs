//! Suites: YAML files of cases, checked at load and turned into validated [`Case`]s.

mod bus_step;
mod case;
mod claim;
pub(crate) mod fields;
pub(crate) mod inventory;
mod load;
pub(crate) mod location;
mod schema;
mod vocabulary;

pub(crate) use bus_step::BusStep;
pub(crate) use case::{parse_duration, Action, Case, OrderSpec, Run, Step, Target};
pub(crate) use load::{load_dir, load_text, Loaded};
pub(crate) use vocabulary::{ParseStep, Vocabulary};

/// Loads suite text for tests in other modules.
#[cfg(test)]
pub(crate) fn load_text_for_tests(text: &str) -> Loaded {
    let mut loaded = Loaded::default();
    load_text(
        &crate::buses::vocabulary(),
        std::path::Path::new("test.yaml"),
        "test",
        text,
        &mut std::collections::HashSet::new(),
        &mut loaded,
    );
    assert!(loaded.errors.is_empty(), "{:?}", loaded.errors);
    loaded
}
