//! Commands over finished report folders: `harness diff OLD NEW` (what changed between two
//! runs, e.g. two firmware releases) and `harness merge` (the shards of a `--shard K/N` run
//! joined into the unsharded run's reports); and over the suites' statement inventories:
//! `harness coverage`.

use clap::Args;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::exit::{verdict_exit, EXIT_FAIL, EXIT_PASS};
use crate::report;

#[derive(Args, Debug)]
pub(crate) struct DiffArgs {
    /// The old run: a report folder, or its `run.json` with the transcripts beside it.
    old: PathBuf,
    /// The new run, the same way.
    new: PathBuf,
    /// Also write `diff.md` and `diff.html` (one self-contained file) into this folder.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Exit 1 only for a regression (passed in OLD; fails, errs or is inconclusive in NEW),
    /// not for a new fail or error of a case that did not pass before or is new.
    #[arg(long)]
    regressions_only: bool,
}

/// Prints (and writes) the comparison; exit 1 when a case regressed (passed in OLD, fails,
/// errs or is inconclusive in NEW) or, unless `--regressions-only`, when NEW has a fail or an
/// error OLD did not have (a new case, not applicable → fail, inconclusive → error); 0
/// otherwise. The last lines name the cases that decided.
pub(crate) fn diff(a: DiffArgs) -> Result<i32, String> {
    let old = report::read(&a.old).map_err(|e| e.to_string())?;
    let new = report::read(&a.new).map_err(|e| e.to_string())?;
    let d = report::compare_runs(
        crate::buses::BUSES,
        &a.old.display().to_string(),
        &old,
        &a.new.display().to_string(),
        &new,
    );
    let (gate, rule) = if a.regressions_only {
        (report::Gate::RegressionsOnly, "regressions only")
    } else {
        (
            report::Gate::NewFailures,
            "regressions and new fails or errors",
        )
    };
    let gated = d.gated(gate);
    let mut out = std::io::stdout().lock();
    // A closed pipe (`| head`) ends the output, not the program.
    let _ = out.write_all(report::diff_text(&d).as_bytes());
    let _ = writeln!(out, "\ngate ({rule}): {} case(s)", gated.len());
    for g in &gated {
        let _ = writeln!(out, "  {g}");
    }
    if let Some(dir) = &a.out {
        let [md, html] = report::write_diff(&d, dir).map_err(|e| e.to_string())?;
        let _ = writeln!(out, "\ndiff: {}, {}", md.display(), html.display());
    }
    Ok(if gated.is_empty() {
        EXIT_PASS
    } else {
        EXIT_FAIL
    })
}

#[derive(Args, Debug)]
pub(crate) struct MergeArgs {
    /// The shards' report folders (or their `run.json` files), one per `--shard K/N`.
    #[arg(required = true)]
    shards: Vec<PathBuf>,
    /// Report folder for the merged run (not one of the shards').
    #[arg(long, default_value = "reports")]
    out: PathBuf,
    /// Transcripts: `one` file, or also `files`, one per case (as `harness run`).
    #[arg(long, value_enum, default_value_t)]
    transcripts: report::Transcripts,
}

/// The folder a report lives in, for telling two spellings of one folder apart.
fn folder(given: &Path) -> PathBuf {
    let json = report::run_json(given);
    let dir = json.parent().unwrap_or(Path::new("."));
    std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf())
}

/// Reads every shard, merges them and writes the reports as `harness run` does; the exit code
/// is the unsharded run's.
pub(crate) fn merge(a: MergeArgs) -> Result<i32, String> {
    let out = folder(&a.out.join("run.json"));
    let mut shards = Vec::with_capacity(a.shards.len());
    for s in &a.shards {
        if folder(s) == out {
            return Err(format!(
                "`--out {}` is one of the shards' folders: merge into another",
                a.out.display()
            ));
        }
        let run = report::read(s).map_err(|e| e.to_string())?;
        shards.push((s.display().to_string(), run));
    }
    let run = report::merge(shards).map_err(|e| e.to_string())?;
    let written = report::write_all(&run, &a.out, a.transcripts).map_err(|e| e.to_string())?;
    let mut stdout = std::io::stdout().lock();
    let _ = write!(stdout, "{}", report::terminal(&run));
    let _ = writeln!(stdout, "{written}");
    Ok(verdict_exit(&run))
}

#[derive(Args, Debug)]
pub(crate) struct CoverageArgs {
    /// Suites folder (its `inventory/` holds the statement inventories).
    #[arg(long)]
    suites: Option<PathBuf>,
    /// Also a problem: a section whose share of testable statements asserted by any case (on
    /// the device or by the model) is below PERCENT (the release gate is 90); a section with
    /// nothing testable has no share and passes.
    #[arg(long, value_name = "PERCENT", value_parser = clap::value_parser!(u8).range(0..=100))]
    min: Option<u8>,
    /// The report folder whose `mutants.json` (`harness mutants --out`) gives the mutation
    /// score of the manuals as code.
    #[arg(long, default_value = "reports")]
    reports: PathBuf,
}

/// Prints the statements per manual and section (statements, asserted on the device, by
/// reference-model cases only, pending, untestable, open; the shares of the testable asserted
/// on the device and by any case, `—` where nothing is testable), each manual's sections (in
/// its table of contents, with statements, with nothing testable), the errata per manual by the
/// check that found them, then
/// what keeps the inventories honest: a case id that no
/// suite has, a case of an inventoried manual that no statement names, an asserted count below
/// its floor. Exit 1 when any of those, 2 when an inventory or suite does not load.
pub(crate) fn coverage(a: CoverageArgs) -> Result<i32, String> {
    use crate::suite::inventory;
    let dir = crate::suite::location::suites_dir(a.suites);
    let vocabulary = crate::bus::vocabulary(crate::buses::BUSES);
    let loaded = crate::suite::load_dir(&dir, &vocabulary).map_err(|e| e.to_string())?;
    if let Some(e) = loaded.errors.first() {
        return Err(e.to_string());
    }
    let inventories = inventory::load(&dir).map_err(|e| e.to_string())?;
    if inventories.is_empty() {
        return Err(format!(
            "no statement inventory in {}",
            dir.join(inventory::DIR).display()
        ));
    }
    let floors = inventory::floors(&dir).map_err(|e| e.to_string())?;
    let mut out = std::io::stdout().lock();
    let sections = inventory::coverage(&inventories, &loaded);
    let _ = out.write_all(report::statements_table(&sections).as_bytes());
    let _ = writeln!(out);
    let _ = out.write_all(report::sections_text(&inventory::sections(&inventories)).as_bytes());
    let _ = writeln!(out);
    let _ = out.write_all(report::errata_table(&loaded.errata).as_bytes());
    let _ = writeln!(out);
    let _ = match crate::mutants::score_in(&a.reports)? {
        Some(m) => writeln!(
            out,
            "{m} ({})",
            a.reports.join(crate::mutants::FILE).display()
        ),
        None => writeln!(
            out,
            "mutation score: not measured (`harness mutants --out {}` measures it)",
            a.reports.display()
        ),
    };
    let mut problems = inventory::check(&inventories, &loaded, &floors);
    if let Some(min) = a.min {
        problems.extend(
            sections
                .iter()
                .filter_map(|s| Some((s, s.percent().filter(|p| *p < f64::from(min))?)))
                .map(|(s, p)| {
                    format!(
                        "{} {} §{}: {} of {} testable statements asserted ({p:.0} %; {} on the device), below {min} %",
                        s.doc,
                        s.edition,
                        s.section,
                        s.asserted + s.model_only,
                        s.testable(),
                        s.asserted,
                    )
                }),
        );
    }
    for p in &problems {
        let _ = writeln!(out, "PROBLEM {p}");
    }
    Ok(if problems.is_empty() {
        EXIT_PASS
    } else {
        EXIT_FAIL
    })
}
