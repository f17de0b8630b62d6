//! `harness mutants`: the mutation score of the manuals as code.
//!
//! Each mutant ([`proto::nord::mutant`]) changes one datum the manuals state. The command runs,
//! for each, the cases that cite the datum against the embedded simulator and the reference
//! model with the datum changed, and compares their verdicts with an unchanged run: a mutant
//! is killed when a case that passed unchanged does not pass. A survivor is a datum the suites
//! would let be wrong.
//!
//! The cases that cite a datum: those naming a statement of its manual section in the
//! inventories (`cases:`), those whose own reference is that section (a parent or a
//! subsection counts), and, for a parameter's datum, every case that reads, writes or computes
//! with that parameter. `--all-cases` runs every case instead.
//!
//! A mutant changes process-wide data, so each runs in a child process of this binary
//! (`--child`, hidden), several at once; nothing in the parent or in tests is ever mutated.

use clap::Args as ClapArgs;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use proto::nord::mutant::{self, Mutant};

use crate::buses::BUSES;
use crate::embedded::EmbeddedFactory;
use crate::exit::{EXIT_FAIL, EXIT_PASS};
use crate::outcome::{MutationScore, RunMeta, Verdict};
use crate::runner::{self, RunOptions};
use crate::suite::inventory::{self, Inventory, Status};
use crate::suite::{Action, Case, Loaded};

/// The file `harness mutants` writes in its report folder, and `run` and `coverage` read.
pub(crate) const FILE: &str = "mutants.json";

#[derive(ClapArgs, Debug)]
pub(crate) struct MutantsArgs {
    /// Suites folder.
    #[arg(long)]
    suites: Option<PathBuf>,
    /// Report folder: `mutants.json` goes there, where `harness run` and `harness coverage`
    /// find the score.
    #[arg(long, default_value = "reports")]
    out: PathBuf,
    /// Only mutants whose id contains this text (repeatable; `--list` shows the ids).
    #[arg(long, value_name = "TEXT")]
    only: Vec<String>,
    /// A sample: every Nth mutant of those chosen.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    every: Option<u32>,
    /// Mutants run at once, each in a process of its own (default: the host's cores).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=64))]
    jobs: Option<u32>,
    /// Run every case against each mutant, not only the cases that cite its datum.
    #[arg(long)]
    all_cases: bool,
    /// List the mutants (id, what changes, where the manual states it) and stop.
    #[arg(long)]
    list: bool,
    /// Exit 1 when fewer than PERCENT of the mutants are killed.
    #[arg(long, value_name = "PERCENT", value_parser = clap::value_parser!(u8).range(0..=100))]
    min: Option<u8>,
    /// Seconds one mutant's run may take; a run still going then is stopped and counted killed
    /// (hung).
    #[arg(long, default_value_t = 300)]
    timeout: u64,
    /// Internal: run the cases listed in this file (results beside it) as a child.
    #[arg(long, hide = true, value_name = "CASES")]
    child: Option<PathBuf>,
    /// Internal: the child's mutant (none: the unchanged run).
    #[arg(long, hide = true)]
    mutant: Option<String>,
}

/// What became of one mutant.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "outcome")]
pub(crate) enum Outcome {
    /// These cases (the first few) passed unchanged and did not pass with the mutant.
    Killed { by: Vec<String> },
    /// Every case that passed unchanged still passed.
    Survived,
    /// The child process failed (a panic is a detection too, but says so).
    Crashed { why: String },
    /// The child ran past `--timeout`.
    Hung,
    /// No case cites the datum: nothing ran, so it survives by definition.
    Uncited,
}

impl Outcome {
    fn killed(&self) -> bool {
        matches!(
            self,
            Outcome::Killed { .. } | Outcome::Crashed { .. } | Outcome::Hung
        )
    }
}

/// One mutant's result in `mutants.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct MutantResult {
    id: String,
    what: String,
    source: String,
    /// The manual and section the result is reported under (the source's first citation).
    manual: String,
    section: String,
    /// Cases run.
    cases: usize,
    #[serde(flatten)]
    outcome: Outcome,
}

/// `mutants.json`.
#[derive(Debug, Serialize, Deserialize)]
pub(crate) struct Doc {
    meta: RunMeta,
    /// `citing` (the cases that cite each datum) or `all`.
    selection: String,
    #[serde(flatten)]
    score: MutationScore,
    results: Vec<MutantResult>,
}

/// Reads the score a `harness mutants` run left in `dir`, if any.
pub(crate) fn score_in(dir: &Path) -> Result<Option<MutationScore>, String> {
    let path = dir.join(FILE);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(format!("{}: {e}", path.display())),
    };
    serde_json::from_str::<Doc>(&text)
        .map(|d| Some(d.score))
        .map_err(|e| format!("{}: {e}", path.display()))
}

pub(crate) fn command(a: MutantsArgs) -> Result<i32, String> {
    if let Some(cases) = &a.child {
        return child(cases, a.mutant.as_deref(), a.suites);
    }
    let chosen: Vec<Mutant> = mutant::all()
        .into_iter()
        .filter(|m| a.only.is_empty() || a.only.iter().any(|o| m.id.contains(o.as_str())))
        .enumerate()
        .filter(|(i, _)| a.every.is_none_or(|n| i % n as usize == 0))
        .map(|(_, m)| m)
        .collect();
    if a.list {
        let mut out = std::io::stdout().lock();
        for m in &chosen {
            let _ = writeln!(out, "{}\t{}\t{}", m.id, m.what, m.source);
        }
        return Ok(EXIT_PASS);
    }
    if chosen.is_empty() {
        return Err("no mutant id contains any `--only` text (`--list` shows them)".into());
    }
    let dir = crate::suite::location::suites_or_usage(a.suites)?;
    let loaded =
        crate::suite::load_dir(&dir, &crate::bus::vocabulary(BUSES)).map_err(|e| e.to_string())?;
    if let Some(e) = loaded.errors.first() {
        return Err(e.to_string());
    }
    let inventories = inventory::load(&dir).map_err(|e| e.to_string())?;
    let meta = crate::record::start(&dir, &loaded.digest);
    let work = tempdir()?;
    let every: BTreeSet<String> = loaded.cases.iter().map(|c| c.id.clone()).collect();
    let plans: Vec<(Mutant, BTreeSet<String>)> = chosen
        .into_iter()
        .map(|m| {
            let cases = match a.all_cases {
                true => every.clone(),
                false => citing(&m, &loaded, &inventories),
            };
            (m, cases)
        })
        .collect();
    let baseline_cases: BTreeSet<String> = plans.iter().flat_map(|(_, c)| c.clone()).collect();
    let timeout = Duration::from_secs(a.timeout);
    let baseline = spawn(&work, "baseline", None, &baseline_cases, &dir, timeout)
        .map_err(|e| format!("the unchanged run failed: {e}"))?;
    let jobs = a.jobs.map_or_else(
        || std::thread::available_parallelism().map_or(1, |n| n.get()),
        |j| j as usize,
    );
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::with_capacity(plans.len()));
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some((m, cases)) = plans.get(i) else {
                    break;
                };
                let outcome = judge(&work, i, m, cases, &baseline, &dir, timeout);
                results
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .push((i, outcome));
            });
        }
    });
    let _ = std::fs::remove_dir_all(&work);
    let mut outcomes = results.into_inner().unwrap_or_else(|e| e.into_inner());
    outcomes.sort_by_key(|(i, _)| *i);
    let results: Vec<MutantResult> = outcomes
        .into_iter()
        .map(|(i, outcome)| {
            let (m, cases) = &plans[i];
            let (manual, section) = citations(m.source).into_iter().next().unwrap_or_default();
            MutantResult {
                id: m.id.clone(),
                what: m.what.clone(),
                source: m.source.to_string(),
                manual,
                section,
                cases: cases.len(),
                outcome,
            }
        })
        .collect();
    let killed = results.iter().filter(|r| r.outcome.killed()).count();
    let doc = Doc {
        score: MutationScore {
            mutants: results.len(),
            killed,
            measured: meta.started.clone(),
            sample: a.every.is_some() || !a.only.is_empty(),
        },
        meta,
        selection: if a.all_cases { "all" } else { "citing" }.into(),
        results,
    };
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let path = a.out.join(FILE);
    let json = serde_json::to_string_pretty(&doc).map_err(|e| e.to_string())?;
    std::fs::write(&path, json).map_err(|e| format!("{}: {e}", path.display()))?;
    let _ = std::io::stdout().lock().write_all(text(&doc).as_bytes());
    let below = a
        .min
        .is_some_and(|min| doc.score.percent() < f64::from(min));
    Ok(if below { EXIT_FAIL } else { EXIT_PASS })
}

/// The report: killed per manual and section, then every survivor.
fn text(doc: &Doc) -> String {
    let mut by: BTreeMap<(&str, &str), (usize, usize)> = BTreeMap::new();
    for r in &doc.results {
        let e = by.entry((&r.manual, &r.section)).or_default();
        e.0 += 1;
        e.1 += usize::from(r.outcome.killed());
    }
    let mut s = String::from("manual   section      mutants  killed\n");
    for ((manual, section), (n, k)) in &by {
        s += &format!("{manual:<8} §{section:<11} {n:>7} {k:>7}\n");
    }
    let survivors: Vec<&MutantResult> =
        doc.results.iter().filter(|r| !r.outcome.killed()).collect();
    if !survivors.is_empty() {
        s += &format!(
            "\n{} survivors (no case noticed the change):\n",
            survivors.len()
        );
        for r in survivors {
            let why = match r.outcome {
                Outcome::Uncited => " [no case cites it]",
                _ => "",
            };
            s += &format!("  {}  {} ({}){why}\n", r.id, r.what, r.source);
        }
    }
    s += &format!("\n{}\n", doc.score);
    s
}

/// The cases that cite `m`'s datum (see the module documentation).
fn citing(m: &Mutant, loaded: &Loaded, inventories: &[Inventory]) -> BTreeSet<String> {
    let cited = citations(m.source);
    let cites =
        |doc: &str, section: &str| cited.iter().any(|(d, s)| d == doc && related(s, section));
    let mut out: BTreeSet<String> = inventories
        .iter()
        .flat_map(|inv| inv.statements.iter().map(move |s| (inv, s)))
        .filter(|(inv, s)| cites(&inv.doc, &s.section))
        .flat_map(|(_, s)| match &s.status {
            Status::Asserted(cases) => cases.clone(),
            _ => Vec::new(),
        })
        .collect();
    out.extend(
        loaded
            .cases
            .iter()
            .filter(|c| cites(&c.manual.doc, &c.manual.section) || names(c, m.parameter))
            .map(|c| c.id.clone()),
    );
    out
}

/// Whether a section is the other, or one holds the other.
fn related(a: &str, b: &str) -> bool {
    a == b || a.starts_with(&format!("{b}.")) || b.starts_with(&format!("{a}."))
}

/// Whether a case reads, writes or computes with the parameter.
fn names(case: &Case, parameter: Option<u16>) -> bool {
    let Some(p) = parameter else {
        return false;
    };
    case.steps.iter().any(|s| match &s.action {
        Action::Read(o) | Action::Write(o) => o.number.get() == p,
        Action::Compute { args, .. } => {
            args.get("param").and_then(|v| v.as_u64()) == Some(p.into())
        }
        _ => false,
    })
}

/// The manual sections a source cites: "BU 0620 §2.5.6.4 …; BU 2100 §7.1" → (BU 0620,
/// 2.5.6.4), (BU 2100, 7.1).
fn citations(source: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut rest = source;
    while let Some(at) = rest.find("BU ") {
        rest = &rest[at + 3..];
        let doc: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let after = rest[doc.len()..].trim_start();
        if let (4, Some(sec)) = (doc.len(), after.strip_prefix('§')) {
            let section: String = sec
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            let section = section.trim_end_matches('.');
            if !section.is_empty() {
                out.push((format!("BU {doc}"), section.to_string()));
            }
        }
    }
    out
}

/// Runs one mutant and compares its verdicts with the unchanged run's.
fn judge(
    work: &Path,
    i: usize,
    m: &Mutant,
    cases: &BTreeSet<String>,
    baseline: &BTreeMap<(String, String), Verdict>,
    dir: &Path,
    timeout: Duration,
) -> Outcome {
    if cases.is_empty() {
        return Outcome::Uncited;
    }
    match spawn(work, &i.to_string(), Some(&m.id), cases, dir, timeout) {
        Err(Spawn::Hung) => Outcome::Hung,
        Err(e) => Outcome::Crashed { why: e.to_string() },
        Ok(verdicts) => {
            let by: Vec<String> = verdicts
                .iter()
                .filter(|(k, v)| **v != Verdict::Pass && baseline.get(*k) == Some(&Verdict::Pass))
                .map(|((id, profile), v)| format!("{id} [{profile}]: {v:?}"))
                .take(3)
                .collect();
            match by.is_empty() {
                true => Outcome::Survived,
                false => Outcome::Killed { by },
            }
        }
    }
}

/// Why a child gave no verdicts.
#[derive(Debug, thiserror::Error)]
enum Spawn {
    #[error("ran past the time-out")]
    Hung,
    #[error("{0}")]
    Failed(String),
}

/// Runs `cases` in a child process with `mutant` installed; its verdicts by (case, profile).
fn spawn(
    work: &Path,
    name: &str,
    mutant: Option<&str>,
    cases: &BTreeSet<String>,
    dir: &Path,
    timeout: Duration,
) -> Result<BTreeMap<(String, String), Verdict>, Spawn> {
    let failed = |e: String| Spawn::Failed(e);
    let list = work.join(format!("{name}.cases"));
    let ids: Vec<&str> = cases.iter().map(String::as_str).collect();
    std::fs::write(&list, ids.join("\n")).map_err(|e| failed(e.to_string()))?;
    let exe = std::env::current_exe().map_err(|e| failed(e.to_string()))?;
    let mut cmd = Command::new(exe);
    cmd.arg("mutants")
        .arg("--suites")
        .arg(dir)
        .arg("--child")
        .arg(&list);
    if let Some(m) = mutant {
        cmd.arg("--mutant").arg(m);
    }
    // A file, not a pipe: a child that writes much (a panic's backtrace) never blocks on it.
    let log = work.join(format!("{name}.stderr"));
    let stderr = std::fs::File::create(&log).map_err(|e| failed(e.to_string()))?;
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(stderr)
        .spawn()
        .map_err(|e| failed(e.to_string()))?;
    let deadline = Instant::now() + timeout;
    let status = loop {
        match child.try_wait().map_err(|e| failed(e.to_string()))? {
            Some(status) => break status,
            None if Instant::now() >= deadline => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(Spawn::Hung);
            }
            None => std::thread::sleep(Duration::from_millis(10)),
        }
    };
    if !status.success() {
        let stderr = std::fs::read_to_string(&log).unwrap_or_default();
        let last = stderr.lines().last().unwrap_or("").to_string();
        return Err(failed(format!("exit {status}: {last}")));
    }
    let text = std::fs::read_to_string(list.with_extension("verdicts"))
        .map_err(|e| failed(e.to_string()))?;
    text.lines()
        .map(|l| {
            let mut f = l.splitn(3, '\t');
            let (id, profile, v) = (f.next(), f.next(), f.next());
            let v: Verdict = serde_json::from_str(&format!("\"{}\"", v.unwrap_or("")))
                .map_err(|e| failed(format!("verdict line `{l}`: {e}")))?;
            Ok(((id.unwrap_or("").into(), profile.unwrap_or("").into()), v))
        })
        .collect()
}

/// The child: installs the mutant, runs the listed cases under every built-in profile on the
/// embedded simulator, and writes one `case \t profile \t verdict` line per case-run beside
/// the list.
fn child(list: &Path, mutant: Option<&str>, suites: Option<PathBuf>) -> Result<i32, String> {
    if let Some(id) = mutant {
        mutant::install(id).map_err(|e| e.to_string())?;
    }
    let text = std::fs::read_to_string(list).map_err(|e| format!("{}: {e}", list.display()))?;
    let only: BTreeSet<String> = text.lines().map(str::to_string).collect();
    let dir = crate::suite::location::suites_or_usage(suites)?;
    let loaded =
        crate::suite::load_dir(&dir, &crate::bus::vocabulary(BUSES)).map_err(|e| e.to_string())?;
    if let Some(e) = loaded.errors.first() {
        return Err(e.to_string());
    }
    crate::binding::simulator::sim_firmware()?;
    let opts = RunOptions {
        only: Some(only),
        ..RunOptions::new(crate::bus::catalog(BUSES).all())
    };
    let mut factory = EmbeddedFactory::new(BUSES);
    let run = runner::run(&loaded, &opts, &mut factory);
    let mut out = String::new();
    for c in &run.cases {
        let v = serde_json::to_string(&c.verdict).map_err(|e| e.to_string())?;
        out += &format!("{}\t{}\t{}\n", c.id, c.profile, v.trim_matches('"'));
    }
    let path = list.with_extension("verdicts");
    std::fs::write(&path, out).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(EXIT_PASS)
}

/// A fresh folder for the children's case lists and verdicts.
fn tempdir() -> Result<PathBuf, String> {
    let dir = std::env::temp_dir().join(format!("harness-mutants-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    Ok(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn citations_read_every_manual_section_of_a_source() {
        assert_eq!(
            citations("BU 2200 §8.4 and BU 2100 §8.3 bus interface errors (P170)"),
            vec![
                ("BU 2200".to_string(), "8.4".to_string()),
                ("BU 2100".to_string(), "8.3".to_string())
            ]
        );
        assert_eq!(
            citations("BU 0620 §2.5.6.4 (P102 set 2); range assumed from BU 0600"),
            vec![("BU 0620".to_string(), "2.5.6.4".to_string())]
        );
        assert_eq!(
            citations("BU 0590 §5.1.2: factory 255"),
            vec![("BU 0590".into(), "5.1.2".into())]
        );
    }

    #[test]
    fn a_parent_or_a_subsection_is_related_a_sibling_is_not() {
        assert!(related("5.5.1", "5.5.1.2"));
        assert!(related("5.5.1.2", "5.5"));
        assert!(related("5.3", "5.3"));
        assert!(!related("5.3", "5.31"));
        assert!(!related("5.3", "5.4"));
    }

    #[test]
    fn hung_and_crashed_count_as_killed_uncited_does_not() {
        assert!(Outcome::Hung.killed());
        assert!(Outcome::Crashed { why: String::new() }.killed());
        assert!(!Outcome::Uncited.killed());
        assert!(!Outcome::Survived.killed());
    }
}
