//! Reports: consumers of a finished [`crate::outcome::RunResult`].
//!
//! `junit.xml`, `run.json`, `summary.md` and one transcript per case, written by
//! [`write_all`]; snapshots of the transcripts compared or stored by [`apply_snapshots`].

mod json;
mod junit;
mod snapshot;
mod summary;
mod transcript;

pub(crate) use snapshot::{apply_snapshots, SnapshotMode};
pub(crate) use summary::terminal;

use std::path::{Path, PathBuf};

use crate::outcome::RunResult;

/// A report could not be written or read.
#[derive(Debug, thiserror::Error)]
pub(crate) enum ReportError {
    /// File system trouble, with the path.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes a file, creating its folder.
fn write(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
    }
    std::fs::write(path, bytes).map_err(io(path))
}

/// The file name of a case's transcript: its id with `/` as `__`.
fn case_file(id: &str) -> String {
    id.replace('/', "__")
}

/// Writes every report into `out`, replacing the transcripts of an earlier run.
pub(crate) fn write_all(run: &RunResult, out: &Path) -> Result<(), ReportError> {
    let transcripts = out.join("transcripts");
    if transcripts.exists() {
        std::fs::remove_dir_all(&transcripts).map_err(io(&transcripts))?;
    }
    write(&out.join("junit.xml"), &junit::render(run))?;
    write(&out.join("run.json"), json::render(run).as_bytes())?;
    write(&out.join("summary.md"), summary::markdown(run).as_bytes())?;
    for case in &run.cases {
        let path = transcripts
            .join(&case.profile)
            .join(format!("{}.txt", case_file(&case.id)));
        write(&path, transcript::render(case).as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use crate::outcome::*;
    use serde_json::json;
    use std::time::Duration;

    fn case(id: &str, profile: &str, verdict: Verdict, message: &str) -> CaseResult {
        CaseResult {
            id: id.into(),
            title: "t".into(),
            profile: profile.into(),
            manual: ManualRef {
                doc: "BU 0620".into(),
                edition: "2020-03 en".into(),
                section: "2.2.7".into(),
                page: 20,
            },
            verdict,
            message: message.into(),
            steps: vec![StepResult {
                step: "write P102 set 2 FI 5 = 250".into(),
                verdict,
                observed: json!({"ak": 1}),
                message: message.into(),
                exchanges: vec![Exchange {
                    sent_hex: "65 01 24 4E 01 00 00 00 00 FA 04 7E 00 00".into(),
                    sent: "AK 2".into(),
                    received_hex: "65 01 14 4E 01 00 00 00 00 FA 0B 31 00 00".into(),
                    received: "AK 1".into(),
                }],
            }],
            duration: Duration::from_millis(1),
        }
    }

    /// A run with one case of each verdict.
    pub(crate) fn sample_run() -> RunResult {
        RunResult {
            dut: "embedded simulator".into(),
            profiles: vec!["sk550p".into(), "tu3-eip".into()],
            cases: vec![
                case("bu0620/addr/coe-p102", "sk550p", Verdict::Pass, ""),
                case(
                    "bu0620/pkw/p102",
                    "sk550p",
                    Verdict::Fail,
                    "status: expected 2865 (0B31h), got 2871 (0B37h)",
                ),
                case(
                    "bu0620/pkw/silent",
                    "tu3-eip",
                    Verdict::Error,
                    "no answer from the DUT within 250 bus cycles",
                ),
                case(
                    "bu0620/addr/coe-p102",
                    "tu3-eip",
                    Verdict::NotApplicable,
                    "the statement is about sk550p, this run is tu3-eip",
                ),
            ],
            errata: vec![Erratum {
                doc: "BU 0620".into(),
                edition: "2020-03 en".into(),
                section: "2.3.5".into(),
                page: 27,
                case: "bu0620/addr-cip/x".into(),
                printed: "class 103".into(),
                correct: "class 102".into(),
                why: "FI 2 is class 102".into(),
            }],
            load_errors: vec![],
            duration: Duration::from_millis(5),
        }
    }
}
