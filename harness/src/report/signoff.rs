//! What a person signing a run off reads first: the overall verdict, by the exit code's rule
//! (the banner at the top of `summary.md` and `index.html`), and the not-applicable cases
//! grouped by why they did not run (motion not allowed, the EEPROM cap, another product,
//! another bus, a declaration the run lacks, a state the DUT cannot offer), so that "778 not
//! applicable" says whether anything the sign-off needs was left out.

use std::fmt::Write;

use super::markup::{count, text};
use super::summary::run_counts_line;
use crate::outcome::{CaseKind, RunResult, Verdict};

/// The run as a whole.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Overall {
    /// A signal stopped the run: the case-runs after it did not run (exit 130).
    Interrupted,
    /// A suite file did not load: its cases did not run (exit 2).
    Incomplete,
    /// A case failed or erred (exit 1).
    Fail,
    /// Nothing failed, and no device case ran either: no verdict about the device.
    NothingChecked,
    /// Nothing failed or erred, and device cases ran (exit 0).
    Pass,
}

impl Overall {
    /// The banner's word.
    pub(super) fn word(self) -> &'static str {
        match self {
            Overall::Interrupted => "INTERRUPTED",
            Overall::Incomplete => "INCOMPLETE",
            Overall::Fail => "FAIL",
            Overall::NothingChecked => "NOTHING CHECKED",
            Overall::Pass => "PASS",
        }
    }

    /// The CSS class of the banner.
    pub(super) fn class(self) -> &'static str {
        match self {
            Overall::Interrupted | Overall::Incomplete => "overall-incomplete",
            Overall::Fail => "overall-fail",
            Overall::NothingChecked => "overall-none",
            Overall::Pass => "overall-pass",
        }
    }
}

/// The banner: the overall verdict, why, and the run's counts.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct Banner {
    /// The verdict.
    pub(super) overall: Overall,
    /// Why, in one sentence.
    pub(super) why: String,
    /// The counts (device, and the model's beside them).
    pub(super) counts: String,
}

/// The overall verdict of `run`.
pub(super) fn banner(run: &RunResult) -> Banner {
    let (fail, error) = (run.count(Verdict::Fail), run.count(Verdict::Error));
    let ran = run
        .cases
        .iter()
        .filter(|c| c.kind == CaseKind::Device && c.verdict != Verdict::NotApplicable)
        .count();
    let (overall, why) = if let Some(i) = &run.meta.interrupted {
        (
            Overall::Interrupted,
            format!(
                "stopped by a signal, {} not run{}",
                count(i.not_run.len(), "case-run", "case-runs"),
                if fail + error > 0 {
                    format!("; {fail} failed, {error} erred before")
                } else {
                    String::new()
                }
            ),
        )
    } else if !run.load_errors.is_empty() {
        (
            Overall::Incomplete,
            format!(
                "{} did not load: their cases did not run",
                count(run.load_errors.len(), "suite file", "suite files")
            ),
        )
    } else if fail + error > 0 {
        (
            Overall::Fail,
            format!("{fail} failed, {error} erred (case-runs, model checks included)"),
        )
    } else if ran == 0 {
        (
            Overall::NothingChecked,
            "no case reached the device: every device case was not applicable".to_string(),
        )
    } else {
        (
            Overall::Pass,
            format!(
                "nothing failed or erred; {} ran",
                count(ran, "device case-run", "device case-runs")
            ),
        )
    };
    Banner {
        overall,
        why,
        counts: run_counts_line(run),
    }
}

/// `summary.md`'s first line.
pub(super) fn markdown_banner(run: &RunResult) -> String {
    let b = banner(run);
    format!(
        "**{}: {}** — {}",
        b.overall.word(),
        b.why,
        b.counts.replace('|', "\\|")
    )
}

/// `index.html`'s first element.
pub(super) fn html_banner(s: &mut String, run: &RunResult) {
    let b = banner(run);
    let _ = writeln!(
        s,
        "<div id=\"overall\" class=\"{}\" data-overall=\"{}\"><strong>{}</strong> {}<br><small>{}</small></div>",
        b.overall.class(),
        b.overall.word(),
        b.overall.word(),
        text(&b.why),
        text(&b.counts)
    );
}

/// Why a case was not applicable, by kind of reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) enum NaReason {
    /// It could turn a motor, and `--allow-motion` was not given.
    Motion,
    /// Its EEPROM writes would pass `--max-eeprom-writes`.
    EepromCap,
    /// The statement is about another product (or a NORD product, under `--profile any`).
    Product,
    /// It needs a bus the profile does not run over, or the DUT does not speak.
    Bus,
    /// It needs a declaration (EDS, GSDML, XDD feature flag) the run lacks.
    Description,
    /// It needs a state or a facility the DUT does not offer (power-on, factory settings,
    /// fault injection, a view of the simulator's inside).
    Capability,
    /// Anything else.
    Other,
}

impl NaReason {
    /// As the reports name it.
    pub(super) fn label(self) -> &'static str {
        match self {
            NaReason::Motion => "motion not allowed",
            NaReason::EepromCap => "EEPROM write cap",
            NaReason::Product => "another product",
            NaReason::Bus => "another bus",
            NaReason::Description => "a declaration the run lacks (description)",
            NaReason::Capability => "a state or facility the DUT does not offer",
            NaReason::Other => "other",
        }
    }
}

/// The kind of a not-applicable reason, from its message (the runner's, the safety guard's, a
/// binding's; `run.json` keeps only the message).
pub(super) fn na_reason(message: &str) -> NaReason {
    if message.starts_with("motion not allowed") {
        NaReason::Motion
    } else if message.starts_with("EEPROM write cap") {
        NaReason::EepromCap
    } else if message.starts_with("the statement is about")
        || message.contains("(any maker's device) runs its bus's own steps only")
    {
        NaReason::Product
    } else if message.contains("--description") || message.contains("declare") {
        NaReason::Description
    } else if let Some(cap) = message
        .strip_prefix("needs `")
        .and_then(|rest| rest.split('`').next())
    {
        // What a case needs is a general capability or a bus's steps.
        if crate::profile::Capability::GENERAL
            .iter()
            .any(|c| c.name() == cap)
        {
            NaReason::Capability
        } else {
            NaReason::Bus
        }
    } else {
        NaReason::Other
    }
}

/// The not-applicable case-runs of one kind of reason.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) struct NaGroup {
    /// The kind of reason.
    pub(super) reason: NaReason,
    /// Device case-runs.
    pub(super) device: usize,
    /// Model case-runs.
    pub(super) model: usize,
    /// The most frequent message, as an example.
    pub(super) example: String,
}

/// The run's not-applicable case-runs by kind of reason, the kinds that occur, in the order
/// [`NaReason`] declares them.
pub(super) fn na_groups(run: &RunResult) -> Vec<NaGroup> {
    use std::collections::BTreeMap;
    let mut by: BTreeMap<NaReason, (usize, usize, BTreeMap<&str, usize>)> = BTreeMap::new();
    for c in run
        .cases
        .iter()
        .filter(|c| c.verdict == Verdict::NotApplicable)
    {
        let g = by.entry(na_reason(&c.message)).or_default();
        match c.kind {
            CaseKind::Device => g.0 += 1,
            CaseKind::Model => g.1 += 1,
        }
        *g.2.entry(c.message.as_str()).or_default() += 1;
    }
    by.into_iter()
        .map(|(reason, (device, model, messages))| NaGroup {
            reason,
            device,
            model,
            // The most frequent; of equals, the first by text.
            example: messages
                .iter()
                .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
                .map(|(m, _)| m.to_string())
                .unwrap_or_default(),
        })
        .collect()
}

/// `## Not applicable, by reason` for `summary.md` (nothing when every case applied).
pub(super) fn markdown_na(s: &mut String, run: &RunResult) {
    let groups = na_groups(run);
    if groups.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "\n## Not applicable, by reason\n\n| reason | device | model | most frequent message |\n|---|---:|---:|---|"
    );
    for g in &groups {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            g.reason.label(),
            g.device,
            g.model,
            g.example.replace('|', "\\|").replace(['\n', '\r'], " ")
        );
    }
}

/// The same table for `index.html`; the page's self-check sums its rows against the totals.
pub(super) fn html_na(s: &mut String, run: &RunResult) {
    let groups = na_groups(run);
    if groups.is_empty() {
        return;
    }
    s.push_str("<section id=\"not-applicable\"><h2>Not applicable, by reason</h2>\n<table><thead><tr><th>reason</th><th>device</th><th>model</th><th>most frequent message</th></tr></thead><tbody>\n");
    for g in &groups {
        let _ = writeln!(
            s,
            "<tr data-reason=\"{:?}\" data-n=\"{}\"><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td></tr>",
            g.reason,
            g.device + g.model,
            text(g.reason.label()),
            g.device,
            g.model,
            text(&g.example)
        );
    }
    s.push_str("</tbody></table></section>\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;
    use rstest::rstest;

    #[rstest]
    #[case(
        "motion not allowed (--allow-motion): control word 047Fh enables operation",
        NaReason::Motion
    )]
    #[case(
        "EEPROM write cap reached (--max-eeprom-writes 6): 6 written, the case needs 2 with its restores",
        NaReason::EepromCap
    )]
    #[case(
        "the statement is about sk550p, this run is tu3-eip",
        NaReason::Product
    )]
    #[case(
        "profile `any@enip` (any maker's device) runs its bus's own steps only; this case has `read P102`",
        NaReason::Product
    )]
    #[case(
        "needs `ecat`, which profile `sk550p@enip` does not run over",
        NaReason::Bus
    )]
    #[case(
        "needs `enip`, which embedded EtherNet/IP adapter (tu3-eip) does not offer",
        NaReason::Bus
    )]
    #[case(
        "needs the connection the adapter declares: give its EDS with `--description`",
        NaReason::Description
    )]
    #[case(
        "node 1 declares no SDO over UDP/IP (feature flags 1F82h = 00000001h, bit 1 clear)",
        NaReason::Description
    )]
    #[case(
        "needs `factory-state`, which EtherNet/IP adapter at 10.0.0.5 does not offer",
        NaReason::Capability
    )]
    #[case("the moon is not full", NaReason::Other)]
    fn reasons_fall_into_their_kind(#[case] message: &str, #[case] want: NaReason) {
        assert_eq!(na_reason(message), want);
    }

    #[test]
    fn the_banner_follows_the_exit_code_rule() {
        let mut run = sample_run();
        let b = banner(&run);
        assert_eq!(b.overall, Overall::Fail);
        assert_eq!(
            b.why,
            "1 failed, 1 erred (case-runs, model checks included)"
        );
        assert!(b.counts.starts_with("1 pass (+1 model), 1 fail"), "{b:?}");
        run.load_errors = vec!["x.yaml:1: bad".into()];
        assert_eq!(banner(&run).overall, Overall::Incomplete);
        assert_eq!(
            banner(&run).why,
            "1 suite file did not load: their cases did not run"
        );
        run.load_errors.clear();
        for c in &mut run.cases {
            if c.verdict != Verdict::Pass {
                c.verdict = Verdict::NotApplicable;
            }
        }
        let b = banner(&run);
        assert_eq!(
            (b.overall, b.why.as_str()),
            (
                Overall::Pass,
                "nothing failed or erred; 1 device case-run ran"
            )
        );
        // Only the model passed: nothing about the device.
        run.cases[0].verdict = Verdict::NotApplicable;
        assert_eq!(banner(&run).overall, Overall::NothingChecked);
        assert!(markdown_banner(&run).starts_with("**NOTHING CHECKED: no case reached the device"));
        // A signal stopped it: that comes first, whatever else it found.
        let mut cut = sample_run();
        cut.meta.interrupted = Some(crate::outcome::Interrupted {
            cut: Vec::new(),
            not_run: vec!["sk550p a".into(), "sk550p b".into()],
        });
        let b = banner(&cut);
        assert_eq!(
            (b.overall, b.why.as_str()),
            (
                Overall::Interrupted,
                "stopped by a signal, 2 case-runs not run; 1 failed, 1 erred before"
            )
        );
        let mut h = String::new();
        html_banner(&mut h, &sample_run());
        assert!(
            h.starts_with("<div id=\"overall\" class=\"overall-fail\" data-overall=\"FAIL\"><strong>FAIL</strong> 1 failed, 1 erred"),
            "{h}"
        );
    }

    #[test]
    fn not_applicable_cases_are_counted_by_reason_with_an_example() {
        let mut run = sample_run();
        let mut motion = run.cases[2].clone();
        motion.message = "motion not allowed (--allow-motion): setpoint 50 %".into();
        run.cases.push(motion.clone());
        motion.kind = CaseKind::Model;
        motion.message = "motion not allowed (--allow-motion): setpoint 20 %".into();
        run.cases.push(motion);
        let g = na_groups(&run);
        assert_eq!(
            g.iter()
                .map(|g| (g.reason, g.device, g.model))
                .collect::<Vec<_>>(),
            [(NaReason::Motion, 1, 1), (NaReason::Product, 1, 0)]
        );
        assert_eq!(
            g[0].example,
            "motion not allowed (--allow-motion): setpoint 20 %"
        );
        let mut md = String::new();
        markdown_na(&mut md, &run);
        assert!(md.contains("## Not applicable, by reason\n\n| reason | device | model | most frequent message |\n|---|---:|---:|---|\n| motion not allowed | 1 | 1 | motion not allowed (--allow-motion): setpoint 20 % |\n| another product | 1 | 0 | the statement is about sk550p, this run is tu3-eip |\n"), "{md}");
        let mut h = String::new();
        html_na(&mut h, &run);
        assert!(
            h.contains("<tr data-reason=\"Motion\" data-n=\"2\"><td>motion not allowed</td><td class=\"n\">1</td><td class=\"n\">1</td>"),
            "{h}"
        );
        run.cases.retain(|c| c.verdict != Verdict::NotApplicable);
        let mut none = String::new();
        markdown_na(&mut none, &run);
        html_na(&mut none, &run);
        assert!(none.is_empty());
    }
}
