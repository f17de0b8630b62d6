//! Writing the reports into the output folder: file layout, typed errors, stale-file cleanup.
//!
//! Layout of `<out>`: `junit.xml`, `run.json`, `summary.md`, `index.html`, and
//! `transcripts.txt`: every transcript of the run, one section each, in the run's order. A file
//! per case (`transcripts/<profile>/<case id with / as __>.txt`) comes on request
//! ([`Transcripts::Files`]): thousands of small files made writing the reports the slowest part of
//! a run.

use std::fmt;
use std::fs::File;
use std::io::Write;
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
}

/// Where the transcripts go besides [`TRANSCRIPTS`] (`--transcripts`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub(crate) enum Transcripts {
    /// Only the one file.
    #[default]
    One,
    /// Also a file per case under `transcripts/`.
    Files,
}

/// The file that holds every transcript of a run.
pub(crate) const TRANSCRIPTS: &str = "transcripts.txt";

/// Starts each section of [`TRANSCRIPTS`], followed by the section's name
/// (`<profile>/<case id>`). No line of a transcript starts with it: after the header fields,
/// each line starts with `step`, `attempt` or spaces.
const SECTION: &str = "=== ";

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
    /// `<out>/transcripts.txt`.
    pub(crate) transcripts: PathBuf,
    /// How many transcripts (one per case and profile that applied).
    pub(crate) transcript_count: usize,
    /// `<out>/transcripts`, when a file per case was asked for.
    pub(crate) files: Option<PathBuf>,
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
        )?;
        if let Some(dir) = &self.files {
            write!(f, " and in {}", dir.display())?;
        }
        Ok(())
    }
}

/// Maps an IO error to [`ReportError::Io`] naming `path`.
pub(super) fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ReportError + '_ {
    move |source| ReportError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes a file as `fill` streams it, creating its folder: the big reports are never held
/// whole in memory (a default run's `run.json` and [`TRANSCRIPTS`] are tens of megabytes, and
/// building them as strings cost more time than writing them).
fn stream_file(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), ReportError> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
    }
    let mut out = std::io::BufWriter::with_capacity(1 << 20, File::create(path).map_err(io(path))?);
    fill(&mut out).and_then(|()| out.flush()).map_err(io(path))
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

/// Where a case's transcript is, as `run.json` and `junit.xml` name it:
/// `transcripts.txt#<profile>/<case id>`, the file and its section; none for a case that did not
/// apply (it exchanged nothing, and `run.json` and `junit.xml` give the reason).
pub(super) fn transcript_file(case: &CaseResult) -> Option<String> {
    (case.verdict != Verdict::NotApplicable)
        .then(|| format!("{TRANSCRIPTS}#{}", section_name(case)))
}

/// A case's section name in [`TRANSCRIPTS`].
fn section_name(case: &CaseResult) -> String {
    format!("{}/{}", case.profile, case.id)
}

/// [`TRANSCRIPTS`]' text, streamed into `out`: each transcript after its section line.
fn write_transcripts(run: &RunResult, out: &mut dyn Write) -> std::io::Result<()> {
    for case in run
        .cases
        .iter()
        .filter(|c| c.verdict != Verdict::NotApplicable)
    {
        write!(
            out,
            "{SECTION}{}\n{}",
            section_name(case),
            transcript::render(case)
        )?;
    }
    Ok(())
}

/// The sections of a [`TRANSCRIPTS`] text by name, each transcript as written.
pub(super) fn sections(text: &str) -> std::collections::HashMap<&str, &str> {
    let mut found = std::collections::HashMap::new();
    let mut rest = text;
    while let Some(after) = rest.strip_prefix(SECTION) {
        let (name, body) = after.split_once('\n').unwrap_or((after, ""));
        let end = body
            .match_indices(&format!("\n{SECTION}"))
            .next()
            .map_or(body.len(), |(i, _)| i + 1);
        found.insert(name, &body[..end]);
        rest = &body[end..];
    }
    found
}

/// Writes `junit.xml`, `run.json`, `summary.md`, `index.html` and `transcripts.txt` into `out`
/// (and a transcript file per case with [`Transcripts::Files`]), each rendered on a thread of
/// its own, after removing what an earlier run left that this one does not replace (so no stale
/// transcript survives).
pub(crate) fn write_all(
    run: &RunResult,
    out: &Path,
    files: Transcripts,
) -> Result<Written, ReportError> {
    let per_case = out.join("transcripts");
    // `symlink_metadata` so a symlinked folder is removed as a link, never followed.
    if std::fs::symlink_metadata(&per_case).is_ok() {
        std::fs::remove_dir_all(&per_case).map_err(io(&per_case))?;
    }
    let written = Written {
        junit: out.join("junit.xml"),
        run_json: out.join("run.json"),
        summary: out.join("summary.md"),
        html: out.join("index.html"),
        transcripts: out.join(TRANSCRIPTS),
        transcript_count: run.cases.iter().filter_map(transcript_file).count(),
        files: (files == Transcripts::Files).then_some(per_case),
    };
    std::thread::scope(|s| {
        let jobs = [
            s.spawn(|| stream_file(&written.junit, |w| junit::write(run, w))),
            s.spawn(|| stream_file(&written.run_json, |w| json::write(run, w))),
            s.spawn(|| write_file(&written.summary, summary::markdown(run).as_bytes())),
            s.spawn(|| write_file(&written.html, html::render(run).as_bytes())),
            s.spawn(|| stream_file(&written.transcripts, |w| write_transcripts(run, w))),
            s.spawn(|| per_case_files(run, written.files.as_deref())),
        ];
        jobs.into_iter()
            .map(|j| j.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect::<Result<(), _>>()
    })?;
    Ok(written)
}

/// A transcript file per case that applied under `dir`, if given.
fn per_case_files(run: &RunResult, dir: Option<&Path>) -> Result<(), ReportError> {
    let Some(dir) = dir else { return Ok(()) };
    for case in run
        .cases
        .iter()
        .filter(|c| c.verdict != Verdict::NotApplicable)
    {
        write_file(
            &dir.join(case_file(case, "txt")),
            transcript::render(case).as_bytes(),
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::{sample_run, temp_dir};

    #[test]
    fn writes_every_report_and_one_transcripts_file() {
        let out = temp_dir("write-all");
        let stale = out.join("transcripts/sk550p/old-case.txt");
        write_file(&stale, b"from an earlier run").unwrap();
        let run = sample_run();
        let w = write_all(&run, &out, Transcripts::One).unwrap();
        assert!(!stale.exists(), "stale transcript removed");
        assert!(
            !out.join("transcripts").exists(),
            "no file per case unless asked"
        );
        for f in [&w.junit, &w.run_json, &w.summary, &w.html, &w.transcripts] {
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
        let text = std::fs::read_to_string(&w.transcripts).unwrap();
        let found = sections(&text);
        assert_eq!(found.len(), 5);
        for c in run
            .cases
            .iter()
            .filter(|c| c.verdict != Verdict::NotApplicable)
        {
            assert_eq!(
                found[section_name(c).as_str()],
                transcript::render(c),
                "{}",
                c.id
            );
        }
        assert!(!found.contains_key(section_name(na).as_str()));
        assert_eq!(
            transcript_file(&run.cases[0]).as_deref(),
            Some("transcripts.txt#sk550p/bu0620/pkw-telegrams/p102-write")
        );
        assert!(w.to_string().contains("5 transcripts"), "{w}");
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn a_file_per_case_on_request() {
        let out = temp_dir("write-files");
        let run = sample_run();
        let w = write_all(&run, &out, Transcripts::Files).unwrap();
        let t = out.join("transcripts/sk550p/bu0620__pkw-telegrams__p102-write.txt");
        let text = std::fs::read_to_string(&t).unwrap();
        assert!(
            text.starts_with("case: bu0620/pkw-telegrams/p102-write\n"),
            "{text}"
        );
        let files: usize = ["sk550p", "tu3-eip"]
            .iter()
            .map(|p| {
                std::fs::read_dir(out.join("transcripts").join(p))
                    .unwrap()
                    .count()
            })
            .sum();
        assert_eq!(files, w.transcript_count);
        let listed = format!("and in {}", out.join("transcripts").display());
        assert!(w.to_string().ends_with(&listed), "{w}");
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn io_errors_name_the_path() {
        let base = temp_dir("write-err");
        let blocker = base.join("not-a-folder");
        write_file(&blocker, b"a file where the output folder should be").unwrap();
        let err = write_all(&sample_run(), &blocker, Transcripts::One).unwrap_err();
        assert!(matches!(err, ReportError::Io { .. }), "{err:?}");
        assert!(err.to_string().contains("not-a-folder"), "{err}");
        let _ = std::fs::remove_dir_all(&base);
    }

    #[test]
    fn case_files_cannot_escape_their_folder() {
        let mut c = sample_run().cases.remove(0);
        c.id = "../..\\x/y".into();
        assert_eq!(case_file(&c, "txt"), Path::new("sk550p/..__..__x__y.txt"));
        c.profile = "..".into();
        assert_eq!(case_file(&c, "snap"), Path::new("_../..__..__x__y.snap"));
    }
}
