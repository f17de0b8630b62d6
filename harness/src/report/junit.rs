//! JUnit XML: one testsuite per profile.
//!
//! junit-report has no properties element, so each testcase carries the manual reference,
//! profile and DUT as `key: value` lines in its system-out, and its classname is
//! `<doc> §<section>` so CI tools group cases by manual section.

use junit_report::{Duration, Report, TestCase, TestSuite};

use crate::outcome::{CaseResult, RunResult, Verdict};

/// What a verdict becomes in JUnit: (kind, message prefix). One table for every writer.
pub(super) fn junit_kind(v: Verdict) -> (&'static str, &'static str) {
    match v {
        Verdict::Pass => ("success", ""),
        Verdict::Fail => ("failure", ""),
        Verdict::Error => ("error", ""),
        Verdict::Inconclusive => ("skipped", "inconclusive: "),
        Verdict::NotApplicable => ("skipped", "not applicable: "),
    }
}

fn testcase(c: &CaseResult, dut: &str) -> TestCase {
    let time = Duration::seconds_f64(c.duration.as_secs_f64());
    let (kind, prefix) = junit_kind(c.verdict);
    let message = format!("{prefix}{}", c.message);
    let mut t = match kind {
        "failure" => TestCase::failure(&c.id, time, "fail", &message),
        "error" => TestCase::error(&c.id, time, "error", &message),
        "skipped" => TestCase::skipped_with_cause(&c.id, c.verdict.name(), &message),
        _ => TestCase::success(&c.id, time),
    };
    t.set_classname(&format!("{} §{}", c.manual.doc, c.manual.section));
    t.set_system_out(&format!(
        "doc: {}\nedition: {}\nsection: {}\npage: {}\nprofile: {}\ndut: {}\ntitle: {}\n",
        c.manual.doc, c.manual.edition, c.manual.section, c.manual.page, c.profile, dut, c.title
    ));
    t
}

/// The XML document.
pub(super) fn render(run: &RunResult) -> Vec<u8> {
    let mut report = Report::new();
    for profile in &run.profiles {
        let mut suite = TestSuite::new(profile);
        suite.add_testcases(
            run.cases
                .iter()
                .filter(|c| &c.profile == profile)
                .map(|c| testcase(c, &run.dut)),
        );
        report.add_testsuite(suite);
    }
    let mut out = Vec::new();
    // Writing into a Vec cannot fail.
    let _ = report.write_xml(&mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::tests::sample_run;

    #[test]
    fn verdict_table() {
        assert_eq!(junit_kind(Verdict::Pass), ("success", ""));
        assert_eq!(junit_kind(Verdict::Fail), ("failure", ""));
        assert_eq!(junit_kind(Verdict::Error), ("error", ""));
        assert_eq!(
            junit_kind(Verdict::Inconclusive),
            ("skipped", "inconclusive: ")
        );
        assert_eq!(
            junit_kind(Verdict::NotApplicable),
            ("skipped", "not applicable: ")
        );
    }

    #[test]
    fn xml_has_one_suite_per_profile_and_each_verdict_mapped() {
        let xml = String::from_utf8(render(&sample_run())).unwrap();
        assert_eq!(xml.matches("<testsuite ").count(), 2, "{xml}");
        assert!(
            xml.contains("<failure") && xml.contains("<error") && xml.contains("<skipped"),
            "{xml}"
        );
        assert!(
            xml.contains("not applicable: the statement is about"),
            "{xml}"
        );
        assert!(xml.contains("classname=\"BU 0620 §2.2.7\""), "{xml}");
        assert!(xml.contains("section: 2.2.7"), "{xml}");
    }
}
