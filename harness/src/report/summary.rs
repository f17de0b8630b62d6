//! The human summary (`summary.md` and the console lines): whether motion was allowed, the run's
//! record, load errors, verdict counts per profile (device and model cases apart), coverage by
//! manual section, the manuals' errata, and the cases that did not pass.

use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write;

use super::markup::count;
use super::record;
use crate::outcome::{CaseKind, CaseResult, RunResult, Verdict};

/// Cases per verdict, every verdict present (zero included); serializes as `{"pass": n, …}`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub(super) struct Counts(BTreeMap<Verdict, usize>);

impl Counts {
    /// Counts the verdicts of `cases`.
    pub(super) fn of<'a>(cases: impl IntoIterator<Item = &'a CaseResult>) -> Self {
        let mut m: BTreeMap<Verdict, usize> = Verdict::ALL.iter().map(|v| (*v, 0)).collect();
        for c in cases {
            *m.entry(c.verdict).or_default() += 1;
        }
        Counts(m)
    }

    /// How many cases ended with `v`.
    pub(super) fn get(&self, v: Verdict) -> usize {
        self.0.get(&v).copied().unwrap_or(0)
    }

    /// Counts the verdicts of the cases of one kind and, given one, one profile.
    pub(super) fn of_kind(run: &RunResult, kind: CaseKind, profile: Option<&str>) -> Self {
        Counts::of(
            run.cases
                .iter()
                .filter(|c| c.kind == kind && profile.is_none_or(|p| c.profile == p)),
        )
    }

    /// Counts the verdicts of the cases of one kind per profile, in [`profiles`]' order, in one
    /// pass over the run (a pass per profile was a few per cent of a default run).
    pub(super) fn per_profile(run: &RunResult, kind: CaseKind) -> Vec<(&str, Counts)> {
        let names = profiles(run);
        let mut counts: Vec<Counts> = names.iter().map(|_| Counts::of([])).collect();
        let mut at = 0;
        for c in run.cases.iter().filter(|c| c.kind == kind) {
            if names[at] != c.profile {
                at = names.iter().position(|p| *p == c.profile).unwrap_or(at);
            }
            *counts[at].0.entry(c.verdict).or_default() += 1;
        }
        names.into_iter().zip(counts).collect()
    }

    pub(super) fn total(&self) -> usize {
        self.0.values().sum()
    }

    /// Table cells in [`Verdict::ALL`] order: `1 | 0 | …`.
    fn cells(&self) -> String {
        Verdict::ALL
            .iter()
            .map(|v| self.get(*v).to_string())
            .collect::<Vec<_>>()
            .join(" | ")
    }
}

/// The run's profiles in order, followed by any profile a case ran under that the run does not
/// list (so no case is left out of a per-profile report).
pub(super) fn profiles(run: &RunResult) -> Vec<&str> {
    let mut out: Vec<&str> = run.profiles.iter().map(String::as_str).collect();
    let mut last = None;
    // A profile's cases come together: only a change of profile is looked up.
    for c in &run.cases {
        if last != Some(c.profile.as_str()) && !out.contains(&c.profile.as_str()) {
            out.push(&c.profile);
        }
        last = Some(c.profile.as_str());
    }
    out
}

/// Sort key for section numbers: numerically per level, so `2.2.7` sorts before `2.10`; a
/// non-numeric level (`A`) sorts after the numbers, by text.
pub(super) fn section_key(s: &str) -> Vec<(u64, &str)> {
    s.split('.')
        .map(|p| p.parse().map_or((u64::MAX, p), |n| (n, "")))
        .collect()
}

/// A Markdown table cell: no `|` or line break may end the cell early.
fn cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

/// `## Verdicts per profile`, `## Coverage by manual section` and the header row they share.
const VERDICT_HEADER: &str = "pass | fail | inconclusive | error | not applicable |";

/// One section of one manual's edition: `(doc, edition, sort key, section)`.
pub(super) type SectionKey<'a> = (&'a str, &'a str, Vec<(u64, &'a str)>, &'a str);

/// A section's verdict counts.
pub(super) struct SectionCases {
    /// Device cases.
    pub(super) device: Counts,
    /// Reference-model cases.
    pub(super) model: Counts,
    /// Device and model cases together.
    pub(super) all: Counts,
}

/// The run's cases by manual, edition and section, sections in numeric order.
pub(super) fn by_section(run: &RunResult) -> BTreeMap<SectionKey<'_>, SectionCases> {
    // Grouped by the text first: a numeric key per case was a default run's most compared one.
    let mut by: std::collections::HashMap<(&str, &str, &str), Vec<&CaseResult>> =
        std::collections::HashMap::new();
    for c in &run.cases {
        let m = &c.manual;
        let key = (m.doc.as_str(), m.edition.as_str(), m.section.as_str());
        by.entry(key).or_default().push(c);
    }
    by.into_iter()
        .map(|((doc, edition, section), cases)| {
            let all = Counts::of(cases.iter().copied());
            let (model, device): (Vec<&CaseResult>, Vec<&CaseResult>) =
                cases.into_iter().partition(|c| c.kind == CaseKind::Model);
            let counts = SectionCases {
                device: Counts::of(device),
                model: Counts::of(model),
                all,
            };
            ((doc, edition, section_key(section), section), counts)
        })
        .collect()
}

fn coverage(s: &mut String, run: &RunResult) {
    let _ = writeln!(
        s,
        "\n## Coverage by manual section\n\nDevice cases per verdict; `model` counts the reference-model checks (passed/all).\n\n| doc | edition | section | cases | {VERDICT_HEADER} model |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|"
    );
    for ((doc, edition, _, section), cases) in by_section(run) {
        let (n, m) = (cases.device, cases.model);
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} |",
            cell(doc),
            cell(edition),
            cell(section),
            n.total(),
            n.cells(),
            model_cell(&m)
        );
    }
}

/// `## Fails by clause`: the device's failing cases grouped by the clause each cites — the
/// standard's for a protocol case, the manual's for NORD's — clauses in numeric order: what an
/// implementer has to fix, rule by rule.
fn fails_by_clause(s: &mut String, run: &RunResult) {
    let mut by: BTreeMap<(&str, Vec<(u64, &str)>, &str), Vec<&CaseResult>> = BTreeMap::new();
    for c in run
        .cases
        .iter()
        .filter(|c| c.kind == CaseKind::Device && c.verdict == Verdict::Fail)
    {
        let m = &c.manual;
        by.entry((m.doc.as_str(), section_key(&m.section), m.section.as_str()))
            .or_default()
            .push(c);
    }
    if by.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "\n## Fails by clause\n\nThe device's failing cases under the clause each cites: what to fix, rule by rule.\n\n| doc | clause | fails | cases |\n|---|---|---:|---|"
    );
    for ((doc, _, section), cases) in by {
        let ids: Vec<String> = cases
            .iter()
            .map(|c| format!("`{}` [{}]", c.id.replace('`', "'"), c.profile))
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            cell(doc),
            cell(section),
            cases.len(),
            cell(&ids.join(", "))
        );
    }
}

fn errata(s: &mut String, run: &RunResult) {
    let _ = writeln!(
        s,
        "\n## Errata: what the manuals print, and what the cases test\n"
    );
    if run.errata.is_empty() {
        let _ = writeln!(s, "None recorded.");
        return;
    }
    let mut list: Vec<_> = run.errata.iter().collect();
    list.sort_by(|a, b| {
        (&a.doc, &a.edition, section_key(&a.section), a.page).cmp(&(
            &b.doc,
            &b.edition,
            section_key(&b.section),
            b.page,
        ))
    });
    let _ = writeln!(
        s,
        "| doc | edition | section | page | printed → correct | why | found by | case |\n|---|---|---|---:|---|---|---|---|"
    );
    for e in list {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | `{}` → `{}` | {} | {} | {} |",
            cell(&e.doc),
            cell(&e.edition),
            cell(&e.section),
            e.page.map_or(String::new(), |p| p.to_string()),
            cell(&e.printed),
            cell(&e.correct),
            cell(&e.reason()),
            cell(&e.found_by()),
            cell(&e.case)
        );
    }
}

/// `passed/all` of a section's model cases; empty when it has none.
pub(super) fn model_cell(m: &Counts) -> String {
    if m.total() == 0 {
        String::new()
    } else {
        format!("{}/{}", m.get(Verdict::Pass), m.total())
    }
}

/// One verdict table: a row per profile and a total row, for cases of `kind`.
fn verdict_table(s: &mut String, run: &RunResult, kind: CaseKind) {
    let _ = writeln!(
        s,
        "| profile | {VERDICT_HEADER}\n|---|---:|---:|---:|---:|---:|"
    );
    for (p, n) in Counts::per_profile(run, kind) {
        if kind == CaseKind::Device || n.total() > 0 {
            let _ = writeln!(s, "| {} | {} |", cell(p), n.cells());
        }
    }
    let _ = writeln!(
        s,
        "| **all** | {} |",
        Counts::of_kind(run, kind, None).cells()
    );
}

/// Cases that did not pass and apply: fail, error, inconclusive.
pub(super) fn not_passed(run: &RunResult) -> impl Iterator<Item = &CaseResult> {
    run.cases.iter().filter(|c| {
        matches!(
            c.verdict,
            Verdict::Fail | Verdict::Error | Verdict::Inconclusive
        )
    })
}

/// `summary.md`: the overall verdict, whether motion was allowed, load errors, the cases that
/// did not pass, then the tables (verdicts per profile, not applicable by reason, coverage,
/// errata) and the run's record.
pub(super) fn markdown(run: &RunResult) -> String {
    let mut s = format!(
        "{}\n\n**{}**\n\n# Run summary\n\n",
        super::signoff::markdown_banner(run),
        record::motion_line(run)
    );
    if !run.load_errors.is_empty() {
        let _ = writeln!(
            s,
            "## ⚠ {} suite file(s) did not load: their cases did not run\n",
            run.load_errors.len()
        );
        for e in &run.load_errors {
            let _ = writeln!(s, "- `{}`", e.replace('`', "'"));
        }
        s.push('\n');
    }
    let mut bad = not_passed(run).peekable();
    if bad.peek().is_some() {
        let _ = writeln!(s, "## Failed, errored and inconclusive cases\n");
        for c in bad {
            let model = if c.kind == CaseKind::Model {
                ", model"
            } else {
                ""
            };
            let _ = writeln!(
                s,
                "- **{}** [{}{model}] `{}` ({} {}): {}",
                c.verdict.name(),
                c.profile,
                c.id,
                c.manual.doc,
                c.manual.place(),
                c.message
            );
        }
    }
    fails_by_clause(&mut s, run);
    let _ = writeln!(s, "\n## Verdicts per profile: device cases\n");
    verdict_table(&mut s, run, CaseKind::Device);
    if run.cases.iter().any(|c| c.kind == CaseKind::Model) {
        let _ = writeln!(
            s,
            "\n## {}\n\nThese cases never reach the DUT: their passes are no passes of the device.\n",
            record::group_title(CaseKind::Model)
        );
        verdict_table(&mut s, run, CaseKind::Model);
    }
    super::signoff::markdown_na(&mut s, run);
    coverage(&mut s, run);
    super::statements::markdown(&mut s, &run.statements);
    if let Some(m) = &run.mutation {
        let _ = writeln!(s, "\n{m} (`harness mutants`).");
    }
    super::statements::sections_markdown(&mut s, &run.sections);
    errata(&mut s, run);
    let _ = writeln!(s, "\n## Record\n");
    for (label, value) in record::lines(run) {
        let _ = writeln!(s, "- {label}: {}", value.replace('\n', " "));
    }
    s
}

/// The console lines: load errors, failing and erroring cases, counts per profile, totals.
pub(crate) fn terminal(run: &RunResult) -> String {
    let mut s = String::new();
    for e in &run.load_errors {
        let _ = writeln!(s, "LOAD ERROR {e}");
    }
    for c in failed_or_errored(run) {
        let _ = writeln!(s, "{}", case_line(c));
        // The statement the DUT broke, and where it stands.
        let _ = writeln!(
            s,
            "      rule: {} ({} {})",
            c.title,
            c.manual.doc,
            c.manual.place()
        );
    }
    let width = profiles(run).iter().map(|p| p.len()).max().unwrap_or(0);
    let device = Counts::per_profile(run, CaseKind::Device);
    let model = Counts::per_profile(run, CaseKind::Model);
    for ((p, n), (_, m)) in device.iter().zip(&model) {
        let _ = writeln!(s, "  {p:<width$} {}", counts_line(n, m));
    }
    s.push_str(&totals_line(run));
    s
}

/// Device counts `n`, each followed by the model cases' count `m` of that verdict when there
/// are any: `210 pass (+40 model), 0 fail, …`, so a model check is never read as a pass of the
/// device.
pub(super) fn counts_line(n: &Counts, m: &Counts) -> String {
    Verdict::ALL
        .iter()
        .map(|v| {
            let name = v.name().replace('_', " ");
            match m.get(*v) {
                0 => format!("{} {name}", n.get(*v)),
                k => format!("{} {name} (+{k} model)", n.get(*v)),
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// [`counts_line`] of the whole run.
pub(super) fn run_counts_line(run: &RunResult) -> String {
    counts_line(
        &Counts::of_kind(run, CaseKind::Device, None),
        &Counts::of_kind(run, CaseKind::Model, None),
    )
}

/// The console's last line: `22496 cases under 19 profiles: …; 134 errata recorded; 0 suite
/// files did not load`.
fn totals_line(run: &RunResult) -> String {
    format!(
        "{} under {}: {}; {} recorded; {} did not load\n",
        count(run.cases.len(), "case", "cases"),
        count(run.profiles.len(), "profile", "profiles"),
        run_counts_line(run),
        count(run.errata.len(), "erratum", "errata"),
        count(run.load_errors.len(), "suite file", "suite files"),
    )
}

/// The console with `-q`: a line per suite file that did not load and per failed or errored
/// case, then the totals line.
pub(crate) fn quiet(run: &RunResult) -> String {
    let mut s = String::new();
    for e in &run.load_errors {
        let _ = writeln!(s, "LOAD ERROR {e}");
    }
    for c in failed_or_errored(run) {
        let _ = writeln!(s, "{}", case_line(c));
    }
    s.push_str(&totals_line(run));
    s
}

/// Failed and errored cases, the ones the console names.
fn failed_or_errored(run: &RunResult) -> impl Iterator<Item = &CaseResult> {
    run.cases
        .iter()
        .filter(|c| matches!(c.verdict, Verdict::Fail | Verdict::Error))
}

/// `FAIL  [sk550p] bu0620/addressing/coe-p102: status: expected …`.
fn case_line(c: &CaseResult) -> String {
    let name = c.verdict.name().to_uppercase();
    let model = if c.kind == CaseKind::Model {
        ", model"
    } else {
        ""
    };
    format!("{name:<5} [{}{model}] {}: {}", c.profile, c.id, c.message)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;
    use rstest::rstest;

    #[rstest]
    #[case("2.2.7", "2.10")]
    #[case("2.2", "2.2.7")]
    #[case("2.9", "2.10")]
    #[case("9", "10")]
    #[case("7.1.3", "A.1")]
    fn sections_sort_numerically(#[case] before: &str, #[case] after: &str) {
        assert!(
            section_key(before) < section_key(after),
            "{before} < {after}"
        );
    }

    #[test]
    fn counts_include_every_verdict() {
        let run = sample_run();
        let n = Counts::of_kind(&run, CaseKind::Device, None);
        assert_eq!(Verdict::ALL.map(|v| n.get(v)), [1, 1, 1, 1, 1]);
        assert_eq!(n.cells(), "1 | 1 | 1 | 1 | 1");
        let m = Counts::of_kind(&run, CaseKind::Model, Some("sk550p"));
        assert_eq!(Verdict::ALL.map(|v| m.get(v)), [1, 0, 0, 0, 0]);
        assert_eq!(
            Counts::of_kind(&run, CaseKind::Model, Some("tu3-eip")).total(),
            0
        );
    }

    #[test]
    fn coverage_table_is_sorted_by_doc_then_section() {
        let mut run = sample_run();
        run.cases[0].manual.section = "2.10".into();
        let md = markdown(&run);
        let row = |needle: &str| md.find(needle).unwrap_or_else(|| panic!("{needle}\n{md}"));
        // BU 0620 §2.2.7: one fail (sk550p) and one not applicable (tu3-eip).
        let r227 = row("| BU 0620 | 2020-03 en | 2.2.7 | 2 | 0 | 1 | 0 | 0 | 1 |  |");
        let r2564 = row("| BU 0620 | 2020-03 en | 2.5.6.4 | 1 | 0 | 0 | 0 | 1 | 0 |  |");
        // The model case counts apart: no device case, one model check passed.
        let r261 = row("| BU 0620 | 2020-03 en | 2.6.1 | 0 | 0 | 0 | 0 | 0 | 0 | 1/1 |");
        let r210 = row("| BU 0620 | 2020-03 en | 2.10 | 1 | 1 | 0 | 0 | 0 | 0 |  |");
        let bu2100 = row("| BU 2100 | en | 5.1 | 1 | 0 | 0 | 1 | 0 | 0 |  |");
        assert!(
            r227 < r2564 && r2564 < r261 && r261 < r210 && r210 < bu2100,
            "{md}"
        );
    }

    #[test]
    fn summary_lists_profiles_failures_and_errata() {
        let md = markdown(&sample_run());
        // The overall verdict first, then whether motion was allowed.
        assert!(
            md.starts_with("**FAIL: 1 failed, 1 erred (case-runs, model checks included)** — 1 pass (+1 model), 1 fail, 1 inconclusive, 1 error, 1 not applicable\n\n**Motion not allowed (--allow-motion not given): cases that could turn a motor were not run**\n"),
            "{md}"
        );
        assert!(
            md.contains("- identity sk550p: NORD SK 550P, firmware V1.2 R0"),
            "{md}"
        );
        assert!(
            md.contains("- command line: harness run --filter 'a b'\n"),
            "{md}"
        );
        assert!(md.contains("- suites revision: 0123456789abcdef"), "{md}");
        // Device rows, then the model group with its own rows: the model pass is not in sk550p's
        // device passes.
        let device = md.find("## Verdicts per profile: device cases").unwrap();
        let model = md
            .find("## model (reference checks of the manuals' formulas, no DUT)")
            .unwrap();
        assert!(device < model, "{md}");
        assert!(
            md[device..model].contains("| sk550p | 1 | 1 | 0 | 0 | 0 |"),
            "{md}"
        );
        assert!(
            md[device..model].contains("| **all** | 1 | 1 | 1 | 1 | 1 |"),
            "{md}"
        );
        let model_part = &md[model..md.find("## Not applicable, by reason").unwrap()];
        assert!(
            model_part.contains("| sk550p | 1 | 0 | 0 | 0 | 0 |"),
            "{md}"
        );
        assert!(!model_part.contains("| tu3-eip |"), "{md}");
        assert!(md.contains("| tu3-eip | 0 | 0 | 1 | 1 | 1 |"), "{md}");
        assert!(
            md.contains("| BU 0620 | 2020-03 en | 2.3.5 | 27 | `class 103` → `class 102` | FI 2 is class 102 |"),
            "{md}"
        );
        assert!(
            md.contains("- **fail** [sk550p] `bu0620/addressing/coe-p102` (BU 0620 §2.2.7 p. 20): status: expected 2865"),
            "{md}"
        );
        assert!(!md.contains("did not load"), "{md}");
        // The failures come before the tables, the record last.
        let failed = md
            .find("## Failed, errored and inconclusive cases")
            .unwrap();
        assert!(failed < device, "{md}");
        assert!(
            md.find("## Record").unwrap() > md.find("## Errata").unwrap(),
            "{md}"
        );
        assert!(
            md.contains(
                "| another product | 1 | 0 | the statement is about sk550p, this run is tu3-eip |"
            ),
            "{md}"
        );
        // The one device fail, under the clause it cites.
        assert!(
            md.contains("## Fails by clause\n\nThe device's failing cases under the clause each cites: what to fix, rule by rule.\n\n| doc | clause | fails | cases |\n|---|---|---:|---|\n| BU 0620 | 2.2.7 | 1 | `bu0620/addressing/coe-p102` [sk550p] |\n"),
            "{md}"
        );
    }

    #[test]
    fn load_errors_come_first() {
        let mut run = sample_run();
        run.load_errors = vec!["suites/bu0620/x.yaml:8: unknown step `wait`".into()];
        let md = markdown(&run);
        let err = md.find("x.yaml:8").unwrap();
        assert!(err < md.find("## Verdicts").unwrap(), "{md}");
        assert!(md.contains("1 suite file(s) did not load"), "{md}");
        let t = terminal(&run);
        assert!(t.starts_with("LOAD ERROR suites/bu0620/x.yaml:8"), "{t}");
    }

    #[test]
    fn terminal_is_short_and_counts_per_profile() {
        let t = terminal(&sample_run());
        assert!(
            t.contains("FAIL  [sk550p] bu0620/addressing/coe-p102: status"),
            "{t}"
        );
        assert!(
            t.contains("ERROR [tu3-eip] bu0620/pkw-telegrams/silent"),
            "{t}"
        );
        assert!(
            t.contains(
                "  sk550p  1 pass (+1 model), 1 fail, 0 inconclusive, 0 error, 0 not applicable"
            ),
            "{t}"
        );
        assert!(
            t.contains("  tu3-eip 0 pass, 0 fail, 1 inconclusive, 1 error, 1 not applicable"),
            "{t}"
        );
        assert!(
            t.contains("6 cases under 2 profiles: 1 pass (+1 model), 1 fail"),
            "{t}"
        );
        assert!(t.contains("      rule: "), "{t}");
        // Two lines per failed or errored case, one per profile, one total.
        assert!(t.lines().count() <= 8, "{t}");
        // A failing model check says it is one.
        let mut run = sample_run();
        run.cases[5].verdict = Verdict::Fail;
        run.cases[5].message = "formula".into();
        let t = terminal(&run);
        assert!(
            t.contains("FAIL  [sk550p, model] bu0620/drive-scaling/setpoint: formula"),
            "{t}"
        );
        assert!(t.contains("  sk550p  1 pass, 1 fail (+1 model),"), "{t}");
    }

    #[test]
    fn nouns_agree_with_their_numbers() {
        let mut run = sample_run();
        run.profiles.truncate(1);
        run.cases.truncate(1);
        run.load_errors = vec!["x.yaml:1: bad".into()];
        let t = terminal(&run);
        assert!(
            t.ends_with("1 case under 1 profile: 1 pass, 0 fail, 0 inconclusive, 0 error, 0 not applicable; 1 erratum recorded; 1 suite file did not load\n"),
            "{t}"
        );
    }

    #[test]
    fn quiet_names_each_failure_and_load_error_then_the_totals() {
        let mut run = sample_run();
        run.load_errors = vec!["suites/bu0620/x.yaml:8: unknown step `wait`".into()];
        let q = quiet(&run);
        let lines: Vec<&str> = q.lines().collect();
        assert_eq!(lines.len(), 4, "{q}");
        assert_eq!(
            lines[0],
            "LOAD ERROR suites/bu0620/x.yaml:8: unknown step `wait`"
        );
        assert!(
            lines[1]
                .starts_with("FAIL  [sk550p] bu0620/addressing/coe-p102: status: expected 2865"),
            "{q}"
        );
        assert_eq!(
            lines[2],
            "ERROR [tu3-eip] bu0620/pkw-telegrams/silent: no answer from the DUT within 250 bus cycles"
        );
        assert!(lines[3].starts_with("6 cases under 2 profiles: "), "{q}");
        // The same totals line as the full console's last.
        assert_eq!(lines[3], terminal(&run).lines().last().unwrap());
        // A clean run is the totals line alone.
        run.load_errors.clear();
        run.cases
            .retain(|c| !matches!(c.verdict, Verdict::Fail | Verdict::Error));
        assert_eq!(quiet(&run).lines().count(), 1);
    }

    #[test]
    fn cells_cannot_break_the_table() {
        assert_eq!(cell("a|b\nc"), "a\\|b c");
    }
}
