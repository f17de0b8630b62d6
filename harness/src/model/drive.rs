//! Compute functions of the `drive` theme (filled in by its owner).

use super::ComputeFn;

/// The functions of this theme.
pub(super) const FNS: &[ComputeFn] = &[];
