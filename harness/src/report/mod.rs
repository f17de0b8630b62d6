//! Reports: consumers of a finished [`crate::outcome::RunResult`] (filled in by its owner).
