//! Reports: consumers of a finished [`crate::outcome::RunResult`].
//!
//! `junit.xml`, `run.json`, `summary.md`, `index.html` and one transcript per case are written by
//! [`write_all`]; snapshots of the transcripts are compared or stored by [`apply_snapshots`];
//! [`terminal`] is the short console summary.

#[cfg(test)]
mod fixtures;
mod html;
mod json;
mod junit;
mod markup;
mod record;
mod snapshot;
mod summary;
mod transcript;
mod write;

pub(crate) use snapshot::{apply_snapshots, SnapshotMode};
pub(crate) use summary::terminal;
pub(crate) use write::write_all;
