//! Writing the reports into the output folder: file layout, typed errors, stale-file cleanup.
//!
//! Layout of `<out>`: `junit.xml`, `run.json`, `summary.md`, `index.html`, and
//! `transcripts/<profile>/<case id with / as __>.txt`.

use std::fmt;
use std::path::{Path, PathBuf};

use super::{html, json, junit, summary, transcript};
use crate::outcome::{CaseResult, RunResult, Verdict};

/// A report could not be written or read. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub(crate) enum ReportError {
    /// File system trouble.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// `run.json` could not be serialized.
    #[error("{path}: cannot write JSON: {source}")]
    Json {
        /// The JSON file.
        path: PathBuf,
        /// What went wrong.
        source: serde_json::Error,
    },
}

/// What [`write_all`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Written {
    /// `<out>/junit.xml`.
    pub(crate) junit: PathBuf,
    /// `<out>/run.json`.
    pub(crate) run_json: PathBuf,
    /// `<out>/summary.md`.
    pub(crate) summary: PathBuf,
    /// `<out>/index.html`.
    pub(crate) html: PathBuf,
    /// `<out>/transcripts`.
    pub(crate) transcripts: PathBuf,
    /// How many transcript files (one per case and profile).
    pub(crate) transcript_count: usize,
}

impl fmt::Display for Written {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "reports: {}, {}, {}, {}; {} transcripts in {}",
            self.junit.display(),
            self.run_json.display(),
            self.summary.display(),
            self.html.display(),
            self.transcript_count,
            self.transcripts.display()
        )
    }
}

/// Maps an IO error to [`ReportError::Io`] naming `path`.
pub(super) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes a file, creating its folder.
pub(super) fn write_file(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
    }
    std::fs::write(path, bytes).map_err(io(path))
}

/// One path component from a name: `/` and `\` become `__`, and a name of dots only (`..`) is
/// prefixed with `_`, so no name can leave its folder.
fn component(name: &str) -> String {
    let s = name.replace(['/', '\\'], "__");
    if s.chars().all(|c| c == '.') {
        format!("_{s}")
    } else {
        s
    }
}

/// A case's file below a per-profile folder: `<profile>/<id with / as __>.<ext>`. Transcripts
/// and snapshots both use it, so one case has one name everywhere.
pub(super) fn case_file(case: &CaseResult, ext: &str) -> PathBuf {
    Path::new(&component(&case.profile)).join(format!("{}.{ext}", component(&case.id)))
}

/// A case's transcript, relative to the output folder; none for a case that did not apply
/// (it exchanged nothing, and `run.json` and `junit.xml` give the reason): most cases do not
/// apply to most profiles, and a file each made the reports the slowest part of a run.
pub(super) fn transcript_file(case: &CaseResult) -> Option<PathBuf> {
    (case.verdict != Verdict::NotApplicable)
        .then(|| Path::new("transcripts").join(case_file(case, "txt")))
}

/// Writes `junit.xml`, `run.json`, `summary.md`, `index.html` and every case's transcript into
/// `out`, after
/// removing the transcripts folder of an earlier run (so no stale transcript survives).
pub(crate) fn write_all(run: &RunResult, out: &Path) -> Result<Written, ReportError> {
    let transcripts = out.join("transcripts");
    // `symlink_metadata` so a symlinked folder is removed as a link, never followed.
    if std::fs::symlink_metadata(&transcripts).is_ok() {
        std::fs::remove_dir_all(&transcripts).map_err(io(&transcripts))?;
    }
    let written = Written {
        junit: out.join("junit.xml"),
        run_json: out.join("run.json"),
        summary: out.join("summary.md"),
        html: out.join("index.html"),
        transcripts,
        transcript_count: run.cases.iter().filter_map(transcript_file).count(),
    };
    write_file(&written.junit, junit::render(run).as_bytes())?;
    let doc = json::render(run).map_err(|source| ReportError::Json {
        path: written.run_json.clone(),
        source,
    })?;
    write_file(&written.run_json, doc.as_bytes())?;
    write_file(&written.summary, summary::markdown(run).as_bytes())?;
    write_file(&written.html, html::render(run).as_bytes())?;
    for case in &run.cases {
        if let Some(file) = transcript_file(case) {
            write_file(&out.join(file), transcript::render(case).as_bytes())?;
        }
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::{sample_run, temp_dir};

    #[test]
    fn writes_every_report_and_removes_stale_transcripts() {
        let out = temp_dir("write-all");
        let stale = out.join("transcripts/sk550p/old-case.txt");
        write_file(&stale, b"from an earlier run").unwrap();
        let run = sample_run();
        let w = write_all(&run, &out).unwrap();
        assert!(!stale.exists(), "stale transcript removed");
        for f in [&w.junit, &w.run_json, &w.summary, &w.html] {
            assert!(f.is_file(), "{}", f.display());
        }
        // One case did not apply: it has no transcript.
        assert_eq!(w.transcript_count, run.cases.len() - 1);
        assert_eq!(w.transcript_count, 5);
        let na = run
            .cases
            .iter()
            .find(|c| c.verdict == Verdict::NotApplicable)
            .unwrap();
        assert_eq!(transcript_file(na), None);
        assert!(!out.join("transcripts").join(case_file(na, "txt")).exists());
        let t = out.join("transcripts/sk550p/bu0620__pkw-telegrams__p102-write.txt");
        let text = std::fs::read_to_string(&t).unwrap();
        assert!(
            text.starts_with("case: bu0620/pkw-telegrams/p102-write\n"),
            "{text}"
        );
        assert!(w.to_string().contains("5 transcripts"), "{w}");
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn io_errors_name_the_path() {
        let base = temp_dir("write-err");
        let blocker = base.join("not-a-folder");
        write_file(&blocker, b"a file where the output folder should be").unwrap();
        let err = write_all(&sample_run(), &blocker).unwrap_err();
        assert!(matches!(err, ReportError::Io { .. }), "{err:?}");
        assert!(err.to_string().contains("not-a-folder"), "{err}");
        let _ = std::fs::remove_dir_all(&base);
    }

    #[test]
    fn case_files_cannot_escape_their_folder() {
        let mut c = sample_run().cases.remove(0);
        c.id = "../..\\x/y".into();
        assert_eq!(
            transcript_file(&c),
            Some(PathBuf::from("transcripts/sk550p/..__..__x__y.txt"))
        );
        c.profile = "..".into();
        assert_eq!(case_file(&c, "snap"), Path::new("_../..__..__x__y.snap"));
    }
}
