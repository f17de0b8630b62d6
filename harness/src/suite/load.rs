//! Loading a suites folder: every `*.yaml` below it, each checked in full.
//!
//! A file that does not load is reported with its path, line and what is wrong, and the run
//! goes on with the files that did: a broken suite is never skipped silently.

use sha2::{Digest, Sha256};
use std::collections::HashSet;
use std::fmt;
use std::path::{Path, PathBuf};

use super::case::{case_head, step, Case};
use super::schema::FileDoc;
use super::Vocabulary;
use crate::outcome::{Erratum, ErratumCheck};

/// What a suites folder held.
#[derive(Debug, Default)]
pub(crate) struct Loaded {
    /// Valid cases, in file order (files sorted by path).
    pub(crate) cases: Vec<Case>,
    /// Errata recorded by the loaded cases.
    pub(crate) errata: Vec<Erratum>,
    /// Files (or cases) that failed to load.
    pub(crate) errors: Vec<LoadError>,
    /// Files read.
    pub(crate) files: usize,
    /// SHA-256 of every file's path (relative to the folder) and text, in load order: the
    /// suites' content, for the run's record when they are not a clean git checkout.
    pub(crate) digest: String,
}

/// A suite problem, placed in its file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct LoadError {
    pub(crate) file: PathBuf,
    /// 1-based line, when known.
    pub(crate) line: Option<u64>,
    pub(crate) message: String,
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{l}: {}", self.file.display(), self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

fn yaml_files(dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir)? {
        let path = entry?.path();
        if path.is_dir() {
            yaml_files(&path, out)?;
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e.eq_ignore_ascii_case("yaml") || e.eq_ignore_ascii_case("yml"))
        {
            out.push(path);
        }
    }
    Ok(())
}

/// Where a suite file runs: by path, except that a folder's `bad-input` file runs after the
/// folder's others. Malformed input is what most often takes a device down (p-net's IO device
/// crashed on one, docs/interop.md), and the cases after a device's departure are not judged:
/// its conformance is judged first, its robustness last.
fn run_order(a: &PathBuf, b: &PathBuf) -> std::cmp::Ordering {
    let key = |f: &PathBuf| {
        let bad_input = f.file_stem().is_some_and(|s| s == "bad-input");
        (f.parent().map(Path::to_path_buf), bad_input, f.clone())
    };
    key(a).cmp(&key(b))
}

/// Loads every suite file below `dir`. Only an unreadable folder is an `Err`.
pub(crate) fn load_dir(dir: &Path, vocabulary: &Vocabulary) -> Result<Loaded, LoadError> {
    let mut files = Vec::new();
    yaml_files(dir, &mut files).map_err(|e| LoadError {
        file: dir.to_path_buf(),
        line: None,
        message: format!("cannot read the suites folder: {e}"),
    })?;
    // The statement inventories are no suites (`suite::inventory` reads them).
    let inventories = dir.join(super::inventory::DIR);
    files.retain(|f| !f.starts_with(&inventories));
    files.sort_by(run_order);
    let mut loaded = Loaded {
        files: files.len(),
        ..Loaded::default()
    };
    let mut ids = HashSet::new();
    let mut digest = Sha256::new();
    let mut texts = Vec::new();
    for file in files {
        let rel = file.strip_prefix(dir).unwrap_or(&file).with_extension("");
        let prefix = rel.to_string_lossy().replace('\\', "/");
        match std::fs::read_to_string(&file) {
            Ok(text) => {
                for part in [prefix.as_bytes(), b"\0", text.as_bytes(), b"\0"] {
                    digest.update(part);
                }
                texts.push((file, prefix, text));
            }
            Err(e) => loaded.errors.push(LoadError {
                file: file.clone(),
                line: None,
                message: format!("cannot read: {e}"),
            }),
        }
    }
    for ((file, prefix, _), doc) in texts.iter().zip(parse_all(&texts)) {
        load_doc(vocabulary, file, prefix, doc, &mut ids, &mut loaded);
    }
    loaded.digest = digest
        .finalize()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    Ok(loaded)
}

/// The files' YAML parsed on as many threads as the host has cores, in the files' order:
/// parsing is most of the loading, and every run pays it.
fn parse_all(texts: &[(PathBuf, String, String)]) -> Vec<Parsed> {
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    let chunk = texts.len().div_ceil(threads).max(1);
    std::thread::scope(|s| {
        let jobs: Vec<_> = texts
            .chunks(chunk)
            .map(|part| s.spawn(|| part.iter().map(|(_, _, text)| parse(text)).collect()))
            .collect();
        jobs.into_iter()
            .flat_map(|j: std::thread::ScopedJoinHandle<'_, Vec<Parsed>>| {
                j.join().unwrap_or_else(|p| std::panic::resume_unwind(p))
            })
            .collect()
    })
}

/// A file's document, or the line and first line of the message where its YAML is wrong.
type Parsed = Result<FileDoc, (Option<u64>, String)>;

fn parse(text: &str) -> Parsed {
    serde_saphyr::from_str(text).map_err(|e| {
        let line = e.location().map(|l| l.line());
        let message = e
            .to_string()
            .lines()
            .next()
            .unwrap_or("invalid YAML")
            .to_string();
        (line, message)
    })
}

/// Loads one file's text. Cases with errors are dropped and reported; the others load.
pub(crate) fn load_text(
    vocabulary: &Vocabulary,
    file: &Path,
    prefix: &str,
    text: &str,
    ids: &mut HashSet<String>,
    loaded: &mut Loaded,
) {
    load_doc(vocabulary, file, prefix, parse(text), ids, loaded);
}

/// Loads one file's parsed document.
fn load_doc(
    vocabulary: &Vocabulary,
    file: &Path,
    prefix: &str,
    doc: Parsed,
    ids: &mut HashSet<String>,
    loaded: &mut Loaded,
) {
    let err = |line: Option<u64>, message: String| LoadError {
        file: file.to_path_buf(),
        line,
        message,
    };
    let doc = match doc {
        Ok(d) => d,
        Err((line, message)) => {
            loaded.errors.push(err(line, message));
            return;
        }
    };
    if doc.cases.is_empty() {
        loaded
            .errors
            .push(err(None, "the file has no cases".into()));
    }
    for spanned in doc.cases {
        let line = Some(spanned.defined.line());
        let case_doc = spanned.value;
        let id = format!("{prefix}/{}", case_doc.id);
        if !ids.insert(id.clone()) {
            loaded
                .errors
                .push(err(line, format!("duplicate case id `{}`", case_doc.id)));
            continue;
        }
        let mut case = match case_head(vocabulary, id, &case_doc, &doc.doc, &doc.edition) {
            Ok(c) => c,
            Err(m) => {
                loaded
                    .errors
                    .push(err(line, format!("case `{}`: {m}", case_doc.id)));
                continue;
            }
        };
        if case_doc.steps.is_empty() {
            loaded
                .errors
                .push(err(line, format!("case `{}` has no steps", case_doc.id)));
            continue;
        }
        let mut ok = true;
        for (i, s) in case_doc.steps.into_iter().enumerate() {
            let step_line = Some(s.defined.line());
            match step(vocabulary, s.value) {
                Ok(st) => case.steps.push(st),
                Err(m) => {
                    loaded.errors.push(err(
                        step_line,
                        format!("case `{}`, step {}: {m}", case_doc.id, i + 1),
                    ));
                    ok = false;
                }
            }
        }
        if !ok {
            continue;
        }
        for e in case_doc.manual_says.into_vec() {
            if e.check == ErratumCheck::Standard && e.standard.is_none() {
                loaded.errors.push(err(
                    line,
                    format!(
                        "case `{}`: an erratum found against a standard names its clause (`standard:`)",
                        case_doc.id
                    ),
                ));
                ok = false;
            }
            case.errata.push(Erratum {
                doc: case.manual.doc.clone(),
                edition: case.manual.edition.clone(),
                section: case.manual.section.clone(),
                page: case.manual.page,
                case: case.id.clone(),
                printed: e.printed,
                correct: e.correct,
                why: e.why,
                ambiguous: e.ambiguous,
                check: e.check,
                standard: e.standard,
            });
        }
        if !ok {
            continue;
        }
        loaded.errata.extend(case.errata.iter().cloned());
        loaded.cases.push(case);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Loaded {
        let mut loaded = Loaded::default();
        load_text(
            &crate::buses::vocabulary(),
            Path::new("t.yaml"),
            "x/t",
            text,
            &mut HashSet::new(),
            &mut loaded,
        );
        loaded
    }

    const GOOD: &str = r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: coe-p102
    title: P102 of FI 3 is 3066h
    ref: { section: "2.2.7", page: 20 }
    manual_says: { printed: "a", correct: "b", why: "c", check: own-text }
    steps:
      - wait: 10ms
        expect: { status: xx31h }
"#;

    #[test]
    fn a_folders_bad_input_runs_after_its_other_files() {
        let mut files: Vec<PathBuf> = [
            "s/pnio/records.yaml",
            "s/pnio/bad-input.yaml",
            "s/ecat/al.yaml",
            "s/pnio/alarms.yaml",
        ]
        .map(PathBuf::from)
        .to_vec();
        files.sort_by(run_order);
        let names: Vec<_> = files
            .iter()
            .map(|f| f.to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            names,
            [
                "s/ecat/al.yaml",
                "s/pnio/alarms.yaml",
                "s/pnio/records.yaml",
                "s/pnio/bad-input.yaml"
            ]
        );
    }

    #[test]
    fn a_good_file_loads_with_its_errata() {
        let l = load(GOOD);
        assert!(l.errors.is_empty(), "{:?}", l.errors);
        assert_eq!(l.cases.len(), 1);
        assert_eq!(l.cases[0].id, "x/t/coe-p102");
        assert_eq!(l.cases[0].manual.edition, "2020-03 en");
        assert_eq!(l.errata[0].printed, "a");
        assert_eq!(l.cases[0].manual.quote, None);
    }

    #[test]
    fn an_erratum_found_against_a_standard_names_its_clause() {
        let bare = load(&GOOD.replace("check: own-text", "check: standard"));
        assert!(bare.cases.is_empty());
        assert!(
            bare.errors[0].message.contains("names its clause"),
            "{:?}",
            bare.errors
        );
        let named = load(&GOOD.replace(
            "check: own-text",
            r#"check: standard, standard: "CiA 301 4.2.0 §7.2.4.3.17""#,
        ));
        assert!(named.errors.is_empty(), "{:?}", named.errors);
        assert_eq!(
            named.errata[0].found_by(),
            "standard: CiA 301 4.2.0 §7.2.4.3.17"
        );
        let unknown = load(&GOOD.replace("check: own-text", "check: hunch"));
        assert!(unknown.cases.is_empty(), "an unknown check is refused");
        let missing = load(&GOOD.replace(", check: own-text", ""));
        assert!(
            missing.cases.is_empty(),
            "every erratum says how it was found"
        );
    }

    #[test]
    fn a_quoted_requirement_is_kept_for_the_reports() {
        let l = load(&GOOD.replace(r#"page: 20 }"#, r#"page: 20, quote: "P102 … 3066h" }"#));
        assert!(l.errors.is_empty(), "{:?}", l.errors);
        assert_eq!(l.cases[0].manual.quote.as_deref(), Some("P102 … 3066h"));
    }

    #[test]
    fn unknown_key_names_file_line_and_key() {
        let l = load(&GOOD.replace("title:", "titel:"));
        assert_eq!(l.cases.len(), 0);
        let e = l.errors[0].to_string();
        assert!(e.starts_with("t.yaml:"), "{e}");
        assert!(e.contains("titel"), "{e}");
        assert!(l.errors[0].line.is_some());
    }

    #[test]
    fn bad_step_is_placed_on_its_line() {
        let l = load(&GOOD.replace("wait: 10ms", "wait: 10 parsecs"));
        assert_eq!(l.errors.len(), 1);
        assert_eq!(l.errors[0].line, Some(10));
        assert!(l.errors[0].message.contains("step 1"), "{}", l.errors[0]);
    }

    #[test]
    fn two_actions_in_one_step_are_refused() {
        let l = load(&GOOD.replace("wait: 10ms", "wait: 10ms\n        read: { param: 102 }"));
        assert!(
            l.errors[0].message.contains("exactly one action"),
            "{}",
            l.errors[0]
        );
    }

    #[test]
    fn out_of_range_values_are_refused_at_load() {
        let l = load(&GOOD.replace("wait: 10ms", "read: { param: 1000, inverter: 9 }"));
        assert!(
            l.errors[0].message.contains("out of range"),
            "{}",
            l.errors[0]
        );
    }

    #[test]
    fn a_profile_where_a_product_belongs_is_refused_with_the_fix() {
        // `profiles:` takes products; a profile name once panicked the loader.
        let l = load(&GOOD.replace("    steps:", "    profiles: [sk550p@can]\n    steps:"));
        assert_eq!(l.cases.len(), 0);
        let e = &l.errors[0].message;
        assert!(e.contains("give `sk550p` and `requires: [can]`"), "{e}");
    }

    #[test]
    fn duplicate_ids_are_refused() {
        let twice = GOOD.to_string() + &GOOD[GOOD.find("  - id").unwrap()..];
        let l = load(&twice);
        assert_eq!(l.cases.len(), 1);
        assert!(l.errors[0].message.contains("duplicate"));
    }
}
