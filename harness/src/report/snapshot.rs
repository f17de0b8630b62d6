//! Transcript snapshots: `--accept` stores every case's transcript, `--snapshots` compares a run
//! with the stored ones and fails each passing case whose transcript changed — how one firmware
//! release is compared with the previous.

use std::fmt;
use std::path::PathBuf;

use super::{case_file, io, transcript, write, ReportError};
use crate::outcome::{RunResult, Verdict};

/// What to do with snapshots.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum SnapshotMode {
    /// Nothing.
    Off,
    /// Compare with the snapshots in the folder.
    Compare(PathBuf),
    /// Store the run's transcripts in the folder.
    Accept(PathBuf),
}

/// What a snapshot pass did.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub(crate) struct SnapshotReport {
    pub(crate) stored: usize,
    pub(crate) same: usize,
    pub(crate) changed: Vec<String>,
    pub(crate) new: Vec<String>,
}

impl fmt::Display for SnapshotReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "snapshots: {} stored, {} unchanged, {} changed, {} without a snapshot",
            self.stored,
            self.same,
            self.changed.len(),
            self.new.len()
        )
    }
}

/// Run-to-run variable data (session handles, connection ids, timestamps) is masked here before
/// comparing. The PPO link has none yet, so this is the identity; protocol bindings that carry
/// such fields extend it.
pub(crate) fn redact(text: &str) -> String {
    text.to_string()
}

/// Applies the mode to the run.
pub(crate) fn apply_snapshots(
    run: &mut RunResult,
    mode: &SnapshotMode,
) -> Result<SnapshotReport, ReportError> {
    let mut report = SnapshotReport::default();
    match mode {
        SnapshotMode::Off => {}
        SnapshotMode::Accept(dir) => {
            for c in &run.cases {
                let path = dir
                    .join(&c.profile)
                    .join(format!("{}.snap", case_file(&c.id)));
                write(&path, redact(&transcript::render(c)).as_bytes())?;
                report.stored += 1;
            }
        }
        SnapshotMode::Compare(dir) => {
            for c in &mut run.cases {
                let path = dir
                    .join(&c.profile)
                    .join(format!("{}.snap", case_file(&c.id)));
                let stored = match std::fs::read_to_string(&path) {
                    Ok(s) => s,
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                        report.new.push(c.id.clone());
                        continue;
                    }
                    Err(e) => return Err(io(&path)(e)),
                };
                let now = redact(&transcript::render(c));
                match first_difference(&stored, &now) {
                    None => report.same += 1,
                    Some((line, want, got)) => {
                        report.changed.push(c.id.clone());
                        if c.verdict == Verdict::Pass {
                            c.verdict = Verdict::Fail;
                            c.message = format!(
                                "transcript differs from snapshot {}: first difference at line {line}: expected `{want}`, got `{got}`",
                                path.display()
                            );
                        }
                    }
                }
            }
        }
    }
    Ok(report)
}

fn first_difference(a: &str, b: &str) -> Option<(usize, String, String)> {
    let (mut x, mut y) = (a.lines(), b.lines());
    for n in 1.. {
        match (x.next(), y.next()) {
            (None, None) => return None,
            (l, r) if l != r => {
                return Some((n, l.unwrap_or("(end)").into(), r.unwrap_or("(end)").into()))
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests::sample_run;

    #[test]
    fn accept_then_compare_then_detect_a_change() {
        let dir = std::env::temp_dir().join(format!("harness-snap-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut run = sample_run();
        let r = apply_snapshots(&mut run, &SnapshotMode::Accept(dir.clone())).unwrap();
        assert_eq!(r.stored, run.cases.len());
        let r = apply_snapshots(&mut run, &SnapshotMode::Compare(dir.clone())).unwrap();
        assert_eq!((r.same, r.changed.len()), (run.cases.len(), 0));
        run.cases[0].steps[0].message = "different".into();
        let r = apply_snapshots(&mut run, &SnapshotMode::Compare(dir.clone())).unwrap();
        assert_eq!(r.changed, vec![run.cases[0].id.clone()]);
        assert_eq!(run.cases[0].verdict, Verdict::Fail);
        assert!(
            run.cases[0].message.contains("first difference at line"),
            "{}",
            run.cases[0].message
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
