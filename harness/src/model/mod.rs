//! The reference model: named functions over `proto::nord` that suite `compute` steps call.
//!
//! A `compute` step names a function (`addr.coe`), passes arguments in the manuals' notation
//! and compares the returned JSON object with its `expect` map. The functions are grouped by
//! theme, one module each; [`registry`] joins them. `harness list --functions` prints them.

mod addr;
mod args;
mod drive;
mod params;
mod pkw;
mod tables;

pub(crate) use args::{Args, ComputeError, Ctx};
use serde_json::Value;

/// One named function of the reference model.
pub(crate) struct ComputeFn {
    /// Name used in suites, `theme.function`.
    pub(crate) name: &'static str,
    /// One line: what it computes and from which manual section.
    pub(crate) doc: &'static str,
    /// The function: arguments in, a JSON object (or scalar) out.
    pub(crate) run: fn(&Ctx, &Args) -> Result<Value, ComputeError>,
}

/// Every function of the reference model.
pub(crate) fn registry() -> impl Iterator<Item = &'static ComputeFn> {
    addr::FNS
        .iter()
        .chain(pkw::FNS)
        .chain(drive::FNS)
        .chain(tables::FNS)
        .chain(params::FNS)
}

impl std::fmt::Debug for ComputeFn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// Looks a function up by name.
pub(crate) fn find(name: &str) -> Option<&'static ComputeFn> {
    registry().find(|f| f.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn names_are_unique_and_themed() {
        let mut seen = HashSet::new();
        for f in registry() {
            assert!(seen.insert(f.name), "duplicate compute fn {}", f.name);
            assert!(f.name.contains('.'), "{} lacks a theme prefix", f.name);
            assert!(!f.doc.is_empty(), "{} has no doc", f.name);
        }
    }
}
