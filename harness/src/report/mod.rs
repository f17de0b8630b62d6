//! Reports: consumers of a finished [`crate::outcome::RunResult`].
//!
//! `junit.xml`, `run.json`, `summary.md`, `index.html` and one transcript per case are written by
//! [`write_all`]; snapshots of the transcripts are compared or stored by [`apply_snapshots`];
//! [`terminal`] is the short console summary. A report folder reads back with [`read`], for
//! [`compare_runs`] (`harness diff`) and [`merge`] (`harness merge` of `--shard` runs).

mod diff;
mod diff_view;
mod errata_counts;
#[cfg(test)]
mod fixtures;
mod html;
mod json;
mod junit;
mod markup;
mod merge;
mod read;
mod record;
mod redact;
mod signoff;
mod snapshot;
mod statements;
mod summary;
mod transcript;
mod write;

pub(crate) use diff::{compare_runs, Gate};
pub(crate) use diff_view::{text as diff_text, write_diff};
pub(crate) use errata_counts::text_table as errata_table;
pub(crate) use merge::merge;
pub(crate) use read::{read, run_json};
pub(crate) use snapshot::{apply_snapshots, SnapshotMode};
pub(crate) use statements::sections_text;
pub(crate) use statements::text_table as statements_table;
pub(crate) use summary::{quiet, terminal};
#[cfg(test)]
pub(crate) use transcript::render as transcript_for_tests;
pub(crate) use transcript::seal;
pub(crate) use write::{write_all, Transcripts};
