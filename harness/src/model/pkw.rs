//! Compute functions of the `pkw` theme (filled in by its owner).

use super::ComputeFn;

/// The functions of this theme.
pub(super) const FNS: &[ComputeFn] = &[];
