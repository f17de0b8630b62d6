//! The human summary: verdicts per profile, coverage by manual section, errata, failures.

use std::collections::BTreeMap;
use std::fmt::Write;

use crate::outcome::{RunResult, Verdict};

/// Sort key for sections: "2.10" after "2.2.7".
fn section_key(s: &str) -> Vec<u32> {
    s.split('.')
        .map(|p| p.parse().unwrap_or(u32::MAX))
        .collect()
}

fn counts_row(counts: &[usize; 5]) -> String {
    counts
        .iter()
        .map(|n| n.to_string())
        .collect::<Vec<_>>()
        .join(" | ")
}

fn index(v: Verdict) -> usize {
    Verdict::ALL.iter().position(|x| *x == v).unwrap_or(0)
}

/// `summary.md`.
pub(super) fn markdown(run: &RunResult) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Run summary\n\nDUT: {}; profiles: {}; {:.3} s\n",
        run.dut,
        run.profiles.join(", "),
        run.duration.as_secs_f64()
    );
    if !run.load_errors.is_empty() {
        let _ = writeln!(s, "## Suite files that did not load\n");
        for e in &run.load_errors {
            let _ = writeln!(s, "- {e}");
        }
        s.push('\n');
    }
    let header = "| pass | fail | inconclusive | error | not applicable |";
    let _ = writeln!(
        s,
        "## Verdicts per profile\n\n| profile {header}\n|---|---|---|---|---|---|"
    );
    for p in &run.profiles {
        let mut c = [0usize; 5];
        for case in run.cases.iter().filter(|c| &c.profile == p) {
            c[index(case.verdict)] += 1;
        }
        let _ = writeln!(s, "| {p} | {} |", counts_row(&c));
    }
    let mut by_section: BTreeMap<(String, Vec<u32>, String), [usize; 5]> = BTreeMap::new();
    for c in &run.cases {
        let key = (
            c.manual.doc.clone(),
            section_key(&c.manual.section),
            c.manual.section.clone(),
        );
        by_section.entry(key).or_default()[index(c.verdict)] += 1;
    }
    let _ = writeln!(s, "\n## Coverage by manual section\n\n| manual | section {header}\n|---|---|---|---|---|---|---|");
    for ((doc, _, section), c) in &by_section {
        let _ = writeln!(s, "| {doc} | {section} | {} |", counts_row(c));
    }
    let _ = writeln!(
        s,
        "\n## Errata (what the manuals print, and what the cases test)\n"
    );
    for e in &run.errata {
        let _ = writeln!(
            s,
            "- {} ({}) §{} p. {}: printed `{}` → correct `{}` — {}",
            e.doc, e.edition, e.section, e.page, e.printed, e.correct, e.why
        );
    }
    let bad: Vec<_> = run
        .cases
        .iter()
        .filter(|c| {
            matches!(
                c.verdict,
                Verdict::Fail | Verdict::Error | Verdict::Inconclusive
            )
        })
        .collect();
    if !bad.is_empty() {
        let _ = writeln!(s, "\n## Failed, errored and inconclusive cases\n");
        for c in bad {
            let _ = writeln!(
                s,
                "- **{}** [{}] {}: {}",
                c.verdict.name(),
                c.profile,
                c.id,
                c.message
            );
        }
    }
    s
}

/// A few lines for the terminal.
pub(crate) fn terminal(run: &RunResult) -> String {
    let mut s = String::new();
    for e in &run.load_errors {
        let _ = writeln!(s, "LOAD ERROR {e}");
    }
    for c in run
        .cases
        .iter()
        .filter(|c| matches!(c.verdict, Verdict::Fail | Verdict::Error))
    {
        let _ = writeln!(
            s,
            "{:<5} [{}] {}: {}",
            c.verdict.name().to_uppercase(),
            c.profile,
            c.id,
            c.message
        );
    }
    let _ = writeln!(
        s,
        "{} cases under {} profiles: {} pass, {} fail, {} inconclusive, {} error, {} not applicable; {} errata recorded",
        run.cases.len(),
        run.profiles.len(),
        run.count(Verdict::Pass),
        run.count(Verdict::Fail),
        run.count(Verdict::Inconclusive),
        run.count(Verdict::Error),
        run.count(Verdict::NotApplicable),
        run.errata.len()
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests::sample_run;

    #[test]
    fn sections_sort_numerically() {
        let mut v = vec![
            section_key("2.10"),
            section_key("2.2.7"),
            section_key("2.2"),
        ];
        v.sort();
        assert_eq!(
            v,
            vec![
                section_key("2.2"),
                section_key("2.2.7"),
                section_key("2.10")
            ]
        );
    }

    #[test]
    fn summary_has_coverage_errata_and_failures() {
        let md = markdown(&sample_run());
        assert!(
            md.contains("| BU 0620 | 2.2.7 | 1 | 1 | 0 | 1 | 1 |"),
            "{md}"
        );
        assert!(
            md.contains("printed `class 103` → correct `class 102`"),
            "{md}"
        );
        assert!(md.contains("**fail** [sk550p]"), "{md}");
        assert!(terminal(&sample_run()).contains("1 pass, 1 fail"));
    }
}
