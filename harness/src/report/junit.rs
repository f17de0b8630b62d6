//! JUnit XML: one `<testsuite>` per profile, one `<testcase>` per case.
//!
//! Testcase name = case id; classname = `<doc> §<section>`, so CI tools group cases by manual
//! section. junit-report 0.9 writes no `<properties>` element (neither on testcases nor on
//! testsuites), so the manual reference (doc, edition, section, page), profile, DUT and
//! transcript file are `key: value` lines in each testcase's `<system-out>`, and each testsuite's
//! `<system-out>` names its profile and the DUT.

use junit_report::{Duration, Report, TestCase, TestResult, TestSuite};

use super::summary::profiles;
use super::write::transcript_file;
use crate::outcome::{CaseResult, RunResult, Verdict};

/// What a verdict becomes in JUnit (DESIGN.md "Verdicts and reports": lossless mapping).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(super) enum JunitResult {
    /// `<testcase>` without a child.
    Success,
    /// `<failure type="fail" message=…>`: the DUT contradicts the manual.
    Failure(String),
    /// `<error type="error" message=…>`: the link or the harness failed.
    Error(String),
    /// `<skipped type=<verdict> message=…>`, the message prefixed with the verdict, so the
    /// reason survives tools that only show the message.
    Skipped {
        /// `inconclusive` or `not_applicable`.
        kind: &'static str,
        /// `inconclusive: …` / `not applicable: …`.
        message: String,
    },
}

/// The verdict → JUnit mapping, the only one.
pub(super) fn junit_result(verdict: Verdict, message: &str) -> JunitResult {
    match verdict {
        Verdict::Pass => JunitResult::Success,
        Verdict::Fail => JunitResult::Failure(message.to_string()),
        Verdict::Error => JunitResult::Error(message.to_string()),
        Verdict::Inconclusive => JunitResult::Skipped {
            kind: verdict.name(),
            message: format!("inconclusive: {message}"),
        },
        Verdict::NotApplicable => JunitResult::Skipped {
            kind: verdict.name(),
            message: format!("not applicable: {message}"),
        },
    }
}

/// Text safe for XML 1.0 and CDATA: characters XML forbids (controls other than tab, line feed
/// and carriage return) become U+FFFD, and `]]>` cannot close a CDATA section early.
fn xml_safe(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '\t' | '\n' | '\r' => c,
            c if c < ' ' || c == '\u{FFFE}' || c == '\u{FFFF}' => '\u{FFFD}',
            c => c,
        })
        .collect::<String>()
        .replace("]]>", "]] >")
}

fn testcase(c: &CaseResult, dut: &str) -> TestCase {
    let result = match junit_result(c.verdict, &c.message) {
        JunitResult::Success => TestResult::Success,
        JunitResult::Failure(message) => TestResult::Failure {
            type_: c.verdict.name().into(),
            message: xml_safe(&message),
            cause: None,
        },
        JunitResult::Error(message) => TestResult::Error {
            type_: c.verdict.name().into(),
            message: xml_safe(&message),
            cause: None,
        },
        JunitResult::Skipped { kind, message } => TestResult::SkippedWithCause {
            type_: kind.into(),
            message: xml_safe(&message),
            cause: None,
        },
    };
    let m = &c.manual;
    let out = format!(
        "doc: {}\nedition: {}\nsection: {}\npage: {}\nprofile: {}\ndut: {}\ntitle: {}\ntranscript: {}\n",
        m.doc,
        m.edition,
        m.section,
        m.page.map_or("-".to_string(), |p| p.to_string()),
        c.profile,
        dut,
        c.title,
        transcript_file(c).map_or("-".into(), |f| f.to_string_lossy().replace('\\', "/"))
    );
    TestCase {
        name: xml_safe(&c.id),
        time: Duration::seconds_f64(c.duration.as_secs_f64()),
        result,
        classname: Some(xml_safe(&format!("{} §{}", m.doc, m.section))),
        filepath: None,
        system_out: Some(xml_safe(&out)),
        system_err: None,
    }
}

/// The XML document. Writing into memory fails only if the XML writer itself does.
pub(super) fn render(run: &RunResult) -> Result<Vec<u8>, junit_report::Error> {
    let mut report = Report::new();
    for profile in profiles(run) {
        let mut suite = TestSuite::new(&xml_safe(profile));
        suite.add_testcases(
            run.cases
                .iter()
                .filter(|c| c.profile == profile)
                .map(|c| testcase(c, &run.dut)),
        );
        suite.set_system_out(&xml_safe(&format!(
            "profile: {profile}\ndut: {}\n",
            run.dut
        )));
        report.add_testsuite(suite);
    }
    let mut out = Vec::new();
    report.write_xml(&mut out)?;
    Ok(out)
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
        JunitResult::Skipped { kind: "inconclusive", message: "inconclusive: setup failed".into() }
    )]
    #[case(
        Verdict::NotApplicable,
        "about sk550p",
        JunitResult::Skipped { kind: "not_applicable", message: "not applicable: about sk550p".into() }
    )]
    fn verdict_mapping(#[case] v: Verdict, #[case] msg: &str, #[case] want: JunitResult) {
        assert_eq!(junit_result(v, msg), want);
    }

    fn xml() -> String {
        String::from_utf8(render(&sample_run()).unwrap()).unwrap()
    }

    #[test]
    fn one_suite_per_profile_with_counts() {
        let x = xml();
        assert_eq!(x.matches("<testsuite ").count(), 2, "{x}");
        assert!(
            x.contains(
                r#"name="sk550p" package="testsuite/sk550p" tests="2" errors="0" failures="1""#
            ),
            "{x}"
        );
        assert!(
            x.contains(
                r#"name="tu3-eip" package="testsuite/tu3-eip" tests="3" errors="1" failures="0""#
            ),
            "{x}"
        );
        assert!(
            x.contains("<![CDATA[profile: tu3-eip\ndut: embedded simulator\n]]>"),
            "{x}"
        );
    }

    #[test]
    fn each_verdict_becomes_its_element() {
        let x = xml();
        assert!(x.contains(r#"<failure type="fail" message="status: expected 2865 (0B31h), got 2871 (0B37h)"/>"#), "{x}");
        assert!(
            x.contains(
                r#"<error type="error" message="no answer from the DUT within 250 bus cycles"/>"#
            ),
            "{x}"
        );
        assert!(x.contains(r#"<skipped type="not_applicable" message="not applicable: the statement is about sk550p, this run is tu3-eip"/>"#), "{x}");
        assert!(x.contains(r#"<skipped type="inconclusive" message="inconclusive: setup step 1 failed: no connection"/>"#), "{x}");
    }

    #[test]
    fn testcases_carry_id_section_and_manual_reference() {
        let x = xml();
        assert!(
            x.contains(r#"<testcase name="bu0620/addressing/coe-p102" time="0.003" classname="BU 0620 §2.2.7">"#),
            "{x}"
        );
        assert!(
            x.contains("doc: BU 0620\nedition: 2020-03 en\nsection: 2.2.7\npage: 20\nprofile: sk550p\ndut: embedded simulator\n"),
            "{x}"
        );
        assert!(
            x.contains("transcript: transcripts/sk550p/bu0620__addressing__coe-p102.txt"),
            "{x}"
        );
    }

    #[test]
    fn hostile_text_stays_well_formed() {
        let mut run = sample_run();
        run.cases[1].message = "a\u{0}b <c> & \"d\"".into();
        run.cases[1].title = "x ]]> y".into();
        let x = String::from_utf8(render(&run).unwrap()).unwrap();
        assert!(
            x.contains(r#"message="a�b &lt;c&gt; &amp; &quot;d&quot;""#),
            "{x}"
        );
        assert!(x.contains("title: x ]] > y"), "{x}");
        assert!(!x.contains('\u{0}'), "{x}");
    }
}
