//! Transcript snapshots: `--accept` stores every case's transcript, `--snapshots` compares a run
//! with the stored ones and fails each passing case whose transcript changed. This is how one
//! firmware release is compared with the previous one (DESIGN.md "Verdicts and reports").
//!
//! Files: `<dir>/<profile>/<case id with / as __>.snap`, the same naming as the transcripts.
//! Both sides pass through [`redact`] (what a device picks anew each run masked) before they
//! are stored or compared, and are compared by
//! the same function as `harness diff` compares two runs' transcripts
//! ([`compare_transcripts`]).

use std::fmt;
use std::path::{Path, PathBuf};

use super::diff::compare_transcripts;
use super::redact::redact;
use super::transcript;
use super::write::{case_file, io, write_file, ReportError};
use crate::bus::Bus;
use crate::outcome::{RunResult, Verdict};

/// What to do with snapshots.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum SnapshotMode {
    /// Nothing.
    Off,
    /// Compare the run's transcripts with the snapshots in the folder.
    Compare(PathBuf),
    /// Store the run's transcripts in the folder as the new snapshots.
    Accept(PathBuf),
}

/// What a snapshot pass did. Cases are named `<profile> <id>`.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub(crate) struct SnapshotReport {
    /// Snapshots written (accept).
    pub(crate) stored: usize,
    /// Transcripts equal to their snapshot (compare).
    pub(crate) same: usize,
    /// Transcripts that differ from their snapshot (compare); passing ones now fail.
    pub(crate) changed: Vec<String>,
    /// Cases without a snapshot (compare): reported, not failed.
    pub(crate) new: Vec<String>,
}

impl fmt::Display for SnapshotReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "snapshots: {} stored, {} unchanged, {} changed, {} new (no snapshot yet)",
            self.stored,
            self.same,
            self.changed.len(),
            self.new.len()
        )?;
        for c in &self.changed {
            write!(f, "\n  changed: {c}")?;
        }
        Ok(())
    }
}

fn compare(
    buses: &[&Bus],
    run: &mut RunResult,
    dir: &Path,
    report: &mut SnapshotReport,
) -> Result<(), ReportError> {
    for c in &mut run.cases {
        let path = dir.join(case_file(c, "snap"));
        let name = format!("{} {}", c.profile, c.id);
        let stored = match std::fs::read_to_string(&path) {
            Ok(s) => s,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                report.new.push(name);
                continue;
            }
            Err(e) => return Err(io(&path)(e)),
        };
        let Some(diff) = compare_transcripts(buses, &stored, &transcript::render(c)) else {
            report.same += 1;
            continue;
        };
        let (place, line, want, got) = diff.first();
        report.changed.push(name);
        if c.verdict == Verdict::Pass {
            c.verdict = Verdict::Fail;
            c.message = format!(
                "transcript differs from snapshot {}: first difference at line {line} ({place}): expected `{want}`, got `{got}`",
                path.display()
            );
        }
    }
    Ok(())
}

/// Applies `mode` to the run: stores every transcript (accept), or compares every transcript with
/// its snapshot and turns each passing case whose transcript changed into a failure (compare).
pub(crate) fn apply_snapshots(
    buses: &[&Bus],
    run: &mut RunResult,
    mode: &SnapshotMode,
) -> Result<SnapshotReport, ReportError> {
    let mut report = SnapshotReport::default();
    match mode {
        SnapshotMode::Off => {}
        SnapshotMode::Accept(dir) => {
            for c in &run.cases {
                let text = redact(buses, &transcript::render(c));
                write_file(&dir.join(case_file(c, "snap")), text.as_bytes())?;
                report.stored += 1;
            }
        }
        SnapshotMode::Compare(dir) => compare(buses, run, dir, &mut report)?,
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::{sample_run, temp_dir};

    #[test]
    fn accept_then_compare_then_detect_a_change() {
        let dir = temp_dir("snap");
        let mut run = sample_run();
        let r = apply_snapshots(
            crate::buses::BUSES,
            &mut run,
            &SnapshotMode::Accept(dir.clone()),
        )
        .unwrap();
        assert_eq!(r.stored, run.cases.len());
        assert!(dir
            .join("sk550p/bu0620__pkw-telegrams__p102-write.snap")
            .is_file());
        let r = apply_snapshots(
            crate::buses::BUSES,
            &mut run,
            &SnapshotMode::Compare(dir.clone()),
        )
        .unwrap();
        assert_eq!(
            (r.same, r.changed.len(), r.new.len()),
            (run.cases.len(), 0, 0)
        );

        // A new firmware answers PWE 251; the passing case fails, the failing one stays failing.
        for c in &mut run.cases[..2] {
            c.steps[0].exchanges[0].received_hex = "65 02 14 4E 01 00 00 00 00 FB".into();
        }
        let r = apply_snapshots(
            crate::buses::BUSES,
            &mut run,
            &SnapshotMode::Compare(dir.clone()),
        )
        .unwrap();
        assert_eq!(
            r.changed,
            vec![
                "sk550p bu0620/pkw-telegrams/p102-write".to_string(),
                "sk550p bu0620/addressing/coe-p102".to_string()
            ]
        );
        assert_eq!(run.cases[0].verdict, Verdict::Fail);
        let want = format!(
            "transcript differs from snapshot {}: first difference at line 12 (step 1: pkw FI 2: 24 4E 01 00 00 00 00 FA): expected `  <- 65 02 14 4E 01 00 00 00 00 FA`, got `  <- 65 02 14 4E 01 00 00 00 00 FB`",
            dir.join("sk550p/bu0620__pkw-telegrams__p102-write.snap").display()
        );
        assert_eq!(run.cases[0].message, want);
        assert_eq!(run.cases[1].verdict, Verdict::Fail);
        assert!(
            run.cases[1].message.starts_with("status: expected"),
            "message kept"
        );
        assert!(r.to_string().contains("2 changed"), "{r}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_missing_snapshot_is_new_not_a_failure() {
        let dir = temp_dir("snap-new");
        let mut run = sample_run();
        let r = apply_snapshots(
            crate::buses::BUSES,
            &mut run,
            &SnapshotMode::Compare(dir.clone()),
        )
        .unwrap();
        assert_eq!(r.new.len(), run.cases.len());
        assert_eq!(run, sample_run(), "verdicts untouched");
    }

    #[test]
    fn off_does_nothing() {
        let mut run = sample_run();
        let r = apply_snapshots(crate::buses::BUSES, &mut run, &SnapshotMode::Off).unwrap();
        assert_eq!((r, run), (SnapshotReport::default(), sample_run()));
    }
}
