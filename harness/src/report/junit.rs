//! JUnit XML: one `<testsuite>` per profile for its device cases, one `<testsuite name="<profile>
//! model">` for its reference-model cases (they never touch the DUT, so no consumer may count
//! their passes as the device's), one `suite files` testsuite with an `<error>` testcase per suite
//! file that did not load, all under a bare `<testsuites>` root (the totals are the suites').
//!
//! Written by hand (junit-report writes no `<properties>`), to one shape that two schemas
//! accept: the Jenkins xunit plugin's `junit-10.xsd` and the stricter Ant JUnit schema
//! (`tests/schemas/`, checked by `tests/report_junit.rs`). What that shape costs:
//!
//! - A testcase holds no `<properties>` and no `<system-out>` (Ant allows only one result
//!   element in it; Jenkins no properties). The run's record — DUT and its identity, profile,
//!   harness and suites revisions, start, command line, motion allowed, the manuals' editions —
//!   is the `<properties>` of each `<testsuite>`; a non-passing case's full manual reference
//!   (doc, edition, section, page), stated requirement, profile, DUT and transcript file are the
//!   text of its `<failure>`, `<error>` or `<skipped>`.
//! - `<skipped>` has no `type` (Ant forbids it): its message starts with the verdict
//!   (`inconclusive: …`, `not applicable: …`).
//! - `<testsuites>` has no attributes: Ant's schema allows none (Jenkins' allows some, and
//!   both sum the suites' counts). Every `<testsuite>` carries `tests`, `failures`, `errors`,
//!   `skipped` and `time`.
//! - Every `<testsuite>` has `id`, `package`, `timestamp` (the run's start, UTC, without zone as
//!   Ant wants) and `hostname` (`localhost`: the run does not record the machine's name), and
//!   its `<properties>`, `<system-out>` and `<system-err>` in Ant's order.
//!
//! The classname is `<profile>.<doc> §<section>` (`sk550p.BU 0620 §2․2․7`), with `model.` after
//! the profile for model cases: the profile makes every (classname, name) pair of a run
//! distinct, and Jenkins, which splits a classname at its last dot into package and class,
//! shows the profile as the package and the manual section as the class. For that the dots
//! within the doc and section are written as U+2024 ONE DOT LEADER, which looks the same; the
//! section as printed, with its real dots, is in the failure text and in `run.json`.

use std::fmt::Write;

use super::markup::{attr, text};
use super::record::{self, group_title, or_unknown};
use super::summary::{profiles, Counts};
use super::write::transcript_file;
use crate::outcome::{CaseKind, CaseResult, RunResult, Verdict};

/// What a verdict becomes in JUnit (DESIGN.md "Verdicts and reports": lossless mapping).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum JunitResult {
    /// `<testcase>` without a child.
    Success,
    /// `<failure type="fail" message=…>`: the DUT contradicts the manual.
    Failure(String),
    /// `<error type="error" message=…>`: the link or the harness failed.
    Error(String),
    /// `<skipped message=…>`, the message prefixed with the verdict, so the reason and the
    /// verdict survive tools that only show the message.
    Skipped(String),
}

/// The verdict → JUnit mapping, the only one.
pub(super) fn junit_result(verdict: Verdict, message: &str) -> JunitResult {
    match verdict {
        Verdict::Pass => JunitResult::Success,
        Verdict::Fail => JunitResult::Failure(message.to_string()),
        Verdict::Error => JunitResult::Error(message.to_string()),
        Verdict::Inconclusive => JunitResult::Skipped(format!("inconclusive: {message}")),
        Verdict::NotApplicable => JunitResult::Skipped(format!("not applicable: {message}")),
    }
}

/// Dots as U+2024 ONE DOT LEADER, so Jenkins does not split there (see the module doc).
fn no_split(s: &str) -> String {
    s.replace('.', "\u{2024}")
}

/// The package part of a classname: the profile, then `model` for model cases.
fn package(profile: &str, kind: CaseKind) -> String {
    match kind {
        CaseKind::Device => profile.to_string(),
        CaseKind::Model => format!("{profile}.model"),
    }
}

/// `sk550p.BU 0620 §2․2․7`.
fn classname(c: &CaseResult) -> String {
    format!(
        "{}.{}",
        package(&c.profile, c.kind),
        no_split(&format!("{} §{}", c.manual.doc, c.manual.section))
    )
}

/// Seconds with at most three decimals, as both schemas' time types accept.
fn secs(d: std::time::Duration) -> String {
    format!("{:.3}", d.as_secs_f64())
}

/// The run's start as Ant's timestamp wants it (`2026-11-27T06:00:00`, no zone), or the epoch
/// when the run did not record its start.
fn timestamp(started: &str) -> &str {
    let head = started.get(..19).unwrap_or("");
    let ok = head.bytes().enumerate().all(|(i, b)| match i {
        4 | 7 => b == b'-',
        10 => b == b'T',
        13 | 16 => b == b':',
        _ => b.is_ascii_digit(),
    });
    if head.len() == 19 && ok {
        head
    } else {
        "1970-01-01T00:00:00"
    }
}

/// The text of a non-passing case's result element: where the manual says it, and what.
fn details(c: &CaseResult, dut: &str) -> String {
    let m = &c.manual;
    format!(
        "manual: {} ({}) {}\nrequirement: {}\nprofile: {}\ncases: {}\ndut: {dut}\ntranscript: {}\n",
        m.doc,
        m.edition,
        m.place(),
        record::requirement(c),
        c.profile,
        c.kind.name(),
        transcript_file(c).unwrap_or_else(|| "-".into()),
    )
}

fn testcase(s: &mut String, c: &CaseResult, dut: &str) {
    let _ = write!(
        s,
        "    <testcase name=\"{}\" classname=\"{}\" time=\"{}\"",
        attr(&c.id),
        attr(&classname(c)),
        secs(c.duration)
    );
    let (element, type_, message) = match junit_result(c.verdict, &c.message) {
        JunitResult::Success => {
            s.push_str("/>\n");
            return;
        }
        JunitResult::Failure(m) => ("failure", Some("fail"), m),
        JunitResult::Error(m) => ("error", Some("error"), m),
        JunitResult::Skipped(m) => ("skipped", None, m),
    };
    let _ = write!(s, ">\n      <{element}");
    if let Some(t) = type_ {
        let _ = write!(s, " type=\"{t}\"");
    }
    let _ = writeln!(
        s,
        " message=\"{}\">{}</{element}>\n    </testcase>",
        attr(&message),
        text(&details(c, dut))
    );
}

/// The `<properties>` every testsuite carries: the run's record, and for a profile's suites the
/// profile, its DUT identity and the manuals' editions its cases cite.
fn properties(s: &mut String, run: &RunResult, profile: Option<&str>, cases: &[&CaseResult]) {
    let m = &run.meta;
    let mut props: Vec<(String, String)> = vec![("dut".into(), run.dut.clone())];
    if let Some(p) = profile {
        props.push(("profile".into(), p.into()));
        if let Some(id) = m.identities.get(p) {
            props.push(("dut.identity".into(), id.line()));
        }
    }
    props.extend([
        ("harness.version".into(), or_unknown(&m.harness_version)),
        ("harness.revision".into(), or_unknown(&m.harness_revision)),
        ("suites.revision".into(), or_unknown(&m.suites_revision)),
        ("started".into(), or_unknown(&m.started)),
        ("duration".into(), secs(run.duration)),
        ("command_line".into(), record::command_line(&m.command_line)),
        ("motion_allowed".into(), m.motion_allowed.to_string()),
    ]);
    let mut editions: Vec<(&str, &str)> = cases
        .iter()
        .map(|c| (c.manual.doc.as_str(), c.manual.edition.as_str()))
        .collect();
    editions.sort_unstable();
    editions.dedup();
    props.extend(
        editions
            .into_iter()
            .map(|(doc, edition)| ("manual".to_string(), format!("{doc} ({edition})"))),
    );
    s.push_str("    <properties>\n");
    for (name, value) in props {
        let _ = writeln!(
            s,
            "      <property name=\"{}\" value=\"{}\"/>",
            attr(&name),
            attr(&value)
        );
    }
    s.push_str("    </properties>\n");
}

/// One suite's counts, in the attributes both schemas require.
struct SuiteHead<'a> {
    id: usize,
    name: &'a str,
    package: &'a str,
    tests: usize,
    failures: usize,
    errors: usize,
    skipped: usize,
    time: String,
}

fn open_suite(s: &mut String, run: &RunResult, h: &SuiteHead<'_>) {
    let _ = writeln!(
        s,
        "  <testsuite id=\"{}\" name=\"{}\" package=\"{}\" tests=\"{}\" failures=\"{}\" errors=\"{}\" skipped=\"{}\" time=\"{}\" timestamp=\"{}\" hostname=\"{}\">",
        h.id,
        attr(h.name),
        attr(h.package),
        h.tests,
        h.failures,
        h.errors,
        h.skipped,
        h.time,
        timestamp(&run.meta.started),
        attr(&hostname(&run.meta.host)),
    );
}

/// The host the run was on; `localhost` for a run that did not record it (Ant requires a
/// name there).
fn hostname(host: &str) -> String {
    if host.is_empty() {
        "localhost".into()
    } else {
        host.to_string()
    }
}

fn close_suite(s: &mut String, out: &str) {
    let _ = writeln!(
        s,
        "    <system-out>{}</system-out>\n    <system-err></system-err>\n  </testsuite>",
        text(out)
    );
}

/// The XML document, streamed into `out` a testsuite at a time (a default run's is over ten
/// megabytes).
pub(super) fn write(run: &RunResult, out: &mut dyn std::io::Write) -> std::io::Result<()> {
    out.write_all(b"<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n")?;
    let mut body = String::new();
    let mut id = 0;
    for profile in profiles(run) {
        for kind in [CaseKind::Device, CaseKind::Model] {
            let cases: Vec<&CaseResult> = run
                .cases
                .iter()
                .filter(|c| c.profile == profile && c.kind == kind)
                .collect();
            if kind == CaseKind::Model && cases.is_empty() {
                continue;
            }
            let n = Counts::of(cases.iter().copied());
            let name = match kind {
                CaseKind::Device => profile.to_string(),
                CaseKind::Model => format!("{profile} model"),
            };
            let head = SuiteHead {
                id,
                name: &name,
                package: &package(profile, kind),
                tests: cases.len(),
                failures: n.get(Verdict::Fail),
                errors: n.get(Verdict::Error),
                skipped: n.get(Verdict::Inconclusive) + n.get(Verdict::NotApplicable),
                time: secs(cases.iter().map(|c| c.duration).sum()),
            };
            open_suite(&mut body, run, &head);
            properties(&mut body, run, Some(profile), &cases);
            for c in &cases {
                testcase(&mut body, c, &run.dut);
            }
            close_suite(
                &mut body,
                &format!(
                    "profile: {profile}\ncases: {}\ndut: {}\n",
                    group_title(kind),
                    run.dut
                ),
            );
            out.write_all(body.as_bytes())?;
            body.clear();
            id += 1;
        }
    }
    if !run.load_errors.is_empty() {
        let head = SuiteHead {
            id,
            name: "suite files",
            package: "suite files",
            tests: run.load_errors.len(),
            failures: 0,
            errors: run.load_errors.len(),
            skipped: 0,
            time: secs(std::time::Duration::ZERO),
        };
        open_suite(&mut body, run, &head);
        properties(&mut body, run, None, &[]);
        for e in &run.load_errors {
            // `file:line: what`: the testcase is named for the file and line.
            let place = e.split_once(": ").map_or(e.as_str(), |(place, _)| place);
            let _ = writeln!(
                body,
                "    <testcase name=\"{}\" classname=\"suite files\" time=\"0.000\">\n      <error type=\"load error\" message=\"{}\">{}</error>\n    </testcase>",
                attr(place),
                attr(e),
                text(&format!("this suite file did not load; its cases did not run\n{e}\n"))
            );
        }
        close_suite(&mut body, "suite files that did not load\n");
    }
    out.write_all(body.as_bytes())?;
    out.write_all(b"</testsuites>\n")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::fixtures::sample_run;
    use rstest::rstest;

    #[rstest]
    #[case(Verdict::Pass, "", JunitResult::Success)]
    #[case(Verdict::Fail, "got 0B37h", JunitResult::Failure("got 0B37h".into()))]
    #[case(Verdict::Error, "no answer", JunitResult::Error("no answer".into()))]
    #[case(
        Verdict::Inconclusive,
        "setup failed",
        JunitResult::Skipped("inconclusive: setup failed".into())
    )]
    #[case(
        Verdict::NotApplicable,
        "about sk550p",
        JunitResult::Skipped("not applicable: about sk550p".into())
    )]
    fn verdict_mapping(#[case] v: Verdict, #[case] msg: &str, #[case] want: JunitResult) {
        assert_eq!(junit_result(v, msg), want);
    }

    fn render(run: &RunResult) -> String {
        let mut out = Vec::new();
        write(run, &mut out).unwrap();
        String::from_utf8(out).unwrap()
    }

    fn xml() -> String {
        render(&sample_run())
    }

    #[test]
    fn one_suite_per_profile_and_kind_with_counts_and_totals() {
        let x = xml();
        assert_eq!(x.matches("<testsuite ").count(), 3, "{x}");
        // A bare root, as Ant's schema wants; the suites carry the counts.
        assert!(
            x.starts_with(
                "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n  <testsuite id=\"0\""
            ),
            "{x}"
        );
        assert!(
            x.contains(r#"<testsuite id="0" name="sk550p" package="sk550p" tests="2" failures="1" errors="0" skipped="0" time="0.006" timestamp="2026-11-27T06:00:00" hostname="qa-bench-1">"#),
            "{x}"
        );
        // The model case is in a suite of its own, never among sk550p's device passes.
        assert!(
            x.contains(r#"<testsuite id="1" name="sk550p model" package="sk550p.model" tests="1" failures="0" errors="0" skipped="0""#),
            "{x}"
        );
        assert!(
            x.contains(r#"<testsuite id="2" name="tu3-eip" package="tu3-eip" tests="3" failures="0" errors="1" skipped="2""#),
            "{x}"
        );
        assert!(
            x.contains("<system-out>profile: tu3-eip\ncases: device\ndut: embedded simulator\n</system-out>\n    <system-err></system-err>\n  </testsuite>"),
            "{x}"
        );
    }

    #[test]
    fn suites_carry_the_run_record_as_properties() {
        let x = xml();
        for p in [
            r#"<property name="dut" value="embedded simulator"/>"#,
            r#"<property name="profile" value="sk550p"/>"#,
            r#"<property name="dut.identity" value="NORD SK 550P, firmware V1.2 R0, serial 123456 (from P743/P707/P780 over the parameter channel)"/>"#,
            r#"<property name="suites.revision" value="0123456789abcdef0123456789abcdef01234567"/>"#,
            r#"<property name="command_line" value="harness run --filter &apos;a b&apos;"/>"#,
            r#"<property name="motion_allowed" value="false"/>"#,
            r#"<property name="manual" value="BU 2100 (en)"/>"#,
            r#"<property name="manual" value="BU 0620 (2020-03 en)"/>"#,
        ] {
            assert!(x.contains(p), "{p}\n{x}");
        }
        // One properties block per suite, first in it.
        assert_eq!(x.matches("<properties>").count(), 3, "{x}");
    }

    #[test]
    fn each_verdict_becomes_its_element() {
        let x = xml();
        assert!(x.contains(r#"<failure type="fail" message="status: expected 2865 (0B31h), got 2871 (0B37h)">manual: BU 0620 (2020-03 en) §2.2.7 p. 20
requirement: title of bu0620/addressing/coe-p102
profile: sk550p
cases: device
dut: embedded simulator
transcript: transcripts.txt#sk550p/bu0620/addressing/coe-p102
</failure>"#), "{x}");
        assert!(
            x.contains(
                r#"<error type="error" message="no answer from the DUT within 250 bus cycles">"#
            ),
            "{x}"
        );
        assert!(x.contains(r#"<skipped message="not applicable: the statement is about sk550p, this run is tu3-eip">"#), "{x}");
        assert!(
            x.contains(r#"<skipped message="inconclusive: setup step 1 failed: no connection">"#),
            "{x}"
        );
        assert!(!x.contains("<skipped type"), "{x}");
    }

    #[test]
    fn classnames_keep_profile_as_package_and_section_whole() {
        let x = xml();
        assert!(
            x.contains("<testcase name=\"bu0620/addressing/coe-p102\" classname=\"sk550p.BU 0620 §2\u{2024}2\u{2024}7\" time=\"0.003\">"),
            "{x}"
        );
        assert!(
            x.contains("<testcase name=\"bu0620/addressing/coe-p102\" classname=\"tu3-eip.BU 0620 §2\u{2024}2\u{2024}7\""),
            "{x}"
        );
        assert!(
            x.contains("<testcase name=\"bu0620/drive-scaling/setpoint\" classname=\"sk550p.model.BU 0620 §2\u{2024}6\u{2024}1\" time=\"0.003\"/>"),
            "{x}"
        );
        // Jenkins' split at the last dot: the package is the profile.
        let run = sample_run();
        for c in &run.cases {
            let cn = classname(c);
            let (pkg, class) = cn.rsplit_once('.').unwrap();
            assert_eq!(pkg, package(&c.profile, c.kind), "{cn}");
            assert!(class.starts_with(&c.manual.doc), "{cn}");
        }
        // Every (classname, name) pair is distinct.
        let mut pairs: Vec<_> = run.cases.iter().map(|c| (classname(c), &c.id)).collect();
        pairs.sort();
        pairs.dedup();
        assert_eq!(pairs.len(), run.cases.len());
    }

    #[test]
    fn load_errors_are_error_testcases_naming_file_and_line() {
        let mut run = sample_run();
        run.load_errors = vec![
            "suites/bu0620/x.yaml:8: unknown step `wait`".into(),
            "suites/bu0620/y.yaml: not YAML".into(),
        ];
        let x = render(&run);
        assert!(
            x.contains(r#"<testsuite id="3" name="suite files" package="suite files" tests="2" failures="0" errors="2" skipped="0""#),
            "{x}"
        );
        assert!(x.contains("<testcase name=\"suites/bu0620/x.yaml:8\" classname=\"suite files\" time=\"0.000\">\n      <error type=\"load error\" message=\"suites/bu0620/x.yaml:8: unknown step `wait`\">"), "{x}");
        assert!(
            x.contains("<testcase name=\"suites/bu0620/y.yaml\" classname=\"suite files\""),
            "{x}"
        );
    }

    #[rstest]
    #[case("2026-11-27T06:00:00Z", "2026-11-27T06:00:00")]
    #[case("2026-11-27T06:00:00.123+00:00", "2026-11-27T06:00:00")]
    #[case("", "1970-01-01T00:00:00")]
    #[case("yesterday, about noon", "1970-01-01T00:00:00")]
    fn timestamps_lose_their_zone(#[case] started: &str, #[case] want: &str) {
        assert_eq!(timestamp(started), want);
    }

    #[test]
    fn hostile_text_stays_well_formed() {
        let mut run = sample_run();
        run.cases[1].message = "a\u{0}b <c> & \"d\"\nnext".into();
        run.cases[1].title = "x ]]> y".into();
        let x = render(&run);
        assert!(
            x.contains(r#"message="a�b &lt;c&gt; &amp; &quot;d&quot;&#10;next""#),
            "{x}"
        );
        assert!(x.contains("requirement: x ]]&gt; y"), "{x}");
        assert!(!x.contains('\u{0}'), "{x}");
    }
}
