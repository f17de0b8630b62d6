//! Reading a report folder back into a [`RunResult`], for `harness diff` and `harness merge`.
//!
//! `run.json` holds every case with the step that decided its verdict, without exchanges; each
//! case's transcript file holds all the steps as text. A case read back carries its deciding
//! step and that text ([`CaseResult::transcript`]), which the reports render in place of the
//! steps, so a run read back writes the same reports again.

use serde::Deserialize;
use std::path::{Component, Path, PathBuf};
use std::time::Duration;

use crate::outcome::{
    CaseKind, CaseResult, Erratum, ManualRef, MutationScore, Refusal, RunMeta, RunResult,
    SectionCount, StatementCoverage, StepResult, Verdict,
};

/// A report folder or `run.json` that cannot be read back. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub(crate) enum ReadError {
    /// File system trouble.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// Not a `run.json` this harness writes.
    #[error("{path}: not a harness run.json: {source}")]
    Json {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: serde_json::Error,
    },
    /// A case names a transcript outside the report folder.
    #[error("{path}: case {case} names transcript `{file}` outside the report folder")]
    Escapes {
        /// `run.json`.
        path: PathBuf,
        /// The case (`<profile> <id>`).
        case: String,
        /// The transcript path as written.
        file: String,
    },
    /// A case names a section its transcripts file does not have.
    #[error("{path}: case {case} names transcript `{named}`, which is not in that file")]
    NoSection {
        /// `run.json`.
        path: PathBuf,
        /// The case (`<profile> <id>`).
        case: String,
        /// The transcript as named.
        named: String,
    },
}

/// The transcript files of a report folder, each read once and split into its sections (a
/// transcripts file holds every case's).
#[derive(Default)]
struct Files(std::collections::HashMap<PathBuf, Read>);

/// A transcript file read: its text, and its sections by name.
struct Read {
    text: String,
    sections: std::collections::HashMap<String, String>,
}

impl Files {
    /// The transcript `named` of case `c` (`<file>#<section>`, or a file of its own as an older
    /// harness or `--transcripts files` wrote it), found beside `run.json` at `path`.
    fn transcript(
        &mut self,
        path: &Path,
        base: &Path,
        c: &Case,
        named: &str,
    ) -> Result<String, ReadError> {
        let case = || format!("{} {}", c.profile, c.id);
        let (file, section) = match named.split_once('#') {
            Some((file, section)) => (file, Some(section)),
            None => (named, None),
        };
        let rel = Path::new(file);
        if !rel.components().all(|p| matches!(p, Component::Normal(_))) {
            return Err(ReadError::Escapes {
                path: path.to_path_buf(),
                case: case(),
                file: file.into(),
            });
        }
        let at = base.join(rel);
        if !self.0.contains_key(&at) {
            let text = std::fs::read_to_string(&at).map_err(|source| ReadError::Io {
                path: at.clone(),
                source,
            })?;
            let sections = super::write::sections(&text)
                .into_iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            self.0.insert(at.clone(), Read { text, sections });
        }
        let read = &self.0[&at];
        match section {
            None => Ok(read.text.clone()),
            Some(section) => {
                read.sections
                    .get(section)
                    .cloned()
                    .ok_or_else(|| ReadError::NoSection {
                        path: path.to_path_buf(),
                        case: case(),
                        named: named.into(),
                    })
            }
        }
    }
}

/// `run.json` as [`super::json`] writes it; what the reports do not need (counts) is left out.
/// Fields an older harness did not write take their defaults.
#[derive(Deserialize)]
struct Doc {
    dut: String,
    #[serde(default)]
    meta: RunMeta,
    profiles: Vec<String>,
    duration: f64,
    load_errors: Vec<String>,
    errata: Vec<Erratum>,
    #[serde(default)]
    statements: Vec<StatementCoverage>,
    #[serde(default)]
    mutation: Option<MutationScore>,
    sections: Vec<SectionCount>,
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    id: String,
    title: String,
    profile: String,
    #[serde(default)]
    kind: CaseKind,
    verdict: Verdict,
    manual: ManualRef,
    message: String,
    duration: f64,
    transcript: Option<String>,
    seq: Option<usize>,
    step: Option<Step>,
    /// Why each discarded attempt did not count (their steps are in the transcript).
    #[serde(default)]
    discarded: Vec<String>,
}

/// The deciding step as `run.json` keeps it (without exchanges).
#[derive(Deserialize)]
struct Step {
    step: String,
    verdict: Verdict,
    observed: serde_json::Value,
    refusal: Option<Refusal>,
    message: String,
}

fn secs(path: &Path, s: f64) -> Result<Duration, ReadError> {
    Duration::try_from_secs_f64(s).map_err(|e| ReadError::Json {
        path: path.to_path_buf(),
        source: serde::de::Error::custom(format!("duration {s}: {e}")),
    })
}

/// Where `run.json` is: `given` itself when it is a file, else `given/run.json`.
pub(crate) fn run_json(given: &Path) -> PathBuf {
    if given.is_dir() {
        given.join("run.json")
    } else {
        given.to_path_buf()
    }
}

/// Reads a report folder (or its `run.json`, with the transcripts beside it) back into a run
/// whose cases carry their transcript text. A case without a `seq` (a report from before
/// sharding) takes its position in the file.
pub(crate) fn read(given: &Path) -> Result<RunResult, ReadError> {
    let path = run_json(given);
    let base = path.parent().unwrap_or(Path::new("."));
    let text = std::fs::read_to_string(&path).map_err(|source| ReadError::Io {
        path: path.clone(),
        source,
    })?;
    let doc: Doc = serde_json::from_str(&text).map_err(|source| ReadError::Json {
        path: path.clone(),
        source,
    })?;
    let mut cases = Vec::with_capacity(doc.cases.len());
    let mut files = Files::default();
    for (n, c) in doc.cases.into_iter().enumerate() {
        let transcript = match &c.transcript {
            None => None,
            Some(named) => Some(files.transcript(&path, base, &c, named)?),
        };
        let mut case = CaseResult {
            duration: secs(&path, c.duration)?,
            id: c.id,
            title: c.title,
            profile: c.profile,
            manual: c.manual,
            kind: c.kind,
            verdict: c.verdict,
            message: c.message,
            steps: c
                .step
                .into_iter()
                .map(|st| StepResult {
                    step: st.step,
                    verdict: st.verdict,
                    observed: st.observed,
                    refusal: st.refusal,
                    message: st.message,
                    exchanges: Vec::new(),
                })
                .collect(),
            seq: c.seq.unwrap_or(n),
            discarded: c
                .discarded
                .into_iter()
                .map(|why| crate::outcome::Discarded {
                    why,
                    steps: Vec::new(),
                })
                .collect(),
            transcript: None,
        };
        if let Some(text) = transcript {
            super::transcript::read_back(&mut case, &text);
        }
        cases.push(case);
    }
    Ok(RunResult {
        dut: doc.dut,
        meta: doc.meta,
        profiles: doc.profiles,
        cases,
        errata: doc.errata,
        statements: doc.statements,
        sections: doc.sections,
        load_errors: doc.load_errors,
        mutation: doc.mutation,
        duration: secs(&path, doc.duration)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::{sample_run, temp_dir};
    use crate::report::write::Transcripts;
    use crate::report::{transcript, write_all};

    #[test]
    fn a_written_run_reads_back_and_writes_the_same_reports_again() {
        let (first, second) = (temp_dir("read-first"), temp_dir("read-second"));
        let mut run = sample_run();
        run.cases[1].steps[0].refusal = Some(Refusal {
            kind: "parameter-channel error".into(),
            code: 3,
            text: "wrong subindex".into(),
        });
        write_all(&run, &first, Transcripts::One).unwrap();
        let back = read(&first).unwrap();
        assert_eq!(back.cases.len(), run.cases.len());
        for (b, c) in back.cases.iter().zip(&run.cases) {
            let deciding = c.deciding_step().map(|st| StepResult {
                exchanges: Vec::new(),
                ..st.clone()
            });
            assert_eq!(b.deciding_step(), deciding.as_ref(), "{}", c.id);
            assert_eq!(
                (&b.id, &b.profile, b.verdict, b.seq),
                (&c.id, &c.profile, c.verdict, c.seq)
            );
            assert_eq!(transcript::render(b), transcript::render(c), "{}", c.id);
        }
        assert_eq!(back.cases[2].transcript, None, "not applicable: no file");
        assert_eq!((&back.errata, &back.dut), (&run.errata, &run.dut));

        // Through run.json itself, into another folder: every file the same but for the time
        // JUnit stamps its suites with when it writes them.
        write_all(
            &read(&first.join("run.json")).unwrap(),
            &second,
            Transcripts::One,
        )
        .unwrap();
        let untimed = |f: &str| {
            let text = std::fs::read_to_string(f).unwrap();
            text.split("timestamp=\"")
                .enumerate()
                .map(|(i, part)| match (i, part.split_once('"')) {
                    (0, _) | (_, None) => part.to_string(),
                    (_, Some((_, rest))) => format!("timestamp=\"…\"{rest}"),
                })
                .collect::<String>()
        };
        for f in [
            "run.json",
            "junit.xml",
            "summary.md",
            "index.html",
            "transcripts.txt",
        ] {
            let (a, b) = (first.join(f), second.join(f));
            assert_eq!(
                untimed(a.to_str().unwrap()),
                untimed(b.to_str().unwrap()),
                "{f}"
            );
        }
        let _ = std::fs::remove_dir_all(&first);
        let _ = std::fs::remove_dir_all(&second);
    }

    #[test]
    fn errors_name_the_file() {
        let dir = temp_dir("read-err");
        let err = read(&dir).unwrap_err();
        assert!(matches!(err, ReadError::Io { .. }), "{err:?}");
        assert!(
            err.to_string().starts_with(&format!("{}: ", dir.display())),
            "{err}"
        );

        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("run.json"), "{\"dut\": 1}").unwrap();
        let err = read(&dir).unwrap_err();
        assert!(matches!(err, ReadError::Json { .. }), "{err:?}");
        assert!(
            err.to_string().contains("run.json: not a harness run.json"),
            "{err}"
        );

        write_all(&sample_run(), &dir, Transcripts::One).unwrap();
        let file = dir.join("transcripts.txt");
        let text = std::fs::read_to_string(&file).unwrap();
        std::fs::write(
            &file,
            text.replace("=== sk550p/bu0620/addressing/coe-p102\n", ""),
        )
        .unwrap();
        let err = read(&dir).unwrap_err();
        assert!(matches!(err, ReadError::NoSection { .. }), "{err:?}");
        assert!(
            err.to_string()
                .contains("names transcript `transcripts.txt#sk550p/bu0620/addressing/coe-p102`"),
            "{err}"
        );
        std::fs::remove_file(&file).unwrap();
        let err = read(&dir).unwrap_err();
        assert!(err.to_string().contains("transcripts.txt"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_transcript_file_of_its_own_reads_back() {
        let dir = temp_dir("read-files");
        let run = sample_run();
        write_all(&run, &dir, Transcripts::Files).unwrap();
        let path = dir.join("run.json");
        let text = std::fs::read_to_string(&path).unwrap().replacen(
            "transcripts.txt#sk550p/bu0620/addressing/coe-p102",
            "transcripts/sk550p/bu0620__addressing__coe-p102.txt",
            1,
        );
        std::fs::write(&path, text).unwrap();
        let back = read(&dir).unwrap();
        assert!(back.cases[1].transcript.is_some());
        assert_eq!(
            transcript::render(&back.cases[1]),
            transcript::render(&run.cases[1])
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_transcript_outside_the_folder_is_refused() {
        let dir = temp_dir("read-escape");
        write_all(&sample_run(), &dir, Transcripts::One).unwrap();
        let path = dir.join("run.json");
        let text = std::fs::read_to_string(&path).unwrap().replacen(
            "transcripts.txt#sk550p/bu0620/addressing/coe-p102",
            "../../etc/passwd",
            1,
        );
        std::fs::write(&path, text).unwrap();
        let err = read(&dir).unwrap_err();
        assert!(matches!(err, ReadError::Escapes { .. }), "{err:?}");
        assert!(err.to_string().contains("`../../etc/passwd`"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
