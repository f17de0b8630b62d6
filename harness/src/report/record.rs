//! The run's record, as every report states it: what was tested (DUT, identity per profile),
//! with what (harness and suites revisions), when and how (start, duration, command line), and
//! whether motion was allowed. One list of lines, so `summary.md`, `junit.xml` and
//! `index.html` cannot disagree about the run they describe.

use super::markup::count;
use crate::outcome::{CaseKind, CaseResult, RunResult};

/// The first line of `summary.md` and the top of `index.html`: a reader must see at once
/// whether cases that could turn a motor ran.
pub(super) fn motion_line(run: &RunResult) -> &'static str {
    match (run.meta.eeprom_cap, run.meta.motion_allowed) {
        (None, _) => "No motor, no EEPROM: the embedded simulator ran every case (--allow-motion and --max-eeprom-writes govern runs against a --dut)",
        (Some(_), true) => "Motion allowed (--allow-motion given): cases that can turn a motor were run",
        (Some(_), false) => "Motion not allowed (--allow-motion not given): cases that could turn a motor were not run",
    }
}

/// `value`, or `unknown` when the run did not record it (a `run.json` from before the record).
pub(super) fn or_unknown(value: &str) -> String {
    if value.is_empty() {
        "unknown".into()
    } else {
        value.to_string()
    }
}

/// The record as labelled lines, in the order reports show them: the DUT, its identity per
/// profile (`identity <profile>`; `not read` for a profile without one), the harness, the
/// suites, the start, the duration, the command line and the profiles.
pub(super) fn lines(run: &RunResult) -> Vec<(String, String)> {
    let m = &run.meta;
    let mut out = Vec::new();
    if let Some(i) = &m.interrupted {
        out.push(("interrupted".to_string(), interrupted_line(i)));
    }
    out.push(("DUT".to_string(), run.dut.clone()));
    if m.identities.is_empty() {
        // One line, not one per profile, when no profile's identity was read (the embedded
        // simulator's runs; a run whose DUT never answered).
        out.push(("identity".into(), "not read".into()));
    }
    for p in super::summary::profiles(run)
        .into_iter()
        .filter(|_| !m.identities.is_empty())
    {
        let identity = m
            .identities
            .get(p)
            .map_or_else(|| "not read".to_string(), |i| i.line());
        out.push((format!("identity {p}"), identity));
    }
    out.extend([
        (
            "harness".into(),
            format!(
                "{} (revision {})",
                or_unknown(&m.harness_version),
                or_unknown(&m.harness_revision)
            ),
        ),
        ("suites revision".into(), or_unknown(&m.suites_revision)),
        (
            "EEPROM writes".into(),
            match m.eeprom_cap {
                Some(cap) => format!("{} (at most {cap}: --max-eeprom-writes)", m.eeprom_writes),
                None => "not counted (the embedded simulator has no EEPROM to wear)".into(),
            },
        ),
        ("started".into(), or_unknown(&m.started)),
        ("host".into(), or_unknown(&m.host)),
        (
            "duration".into(),
            format!("{:.3} s", run.duration.as_secs_f64()),
        ),
        ("command line".into(), command_line(&m.command_line)),
        ("profiles".into(), run.profiles.join(", ")),
    ]);
    if let Some(seed) = m.shuffle {
        out.push((
            "case order".into(),
            format!("shuffled, seed {seed} (--shuffle)"),
        ));
    }
    if m.eeprom_cap.is_some() {
        out.push((
            "host timing".into(),
            match m.discarded_attempts {
                0 => "on time: no attempt discarded".into(),
                n => format!(
                    "late: {n} attempts discarded and run again (each case's transcript says why)"
                ),
            },
        ));
    }
    out
}

/// What a signal left of the run: its report covers the case-runs before it.
pub(super) fn interrupted_line(i: &crate::outcome::Interrupted) -> String {
    let cut = match i.cut.as_slice() {
        [] => String::new(),
        cut => format!(
            "{} cut short between two steps, not judged, its cleanup run ({}); ",
            count(cut.len(), "case-run", "case-runs"),
            cut.join(", ")
        ),
    };
    format!(
        "by a signal (Ctrl-C or SIGTERM): {cut}{} not run (run.json lists them)",
        count(i.not_run.len(), "case-run", "case-runs")
    )
}

/// The command line as one shell-readable line: an argument with a space or a quote is
/// single-quoted.
pub(super) fn command_line(args: &[String]) -> String {
    if args.is_empty() {
        return "unknown".into();
    }
    args.iter()
        .map(|a| {
            if a.is_empty() || a.contains(|c: char| c.is_whitespace() || "'\"\\$`".contains(c)) {
                format!("'{}'", a.replace('\'', r"'\''"))
            } else {
                a.clone()
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The requirement a case checks: the manual's words where the suite quotes them, then the
/// case title (the requirement as the suite states it).
pub(super) fn requirement(c: &CaseResult) -> String {
    match &c.manual.quote {
        Some(q) => format!("“{q}” ({})", c.title),
        None => c.title.clone(),
    }
}

/// What a kind's group is called in the reports.
pub(super) fn group_title(kind: CaseKind) -> &'static str {
    match kind {
        CaseKind::Device => "device",
        CaseKind::Model => "model (reference checks of the manuals' formulas, no DUT)",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;

    #[test]
    fn record_names_dut_identities_revisions_and_command() {
        let run = sample_run();
        let l = lines(&run);
        let get = |k: &str| {
            l.iter()
                .find(|(label, _)| label == k)
                .map(|(_, v)| v.as_str())
                .unwrap_or_else(|| panic!("{k}: {l:?}"))
        };
        assert_eq!(get("DUT"), "embedded simulator");
        assert_eq!(
            get("identity sk550p"),
            "NORD SK 550P, firmware V1.2 R0, serial 123456 (from P743/P707/P780 over the parameter channel)"
        );
        assert_eq!(get("identity tu3-eip"), "not read");
        assert_eq!(
            get("harness"),
            "0.1.0 (revision 0123456789abcdef0123456789abcdef01234567)"
        );
        assert_eq!(get("started"), "2026-11-27T06:00:00Z");
        assert_eq!(get("duration"), "0.015 s");
        assert_eq!(get("command line"), "harness run --filter 'a b'");
        assert_eq!(get("profiles"), "sk550p, tu3-eip");
        assert!(l.iter().all(|(label, _)| label != "interrupted"), "{l:?}");
    }

    #[test]
    fn an_interrupted_run_says_so_first() {
        let mut run = sample_run();
        run.meta.interrupted = Some(crate::outcome::Interrupted {
            cut: vec!["sk550p bu0620/x".into()],
            not_run: vec!["sk550p bu0620/y".into(), "tu3-eip bu0620/y".into()],
        });
        assert_eq!(
            lines(&run)[0],
            (
                "interrupted".to_string(),
                "by a signal (Ctrl-C or SIGTERM): 1 case-run cut short between two steps, not judged, its cleanup run (sk550p bu0620/x); 2 case-runs not run (run.json lists them)".to_string()
            )
        );
    }

    #[test]
    fn missing_record_says_unknown() {
        let mut run = sample_run();
        run.meta = Default::default();
        let l = lines(&run);
        assert!(
            l.contains(&("suites revision".into(), "unknown".into())),
            "{l:?}"
        );
        assert!(
            l.contains(&("command line".into(), "unknown".into())),
            "{l:?}"
        );
    }

    #[test]
    fn motion_line_follows_the_flag() {
        let mut run = sample_run();
        assert!(motion_line(&run).starts_with("Motion not allowed (--allow-motion not given)"));
        run.meta.motion_allowed = true;
        assert!(motion_line(&run).starts_with("Motion allowed"));
        // No limits: the embedded simulator's run, which has no motor.
        run.meta.eeprom_cap = None;
        assert!(motion_line(&run).starts_with("No motor, no EEPROM"));
    }

    #[test]
    fn requirement_quotes_the_manual_when_the_suite_does() {
        let mut c = sample_run().cases.remove(1);
        assert_eq!(requirement(&c), "title of bu0620/addressing/coe-p102");
        c.manual.quote = Some("P102 = 3066h".into());
        assert_eq!(
            requirement(&c),
            "“P102 = 3066h” (title of bu0620/addressing/coe-p102)"
        );
    }

    #[test]
    fn command_line_quotes_what_a_shell_would_split() {
        assert_eq!(
            command_line(&["a".into(), "it's x".into(), String::new()]),
            r"a 'it'\''s x' ''"
        );
    }
}
